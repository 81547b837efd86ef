"""The background-aware contrast cue and fusion-pf."""

import numpy as np
import pytest

import pftrack
from pftrack._numba import NUMBA_INSTALLED
from pftrack.cues.contrast import box_counts, contrast_scores, foreground_lut, probability_integral
from pftrack.geometry import iou
from pftrack.synth import SceneSpec, Target, occlusion_scene, simple_scene

from .conftest import grey_frames, render_scene


def test_foreground_lut():
    lut = foreground_lut(np.array([3.0, 0.0, 1.0, 0.0]), np.array([1.0, 2.0, 1.0, 0.0]))
    assert lut.tolist() == pytest.approx([0.75, 0.0, 0.5, 0.5])


def test_box_counts_inside_and_ring():
    bins = np.zeros((10, 10), np.uint16)
    bins[4:6, 4:6] = 1  # a 2x2 object of colour 1 on colour 0
    inside, ring = box_counts(bins, 0, 0, (4, 4, 2, 2), 2, ring=0.5)
    assert inside.tolist() == [0, 4] and ring.tolist() == [12, 0]  # 4x4 outer box minus the 2x2


def test_contrast_peaks_on_the_object_box_in_position_and_scale():
    bins = np.zeros((100, 100), np.uint16)
    bins[30:70, 40:60] = 1  # object: 20 wide, 40 high at (40, 30)
    lut = foreground_lut(np.array([0.0, 800.0]), np.array([1200.0, 0.0]))
    ii = probability_integral(bins, lut)
    true = np.array([40.0, 30.0, 20.0, 40.0])
    cands = [true, true + [5, 0, 0, 0], true + [0, -6, 0, 0], true * [1, 1, 1.4, 1.4] - [4, 8, 0, 0],
             true * [1, 1, 0.6, 0.6] + [4, 8, 0, 0]]
    c = contrast_scores(ii, 0, 0, np.array(cands), ring=0.5)
    assert int(np.argmax(c)) == 0 and c[0] == pytest.approx(1.0)
    assert c[3] < c[0] and c[4] < c[0]  # too large and too small both lose: the cue observes scale


@pytest.mark.skipif(not NUMBA_INSTALLED, reason="numba not installed")
def test_contrast_kernels_match_reference(rng):
    from pftrack._numba import set_numba_enabled

    bins = rng.integers(0, 512, (60, 90)).astype(np.uint16)
    lut = rng.random(512).astype(np.float32)
    boxes = np.column_stack([rng.uniform(-20, 100, 80), rng.uniform(-20, 70, 80), rng.uniform(1, 40, 80),
                             rng.uniform(1, 40, 80)])
    out = {}
    for flag in (True, False):
        prev = set_numba_enabled(flag)
        try:
            ii = probability_integral(bins, lut)
            out[flag] = (ii, contrast_scores(ii, 3, 4, boxes, ring=0.5, pitch=2))
        finally:
            set_numba_enabled(prev)
    assert np.allclose(out[True][0], out[False][0], atol=1e-9)
    assert np.allclose(out[True][1], out[False][1], atol=1e-12)


@pytest.mark.skipif(not NUMBA_INSTALLED, reason="numba not installed")
def test_compiled_counts_and_ellipse_contrast_equal_the_numpy_paths(rng):
    """The one-pass object/surround counts and the contrast of ellipses give exactly the NumPy paths' numbers."""
    from pftrack._numba import set_numba_enabled
    from pftrack.cues.contrast import contrast_scores_ellipses
    from pftrack.geometry import ellipse_to_box

    bins = rng.integers(0, 512, (60, 90)).astype(np.uint16)
    ii = probability_integral(bins, rng.random(512).astype(np.float32))
    ell = np.column_stack([rng.uniform(-10, 200, 60), rng.uniform(-10, 140, 60), rng.uniform(1, 30, 60),
                           rng.uniform(1, 30, 60)])
    fast = contrast_scores_ellipses(ii, 5, 7, ell, ring=0.5, pitch=2)
    assert np.array_equal(fast, contrast_scores(ii, 5, 7, ellipse_to_box(ell), ring=0.5, pitch=2))
    boxes = [(10.3, 8.7, 31.2, 22.9), (-5.0, -3.0, 20.0, 18.0), (150.0, 100.0, 60.0, 60.0), (40.0, 30.0, 0.5, 0.5)]
    for box in boxes:
        compiled = box_counts(bins, 3, 4, box, 512, ring=0.5, pitch=2)
        prev = set_numba_enabled(False)
        try:
            ref = box_counts(bins, 3, 4, box, 512, ring=0.5, pitch=2)
        finally:
            set_numba_enabled(prev)
        assert np.array_equal(compiled[0], ref[0]) and np.array_equal(compiled[1], ref[1]), box


def run(name, spec, seed=0, **params):
    scene, frames, _ = render_scene(spec)
    gt = scene.groundtruth(0)
    tr = pftrack.create_tracker(name, seed=seed, **params)
    states = [tr.init(frames[0], gt[0])] + [tr.update(f) for f in frames[1:]]
    return gt, np.array([s.box for s in states]), states


def zoom_scene(seed):
    rng = np.random.default_rng(seed)
    path = ((0, 120.0, 120.0 + rng.uniform(-10, 10)), (79, 200.0, 120.0))
    return SceneSpec(n_frames=80, seed=seed, targets=(Target(path=path, size=(20, 40), scale_rate=0.006),))


def test_fusion_follows_a_growing_target_better_than_color_pf():
    ious = {"fusion-pf": [], "color-pf": []}
    for seed in range(3):
        for name in ious:
            gt, boxes, _ = run(name, zoom_scene(seed), seed)
            ious[name].append(iou(boxes, gt)[-20:].mean())  # the target is 1.6x its first size by then
    assert np.mean(ious["fusion-pf"]) > 0.45
    assert np.mean(ious["fusion-pf"]) > np.mean(ious["color-pf"])


def test_fusion_tracks_simple_scenes():
    # mean IoU per seed measured 0.67-0.92 (mean 0.82); one seed alone is too noisy a bound. (Seed 1's box shrinks
    # from 30 x 60 to 23 x 46 px, with or without the size search: the structural cue scores the target's inside
    # against a moving background better than its border; 0.73 without the search, 0.67 with it.)
    ious = [iou(b, g).mean() for g, b, _ in (run("fusion-pf", simple_scene(s), s) for s in range(6))]
    assert np.mean(ious) > 0.75, ious
    assert min(ious) > 0.62, ious


@pytest.mark.parametrize("seed", [0, 1])
def test_fusion_tracks_and_reports_loss(seed):
    gt, boxes, states = run("fusion-pf", occlusion_scene(seed, full=True), seed)
    assert any(s.lost for s in states) and not states[-1].lost
    assert iou(boxes[-10:], gt[-10:]).mean() > 0.5


def test_fusion_is_the_default_tracker(capsys):
    from pftrack.cli import DEFAULT_TRACKER, main

    assert DEFAULT_TRACKER == "fusion-pf"
    assert main(["list", "fusion-pf"]) == 0
    assert "contrast_gain" in capsys.readouterr().out


def _disc_integral(hx=30.0, hy=50.0, size=200):
    yy, xx = np.mgrid[0:size, 0:size]
    p = (((xx + 0.5 - size / 2) / hx) ** 2 + ((yy + 0.5 - size / 2) / hy) ** 2 <= 1).astype(np.float64)
    ii = np.zeros((size + 1, size + 1))
    ii[1:, 1:] = p.cumsum(0).cumsum(1)
    return ii, p


def test_elliptic_contrast_peaks_near_the_true_size_where_the_box_contrast_shrinks():
    """An elliptic object of probability 1 on 0: the box contrast peaks at 0.8-0.85 of the size (the box's corners
    are background), the elliptic one and the ellipse against the box's ring within 5 % of it (docs/robustness.md)."""
    from pftrack.cues.contrast import _strips_sum, contrast_scores_ellipses

    ii, p = _disc_integral()
    scales = np.linspace(0.6, 1.4, 33)
    ell = np.array([[100.0, 100.0, 30.0 * a, 50.0 * a] for a in scales])
    box = contrast_scores_ellipses(ii, 0, 0, ell, ring=0.5)
    elliptic = contrast_scores_ellipses(ii, 0, 0, ell, ring=0.5, shape="ellipse")
    assert 0.78 <= scales[np.argmax(box)] <= 0.88
    assert 0.94 <= scales[np.argmax(elliptic)] <= 1.05
    in_box = contrast_scores_ellipses(ii, 0, 0, ell, ring=0.5, shape="ellipse-box")
    assert 0.94 <= scales[np.argmax(in_box)] <= 1.05  # the ellipse against the box's ring: the corners in neither
    s, a = _strips_sum(ii, 100.0, 100.0, 30.0, 50.0, 8, 0.5)
    assert abs(a - np.pi * 30 * 50) < 0.05 * np.pi * 30 * 50 and s / a > 0.95  # the strips cover the ellipse
    with pytest.raises(ValueError, match="shape"):
        contrast_scores_ellipses(ii, 0, 0, ell, shape="circle")


def test_contrast_shape_is_an_option_of_fusion_pf():
    assert pftrack.create_tracker("fusion-pf", contrast_shape="ellipse-box").params.contrast_shape == "ellipse-box"
    t = pftrack.create_tracker("fusion-pf", contrast_shape="ellipse")
    assert t.params.contrast_shape == "ellipse" and pftrack.create_tracker("fusion-pf").params.contrast_shape == "box"
    with pytest.raises(pftrack.ParameterError):
        pftrack.create_tracker("fusion-pf", contrast_shape="circle")


def test_velocity_step_carries_the_samples_past_a_look_alike():
    """Two identical targets swing past each other, the one in front hiding the other (the waving scene): with
    velocity_step the samples keep the target's motion through each crossing instead of following the look-alike."""
    from pftrack.synth import waving_scene

    plain, stepped = [], []
    for seed in range(3):
        spec = waving_scene(seed)
        gt, boxes, _ = run("fusion-pf", spec)
        plain.append(iou(boxes, gt).mean())
        gt, boxes, _ = run("fusion-pf", spec, velocity_step=0.25, velocity_noise=0.0)
        stepped.append(iou(boxes, gt).mean())
    assert min(stepped) > 0.7 and max(plain) < 0.5


def test_grey_velocity_settings_keep_grey_input_on_the_former_dynamics():
    """grey_velocity_step and grey_velocity_noise apply on grey input only: with them at fusion-pf's former values,
    grey frames give the default's boxes, colour frames the option's."""
    spec = simple_scene(2)
    scene, frames, _ = render_scene(spec)
    gt = scene.groundtruth(0)
    opts = dict(velocity_step=0.25, velocity_noise=0.0)
    keep = dict(opts, grey_velocity_step=0.0, grey_velocity_noise=0.025)

    def boxes(fr, **params):
        tr = pftrack.create_tracker("fusion-pf", seed=0, **params)
        return np.array([tr.init(fr[0], gt[0]).box] + [tr.update(f).box for f in fr[1:]])

    grey = grey_frames(frames)
    np.testing.assert_array_equal(boxes(grey, **keep), boxes(grey))
    assert not np.array_equal(boxes(grey, **opts), boxes(grey))
    np.testing.assert_array_equal(boxes(frames, **keep), boxes(frames, **opts))
    assert not np.array_equal(boxes(frames, **opts), boxes(frames))
