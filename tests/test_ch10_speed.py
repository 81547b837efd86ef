"""Book ch. 10: the trackerless tripwire's speed paths (the band MOG2 models, its reach and scale, the speed limit
read from the video, the block matching's near-first search) give the numbers of the slower paths."""

import numpy as np
import pytest

from pftrack.cli import main
from pftrack.events.geometry import polyline_project
from pftrack.events.scoring import ssd_motion
from pftrack.events.tripwire import TrackerlessTripwire, TripwireParams
from pftrack.synth.traffic import export_traffic, traffic_scene

from .test_ch10_tripwire import _sparse_road, _two_movers


def _rects_mask(rects, shape) -> np.ndarray:
    """True inside ``rects`` ``(y0, y1, x0, x1)``."""
    mask = np.zeros(shape, bool)
    for y0, y1, x0, x1 in rects:
        mask[y0:y1, x0:x1] = True
    return mask

def test_band_rects_hold_every_pixel_within_reach_and_leave_out_an_oblique_wires_corners():
    from pftrack.events.geometry import band_rects

    wire = np.array([[30.0, 20.0], [200.0, 150.0], [260.0, 60.0]])
    origin, shape, reach = (10, 5), (170, 270), 25.0
    rects = band_rects(wire, origin, shape, reach, rows=8)
    covered = np.zeros(shape, bool)
    for y0, y1, x0, x1 in rects:
        assert not covered[y0:y1, x0:x1].any()  # the rectangles do not overlap
        covered[y0:y1, x0:x1] = True
    ys, xs = np.mgrid[0:shape[0], 0:shape[1]]
    pts = np.stack([xs.ravel() + origin[0], ys.ravel() + origin[1]], 1).astype(float)
    dist = polyline_project(pts, wire)[0].reshape(shape)
    assert covered[dist <= reach].all()
    assert covered.mean() < 0.75  # an oblique wire's bounding box is mostly left out
    # a horizontal wire's region: bands of full rows beside the wire, merged, and narrower ones at the ends
    flat = band_rects(np.array([[20.0, 50.0], [220.0, 50.0]]), (0, 0), (100, 240), 40.0)
    assert any(y0 <= 24 and y1 >= 80 and (x0, x1) == (0, 240) for y0, y1, x0, x1 in flat)
    assert len(flat) <= 8 and flat[0][0] == 8 and flat[-1][1] == 96


def test_the_rectangles_strips_cover_each_of_their_pixels_once_side_by_side():
    from pftrack.cues.foreground import PACK_ROWS, pack_strips

    rects = [(0, 10, 0, 64), (10, 30, 5, 40), (30, 48, 20, 64), (48, 51, 0, 3)]
    strips = pack_strips(rects)
    seen = np.zeros((51, 64), int)
    for y0, y1, x0, x1, _ in strips:
        assert 0 < y1 - y0 <= PACK_ROWS
        seen[y0:y1, x0:x1] += 1
    inside = np.zeros((51, 64), bool)
    for y0, y1, x0, x1 in rects:
        inside[y0:y1, x0:x1] = True
    assert (seen[inside] == 1).all() and not seen[~inside].any()
    # laid side by side: each strip starts where the one before ends
    np.testing.assert_array_equal(strips[1:, 4], np.cumsum(strips[:-1, 3] - strips[:-1, 2]))
    assert strips[0, 4] == 0


def test_foreground_on_rectangles_labels_their_pixels_as_the_whole_frame_does():
    from pftrack.cues.foreground import Foreground

    rng = np.random.default_rng(4)
    rects = [(0, 10, 0, 64), (10, 30, 5, 40), (30, 45, 20, 64)]  # strips of 8, 2, 8, 8, 4, 8, 7 rows
    whole, parts = Foreground(50, 16.0), Foreground(50, 16.0, rects=rects)
    for t in range(40):
        f = np.clip(rng.normal(120, 6, (48, 64, 3)), 0, 255).astype(np.uint8)
        f[8:30, (t % 50):(t % 50) + 12] = (30, 200, 60)
        if t >= 30:  # grey frames: the grey shadow threshold applies in every rectangle
            f[:] = f.mean(2, keepdims=True).astype(np.uint8)
        a, b = whole.apply(f), parts.apply(f)
        inside = np.zeros(a.shape, bool)
        for y0, y1, x0, x1 in rects:
            inside[y0:y1, x0:x1] = True
        np.testing.assert_array_equal(b[inside], a[inside])
        assert not b[~inside].any() and set(np.unique(a)) <= {0, 1}
    assert parts.grey and whole.grey


def test_an_oblique_wire_gives_the_same_events_with_its_band_only():
    from pftrack.synth.walkers import walkers_scene

    sc = walkers_scene(3, wire="oblique", n_frames=120)
    runs = {}
    for band in (False, True):
        tw = TrackerlessTripwire(sc.wire, sc.frames[0].shape[:2], sc.fps, TripwireParams(radius=8, bgs_band=band,
                                                                                     bgs_outer_scale=1))
        ev = []
        for n, f in enumerate(sc.frames, 1):
            ev += tw.process(f, n)
        ev += tw.finish()
        runs[band] = ([(e.frame, e.direction, e.x, e.y) for e in ev], tw._bgs.rects)
    assert runs[True][0] == runs[False][0] and runs[True][0]
    area = sum((y1 - y0) * (x1 - x0) for y0, y1, x0, x1 in runs[True][1])
    assert runs[False][1] is None and area < 0.9 * tw._fg.size


def test_bgs_reach_narrows_the_band_to_its_radii_but_never_widens_it_and_keeps_the_patches_inside():
    wire = np.array([[100.0, 500.0], [700.0, 80.0]])
    shape = (576, 768)

    def band(**kw):
        tw = TrackerlessTripwire(wire, shape, 7.0, TripwireParams(radius=12, bgs_outer_scale=1, **kw))
        inside = np.zeros((tw.y1 - tw.y0, tw.x1 - tw.x0), bool)
        for y0, y1, x0, x1 in tw._bgs.rects:
            inside[y0:y1, x0:x1] = True
        return tw, inside

    tw, full = band()
    _, wide = band(bgs_reach=100.0)           # wider than the full reach: the full reach
    np.testing.assert_array_equal(wide, full)
    for k in (4.0, 6.0):
        _, narrow = band(bgs_reach=k)
        assert not (narrow & ~full).any() and narrow.sum() < 0.8 * full.sum()
        assert narrow.ravel()[tw._disc].all()  # every patch's disc is modelled
        # a pixel left out lies beyond k r of the wire; one modelled within k r and the 8-row bands' slack
        ys, xs = np.nonzero(~narrow & full)
        pts = np.stack([xs + tw.x0, ys + tw.y0], 1).astype(float)
        assert polyline_project(pts, wire)[0].min() > k * 12 - 1e-6
        ys, xs = np.nonzero(narrow)
        pts = np.stack([xs + tw.x0, ys + tw.y0], 1).astype(float)
        assert polyline_project(pts, wire)[0].max() < k * 12 + 10


def test_bgs_outer_scale_keeps_the_full_size_labels_near_the_wire_and_the_same_events():
    """bgs_outer_scale (4 by default, docs/rules/tripwire_outer_scale_34_rule.txt): within bgs_near r of the wire (every
    disc and block) the mask is the full-size model's; beyond it the reduced model's, brought back to full size."""
    from pftrack.synth.walkers import walkers_scene

    sc = walkers_scene(3, wire="oblique", n_frames=120)
    shape = sc.frames[0].shape[:2]
    base = TrackerlessTripwire(sc.wire, shape, sc.fps, TripwireParams(radius=8, bgs_outer_scale=1))
    tw = TrackerlessTripwire(sc.wire, shape, sc.fps, TripwireParams(radius=8, bgs_outer_scale=2, bgs_near=3))
    near = tw._bgs_near
    inside = _rects_mask(near.rects, (tw.y1 - tw.y0, tw.x1 - tw.x0))
    assert tw._bgs.scale == 2 and near.scale == 1 and 0.1 < inside.mean() < 0.9
    assert inside.ravel()[tw._disc].all()  # every disc is labelled at full size
    ys, xs = np.nonzero(inside)
    pts = np.stack([xs + tw.x0, ys + tw.y0], 1).astype(float)
    assert polyline_project(pts, sc.wire)[0].max() < 3 * 8 + 10
    agree = []
    for f in sc.frames:
        roi = f[tw.y0:tw.y1, tw.x0:tw.x1]
        a, b = base._apply_bgs(roi), tw._apply_bgs(roi)
        np.testing.assert_array_equal(b[inside], a[inside])
        band = np.zeros(a.shape, bool)
        for y0, y1, x0, x1 in base._bgs.rects:
            band[y0:y1, x0:x1] = True
        outer = band & ~inside
        if a[outer].any():
            agree.append((a[outer] & b[outer]).sum() / max(a[outer].sum(), b[outer].sum()))
    assert len(agree) > 50 and np.median(agree) > 0.8  # the walkers beyond the near band, at half the resolution
    runs = []
    for params in (TripwireParams(radius=8, bgs_outer_scale=1),
                   TripwireParams(radius=8, bgs_outer_scale=2, bgs_near=3), TripwireParams(radius=8)):
        t = TrackerlessTripwire(sc.wire, shape, sc.fps, params)
        ev = [e for n, f in enumerate(sc.frames, 1) for e in t.process(f, n)] + t.finish()
        runs.append(sorted((e.frame, e.direction) for e in ev))
    assert runs[1] == runs[0] and len(runs[0]) == 7  # this scene's seven events, the same
    # the default (a quarter beyond 5 r): the same events, one of them a frame earlier (103 against 104)
    assert [d for _, d in runs[2]] == [d for _, d in runs[0]]
    assert max(abs(a - b) for (a, _), (b, _) in zip(runs[2], runs[0])) <= 1
    for wire in ([[0.0, 0.0], [300.0, 0.0]], [[-50.0, -40.0], [400.0, -40.0]]):  # on the view's edge, and beyond it
        t = TrackerlessTripwire(np.array(wire), shape, sc.fps, TripwireParams(radius=8))
        assert t.process(sc.frames[0], 1) == [] and t._fg.shape == (t.y1 - t.y0, t.x1 - t.x0)


def test_blocks_outside_leave_out_only_wide_runs_of_blocks_wholly_inside():
    from pftrack.events.geometry import blocks_outside

    inside = np.zeros((40, 80), bool)
    inside[4:36, 20:61] = True  # full-size pixels; with k = 2, block columns 10-29 wholly inside on block rows 2-17
    rects = [(0, 20, 0, 40)]
    kept = blocks_outside(rects, inside, 2, rows=8, min_cols=8)
    cover = np.zeros((20, 40), int)
    for y0, y1, x0, x1 in kept:
        assert y1 - y0 <= 8 and y0 // 8 == (y1 - 1) // 8  # within one band of 8 rows
        cover[y0:y1, x0:x1] += 1
    assert cover.max() == 1
    blocks_in = inside.reshape(20, 2, 40, 2).all(axis=(1, 3))
    assert cover[~blocks_in].all()  # every block not wholly inside is kept
    assert cover[8:16, 10:30].sum() == 0  # the band whose 8 block rows are all inside loses those columns
    assert cover[0:8].all() and cover[16:20].all()  # bands with a block row outside keep every column
    # a run narrower than min_cols stays, and nothing left gives the rectangles back
    assert blocks_outside(rects, inside, 2, rows=8, min_cols=21) == [(0, 8, 0, 40), (8, 16, 0, 40), (16, 20, 0, 40)]
    assert blocks_outside([(8, 16, 10, 30)], inside, 2) == [(8, 16, 10, 30)]


def test_the_reduced_model_skips_the_full_size_models_blocks_and_the_mask_is_the_same(monkeypatch):
    """The reduced model labels no block the full-size model labels wholly (``blocks_outside``); the mask is the
    one the two models give when the reduced one labels its whole band and the full-size labels are copied over."""
    import pftrack.events.tripwire as tripwire_module
    from pftrack.synth.walkers import walkers_scene

    sc = walkers_scene(5, wire="oblique", n_frames=60)
    shape = sc.frames[0].shape[:2]
    tw = TrackerlessTripwire(sc.wire, shape, sc.fps, TripwireParams(radius=8))
    monkeypatch.setattr(tripwire_module, "blocks_outside", lambda rects, *a, **k: rects)
    ref = TrackerlessTripwire(sc.wire, shape, sc.fps, TripwireParams(radius=8))
    near = ref._bgs_near
    inside = _rects_mask(near.rects, (ref.y1 - ref.y0, ref.x1 - ref.x0))
    assert tw._bgs_near.rects == near.rects

    def area(rects):
        return sum((y1 - y0) * (x1 - x0) for y0, y1, x0, x1 in rects)

    assert area(tw._bgs.rects) < 0.8 * area(ref._bgs.rects)
    for f in sc.frames:
        roi = f[tw.y0:tw.y1, tw.x0:tw.x1]
        want = ref._bgs.apply(roi)
        np.copyto(want, near.apply(roi), where=inside)
        np.testing.assert_array_equal(tw._apply_bgs(roi), want)
    with pytest.raises(ValueError):  # out= is for a model of rectangles, of the frame's size
        near.apply(sc.frames[0][tw.y0:tw.y1, tw.x0:tw.x1], out=np.zeros((3, 3), np.uint8))


def test_foreground_at_a_reduced_scale_returns_a_full_size_mask_and_the_tripwire_still_counts():
    from pftrack.cues.foreground import Foreground

    rng = np.random.default_rng(6)
    fg = Foreground(30, 16.0, scale=2)
    for t in range(20):
        f = np.clip(rng.normal(120, 4, (49, 65, 3)), 0, 255).astype(np.uint8)
        if t == 19:
            f[10:30, 20:40] = (20, 220, 40)
        m = fg.apply(f)
    assert m.shape == (49, 65) and m[12:28, 22:38].all() and m[:, :16].sum() == 0
    with pytest.raises(ValueError):
        Foreground(scale=0)
    # on rectangles (in the reduced frame's pixels) only their blocks are reduced: on a frame of whole blocks each
    # label inside them is the whole frame's
    rects = [(0, 5, 0, 32), (5, 20, 4, 20), (20, 24, 10, 32)]
    whole, parts = Foreground(30, 16.0, scale=2), Foreground(30, 16.0, scale=2, rects=rects)
    inside = np.zeros((48, 64), bool)
    for y0, y1, x0, x1 in rects:
        inside[2 * y0:2 * y1, 2 * x0:2 * x1] = True
    seen = 0
    for t in range(30):
        f = np.clip(rng.normal(120, 6, (48, 64, 3)), 0, 255).astype(np.uint8)
        f[8:30, (2 * t) % 50:(2 * t) % 50 + 12] = (30, 200, 60)
        a, b = whole.apply(f), parts.apply(f)
        assert b.shape == (48, 64) and not b[~inside].any()
        np.testing.assert_array_equal(b[inside], a[inside])
        seen += int(a[inside].sum())
    assert seen > 500  # the mover, labelled inside the rectangles
    wire, frames = _two_movers()
    tw = TrackerlessTripwire(wire, frames[0].shape[:2], 30.0, TripwireParams(radius=10, bgs_history=50, bgs_scale=2))
    ev = []
    for n, f in enumerate(frames, 1):
        ev += tw.process(f, n)
    assert sorted(e.direction for e in ev) == [-1, 1]


def test_mog_on_rectangles_labels_as_the_whole_frame_and_the_tripwire_counts_with_it():
    """bgs = "mog" (an option, docs/rules/tripwire_bgs_mog_rule.txt): OpenCV contrib's MOG on the band's rectangles
    gives each pixel the whole frame's label, and the two movers are counted in their directions."""
    from pftrack.cues.foreground import Foreground

    rng = np.random.default_rng(5)
    rects = [(0, 10, 0, 64), (10, 30, 5, 40), (30, 48, 20, 64)]
    whole, parts = Foreground(50, model="mog"), Foreground(50, model="mog", rects=rects)
    inside = np.zeros((48, 64), bool)
    for y0, y1, x0, x1 in rects:
        inside[y0:y1, x0:x1] = True
    for t in range(40):
        f = np.clip(rng.normal(120, 6, (48, 64, 3)), 0, 255).astype(np.uint8)
        f[8:30, (t % 50):(t % 50) + 12] = (30, 200, 60)
        a, b = whole.apply(f), parts.apply(f)
        np.testing.assert_array_equal(b[inside], a[inside])
        assert not b[~inside].any()
    assert a[10:28, (39 % 50) + 2:(39 % 50) + 10].all() and a[40:, :30].sum() == 0  # the mover, not the ground
    assert type(parts._model).__name__ == "BackgroundSubtractorMOG"
    with pytest.raises(ValueError):
        Foreground(model="knn")
    with pytest.raises(ValueError):
        Foreground(model="mog", mog_ratio=0.0)
    wire, frames = _two_movers()
    tw = TrackerlessTripwire(wire, frames[0].shape[:2], 30.0, TripwireParams(radius=10, bgs_history=50, bgs="mog"))
    assert tw._bgs.model == "mog"
    ev = []
    for n, f in enumerate(frames, 1):
        ev += tw.process(f, n)
    assert sorted(e.direction for e in ev) == [-1, 1]


def test_estimate_speed_reads_the_movers_speed_and_v_max_auto_counts_as_the_api_with_it(tmp_path, capsys):
    from pftrack.events.blobs import estimate_speed
    from pftrack.events.geometry import parse_polyline
    from pftrack.io import open_source

    wire, frames = _two_movers()  # discs moving 2 px a frame at 30 fps: 60 px/s
    v = estimate_speed(frames[:60], wire, 30.0)
    assert 100.0 <= v <= 140.0  # twice the 95th percentile of about 60 px/s
    assert estimate_speed(frames[:3], wire, 30.0) == 600.0  # too few speeds read: the default
    sc = traffic_scene(8, kind="sparse", n_vehicles=4)
    export_traffic(sc, tmp_path / "road")
    text = (tmp_path / "road" / "wire.txt").read_text().strip()
    out = tmp_path / "ev.csv"
    assert main(["tripwire", str(tmp_path / "road"), "--line", text, "--radius", "10", "--v-max", "auto",
                 "--out", str(out), "--quiet"]) == 0
    line = parse_polyline(text)
    read = [f for _, f in open_source(tmp_path / "road").numbered()]
    v = estimate_speed(read[:int(10 * sc.fps)], line, sc.fps)
    assert f"v_max = {v:.0f} px/s" in capsys.readouterr().err and v < 600.0
    tw = TrackerlessTripwire(line, read[0].shape[:2], sc.fps, TripwireParams(radius=10, v_max=v))
    ev = [e for n, f in enumerate(read, 1) for e in tw.process(f, n)] + tw.finish()
    assert [int(x.split(",")[0]) for x in out.read_text().splitlines()[1:]] == [e.frame for e in ev]
    assert main(["tripwire", str(tmp_path / "road"), "--line", text, "--v-max", "fast", "--out", str(out)]) == 2
    assert "--v-max must be a number or 'auto'" in capsys.readouterr().err


@pytest.mark.parametrize("shift", [(3, -2), (14, 5), (27, -19), (-40, 33)])
def test_ssd_motion_searching_near_first_gives_the_whole_windows_answer(monkeypatch, shift):
    """With the prior, the search over +-NEAR_SEARCH px first, widened only as far as the prior lets a better match
    lie, returns what the whole window returns: small motions, motions past the first window, near the edge."""
    import cv2

    import pftrack.events.scoring as scoring

    rng = np.random.default_rng(7)
    img = np.clip(cv2.GaussianBlur(rng.normal(128, 40, (160, 200)), (0, 0), 2.0), 0, 255).astype(np.uint8)
    moved = np.roll(np.roll(img, shift[0], axis=1), shift[1], axis=0)
    noisy = np.clip(moved + rng.normal(0, 6, moved.shape), 0, 255).astype(np.uint8)
    mask = (rng.random(img.shape) < 0.7).astype(np.uint8)
    for centre, pen, m in (((100, 80), 1.0, None), ((100, 80), 0.2, mask), ((20, 150), 0.5, mask),
                           ((100, 80), 0.05, None)):
        got = ssd_motion(img, noisy, centre, 8, 60, mask=m, penalty=pen)
        monkeypatch.setattr(scoring, "NEAR_SEARCH", 10 ** 6)
        whole = ssd_motion(img, noisy, centre, 8, 60, mask=m, penalty=pen)
        monkeypatch.setattr(scoring, "NEAR_SEARCH", 16)
        # the same displacement; OpenCV's correlation rounds differently over a smaller window (sub-pixel step)
        np.testing.assert_allclose(got[0], whole[0], atol=0.01)
        assert got[1] == pytest.approx(whole[1], rel=1e-3, abs=1e-2)


def test_radius_auto_on_a_camera_reads_its_first_seconds_once_and_counts_them(tmp_path, monkeypatch, capsys):
    """A camera cannot be read twice: ``--radius auto`` keeps the first 10 s it reads and counts them, then the live
    stream goes on, with the same rows as the same frames given as a folder (formerly: exit 2, "give --radius")."""
    import cv2

    import pftrack.io.sources as sources

    sc = _sparse_road()
    real = cv2.VideoCapture
    reads = []

    class Camera:  # camera 0 serves the scene's frames once, at 30 fps; anything else is OpenCV's
        def __init__(self, target):
            self.live = isinstance(target, int)
            self.cap = None if self.live else real(target)
            self.left = list(sc.frames)

        def isOpened(self):
            return True if self.live else self.cap.isOpened()

        def read(self):
            if not self.live:
                return self.cap.read()
            reads.append(1)
            return (True, self.left.pop(0)) if self.left else (False, None)

        def get(self, prop):
            if not self.live:
                return self.cap.get(prop)
            return 30.0 if prop == cv2.CAP_PROP_FPS else 0.0

        def grab(self):
            return self.read()[0]

        def release(self):
            if self.cap is not None:
                self.cap.release()

    export_traffic(sc, tmp_path / "road")
    wire = (tmp_path / "road" / "wire.txt").read_text().strip()
    folder = tmp_path / "folder.csv"
    assert main(["tripwire", str(tmp_path / "road"), "--line", wire, "--fps", "30", "--stride", "2",
                 "--out", str(folder), "--quiet"]) == 0
    said = capsys.readouterr().err
    # the folder's JPEG frames, as the command read them, served by the camera
    from pftrack.io import open_source

    sc = type(sc)([f for _, f in open_source(tmp_path / "road").numbered()], sc.tracks, sc.wire, sc.fps, sc.meta)
    monkeypatch.setattr(sources.cv2, "VideoCapture", Camera)
    live = tmp_path / "live.csv"
    assert main(["tripwire", "0", "--line", wire, "--stride", "2", "--out", str(live), "--quiet"]) == 0
    assert live.read_text() == folder.read_text() and len(folder.read_text().splitlines()) > 1
    assert len(reads) == len(sc.frames) + 1  # every frame read once (and the end of the stream)
    radius = said.split("r = ")[1].split(" px")[0]
    assert f"r = {radius} px" in capsys.readouterr().err
    # a camera whose first 10 s would not fit the memory allowed reads a shorter window, still once
    import pftrack.cli.events as events

    import pftrack.events.tripwire as tripwire

    monkeypatch.setattr(events, "CAMERA_CALIBRATION_BYTES", 20 * sc.frames[0].nbytes)
    seen = []
    radius = tripwire.estimate_radius
    monkeypatch.setattr(tripwire, "estimate_radius", lambda frames, *a, **k: seen.append(len(frames)) or radius(
        frames, *a, **k))
    reads.clear()
    assert main(["tripwire", "0", "--line", wire, "--stride", "2", "--out", str(live), "--quiet"]) == 0
    assert seen == [20]  # 20 processed frames, not the 10 s
    assert len(reads) == len(sc.frames) + 1 and live.read_text().startswith("frame,direction")


def test_a_cameras_calibration_frames_are_let_go_as_they_are_counted():
    from pftrack.cli.events import _let_go

    kept = [(1, "a"), (3, "b"), (5, "c")]
    seen = []
    for item in _let_go(kept):
        seen.append((item, len(kept)))
    assert seen == [((1, "a"), 2), ((3, "b"), 1), ((5, "c"), 0)] and kept == []
