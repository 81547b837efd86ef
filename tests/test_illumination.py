"""The self-quotient image (pftrack.cues.illumination) and the colour trackers' ``illumination`` option."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.cues.illumination import QuotientImage, illumination_quotient
from pftrack.cues.intensity import is_gray
from pftrack.geometry import iou


def _texture(rng, shape, sigma, mean, std):
    t = cv2.GaussianBlur(rng.normal(0.0, 1.0, shape).astype(np.float32), (0, 0), sigma)
    return mean + std * t / t.std()


def _light(h, w, t, centre0, centre1):
    """A global gain falling to 0.4 and back, times a lamp that drifts from ``centre0`` to ``centre1``
    (the lighting of scripts/make_variants.py)."""
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    cx, cy = centre0[0] + (centre1[0] - centre0[0]) * t, centre0[1] + (centre1[1] - centre0[1]) * t
    spot = np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2) / (0.35 * max(h, w)) ** 2)
    return (1.0 - 0.6 * np.sin(np.pi * t)) * (0.55 + 0.9 * spot)


def spot_scene(seed: int, n: int = 80, h: int = 240, w: int = 320):
    """A textured grey target crossing textured ground under a drifting lamp: BGR frames and boxes."""
    rng = np.random.default_rng(seed)
    bg = _texture(rng, (h, w), 6, 110, 40)
    tw, th = 30, 40
    tex = _texture(rng, (th, tw), 2, 150, 30)
    yy, xx = np.mgrid[0:th, 0:tw]
    inside = ((xx - (tw - 1) / 2) / (tw / 2)) ** 2 + ((yy - (th - 1) / 2) / (th / 2)) ** 2 <= 1
    x0, y0 = rng.uniform(20, 60), rng.uniform(60, 140)
    vx, vy = rng.uniform(1.5, 2.5), rng.uniform(-0.5, 0.5)
    c0, c1 = rng.uniform((0, 0), (w, h)), rng.uniform((0, 0), (w, h))
    frames, boxes = [], []
    for t in range(n):
        f = bg.copy()
        ix, iy = int(round(x0 + vx * t)), int(round(y0 + vy * t))
        f[iy:iy + th, ix:ix + tw][inside] = tex[inside]
        g = f * _light(h, w, t / (n - 1), c0, c1) + rng.normal(0.0, 2.0, f.shape)
        frames.append(cv2.cvtColor(np.clip(g, 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR))
        boxes.append((ix, iy, tw, th))
    return frames, boxes


def test_a_uniform_gain_passes_through_and_the_output_stays_grey():
    rng = np.random.default_rng(0)
    img = np.clip(_texture(rng, (120, 160), 3, 120, 30), 0, 255).astype(np.uint8)
    q1 = illumination_quotient(img)
    q2 = illumination_quotient((img.astype(np.float32) * 0.5).round().astype(np.uint8))
    assert q1.shape == (120, 160, 3) and q1.dtype == np.uint8 and is_gray(q1)
    # the frame's mean level is kept (global equalisation takes care of a uniform gain): half the light, half
    # the levels, everywhere alike
    assert np.abs(q1.astype(np.float64) * 0.5 - q2).mean() < 1.0
    # a BGR grey frame and its single channel give the same image
    assert np.array_equal(illumination_quotient(cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)), q1)


@pytest.mark.parametrize("shape", [(120, 160), (10, 12), (8, 40), (40, 8), (17, 33), (1, 1)])
def test_a_flat_frame_stays_flat_at_any_size(shape):
    q = QuotientImage()
    for level in (100, 30):  # the kept buffers are refilled on every frame
        out = q(np.full(shape, level, np.uint8))
        assert out.shape == (*shape, 3)
        assert np.all(out == level)


def test_a_smooth_light_field_is_divided_out():
    rng = np.random.default_rng(1)
    h, w = 240, 320
    refl = _texture(rng, (h, w), 2, 120, 30)
    light = _light(h, w, 0.5, (40, 40), (300, 200))  # gain 0.4 times a lamp: 0.22 to 0.58
    lit = np.clip(refl * light, 0, 255).astype(np.uint8)
    plain = np.clip(refl, 0, 255).astype(np.uint8)
    inner = (slice(20, h - 20), slice(20, w - 20))
    q_lit = illumination_quotient(lit).astype(np.float64)[..., 0][inner]
    q_plain = illumination_quotient(plain).astype(np.float64)[..., 0][inner]
    # the lit frame's levels differ from the plain frame's by a factor that varies over the frame; after the
    # quotient the two differ by one global factor only
    before = np.corrcoef(lit[inner].ravel(), plain[inner].ravel())[0, 1]
    after = np.corrcoef(q_lit.ravel(), q_plain.ravel())[0, 1]
    assert after > 0.97 > before + 0.05
    ratio = q_lit / np.maximum(q_plain, 1.0)
    assert np.std(ratio) / np.mean(ratio) < 0.1
    ratio = lit[inner] / np.maximum(plain[inner], 1.0)
    assert np.std(ratio) / np.mean(ratio) > 0.2


def test_colour_input_is_never_changed():
    rng = np.random.default_rng(2)
    frame = rng.integers(0, 256, (60, 80, 3), dtype=np.uint8)
    for name in ("color-pf", "fusion-pf"):
        t = pftrack.create_tracker(name, seed=0, illumination="quotient")
        t.init(frame, (20, 15, 20, 20))
        assert t._quotient is None
        assert t._transform_input(frame, first=False) is frame


@pytest.mark.parametrize("name", ["color-pf", "fusion-pf"])
def test_quotient_tracks_a_grey_target_under_a_drifting_lamp(name):
    # the lamp brightens and darkens the target differently from the ground around it: global equalisation
    # cannot undo that, the quotient does
    scores = {}
    modes = {"none": {}, "quotient": {"illumination": "quotient"}}
    if name == "color-pf":  # the histograms alone (the structural cue only at re-acquisition), and with it
        modes["levels"] = {"grey_histogram": "levels", "grey_check": "structure"}
        modes["both"] = {"grey_check": "structure"}
        modes["levels_fused"] = {"grey_histogram": "levels"}
    for mode, params in modes.items():
        ious = []
        for seed in range(3):
            frames, boxes = spot_scene(seed)
            t = pftrack.create_tracker(name, seed=0, **params)
            t.init(frames[0], boxes[0])
            ious.append(np.mean([iou(t.update(f).box, b) for f, b in zip(frames[1:], boxes[1:])]))
        scores[mode] = float(np.mean(ious))
    assert scores["quotient"] > 0.75
    if name == "color-pf":
        # the histogram of the grey levels alone is lost without the quotient (measured 0.54); a second model of
        # the quotient beside it (grey_histogram="both") holds (measured 0.80), and so does the grey levels'
        # histogram fused with the structural cue (grey_check="fused", measured 0.90; the default 0.91)
        assert scores["levels"] < scores["both"] - 0.2
        assert scores["levels"] < scores["levels_fused"] - 0.2
        assert scores["none"] > 0.75


def test_raw_frame_check_refuses_background_and_accepts_the_target():
    from pftrack.filtering.loss import LossDetector
    from pftrack.trackers.raw_check import RawGreyCheck

    rng = np.random.default_rng(3)
    h, w = 160, 200
    frame = _texture(rng, (h, w), 4, 90, 25)
    target = (60.0, 80.0, 12.0, 18.0)  # cx, cy, hx, hy
    yy, xx = np.mgrid[0:h, 0:w]
    inside = ((xx - target[0]) / target[2]) ** 2 + ((yy - target[1]) / target[3]) ** 2 <= 1
    frame[inside] = _texture(rng, (h, w), 1, 190, 20)[inside]
    bgr = cv2.cvtColor(np.clip(frame, 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR)
    check = RawGreyCheck(gray_bins=(16, 8), kernel="nummiaro", max_pixels=1000, gradient_threshold=40.0,
                         alpha=0.05, detector=LossDetector())
    check.init(bgr, np.array(target))
    gx, gy = np.meshgrid(np.arange(20, w, 25.0), np.arange(20, h, 25.0))
    grid = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, 12.0), np.full(gx.size, 18.0)])
    far = (np.abs(grid[:, 0] - target[0]) > 30) | (np.abs(grid[:, 1] - target[1]) > 40)
    check.set_background(bgr, grid[far])
    for _ in range(10):
        check.new_frame()
        check.learn(bgr, np.array(target))
    assert not check.vetoes(bgr, np.array(target))
    assert check.vetoes(bgr, np.array([150.0, 40.0, 12.0, 18.0]))
    assert np.isnan(check.rho(bgr, np.array([[-500.0, -500.0, 5.0, 5.0]]))[0])


def test_automatic_initialisation_leaves_the_frames_as_they_are():
    frames, boxes = spot_scene(0, n=3)
    t = pftrack.create_tracker("color-pf", seed=0, illumination="quotient")
    t.init(frames[0], boxes[0])
    assert t._quotient is not None
    hist = t.cue.histogram(frames[0], np.array([45.0, 100.0, 15.0, 20.0]))
    t.init_auto(frames[0], hist, (30, 40))
    assert t._quotient is None and t._raw_check is None
    assert t._transform_input(frames[1], first=False) is frames[1]


def test_track_command_runs_the_quotient_option_on_grey_video(tmp_path, capsys):
    from pftrack.cli import main
    from pftrack.io import read_track_csv

    frames, boxes = spot_scene(2, n=25)
    folder = tmp_path / "img"
    folder.mkdir()
    for i, f in enumerate(frames, 1):
        cv2.imwrite(str(folder / f"{i:04d}.png"), f[..., 0])  # single-channel files: a monochrome camera
    out = tmp_path / "t.csv"
    box = ",".join(str(v) for v in boxes[0])
    assert main(["track", str(folder), "--box", box, "--out", str(out), "--quiet",
                 "--param", "illumination=quotient"]) == 0
    rows = read_track_csv(out)
    assert rows.shape == (25, 7)
    assert np.mean([iou(tuple(r[1:5]), b) for r, b in zip(rows[1:], boxes[1:])]) > 0.6
