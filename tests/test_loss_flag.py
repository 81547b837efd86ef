"""The lost flag as a detector (GUIDE §8): the loss test, grey input, acquisition and bounds over varied scenes."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.cues.histogram_cue import ColorCue
from pftrack.cues.intensity import equalization_lut, is_gray, quantize_gray
from pftrack.eval.metrics import lost_detection
from pftrack.filtering.loss import (LossDetector, absent_distribution, confidence, score_llr)
from pftrack.geometry import iou
from pftrack.synth import hidden_frames, leave_scene, vanish_scene, varied_scene

from .conftest import cached_scene, lost_flag_run

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


def test_background_statistics_are_numpys_numbers():
    """robust_background and absent_distribution compute means and spreads without NumPy's wrappers: the same
    numbers as s.mean(), s.std() and np.median, with NaNs left out, ties, and fewer scores than the tail's three."""
    from pftrack.filtering.loss import robust_background

    rng = np.random.default_rng(7)
    for t in range(400):
        s = rng.normal(rng.normal(), rng.uniform(0.0, 2.0), int(rng.integers(1, 260)))
        if t % 3 == 0:
            s = np.round(s, 1)
        if t % 4 == 0:
            s[rng.integers(0, s.size, 2)] = np.nan
        f = s[np.isfinite(s)]
        if f.size == 0:
            continue
        mad = 1.4826 * float(np.median(np.abs(f - np.median(f))))
        assert robust_background(s, sd_floor=0.01) == (float(f.mean()), max(float(f.std()), mad, 0.01))
        top = np.sort(f)[-max(3, int(np.ceil(0.1 * f.size))):]
        assert absent_distribution(s, tail=0.1, sd_floor=0.01) == (float(top.mean()), max(float(top.std()), 0.01))


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
        scene = cached_scene(spec)
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
    scene = cached_scene(spec)
    gt = scene.groundtruth(0)
    h, w = scene.render(0)[0].shape[:2]
    runs = {}
    for m in (0.0, 0.4):
        t = pftrack.create_tracker("color-pf", seed=0, min_in_frame=m)
        t.init(scene.render(0)[0], tuple(gt[0]))
        runs[m] = [t.update(scene.render(k)[0]) for k in range(1, spec.n_frames)]
    flagged = 0
    for st in runs[0.4]:
        full = st.info.get("box_full", st.box)  # the whole estimate (the reported box is its visible part)
        if st.info.get("mode") == "tracking" and in_frame_fraction(full, w, h) < 0.4:
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


def test_color_pf_does_not_call_a_camouflaged_target_lost_on_its_unstretched_bins():
    """A target drawn in the background's colours: the colour cannot tell, so the flag stays down (no evidence).

    With color-pf's default haze_stretch = 1.8 the camouflage scenes' narrow palette (a level span that needs a gain
    of about 3.9) is stretched over the bins: the colour then tells a little, the box covers the target on more
    frames (seeds 200-207: 260 against 119), and the flag is raised on 0-47 % of them (0 % unstretched); a
    shortfall of that default, measured in docs/robustness.md ("A hazy camera")."""
    from pftrack.synth import camouflage_scene

    res = [lost_flag_run(camouflage_scene(seed), seed=seed, haze_stretch=0.0) for seed in (200, 201)]
    assert max(r.false_rate for r in res) <= 0.05, [r.false_rate for r in res]


def test_relit_search_reacquires_a_target_whose_light_changed_while_hidden():
    """color-pf's relit_search: a global light change while the target is hidden (fresh colour vanish scenes)."""
    specs = [vanish_scene(seed, gray=0.0, illumination=1.0, distractors=(0, 1)) for seed in (202, 204, 205, 206)]
    assert not any(dict(s.nuisances)["illumination_target_only"] for s in specs)
    got = {m: sum(lost_flag_run(s, seed=200 + i, relit_search=m).reacquired for i, s in enumerate(specs))
           for m in ("off", "max")}
    # measured 4 against 0 (scenes 200-215 with their own seed as run seed: 9 of 10 against 2)
    assert got["max"] >= 3 and got["max"] > got["off"], got
