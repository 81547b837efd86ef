"""A target at the image's edge: trackers report the part of their box inside the frame, the synthetic ground
truth boxes the same part, and `pftrack eval` scores both within the frame (the VOT toolkit's bounds)."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.eval.metrics import lost_detection, ope_scores, within_frame
from pftrack.eval.vot import run_vot
from pftrack.geometry import visible_box
from pftrack.synth import Scene
from pftrack.synth.scenes import SceneSpec, Target, export_otb


def test_visible_box_cuts_to_the_frame_and_keeps_a_pixel():
    assert visible_box((10.0, 10.0, 5.0, 5.0), 100, 100) is None  # inside: unchanged
    assert visible_box((0.0, 0.0, 100.0, 100.0), 100, 100) is None  # the whole frame is inside
    assert visible_box((-5.0, 10.0, 20.0, 5.0), 100, 100) == (0.0, 10.0, 15.0, 5.0)
    assert visible_box((98.0, 95.0, 20.0, 20.0), 100, 100) == (98.0, 95.0, 2.0, 5.0)
    assert visible_box((-50.0, -50.0, 5.0, 5.0), 100, 100) == (0.0, 0.0, 1.0, 1.0)  # wholly outside
    assert visible_box((150.0, 20.0, 5.0, 5.0), 100, 100) == (99.0, 20.0, 1.0, 5.0)
    # a box under a pixel inside the frame grows to one from its top-left corner (the protocol's smallest box)
    assert visible_box((40.5, 41.0, 0.95, 0.99), 100, 100) == (40.5, 41.0, 1.0, 1.0)
    assert visible_box((40.5, 41.0, 0.5, 3.0), 100, 100) == (40.5, 41.0, 1.0, 3.0)
    assert visible_box((99.5, 20.0, 0.2, 0.2), 100, 100) == (99.0, 20.0, 1.0, 1.0)  # at the edge: kept inside


def _leaving_scene(seed: int) -> SceneSpec:
    """A target that walks out through the right edge (gone from about frame 27)."""
    target = Target(path=((0, 230.0, 120.0), (40, 380.0, 120.0)), size=(26.0, 52.0))
    return SceneSpec(n_frames=40, seed=seed, targets=(target,), background="flat", kind="exit")


@pytest.mark.parametrize("name", ["color-pf", "fusion-pf", "opencv-kcf"])
def test_trackers_report_the_visible_part_and_keep_the_whole_estimate(name):
    scene = Scene(_leaving_scene(0))
    frames = scene.frames()
    h, w = frames[0].shape[:2]
    t = pftrack.create_tracker(name, seed=0)
    t.init(frames[0], tuple(scene.groundtruth()[0]))
    cut = 0
    for f in frames[1:]:
        st = t.update(f)
        x, y, bw, bh = st.box
        assert x >= 0 and y >= 0 and x + bw <= w + 1e-9 and y + bh <= h + 1e-9 and bw >= 1 and bh >= 1
        if "box_full" in st.info:
            fx, fy, fw, fh = st.info["box_full"]
            assert fx < 0 or fy < 0 or fx + fw > w or fy + fh > h  # only set when the estimate reaches out
            assert visible_box(st.info["box_full"], w, h) == tuple(st.box)
            cut += 1
    if name != "opencv-kcf":  # the particle filters follow the target to the edge
        assert cut > 0


def test_scores_within_the_frame_agree_whatever_the_annotation_convention():
    """A prediction that reaches beyond the edge scores the same against a whole-body box (MOTChallenge style) as
    against its visible part (OTB style); without bounds the two conventions disagree."""
    whole = np.array([[80.0, 10.0, 40.0, 30.0], [90.0, 10.0, 40.0, 30.0]])
    visible = within_frame(whole, (100, 100))
    np.testing.assert_allclose(visible, [[80, 10, 20, 30], [90, 10, 10, 30]])
    pred = whole + [1.0, 0.0, 0.0, 0.0]
    a = ope_scores(pred, whole, bounds=(100, 100))
    b = ope_scores(pred, visible, bounds=(100, 100))
    assert a.auc == pytest.approx(b.auc) and a.mean_iou == pytest.approx(b.mean_iou)
    assert ope_scores(pred, visible).mean_iou < 0.6 < a.mean_iou  # the part outside counted against it
    # a ground-truth box wholly outside the frame counts as missing
    out = np.vstack([whole, [[120.0, 10.0, 10.0, 10.0]]])
    assert ope_scores(np.vstack([pred, [[0, 0, 5, 5]]]), out, bounds=(100, 100)).n_frames == 2


def test_lost_detection_within_the_frame():
    gt = np.array([[np.nan] * 4, [90.0, 10.0, 40.0, 30.0], [90.0, 10.0, 40.0, 30.0]])
    pred = np.array([[0.0, 0, 5, 5], [90.0, 10.0, 10.0, 30.0], [90.0, 10.0, 10.0, 30.0]])  # the visible part
    absent = np.array([True, False, False])
    lost = np.array([True, False, False])
    assert lost_detection(lost, pred, gt, absent).reacquired == 0  # IoU 0.25 against the whole box
    assert lost_detection(lost, pred, gt, absent, bounds=(100, 100)).reacquired == 1


def test_vot_overlap_within_the_frame():
    class Fixed:
        def init(self, frame, box):
            pass

        def update(self, frame):
            return pftrack.TrackState(box=(90.0, 10.0, 10.0, 30.0), score=1.0, lost=False)

    frames = [np.zeros((100, 100, 3), np.uint8)] * 20
    gt = np.tile([90.0, 10.0, 40.0, 30.0], (20, 1))
    res = run_vot(Fixed(), frames, gt)
    assert res.failures == 0 and res.accuracy == pytest.approx(1.0)


def test_synthetic_ground_truth_boxes_the_visible_part(tmp_path):
    spec = _leaving_scene(0)
    export_otb(spec, tmp_path / "s")
    gt = np.loadtxt(tmp_path / "s" / "groundtruth_rect.txt", delimiter=",")
    meta = json.loads((tmp_path / "s" / "meta.json").read_text())
    whole = Scene(spec).groundtruth()
    w = Scene(spec).render(0)[0].shape[1]
    ok = np.isfinite(gt).all(axis=1)
    assert (gt[ok, 0] + gt[ok, 2] <= w + 1e-6).all() and (gt[ok, 0] >= 0).all()
    cut = ok & (whole[:, 0] + whole[:, 2] > w)
    assert cut.any()  # the scene takes the target across the edge
    np.testing.assert_allclose(gt[cut, 2], w - whole[cut, 0], atol=1e-3)
    vis = np.array(meta["visible"])
    assert np.isnan(gt[vis <= 0]).all()


def test_eval_scores_a_whole_body_annotation_within_the_frame(tmp_path):
    """`pftrack eval` on an OTB folder whose boxes run past the edge (MOTChallenge style): scored within the frame,
    and a box wholly outside the frame is an absent frame."""
    from pftrack.eval.runner import Job, TrackerConfig, run_job

    scene = Scene(_leaving_scene(0))
    frames = scene.frames()
    whole = scene.groundtruth()
    h, w = frames[0].shape[:2]
    (tmp_path / "s" / "img").mkdir(parents=True)
    for t, f in enumerate(frames):
        cv2.imwrite(str(tmp_path / "s" / "img" / f"{t + 1:04d}.png"), f)
    np.savetxt(tmp_path / "s" / "groundtruth_rect.txt", whole, delimiter=",", fmt="%.3f")
    rec = run_job(Job(TrackerConfig("fusion-pf", "fusion-pf"), str(tmp_path / "s"), "s", 0, "ope"))
    outside = whole[:, 0] >= w
    assert outside[1:].any() and rec["absent_frames"] == int(outside[1:].sum())
    boxes = np.array(rec["boxes"], float).reshape(-1, 4)
    assert rec["mean_iou"] == pytest.approx(ope_scores(boxes, whole, bounds=(w, h)).mean_iou)


def test_track_writes_the_whole_box_beside_the_visible_part(tmp_path):
    """`pftrack track --json-out`: a frame whose estimate reaches past the edge carries `box_full` beside `box`."""
    from pftrack.cli import main

    export_otb(_leaving_scene(0), tmp_path / "s")
    out = tmp_path / "t.jsonl"
    assert main(["track", str(tmp_path / "s"), "--tracker", "fusion-pf", "--out", str(tmp_path / "t.csv"),
                 "--json-out", str(out), "--quiet"]) == 0
    recs = [json.loads(line) for line in out.read_text().splitlines()]
    cut = [r for r in recs if "box_full" in r]
    assert cut and all(r["box"][0] + r["box"][2] <= 320 + 1e-9 for r in recs)
    assert all(visible_box(r["box_full"], 320, 240) == tuple(r["box"]) for r in cut)
