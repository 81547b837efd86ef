"""Behaviour of color-pf on synthetic scenes with exact ground truth."""

import numpy as np
import pytest

import pftrack
from pftrack.errors import BoxError, FrameError, ParameterError
from pftrack.geometry import box_to_ellipse, center_error, iou
from pftrack.synth import entering_scene, illumination_scene, occlusion_scene, simple_scene

from .conftest import render_scene


def run(spec, seed=0, box=None, **params):
    scene, frames, truths = render_scene(spec)
    gt = scene.groundtruth(0)
    tr = pftrack.create_tracker("color-pf", seed=seed, **params)
    states = [tr.init(frames[0], gt[0] if box is None else box)]
    states += [tr.update(f) for f in frames[1:]]
    return gt, truths, states, tr


def boxes(states):
    return np.array([s.box for s in states])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_tracks_a_simple_scene(seed):
    gt, _, states, _ = run(simple_scene(seed), seed)
    err = center_error(boxes(states), gt)
    assert err.mean() < 2.0
    assert not any(s.lost for s in states)
    assert iou(boxes(states), gt).mean() > 0.75


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_partial_occlusion_keeps_centre_error_small(seed):
    gt, truths, states, _ = run(occlusion_scene(seed), seed)
    err = center_error(boxes(states), gt)
    vis = np.array([t.visible[0] for t in truths])
    assert vis.min() < 0.7  # the scene really occludes the target
    assert err.mean() < 4.0  # a few pixels for a 28x56 target whose lower half is hidden
    assert err.max() < 15.0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_full_occlusion_is_flagged_lost_and_target_reacquired(seed):
    gt, truths, states, _ = run(occlusion_scene(seed, full=True), seed)
    vis = np.array([t.visible[0] for t in truths])
    lost = np.array([s.lost for s in states])
    hidden = vis < 0.05
    assert hidden.sum() >= 10
    assert (lost & hidden).sum() >= 0.6 * hidden.sum()  # flagged lost for most hidden frames
    assert not (lost & (vis > 0.9))[: int(np.argmax(hidden))].any()  # no false alarm before the occlusion
    # re-acquired within a few frames of reappearing, and on the right spot
    back = int(np.nonzero(hidden)[0][-1]) + 1
    visible_again = back + int(np.argmax(vis[back:] > 0.6))
    reacq = visible_again + int(np.argmax(~lost[visible_again:]))
    assert reacq - visible_again <= 4
    tail = slice(reacq + 2, len(states))
    assert center_error(boxes(states)[tail], gt[tail]).mean() < 5.0


@pytest.mark.parametrize("seed", [0, 1])
def test_search_interval_searches_every_kth_frame_after_the_dense_ones_and_still_reacquires(seed):
    dense, every = 3, 3
    gt, truths, states, tr = run(occlusion_scene(seed, full=True), seed, search_interval=every, search_dense=dense)
    vis = np.array([t.visible[0] for t in truths])
    modes = [s.info.get("mode") for s in states]
    lost = np.array([s.lost for s in states])
    start = modes.index("lost")  # the frame the loss was declared; the search starts on the next one
    run_end = start + 1
    while run_end < len(modes) and modes[run_end] in ("searching", "waiting"):
        run_end += 1
    assert run_end - start > dense + 2 * every  # long enough to see the pattern
    for t in range(start + 1, run_end):
        k = t - start
        assert modes[t] == ("searching" if k <= dense or k % every == 0 else "waiting"), (t, k, modes[t])
        assert lost[t]
        if modes[t] == "waiting":  # the last search's result again
            assert states[t].box == states[t - 1].box and states[t].score == states[t - 1].score
    # re-acquired on a searched frame, within a few frames of reappearing, on the right spot
    k = run_end - start
    assert modes[run_end] == "acquired" and (k <= dense or k % every == 0)
    hidden = vis < 0.05
    back = int(np.nonzero(hidden)[0][-1]) + 1
    visible_again = back + int(np.argmax(vis[back:] > 0.6))
    assert run_end - visible_again <= 4 + every - 1
    tail = slice(run_end + 2, len(states))
    assert center_error(boxes(states)[tail], gt[tail]).mean() < 5.0
    # nothing of this search is re-reported after a later loss
    assert tr.mode == "tracking" and tr._last_search is None


def test_model_update_beats_no_update_under_illumination_drift():
    errs = {}
    for gate in ("threshold", "never"):
        e = []
        for seed in range(3):
            gt, _, states, _ = run(illumination_scene(seed), seed, update_gate=gate)
            e.append(center_error(boxes(states), gt).mean())
        errs[gate] = float(np.mean(e))
    assert errs["threshold"] < 0.5 * errs["never"], errs


def test_automatic_initialisation_finds_entering_target():
    spec = entering_scene(0, enter_at=15)
    scene, frames, truths = render_scene(spec)
    gt = scene.groundtruth(0)
    tr = pftrack.create_tracker("color-pf", seed=0)
    # the known target histogram, measured once on a frame where the target is visible
    q = tr.cue.histogram(frames[40], box_to_ellipse(gt[40]))
    st = tr.init_auto(frames[0], q, size=gt[40][2:])
    states = [st] + [tr.update(f) for f in frames[1:]]
    lost = np.array([s.lost for s in states])
    assert lost[:15].all()  # nothing to find before the target enters
    fully_in = int(np.argmax([t.visible[0] > 0.99 and t.boxes[0][0] > 0 for t in truths]))
    found = int(np.argmax(~lost))
    assert 15 <= found <= fully_in + 5
    tail = slice(found + 3, len(states))
    assert center_error(boxes(states)[tail], gt[tail]).mean() < 6.0
    assert not lost[found:].any()


def test_automatic_initialisation_with_entry_regions_and_variance_test():
    spec = entering_scene(1, enter_at=10)
    scene, frames, _ = render_scene(spec)
    gt = scene.groundtruth(0)
    tr = pftrack.create_tracker("color-pf", seed=3, search_method="variance", variance_threshold=30.0)
    q = tr.cue.histogram(frames[40], box_to_ellipse(gt[40]))
    tr.init_auto(frames[0], q, size=gt[40][2:], regions=[(0, 0, 80, 240)])
    states = [tr.update(f) for f in frames[1:]]
    found = int(np.argmax([not s.lost for s in states])) + 1
    assert not states[-1].lost
    assert 10 <= found <= 40
    assert center_error(np.array(states[-1].box), gt[-1]) < 6.0


def test_detector_initialisation():
    spec = entering_scene(2, enter_at=10)
    scene, frames, _ = render_scene(spec)
    gt = scene.groundtruth(0)

    def detector(frame):
        t = next(i for i, f in enumerate(frames) if f is frame)
        return [] if t < 25 else [tuple(gt[t]) + (0.9,)]

    tr = pftrack.create_tracker("color-pf", seed=0, detector=detector)
    first = tr.init_detect(frames[0])
    assert first.lost
    states = [tr.update(f) for f in frames[1:]]
    assert all(s.lost for s in states[:23])
    assert not states[24].lost
    assert center_error(np.array(states[-1].box), gt[-1]) < 6.0


@pytest.mark.parametrize("variant", [{"adaptive_sigma": True}, {"update_gate": "lambda"},
                                     {"resampler": "systematic"}, {"color_space": "hsv"},
                                     {"kernel": "epanechnikov"}, {"resample_ess": 0.5}])
def test_variants_track(variant):
    gt, _, states, _ = run(simple_scene(4), 0, **variant)
    assert center_error(boxes(states), gt).mean() < 3.0


def test_same_seed_same_output_and_reinit():
    spec = occlusion_scene(0)
    _, _, a, tr = run(spec, seed=7)
    _, _, b, _ = run(spec, seed=7)
    assert boxes(a).tobytes() == boxes(b).tobytes()
    assert [s.score for s in a] == [s.score for s in b]
    _, _, c, _ = run(spec, seed=8)
    assert boxes(a).tobytes() != boxes(c).tobytes()
    # re-initialising the same instance starts afresh
    scene, frames, _ = render_scene(spec)
    gt = scene.groundtruth(0)
    st = tr.init(frames[0], gt[0])
    assert st.box == pytest.approx(tuple(gt[0])) and not st.lost


def test_state_contents():
    gt, _, states, tr = run(simple_scene(0, n_frames=5), 0, n_particles=37)
    s = states[-1]
    assert s.particles.shape == (37, 7) and s.weights.shape == (37,)
    assert s.state_names == ("x", "y", "vx", "vy", "hx", "hy", "adot")
    assert np.isclose(s.weights.sum(), 1.0)
    assert 0.0 <= s.score <= 1.0


def test_target_leaving_image_is_lost_without_nan():
    # the target walks out of the right edge and never comes back
    from pftrack.synth import SceneSpec, Target

    spec = SceneSpec(n_frames=60, seed=3, targets=(Target(path=((0, 200.0, 120.0), (40, 380.0, 120.0))),))
    gt, _, states, _ = run(spec, 0)
    assert all(np.all(np.isfinite(s.box)) and np.isfinite(s.score) for s in states)
    assert all(s.lost for s in states[-10:])


def test_bad_inputs_raise_specific_errors():
    tr = pftrack.create_tracker("color-pf", seed=0)
    frame = np.zeros((50, 60, 3), np.uint8)
    with pytest.raises(BoxError):
        tr.init(frame, (100, 100, 5, 5))
    with pytest.raises(BoxError):
        tr.init(frame, (1, 1, 0, 5))
    with pytest.raises(RuntimeError):
        pftrack.create_tracker("color-pf").update(frame)
    tr.init(frame, (10, 10, 10, 10))
    with pytest.raises(FrameError):
        tr.update(np.zeros((40, 60, 3), np.uint8))
    with pytest.raises(FrameError, match="outside"):
        tr.update(np.full((50, 60, 3), 200.0, np.float32))
    with pytest.raises(FrameError):
        tr.update(np.zeros((50, 60, 3), np.complex64))
    # grayscale, 16-bit and float frames in [0, 1] are converted
    tr.update(np.zeros((50, 60, 3), np.float32))
    tr.update(np.zeros((50, 60), np.uint8))
    tr.update(np.zeros((50, 60, 3), np.uint16))
    with pytest.raises(ParameterError):
        pftrack.create_tracker("color-pf", sigma=0)
    with pytest.raises(ParameterError):
        pftrack.create_tracker("color-pf", bins=(8, 8))
    with pytest.raises(ParameterError):
        pftrack.create_tracker("color-pf", colour_space="rgb")
    with pytest.raises(ParameterError):
        pftrack.create_tracker("no-such-tracker")


def test_compiled_and_reference_paths_track_identically():
    """The Numba kernels and the NumPy reference path give the same trajectory (to rounding)."""
    from pftrack._numba import NUMBA_INSTALLED, set_numba_enabled

    if not NUMBA_INSTALLED:
        pytest.skip("numba not installed")
    spec = occlusion_scene(3, n_frames=40)
    res = {}
    for flag in (True, False):
        prev = set_numba_enabled(flag)
        try:
            _, _, states, _ = run(spec, seed=5)
            res[flag] = states
        finally:
            set_numba_enabled(prev)
    a, b = boxes(res[True]), boxes(res[False])
    assert np.allclose(a, b, rtol=0, atol=1e-6)
    assert np.allclose([s.score for s in res[True]], [s.score for s in res[False]], atol=1e-9)


@pytest.mark.parametrize("name", ["color-pf", "fusion-pf"])
def test_grey_scale_rate_noise_applies_on_grey_input_only(name):
    """``grey_scale_rate_noise`` replaces ``scale_rate_noise`` when the cue works on grey input; colour input keeps
    ``scale_rate_noise``, and the default (None) keeps it on both."""
    rng = np.random.default_rng(0)
    colour = rng.integers(0, 255, (120, 160, 3), dtype=np.uint8)
    grey = np.repeat(colour[..., :1], 3, axis=2)
    box = (60, 40, 30, 30)
    for frame, expect_grey in ((colour, False), (grey, True)):
        t = pftrack.create_tracker(name, seed=0, grey_scale_rate_noise=0.0)
        t.init(frame, box)
        rate = t._noise_std(15.0, 15.0)[-1]
        assert rate == (0.0 if expect_grey else t.params.scale_rate_noise)
        d = pftrack.create_tracker(name, seed=0)
        d.init(frame, box)
        assert d._noise_std(15.0, 15.0)[-1] == d.params.scale_rate_noise > 0


def _two_tone(frame, x, y, top, bottom, w=24, h=48):
    frame[y:y + h // 2, x:x + w] = top
    frame[y + h // 2:y + h, x:x + w] = bottom


@pytest.mark.parametrize("name", ["color-pf", "fusion-pf"])
def test_two_part_histograms_tell_a_reversed_layout_apart(name):
    """``histogram_parts=2``: a look-alike with the target's colours in the reverse order (red over blue against
    blue over red) scores as the target in one histogram, and far below it in two parts; the models and the cue
    have twice the bins, on colour and on grey input."""
    rng = np.random.default_rng(0)
    frame = rng.integers(90, 130, (120, 200, 3), dtype=np.uint8)
    _two_tone(frame, 40, 40, (0, 0, 220), (220, 0, 0))  # the target: red (BGR) over blue
    _two_tone(frame, 130, 40, (220, 0, 0), (0, 0, 220))  # the look-alike: blue over red
    target, other = np.array([[52.0, 64.0, 12.0, 24.0]]), np.array([[142.0, 64.0, 12.0, 24.0]])
    scores = {}
    for parts in (1, 2):
        t = pftrack.create_tracker(name, seed=0, histogram_parts=parts)
        t.init(frame, (40, 40, 24, 48))
        assert t.cue.n_bins == 512 * parts and t.q.size == 512 * parts
        scores[parts] = [float(t._rho(frame, e)[0][0]) for e in (target, other)]
    assert scores[1][0] > 0.99 and scores[1][1] > 0.99  # one histogram: the same colours, the same score
    assert scores[2][0] > 0.99 and scores[2][1] < 0.1  # two parts: the layout differs
    grey = np.repeat(frame[..., 1:2], 3, axis=2)
    t = pftrack.create_tracker(name, seed=0, histogram_parts=2)
    t.init(grey, (40, 40, 24, 48))
    assert t.cue.color_space == "gray" and t.cue.n_bins == 2 * t.cue.feature_bins == t.q.size
    assert t.update(grey).box is not None


def test_two_part_histograms_refuse_the_grey_bin_shift():
    with pytest.raises(ParameterError, match="histogram_parts"):
        pftrack.create_tracker("color-pf", histogram_parts=2, grey_relit_shift=1)
