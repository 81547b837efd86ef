"""Book ch. 7: LK points gated by RLS prediction through occlusions, stereo, the CLIs (ch07.md §5.1)."""

import json

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.cli import main
from pftrack.cues.lk import LKConfig, lk_flow, reanchor
from pftrack.synth.occluder import (
    export_point_scene,
    export_stereo_scene,
    occluder_scene,
    stereo_rail_scene,
    texture,
)
from pftrack.trackers.point_gate import FLOW, PREDICTION, PointParams, PointTracker
from pftrack.trackers.stereo import (
    StereoParams,
    StereoTracker,
    disparity_search,
    triangulate,
)

TUNE_SEEDS = range(12)  # synthetic tune split; the report figures use seeds 100+


def _gray_texture(seed=0, shape=(120, 160)):
    rng = np.random.default_rng(seed)
    return np.clip(texture(rng, *shape, color=False)[:, :, 0], 0, 255).astype(np.uint8)


def _run(scene, **kw):
    pt = PointTracker(PointParams(**kw))
    first = pt.init(scene.frames[0], scene.points[0])
    steps = [first] + [pt.step(f) for f in scene.frames[1:]]
    return steps, np.array([s.pos for s in steps])


def test_lk_estimates_a_subpixel_shift():
    img = _gray_texture(0)
    m = np.float32([[1, 0, 2.3], [0, 1, -1.7]])
    moved = cv2.warpAffine(img, m, img.shape[::-1], flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    pts = np.random.default_rng(1).uniform(20, [140, 100], (50, 2))
    new, ok = lk_flow(img, moved, pts, LKConfig(levels=2))
    assert ok.all()
    err = np.abs(new - pts - [2.3, -1.7])
    # 7x7 windows on a bilinearly shifted texture: 0.02 px typical, a few windows 0.1 px
    assert np.median(err) <= 0.05 and err.max() <= 0.25


def test_lk_marks_failures_and_points_leaving_the_image():
    img = _gray_texture(1)
    flat = np.full_like(img, 128)
    new, ok = lk_flow(flat, flat, np.array([[50.0, 50.0]]))
    assert not ok[0] and np.isnan(new[0]).all()  # eigenvalue test on a flat window
    shifted = np.roll(img, 6, axis=1)
    new, ok = lk_flow(img, shifted, np.array([[157.0, 60.0], [-3.0, 10.0]]))
    assert not ok.any()  # the first moves out of the image, the second starts outside
    back_ok = lk_flow(img, shifted, np.array([[60.0, 60.0]]), LKConfig(fb_check=True))[1]
    assert back_ok[0]


def test_reanchor_finds_the_reference_under_gain_change():
    img = _gray_texture(2)
    later = cv2.warpAffine(img, np.float32([[1, 0, 3.4], [0, 1, 1.2]]), img.shape[::-1], flags=cv2.INTER_LINEAR)
    later = np.clip(later.astype(np.float32) * 0.8 + 20, 0, 255).astype(np.uint8)
    ref = np.array([[70.0, 60.0]])
    guess = ref + [3.4, 1.2] + [4.0, -3.0]  # a drifted estimate
    fixed, ok = reanchor(img, later, ref, guess, half=4, max_shift=8)
    assert ok[0]
    np.testing.assert_allclose(fixed[0], ref[0] + [3.4, 1.2], atol=0.3)


def test_occluder_scene_ground_truth():
    sc = occluder_scene(3, trajectory="line", vel=3.0, occlusion_frames=10, bar="textured")
    ex = sc.exit_frames()
    assert (ex > 0).all()
    for j in range(sc.points.shape[1]):
        hidden = np.flatnonzero(sc.occluded[:, j])
        assert 8 <= len(hidden) <= 12 and np.all(np.diff(hidden) == 1)
    steps = np.diff(sc.points, axis=0)
    np.testing.assert_allclose(np.hypot(*steps.reshape(-1, 2).T), 3.0, atol=1e-9)
    a, b = occluder_scene(3), occluder_scene(3)
    np.testing.assert_array_equal(a.frames[5], b.frames[5])


@pytest.mark.parametrize("vel", [2.0, 3.0, 4.0])
def test_e71_error_profile_inside_the_obstacle(vel):
    """E7.1: with the window fully on the static obstacle LK returns ~0, so eps ~ vel."""
    sc = occluder_scene(1, trajectory="line", vel=vel, bar="textured", occlusion_frames=round(37 / vel))
    steps, _ = _run(sc, method="rls")
    eps = np.array([s.eps for s in steps])
    x0, x1 = sc.obstacle
    inside = (sc.points[:, :, 0] - 3.5 > x0) & (sc.points[:, :, 0] + 3.5 < x1)
    mean = float(np.mean(eps[inside]))
    assert 0.8 * vel <= mean <= 1.2 * vel


def test_gate_switches_to_prediction_on_occlusion_and_back():
    sc = occluder_scene(2, trajectory="line", vel=3.0, bar="textured", occlusion_frames=12)
    steps, pos = _run(sc, method="rls")
    src = np.array([s.source for s in steps])
    x0, x1 = sc.obstacle
    full = (sc.points[:, :, 0] - 3.5 > x0) & (sc.points[:, :, 0] + 3.5 < x1)
    assert np.mean(src[full] == PREDICTION) >= 0.9
    occ = sc.occluded
    near = np.zeros_like(occ)
    for d in range(-2, 3):
        near |= np.roll(occ, d, axis=0)
    far = ~near
    far[:8] = False  # the filter's first N_in frames
    assert np.mean(src[far] == FLOW) >= 0.95
    err = np.hypot(*(pos[-1] - sc.points[-1]).T)
    assert np.median(err) <= 3.0


def test_recovery_after_occlusion_gate_matters():
    """The issue's 'done when' on the tune seeds: >= 80 % within 3 px five frames after the bar (rls,
    fuzzy); plain LK stays on the bar (<= 50 %)."""
    ok: dict[str, list] = {"lk": [], "rls": [], "fuzzy": []}
    for seed in TUNE_SEEDS:
        sc = occluder_scene(seed)
        for method in ok:
            _, pos = _run(sc, method=method)
            err = np.hypot(*(pos - sc.points).transpose(2, 0, 1))
            ok[method] += [err[e + 5, j] <= 3.0 for j, e in enumerate(sc.exit_frames()) if e >= 0]
    rates = {m: float(np.mean(v)) for m, v in ok.items()}
    assert rates["rls"] >= 0.8 and rates["fuzzy"] >= 0.8, rates
    assert rates["lk"] <= 0.5, rates


def test_fuzzy_gain_drops_on_occluded_frames():
    """E7.3: k falls on the hidden frames and stays high elsewhere."""
    lows, highs = [], []
    for seed in (0, 1, 2):
        sc = occluder_scene(seed, trajectory="curve", bar="textured")
        steps, _ = _run(sc, method="fuzzy")
        k = np.array([s.k for s in steps])
        x0, x1 = sc.obstacle
        full = (sc.points[:, :, 0] - 3.5 > x0) & (sc.points[:, :, 0] + 3.5 < x1)
        near = np.zeros_like(sc.occluded)
        for d in range(-3, 4):
            near |= np.roll(sc.occluded, d, axis=0)
        clear = ~near
        clear[:9] = False
        lows.append(np.nanmean(k[full]))
        highs.append(np.nanmean(k[clear]))
    assert np.mean(lows) <= 0.65
    assert np.mean(highs) >= 0.9


def test_a_point_hidden_too_long_is_lost():
    sc = occluder_scene(4, trajectory="line", vel=2.0, occlusion_frames=12)
    steps, _ = _run(sc, method="rls", max_predict=3, reanchor=False, verify=False)
    assert any((s.source == 2).any() for s in steps)


def test_triangulation_is_exact():
    f, B, cx, cy = 500.0, 0.1, 320.0, 240.0
    X, Y, Z = np.array([0.3, -0.2]), np.array([0.1, 0.05]), np.array([2.0, 4.0])
    x1, y1 = f * X / Z + cx, f * Y / Z + cy
    x2 = f * (X - B) / Z + cx
    Xe, Ye, Ze = triangulate(x1, y1, x1 - x2, f=f, B=B, cx=cx, cy=cy)
    np.testing.assert_allclose(np.stack([Xe, Ye, Ze]), np.stack([X, Y, Z]), atol=1e-12)
    assert np.isnan(triangulate(1.0, 1.0, -2.0, f=f, B=B, cx=cx, cy=cy)[2])


def test_disparity_search_is_subpixel():
    img = _gray_texture(5, (120, 200))
    for true_d in (12.5, 17.3, 25.0):
        right = cv2.warpAffine(img, np.float32([[1, 0, -true_d], [0, 1, 0]]), (200, 120), flags=cv2.INTER_LINEAR)
        d, score = disparity_search(img, right, np.array([[120.0, 60.0], [150.0, 40.0]]), 0, 40)
        np.testing.assert_allclose(d, true_d, atol=0.25)
        assert (score > 0.9).all()


def test_stereo_depth_through_occlusion():
    for seed in (0, 3):
        sc = stereo_rail_scene(seed)
        rel = {}
        for method in ("fuzzy", "lk"):
            tr = StereoTracker(sc.calib, StereoParams(method=method))
            steps = [tr.init(sc.left[0], sc.right[0], sc.xl[0])]
            steps += [tr.step(a, b) for a, b in zip(sc.left[1:], sc.right[1:])]
            Z = np.array([s.Z for s in steps])
            r = np.abs(Z - sc.depth) / sc.depth
            rel[method] = np.where(np.isfinite(r), r, 1.0)
        assert np.median(rel["fuzzy"]) <= 0.05
        assert (sc.occluded_left & sc.occluded_right).any()
        assert np.median(rel["lk"][-10:]) > 0.05  # without prediction the points stay on the bar


def test_points_cli(tmp_path):
    sc = occluder_scene(6, trajectory="line", vel=3.0)
    export_point_scene(sc, tmp_path / "scene")
    meta = json.loads((tmp_path / "scene" / "meta.json").read_text())
    out, diag = tmp_path / "p.csv", tmp_path / "d.csv"
    assert main(["points", str(tmp_path / "scene"), "--points", meta["points"], "--method", "rls", "--out", str(out),
                 "--diag", str(diag), "--quiet"]) == 0
    rows = out.read_text().splitlines()
    assert rows[0] == "frame,point,x,y,source"
    n = sc.points.shape[1]
    assert len(rows) == 1 + n * len(sc.frames)
    first = rows[1].split(",")
    assert first[0] == "1" and first[1] == "0" and first[4] == "flow"
    assert {r.split(",")[4] for r in rows[1:]} <= {"flow", "prediction", "lost"}
    assert "prediction" in {r.split(",")[4] for r in rows[1:]}
    assert diag.read_text().splitlines()[0].startswith("frame,point,x,y,vx_of")
    assert main(["points", str(tmp_path / "scene"), "--points", "5000,10", "--out", str(out), "--quiet"]) == 2
    assert main(["points", str(tmp_path / "scene"), "--points", "1,2,3", "--out", str(out), "--quiet"]) == 2
    assert main(["points", str(tmp_path / "missing"), "--points", "1,2", "--out", str(out), "--quiet"]) == 2


def test_stereo_cli(tmp_path):
    sc = stereo_rail_scene(1)
    export_stereo_scene(sc, tmp_path / "st")
    meta = json.loads((tmp_path / "st" / "meta.json").read_text())
    left, right, calib = (str(tmp_path / "st" / k) for k in ("left", "right", "calib.json"))
    out = tmp_path / "s.csv"
    assert main(["stereo", left, right, "--calib", calib, "--points", meta["points"], "--out", str(out),
                 "--quiet"]) == 0
    rows = out.read_text().splitlines()
    assert rows[0] == "frame,point,xl,yl,xr,yr,Z"
    vals = np.array([[float(v) for v in r.split(",")] for r in rows[1:]])
    assert len(vals) == sc.xl.shape[1] * len(sc.left)
    gt = sc.depth.reshape(-1)
    assert np.median(np.abs(vals[:, 6] - gt) / gt) <= 0.05
    assert main(["stereo", left, right, "--calib", str(tmp_path / "none.json"), "--points", meta["points"],
                 "--out", str(out), "--quiet"]) == 2
    bad = tmp_path / "bad.json"
    bad.write_text('{"f": 300}')
    assert main(["stereo", left, right, "--calib", str(bad), "--points", meta["points"], "--out", str(out),
                 "--quiet"]) == 2
    assert main(["stereo", left, right, "--calib", calib, "--points=-4,10", "--out", str(out), "--quiet"]) == 2


def test_points_cli_draws_each_frame_with_the_points_trails(tmp_path):
    sc = occluder_scene(6, trajectory="line", vel=3.0)
    export_point_scene(sc, tmp_path / "scene")
    meta = json.loads((tmp_path / "scene" / "meta.json").read_text())
    video = tmp_path / "p.mp4"
    assert main(["points", str(tmp_path / "scene"), "--points", meta["points"], "--out", str(tmp_path / "p.csv"),
                 "--video-out", str(video), "--quiet"]) == 0
    cap = cv2.VideoCapture(str(video))
    drawn = []
    while (got := cap.read())[0]:
        drawn.append(got[1])
    cap.release()
    assert len(drawn) == len(sc.frames)
    plain = sc.frames[-1] if sc.frames[-1].ndim == 3 else cv2.cvtColor(sc.frames[-1], cv2.COLOR_GRAY2BGR)
    diff = np.abs(drawn[-1].astype(int) - plain.astype(int)).max(axis=2)
    assert (diff > 100).sum() > 20 * meta["points"].count(";")  # markers and trails drawn on the last frame


def test_stereo_cli_refuses_bad_calibrations_and_unmatched_frames(tmp_path, capsys):
    sc = stereo_rail_scene(1)
    export_stereo_scene(sc, tmp_path / "st")
    meta = json.loads((tmp_path / "st" / "meta.json").read_text())
    left, right = (str(tmp_path / "st" / k) for k in ("left", "right"))
    out = tmp_path / "s.csv"
    bad = tmp_path / "bad.json"
    for text, message in [("[1, 2]", "calibration lacks f, B, cx, cy"), ("{", "not a JSON calibration"),
                          ('{"f": "x", "B": 0.1, "cx": 1, "cy": 2}', "must be numbers"),
                          ('{"f": 300, "B": -0.1, "cx": 1, "cy": 2}', "f and B must be positive")]:
        bad.write_text(text)
        assert main(["stereo", left, right, "--calib", str(bad), "--points", meta["points"], "--out", str(out),
                     "--quiet"]) == 2
        assert message in capsys.readouterr().err
    small = tmp_path / "small"
    small.mkdir()
    for f in sorted((tmp_path / "st" / "right").iterdir()):
        cv2.imwrite(str(small / f.name), cv2.imread(str(f))[:-8])
    assert main(["stereo", left, str(small), "--calib", str(tmp_path / "st" / "calib.json"), "--points",
                 meta["points"], "--out", str(out), "--quiet"]) == 2
    assert "right frames" in capsys.readouterr().err


def test_lk_rls_box_tracker_through_the_bar():
    sc = occluder_scene(7, trajectory="line", vel=3.0, bar="textured", occlusion_frames=12, size=34)
    size = sc.meta["size"]
    # the object's box from its points' offsets: the first point is inside the sprite
    corner0 = sc.points[0, 0] - (sc.points[0, 0] - sc.points[0].min(0)) - 3
    box = (*corner0, size * 0.7, size * 0.7)
    states = []
    for name in ("lk-rls", "lk-rls-fuzzy"):
        tr = pftrack.create_tracker(name)
        s = [tr.init(sc.frames[0], box)] + [tr.update(f) for f in sc.frames[1:]]
        states.append(s)
        centres = np.array([[b.box[0] + b.box[2] / 2, b.box[1] + b.box[3] / 2] for b in s])
        truth = sc.points.mean(1)
        moved = centres - centres[0] - (truth - truth[0])
        assert np.hypot(*moved[-1]) <= 6.0  # through the bar and out with the object
        assert 0.0 <= min(b.score for b in s) <= max(b.score for b in s) <= 1.0
    assert pftrack.create_tracker("lk-rls").params.method == "rls"
    assert pftrack.create_tracker("lk-rls-fuzzy").params.method == "fuzzy"


def test_lk_rls_calls_a_target_that_left_the_view_lost():
    """Over leave and exit scenes of three seeds each: a walker that leaves through an edge is flagged while out of
    view. With exit_share=0 (the former default) fresh corners were clipped onto the border, followed the still
    background, and the flag stayed down on whole scenes (docs/points.md, "Targets that leave the view")."""
    from pftrack.eval.metrics import lost_detection
    from pftrack.synth import Scene, hidden_frames, leave_scene
    from pftrack.synth.varied import exit_scene

    def flag(frames, gt, hid, **params):
        t = pftrack.create_tracker("lk-rls", **params)
        t.init(frames[0], tuple(gt[0]))
        states = [t.update(f) for f in frames[1:]]
        return lost_detection(np.array([s.lost for s in states]), np.array([s.box for s in states]), gt[1:], hid[1:])

    now, before = [], []
    for spec in (make(seed) for make in (leave_scene, exit_scene) for seed in range(300, 303)):
        scene = Scene(spec)
        frames, gt, hid = scene.frames(), scene.groundtruth(0), hidden_frames(spec)
        now.append(flag(frames, gt, hid))
        before.append(flag(frames, gt, hid, exit_share=0.0))
    assert all(r.recall >= 0.9 for r in now if r.absent_frames)
    assert all(not r.false_rate > 0.02 for r in now)   # NaN when no frame is covered
    assert sum(r.recall < 0.1 for r in before if r.absent_frames) >= 2


def test_lk_rls_share_in_view_and_corners_in_view():
    from pftrack.geometry import in_frame_fraction as share_in_view   # lk-rls's exit test
    from pftrack.trackers.lk_rls import box_points

    assert share_in_view((10, 10, 20, 20), 100, 80) == 1.0
    assert share_in_view((-15, 10, 20, 20), 100, 80) == pytest.approx(0.25)
    assert share_in_view((90, 70, 20, 20), 100, 80) == pytest.approx(0.25)
    assert share_in_view((-30, 10, 20, 20), 100, 80) == 0.0
    flat = np.full((80, 100), 128, np.uint8)               # no corners: the grid pads
    clipped = box_points(flat, (-15, 10, 20, 20), 16)
    assert len(clipped) == 16 and (clipped[:, 0] == 0).sum() >= 8      # the former way: piled on the border
    seen = box_points(flat, (-15, 10, 20, 20), 16, in_view=True)
    assert len(seen) and (seen[:, 0] > 0).all()
    assert len(box_points(flat, (-30, 10, 20, 20), 16, in_view=True)) == 0


def test_lk_rls_box_patch_and_ncc():
    from pftrack.trackers.lk_rls import PATCH, box_ncc, box_patch

    rng = np.random.default_rng(0)
    gray = rng.integers(0, 255, (60, 80)).astype(np.uint8)
    crop = cv2.resize(gray[10:42, 20:52], (PATCH, PATCH), interpolation=cv2.INTER_AREA).astype(np.float64)
    patch = box_patch(gray, (20, 10, 32, 32))
    assert patch.shape == (PATCH, PATCH)
    assert np.corrcoef(patch.ravel(), crop.ravel())[0, 1] > 0.6          # the box's content, not elsewhere
    assert box_ncc(gray, (20, 10, 32, 32), patch) == pytest.approx(1.0)
    lit = np.clip(gray.astype(np.float64) * 0.5 + 40, 0, 255).astype(np.uint8)     # a gain and an offset
    assert box_ncc(lit, (20, 10, 32, 32), patch) > 0.99
    assert box_ncc(gray, (20, 10, 32, 32), np.full((PATCH, PATCH), 7.0)) == 0.0    # a flat template
    assert abs(box_ncc(gray, (40, 25, 32, 32), patch)) < 0.5


def test_lk_rls_reseed_lost_ends_a_flag_stuck_on_the_face():
    """``reseed_lost`` (an option, docs/points.md): over grey face scenes of three seeds, one locks up without it
    (most points fall to prediction under the dimming light, nothing is replaced while lost, and the flag stays up
    on the face); with it the flagged frames fall by more than half and the boxes are as good."""
    from .conftest import face_proxy_run

    runs = [(face_proxy_run("lk-rls", s), face_proxy_run("lk-rls", s, reseed_lost=0.7)) for s in range(303, 306)]
    before = [sum(a[1]) for a, _ in runs]
    after = [sum(b[1]) for _, b in runs]
    assert max(before) >= 30 and sum(after) < 0.5 * sum(before)
    assert all(b[0] >= a[0] - 0.01 for a, b in runs)
    assert pftrack.create_tracker("lk-rls").params.reseed_lost == 0.0
