"""Book ch. 8: motion vectors from a compressed stream, block groups, temporal refinement, labels, activity."""

from __future__ import annotations

import sys

import cv2
import numpy as np
import pytest

from pftrack.multi import compressed as C
from pftrack.multi import motion_activity as A

av = pytest.importorskip("av")
needs_x264 = pytest.mark.skipif("libx264" not in av.codecs_available, reason="PyAV without libx264")


def _texture(seed=0, size=(300, 520)):
    rng = np.random.default_rng(seed)
    t = cv2.GaussianBlur(rng.standard_normal(size), (0, 0), 2.0)
    return ((t - t.min()) / np.ptp(t) * 255).astype(np.uint8)


@needs_x264
def test_reader_recovers_a_known_global_shift_and_exact_pseudo_residual(tmp_path):
    from pftrack.io.motion_vectors import (
        block_energy,
        encode_h264,
        iter_mv_frames,
        mv_field,
        pseudo_residual,
    )

    tex = _texture()
    frames = [cv2.cvtColor(tex[30:270, 160 - 2 * i:160 - 2 * i + 320], cv2.COLOR_GRAY2BGR) for i in range(24)]
    path = encode_h264(frames, tmp_path / "pan.mp4", qp=20, exact=True)
    ok = n_p = 0
    prev = None
    for f in iter_mv_frames(path):
        if f.number == 1:
            assert f.pict_type == "I" and f.mvs is None
        else:
            assert f.pict_type == "P"
            fwd, has = mv_field(f.mvs, f.y.shape)
            n_p += 1
            ok += bool(np.array_equal(np.median(fwd[has], axis=0), [2.0, 0.0]))
            if f.number >= 6:      # content moves right by 2 px: the interior is predicted exactly
                E = block_energy(pseudo_residual(f.y, prev.y, fwd))
                assert np.mean(E[2:-2, 2:-2] == 0) >= 0.98
        prev = f
    assert n_p == 23 and ok >= 0.95 * n_p


def test_grouping_positions_connectivity_direction_and_energy():
    I, J = 20, 30
    fg = np.zeros((I, J), bool)
    fg[2:5, 3:6] = True          # blob 1
    fg[5:8, 6:9] = True          # blob 2 touches blob 1 diagonally
    fwd = np.zeros((I, J, 2), np.float32)
    fwd[fg] = (2.0, 0.0)         # motion_x = -8 quarter-pel
    E = np.zeros((I, J))
    E[fg] = 100.0
    p8 = C.CDParams(closing=0, n_min=1)
    g = C.group_blocks(fg, fwd, E, p8)
    assert len(g) == 1
    assert g[0].box[:2] == (12.0, 8.0) and g[0].direction == 0.0 and g[0].energy == pytest.approx(1800.0, abs=1e-9)
    # 4-connectivity would split them: check through two separated blobs
    fg2 = fg.copy()
    fg2[5:8, 6:9] = False
    fg2[5:8, 7:10] = True
    assert len(C.group_blocks(fg2, fwd, E, p8)) == 2
    fwd[fg] = (0.0, -3.0)        # moving up: 270 degrees in image axes
    assert C.group_blocks(fg, fwd, E, p8)[0].direction == 270.0


def _g(x, y, w=16, h=16, d=0.0, e=1e4, shape=(60, 80)):
    m = np.zeros(shape, bool)
    m[int(y) // 4:int(y + h) // 4, int(x) // 4:int(x + w) // 4] = True
    return C.Group((float(x), float(y), float(w), float(h)), m, d, e, (1.0, 0.0), int(m.sum()))


def test_temporal_refinement_removes_flicker_and_fills_a_gap():
    ref = C.TemporalRefiner()
    out = []
    seq = [[_g(40, 40)], [_g(44, 40), _g(200, 150)], [], [_g(52, 40), _g(200, 150)], [_g(56, 40)], [_g(60, 40)],
           [_g(64, 40)]]
    for n, gs in enumerate(seq, start=1):
        out += ref.push(n, gs)
    out += ref.flush()
    by = dict(out)
    assert 3 in by and len(by[3]) == 1                          # the missing frame is filled ...
    assert by[3][0].box[0] == pytest.approx(np.mean([40, 44, 52, 56]))   # ... with the mean position
    assert all(not any(g.box[0] == 200 for g in by[k]) for k in by)     # 2-of-5 flicker removed


def test_labels_survive_an_occlusion_by_direction_and_energy():
    """A (0 deg, e = 1e4) and B (180 deg, e = 1e6) approach, merge into one group for 10 frames, split and
    swap sides: both labels come back (ch08.md §5.1), in both similarity modes."""
    for mode in ("default", "faithful"):
        trk = C.CDTracker((320, 240), C.CDParams(similarity=mode))
        before = {}
        for t in range(32):
            if t < 12:
                objs = trk.step([_g(60 + 4 * t, 100, d=0.0, e=1e4), _g(172 - 4 * t, 100, d=180.0, e=1e6)])
                before = {o.group.direction: o.label for o in objs}
            elif t < 22:
                objs = trk.step([_g(108 + (t - 12), 100, w=40, d=90.0, e=1e6)])
                assert len(objs) == 1 and objs[0].status == 1
            else:
                objs = trk.step([_g(110 - 4 * (t - 22), 100, d=180.0, e=1e6),
                                 _g(150 + 4 * (t - 22), 100, d=0.0, e=1e4)])
                assert {o.group.direction: o.label for o in objs} == before, mode


def test_statuses_entering_and_leaving():
    trk = C.CDTracker((320, 240), C.CDParams())
    objs = trk.step([_g(2, 100)])
    assert objs[0].status == 4                  # into frame at the border
    objs = trk.step([_g(100, 100)])
    lab = objs[0].label
    assert trk.step([]) == [] and trk.waiting[lab].status == 3     # gone in the interior: stopped, kept
    objs = trk.step([_g(104, 100)])
    assert objs[0].label == lab                                     # ... and it resumes with its label
    trk.step([_g(300, 100)])
    assert trk.step([]) == [] and all(o.status != 2 for o in trk.waiting.values())   # out of frame: forgotten


def test_activity_levels_and_weights():
    assert A.intensity_level([0.5, 3.9, 10.0, 17.0, 20.0, 40.0]).tolist() == [1, 2, 2, 3, 4, 5]
    w = A.partition_weights([16, 8, 16, 8], [16, 8, 8, 4], np.arange(4), n_mb=300, penalty=False)
    assert np.allclose(w, [1.0, 4.0, np.sqrt(2.0), np.sqrt(8.0)])
    # the penalty damps the n-th partition of a class more than the first
    wp = A.partition_weights([8] * 5, [8] * 5, np.arange(5), n_mb=20, penalty=True)
    assert np.all(np.diff(wp) < 0)
    dt = np.dtype([("source", "i4"), ("w", "u1"), ("h", "u1"), ("src_x", "i2"), ("src_y", "i2"), ("dst_x", "i2"),
                   ("dst_y", "i2"), ("flags", "u8"), ("motion_x", "i4"), ("motion_y", "i4"), ("motion_scale", "u2")])
    mvs = np.zeros(300, dt)
    mvs["source"], mvs["w"], mvs["h"], mvs["motion_scale"] = -1, 16, 16, 4
    mvs["dst_x"] = (np.arange(300) % 20) * 16 + 8
    mvs["dst_y"] = (np.arange(300) // 20) * 16 + 8
    small = np.zeros(12, dt)
    small["source"], small["w"], small["h"], small["motion_scale"] = -1, 8, 8, 4
    small["motion_x"] = -24          # 6 px
    m = np.concatenate([mvs, small])
    s0 = A.motion_sigma(m, 320, 240, weighted=False, mv_scale=1.0)
    s1 = A.motion_sigma(m, 320, 240, weighted=True, penalty=False, mv_scale=1.0)
    assert s1 > s0 and A.intensity_level(s0) == 1 and A.intensity_level(s1) > 1


def test_missing_pyav_names_the_extra(monkeypatch):
    from pftrack.errors import ParameterError
    from pftrack.io import motion_vectors as M

    monkeypatch.setitem(sys.modules, "av", None)
    with pytest.raises(ParameterError, match=r"pftrack\[mv\]"):
        M.require_av()


@needs_x264
def test_cli_mot_mv_cd_and_activity(tmp_path, capsys):
    from pftrack.cli import main
    from pftrack.io.motion_vectors import encode_h264

    bg = _texture(3, (240, 320))
    obj = _texture(4, (40, 40))
    frames = []
    rng = np.random.default_rng(5)
    for t in range(30):       # a textured square with per-frame noise (sigma 4) inside, moving 6 px/frame
        f = bg.copy()
        x = 40 + 6 * t
        f[100:140, x:x + 40] = np.clip(obj + rng.normal(0, 4, obj.shape), 0, 255).astype(np.uint8)
        frames.append(cv2.cvtColor(f, cv2.COLOR_GRAY2BGR))
    path = encode_h264(frames, tmp_path / "obj.mp4", qp=20, exact=True)
    args = ["--param", "n_min=4", "--param", "tau_r=64"]
    threads = cv2.getNumThreads()
    assert main(["mot", str(path), "--detector", "mv", "--out", str(tmp_path / "mv.txt"), "--quiet", *args]) == 0
    assert cv2.getNumThreads() == threads  # the mv pipeline turns OpenCV's pool off only while it runs
    assert main(["mot", str(path), "--tracker", "cd", "--out", str(tmp_path / "cd.txt"), "--quiet",
                 "--mpeg7", str(tmp_path / "cd.xml"), *args]) == 0
    import xml.etree.ElementTree as ET

    root = ET.parse(tmp_path / "cd.xml").getroot()                      # well formed, one trajectory per label
    ns = "{urn:mpeg:mpeg7:schema:2001}"
    assert root.tag == ns + "Mpeg7" and len(root.findall(f".//{ns}MotionTrajectory")) == 1
    xs = root.find(f".//{ns}KeyValue[@dim='x']").text.split()
    assert len(xs) == len(root.findall(f".//{ns}CoordKeyPoints/{ns}MediaTimePoint")) > 10
    assert main(["mot", str(path), "--out", str(tmp_path / "x.txt"), "--mpeg7", str(tmp_path / "x.xml")]) == 2
    rows = np.loadtxt(tmp_path / "cd.txt", delimiter=",", ndmin=2)
    assert len(np.unique(rows[:, 1])) == 1 and len(rows) >= 20        # one label throughout
    f20 = rows[rows[:, 0] == 20][0]
    assert abs(f20[2] - (40 + 6 * 19)) <= 12 and abs(f20[3] - 100) <= 12     # 16x16 vectors, 4 px blocks
    assert main(["activity", str(path), "--out", str(tmp_path / "a.csv"), "--plot", str(tmp_path / "a.png"),
                 "--weighting", "auto", "--quiet"]) == 0
    a = np.loadtxt(tmp_path / "a.csv", delimiter=",", skiprows=1)
    assert len(a) == 30 and set(np.unique(a[:, 1])) <= {1, 2, 3, 4, 5}
    assert main(["activity", str(tmp_path / "missing.mp4")]) == 2
    assert main(["activity", str(tmp_path / "missing.mp4"), "--out", str(tmp_path / "none.csv")]) == 2
    assert not (tmp_path / "none.csv").exists()  # bad input is refused before any output is written
    assert main(["mot", str(tmp_path / "missing.mp4"), "--detector", "mv"]) == 2
    assert "error" in capsys.readouterr().err
    assert main(["activity", str(tmp_path)]) == 2
    assert "is a folder" in capsys.readouterr().err


def test_block_energy_at_matches_the_full_pseudo_residual():
    from pftrack.io.motion_vectors import block_energy, block_energy_at, pseudo_residual

    rng = np.random.default_rng(0)
    a = rng.integers(0, 255, (48, 64)).astype(np.uint8)
    b = rng.integers(0, 255, (48, 64)).astype(np.uint8)
    fwd = rng.uniform(-3, 3, (12, 16, 2)).astype(np.float32)
    mask = rng.random((12, 16)) < 0.4
    mask[0, :] = mask[-1, :] = mask[:, 0] = mask[:, -1] = False     # away from the replicated border
    full = block_energy(pseudo_residual(a, b, fwd))
    # cv2.remap (the full path) quantises coordinates to 1/32 px; the block path samples exactly
    assert np.allclose(block_energy_at(a, b, fwd, mask)[mask], full[mask], rtol=0.05)


def test_trailing_trim_keeps_the_current_position_of_a_frame_difference_region():
    """A 20x40 object moving by (+6, -2) px between two frames: the difference region covers both positions
    (x 100..126, y 48..90); cutting back the trailing side by the displacement gives the current box."""
    union = (100.0, 48.0, 26.0, 42.0)
    assert C.trailing_trim(union, (6.0, -2.0)) == pytest.approx((106.0, 48.0, 20.0, 40.0))
    assert C.trailing_trim(union, (-6.0, 2.0)) == pytest.approx((100.0, 50.0, 20.0, 40.0))
    assert C.trailing_trim(union, (0.0, 0.0)) == pytest.approx(union)
    # a displacement larger than the region never leaves less than one block
    x, y, w, h = C.trailing_trim((0.0, 0.0, 8.0, 8.0), (30.0, 0.0))
    assert w == pytest.approx(C.BLOCK) and x == pytest.approx(8.0 - C.BLOCK)


def test_the_analyser_trims_a_moving_object_to_its_current_position():
    """A textured 20x40 object moves by +8 px between two frames. The frame difference covers both positions
    (28 px wide); the analyser's box, cut back by the median vector of the object's moving blocks, is the
    current one. The vectors cover only part of the group (8x8 partitions on the current position), so a
    mean over all the group's blocks would trim less."""
    from pftrack.io.motion_vectors import MVFrame

    texture = np.random.default_rng(0).integers(120, 255, (40, 20)).astype(np.uint8)  # textured: differences inside
    prev = np.full((120, 240), 60, np.uint8)
    cur = prev.copy()
    prev[40:80, 100:120] = texture
    cur[40:80, 108:128] = texture
    dt = np.dtype([("source", "i4"), ("w", "u1"), ("h", "u1"), ("src_x", "i2"), ("src_y", "i2"), ("dst_x", "i2"),
                   ("dst_y", "i2"), ("flags", "u8"), ("motion_x", "i4"), ("motion_y", "i4"), ("motion_scale", "u2")])
    xs, ys = np.meshgrid(np.arange(108, 128, 8), np.arange(40, 80, 8))
    mvs = np.zeros(xs.size, dt)
    mvs["source"], mvs["w"], mvs["h"], mvs["motion_scale"] = -1, 8, 8, 4
    mvs["dst_x"], mvs["dst_y"] = xs.ravel() + 4, ys.ravel() + 4
    mvs["motion_x"] = -32                                 # a forward displacement of +8 px
    an = C.BlockAnalyser(C.CDParams(n_min=4, shape="blocks"))
    assert an(MVFrame(1, "P", mvs, prev)) == []
    (g,) = an(MVFrame(2, "P", mvs, cur))
    assert g.box[0] == pytest.approx(108.0) and g.box[0] + g.box[2] == pytest.approx(128.0)
    assert g.box[1] == pytest.approx(40.0) and g.box[3] == pytest.approx(40.0)
    untrimmed = C.BlockAnalyser(C.CDParams(n_min=4, trim=False, shape="blocks"))
    untrimmed(MVFrame(1, "P", mvs, prev))
    (u,) = untrimmed(MVFrame(2, "P", mvs, cur))
    assert u.box[0] == pytest.approx(100.0) and u.box[2] == pytest.approx(28.0)
    assert C.trailing_trim(u.box, u.velocity)[0] < 107.0  # the group's mean vector, zero blocks included


def test_compiled_field_energy_and_hole_filling_equal_their_references():
    """The compiled motion-vector painting and block energies equal the NumPy code bit for bit (overlapping
    partitions of several sizes included), and the OpenCV hole filling equals SciPy's."""
    from scipy.ndimage import binary_fill_holes

    from pftrack._numba import NUMBA_INSTALLED, set_numba_enabled
    from pftrack.io.motion_vectors import block_energy_at, mv_field

    rng = np.random.default_rng(5)
    dt = np.dtype([("source", "i4"), ("w", "u1"), ("h", "u1"), ("src_x", "i2"), ("src_y", "i2"), ("dst_x", "i2"),
                   ("dst_y", "i2"), ("flags", "u8"), ("motion_x", "i4"), ("motion_y", "i4"), ("motion_scale", "u2")])
    n = 400
    mvs = np.zeros(n, dt)
    mvs["source"] = rng.choice([-1, 1], n, p=[0.9, 0.1])
    mvs["w"] = rng.choice([4, 8, 16], n)
    mvs["h"] = rng.choice([4, 8, 16], n)
    mvs["dst_x"] = rng.integers(-8, 170, n)       # some partitions reach over the frame's edges
    mvs["dst_y"] = rng.integers(-8, 130, n)
    mvs["motion_x"] = rng.integers(-40, 40, n)
    mvs["motion_y"] = rng.integers(-40, 40, n)
    mvs["motion_scale"] = 4
    y_prev = rng.integers(0, 255, (121, 161)).astype(np.uint8)
    y_cur = rng.integers(0, 255, (121, 161)).astype(np.uint8)
    out = {}
    for enabled in ([False, True] if NUMBA_INSTALLED else [False]):
        prev = set_numba_enabled(enabled)
        try:
            fwd, has = mv_field(mvs, y_cur.shape)
            out[enabled] = (fwd, has, block_energy_at(y_cur, y_prev, fwd, has))
        finally:
            set_numba_enabled(prev)
    if NUMBA_INSTALLED:
        for a, b in zip(out[False], out[True]):
            assert np.array_equal(a, b)
    assert out[False][1].any() and (out[False][2] > 0).any()
    for _ in range(50):
        m = (rng.random((30, 40)) < rng.uniform(0.2, 0.8)).astype(np.uint8)
        assert np.array_equal(C.fill_holes(m), binary_fill_holes(m).astype(np.uint8))


def test_prefetch_keeps_order_raises_the_producers_error_and_stops_when_closed():
    import threading

    from pftrack.io.prefetch import prefetch

    assert list(prefetch(iter(range(50)), depth=3)) == list(range(50))
    assert list(prefetch(iter(range(5)), depth=0)) == list(range(5))

    def failing():
        yield 1
        raise ValueError("broken stream")

    with pytest.raises(ValueError, match="broken stream"):
        list(prefetch(failing(), depth=2))

    produced = []

    def endless():
        k = 0
        while True:
            produced.append(k)
            yield k
            k += 1

    g = prefetch(endless(), depth=2)
    assert [next(g) for _ in range(3)] == [0, 1, 2]
    g.close()  # the consumer stops early: the producer must stop too
    n = len(produced)
    assert not any(t.name == "pftrack-prefetch" and t.is_alive() for t in threading.enumerate())
    assert len(produced) == n and n <= 3 + 2 + 2


def test_bgr_pixels_from_the_planes_match_ffmpegs_scaler(tmp_path):
    """The reader converts yuv420p frames to BGR with OpenCV: the luma is the decoded plane, and the colours
    are within a grey level or two of FFmpeg's own scaler (what OpenCV's video reader returns)."""
    import av

    from pftrack.io.motion_vectors import encode_h264, iter_mv_frames

    rng = np.random.default_rng(3)
    base = cv2.GaussianBlur(rng.integers(0, 255, (96, 128, 3)).astype(np.uint8), (7, 7), 0)
    frames = [np.roll(base, 2 * i, axis=1) for i in range(6)]
    path = encode_h264(frames, tmp_path / "col.mp4", qp=20)
    ours = list(iter_mv_frames(path, bgr=True))
    with av.open(str(path)) as c:
        ref = [(f.to_ndarray(format="bgr24"), f.to_ndarray()[:96]) for f in c.decode(c.streams.video[0])]
    assert len(ours) == len(ref) == 6
    for f, (bgr, y) in zip(ours, ref):
        assert np.array_equal(f.y, y)
        d = np.abs(f.bgr.astype(int) - bgr)
        assert d.mean() < 2.0 and d.max() <= 16


def test_detections_found_on_the_decoding_thread_equal_those_found_on_call(tmp_path):
    """MVSource runs the mv detector as it decodes (ahead of the tracker, on the prefetch thread); the boxes and
    foreground each frame then carries equal those of the detector run in the caller's thread."""
    from pftrack.io.motion_vectors import MVSource, encode_h264

    bg = _texture(3, (240, 320))
    obj = _texture(4, (60, 30))
    frames = []
    for t in range(25):
        f = bg.copy()
        f[90:150, 30 + 5 * t:60 + 5 * t] = obj
        frames.append(cv2.cvtColor(f, cv2.COLOR_GRAY2BGR))
    path = encode_h264(frames, tmp_path / "walk.mp4", qp=20)
    params = C.CDParams(n_min=4)

    ahead = MVSource(path)
    det = C.MVDetector(ahead, params)
    assert ahead.analyse == det.detect
    got = []
    for _, frame in ahead.numbered():
        assert ahead.current.analysis is not None
        got.append((det(frame), det.foreground))

    inline = MVSource(path)
    det2 = C.MVDetector(inline, params)
    inline.analyse = None                          # found on call instead
    ref = []
    for _, frame in inline.numbered():
        assert inline.current.analysis is None
        ref.append((det2(frame), det2.foreground))
    assert len(got) == len(ref) == 25
    assert sum(len(b) for b, _ in got) >= 10
    for (b1, f1), (b2, f2) in zip(got, ref):
        np.testing.assert_array_equal(b1, b2)
        assert (f1 is None) == (f2 is None)
        if f1 is not None:
            np.testing.assert_array_equal(f1[0], f2[0])


def test_mpeg7_marks_each_run_of_high_activity_once(tmp_path):
    import xml.etree.ElementTree as ET

    from pftrack.io.mpeg7 import write_mpeg7

    activity = [(1, 1), (2, 4), (3, 5), (4, 2), (5, 4), (6, 4)]  # two runs at level >= 4: frames 2-3 and 5-6 (the end)
    path = write_mpeg7({3: [(2, 10.0, 20.0), (1, 5.0, 6.0)], 7: []}, activity, tmp_path / "a.xml", fps=25)
    root = ET.parse(path).getroot()
    ns = "{urn:mpeg:mpeg7:schema:2001}"
    videos = root.findall(f".//{ns}Video")
    assert [v.get("id") for v in videos] == ["object3"]  # a label without points has no description
    keys = videos[0].find(f".//{ns}CoordKeyPoints")
    assert [t.text for t in keys.findall(f"{ns}MediaTimePoint")] == ["T00:00:00:0F25", "T00:00:00:1F25"]
    assert keys.find(f"{ns}KeyValue[@dim='x']").text == "5.0 10.0"
    assert keys.find(f"{ns}KeyValue[@dim='y']").text == "6.0 20.0"
    segs = [(s.find(f".//{ns}MediaTimePoint").text, s.find(f".//{ns}MediaIncrDuration").text,
             s.find(f".//{ns}Intensity").text) for s in root.findall(f".//{ns}VideoSegment")]
    assert segs == [("T00:00:00:1F25", "2", "5"), ("T00:00:00:4F25", "2", "4")]
