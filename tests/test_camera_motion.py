"""The camera's translation from integral projections (``pftrack.cues.camera_shift``) and the colour particle
filters' ``camera_motion`` option, which moves every sample by it."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.cues import camera_shift as cs
from pftrack.eval.metrics import per_frame_iou


def disc_scene(seed: int, shape=(360, 480), channels: int = 3) -> np.ndarray:
    """Discs of other shades on grey: a scene with structure at several scales."""
    rng = np.random.default_rng(seed)
    h, w = shape
    y, x = np.mgrid[0:h, 0:w]
    scene = np.full((h, w, channels), 128.0)
    for _ in range(60):
        cx, cy, r = rng.uniform(0, w), rng.uniform(0, h), rng.uniform(5, 35)
        scene[(x - cx) ** 2 + (y - cy) ** 2 < r * r] += rng.uniform(-80, 80, channels)
    out = np.clip(scene, 0, 255).astype(np.uint8)
    return out[:, :, 0] if channels == 1 else out


@pytest.mark.parametrize("channels,step", [(3, 1), (3, 2), (1, 3), (3, 4)])
def test_compiled_profiles_equal_the_numpy_means(channels, step):
    f = disc_scene(0, (61, 83), channels)
    rows, cols = cs.frame_profiles(f, step)
    g = (f[:, :, None] if channels == 1 else f)[::step, ::step].astype(np.float64).sum(axis=2)
    np.testing.assert_allclose(rows, g.mean(axis=1), rtol=0, atol=1e-9)
    np.testing.assert_allclose(cols, g.mean(axis=0), rtol=0, atol=1e-9)


def test_compiled_shift_equals_the_numpy_reference():
    rng = np.random.default_rng(3)
    for _ in range(30):
        a = np.cumsum(rng.normal(size=int(rng.integers(20, 200))))
        b = np.roll(a, int(rng.integers(-8, 9))) + rng.normal(0, 0.3, a.size)
        m = int(rng.integers(1, 12))
        da, db = cs._normalised_derivative(a), cs._normalised_derivative(b)
        n = min(da.size, db.size)
        ref = cs._refine(cs._shift_costs_numpy(da, db, min(m, n // 2)), min(m, n // 2), 0.8)
        assert cs._profile_shift_numba(a, b, m, 0.8) == pytest.approx(ref, abs=1e-9)


def test_compiled_costs_equal_one_serial_sum_per_shift_to_the_bit():
    """The kernel sums four shifts side by side; each sum keeps the order of one loop per shift."""
    rng = np.random.default_rng(11)
    for _ in range(200):
        n = int(rng.integers(2, 90))
        m = int(rng.integers(1, n // 2 + 1))
        da, db = rng.normal(size=n), rng.normal(size=n)
        ref = []
        for s in range(-m, m + 1):
            lo, hi = max(0, -s), min(n, n - s)
            acc = 0.0
            for i in range(lo, hi):
                acc += abs(float(da[i]) - float(db[i + s]))
            ref.append(acc / (hi - lo))
        assert cs._shift_costs(da, db, m).tolist() == ref


def test_a_featureless_view_of_noise_alone_gives_hardly_any_shift():
    """Profiles of noise alone give one of some seventy costs below no shift's by chance (about one axis in ten);
    the shift must also be below 0.8 of the median cost, which noise hardly reaches."""
    rng = np.random.default_rng(0)
    for h, w in ((240, 320), (480, 854)):
        step = cs.lattice_step(h, w)
        frames = [np.clip(128 + rng.normal(0, 3, (h, w, 3)), 0, 255).astype(np.uint8) for _ in range(41)]
        prof = [cs.frame_profiles(f, step) for f in frames]
        moved = sum((dx != 0) + (dy != 0) for dx, dy in (
            cs.camera_shift(a, b, max_shift=(0.15 * w, 0.15 * h), step=step) for a, b in zip(prof, prof[1:])))
        assert moved <= 4, moved  # of 80 axes


def test_shift_of_a_moved_view_is_found_within_a_pixel():
    scene = disc_scene(1, (560, 720))
    rng = np.random.default_rng(4)
    for _ in range(20):
        x0, y0 = rng.integers(60, 180, 2)
        dx, dy = rng.integers(-40, 41, 2)
        a = scene[y0:y0 + 360, x0:x0 + 480]
        b = scene[y0 - dy:y0 - dy + 360, x0 - dx:x0 - dx + 480]  # the content moves by (dx, dy)
        step = cs.lattice_step(360, 480)
        ex, ey = cs.camera_shift(cs.frame_profiles(a, step), cs.frame_profiles(b, step), max_shift=(72, 54),
                                 step=step)
        assert abs(ex - dx) <= 1.0 and abs(ey - dy) <= 1.0, (dx, dy, ex, ey)


def test_no_shift_without_a_clear_match():
    flat = np.full((120, 160, 3), 90, np.uint8)
    p = cs.frame_profiles(flat)
    assert cs.camera_shift(p, p, max_shift=30) == (0.0, 0.0)  # nothing to match
    scene = disc_scene(2, (120, 160))
    q = cs.frame_profiles(scene)
    assert cs.camera_shift(q, q, max_shift=30) == (0.0, 0.0)  # the same view
    assert cs.lattice_step(480, 854) == 4 and cs.lattice_step(240, 320) == 2 and cs.lattice_step(100, 80) == 1


def shaky_scene(seed: int, *, n: int = 30, shape=(240, 320), size=(24, 40), shake: int = 20):
    """A two-colour box walking slowly over blurred colour noise, seen by a camera that jumps up to ``shake`` px
    along each axis every frame."""
    rng = np.random.default_rng(seed)
    (H, W), (w, h) = shape, size
    big = cv2.GaussianBlur(rng.integers(0, 255, (H + 4 * shake, W + 4 * shake, 3), dtype=np.uint8), (0, 0), 4)
    big = cv2.normalize(big, None, 30, 220, cv2.NORM_MINMAX)
    target = np.zeros((h, w, 3), np.uint8)
    target[: h // 2], target[h // 2:] = (30, 30, 220), (220, 200, 30)
    wx, wy = (W + 4 * shake) / 2 - w / 2, (H + 4 * shake) / 2 - h / 2
    vx, vy = rng.uniform(-2, 2, 2)
    frames, gt = [], []
    for i in range(n):
        cx = cy = 2 * shake
        if i:
            wx, wy = wx + vx, wy + vy
            cx, cy = 2 * shake + rng.integers(-shake, shake + 1, 2)
        f = big.copy()
        xi, yi = int(round(wx)), int(round(wy))
        f[yi:yi + h, xi:xi + w] = target
        frames.append(np.ascontiguousarray(f[cy:cy + H, cx:cx + W]))
        gt.append((xi - cx, yi - cy, w, h))
    return frames, np.array(gt, dtype=np.float64)


def track(name: str, frames, gt, **params):
    t = pftrack.create_tracker(name, seed=0, **params)
    states = [t.init(f, tuple(gt[0])) if i == 0 else t.update(f) for i, f in enumerate(frames)]
    return t, np.array([s.box for s in states])


@pytest.mark.parametrize("name", ["fusion-pf", "color-pf"])
def test_samples_moved_with_a_shaking_camera_stay_on_the_target(name):
    plain, moved = [], []
    for seed in range(3):
        frames, gt = shaky_scene(seed)
        plain.append(np.nanmean(per_frame_iou(track(name, frames, gt, camera_motion=False)[1], gt)))
        moved.append(np.nanmean(per_frame_iou(track(name, frames, gt, camera_motion=True)[1], gt)))
    assert np.mean(moved) > 0.8 and np.mean(moved) > np.mean(plain) + 0.15, (plain, moved)


def test_a_static_camera_moves_no_sample():
    frames, gt = shaky_scene(5, shake=0)
    t, boxes = track("fusion-pf", frames, gt, camera_motion=True)
    assert t._camera_move == (0.0, 0.0)
    np.testing.assert_array_equal(boxes, track("fusion-pf", frames, gt, camera_motion=False)[1])
    assert pftrack.create_tracker("color-pf").params.camera_motion is False
    assert pftrack.create_tracker("fusion-pf").params.camera_motion is True  # motion_proposal_tre_rule.txt


def test_the_lattice_follows_camera_samples():
    """``camera_samples`` bounds the samples along the longer side (fusion-pf 176: every 5th pixel of 854 x 480, as
    chosen by docs/rules/camera_samples_rule.txt), and a coarser lattice still reads the shake."""
    assert pftrack.create_tracker("fusion-pf").params.camera_samples == 176
    assert pftrack.create_tracker("color-pf").params.camera_samples == 256
    frame = np.zeros((480, 854, 3), np.uint8)
    for samples, rows, cols in ((256, 120, 214), (176, 96, 171), (128, 69, 122)):
        t = pftrack.create_tracker("fusion-pf", seed=0, camera_samples=samples)
        t.init(frame, (400, 200, 40, 60))
        assert (t._camera_prev[0].size, t._camera_prev[1].size) == (rows, cols)
    frames, gt = shaky_scene(1)
    for samples in (64, 256):
        moved = np.nanmean(per_frame_iou(track("fusion-pf", frames, gt, camera_samples=samples)[1], gt))
        assert moved > 0.8, (samples, moved)
