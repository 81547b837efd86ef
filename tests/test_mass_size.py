"""fusion-pf's mass_size: the object's size from the mass of the foreground-probability map (cues.mass_size)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pftrack import create_tracker
from pftrack.cues.mass_size import INNER, MAX_RATIO, mass_factor, object_area, window_mass
from pftrack.synth.scenes import Scene, SceneSpec, Target, _wander


def _integral(p: np.ndarray) -> np.ndarray:
    ii = np.zeros((p.shape[0] + 1, p.shape[1] + 1))
    ii[1:, 1:] = p.cumsum(0).cumsum(1)
    return ii


def _ellipse_map(h=200, w=240, cx=120.0, cy=100.0, hx=15.0, hy=30.0, p_obj=0.95, p_bg=0.1, seed=0):
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:h, 0:w] + 0.5
    inside = ((x - cx) / hx) ** 2 + ((y - cy) / hy) ** 2 <= 1.0
    p = np.where(inside, p_obj, p_bg) + rng.uniform(-0.05, 0.05, (h, w))
    return np.clip(p, 0.0, 1.0), int(inside.sum())


def test_window_mass_sums_the_lattice_samples_inside_the_rectangle():
    p = np.arange(12.0).reshape(3, 4)
    ii = _integral(p)
    assert window_mass(ii, 0, 0, 1, (1, 0, 3, 2)) == (p[0:2, 1:3].sum(), 4)
    # a lattice of pitch 2 starting at frame pixel (10, 20): the rectangle in frame pixels, clipped to the lattice
    assert window_mass(ii, 10, 20, 2, (12, 20, 100, 100)) == (p[:, 1:].sum(), 9)
    assert window_mass(ii, 0, 0, 1, (5, 5, 9, 9)) == (0.0, 0)


def test_the_area_of_an_elliptic_object_is_its_pixel_count_whatever_the_box():
    p, n = _ellipse_map()
    ii = _integral(p)
    for f in (0.7, 0.85, 1.0, 1.2):  # the estimate's box smaller or larger than the object's
        area, sep = object_area(ii, 0, 0, 1, (120.0, 100.0, 15.0 * f, 30.0 * f))
        assert sep == pytest.approx(0.85, abs=0.03)
        assert area == pytest.approx(n, rel=0.06)
    # so the area tells the size: a box shrunk to 0.8 is moved back toward 1
    ref = object_area(ii, 0, 0, 1, (120.0, 100.0, 15.0, 30.0))[0], math.sqrt(15.0 * 30.0)
    small = object_area(ii, 0, 0, 1, (120.0, 100.0, 12.0, 24.0))[0]
    k = mass_factor(ref, small, math.sqrt(12.0 * 24.0), 1.0)
    assert k == pytest.approx(1.25, rel=0.05)


def test_no_reading_where_the_map_does_not_separate_the_object_or_the_window_is_cut():
    p, _ = _ellipse_map(p_obj=0.6, p_bg=0.2)
    assert object_area(_integral(p), 0, 0, 1, (120.0, 100.0, 15.0, 30.0)) is None  # separation 0.4 < 0.8
    assert object_area(_integral(p), 0, 0, 1, (120.0, 100.0, 15.0, 30.0), gate=0.3) is not None
    p, _ = _ellipse_map(cx=20.0)  # the window (twice the box) runs past the map's left edge
    assert INNER * 15.0 > 20.0
    assert object_area(_integral(p), 0, 0, 1, (20.0, 100.0, 15.0, 30.0)) is None
    p, _ = _ellipse_map(cx=31.0)  # the window inside the map
    assert object_area(_integral(p), 0, 0, 1, (31.0, 100.0, 15.0, 30.0)) is not None


def test_with_the_frame_only_the_windows_part_inside_it_must_be_covered():
    """mass_frame: the map is the whole frame; an object near its bottom edge, whose window (twice the box) runs
    past the edge, is read with the frame given (its pixel count within 6 %, from boxes 0.8-1.1 of it), and not
    without; a window cut by the quantised region's edge inside the frame is still refused."""
    p, n = _ellipse_map(h=160, cy=125.0)  # the box's bottom at 155, the window's at 185, the frame's at 160
    ii = _integral(p)
    assert object_area(ii, 0, 0, 1, (120.0, 125.0, 15.0, 30.0)) is None
    for f in (0.8, 1.0, 1.1):
        area, _ = object_area(ii, 0, 0, 1, (120.0, 125.0, 15.0 * f, 30.0 * f), frame=(240, 160))
        assert area == pytest.approx(n, rel=0.06)
    # the same map as a region quantised inside a larger frame: its edge is not the frame's
    assert object_area(ii, 0, 0, 1, (120.0, 125.0, 15.0, 30.0), frame=(240, 300)) is None
    # the compiled path and the reference agree
    from pftrack._numba import set_numba_enabled

    on = object_area(ii, 0, 0, 1, (120.0, 125.0, 15.0, 30.0), frame=(240, 160))
    before = set_numba_enabled(False)
    try:
        off = object_area(ii, 0, 0, 1, (120.0, 125.0, 15.0, 30.0), frame=(240, 160))
    finally:
        set_numba_enabled(before)
    assert off == pytest.approx(on, rel=1e-12)


def test_mass_factor_moves_by_a_share_of_the_ratio_in_log_scale_clipped():
    assert mass_factor((400.0, 20.0), 400.0, 20.0, 0.25) == 1.0
    assert mass_factor((400.0, 20.0), 400.0 * 1.1 ** 2, 20.0, 0.5) == pytest.approx(1.1 ** 0.5)
    assert mass_factor((400.0, 20.0), 4000.0, 20.0, 1.0) == pytest.approx(MAX_RATIO)
    assert mass_factor((400.0, 20.0), 4.0, 20.0, 0.5) == pytest.approx(MAX_RATIO ** -0.5)


def _sizes(tracker, scene: Scene) -> float:
    """The median of sqrt(box area / true area) over the second half of the frames."""
    frames, gt = scene.frames(), scene.groundtruth()
    tracker.init(frames[0], tuple(gt[0]))
    boxes = np.array([gt[0]] + [tracker.update(f).box for f in frames[1:]])
    late = slice(len(gt) // 2, None)
    return float(np.median(np.sqrt(boxes[late, 2] * boxes[late, 3] / (gt[late, 2] * gt[late, 3]))))


@pytest.mark.parametrize("seed", [7860, 7866])
def test_fusion_pf_keeps_an_elliptic_targets_size_with_mass_size(seed):
    """A two-coloured elliptic target of little texture wandering over a textured background (the simple scene's
    kind, seeds of neither split): its box shrinks without mass_size and keeps its size with it."""
    rng = np.random.default_rng(seed)
    tgt = Target(path=_wander(rng, 80, 320, 240, (30, 60), speed=2.0), size=(30, 60), texture=4.0)
    scene = Scene(SceneSpec(n_frames=80, seed=seed, targets=(tgt,)))
    plain = _sizes(create_tracker("fusion-pf", seed=0, mass_size=0), scene)
    mass = create_tracker("fusion-pf", seed=0, mass_size=0.25)
    with_mass = _sizes(mass, scene)
    assert plain < 0.8 and with_mass > 0.95
    assert mass._mass_ref is not None


def test_mass_size_off_reads_nothing():
    tgt = Target(path=((0, 100.0, 100.0), (19, 140.0, 100.0)), size=(30, 60))
    scene = Scene(SceneSpec(n_frames=20, seed=1, targets=(tgt,)))
    t = create_tracker("fusion-pf", seed=0, mass_size=0)
    _sizes(t, scene)
    assert t._mass_ref is None
    assert create_tracker("fusion-pf").params.mass_size == 0.1  # the default (docs/rules/mass_size_rule2.txt)


def test_the_mass_is_read_only_on_frames_the_models_learn_from(monkeypatch):
    """Not while the target is lost, nor on a frame the loss test doubts: a box off the target would read another
    area (the reading's frames are those whose state is confident, never a lost one)."""
    import pftrack.trackers.fusion_pf as fusion

    target = Target(path=((0, 80.0, 120.0), (59, 260.0, 120.0)), size=(26.0, 52.0), disappear=30)
    scene = Scene(SceneSpec(n_frames=60, seed=3, targets=(target,), kind="vanish"))
    frames, gt = scene.frames(), scene.groundtruth()
    read: list[int] = []
    real = fusion.object_area
    t = create_tracker("fusion-pf", seed=0, mass_size=0.25)
    monkeypatch.setattr(fusion, "object_area", lambda *a, **k: read.append(t.frame_index) or real(*a, **k))
    t.init(frames[0], tuple(gt[0]))
    lost = {t.frame_index for f in frames[1:] if t.update(f).lost}
    assert read and lost and not lost & set(read)


@pytest.mark.parametrize("seed", [0, 1])
def test_the_mass_alone_follows_a_growing_target(seed):
    """The particles' own scale frozen and the NCC size search off: the map's mass moves the box from the first
    size (34.6 px, sqrt of the area) most of the way to the target's 1.5 times (52.0; measured 48.6), at most
    1.25^0.1 a frame."""
    from .test_scale_search import _growing_scene

    frames, gt = _growing_scene(seed)
    t = create_tracker("fusion-pf", seed=seed, scale_search=0.0, scale_rate_noise=0.0)
    t.init(frames[0], gt[0])
    box = [t.update(f) for f in frames[1:]][-1].box
    size, true = math.sqrt(box[2] * box[3]), math.sqrt(gt[-1, 2] * gt[-1, 3])
    assert 0.85 * true < size < 1.05 * true


def test_the_compiled_reading_gives_the_reference_numbers():
    from pftrack._numba import set_numba_enabled

    rng = np.random.default_rng(5)
    p, _ = _ellipse_map()
    ii = _integral(p)
    cases = [(120.0, 100.0, 15.0, 30.0), (20.0, 100.0, 15.0, 30.0), (120.0, 100.0, 0.0, 30.0)]
    cases += [tuple(v) for v in np.c_[rng.uniform(0, 240, 60), rng.uniform(0, 200, 60), rng.uniform(3, 40, (60, 2))]]
    for x0, y0, pitch, gate in ((0, 0, 1, 0.8), (7, 3, 2, 0.3), (0, 0, 3, 0.0)):
        compiled = [object_area(ii, x0, y0, pitch, e, gate=gate) for e in cases]
        previous = set_numba_enabled(False)
        try:
            reference = [object_area(ii, x0, y0, pitch, e, gate=gate) for e in cases]
        finally:
            set_numba_enabled(previous)
        assert compiled == reference
        assert any(r is not None for r in reference) and any(r is None for r in reference)
