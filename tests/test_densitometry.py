"""Book ch. 14 densitometry: the line follows the tracked segment; eq. (1) on a known vessel; the CLI."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from pftrack.cli import main
from pftrack.densitometry import (
    background_line,
    densitometric_area,
    profile_along,
    translate_line,
    vessel_edges,
)


def _vessel_frame(shift=(0.0, 0.0), contrast=0.5, size=(160, 200), seed=0):
    """Bright background with a texture; a vertical dark vessel (Gaussian profile) near x = 100 + dx."""
    h, w = size
    rng = np.random.default_rng(seed)
    tex = cv2.GaussianBlur(rng.uniform(-1, 1, (h + 40, w + 40)), (0, 0), 3) * 300
    yy, xx = np.mgrid[0:h + 40, 0:w + 40].astype(np.float64)
    base = 180 + tex + 0.1 * xx
    vessel = np.exp(-0.5 * ((xx - 120) / 3.0) ** 2)  # sigma 3 px
    img = base * (1 - contrast * vessel)
    m = np.float32([[1, 0, shift[0] - 20], [0, 1, shift[1] - 20]])
    return cv2.warpAffine(img.astype(np.float32), m, (w, h), flags=cv2.INTER_LINEAR)


def test_area_and_edges_of_a_known_vessel():
    img = np.full((40, 80), 200.0)
    x = np.arange(80)
    trans = 1 - 0.4 * np.exp(-0.5 * ((x - 40) / 4.0) ** 2)
    img *= trans[None, :]
    prof = profile_along(img, (10, 20, 70, 20))
    bg = background_line(prof, method="II")
    assert np.allclose(bg, 200.0)
    d1, d2 = vessel_edges(prof, bg)
    fwhm = 2 * np.sqrt(2 * np.log(2)) * 4.0  # of -ln(transmission), close to the Gaussian's own for small contrast
    assert abs((d2 - d1 + 1) - fwhm) <= 2.0
    expected = -np.log(trans[10 + d1:10 + d2 + 1]).sum()
    assert densitometric_area(prof, bg, d1, d2) == pytest.approx(expected, rel=1e-6)


def test_background_methods():
    prof = np.linspace(100, 160, 41)
    prof[18:24] -= 50
    for method in ("I", "II", "III"):
        bg = background_line(prof, method=method)
        assert np.allclose(bg[[0, -1]], [100, 160], atol=2.0), method
    assert np.allclose(background_line(prof, method="III"), np.linspace(100, 160, 41), atol=1e-9)
    assert np.allclose(translate_line((1, 2, 3, 4), (10, -1)), [11, 1, 13, 3])


def test_cli_line_follows_the_segment(tmp_path):
    shifts = [(0.0, 0.0)] + [(2.0 * np.sin(t / 3), 1.5 * t / 4) for t in range(1, 12)]
    folder = tmp_path / "cine"
    folder.mkdir()
    for i, s in enumerate(shifts):
        cv2.imwrite(str(folder / f"{i + 1:03d}.png"), np.clip(_vessel_frame(s), 0, 255).astype(np.uint8))
    out = tmp_path / "curve.csv"
    assert main(["densitometry", str(folder), "--box", "80,40,40,50", "--line", "88,65,112,65", "--out", str(out),
                 "--video-out", str(tmp_path / "v.mp4"), "--quiet"]) == 0
    rows = np.genfromtxt(out, delimiter=",", names=True)
    assert rows.shape[0] == len(shifts)
    assert np.allclose(rows["dx"], [s[0] for s in shifts], atol=0.3)
    assert np.allclose(rows["dy"], [s[1] for s in shifts], atol=0.3)
    assert np.all(rows["A"] > 0.5) and np.ptp(rows["A"]) < 0.35 * rows["A"].mean()  # same vessel under the line
    assert (tmp_path / "v.mp4").stat().st_size > 0
    # the tripwire's form of a line gives the same curve
    out2 = tmp_path / "curve2.csv"
    assert main(["densitometry", str(folder), "--box", "80,40,40,50", "--line", "88,65;112,65", "--out", str(out2),
                 "--quiet"]) == 0
    assert out2.read_text() == out.read_text()


def test_cli_bad_input_exits_2(tmp_path, capsys):
    folder = tmp_path / "cine"
    folder.mkdir()
    cv2.imwrite(str(folder / "001.png"), np.clip(_vessel_frame(), 0, 255).astype(np.uint8))
    out = tmp_path / "c.csv"
    assert main(["densitometry", str(folder), "--box", "80,40,40,50", "--line", "88,65,900,65", "--out", str(out)]) == 2
    assert "outside" in capsys.readouterr().err and not out.exists()
    assert main(["densitometry", str(folder), "--box", "80,40,40,50", "--line", "88,65;112", "--out", str(out)]) == 2
    assert "4 numbers" in capsys.readouterr().err and not out.exists()
    assert main(["densitometry", str(tmp_path / "missing"), "--box", "1,1,5,5", "--line", "1,1,4,4",
                 "--out", str(out)]) == 2
    capsys.readouterr()
    args = ["densitometry", str(folder), "--box", "80,40,40,50", "--out", str(out)]
    for extra, message in [(["--line", "88,65,a,65"], "4 numbers"), (["--line", "88,65,112,65", "--width", "0"],
                                                                       "--width must be >= 1"),
                           (["--line", "88,65,112,65", "--template-frame", "0"], "--template-frame must be >= 1"),
                           (["--line", "88,65,112,65", "--template-frame", "5"], "no frame 5")]:
        assert main(args + extra) == 2
        err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
        assert len(err) == 1 and message in err[0] and not out.exists()


def test_cli_template_frame_in_the_middle_tracks_backwards(tmp_path):
    shifts = [(2.0 * np.sin(t / 3), 1.5 * t / 4) for t in range(12)]
    folder = tmp_path / "cine"
    folder.mkdir()
    for i, s in enumerate(shifts):
        cv2.imwrite(str(folder / f"{i + 1:03d}.png"), np.clip(_vessel_frame(s), 0, 255).astype(np.uint8))
    nr = 5
    sx, sy = shifts[nr - 1]
    out = tmp_path / "curve.csv"
    box = f"{80 + sx:.2f},{40 + sy:.2f},40,50"
    line = f"{88 + sx:.2f},{65 + sy:.2f},{112 + sx:.2f},{65 + sy:.2f}"
    assert main(["densitometry", str(folder), "--box", box, "--line", line, "--template-frame", str(nr),
                 "--out", str(out), "--quiet"]) == 0
    rows = np.genfromtxt(out, delimiter=",", names=True)
    assert list(rows["frame"].astype(int)) == [5, 4, 3, 2, 1, 6, 7, 8, 9, 10, 11, 12]  # rows as computed
    for r in rows:
        k = int(r["frame"]) - 1
        assert abs(r["dx"] - (shifts[k][0] - sx)) < 0.3 and abs(r["dy"] - (shifts[k][1] - sy)) < 0.3
