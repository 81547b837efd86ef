"""scripts/make_variants.py: grey and grey + illumination copies, fresh draws of the lamp (--light-seeds),
resized copies (--scale), copies at a lower frame rate (--stride), through a shaking camera (--shake), with
motion blur (--blur), from a dark, noisy camera (--dim, --noise), through haze (--haze), with a white balance that
jumps (--cast) and through a steady zoom (--zoom)."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from pftrack.io.datasets import read_sequence, write_groundtruth

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "make_variants.py"


def _otb(root: Path, n: int = 6) -> Path:
    """A tiny OTB folder: textured colour frames and a box per frame."""
    rng = np.random.default_rng(0)
    seq = root / "tiny"
    (seq / "img").mkdir(parents=True)
    for i in range(n):
        cv2.imwrite(str(seq / "img" / f"{i + 1:04d}.png"), rng.integers(60, 200, (48, 64, 3), dtype=np.uint8))
    write_groundtruth(seq / "groundtruth_rect.txt", np.tile([10.0, 12.0, 20.0, 16.0], (n, 1)))
    return seq


def _script():
    spec = importlib.util.spec_from_file_location("make_variants", SCRIPT)
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    return script


def _run(*args: str) -> None:
    subprocess.run([sys.executable, str(SCRIPT), *args], check=True, capture_output=True, text=True)


def _frames(path: Path) -> np.ndarray:
    return np.stack([cv2.imread(str(p), cv2.IMREAD_GRAYSCALE) for p in read_sequence(path).frames]).astype(float)


def test_light_seeds_write_only_fresh_lamps_each_its_own(tmp_path):
    seq = _otb(tmp_path)
    _run(str(seq), "--out", str(tmp_path / "a"))
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == ["tiny-gray", "tiny-gray-light"]
    _run(str(seq), "--light-seeds", "1-2", "--out", str(tmp_path / "b"))
    b = tmp_path / "b"
    assert sorted(p.name for p in b.iterdir()) == ["tiny-gray-light-s1", "tiny-gray-light-s2"]
    s1, s2, base = _frames(b / "tiny-gray-light-s1"), _frames(b / "tiny-gray-light-s2"), _frames(tmp_path / "a" /
                                                                                                   "tiny-gray-light")
    grey = _frames(tmp_path / "a" / "tiny-gray")
    # the lamps differ between seeds and from the name's own lamp; the first frame has the full gain (1) everywhere
    # but under the spot, so each copy is the grey frame times a field in [0.55, 1.45]
    assert np.abs(s1 - s2).mean() > 2 and np.abs(s1 - base).mean() > 2
    assert np.array_equal(read_sequence(b / "tiny-gray-light-s1").groundtruth, read_sequence(seq).groundtruth)
    ratio = (s1[0] + 1) / (grey[0] + 1)
    assert 0.45 < np.median(ratio) < 1.55
    # the same seed gives the same copy again
    _run(str(seq), "--light-seeds", "1", "--out", str(tmp_path / "c"))
    assert np.array_equal(_frames(tmp_path / "c" / "tiny-gray-light-s1"), s1)


def test_scale_writes_one_resized_copy_with_its_truth_scaled(tmp_path):
    seq = _otb(tmp_path)
    gt = read_sequence(seq).groundtruth.copy()
    gt[2] = np.nan  # an absent frame stays absent
    write_groundtruth(seq / "groundtruth_rect.txt", gt)
    for f, name, size in ((0.5, "tiny-x0.5", (24, 32)), (2.0, "tiny-x2", (96, 128))):
        _run(str(seq), "--scale", str(f), "--out", str(tmp_path / "s"))
        copy = read_sequence(tmp_path / "s" / name)
        assert len(copy.frames) == 6 and cv2.imread(str(copy.frames[0])).shape == size + (3,)
        np.testing.assert_allclose(copy.groundtruth, gt * f)
    assert sorted(p.name for p in (tmp_path / "s").iterdir()) == ["tiny-x0.5", "tiny-x2"]
    bad = subprocess.run([sys.executable, str(SCRIPT), str(seq), "--scale", "0", "--out", str(tmp_path / "z")],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "positive" in bad.stderr


def test_stride_keeps_every_kth_frame_as_it_is_with_its_truth_rows(tmp_path):
    seq = _otb(tmp_path, n=7)
    gt = read_sequence(seq).groundtruth.copy()
    gt[:, 0] += np.arange(7)  # a box that moves, so a row taken from the wrong frame shows
    gt[4] = np.nan  # an absent frame stays absent
    write_groundtruth(seq / "groundtruth_rect.txt", gt)
    meta = {"kind": "mot-person", "hidden": [2, 3], "unannotated": [5, 6], "visible": [1, 0.5, 0, 0, 1, 1, 0.9]}
    (seq / "meta.json").write_text(json.dumps(meta), encoding="utf-8")
    _run(str(seq), "--stride", "2", "--out", str(tmp_path / "s"))
    copy = read_sequence(tmp_path / "s" / "tiny-s2")
    # frame 3 (hidden) and 5 (unannotated) are kept as frames 2 and 3; frames 2 and 6 are dropped
    assert json.loads((tmp_path / "s" / "tiny-s2" / "meta.json").read_text()) == {
        "kind": "mot-person", "hidden": [2], "unannotated": [3], "visible": [1, 0, 1, 0.9]}
    assert copy.absent.tolist() == [False, True, False, False]
    assert [p.name for p in copy.frames] == ["0001.png", "0002.png", "0003.png", "0004.png"]
    np.testing.assert_array_equal(copy.groundtruth, gt[[0, 2, 4, 6]])
    original = read_sequence(seq).frames
    for k, p in enumerate(copy.frames):  # the same bytes as frames 1, 3, 5, 7
        assert p.read_bytes() == original[2 * k].read_bytes()
    _run(str(seq), "--stride", "1", "--out", str(tmp_path / "one"))
    np.testing.assert_array_equal(read_sequence(tmp_path / "one" / "tiny-s1").groundtruth, gt)
    bad = subprocess.run([sys.executable, str(SCRIPT), str(seq), "--stride", "0", "--out", str(tmp_path / "z")],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "stride" in bad.stderr


def test_shake_cuts_each_frame_at_its_offset_and_moves_the_truth_alike(tmp_path):
    script = _script()
    off = script.shake_offsets(6, 3, "tiny")
    assert off[0].tolist() == [0, 0] and np.abs(off).max() <= 3 and np.any(off[1:] != 0)
    seq = _otb(tmp_path, n=6)
    yy, xx = np.mgrid[0:48, 0:64]
    smooth = np.dstack([3 * xx, 4 * yy, 128 + 90 * np.sin(xx / 4.0) * np.cos(yy / 5.0)]).astype(np.uint8)
    for p in read_sequence(seq).frames:  # smooth frames with structure: JPEG keeps each pixel within a few levels
        cv2.imwrite(str(p), smooth)
    gt = read_sequence(seq).groundtruth.copy()
    gt[3] = [3 + off[3, 0] + 58.5, 10.0, 2.0, 2.0]  # just right of frame 4's cut: wholly outside it
    write_groundtruth(seq / "groundtruth_rect.txt", gt)
    _run(str(seq), "--shake", "3", "--out", str(tmp_path / "k"))
    copy = read_sequence(tmp_path / "k" / "tiny-shake3")
    for i, p in enumerate(copy.frames):
        x0, y0 = 3 + off[i, 0], 3 + off[i, 1]
        cut = cv2.imread(str(p), cv2.IMREAD_COLOR).astype(float)
        assert cut.shape == (42, 58, 3)
        err = np.abs(cut - smooth[y0:y0 + 42, x0:x0 + 58]).mean()
        assert err < 2  # the same pixels, through JPEG
        if np.any(off[i] != 0):  # and not those of the frame's centre cut
            assert np.abs(cut - smooth[3:45, 3:61]).mean() > 2 * err
    moved = gt.copy()
    moved[:, :2] -= 3 + off
    moved[3] = np.nan
    np.testing.assert_allclose(copy.groundtruth, moved)
    bad = subprocess.run([sys.executable, str(SCRIPT), str(seq), "--shake", "0", "--out", str(tmp_path / "z")],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "shake" in bad.stderr


def test_blur_smears_about_half_the_frames_along_a_line_and_keeps_the_truth(tmp_path):
    kernels = _script().blur_kernels(200, 8, "tiny")
    assert kernels[0] is None and 70 < sum(k is not None for k in kernels) < 130
    for k in kernels:
        if k is not None:  # a normalised line through the centre, 4 to 8 px long and about one pixel wide
            assert abs(k.sum() - 1) < 1e-6 and k.shape[0] % 2 == 1 and k[k.shape[0] // 2, k.shape[1] // 2] > 0
            yy, xx = np.mgrid[0:k.shape[0], 0:k.shape[1]] - (k.shape[0] - 1) / 2
            cov = np.cov(np.stack([xx.ravel(), yy.ravel()]), aweights=k.ravel(), bias=True)
            spread_along, spread_across = np.sqrt(np.linalg.eigvalsh(cov))[::-1]
            assert 4 / np.sqrt(12) - 0.3 < spread_along < 8 / np.sqrt(12) + 0.3 and spread_across < 0.5
    seq = _otb(tmp_path, n=12)
    _run(str(seq), "--blur", "8", "--out", str(tmp_path / "b"))
    copy, orig = _frames(tmp_path / "b" / "tiny-blur8"), _frames(seq)
    blurred = [k is not None for k in _script().blur_kernels(12, 8, "tiny")]
    for i in range(12):  # the random texture loses most of its contrast where blurred, keeps it (through JPEG) else
        assert (copy[i].std() < 0.7 * orig[i].std()) == blurred[i]
    np.testing.assert_array_equal(read_sequence(tmp_path / "b" / "tiny-blur8").groundtruth,
                                  read_sequence(seq).groundtruth)
    bad = subprocess.run([sys.executable, str(SCRIPT), str(seq), "--blur", "1", "--out", str(tmp_path / "z")],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "blur" in bad.stderr


def test_dim_darkens_every_frame_and_adds_the_noise_asked(tmp_path):
    seq = _otb(tmp_path, n=4)
    flat = np.full((48, 64, 3), 200, np.uint8)
    for p in read_sequence(seq).frames:
        cv2.imwrite(str(p), flat)
    _run(str(seq), "--dim", "0.25", "--noise", "4", "--out", str(tmp_path / "d"))
    copy = read_sequence(tmp_path / "d" / "tiny-dim0.25-noise4")
    for p in copy.frames:
        img = cv2.imread(str(p), cv2.IMREAD_COLOR).astype(float)
        assert abs(img.mean() - 50) < 1.5 and 2.0 < img.std() < 5.0  # 200 x 0.25, noise of 4 levels through JPEG
    np.testing.assert_array_equal(copy.groundtruth, read_sequence(seq).groundtruth)
    _run(str(seq), "--dim", "0.5", "--noise", "0", "--out", str(tmp_path / "e"))
    img = cv2.imread(str(read_sequence(tmp_path / "e" / "tiny-dim0.5-noise0").frames[0]), cv2.IMREAD_COLOR)
    assert np.abs(img.astype(float) - 100).max() <= 1
    for bad_args in (["--dim", "0"], ["--dim", "1.5"], ["--dim", "0.5", "--noise", "-1"]):
        bad = subprocess.run([sys.executable, str(SCRIPT), str(seq), *bad_args, "--out", str(tmp_path / "z")],
                             capture_output=True, text=True)
        assert bad.returncode == 2 and ("dim" in bad.stderr or "noise" in bad.stderr)


def test_haze_veils_every_frame_with_a_bright_bluish_airlight(tmp_path):
    seq = _otb(tmp_path, n=3)
    base = np.zeros((48, 64, 3), np.uint8)
    base[:, 32:] = 200
    for p in read_sequence(seq).frames:
        cv2.imwrite(str(p), base)
    _run(str(seq), "--haze", "0.6", "--noise", "0", "--out", str(tmp_path / "h"))
    copy = read_sequence(tmp_path / "h" / "tiny-haze0.6-noise0")
    np.testing.assert_array_equal(copy.groundtruth, read_sequence(seq).groundtruth)
    for p in copy.frames:
        img = cv2.imread(str(p), cv2.IMREAD_COLOR).astype(float)
        dark, bright = img[:, 4:28].mean(axis=(0, 1)), img[:, 36:60].mean(axis=(0, 1))
        assert np.all((dark > 0.6 * 215 - 2) & (dark < 0.6 * 245 + 2))  # black becomes the veil alone
        assert dark[0] >= dark[1] - 1 >= dark[2] - 2  # bluish: B >= G >= R
        assert np.allclose(bright - dark, 0.4 * 200, atol=3)  # the contrast cut to 1 - H
    for bad_args in (["--haze", "0"], ["--haze", "1"], ["--haze", "0.5", "--dim", "0.5"]):
        bad = subprocess.run([sys.executable, str(SCRIPT), str(seq), *bad_args, "--out", str(tmp_path / "z")],
                             capture_output=True, text=True)
        assert bad.returncode == 2 and "haze" in bad.stderr


def test_cast_jumps_the_white_balance_a_third_of_the_way_through(tmp_path):
    seq = _otb(tmp_path, n=6)
    _run(str(seq), "--cast", "0.3", "--out", str(tmp_path / "c"))
    copy = read_sequence(tmp_path / "c" / "tiny-cast0.3")
    np.testing.assert_array_equal(copy.groundtruth, read_sequence(seq).groundtruth)
    gains = _script().cast_gains("tiny", 0.3)
    assert gains[1] == 1.0 and sorted(np.round(gains[[0, 2]], 6)) == [0.7, 1.3]
    for i, (orig, new) in enumerate(zip(read_sequence(seq).frames, copy.frames)):
        a = cv2.imread(str(orig), cv2.IMREAD_COLOR).astype(float).mean(axis=(0, 1))
        b = cv2.imread(str(new), cv2.IMREAD_COLOR).astype(float).mean(axis=(0, 1))
        expect = a * gains if i >= 2 else a  # frames 3-6 (from 1) of six: floor(6/3) + 1 on
        assert np.allclose(b, expect, atol=2.0), (i, b, expect)
    for bad in ("0", "0.7", "-0.2"):
        res = subprocess.run([sys.executable, str(SCRIPT), str(seq), "--cast", bad, "--out", str(tmp_path / "z")],
                             capture_output=True, text=True)
        assert res.returncode == 2 and "cast" in res.stderr


def test_light_jumps_every_channel_a_third_of_the_way_through(tmp_path):
    seq = _otb(tmp_path, n=6)
    _run(str(seq), "--light", "1.3", "--out", str(tmp_path / "l"))
    copy = read_sequence(tmp_path / "l" / "tiny-light1.3")
    np.testing.assert_array_equal(copy.groundtruth, read_sequence(seq).groundtruth)
    for i, (orig, new) in enumerate(zip(read_sequence(seq).frames, copy.frames)):
        a = cv2.imread(str(orig), cv2.IMREAD_COLOR).astype(float)
        b = cv2.imread(str(new), cv2.IMREAD_COLOR).astype(float)
        expect = np.clip(a * 1.3, 0, 255) if i >= 2 else a
        assert np.allclose(b.mean(axis=(0, 1)), expect.mean(axis=(0, 1)), atol=2.0), i
    for bad in ("1", "0.1", "5"):
        res = subprocess.run([sys.executable, str(SCRIPT), str(seq), "--light", bad, "--out", str(tmp_path / "z")],
                             capture_output=True, text=True)
        assert res.returncode == 2 and "light" in res.stderr


def test_lamps_light_a_dark_copy_away_from_the_target(tmp_path):
    script = _script()
    boxes = np.tile([100.0, 60.0, 40.0, 80.0], (30, 1))
    light = script.lamp_field(240, 320, 3, "tiny", boxes)
    assert light.shape == (240, 320, 3) and light.max() > 255  # saturated cores
    r = 0.02 * np.hypot(240, 320)
    bright = light.max(axis=2) > 100
    x, y, w, h = boxes[0]
    assert not bright[int(y - r):int(y + h + r), int(x - r):int(x + w + r)].any()  # none over the target
    assert 0.002 < bright.mean() < 0.05
    np.testing.assert_array_equal(light, script.lamp_field(240, 320, 3, "tiny", boxes))  # drawn from the name
    seq = _otb(tmp_path, n=3)
    _run(str(seq), "--dim", "0.3", "--lamps", "4", "--out", str(tmp_path / "n"))
    f = cv2.imread(str(read_sequence(tmp_path / "n" / "tiny-dim0.3-noise3-lamps4").frames[0]), cv2.IMREAD_COLOR)
    assert np.percentile(f, 99.5) > 200 and np.median(f) < 70  # lamps in a dark frame
    bad = subprocess.run([sys.executable, str(SCRIPT), str(seq), "--lamps", "2", "--out", str(tmp_path / "z")],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "lamps" in bad.stderr


def test_ramp_raises_the_gain_to_one_over_its_frames(tmp_path):
    script = _script()
    assert script.ramp_gain(0, 0.4, 10) == 0.4 and script.ramp_gain(5, 0.4, 10) == pytest.approx(0.7)
    assert script.ramp_gain(10, 0.4, 10) == 1.0 and script.ramp_gain(50, 0.4, 10) == 1.0
    assert script.ramp_gain(7, 0.4, 0) == 0.4  # no ramp: the gain throughout
    seq = _otb(tmp_path, n=6)
    flat = np.full((48, 64, 3), 200, np.uint8)
    for p in read_sequence(seq).frames:
        cv2.imwrite(str(p), flat)
    _run(str(seq), "--dim", "0.5", "--noise", "0", "--ramp", "4", "--out", str(tmp_path / "r"))
    copy = _frames(tmp_path / "r" / "tiny-dim0.5-noise0-ramp4")
    np.testing.assert_allclose(copy.mean(axis=(1, 2)), [100, 125, 150, 175, 200, 200], atol=1.0)
    bad = subprocess.run([sys.executable, str(SCRIPT), str(seq), "--ramp", "3", "--out", str(tmp_path / "z")],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "ramp" in bad.stderr


def _bright_box(img: np.ndarray) -> np.ndarray:
    """x, y, w, h (pixel edges) of the pixels above mid-grey, with half-covered edge pixels counted by level."""
    g = img.astype(float) / 255.0
    cols, rows = g.max(axis=0), g.max(axis=1)
    x = np.flatnonzero(cols > 0.5)
    y = np.flatnonzero(rows > 0.5)
    return np.array([x[0], y[0], x[-1] + 1 - x[0], y[-1] + 1 - y[0]], dtype=float)


@pytest.mark.parametrize("zoom", [2.0, 0.5])
def test_zoom_maps_the_frames_and_the_truth_alike(tmp_path, zoom):
    script = _script()
    v = script.zoom_views(5, zoom, (30.0, 20.0), (64, 48))
    m = v[:, 0]
    np.testing.assert_allclose(m[-1] / m[0], zoom)  # the target's size changes `zoom` times
    assert min(m) == pytest.approx(1.0) and np.all(np.diff(np.log(m)) == pytest.approx(np.log(zoom) / 4))
    # the view stays inside the frame
    assert np.all(v[:, 1] >= 0) and np.all(v[:, 1] + 64 / m <= 64 + 1e-9) and np.all(v[:, 2] + 48 / m <= 48 + 1e-9)
    # frames: black with a white 16 x 12 box at (22, 14), not moving; the copy's box follows the truth's
    seq = tmp_path / "box"
    (seq / "img").mkdir(parents=True)
    frame = np.zeros((48, 64, 3), np.uint8)
    frame[14:26, 22:38] = 255
    for i in range(5):
        cv2.imwrite(str(seq / "img" / f"{i + 1:04d}.png"), frame)
    write_groundtruth(seq / "groundtruth_rect.txt", np.tile([22.0, 14.0, 16.0, 12.0], (5, 1)))
    _run(str(seq), "--zoom", f"{zoom:g}", "--out", str(tmp_path / "z"))
    copy = read_sequence(tmp_path / "z" / f"box-zoom{zoom:g}")
    assert len(copy.frames) == 5
    for i, p in enumerate(copy.frames):
        seen = _bright_box(cv2.imread(str(p), cv2.IMREAD_GRAYSCALE))
        np.testing.assert_allclose(seen, copy.groundtruth[i], atol=1.5)
        np.testing.assert_allclose(copy.groundtruth[i, 2:], np.array([16.0, 12.0]) * m[i], rtol=1e-3)
    bad = subprocess.run([sys.executable, str(SCRIPT), str(seq), "--zoom", "1", "--out", str(tmp_path / "x")],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "zoom" in bad.stderr


def test_zoom_drops_the_truth_of_a_box_the_view_leaves_out(tmp_path):
    seq = _otb(tmp_path, n=4)
    gt = np.tile([10.0, 12.0, 20.0, 16.0], (4, 1))
    gt[3] = [0.0, 0.0, 6.0, 6.0]  # top-left corner: out of a view magnified about the first box's centre
    write_groundtruth(seq / "groundtruth_rect.txt", gt)
    _run(str(seq), "--zoom", "3", "--out", str(tmp_path / "z"))
    out = read_sequence(tmp_path / "z" / "tiny-zoom3").groundtruth
    assert np.isfinite(out[:3]).all() and np.isnan(out[3]).all()
