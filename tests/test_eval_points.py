"""Measures of the point-tracking experiments (book ch. 7): recovery after occlusion, runs, passes behind a post."""

from __future__ import annotations

import numpy as np

from pftrack.eval.points import box_passes, recovery, run_points, run_stereo
from pftrack.synth.occluder import occluder_scene, stereo_rail_scene
from pftrack.trackers.point_gate import PointParams, PointTracker
from pftrack.trackers.stereo import StereoParams


def test_recovery_checks_each_occluded_point_after_its_exit():
    truth = np.zeros((10, 4, 2))
    pos = truth.copy()
    pos[7, 0] = (2.0, 2.0)  # 2.83 px off five frames after its exit at frame 2: recovered
    pos[8, 1] = (3.0, 1.0)  # 3.16 px off at its check frame: not recovered
    exits = np.array([2, 3, -1, 6])  # point 2 was never occluded; point 3's check frame (11) is past the end
    np.testing.assert_array_equal(recovery(pos, truth, exits, after=5, tol=3.0), [True, False])
    np.testing.assert_array_equal(recovery(pos, truth, exits, after=5, tol=3.5), [True, True])
    assert recovery(pos, truth, np.array([-1, -1, -1, -1])).size == 0


def _gt(rows):
    return np.array([[f, tid, x, 100.0, 20.0, 50.0, 1, 1, 1] for f, tid, x in rows])


def test_box_passes_finds_contiguous_overlaps_with_margins_present():
    post = (200.0, 210.0)
    rows = []
    # identity 1 walks right past the post (overlap while 180 < x < 210), present on frames 1-40
    rows += [(f, 1, 150.0 + 3 * (f - 1)) for f in range(1, 41)]
    # identity 2 overlaps on frames 20-24 but is missing from frame 30 on: the tail is not seen, no pass
    rows += [(f, 2, 185.0) if 20 <= f <= 24 else (f, 2, 50.0) for f in range(1, 30)]
    # identity 3 passes twice: frames 10-12 and 25-26, present throughout
    rows += [(f, 3, 195.0 if f in (10, 11, 12, 25, 26) else 20.0) for f in range(1, 60)]
    passes = box_passes(_gt(rows), post, lead=5, tail=10)
    got = {(p["id"], p["start"], p["exit"], p["init"]) for p in passes}
    x = 150.0 + 3 * np.arange(40)
    over = np.flatnonzero((x < 210) & (x + 20 > 200)) + 1  # frames numbered from 1
    assert got == {(1, int(over[0]), int(over[-1]) + 1, int(over[0]) - 5), (3, 10, 13, 5), (3, 25, 27, 20)}
    # a vertical range that misses the boxes (y 100-150) finds nothing
    assert box_passes(_gt(rows), post, y_range=(300.0, 400.0)) == []


def test_run_points_is_the_point_tracker_frame_by_frame():
    sc = occluder_scene(2, trajectory="line", vel=3.0, bar="textured", occlusion_frames=12)
    r = run_points(sc.frames, sc.points[0], PointParams(method="rls"))
    tr = PointTracker(PointParams(method="rls"))
    steps = [tr.init(sc.frames[0], sc.points[0])] + [tr.step(f) for f in sc.frames[1:]]
    np.testing.assert_array_equal(r["pos"], np.array([s.pos for s in steps]))
    np.testing.assert_array_equal(r["source"], np.array([s.source for s in steps]))
    T, P = sc.points.shape[:2]
    assert r["pos"].shape == (T, P, 2) and r["k"].shape == (T, P) and r["eps"].shape == (T, P)
    ok = recovery(r["pos"], sc.points, sc.exit_frames())
    assert ok.size > 0 and ok.mean() >= 0.5


def test_run_stereo_returns_both_views_and_depth_per_frame():
    sc = stereo_rail_scene(1, n_points=3)
    r = run_stereo(sc, StereoParams(method="rls"))
    T, P = sc.xl.shape[:2]
    assert r["xl"].shape == (T, P, 2) and r["xr"].shape == (T, P) and r["Z"].shape == (T, P)
    assert r["src_l"].shape == (T, P) and r["src_r"].shape == (T, P)
    np.testing.assert_allclose(r["xl"][0], sc.xl[0])
    np.testing.assert_allclose(r["Z"][0], sc.depth[0], rtol=0.05)  # depth from the first frame's disparity
