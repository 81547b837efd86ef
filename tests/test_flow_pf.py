"""EMD in closed form, HSV integral histograms and flow-pf (Tung & Matsuyama)."""

import numpy as np
import pytest

import pftrack
from pftrack.cues.emd import emd_circular, emd_general, emd_linear
from pftrack.cues.hsv import HSVHistogramCue, integral_counts
from pftrack.geometry import iou
from pftrack.synth import simple_scene
from pftrack.trackers.flow_pf import FlowPFGroup, FlowPFParams, _untracked_share

from .conftest import grey_frames, render_scene


def test_closed_form_emd_is_exact_against_the_general_solver(rng):
    for _ in range(60):
        n = int(rng.integers(3, 16))
        p, q = rng.random(n) ** 3, rng.random(n) ** 3
        # cv2.EMD works in float32: agreement to its precision
        assert emd_linear(p, q) == pytest.approx(emd_general(p, q), rel=1e-4, abs=1e-5)
        assert emd_circular(p, q) == pytest.approx(emd_general(p, q, circular=True), rel=1e-4, abs=1e-5)


def test_emd_known_values_and_batching():
    a = np.array([1.0, 0, 0, 0])
    b = np.array([0, 0, 0, 1.0])
    assert emd_linear(a, b) == pytest.approx(3.0)
    assert emd_circular(a, b) == pytest.approx(1.0)  # around the circle
    batch = np.stack([a, b, a])
    assert emd_linear(batch, b).tolist() == pytest.approx([3.0, 0.0, 3.0])


def test_integral_histograms_match_direct_counts(rng):
    from pftrack._numba import NUMBA_INSTALLED, set_numba_enabled

    img = rng.integers(0, 256, (40, 50, 3), dtype=np.uint8)
    cue = HSVHistogramCue(10)
    maps = cue.bin_maps(img)
    for flag in ([True, False] if NUMBA_INSTALLED else [False]):
        prev = set_numba_enabled(flag)
        try:
            feats = cue.prepare(img, (0, 0, 50, 40))
        finally:
            set_numba_enabled(prev)
        boxes = np.array([[3, 4, 10, 12], [0, 0, 50, 40], [40, 30, 20, 20]], float)
        hist, n = cue.box_histograms(feats, boxes)
        for k, (x, y, w, h) in enumerate(boxes.astype(int)):
            sub = maps[:, y:y + h, x:x + w].reshape(3, -1)
            expected = np.stack([np.bincount(c, minlength=10) for c in sub]) / sub.shape[1]
            assert np.allclose(hist[k], expected) and n[k] == sub.shape[1]
    assert integral_counts(maps, 10).shape == (3, 10, 41, 51)


def test_untracked_share():
    features = np.array([[5.0, 5.0], [6.0, 6.0], [50.0, 50.0]])
    tracked = np.array([True, False, False])
    boxes = np.array([[0, 0, 10, 10], [40, 40, 20, 20], [100, 100, 5, 5]], float)
    assert _untracked_share(features, tracked, boxes).tolist() == pytest.approx([0.5, 1.0, 1.0])


def test_flow_prediction_follows_the_target():
    """The median displacement of the tracked features (those whose match lies in the previous window) is the
    target's motion, also when the search region holds a background moving the other way."""
    import cv2

    rng = np.random.default_rng(0)
    blob = lambda shape: cv2.normalize(cv2.GaussianBlur(rng.random(shape).astype(np.float32), (0, 0), 2.0), None, 0,
                                       255, cv2.NORM_MINMAX).astype(np.uint8)  # smooth texture, like real surfaces
    bg = np.stack([blob((240, 320))] * 3, axis=-1)
    tex = blob((40, 40))
    frames = []
    for t in range(2):
        f = np.roll(bg, -3 * t, axis=1).copy()  # background moves left by 3 px
        x = 140 + 5 * t  # target moves right by 5 px, down by 2
        y = 100 + 2 * t
        f[y:y + 40, x:x + 40] = tex[..., None]
        frames.append(f)
    tr = pftrack.create_tracker("flow-pf", seed=0)
    tr.init(frames[0], (140, 100, 40, 40))
    from pftrack.cues.motion import to_gray

    disp, feats, tracked = tr._flow(to_gray(frames[1]))
    assert disp is not None and np.allclose(disp, [5, 2], atol=0.3)
    assert tracked.sum() >= 10 and (~tracked).sum() >= 10  # background features are found but not tracked


@pytest.mark.parametrize("variant", [{}, {"motion": False}, {"anchor": True}])
def test_flow_pf_tracks_a_simple_scene(variant):
    scene, frames, _ = render_scene(simple_scene(1))
    gt = scene.groundtruth(0)
    tr = pftrack.create_tracker("flow-pf", seed=0, **variant)
    boxes = [tr.init(frames[0], gt[0]).box] + [tr.update(f).box for f in frames[1:]]
    assert iou(np.array(boxes), gt).mean() > 0.6
    assert len(tr.subspace) <= tr.params.templates


def test_detection_replaces_the_response_and_feeds_the_subspace():
    scene, frames, _ = render_scene(simple_scene(2, n_frames=20))
    gt = scene.groundtruth(0)
    calls = []

    def detector(frame):
        calls.append(1)
        t = next(i for i, f in enumerate(frames) if f is frame)
        return [tuple(gt[t]) + (1.0,)]

    tr = pftrack.create_tracker("flow-pf", seed=0, detector=detector)
    tr.init(frames[0], gt[0])
    for t in range(1, 20):
        st = tr.update(frames[t])
        assert st.info["detection"]
        assert iou(np.array(st.box), gt[t]) > 0.95  # z_t = y_t
    assert len(calls) == 19


def test_haar_face_detector_loads():
    from pftrack.trackers.flow_pf import haar_face_detector

    det = haar_face_detector()
    assert det(np.zeros((120, 160, 3), np.uint8)).shape[1] == 5


def test_group_tracks_several_objects_with_their_own_subspaces():
    from pftrack.synth import crossing_scene

    scene, frames, truths = render_scene(crossing_scene(5, same_colors=False))
    boxes0 = [tuple(truths[0].boxes[k]) for k in range(2)]
    group = FlowPFGroup(FlowPFParams(motion=False), seed=1)
    states = group.init(frames[0], boxes0)
    assert len(states) == 2
    for f in frames[1:]:
        states = group.update(f)
    assert len(states) == 2 and group.trackers[0].subspace is not group.trackers[1].subspace
    assert iou(np.array(states[1].box), truths[-1].boxes[1]) > 0.3


def test_kernel_levels_weight_the_centre():
    """kernel_levels = L: the mean of the histograms of L nested boxes, so central pixels weigh more."""
    frame = np.zeros((60, 60, 3), np.uint8)
    frame[20:40, 20:40] = (0, 0, 255)  # red centre, black border
    flat = pftrack.create_tracker("flow-pf", kernel_levels=1)
    nested = pftrack.create_tracker("flow-pf", kernel_levels=3)
    box = (10, 10, 40, 40)
    q1, q3 = flat._model(frame, box), nested._model(frame, box)
    assert np.allclose(q1.sum(axis=-1), 1) and np.allclose(q3.sum(axis=-1), 1)
    v_bin = nested.cue.bin_maps(frame[20:21, 20:21])[2, 0, 0]
    # flat: 400 of 1600 pixels are red; nested (scales 1, 2/3, 1/3): about (0.25 + 0.59 + 1) / 3
    assert q1[2, v_bin] == pytest.approx(0.25, abs=0.02) and q3[2, v_bin] > 0.55


def test_subspace_update_is_gated_by_distance():
    """An estimate whose colours are far from every template does not join the subspace (update_distance);
    with the paper's ungated update it does."""
    frame = np.full((120, 160, 3), 90, np.uint8)
    frame[40:80, 60:100] = (0, 0, 230)
    changed = frame.copy()
    changed[40:80, 60:100] = (230, 160, 0)  # the target turns from red to blue-cyan
    sizes = {}
    for ud in (0.3, 1e9):
        tr = pftrack.create_tracker("flow-pf", seed=0, update_distance=ud, motion=False)
        tr.init(frame, (60, 40, 40, 40))
        n0 = len(tr.subspace)
        tr.update(changed)
        sizes[ud] = len(tr.subspace) - n0
    assert sizes == {0.3: 0, 1e9: 1}


def test_on_grey_input_the_colour_distance_is_the_value_channels():
    """Hue and saturation are 0 in every box of a grey frame: their zero distances flattened the likelihood
    threefold (``grey_value_only``, default on, keeps V's alone); colour frames are unchanged."""
    from pftrack.eval.metrics import ope_scores
    from pftrack.synth import Scene

    auc = {True: [], False: []}
    for seed in (1, 2):
        sc = Scene(simple_scene(seed, n_frames=40))
        frames, gt = sc.frames(), sc.groundtruth(0)
        grey = grey_frames(frames)
        for v_only in (True, False):
            t = pftrack.create_tracker("flow-pf", seed=0, grey_value_only=v_only)
            t.init(grey[0], tuple(gt[0]))
            auc[v_only].append(ope_scores(np.array([gt[0]] + [t.update(f).box for f in grey[1:]]), gt).auc)
        colour = []
        for v_only in (True, False):  # colour frames: the same boxes either way
            t = pftrack.create_tracker("flow-pf", seed=0, grey_value_only=v_only)
            t.init(frames[0], tuple(gt[0]))
            colour.append([t.update(f).box for f in frames[1:10]])
        assert colour[0] == colour[1]
    assert np.mean(auc[True]) > np.mean(auc[False]) + 0.1, auc


def test_grey_input_compares_finer_value_histograms():
    """``grey_bins``: on grey input V alone is compared, in 20 bins (docs/flow-pf.md); colour input keeps ``bins``
    and its boxes.  On a grey vanish scene (tune seed 8) the estimate covers the target on 33 frames against 6 with
    the former 10 bins (measured)."""
    from pftrack.synth.varied import vanish_scene

    from .conftest import lost_flag_run

    scene, frames, _ = render_scene(simple_scene(3, n_frames=30))
    gt = scene.groundtruth(0)
    boxes = {}
    for gb in (20, 0):
        t = pftrack.create_tracker("flow-pf", seed=0, grey_bins=gb)
        t.init(frames[0], tuple(gt[0]))
        assert t.cue.n_bins == 10
        boxes[gb] = [t.update(f).box for f in frames[1:]]
    assert boxes[20] == boxes[0]
    grey = [np.repeat(f.mean(axis=2, keepdims=True).astype(np.uint8), 3, axis=2) for f in frames]
    t = pftrack.create_tracker("flow-pf", seed=0)
    t.init(grey[0], tuple(gt[0]))
    assert t.cue.n_bins == 20
    t.init(frames[0], tuple(gt[0]))  # re-initialised on colour: the colour bins again
    assert t.cue.n_bins == 10
    new = lost_flag_run(vanish_scene(8, gray=1.0), "flow-pf")
    old = lost_flag_run(vanish_scene(8, gray=1.0), "flow-pf", grey_bins=0)
    assert new.covered_frames >= old.covered_frames + 15, (new, old)


def test_the_likelihood_loss_test_changes_the_flag_not_the_track():
    """loss_test='likelihood' (the colour PFs' two-class test on 1 / (1 + d)): the same boxes as the distance test,
    since its background boxes come from a fixed grid; the flag rises while the target hides and drops when the
    score is target-like again, and the score is the test's confidence."""
    from pftrack.synth import Scene, hidden_frames, vanish_scene

    spec = vanish_scene(100, n_frames=90)
    hidden = hidden_frames(spec)
    pairs = [(f, tr.boxes[0]) for f, tr in Scene(spec)]
    runs = {}
    for test in ("distance", "likelihood"):
        t = pftrack.create_tracker("flow-pf", seed=0, loss_test=test)
        t.init(pairs[0][0], pairs[0][1])
        runs[test] = [t.update(f) for f, _ in pairs[1:]]
    assert [s.box for s in runs["distance"]] == [s.box for s in runs["likelihood"]]
    lik = runs["likelihood"]
    on_hidden = {k: sum(s.lost for s, h in zip(v, hidden[1:]) if h) for k, v in runs.items()}
    assert on_hidden["likelihood"] >= 0.9 * hidden.sum() > on_hidden["distance"]
    assert not any(s.lost for s in lik[:3])  # the target in view at the start: no alarm
    assert all(0.0 <= s.score <= 1.0 for s in lik)
    assert all(s.score < 0.5 for s in lik if s.lost)
