"""Sources, dataset readers and sinks."""

import json

import cv2
import numpy as np
import pytest

from pftrack.errors import FormatError, FrameError, OutputError, SourceError
from pftrack.io import (CsvTrackSink, JsonLinesSink, MotSink, VideoSink, discover_sequences, open_source,
                        prepare_output, read_sequence, read_track_csv)


def write_frames(folder, n=5, size=(40, 30), start=1, ext=".png"):
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(0)
    frames = []
    for i in range(n):
        f = rng.integers(0, 256, (size[1], size[0], 3), dtype=np.uint8)
        cv2.imwrite(str(folder / f"{i + start:04d}{ext}"), f)
        frames.append(f)
    return frames


def test_image_folder_in_natural_order(tmp_path):
    d = tmp_path / "frames"
    d.mkdir()
    for i in (1, 2, 10):
        cv2.imwrite(str(d / f"f{i}.png"), np.full((8, 8, 3), i, np.uint8))
    src = open_source(d)
    assert len(src) == 3
    assert [int(f[0, 0, 0]) for f in src] == [1, 2, 10]


def _write_clip(path, n: int, step: int):
    """An MJPG clip of ``n`` flat 64x48 frames of levels 0, step, 2 step, ..."""
    vw = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10, (64, 48))
    for i in range(n):
        vw.write(np.full((48, 64, 3), step * i, np.uint8))
    vw.release()
    return path


def test_video_file_roundtrip(tmp_path):
    path = _write_clip(tmp_path / "clip.avi", 6, 40)
    with open_source(str(path)) as src:
        frames = list(src)
    assert len(frames) == 6 and frames[0].shape == (48, 64, 3) and frames[0].dtype == np.uint8
    assert abs(int(frames[3].mean()) - 120) < 6


def test_file_sources_read_ahead_on_a_thread_that_stops_with_the_source(tmp_path):
    """Frames decoded ahead (pftrack.io.prefetch) are the same frames in the same order; stopping early and
    closing the source ends the reading thread."""
    import threading

    path = _write_clip(tmp_path / "clip.avi", 12, 20)
    with open_source(str(path)) as src:
        src.prefetch = 4
        ahead = list(src.numbered())
    with open_source(str(path)) as src:
        src.prefetch = 0
        inline = list(src.numbered())
    assert [n for n, _ in ahead] == list(range(1, 13))
    assert all(np.array_equal(a, b) for (_, a), (_, b) in zip(ahead, inline, strict=True))
    src = open_source(str(path))
    src.prefetch = 4
    it = src.numbered()
    assert next(it)[0] == 1 and next(it)[0] == 2
    src.close()  # the consumer stops early: the reader stops before the decoder is released
    assert not any(t.name == "pftrack-prefetch" and t.is_alive() for t in threading.enumerate())


def test_file_sources_decode_in_the_callers_thread_on_one_cpu(tmp_path, monkeypatch):
    """With one CPU to run on there is no second core to decode ahead on: the file sources read in the caller's
    thread, with the same frames."""
    import os

    from pftrack.io import prefetch as pf

    path = _write_clip(tmp_path / "clip.avi", 6, 20)
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0}, raising=False)
    assert pf.usable_cpus() == 1 and pf.default_depth() == 0
    with open_source(str(path)) as src:
        assert src.prefetch == 0
        one = list(src.numbered())
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    assert pf.default_depth() == pf.DEPTH > 0
    with open_source(str(path)) as src:
        assert src.prefetch == pf.DEPTH
        two = list(src.numbered())
    assert [n for n, _ in one] == [n for n, _ in two] == list(range(1, 7))
    assert all(np.array_equal(a, b) for (_, a), (_, b) in zip(one, two, strict=True))

    def no_affinity(pid):
        raise OSError("not supported")

    monkeypatch.setattr(os, "sched_getaffinity", no_affinity, raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 1)
    assert pf.usable_cpus() == 1 and pf.default_depth() == 0


def test_missing_empty_and_fake_sources(tmp_path):
    with pytest.raises(SourceError, match="no such file"):
        open_source(tmp_path / "nope.mp4")
    (tmp_path / "empty").mkdir()
    with pytest.raises(SourceError, match="no images"):
        open_source(tmp_path / "empty")
    fake = tmp_path / "fake.mp4"
    fake.write_text("not a video")
    with pytest.raises(SourceError, match="cannot open|no readable"):
        open_source(fake)


def test_grayscale_16bit_and_alpha_frames_are_converted(tmp_path):
    d = tmp_path / "mixed"
    d.mkdir()
    cv2.imwrite(str(d / "1.png"), np.full((10, 12), 200, np.uint8))
    cv2.imwrite(str(d / "2.png"), np.full((10, 12, 3), 256 * 100, np.uint16))
    cv2.imwrite(str(d / "3.png"), np.full((10, 12, 4), 50, np.uint8))
    frames = list(open_source(d))
    assert all(f.shape == (10, 12, 3) and f.dtype == np.uint8 for f in frames)
    assert frames[0][0, 0].tolist() == [200, 200, 200]
    assert frames[1][0, 0].tolist() == [100, 100, 100]
    assert frames[2][0, 0].tolist() == [50, 50, 50]


def test_a_frame_made_from_grey_remembers_its_grey_image_exactly():
    from pftrack.cues.lk import gray_of
    from pftrack.frames import as_bgr_uint8, grey_origin

    rng = np.random.default_rng(3)
    g = rng.integers(0, 256, (37, 53), dtype=np.uint8)
    for src in (g, g[:, :, None], (g.astype(np.uint16) << 8) | 77):
        bgr = as_bgr_uint8(src)
        origin = grey_origin(bgr)
        assert origin is not None and origin is not src
        np.testing.assert_array_equal(origin, g)
        # the grey features read the origin: the same levels as converting the BGR frame back
        assert gray_of(bgr) is origin
        np.testing.assert_array_equal(cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY), g)
    # the caller's grey buffer is copied: refilling it does not change the remembered image
    buf = g.copy()
    bgr = as_bgr_uint8(buf)
    buf[:] = 0
    np.testing.assert_array_equal(grey_origin(bgr), g)
    # colour frames and arrays derived from a remembered frame have no origin
    colour = rng.integers(0, 256, (5, 6, 3), dtype=np.uint8)
    assert grey_origin(as_bgr_uint8(colour)) is None
    assert grey_origin(bgr.copy()) is None and grey_origin(bgr[1:, 1:]) is None
    # the record goes with the frame
    from pftrack import frames as frames_module

    n = len(frames_module._GREY_ORIGINS)
    tmp = as_bgr_uint8(g)
    assert len(frames_module._GREY_ORIGINS) == n + 1
    del tmp
    assert len(frames_module._GREY_ORIGINS) == n


def test_corrupt_frame_stops_or_is_skipped(tmp_path):
    d = tmp_path / "seq"
    write_frames(d, 4)
    (d / "0003.png").write_bytes(b"garbage")
    src = open_source(d)
    seen = []
    with pytest.raises(FrameError, match="frame 3"):
        for n, _ in src.numbered():
            seen.append(n)
    assert seen == [1, 2]
    src = open_source(d, skip_bad_frames=True)
    with pytest.warns(UserWarning, match="skipping"):
        numbers = [n for n, _ in src.numbered()]
    assert numbers == [1, 2, 4] and src.skipped == [3]


def test_frame_size_change_is_an_error(tmp_path):
    d = tmp_path / "seq"
    write_frames(d, 2, size=(40, 30))
    cv2.imwrite(str(d / "0003.png"), np.zeros((31, 40, 3), np.uint8))
    with pytest.raises(FrameError, match="frame 3.*differs"):
        list(open_source(d))


def test_otb_reader(tmp_path):
    seq = tmp_path / "Seq"
    write_frames(seq / "img", 5)
    (seq / "groundtruth_rect.txt").write_text("1,2,3,4\n5\t6\t7\t8\nNaN,NaN,NaN,NaN\n")
    with pytest.warns(UserWarning, match="3 ground-truth rows for 5 images"):  # a misaligned folder is announced
        s = read_sequence(seq)
    assert s.kind == "otb" and len(s) == 5
    assert s.groundtruth.shape == (5, 4)
    assert s.groundtruth[1].tolist() == [5, 6, 7, 8]
    assert np.isnan(s.groundtruth[2:]).all()  # NaN row and missing rows
    assert s.init_box == (1, 2, 3, 4)
    with pytest.warns(UserWarning, match="rows"):
        src = open_source(seq)
    assert src.init_box == (1, 2, 3, 4) and len(src) == 5



@pytest.mark.parametrize("folder", ["David", "otb_david"])
def test_otb_known_partial_sequences_are_cut_to_their_annotated_stretch(tmp_path, folder):
    """OTB-100's David has 770 images and 471 boxes, for frames 300-770 (the benchmark's configuration): the boxes
    must not be paired with frames 1-471.  A folder already cut, or of another name, is left as it is."""
    def make(name, n_img, n_rows):
        seq = tmp_path / name
        (seq / "img").mkdir(parents=True)
        for i in range(1, n_img + 1):
            (seq / "img" / f"{i:04d}.jpg").touch()  # the reader lists frames; it does not decode them
        (seq / "groundtruth_rect.txt").write_text("".join(f"{i},1,20,30\n" for i in range(n_rows)))
        return read_sequence(seq)

    s = make(folder, 770, 471)
    assert len(s) == 471 and s.frames[0].name == "0300.jpg" and s.frames[-1].name == "0770.jpg"
    assert s.groundtruth[0].tolist() == [0, 1, 20, 30] and s.groundtruth[-1].tolist() == [470, 1, 20, 30]
    assert len(make(folder + "_cut", 471, 471)) == 471  # not a known name: as it is
    assert make("Freeman4", 283, 283).frames[-1].name == "0283.jpg"  # already the stretch
    s = make("Diving", 231, 215)
    assert len(s) == 215 and s.frames[-1].name == "0215.jpg"
    with pytest.warns(UserWarning, match="50 ground-truth rows for 84 images"):
        s = make("Football1", 74 + 10, 50)  # other rows than the stretch's: not the benchmark's sequence
    assert len(s) == 84


def test_otb_folder_with_two_targets_gives_two_sequences(tmp_path):
    """OTB-100's Jogging annotates two people (groundtruth_rect.1.txt, .2.txt): a sequence each, named as the
    benchmark names them, and an evaluation job re-reads the right one."""
    from pftrack.eval.runner import build_jobs, parse_tracker_list, run_job

    data = tmp_path / "otb"
    seq = data / "Jogging"
    write_frames(seq / "img", 4, size=(64, 48))
    (seq / "groundtruth_rect.1.txt").write_text("2,3,10,12\n" * 4)
    (seq / "groundtruth_rect.2.txt").write_text("30,20,12,14\n" * 4)
    write_frames(data / "Other" / "img", 4, size=(64, 48))
    (data / "Other" / "groundtruth_rect.txt").write_text("5,5,10,10\n" * 4)
    seqs = discover_sequences(data)
    assert [s.name for s in seqs] == ["Jogging.1", "Jogging.2", "Other"]
    assert [s.target for s in seqs] == [1, 2, None]
    assert seqs[0].init_box == (2, 3, 10, 12) and seqs[1].init_box == (30, 20, 12, 14)
    assert [s.name for s in discover_sequences(seq)] == ["Jogging.1", "Jogging.2"]
    assert read_sequence(seq).init_box == (2, 3, 10, 12)  # one folder read alone: its first target
    jobs = build_jobs(seqs[:2], parse_tracker_list("template"), seeds=1, protocol="ope")
    recs = [run_job(j) for j in jobs]
    assert [r["sequence"] for r in recs] == ["Jogging.1", "Jogging.2"]
    assert recs[1]["boxes"][:4] == [30.0, 20.0, 12.0, 14.0]  # flattened rows; the first is the init box
    from pftrack.cli import main

    assert main(["eval", str(data), "--trackers", "template", "--quiet", "--report", str(tmp_path / "rep")]) == 0
    rows = (tmp_path / "rep" / "results.csv").read_text().splitlines()
    assert sum(r.split(",")[1] in ("Jogging.1", "Jogging.2", "Other") for r in rows[1:]) == 3


def test_eval_refuses_two_sequences_of_one_name_and_says_which(tmp_path, capsys):
    from pftrack.cli import main

    for part in ("a", "b"):
        write_frames(tmp_path / part / "walk" / "img", 3, size=(64, 48))
        (tmp_path / part / "walk" / "groundtruth_rect.txt").write_text("5,5,10,10\n" * 3)
    assert main(["eval", str(tmp_path / "a"), str(tmp_path / "b"), "--trackers", "template", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "'walk'" in err and str(tmp_path / "a" / "walk") in err and str(tmp_path / "b" / "walk") in err
    assert len(err.strip().splitlines()) == 1


def test_lasot_and_got10k_folders(tmp_path):
    """LaSOT: frames in img/, groundtruth.txt, and full_occlusion.txt / out_of_view.txt (one line of 0/1 flags);
    GOT-10k: frames beside groundtruth.txt and absence.label (a flag a line).  The flags give the absent frames."""
    las = tmp_path / "airplane-1"
    write_frames(las / "img", 6, start=1, ext=".jpg")
    (las / "groundtruth.txt").write_text("1,2,10,12\n" * 6)
    (las / "full_occlusion.txt").write_text("0,0,1,1,0,0")
    (las / "out_of_view.txt").write_text("0,0,0,0,0,1")
    s = read_sequence(las)
    assert len(s) == 6 and s.init_box == (1, 2, 10, 12)
    assert s.absent.tolist() == [False, False, True, True, False, True]
    got = tmp_path / "GOT-10k_Val_000001"
    write_frames(got, 4, start=1, ext=".jpg")
    (got / "groundtruth.txt").write_text("3,4,10,12\n" * 4)
    (got / "absence.label").write_text("0\n1\n0\n0\n")
    s = read_sequence(got)
    assert len(s) == 4 and s.absent.tolist() == [False, True, False, False]
    (got / "absence.label").write_text("0\nx\n")
    with pytest.raises(FormatError, match="absence.label"):
        read_sequence(got)


def test_a_dataset_grouped_in_folders_gives_the_sequences_one_level_further(tmp_path):
    """LaSOT keeps its sequences in category folders (airplane/airplane-1); a folder with no sequence among its
    subfolders gives those of the level below, in order, and a folder with neither is still an error."""
    for group, name in (("bird", "bird-2"), ("airplane", "airplane-10"), ("airplane", "airplane-1")):
        seq = tmp_path / "lasot" / group / name
        write_frames(seq / "img", 3, start=1, ext=".jpg")
        (seq / "groundtruth.txt").write_text("1,2,10,12\n" * 3)
    assert [s.name for s in discover_sequences(tmp_path / "lasot")] == ["airplane-1", "airplane-10", "bird-2"]
    (tmp_path / "empty" / "a" / "b").mkdir(parents=True)
    with pytest.raises(SourceError, match="no OTB"):
        discover_sequences(tmp_path / "empty")


def test_rows_of_no_extent_are_absent_frames(tmp_path):
    """A ground-truth row of zero width or height (``0,0,0,0``) is a frame without the target, as a NaN row is: the
    lost flag is scored there, and the frame is not scored for overlap."""
    seq = tmp_path / "zeros"
    write_frames(seq / "img", 5, start=1, ext=".jpg")
    (seq / "groundtruth_rect.txt").write_text("1,2,10,12\n0,0,0,0\nnan,nan,nan,nan\n5,6,0,12\n3,4,10,12\n")
    s = read_sequence(seq)
    assert s.absent.tolist() == [False, True, True, True, False]


def test_temple_color_128_folder(tmp_path):
    """Temple Color 128: img/ + FOLDER_gt.txt, and FOLDER_frames.txt naming the annotated stretch of the images."""
    seq = tmp_path / "Airport_ce"
    write_frames(seq / "img", 6, start=1, ext=".jpg")
    (seq / "Airport_ce_gt.txt").write_text("".join(f"{i},2,10,12\n" for i in range(4)))
    (seq / "Airport_ce_frames.txt").write_text("2,5\n")
    s = read_sequence(seq)
    assert s.kind == "otb" and s.name == "Airport_ce"
    assert [f.name for f in s.frames] == ["0002.jpg", "0003.jpg", "0004.jpg", "0005.jpg"]
    assert s.init_box == (0, 2, 10, 12) and s.groundtruth[3].tolist() == [3, 2, 10, 12]
    (seq / "Airport_ce_frames.txt").unlink()  # no stretch given: every image
    with pytest.warns(UserWarning, match="4 ground-truth rows for 6 images"):
        assert len(read_sequence(seq)) == 6
    (seq / "Airport_ce_frames.txt").write_text("5\n")
    with pytest.raises(FormatError, match="frames.txt"):
        read_sequence(seq)

def test_otb_malformed_groundtruth(tmp_path):
    seq = tmp_path / "Seq"
    write_frames(seq / "img", 2)
    (seq / "groundtruth_rect.txt").write_text("1,2,3\n")
    with pytest.raises(FormatError, match="groundtruth_rect.txt:1"):
        read_sequence(seq)
    (seq / "groundtruth_rect.txt").write_text("1,2,x,4\n")
    with pytest.raises(FormatError, match="expected numbers"):
        read_sequence(seq)


def test_vot_reader_polygons_and_boxes(tmp_path):
    seq = tmp_path / "bag"
    write_frames(seq, 3, start=1, ext=".jpg")
    (seq / "groundtruth.txt").write_text("0,0,10,0,10,10,0,10\n1,1,4,4\n3,1,5,3,3,5,1,3\n")
    s = read_sequence(seq)
    assert s.kind == "vot"
    assert s.groundtruth.tolist() == [[0, 0, 10, 10], [1, 1, 4, 4], [1, 1, 4, 4]]


def test_mot_reader(tmp_path):
    seq = tmp_path / "MOT"
    write_frames(seq / "img1", 4, start=1, ext=".jpg")
    (seq / "seqinfo.ini").write_text(
        "[Sequence]\nname=MOT\nimDir=img1\nframeRate=7\nseqLength=3\nimWidth=40\nimHeight=30\n")
    (seq / "gt").mkdir()
    (seq / "gt" / "gt.txt").write_text("1,1,5,5,10,20,1,-1,-1,-1\n2,1,6,5,10,20,1,-1,-1,-1\n")
    s = read_sequence(seq)
    assert s.kind == "mot" and len(s) == 3 and s.fps == 7 and s.size == (40, 30)
    assert s.mot_gt.shape == (2, 10)
    (seq / "seqinfo.ini").write_text("name=MOT\n")
    with pytest.raises(FormatError, match="seqinfo"):
        read_sequence(seq)


def test_discover_sequences(tmp_path):
    for name in ("b", "a"):
        write_frames(tmp_path / name / "img", 2)
        (tmp_path / name / "groundtruth_rect.txt").write_text("1,1,5,5\n1,1,5,5\n")
    assert [s.name for s in discover_sequences(tmp_path)] == ["a", "b"]
    with pytest.raises(SourceError):
        discover_sequences(tmp_path / "a" / "img")


def test_csv_sink_streams_whole_rows(tmp_path):
    path = tmp_path / "out" / "t.csv"
    sink = CsvTrackSink(path)
    sink.write(1, (1.5, 2.25, 3, 4), 0.987654, False)
    # flushed: readable before close
    assert path.read_text().splitlines() == ["frame,x,y,w,h,score,lost", "1,1.5,2.25,3,4,0.98765,0"]
    sink.write(2, (-0.0001, 2, 3, 4), 0.5, True)
    sink.close()
    rows = read_track_csv(path)
    assert rows.shape == (2, 7) and rows[1, 6] == 1


def test_mot_and_jsonl_sinks(tmp_path):
    with MotSink(tmp_path / "m.txt") as m:
        m.write(3, 7, (1, 2, 3, 4), 0.9)
    assert (tmp_path / "m.txt").read_text() == "3,7,1,2,3,4,0.9,-1,-1,-1\n"
    with JsonLinesSink(tmp_path / "r.jsonl") as j:
        j.write({"frame": 1, "box": np.array([1.0, 2.0, 3.0, 4.0])})
    assert json.loads((tmp_path / "r.jsonl").read_text()) == {"frame": 1, "box": [1.0, 2.0, 3.0, 4.0]}


def test_jsonl_sink_takes_numpy_scalars_and_refuses_what_json_cannot_hold(tmp_path):
    with JsonLinesSink(tmp_path / "r.jsonl") as j:
        j.write({"frame": np.int64(2), "score": np.float32(0.5), "lost": np.bool_(True)})
        with pytest.raises(TypeError, match="cannot serialise object"):
            j.write({"frame": 3, "extra": object()})
        with pytest.raises(ValueError):  # NaN is not JSON: a record with one is refused, not written as NaN
            j.write({"frame": 4, "score": float("nan")})
    assert [json.loads(line) for line in (tmp_path / "r.jsonl").read_text().splitlines()] == [
        {"frame": 2, "score": 0.5, "lost": True}]
    with pytest.raises(OutputError, match="sink is closed"):
        j.write({"frame": 5})


@pytest.mark.parametrize("text, message", [
    ("", "expected header"),
    ("frame,x,y,w,h\n1,2,3,4,5\n", "expected header"),
    ("frame,x,y,w,h,score,lost\n1,2,3,4,5,0.9\n", r":2: expected 7 values, got 6"),
    ("frame,x,y,w,h,score,lost\n1,2,3,4,5,0.9,0\n\n2,a,3,4,5,0.9,0\n", r":4: expected numbers"),
])
def test_reading_a_track_csv_names_the_bad_line(tmp_path, text, message):
    path = tmp_path / "t.csv"
    path.write_text(text)
    with pytest.raises(FormatError, match=message):
        read_track_csv(path)


def test_video_sink(tmp_path):
    path = tmp_path / "v.mp4"
    with VideoSink(path, fps=10) as v:
        for i in range(5):
            v.write(np.full((32, 48, 3), 50 * i, np.uint8))
    cap = cv2.VideoCapture(str(path))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 5
    cap.release()


@pytest.mark.parametrize("ext", [".mkv", ".avi", ".mov", ".wmv"])
def test_video_sink_writes_each_listed_container(tmp_path, ext):
    with VideoSink(tmp_path / f"v{ext}", fps=10) as v:
        for i in range(3):
            v.write(np.full((32, 48, 3), 50 * i, np.uint8))
    cap = cv2.VideoCapture(str(tmp_path / f"v{ext}"))
    n = 0
    while cap.read()[0]:
        n += 1
    assert n == 3


def test_a_video_format_that_cannot_be_written_is_refused_before_any_work(tmp_path, capsys):
    from pftrack.cli import main

    with pytest.raises(OutputError, match="cannot write a video as '.gif'"):
        VideoSink(tmp_path / "v.gif")
    frames = tmp_path / "frames"
    write_frames(frames, n=3)
    out = tmp_path / "t.csv"
    assert main(["track", str(frames), "--box", "5,5,10,10", "--out", str(out), "--video-out",
                 str(tmp_path / "v.gif"), "--quiet"]) == 2
    assert "use .avi, .m4v, .mkv" in capsys.readouterr().err and not out.exists()


def test_unwritable_outputs(tmp_path):
    (tmp_path / "adir").mkdir()
    with pytest.raises(OutputError, match="is a folder"):
        prepare_output(tmp_path / "adir")
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(OutputError):
        prepare_output(blocker / "sub" / "out.csv")
    with pytest.raises(OutputError, match="outside"):
        prepare_output(tmp_path / ".." / "escape.csv", within=tmp_path)


def test_h264_round_trip_keeps_count_and_size_and_is_close():
    pytest.importorskip("av")
    from pftrack.errors import ParameterError
    from pftrack.io.codec import h264_round_trip

    yy, xx = np.mgrid[0:21, 0:33]
    frames = [np.stack([(xx * 7 + k * 3) % 256, (yy * 11) % 256, np.full_like(xx, 128)], axis=2).astype(np.uint8)
              for k in range(5)]
    out = h264_round_trip(frames, 18, fps=7)
    assert len(out) == 5
    assert all(f.shape == (21, 33, 3) and f.dtype == np.uint8 for f in out)  # odd sizes padded and cropped back
    err = np.mean([np.abs(a.astype(int) - b.astype(int)).mean() for a, b in zip(out, frames)])
    assert 0.0 < err < 8.0  # lossy, but close at a high quality
    worse = h264_round_trip(frames, 45, fps=7)
    assert np.mean([np.abs(a.astype(int) - b.astype(int)).mean() for a, b in zip(worse, frames)]) > err
    grey = h264_round_trip([f[:, :, 0] for f in frames[:2]], 18)
    assert grey[0].shape == (21, 33, 3)
    with pytest.raises(ParameterError):
        h264_round_trip(frames, 60)


def test_float_and_wide_integer_frames_are_converted_or_refused_with_their_range():
    from pftrack.frames import as_bgr_uint8

    rng = np.random.default_rng(5)
    img = rng.integers(0, 256, (7, 9, 3), dtype=np.uint8)
    for dtype in (np.float32, np.float64):
        np.testing.assert_array_equal(as_bgr_uint8((img / 255.0).astype(dtype)), img)
    for dtype in (np.int32, np.int64, np.int16, np.uint32):
        np.testing.assert_array_equal(as_bgr_uint8(img.astype(dtype)), img)
    np.testing.assert_array_equal(as_bgr_uint8(img[:, :, 0].astype(np.int64)), img[:, :, [0, 0, 0]])
    with pytest.raises(FrameError, match=r"0\.5\.\.255 lie outside \[0, 1\]"):
        as_bgr_uint8(np.linspace(0.5, 255, 63).reshape(7, 9))
    with pytest.raises(FrameError, match="NaN"):
        as_bgr_uint8(np.full((4, 4), np.nan))
    with pytest.raises(FrameError, match="-1..255 lie outside 0..255"):
        as_bgr_uint8(np.array([[-1, 255]], np.int32))
    with pytest.raises(FrameError, match="unsupported pixel type"):
        as_bgr_uint8(np.zeros((4, 4), np.complex64))
