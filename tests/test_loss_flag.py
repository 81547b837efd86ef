"""The lost flag as a detector (GUIDE §8): the loss test, grey input, and bounds over varied scenes."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.cues.histogram_cue import ColorCue
from pftrack.cues.intensity import equalization_lut, is_gray, quantize_gray
from pftrack.eval.metrics import lost_detection
from pftrack.filtering.loss import (FusedLoss, LossDetector, absent_distribution, confidence, score_llr,
                                    toward_background)
from pftrack.geometry import displacement_rate, iou
from pftrack.synth import Scene, hidden_frames, leave_scene, vanish_scene, varied_scene
from pftrack.synth.scenes import SceneSpec, Target

from .conftest import lost_flag_run


# ------------------------------------------------------------------------------ pure functions

def test_llr_is_monotone_and_clamped():
    s = np.linspace(0.0, 1.0, 101)
    llr = np.array([score_llr(v, 0.9, 0.05, 0.4, 0.1) for v in s])
    assert np.all(np.diff(llr) >= -1e-12)
    assert llr[0] == llr[40] and llr[-1] == llr[90]  # clamped outside [mu_b, mu_t]
    assert score_llr(0.95, 0.5, 0.05, 0.6, 0.1) == 0.0  # a history that does not beat the background
    assert confidence(0.0) == 0.5


def test_absent_distribution_is_the_upper_tail():
    rng = np.random.default_rng(0)
    bg = rng.normal(0.3, 0.05, 400)
    mu, sd = absent_distribution(bg, tail=0.1, sd_floor=0.03)
    assert mu > np.percentile(bg, 85) and sd >= 0.03


def test_detector_hysteresis_and_history():
    det = LossDetector(lost_frames=3)
    det.reset(1.0)
    det.set_background(np.random.default_rng(1).normal(0.3, 0.05, 200))
    for _ in range(30):
        lost, conf = det.step(0.92)
        assert not lost and conf > 0.99
    assert abs(det.mu_t - 0.92) < 0.03  # the history followed the confident scores
    lost = [det.step(0.45)[0] for _ in range(3)]
    assert lost == [False, False, True]  # lost after lost_frames frames of absence evidence
    assert det.mu_t > 0.85  # the absent scores were not learned
    assert not det.acquire(0.55)  # clutter does not end the loss
    assert det.acquire(0.91)  # the target does


def test_lost_detection_metric_counts_both_directions():
    gt = np.tile([10.0, 10.0, 20.0, 20.0], (10, 1))
    pred = gt.copy()
    absent = np.zeros(10, bool)
    absent[4:7] = True
    lost = np.zeros(10, bool)
    lost[[4, 5, 8]] = True  # 2 of 3 absent frames flagged; one false alarm on a covered frame
    r = lost_detection(lost, pred, gt, absent)
    assert r.recall == pytest.approx(2 / 3)
    assert r.false_rate == pytest.approx(1 / 7)
    assert (r.reappearances, r.reacquired) == (1, 1)
    r2 = lost_detection(np.ones(10, bool), pred, gt, absent)
    assert (r2.reappearances, r2.reacquired) == (1, 0)  # never un-lost: not re-acquired


# ------------------------------------------------------------------------------ grey features

def test_grey_frames_are_detected_and_get_grey_features():
    rng = np.random.default_rng(0)
    g = rng.integers(0, 256, (60, 80), dtype=np.uint8)
    grey = np.repeat(g[..., None], 3, axis=2)
    colour = rng.integers(0, 256, (60, 80, 3), dtype=np.uint8)
    assert is_gray(grey) and is_gray(g) and not is_gray(colour)
    cue = ColorCue("auto")
    assert cue.adapt_to(grey) == "gray" and cue.n_bins == 16 * 9
    assert cue.adapt_to(colour) == "rgb" and cue.n_bins == 512


def test_strided_lattice_copy_equals_numpy_slicing(rng):
    from pftrack.cues.intensity import _lattice

    for f in [rng.integers(0, 256, (97, 131, 3), dtype=np.uint8), rng.integers(0, 256, (40, 41), dtype=np.uint8)]:
        for stride in (1, 2, 3, 4, 7):
            assert np.array_equal(_lattice(f, stride), f[::stride, ::stride])


@pytest.mark.parametrize("pitch, size", [(5, (97, 131)), (8, (97, 131)), (11, (97, 131)), (4, (364, 380))])
def test_grey_features_from_lattice_neighbourhoods_equal_the_whole_region(rng, pitch, size):
    """From pitch 5 on (4 on large regions), the grey features are computed on the lattice points' 3x3
    neighbourhoods only: the same bins as the whole-region computation, at the frame's edges and past them."""

    import pftrack.cues.intensity as it

    h, w = size
    frames = [rng.integers(0, 256, (h, w, 3), dtype=np.uint8),
              cv2.GaussianBlur(rng.integers(0, 256, (h, w, 3), dtype=np.uint8), (9, 9), 3)]
    frames.append(np.repeat(frames[1][..., :1], 3, axis=2))  # grey input
    frames.append(np.ascontiguousarray(frames[1][..., 0]))  # one channel
    lut = equalization_lut(frames[1])
    kw = dict(n_intensity=16, n_orientation=8, gradient_threshold=40.0)
    for f in frames:
        for roi in [(0, 0, w, h), (0, 0, w + 19, h + 23), (pitch, 2 * pitch, w - 41, h - 37), (3 * pitch, pitch, w, h)]:
            got = quantize_gray(f, roi, pitch, lut, **kw)
            previous = it._NEIGHBOURHOOD_PITCH
            it._NEIGHBOURHOOD_PITCH = 10 ** 9  # the whole-region computation
            try:
                expected = quantize_gray(f, roi, pitch, lut, **kw)
            finally:
                it._NEIGHBOURHOOD_PITCH = previous
            assert got.shape == expected.shape and np.array_equal(got, expected), roi


@pytest.mark.parametrize("shape", [(1, 1), (2, 7), (7, 2), (3, 3), (61, 83), (170, 150)])
def test_the_grey_gradients_are_the_float_sobel_filters(shape):
    """One spatialGradient pass gives the numbers of the two float 3x3 Sobel filters (replicated border)."""
    from pftrack.cues.intensity import _sobel3

    g = cv2.GaussianBlur(np.random.default_rng(shape[0]).integers(0, 256, shape, dtype=np.uint8), (0, 0), 1.0)
    dx, dy = _sobel3(g)
    assert dx.dtype == np.int16 and dy.dtype == np.int16
    ex = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3, borderType=cv2.BORDER_REPLICATE)
    ey = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3, borderType=cv2.BORDER_REPLICATE)
    assert np.array_equal(dx.astype(np.float32), ex) and np.array_equal(dy.astype(np.float32), ey)


def test_grey_features_ignore_a_global_gain():
    """Equalised intensity x orientation: a monotonic brightness change leaves the bins nearly unchanged."""
    rng = np.random.default_rng(3)
    base = (rng.random((80, 100)) * 120 + 40).astype(np.float32)
    base = np.clip(base + 60 * (np.arange(100)[None, :] > 50), 0, 255)
    a = base.astype(np.uint8)
    b = np.clip(base * 0.55, 0, 255).astype(np.uint8)
    qa = quantize_gray(a, (0, 0, 100, 80), 1, equalization_lut(a), n_intensity=16, n_orientation=8,
                       gradient_threshold=40)
    qb = quantize_gray(b, (0, 0, 100, 80), 1, equalization_lut(b), n_intensity=16, n_orientation=8,
                       gradient_threshold=40)
    ha = np.bincount(qa.ravel(), minlength=144) / qa.size
    hb = np.bincount(qb.ravel(), minlength=144) / qb.size
    assert np.sum(np.sqrt(ha * hb)) > 0.9  # Bhattacharyya coefficient of the two frames' histograms


@pytest.mark.parametrize("tracker", ["color-pf", "fusion-pf"])
def test_grey_input_tracking_on_varied_scenes(tracker):
    """Grey versions of varied scenes (distractors, light) are tracked, and not flagged lost."""
    ious, lost = [], []
    for seed in range(5):
        spec = varied_scene(seed, n_frames=60, gray=1.0)
        scene = Scene(spec)
        gt = scene.groundtruth(0)
        t = pftrack.create_tracker(tracker, seed=seed)
        frame, _ = scene.render(0)
        assert is_gray(frame)
        t.init(frame, tuple(gt[0]))
        for k in range(1, spec.n_frames):
            st = t.update(scene.render(k)[0])
            ious.append(iou(np.array([st.box]), gt[k:k + 1])[0])
            lost.append(st.lost)
    assert np.mean(ious) > 0.5, np.mean(ious)
    assert np.mean(lost) < 0.1


# ------------------------------------------------------------------------------ the flag over varied scenes

def test_lost_flag_recall_and_false_alarms_over_vanish_scenes():
    """Over 6 seeds of varied vanish scenes (grey or colour, light, similar-hued distractors)."""
    res = [lost_flag_run(vanish_scene(seed), seed=seed) for seed in range(200, 206)]
    recall = np.nanmean([r.recall for r in res])
    false = np.nanmean([r.false_rate for r in res])
    assert recall >= 0.6, recall  # measured 0.77 (the paper's appearance test: 0.13)
    assert false <= 0.1, false


def test_lost_flag_on_a_target_leaving_the_frame():
    res = [lost_flag_run(leave_scene(seed), seed=seed) for seed in range(200, 205)]
    recall = np.nanmean([r.recall for r in res])
    false = np.nanmean([r.false_rate for r in res])
    assert recall >= 0.7, recall
    assert false <= 0.15, false  # measured 0.10 on these seeds (the paper's test: 0.16)
    assert all(math.isfinite(r.recall) for r in res)


def test_gain_normalisation_undoes_a_per_channel_light_change():
    """'gain'/'adaptive' RGB normalisation: a frame under a coloured light change gets the reference bins back."""
    rng = np.random.default_rng(5)
    ref = rng.integers(30, 160, (60, 80, 3), dtype=np.uint8)
    lit = np.clip(ref.astype(np.float64) * np.array([1.4, 0.8, 1.2]), 0, 255).astype(np.uint8)
    for mode in ("gain", "adaptive"):
        cue = ColorCue("rgb", normalize=mode)
        cue.adapt_to(ref)
        cue.new_frame(ref)
        a = cue.prepare_frame(ref).bins.copy()
        cue.new_frame(lit)
        b = cue.prepare_frame(lit).bins
        assert np.mean(a == b) > 0.9, mode
    raw = ColorCue("rgb")
    raw.new_frame(lit)
    assert np.mean(raw.prepare_frame(lit).bins == a) < 0.5


def test_adaptive_reference_follows_confident_frames_only():
    rng = np.random.default_rng(6)
    f0 = rng.integers(30, 160, (40, 40, 3), dtype=np.uint8)
    f1 = np.clip(f0 * 1.5, 0, 255).astype(np.uint8)
    cue = ColorCue("rgb", normalize="adaptive")
    cue.adapt_to(f0)
    cue.new_frame(f1)
    before = cue._ref_levels.copy()
    cue.confirm(0.5)
    assert np.all(cue._ref_levels > before)  # moved half-way towards the new light


def test_short_median_equals_numpys():
    """The background statistics' median (sort-based, for about a hundred scores) is np.median's number."""
    from pftrack.filtering.loss import _median

    rng = np.random.default_rng(3)
    for n in (1, 2, 3, 8, 99, 100, 101):
        for _ in range(20):
            x = np.round(rng.random(n), int(rng.integers(1, 6)))
            assert _median(x) == float(np.median(x))


def test_in_frame_fraction():
    from pftrack.geometry import in_frame_fraction

    f = [in_frame_fraction(b, 320, 240)
         for b in ([-10, 0, 20, 10], [0, 0, 5, 5], [310, 230, 20, 20], [400, 0, 10, 10], [0, 0, 0, 0])]
    np.testing.assert_allclose(f, [0.5, 1.0, 0.25, 0.0, 0.0])


def test_out_of_view_is_reported_absent_without_searching():
    """min_in_frame: a target walking out is reported lost while its box is mostly outside, and tracked on."""
    from pftrack.geometry import in_frame_fraction

    spec = leave_scene(201)
    scene = Scene(spec)
    gt = scene.groundtruth(0)
    h, w = scene.render(0)[0].shape[:2]
    runs = {}
    for m in (0.0, 0.4):
        t = pftrack.create_tracker("color-pf", seed=0, min_in_frame=m)
        t.init(scene.render(0)[0], tuple(gt[0]))
        runs[m] = [t.update(scene.render(k)[0]) for k in range(1, spec.n_frames)]
    flagged = 0
    for st in runs[0.4]:
        if st.info.get("mode") == "tracking" and in_frame_fraction(st.box, w, h) < 0.4:
            assert st.lost and st.score <= 0.5 and st.info["out_of_view"]
            flagged += 1
    assert flagged > 0  # the scene takes the box across the border
    hid = hidden_frames(spec)[1:]
    rec = {m: np.mean([s.lost for s, a in zip(r, hid) if a]) for m, r in runs.items()}
    assert rec[0.4] >= rec[0.0]


def test_acquire_adds_the_position_log_prior():
    det = LossDetector(lost_frames=3)
    det.reset(1.0)
    det.set_background(np.random.default_rng(1).normal(0.3, 0.05, 200))
    for _ in range(30):
        det.step(0.92)
    s = 0.9  # a candidate that ends the loss on its own evidence ...
    assert det.evaluate(s) > det.reacquire_margin + 0.5
    llr = det.evaluate(s)
    assert not det.acquire(s, log_prior=-(llr - det.reacquire_margin) - 0.1)  # ... but not far from the prediction
    assert det.llr == pytest.approx(llr - (llr - det.reacquire_margin) - 0.1)
    assert det.acquire(s)


def _trained(**kw) -> LossDetector:
    """A detector that has learned a target at 0.92 against a background at 0.3 (spread 0.05)."""
    det = LossDetector(lost_frames=3, **kw)
    det.reset(1.0)
    det.set_background(np.random.default_rng(1).normal(0.3, 0.05, 200))
    for _ in range(30):
        det.step(0.92)
    return det


def test_acquire_z_widens_the_acquisition_bound_only():
    """``acquire_z`` (color-pf's ``reacquire_z``): a candidate far above the background but between 2 and 3 spreads
    below the history re-acquires with the bound 3, not with the learning bound 2; learning keeps 2."""
    det = _trained()
    s = det.mu_t - 2.5 * det.sd_t
    assert det.evaluate(s) > det.reacquire_margin
    assert not det.would_acquire(s)[0] and not det.acquire(s)
    wide = _trained(acquire_z=3.0)
    assert wide.would_acquire(s)[0] and wide.acquire(s)
    assert not wide.confident(s)  # the update gate and the learning still use learn_z
    assert not wide.acquire(wide.mu_t - 3.5 * wide.sd_t)


def test_acquire_llr_waives_the_history_bound_for_a_strong_ratio_only():
    """``acquire_llr`` (color-pf's ``reacquire_llr``): a candidate whose ratio reaches it re-acquires however far
    below the history it lies; a weaker one is still held to the bound, and learning is unchanged."""
    det = _trained()
    far = det.mu_t - 5.0 * det.sd_t  # well above the background: a strong ratio
    llr = det.evaluate(far)
    assert llr > 5.0 and not det.would_acquire(far)[0]
    assert _trained(acquire_llr=llr + 1.0).would_acquire(far)[0] is False
    strong = _trained(acquire_llr=llr - 1.0)
    assert strong.would_acquire(far)[0] and not strong.confident(far, llr=llr)
    assert strong.acquire(far) and not strong.lost


@pytest.mark.parametrize("name, v", [("color-pf", 20.0), ("fusion-pf", 0.0), ("local-motion-pf", 0.0)])
def test_reacquire_llr_defaults(name, v):
    tracker = pftrack.create_tracker(name)
    assert tracker.params.reacquire_llr == v
    assert getattr(tracker.loss, "acquire_llr", 0.0) == v


@pytest.mark.parametrize("name, z", [("color-pf", 0.0), ("fusion-pf", 0.0), ("local-motion-pf", 0.0)])
def test_reacquire_z_defaults(name, z):
    assert pftrack.create_tracker(name).params.reacquire_z == z


def test_search_position_prior_penalises_only_far_candidates():
    """fusion-pf's search_prior: log((1 - e) A N(x; m, s^2) + e), capped at 0: 0 at the prediction, log(e) far."""
    t = pftrack.create_tracker("fusion-pf", seed=0)
    frame = np.zeros((240, 320, 3), np.uint8)
    frame[100:140, 100:120] = (0, 0, 200)
    t.init(frame, (100, 100, 20, 40))
    t.frame_index = 10
    t._lost_at = (6, np.array([110.0, 120.0]), np.array([2.0, 0.0]))  # lost 4 frames ago, moving right
    states = np.zeros((3, t.dim))
    states[:, :2] = [[118.0, 120.0], [300.0, 20.0], [130.0, 120.0]]
    lp = t._position_log_prior(states)
    assert lp[0] == 0.0  # at the prediction (110 + 4 * 2, 120)
    assert lp[1] == pytest.approx(math.log(t.params.search_prior), abs=1e-6)  # far away: log e
    assert math.log(t.params.search_prior) < lp[2] <= 0.0
    off = pftrack.create_tracker("color-pf", seed=0)
    off.init(frame, (100, 100, 20, 40))
    off._lost_at = t._lost_at
    assert off._position_log_prior(states) is None  # color-pf: off by default


def test_llr_is_zero_when_the_means_do_not_separate_for_their_spreads():
    # a camouflaged target: its history barely above the background's tail, its spread the wider
    assert score_llr(0.99, 0.99, 0.05, 0.98, 0.02) == 0.0
    assert score_llr(0.5, 0.99, 0.05, 0.98, 0.02) == 0.0
    # separated means keep the ratio's sign change between them
    assert score_llr(0.9, 0.9, 0.05, 0.5, 0.1) > 0 > score_llr(0.5, 0.9, 0.05, 0.5, 0.1)


def test_color_pf_does_not_call_a_camouflaged_target_lost():
    """A target drawn in the background's colours: the colour cannot tell, so the flag stays down (no evidence)."""
    from pftrack.synth import camouflage_scene

    res = [lost_flag_run(camouflage_scene(seed), seed=seed) for seed in (200, 201)]
    assert max(r.false_rate for r in res) <= 0.05, [r.false_rate for r in res]


def test_relit_search_reacquires_a_target_whose_light_changed_while_hidden():
    """color-pf's relit_search: a global light change while the target is hidden (fresh colour vanish scenes)."""
    specs = [vanish_scene(seed, gray=0.0, illumination=1.0, distractors=(0, 1)) for seed in (202, 204, 205, 206)]
    assert not any(dict(s.nuisances)["illumination_target_only"] for s in specs)
    got = {m: sum(lost_flag_run(s, seed=200 + i, relit_search=m).reacquired for i, s in enumerate(specs))
           for m in ("off", "max")}
    # measured 4 against 0 (scenes 200-215 with their own seed as run seed: 9 of 10 against 2)
    assert got["max"] >= 3 and got["max"] > got["off"], got


def test_displacement_rate():
    assert displacement_rate([]) == (0.0, 0.0)
    assert displacement_rate([(3, 10.0, 5.0)]) == (0.0, 0.0)
    assert displacement_rate([(3, 10.0, 5.0), (4, 18.0, 4.0), (7, 42.0, 1.0)]) == (8.0, -1.0)


def _exit_scene(seed: int) -> SceneSpec:
    """The target walks out through the right edge and stays out; its twin (same colours) stands in the left half."""
    twin_x = 80.0 + 10.0 * seed
    target = Target(path=((0, 230.0, 120.0), (30, 360.0, 120.0)), size=(26.0, 52.0))
    twin = Target(path=((0, twin_x, 150.0),), size=(26.0, 52.0))
    return SceneSpec(n_frames=70, seed=seed, targets=(target, twin), background="flat", kind="exit")


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_target_that_left_the_view_is_not_replaced_by_its_twin_inside(seed):
    """reenter_border: after the exit, the search may only re-acquire near the right edge (a strip that widens at
    the target's speed, about 5 px per frame here, from the start of the search, as the target leaves: it reaches the
    twin after about 35 frames), so the twin is not taken for the target in the 20 frames after the exit (it is
    without the rule)."""
    scene = Scene(_exit_scene(seed))
    frames = scene.frames()
    gt = scene.groundtruth()
    runs = {}
    for border in (0.0, 1.0):  # the rule alone: the still twin is also the scene's (static_ncc)
        t = pftrack.create_tracker("color-pf", seed=seed, reenter_border=border, static_ncc=0.0)
        t.init(frames[0], tuple(gt[0]))
        runs[border] = [t.update(f) for f in frames[1:]]
    gone = [s for k, s in enumerate(runs[1.0], start=1) if 30 <= k <= 50]  # the target is out of view from frame 27
    assert all(s.lost for s in gone)
    twin_box = scene.groundtruth(target=1)
    taken = [iou(s.box, twin_box[k]) > 0.5 and not s.lost for k, s in enumerate(runs[0.0], start=1) if k >= 30]
    assert any(taken)  # without the rule the twin is acquired


def test_exit_band_is_the_strip_along_the_edge_left_through():
    t = pftrack.create_tracker("color-pf", seed=0)
    frame = np.zeros((240, 320, 3), np.uint8)
    frame[100:140, 100:120] = (0, 0, 200)
    t.init(frame, (100, 100, 20, 40))
    hx, hy = t.size
    t.frame_index = t._search_since = 20
    t._lost_at = (16, np.array([310.0, 120.0]), np.zeros(2))
    t._exit_velocity = (6.0, 0.0)  # predicted at 334: out through the right edge
    band = t._exit_band()
    np.testing.assert_allclose(band, [[320 - 3 * hx, 0.0, 3 * hx, 240.0]])
    states = np.zeros((3, t.dim))
    states[:, :2] = [[318.0, 50.0], [330.0, 200.0], [150.0, 120.0]]  # in the strip, beyond the edge, inside
    np.testing.assert_array_equal(t._position_log_prior(states), [0.0, 0.0, -np.inf])
    t.frame_index = 30  # ten frames later the target could have walked 60 px in
    np.testing.assert_allclose(t._exit_band()[0, 2], 3 * hx + 60.0)
    t._exit_velocity = (0.5, 0.0)  # slowly: predicted over half inside, not an exit
    assert t._exit_band() is None
    t.frame_index = 20
    t._exit_velocity = (0.0, -40.0)  # up and out through the top
    np.testing.assert_allclose(t._exit_band(), [[0.0, 0.0, 320.0, 3 * hy]])


@pytest.mark.parametrize("grow, width", [(0.0, 0.0), (0.5, 30.0), (1.0, 60.0)])
def test_the_exit_strip_widens_at_reenter_grow_times_the_exit_speed(grow, width):
    t = pftrack.create_tracker("color-pf", seed=0, reenter_grow=grow)
    frame = np.zeros((240, 320, 3), np.uint8)
    frame[100:140, 100:120] = (0, 0, 200)
    t.init(frame, (100, 100, 20, 40))
    hx = t.size[0]
    t.frame_index, t._search_since = 30, 20  # ten frames into the search, the target left at 6 px a frame
    t._lost_at = (16, np.array([310.0, 120.0]), np.zeros(2))
    t._exit_velocity = (6.0, 0.0)
    np.testing.assert_allclose(t._exit_band()[0, 2], 3 * hx + width)


def _flow_scene(seed: int) -> SceneSpec:
    """The target walks out through the right edge; its twin (same colours) follows at the same speed, 170 px
    behind, and leaves too."""
    target = Target(path=((0, 230.0, 120.0), (30, 360.0, 120.0)), size=(26.0, 52.0))
    twin = Target(path=((0, 60.0 - 4.0 * seed, 150.0), (70, 363.0 - 4.0 * seed, 150.0)), size=(26.0, 52.0))
    return SceneSpec(n_frames=70, seed=seed, targets=(target, twin), background="flat", kind="exit")


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_look_alike_heading_out_through_the_exit_edge_is_not_acquired(seed):
    """reenter_outward: the exit strip widens until it covers the twin walking the target's way (about 12 frames
    after the exit); a candidate moving out through the edge the target left by is not the target coming back.
    Without the rule the twin is acquired there."""
    scene = Scene(_flow_scene(seed))
    frames = scene.frames()
    gt = scene.groundtruth()
    twin_box = scene.groundtruth(target=1)
    runs = {}
    for k_out in (0.0, 0.5):
        t = pftrack.create_tracker("color-pf", seed=seed, reenter_outward=k_out)
        t.init(frames[0], tuple(gt[0]))
        runs[k_out] = [t.update(f) for f in frames[1:]]
    assert all(s.lost for k, s in enumerate(runs[0.5], start=1) if k >= 30)
    assert any(s.info.get("vetoed") for s in runs[0.5])
    taken = [iou(s.box, twin_box[k]) > 0.5 and not s.lost for k, s in enumerate(runs[0.0], start=1) if k >= 30]
    assert any(taken)


def test_patch_shift_recovers_a_shift_and_refuses_a_flat_patch():

    from pftrack.cues.template import patch_shift

    rng = np.random.default_rng(4)
    base = cv2.GaussianBlur((rng.random((60, 80)) * 255).astype(np.float32), (0, 0), 1.5)
    prev = np.full((240, 320), 128.0, np.float32)
    cur = prev.copy()
    prev[100:160, 100:180] = base
    cur[98:158, 105:185] = base  # moved by (+5, -2)
    d = patch_shift(prev.astype(np.uint8), cur.astype(np.uint8), (115.0, 108.0, 50.0, 40.0), 8)
    np.testing.assert_allclose(d, [5.0, -2.0], atol=0.3)
    # the box half outside the frame: its in-frame part is matched
    prev2, cur2 = np.roll(prev, 200, axis=1), np.roll(cur, 200, axis=1)
    d = patch_shift(prev2.astype(np.uint8), cur2.astype(np.uint8), (300.0, 108.0, 50.0, 40.0), 8)
    np.testing.assert_allclose(d, [5.0, -2.0], atol=0.3)
    flat = np.full((240, 320), 90, np.uint8)
    assert patch_shift(flat, flat, (115.0, 108.0, 50.0, 40.0), 8) is None


def test_toward_background_blends_each_cue_with_its_absent_mean():
    single = LossDetector()
    single.mu_b = 0.4
    assert toward_background(single, 0.9, 1.0) == 0.9
    assert toward_background(single, 0.9, 1.7) == 0.9  # a box wholly inside: unchanged
    assert math.isclose(toward_background(single, 0.9, 0.25), 0.25 * 0.9 + 0.75 * 0.4)
    assert math.isclose(toward_background(single, 0.9, -0.1), 0.4)
    fused = FusedLoss(2)
    fused.members[0].mu_b, fused.members[1].mu_b = 0.3, 0.6
    got = toward_background(fused, np.array([0.8, 0.9]), 0.5)
    assert np.allclose(got, [0.55, 0.75])
    assert np.allclose(toward_background(fused, np.array([0.8]), 0.0), [0.3, 0.6])  # a scalar is broadcast


@pytest.mark.parametrize("tracker", ["fusion-pf", "color-pf"])
def test_edge_share_raises_the_flag_as_the_target_slides_out_not_on_its_last_sliver(tracker):
    """The target walks out through the right edge: 63 % of its box is inside at frame 20, 29 % at 22, none from 24.
    With edge_share = 0.5 (fusion-pf's default) the estimate's sliver at the edge counts for little, and the flag is
    up within a frame of the target being gone (measured: frames 24-25 for fusion-pf, 22 for color-pf); without it,
    one to three frames later (25-26), on the sliver alone."""
    for seed in range(3):
        scene = Scene(_exit_scene(seed))
        frames = scene.frames()
        gt = scene.groundtruth()
        first = {}
        for share in (0.0, 0.5):
            t = pftrack.create_tracker(tracker, seed=seed, edge_share=share)
            t.init(frames[0], tuple(gt[0]))
            lost = [t.update(f).lost for f in frames[1:]]
            first[share] = lost.index(True) + 1
        assert 21 <= first[0.5] <= 25, first
        assert first[0.5] < first[0.0], first


def _return_scene(seed: int) -> SceneSpec:
    """The target walks out through the right edge (gone from frame 27), waits outside, and walks back in from
    frame 40 on: 27 % of its box is inside at frame 51, 73 % at 54."""
    target = Target(path=((0, 230.0, 120.0), (25, 370.0, 120.0), (40, 370.0, 120.0), (70, 250.0, 120.0)),
                    size=(26.0, 52.0))
    return SceneSpec(n_frames=75, seed=seed, targets=(target,), background="flat", kind="exit")


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_acquire_in_frame_waits_until_half_of_the_candidate_is_in(seed):
    """acquire_in_frame = 0.5 (the default): the returning target is not acquired on its first sliver at the edge
    (frame 51 without the rule, the box a quarter inside) but once about half of it is in (frames 52-54 measured),
    still within a few frames of its return; nothing is acquired while it is away."""
    from pftrack.geometry import in_frame_fraction

    scene = Scene(_return_scene(seed))
    frames = scene.frames()
    gt = scene.groundtruth()
    h, w = frames[0].shape[:2]
    first = {}
    for g in (0.0, 0.5):
        t = pftrack.create_tracker("fusion-pf", seed=seed, acquire_in_frame=g)
        t.init(frames[0], tuple(gt[0]))
        states = [t.update(f) for f in frames[1:]]
        assert all(s.lost for s in states[29:45])  # frames 30-45: the target is out of view
        k = next(k for k, s in enumerate(states, start=1) if k > 30 and s.info.get("mode") == "acquired")
        first[g] = (k, in_frame_fraction(states[k - 1].box, w, h))
    assert first[0.0][1] < 0.4 and first[0.5][1] >= 0.45, first
    assert first[0.0][0] < first[0.5][0] <= 56, first
