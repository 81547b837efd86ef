"""Multi-object tracking: detectors, life cycle, occlusion mechanics, CLI and MOT evaluation."""

import numpy as np
import pytest

from pftrack.cli import main
from pftrack.eval.mot import mot_scores
from pftrack.io.datasets import read_mot_txt
from pftrack.multi import create_detector, create_multi_tracker
from pftrack.multi.detectors import nms
from pftrack.synth import SceneSpec, Target, crossing_scene

from .conftest import render_scene, shared_sequence


def movers(seed=0, n=40):
    """Two differently coloured, textured (like clothing) people-sized targets walking across a static background."""
    rng = np.random.default_rng(seed)
    a = Target(path=((0, 60.0, 100.0 + rng.uniform(-10, 10)), (n - 1, 250.0, 110.0)), size=(24, 60), texture=30)
    b = Target(path=((0, 270.0, 170.0), (n - 1, 80.0, 165.0 + rng.uniform(-10, 10))), size=(24, 60),
               colors=((60, 180, 60), (180, 60, 160)), texture=30)
    return SceneSpec(n_frames=n, seed=seed, targets=(a, b), noise=2.0)


@pytest.mark.parametrize("name", ["mog2", "motion"])
def test_detectors_find_synthetic_movers(name):
    scene, frames, truths = render_scene(movers(1))
    det = create_detector(name)
    found = 0
    from pftrack.geometry import iou_matrix

    for t, f in enumerate(frames):
        d = det(f)
        assert d.ndim == 2 and d.shape[1] == 5
        if t >= 10:  # after the background model / frame history has settled
            m = iou_matrix(truths[t].boxes, d[:, :4]) if len(d) else np.zeros((2, 0))
            found += int((m.max(axis=1) > 0.1).sum()) if m.size else 0
    # frame differencing only sees the parts of a target that changed since the last two frames
    assert found >= {"mog2": 0.8, "motion": 0.5}[name] * 2 * (len(frames) - 10)


def test_hog_and_nms():
    det = create_detector("hog")
    out = det(np.zeros((200, 200, 3), np.uint8))
    assert out.shape[1] == 5
    boxes = np.array([[0, 0, 10, 10], [1, 1, 10, 10], [50, 50, 10, 10]], float)
    assert nms(boxes, np.array([0.9, 0.8, 0.7]), 0.5).tolist() == [0, 2]


def test_callable_detector_and_bad_names():
    from pftrack.errors import ParameterError

    tr = create_multi_tracker(detector_fn=lambda f: [(10, 10, 20, 40)])
    assert tr.update(np.zeros((100, 100, 3), np.uint8)) == []  # not yet confirmed
    with pytest.raises(ParameterError):
        create_detector("nope")
    with pytest.raises(ParameterError):
        create_multi_tracker(bogus=1)


def scripted(boxes_per_frame):
    it = iter(boxes_per_frame)

    def det(frame):
        return next(it)

    return det


def test_birth_is_confirmed_after_k_frames():
    frames = [np.full((120, 160, 3), 90, np.uint8) for _ in range(8)]
    for f in frames:
        f[40:100, 60:84] = (30, 30, 200)
    box = (60.0, 40.0, 24.0, 60.0)
    tr = create_multi_tracker(detector_fn=scripted([[box]] * 8), birth_frames=3)
    seen = [len(tr.update(f)) for f in frames]
    assert seen[:2] == [0, 0] and seen[2] == 1 and all(s == 1 for s in seen[2:])
    assert tr.tracks[0].id == 1


def test_target_leaving_the_image_dies_and_ids_are_never_reused():
    spec = SceneSpec(n_frames=60, seed=2,
                     targets=(Target(path=((0, 200.0, 120.0), (45, 360.0, 120.0)), size=(24, 60)),))
    scene, frames, truths = render_scene(spec)
    dets = [[tuple(truths[t].boxes[0])] if truths[t].present[0] and truths[t].boxes[0][0] < 300 else []
            for t in range(60)]
    tr = create_multi_tracker(detector_fn=scripted(dets), birth_frames=2)
    for f in frames:
        tr.update(f)
    assert tr.tracks == []  # gone once it left the image
    assert tr.next_id == 2  # one identity was ever issued


def test_occlusion_state_freezes_a_hidden_target():
    """§3.7 mechanics: an occluded target coasts at constant velocity and its model is frozen."""
    # differently coloured, so the hidden one's likelihood drops (the paper's test for "which is behind")
    scene, frames, truths = render_scene(crossing_scene(0, n_frames=80, same_colors=False))
    gt = [truths[t].boxes for t in range(80)]
    dets = [[tuple(b) for b, vis in zip(gt[t], truths[t].visible) if vis > 0.6] for t in range(80)]
    tr = create_multi_tracker(detector_fn=scripted(dets), occlusion=True, occlusion_predict=True, birth_frames=2)
    was_occluded = False
    for t, f in enumerate(frames):
        before = {k.id: (k.q.copy(), k.state.copy()) for k in tr.tracks}
        tr.update(f)
        for k in tr.tracks:
            if k.occluded and k.id in before:
                was_occluded = True
                q0, s0 = before[k.id]
                assert np.array_equal(k.q, q0)  # no model update while occluded
                assert np.allclose(k.state[0:2], s0[0:2] + s0[2:4])  # constant velocity
                assert np.allclose(k.state[4:6], s0[4:6])  # no size update
    assert was_occluded


def crossing_run(seed, same_colors, occlusion, min_visible=0.95):
    """A crossing with detections only while a target is (almost) fully visible: the filters must carry
    the identities through the gap."""
    scene, frames, truths = render_scene(crossing_scene(seed, n_frames=80, same_colors=same_colors))
    dets = [[tuple(b) for b, v in zip(truths[t].boxes, truths[t].visible) if v > min_visible] for t in range(80)]
    tr = create_multi_tracker(seed=seed, birth_frames=2, occlusion=occlusion, occlusion_predict=True,
                              detector_fn=scripted(dets))
    gt_rows, hyp = [], []
    for t, f in enumerate(frames):
        for k in range(2):
            if truths[t].present[k]:
                gt_rows.append([t + 1, k + 1, *truths[t].boxes[k], 1])
        hyp.extend([t + 1, o.track_id, *o.box, o.score] for o in tr.update(f))
    return mot_scores(np.array(gt_rows), np.array(hyp).reshape(-1, 7))


def test_same_colour_crossings_keep_their_identities_with_the_predicted_occlusion_state():
    """§3.7: the detector sees a target only while it is fully visible; the hidden one coasts."""
    for seed in range(4):
        s = crossing_run(seed, same_colors=True, occlusion=True)
        assert s.num_switches == 0 and s.idf1 > 0.9


@pytest.mark.experiment
def test_occlusion_handling_helps_through_detection_gaps():
    on = [crossing_run(seed, same_colors=False, occlusion=True) for seed in range(12)]
    off = [crossing_run(seed, same_colors=False, occlusion=False) for seed in range(12)]
    assert sum(s.num_switches for s in on) <= sum(s.num_switches for s in off)
    assert np.mean([s.mota for s in on]) > np.mean([s.mota for s in off])


def merged_blob_run(seed, occlusion):
    """Two same-coloured targets cross; like a blob detector, the detector returns one box (their union)
    while they overlap."""
    from pftrack.geometry import iou_matrix

    scene, frames, truths = render_scene(crossing_scene(seed, n_frames=80, same_colors=True))
    dets = []
    for t in range(80):
        b = [np.asarray(x, float) for x, on in zip(truths[t].boxes, truths[t].present) if on]
        if len(b) == 2 and iou_matrix(b[0][None], b[1][None])[0, 0] > 0:
            lo, hi = np.minimum(b[0][:2], b[1][:2]), np.maximum(b[0][:2] + b[0][2:], b[1][:2] + b[1][2:])
            b = [np.concatenate([lo, hi - lo])]
        dets.append([tuple(x) for x in b])
    tr = create_multi_tracker(seed=seed, birth_frames=2, occlusion=occlusion, detector_fn=scripted(dets))
    gt_rows, hyp = [], []
    for t, f in enumerate(frames):
        gt_rows.extend([t + 1, k + 1, *truths[t].boxes[k], 1] for k in range(2) if truths[t].present[k])
        hyp.extend([t + 1, o.track_id, *o.box, o.score] for o in tr.update(f))
    return mot_scores(np.array(gt_rows), np.array(hyp).reshape(-1, 7))


def test_merged_detections_keep_identities_through_crossings():
    """Occlusion handling of merged blobs: the union box is the detection of neither target, so neither is
    pulled over the pair and swapped with the other."""
    on = [merged_blob_run(seed, True) for seed in range(8)]
    off = [merged_blob_run(seed, False) for seed in range(8)]
    assert 3 * sum(s.num_switches for s in on) <= sum(s.num_switches for s in off)
    assert sum(s.num_switches for s in off) >= 4
    assert np.mean([s.mota for s in on]) > np.mean([s.mota for s in off])
    assert np.mean([s.idf1 for s in on]) > 0.9


def test_mot_cli_writes_motchallenge_rows(tmp_path, capsys):
    import cv2

    scene, frames, _ = render_scene(movers(3))
    d = tmp_path / "frames"
    d.mkdir()
    for t, f in enumerate(frames):
        cv2.imwrite(str(d / f"{t:04d}.png"), f)
    out = tmp_path / "tracks.txt"
    assert main(["mot", str(d), "--out", str(out), "--quiet", "--video-out", str(tmp_path / "v.mp4")]) == 0
    rows = read_mot_txt(out)
    assert rows.shape[1] == 10 and rows.shape[0] > 20
    assert set(np.unique(rows[:, 7:10])) == {-1.0}
    assert len(np.unique(rows[:, 1])) >= 2
    assert main(["mot", str(tmp_path / "missing"), "--quiet"]) == 2
    assert main(["mot", str(d), "--param", "bogus=1", "--quiet", "--out", str(out)]) == 2


@pytest.mark.shared_data
def test_mot_protocol_on_pets_prefix(tmp_path):
    from pftrack.eval.runner import Job, TrackerConfig, run_job

    path = shared_sequence("pets09_s2l1_dev")
    rec = run_job(Job(TrackerConfig("multi-pf", "multi-pf"), str(path), "pets", 0, "mot"))
    assert rec["frames"] == 400 and rec["mota"] > 0.5 and rec["idf1"] > 0.5
    assert rec["fps"] > 10


def test_association_uses_colour_when_overlap_is_ambiguous():
    """Two tracks between two detections: by overlap alone the Hungarian assignment swaps them; the colour
    term (appearance_weight) gives each track the detection of its own colour."""
    frame = np.full((200, 300, 3), 128, np.uint8)
    red, blue = (30, 30, 220), (220, 40, 30)
    frame[50:110, 100:118] = red  # detection 1 (x 100..124) is mostly red
    frame[50:110, 118:136] = blue  # detection 2 (x 112..136) is mostly blue
    dets = np.array([[100, 50, 24, 60, 1.0], [112, 50, 24, 60, 1.0]])
    init = frame.copy()
    init[50:110, 40:64], init[50:110, 200:224] = red, blue  # where the tracks' colour models come from
    results = {}
    for w in (0.0, 1.0):
        mt = create_multi_tracker(detector_fn=lambda f: np.zeros((0, 5)), appearance_weight=w)
        mt._shape = frame.shape[:2]
        a, b = mt._new_track(init, (40, 50, 24, 60)), mt._new_track(init, (200, 50, 24, 60))
        # predictions: the red track's box overlaps the blue detection more, and vice versa
        a.pred = np.array([119.0, 80, 0, 0, 24, 60, 0, 0])  # IoU 0.55 with detection 1, 0.66 with 2
        b.pred = np.array([117.0, 80, 0, 0, 24, 60, 0, 0])  # IoU 0.66 with detection 1, 0.55 with 2
        mt.tracks = [a, b]
        used = mt._associate(frame, dets)
        assert used.all()
        results[w] = (a.det[0], b.det[0])
    assert results[0.0] == (112, 100)  # overlap alone: swapped
    assert results[1.0] == (100, 112)  # with colour: red to red, blue to blue


def test_a_detection_covering_two_targets_is_a_group_but_not_a_duplicate():
    frame = np.full((200, 300, 3), 128, np.uint8)
    mt = create_multi_tracker(detector_fn=lambda f: np.zeros((0, 5)))
    mt._shape = frame.shape[:2]
    a, b = mt._new_track(frame, (100, 50, 24, 60)), mt._new_track(frame, (120, 50, 24, 60))
    a.pred, b.pred = a.state.copy(), b.state.copy()
    mt.tracks = [a, b]
    blob = np.array([[98.0, 48, 50, 64, 1.0]])  # covers both
    used = mt._associate(frame, blob)
    assert used.all() and a.grouped and b.grouped and a.det is None and b.det is None
    b.pred = a.pred.copy() + [2, 0, 0, 0, 0, 0, 0, 0]  # the same target twice: not a group
    mt._associate(frame, blob)
    assert not a.grouped and not b.grouped and (a.det is not None) != (b.det is not None)
    mt = create_multi_tracker(detector_fn=lambda f: np.zeros((0, 5)), occlusion=False)
    mt._shape, mt.tracks = frame.shape[:2], [a, b]
    b.pred = b.state.copy()
    mt._associate(frame, blob)
    assert not a.grouped and not b.grouped


def test_a_merged_blob_is_gated_to_its_front_member_or_to_none():
    from pftrack.geometry import iou_matrix
    from pftrack.multi.track_state import gate_merged_detections

    pred = np.array([[100.0, 50, 24, 60], [118, 52, 24, 60], [250, 50, 24, 60]])
    dets = np.array([[98.0, 48, 46, 64], [250, 50, 24, 60]])
    m = iou_matrix(pred, dets)
    gate, used = m >= 0.3, np.zeros(2, bool)
    grouped = gate_merged_detections(pred, dets, m, gate, used, 0.8, 0.3, 0.3)  # target 0 fits the blob alone
    assert grouped == {0: False, 1: True} and not used.any()
    assert gate[:, 0].tolist() == [True, False, False] and gate[2, 1]
    gate, used = m >= 0.3, np.zeros(2, bool)
    grouped = gate_merged_detections(pred, dets, m, gate, used, 0.8, 0.9, 0.3)  # none fits it alone
    assert grouped == {0: True, 1: True} and used.tolist() == [True, False] and not gate[:, 0].any()


def test_the_mog2_background_started_from_the_first_frames_finds_who_was_there_from_the_start():
    """MOG2 takes its first frame for the background: the two movers, in view from frame 1, are not found on the
    first frames. Started from the first 8 frames with their moving pixels replaced by the median (``prime``),
    the detector finds them from the first frame, and multi-pf reports them 5 frames earlier."""
    scene, frames, _ = render_scene(movers(3))
    plain, primed = create_detector("mog2"), create_detector("mog2")
    primed.prime(frames[:8])
    assert [len(plain(f)) for f in frames[:4]] == [0, 0, 0, 0]
    assert len(primed(frames[0])) == 2
    first = {}
    for k in (0, 8):
        tr = create_multi_tracker("multi-pf", seed=0, bootstrap_frames=k)
        assert tr.bootstrap_frames == k
        if k:
            tr.prime(frames[:k])
        first[k] = next(t for t, f in enumerate(frames, 1) if tr.update(f))
    assert first[8] <= first[0] - 3
    assert create_multi_tracker("multi-pf", detector="hog", bootstrap_frames=8).bootstrap_frames == 0  # no background


def test_mot_cli_and_eval_read_the_bootstrap_frames_ahead(tmp_path):
    import cv2

    from pftrack.eval.runner import Job, TrackerConfig, run_job
    from pftrack.io.datasets import write_mot_groundtruth, write_seqinfo

    scene, frames, truths = render_scene(movers(3))
    d = tmp_path / "movers" / "movers"
    (d / "img1").mkdir(parents=True)
    (d / "gt").mkdir()
    for t, f in enumerate(frames, 1):
        cv2.imwrite(str(d / "img1" / f"{t:06d}.png"), f)
    rows = [[t, k + 1, *box, 1, 1, 1] for t, tr in enumerate(truths, 1) for k, box in enumerate(tr.boxes)
            if np.all(np.isfinite(box))]
    write_mot_groundtruth(d / "gt" / "gt.txt", np.array(rows, dtype=np.float64))
    write_seqinfo(d, name="movers", fps=10, length=len(frames), width=320, height=240, ext=".png")
    firsts = {}
    for k in (0, 8):
        out = tmp_path / f"tracks{k}.txt"
        assert main(["mot", str(d), "--out", str(out), "--quiet", "--param", f"bootstrap_frames={k}"]) == 0
        got = read_mot_txt(out)
        firsts[k] = got[:, 0].min()
        assert got[:, 0].max() == len(frames)          # every frame tracked once, numbered as read
        rec = run_job(Job(TrackerConfig("multi-pf", "multi-pf", (("bootstrap_frames", k),)), str(d), "movers", 0,
                          "mot"))
        assert rec["frames"] == len(frames)
        firsts[f"eval {k}"] = rec["mota"]
    assert firsts[8] < firsts[0]
    assert firsts["eval 8"] > firsts["eval 0"]
