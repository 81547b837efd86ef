"""Book ch. 10: the trackerless tripwire, crossings of tracks, event scoring, the command (ch10.md §5)."""

import functools

import numpy as np
import pytest

from pftrack.cli import main
from pftrack.events.eval import match_events, track_crossings
from pftrack.events.geometry import (
    build_patches,
    crossings_of_track,
    parse_polyline,
    polyline_project,
)
from pftrack.events.scoring import bhattacharyya_distance, patch_similarity, ssd_motion
from pftrack.events.tripwire import TrackerlessTripwire, TripwireParams, estimate_radius
from pftrack.synth.traffic import export_traffic, traffic_scene

from .conftest import grey_frames

WIRE = np.array([[100.0, 200.0], [300.0, 200.0]])

def test_patches_of_a_straight_wire():
    lay = build_patches(WIRE, r=10, spacing=10)
    inner, outer = lay.of_side(-1), lay.of_side(1)
    assert len(inner) == len(outer) == 21
    np.testing.assert_allclose(lay.centres[inner, 1], 190.0)
    np.testing.assert_allclose(lay.centres[outer, 1], 210.0)
    np.testing.assert_allclose(lay.w[inner], np.tile([0.0, 1.0], (21, 1)), atol=1e-12)
    np.testing.assert_allclose(lay.w[outer], np.tile([0.0, -1.0], (21, 1)), atol=1e-12)
    rev = build_patches(WIRE[::-1], r=10, spacing=10)  # reversed vertex order swaps the sides
    np.testing.assert_allclose(rev.centres[rev.of_side(-1), 1], 210.0)


def test_patches_of_an_l_shaped_wire():
    pts = np.array([[100.0, 100.0], [200.0, 100.0], [200.0, 200.0]])
    lay = build_patches(pts, r=10)
    dist = polyline_project(lay.centres, pts)[0]
    np.testing.assert_allclose(dist, 10.0, atol=1e-9)
    assert len(lay.of_side(-1)) != len(lay.of_side(1))
    with pytest.raises(ValueError):
        parse_polyline("1,2")
    with pytest.raises(ValueError):
        parse_polyline("1,2;1,2")
    np.testing.assert_array_equal(parse_polyline("1,2; 3,4;5,6"), [[1, 2], [3, 4], [5, 6]])


def test_signed_side_matches_the_issue_convention():
    # s(P) = (x2-x1)(Py-y1) - (y2-y1)(Px-x1) > 0 is the outer (positive) side
    p = np.array([[150.0, 230.0], [150.0, 170.0]])
    s_issue = (300 - 100) * (p[:, 1] - 200) - 0 * (p[:, 0] - 100)
    signed = polyline_project(p, WIRE)[4]
    np.testing.assert_array_equal(np.sign(signed), np.sign(s_issue))


def test_state_machine_counts_once_and_ignores_hovering():
    f = np.arange(30)
    down = np.stack([np.full(30, 150.0), np.linspace(170, 230, 30)], 1)
    c = crossings_of_track(f, down, WIRE, hysteresis=5)
    assert len(c) == 1 and c[0].direction == 1 and abs(c[0].frame - 14.5) < 0.6
    up = down[::-1]
    assert [x.direction for x in crossings_of_track(f, up, WIRE, hysteresis=5)] == [-1]
    hover = np.stack([np.full(60, 150.0), 200 + 3 * np.sin(np.arange(60))], 1)
    assert crossings_of_track(np.arange(60), hover, WIRE, hysteresis=5) == []
    beyond = down + [250.0, 0.0]  # passes beside the wire's end
    assert crossings_of_track(f, beyond, WIRE, hysteresis=5) == []
    # back and forth across the line: one crossing each way, never more
    y = np.interp(np.arange(90), [0, 30, 60, 89], [170, 230, 170, 230])
    zig = np.stack([np.full(90, 150.0), y], 1)
    dirs = [x.direction for x in crossings_of_track(np.arange(90), zig, WIRE, hysteresis=5)]
    assert dirs == [1, -1, 1]


def test_unconfirmed_tracks_are_ignored_and_each_track_counts_alone():
    rows = []
    for tid, x in ((1, 140.0), (2, 180.0)):
        for k, y in enumerate(np.linspace(150, 240, 20)):
            rows.append([k + 1, tid, x, y - 40, 20, 40, 1, -1, -1, -1])
    rows += [[5, 9, 200, 150, 20, 40, 1, -1, -1, -1], [6, 9, 200, 230, 20, 40, 1, -1, -1, -1]]  # 2 frames only
    c = track_crossings(np.array(rows), WIRE, hysteresis=5, min_frames=3)
    assert sorted(x.track for x in c) == [1, 2]


def test_bhattacharyya_distance_and_similarity():
    rng = np.random.default_rng(0)
    h = rng.random(512)
    h /= h.sum()
    a = np.zeros(512)
    a[:10] = 0.1
    b = np.zeros(512)
    b[20:30] = 0.1
    assert bhattacharyya_distance(h, h[None])[0] == pytest.approx(0.0, abs=1e-7)
    assert bhattacharyya_distance(a, b[None])[0] == pytest.approx(1.0)
    assert bhattacharyya_distance(a, h[None])[0] == pytest.approx(bhattacharyya_distance(h, a[None])[0])
    V = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 2.0]])
    S, s_c, s_m = patch_similarity(a, [2.0, 0.0], np.stack([a, a, a]), V, alpha_c=0.7, alpha_m=0.3)
    np.testing.assert_allclose(s_m, [1.0, -1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(s_c, [1.0, 0.0, 0.0], atol=1e-7)  # S_c = 0 where S_m <= 0 (Eq. 6)
    np.testing.assert_allclose(S, [1.0, -0.3, 0.0], atol=1e-7)


def test_ssd_motion():
    rng = np.random.default_rng(1)
    import cv2

    img = np.clip(cv2.GaussianBlur(rng.normal(128, 50, (80, 80)), (0, 0), 1.5), 0, 255).astype(np.uint8)
    moved = np.roll(np.roll(img, 3, axis=1), -2, axis=0)
    v, _ = ssd_motion(img, moved, (40, 40), 8, 6)
    np.testing.assert_allclose(v, [3.0, -2.0], atol=1e-9)
    half = cv2.warpAffine(img, np.float32([[1, 0, 2.5], [0, 1, 0]]), (80, 80), flags=cv2.INTER_LINEAR)
    v, _ = ssd_motion(img, half, (40, 40), 8, 6)
    assert abs(v[0] - 2.5) <= 0.2 and abs(v[1]) <= 0.2


def test_ssd_motion_small_motion_prior():
    """A flat dark patch (a uniformly dark coat) matches equally well far away; the prior keeps the small motion,
    and a textured patch's true motion survives it."""
    import cv2

    prev = np.full((120, 200), 180, np.uint8)
    prev[50:80, 60:80] = 40        # the object, one step earlier
    prev[50:80, 150:170] = 40      # a look-alike 90 px further on
    cur = np.full_like(prev, 180)
    cur[50:80, 63:83] = 40         # the object moved 3 px right
    cur[50:80, 150:170] = 40
    mask = (cur < 100).astype(np.uint8)
    # the square sees only the dark interior: every position inside either dark block is an exact match
    v0, _ = ssd_motion(prev, cur, (73, 65), 5, 95, mask=mask)
    v1, _ = ssd_motion(prev, cur, (73, 65), 5, 95, mask=mask, penalty=1.0)
    assert np.hypot(*v0) > 5  # plain SSD takes the first of the equal minima, far from the true motion
    assert np.hypot(*v1) < 1e-9  # inside a flat block the zero motion is as good as any: the prior takes it
    rng = np.random.default_rng(1)
    img = np.clip(cv2.GaussianBlur(rng.normal(128, 50, (80, 80)), (0, 0), 1.5), 0, 255).astype(np.uint8)
    moved = np.roll(np.roll(img, 3, axis=1), -2, axis=0)
    v, ssd = ssd_motion(img, moved, (40, 40), 8, 6, penalty=1.0)
    np.testing.assert_allclose(v, [3.0, -2.0], atol=1e-9)
    assert ssd == pytest.approx(0.0, abs=1e-6)  # the cost returned is the SSD, without the prior
    # near the frame's edge (a clipped search window) the prior is centred on the zero motion too
    v, _ = ssd_motion(img, moved, (12, 12), 8, 6, penalty=1.0)
    np.testing.assert_allclose(v, [3.0, -2.0], atol=1e-9)


def test_motion_prior_is_per_source_frame(monkeypatch):
    """With --stride K a displacement spans K source frames: the prior passed to the block matching is lambda / K^2,
    and the text's plain SSD (faithful) has none."""
    import pftrack.events.tripwire as tw_mod

    seen = []

    def spy(*args, penalty=0.0, **kw):
        seen.append(penalty)
        return np.zeros(2), 0.0

    monkeypatch.setattr(tw_mod, "ssd_motion", spy)
    rng = np.random.default_rng(0)
    # independent noise frames: the frame difference marks every patch foreground, so every patch matches motion
    frames = [np.clip(rng.normal(120, 60, (60, 80, 3)), 0, 255).astype(np.uint8) for _ in range(4)]
    for stride, faithful, expect in ((1, False, 2.0), (3, False, 2.0 / 9), (3, True, 0.0)):
        seen.clear()
        tw = TrackerlessTripwire(np.array([[40.0, 5.0], [40.0, 55.0]]), (60, 80), 10.0,
                                 TripwireParams(radius=4.0, motion_prior=2.0, faithful=faithful, bgs="diff"),
                                 stride=stride)
        for k, f in enumerate(frames):
            tw.process(f, 1 + k * stride)
        assert seen and all(v == pytest.approx(expect) for v in seen)


def test_event_matching():
    s = match_events([(10, 1), (50, 1), (90, -1)], [(12, 1), (49, -1), (95, -1), (200, 1)], tol=10)
    assert (s.gt, s.detected, s.tp) == (4, 3, 2)
    assert s.accuracy == pytest.approx(0.5) and s.precision == pytest.approx(2 / 3)
    assert match_events([(10, 1), (11, 1)], [(10, 1)], tol=5).tp == 1  # one-to-one


def _movers(positions, shape=(160, 240), colours=((40, 40, 220), (220, 60, 40))):
    """Frames of textured discs moving along the given (T, k, 2) paths over textured ground."""
    import cv2

    rng = np.random.default_rng(3)
    bg = np.clip(rng.normal(100, 8, (*shape, 3)), 0, 255).astype(np.uint8)
    frames = []
    for t in range(positions.shape[0]):
        f = bg.copy()
        for k, (x, y) in enumerate(positions[t]):
            cv2.circle(f, (int(round(x)), int(round(y))), 14, colours[k % len(colours)], -1)
            cv2.circle(f, (int(round(x)) - 4, int(round(y)) - 3), 4, (255, 255, 255), -1)
        frames.append(f)
    return frames


def _two_movers():
    """A horizontal wire, one disc crossing it downwards (+) and one upwards (-), 90 frames."""
    wire = np.array([[20.0, 80.0], [220.0, 80.0]])
    T = 90
    down = np.stack([np.full(T, 70.0), np.clip(10 + 2.0 * np.arange(T), None, 150)], 1)       # one crossing, +
    up = np.stack([np.full(T, 170.0), np.clip(160 - 2.0 * np.arange(T), 10, None)], 1)        # one crossing, -
    return wire, _movers(np.stack([down, up], 1))


def test_trackerless_tripwire_direction_and_count_once():
    wire, frames = _two_movers()
    tw = TrackerlessTripwire(wire, frames[0].shape[:2], 30.0, TripwireParams(radius=10, bgs_history=50))
    ev = []
    for n, f in enumerate(frames, 1):
        ev += tw.process(f, n)
    dirs = sorted(e.direction for e in ev)
    assert dirs == [-1, 1], [(e.frame, e.direction, e.x) for e in ev]
    pos_ev = next(e for e in ev if e.direction > 0)
    # the disc going down (radius 14, centre at y = 10 + 2 (n - 1)) has its foot point on y = 80 at frame 29
    assert pos_ev.x < 120 and 28 <= pos_ev.frame <= 30, pos_ev


@pytest.mark.parametrize("bits", [2, 3])
def test_patch_histograms_have_the_chosen_bins(bits):
    """``bits`` per channel: every history entry is a normalised histogram of 2^(3 bits) bins, and the crossings
    are found with either."""
    wire, frames = _two_movers()
    tw = TrackerlessTripwire(wire, frames[0].shape[:2], 30.0, TripwireParams(radius=10, bgs_history=50, bits=bits))
    ev = []
    for n, f in enumerate(frames, 1):
        ev += tw.process(f, n)
    entries = [e for p in tw.patches for e in p.entries]
    assert entries and all(e.hist.shape == (8 ** bits,) for e in entries)
    assert np.allclose([e.hist.sum() for e in entries], 1.0)
    assert sorted(e.direction for e in ev) == [-1, 1]


def test_trackerless_tripwire_ignores_a_mover_hovering_on_the_line():
    wire = np.array([[20.0, 80.0], [220.0, 80.0]])
    T = 120
    hover = np.stack([60 + 0.8 * np.arange(T), 80 + 6 * np.sin(np.arange(T) / 3.0)], 1)[:, None, :]
    frames = _movers(hover)
    tw = TrackerlessTripwire(wire, frames[0].shape[:2], 30.0, TripwireParams(radius=10, bgs_history=50))
    ev = []
    for n, f in enumerate(frames, 1):
        ev += tw.process(f, n)
    assert len(ev) <= 1


def test_synthetic_sparse_traffic_is_counted():
    gt = det = tp = 0
    for seed in (8, 10):
        sc = traffic_scene(seed, kind="sparse", n_vehicles=10)
        truth = [(c.frame, c.direction) for c in track_crossings(sc.tracks, sc.wire, hysteresis=3, point="centre")]
        assert len(truth) == 10
        tw = TrackerlessTripwire(sc.wire, sc.frames[0].shape[:2], sc.fps, TripwireParams(timing="match"))
        ev = []
        for n, f in enumerate(sc.frames, 1):
            ev += tw.process(f, n)
        s = match_events([(e.frame, e.direction) for e in ev], truth, tol=30)
        gt, det, tp = gt + s.gt, det + s.detected, tp + s.tp
    assert tp / gt >= 0.65 and tp / det >= 0.7, (gt, det, tp)


@functools.lru_cache(maxsize=1)
def _sparse_road():
    """The sparse traffic scene of the command's tests, rendered once (not changed by them)."""
    return traffic_scene(8, kind="sparse", n_vehicles=4)


def test_tripwire_cli(tmp_path):
    sc = _sparse_road()
    export_traffic(sc, tmp_path / "road")
    wire = (tmp_path / "road" / "wire.txt").read_text().strip()
    out = tmp_path / "ev.csv"
    assert main(["tripwire", str(tmp_path / "road"), "--line", wire, "--radius", "12", "--out", str(out),
                 "--quiet"]) == 0
    rows = out.read_text().splitlines()
    assert rows[0].startswith("frame,direction")
    assert all(r.split(",")[1] in ("positive", "negative") for r in rows[1:])
    gt = tmp_path / "gt.csv"
    assert main(["tripwire", "--from-tracks", str(tmp_path / "road" / "gt" / "gt.txt"), "--line", wire,
                 "--point", "centre", "--out", str(gt)]) == 0
    assert len(gt.read_text().splitlines()) == 1 + 4
    assert main(["tripwire", str(tmp_path / "road"), "--line", "10,10", "--out", str(out), "--quiet"]) == 2
    for fps in ("0", "-5", "nan", "inf"):
        assert main(["tripwire", str(tmp_path / "road"), "--line", wire, "--fps", fps, "--out", str(out)]) == 2
    assert main(["tripwire", "--from-tracks", str(tmp_path / "none.txt"), "--line", wire, "--out", str(out)]) == 2
    assert main(["tripwire", "--from-tracks", str(tmp_path / "road" / "gt" / "gt.txt"), "--line", wire,
                 "--point", "match", "--out", str(gt)]) == 2
    bad = tmp_path / "bad.txt"
    bad.write_text("not,a,track\n")
    assert main(["tripwire", "--from-tracks", str(bad), "--line", wire, "--out", str(out)]) == 2


def test_tripwire_cli_counts_several_lines_in_one_pass_as_each_alone(tmp_path, capsys):
    """Repeated --line: each line's rows (numbered in the last column) are those of the line run alone, with the
    radius read for that line; the tracker-based tripwire numbers its rows the same way; a bad second line names
    itself and exits 2."""
    sc = _sparse_road()
    road = tmp_path / "road"
    export_traffic(sc, road)
    lines = ["99,120;221,120", "20,90;300,90"]
    alone = []
    for k, text in enumerate(lines, 1):
        out = tmp_path / f"alone{k}.csv"
        assert main(["tripwire", str(road), "--line", text, "--stride", "3", "--out", str(out), "--quiet"]) == 0
        alone.append([r.rsplit(",", 1) for r in out.read_text().splitlines()[1:]])
        assert all(n == "1" for _, n in alone[-1]) and alone[-1]
    capsys.readouterr()
    both = tmp_path / "both.csv"
    video = tmp_path / "both.mp4"
    assert main(["tripwire", str(road), "--line", lines[0], "--line", lines[1], "--stride", "3", "--out", str(both),
                 "--video-out", str(video), "--quiet"]) == 0
    import cv2

    cap = cv2.VideoCapture(str(video))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == len(range(0, len(sc.frames), 3))
    cap.release()
    rows = both.read_text().splitlines()
    assert rows[0].endswith(",line")
    for k in (1, 2):
        assert sorted(r for r, n in (x.rsplit(",", 1) for x in rows[1:]) if n == str(k)) == sorted(
            r for r, _ in alone[k - 1])
    err = capsys.readouterr().err
    assert "line 1: " in err and "line 2: " in err and "on 2 lines" in err
    tracks = tmp_path / "tracks.csv"
    assert main(["tripwire", "--from-tracks", str(road / "gt" / "gt.txt"), "--line", lines[0], "--line", lines[1],
                 "--point", "centre", "--out", str(tracks)]) == 0
    got = [r.split(",") for r in tracks.read_text().splitlines()]
    assert got[0] == ["frame", "direction", "track", "x", "y", "line"]
    assert [r[5] for r in got[1:]].count("1") == 4 and [r[5] for r in got[1:]].count("2") == 4
    assert [float(r[0]) for r in got[1:]] == sorted(float(r[0]) for r in got[1:])
    assert main(["tripwire", str(road), "--line", lines[0], "--line", "5,5", "--out", str(both), "--quiet"]) == 2
    assert "--line 2: " in capsys.readouterr().err


def test_tripwire_cli_radius_auto_and_overlay_video(tmp_path, capsys):
    """``--radius auto`` measures the blobs near the wire over the first 10 s and counts as the API does with that
    radius; ``--video-out`` writes one overlay frame per processed frame."""
    import cv2

    from pftrack.events.geometry import parse_polyline
    from pftrack.io import open_source

    sc = _sparse_road()
    export_traffic(sc, tmp_path / "road")
    wire = (tmp_path / "road" / "wire.txt").read_text().strip()
    out, video = tmp_path / "ev.csv", tmp_path / "overlay.mp4"
    assert main(["tripwire", str(tmp_path / "road"), "--line", wire, "--radius", "auto", "--stride", "2",
                 "--out", str(out), "--video-out", str(video), "--quiet"]) == 0
    line = parse_polyline(wire)
    frames = [f for _, f in open_source(tmp_path / "road").numbered()]  # the JPEG frames the command read
    r = estimate_radius(frames[:int(10 * sc.fps)][::2], line)
    err = capsys.readouterr().err
    assert f"(r = {r:.1f} px, v_max = 600 px/s, " in err and " frames/s decode excluded)" in err
    tw = TrackerlessTripwire(line, frames[0].shape[:2], sc.fps, TripwireParams(radius=r), stride=2)
    ev = []
    for n, f in enumerate(frames, 1):
        if (n - 1) % 2 == 0:
            ev += tw.process(f, n)
    ev += tw.finish()
    rows = out.read_text().splitlines()[1:]
    assert [(int(x.split(",")[0]), x.split(",")[1]) for x in rows] == [
        (e.frame, "positive" if e.direction > 0 else "negative") for e in ev]
    cap = cv2.VideoCapture(str(video))
    n_video = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
    cap.release()
    assert n_video == len(range(0, len(sc.frames), 2))


def test_dark_levels_stretch_a_dark_camera_and_smooth_a_noisy_one():
    from pftrack.events.tripwire import dark_levels

    p = TripwireParams()
    bright = np.full((60, 80, 3), 120, np.uint8)
    bright[10:20, 10:20] = 250
    assert dark_levels(bright, p) == (1.0, False)
    flat = np.full((60, 80, 3), 20, np.uint8)  # dark and clean: stretched, not smoothed
    g, smooth = dark_levels(flat, p)
    assert g == pytest.approx(8.0) and not smooth
    noisy = np.clip(np.rint(flat + np.random.default_rng(0).normal(0, 4, flat.shape)), 0, 255).astype(np.uint8)
    g, smooth = dark_levels(noisy, p)
    assert 5 < g <= 8 and smooth  # noise of 4 levels times a gain above 5: more than MOG2 can model
    assert dark_levels(noisy, TripwireParams(faithful=True)) == (1.0, False)
    assert dark_levels(noisy, TripwireParams(dark_stretch=0)) == (1.0, False)
    grey = np.full((60, 80), 20, np.uint8)  # one channel
    assert dark_levels(grey, p)[0] == pytest.approx(8.0)


def test_trackerless_tripwire_counts_movers_seen_by_a_dark_noisy_camera():
    """The two movers at a fifth of the light with noise of 5 levels: both crossings are found with the defaults
    (the neighbourhood smoothed, then stretched), none without the stretch or without the smoothing."""
    wire, frames = _two_movers()
    rng = np.random.default_rng(7)
    dark = [np.clip(np.rint(f * 0.2 + rng.normal(0, 5, f.shape)), 0, 255).astype(np.uint8) for f in frames]

    def crossings(**kw):
        tw = TrackerlessTripwire(wire, dark[0].shape[:2], 30.0, TripwireParams(radius=10, bgs_history=50, **kw))
        ev = []
        for n, f in enumerate(dark, 1):
            ev += tw.process(f, n)
        return sorted((e.direction, e.frame) for e in ev)

    found = crossings()
    assert [d for d, _ in found] == [-1, 1], found
    assert 26 <= dict((d, f) for d, f in found)[1] <= 31  # the foot point crosses at frame 29
    assert crossings(dark_stretch=0.0) == [] and crossings(dark_denoise=0.0) == []


def test_radius_auto_reads_the_frames_as_the_tripwire_sees_them():
    import cv2

    from pftrack.events.tripwire import estimate_radius

    wire, frames = _two_movers()
    rng = np.random.default_rng(7)
    dark = [np.clip(np.rint(f * 0.2 + rng.normal(0, 5, f.shape)), 0, 255).astype(np.uint8) for f in frames[:60]]
    g = 5.0
    seen = [cv2.convertScaleAbs(cv2.GaussianBlur(f, (3, 3), 0), alpha=g) for f in dark]
    r = estimate_radius(dark, wire, min_area=30, gain=g, smooth=True)
    assert r == estimate_radius(seen, wire, min_area=30)
    assert 10 <= r <= 16  # half the short side of a disc of radius 14


@pytest.mark.parametrize("warm, option, grey", [(np.array([0.75, 1.0, 1.25]), "cast_jump", False),
                                               (np.full(3, 1.3), "light_jump", False),
                                               (np.full(3, 1.3), "light_jump_grey", True)])
def test_trackerless_tripwire_counts_through_a_jump_of_the_white_balance(warm, option, grey):
    """The two movers with a warm cast (blue times 0.75, red times 1.25), or with the lamps switched on (every channel
    times 1.3; also seen by a grey camera), from frame 15, 25 or 40: with the jump undone (cast_jump, light_jump,
    light_jump_grey, the defaults) the two crossings are found once each at their frames; without, the jump's frame
    gives a false event or puts a crossing off its frame (measured: all three, each)."""
    wire, frames = _two_movers()
    if grey:
        frames = grey_frames(frames)

    def crossings(at, **kw):
        cast = [np.clip(np.rint(f * warm), 0, 255).astype(np.uint8) if k >= at else f for k, f in enumerate(frames)]
        tw = TrackerlessTripwire(wire, cast[0].shape[:2], 30.0, TripwireParams(radius=10, bgs_history=50, **kw))
        ev = []
        for n, f in enumerate(cast, 1):
            ev += tw.process(f, n)
        return sorted((e.direction, e.frame) for e in ev)

    p = TripwireParams()
    assert p.cast_jump == 0.2 and p.light_jump == 0.18 and p.light_jump_grey
    wrong = 0
    still = crossings(len(frames))  # no jump
    for at in (15, 25, 40):
        found = crossings(at)
        if grey:  # in grey the mover going down has about the ground's level (94 against 100): not found, jump or not
            assert found == still == [(-1, 43)], (at, found)
        else:
            assert [d for d, _ in found] == [-1, 1], (at, found)
            assert 27 <= dict(found)[1] <= 31 and 41 <= dict(found)[-1] <= 45, (at, found)
        wrong += crossings(at, **{option: False if grey else 0.0}) != found
    assert wrong >= 2
