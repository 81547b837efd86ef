"""A folder holding one video and its ground truth (like the bundled clip) is a sequence: read, tracked, evaluated."""

from pathlib import Path

import cv2
import numpy as np
import pytest

from pftrack.errors import SourceError
from pftrack.io import discover_sequences, open_source, read_sequence
from pftrack.io.datasets import detect_layout, write_groundtruth
from pftrack.io.sources import read_image
from pftrack.io.video_frames import VideoFrame, count_frames
from pftrack.synth import Scene, simple_scene

N = 24


def _video_folder(folder: Path, *, gt: str | None = "otb", seed: int = 3) -> tuple[Path, np.ndarray]:
    """A synthetic scene written as one MJPG video (lossy, so frames are compared against the video's own decode),
    with its ground truth as OTB rows, VOT polygons or none."""
    scene = Scene(simple_scene(seed, n_frames=N))
    frames = list(scene.frames())
    folder.mkdir(parents=True)
    h, w = frames[0].shape[:2]
    vw = cv2.VideoWriter(str(folder / "clip.avi"), cv2.VideoWriter_fourcc(*"MJPG"), 10, (w, h))
    for f in frames:
        vw.write(f)
    vw.release()
    boxes = scene.groundtruth(0)
    if gt == "otb":
        write_groundtruth(folder / "groundtruth_rect.txt", boxes)
    elif gt == "vot":  # the boxes as 8-value polygons (their corners)
        rows = [",".join(f"{v:.2f}" for v in (x, y, x + bw, y, x + bw, y + bh, x, y + bh)) for x, y, bw, bh in boxes]
        (folder / "groundtruth.txt").write_text("\n".join(rows) + "\n")
    return folder, boxes


def _decoded(video: Path) -> list[np.ndarray]:
    cap = cv2.VideoCapture(str(video))
    out = []
    while True:
        ok, img = cap.read()
        if not ok:
            return out
        out.append(img)


def test_a_video_and_its_otb_ground_truth_read_as_a_sequence(tmp_path):
    folder, boxes = _video_folder(tmp_path / "clip")
    assert detect_layout(folder) == "video"
    seq = read_sequence(folder)
    assert seq.kind == "video" and seq.name == "clip" and len(seq) == N == count_frames(folder / "clip.avi")
    assert np.allclose(seq.groundtruth, np.round(boxes, 2)) and seq.init_box == pytest.approx(tuple(boxes[0]), abs=0.01)
    assert not seq.absent.any()
    ref = _decoded(folder / "clip.avi")
    # in order (one decode from start to end), then out of order (a seek)
    assert all(np.array_equal(read_image(f), ref[k]) for k, f in enumerate(seq.frames))
    for k in (17, 4, 5, 0):
        assert np.array_equal(read_image(seq.frames[k]), ref[k])
    assert read_image(VideoFrame(folder / "clip.avi", N + 5)) is None
    assert str(seq.frames[2]).endswith("clip.avi (frame 3)")


def test_vot_polygons_beside_a_video_and_absent_rows(tmp_path):
    folder, boxes = _video_folder(tmp_path / "v", gt="vot")
    seq = read_sequence(folder)
    assert seq.kind == "video" and seq.polygons.shape == (N, 8)
    assert np.allclose(seq.groundtruth, boxes, atol=0.02)
    folder2, boxes2 = _video_folder(tmp_path / "o")
    rows = (folder2 / "groundtruth_rect.txt").read_text().splitlines()
    rows[5] = "NaN,NaN,NaN,NaN"
    (folder2 / "groundtruth_rect.txt").write_text("\n".join(rows[:-2]) + "\n")  # two rows short
    with pytest.warns(UserWarning, match="22 ground-truth rows for 24 frames"):
        seq2 = read_sequence(folder2)
    assert seq2.absent[5] and seq2.absent.sum() == 1 and np.isnan(seq2.groundtruth[-2:]).all()


def test_what_is_not_a_video_folder(tmp_path):
    folder, _ = _video_folder(tmp_path / "two")
    (folder / "copy.avi").write_bytes((folder / "clip.avi").read_bytes())
    assert detect_layout(folder) is None  # two videos: not one sequence
    with pytest.raises(SourceError, match="no single video"):
        open_source(folder)
    imgs, _ = _video_folder(tmp_path / "imgs")
    cv2.imwrite(str(imgs / "0001.png"), np.zeros((8, 8, 3), np.uint8))
    assert detect_layout(imgs) == "frames"  # images beside the video: an image folder, as before


def test_a_video_that_cannot_be_read_is_one_line(tmp_path, capsys):
    from pftrack.cli import main
    from pftrack.io.video_frames import read_video_folder, read_video_frame

    folder, boxes = _video_folder(tmp_path / "broken")
    (folder / "clip.avi").write_bytes(b"not a video at all" * 64)
    assert count_frames(folder / "clip.avi") == 0 and count_frames(folder / "missing.avi") == 0
    with pytest.raises(SourceError, match="cannot open as a video, or contains no readable frames"):
        read_video_folder(folder)
    assert read_video_frame(VideoFrame(folder / "clip.avi", 0)) is None
    assert VideoFrame(folder / "clip.avi", 4).name == "clip.avi#5"
    box = ",".join(f"{v:g}" for v in boxes[0])
    assert main(["track", str(folder), "--box", box, "--out", str(tmp_path / "o.csv"), "--quiet"]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1 and "clip.avi" in err[0]


def test_discovery_takes_annotated_video_folders_only(tmp_path):
    _video_folder(tmp_path / "data" / "b_video")
    _video_folder(tmp_path / "data" / "c_bare", gt=None)
    otb = tmp_path / "data" / "a_otb"
    (otb / "img").mkdir(parents=True)
    for k in range(3):
        cv2.imwrite(str(otb / "img" / f"{k + 1:04d}.png"), np.zeros((30, 40, 3), np.uint8))
    write_groundtruth(otb / "groundtruth_rect.txt", [[5, 5, 10, 10]] * 3)
    assert [s.name for s in discover_sequences(tmp_path / "data")] == ["a_otb", "b_video"]
    assert read_sequence(tmp_path / "data" / "c_bare").groundtruth is None  # trackable with --box, not scored


def test_track_and_eval_a_video_folder(tmp_path, capsys):
    from pftrack.cli import main
    from pftrack.io.sinks import read_track_csv

    folder, boxes = _video_folder(tmp_path / "clip")
    src = open_source(folder)
    assert src.kind == "video" and src.init_box == pytest.approx(tuple(boxes[0]), abs=0.01)
    src.close()
    out = tmp_path / "t.csv"
    assert main(["track", str(folder), "--tracker", "color-pf", "--param", "n_particles=30", "--out", str(out),
                 "--quiet"]) == 0
    rows = read_track_csv(out)
    assert len(rows) == N and rows[0][1:5] == pytest.approx(tuple(boxes[0]), abs=0.01)
    assert main(["eval", str(folder), "--trackers", "color-pf[n_particles=30]", "--seeds", "1", "--workers", "1",
                 "--quiet", "--report", str(tmp_path / "r")]) == 0
    text = (tmp_path / "r" / "summary.md").read_text()
    auc = float(next(line for line in text.splitlines() if line.startswith("| `color-pf[")).split("|")[2])
    assert auc > 0.5
    bare, _ = _video_folder(tmp_path / "bare", gt=None)
    assert main(["track", str(bare), "--out", str(tmp_path / "b.csv"), "--quiet"]) == 2  # no ground truth, no --box
    assert "give an initial box" in capsys.readouterr().err and not (tmp_path / "b.csv").exists()


def test_a_malformed_ground_truth_beside_a_video_is_one_line(tmp_path, capsys):
    from pftrack.cli import main

    folder, _ = _video_folder(tmp_path / "clip")
    (folder / "groundtruth_rect.txt").write_text("1,2,3\n")
    assert main(["track", str(folder), "--out", str(tmp_path / "t.csv"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "groundtruth_rect.txt:1: expected 4 values" in err[0]
    assert main(["eval", str(folder), "--trackers", "color-pf", "--quiet"]) == 2


def test_a_tre_run_on_a_video_starts_on_the_frame_it_names(tmp_path):
    """TRE starts a run mid-sequence: on a video the frames before the start are decoded in order and dropped, so
    the run sees the very frames an image folder of the video's decode would give (no seek by frame number)."""
    from pftrack.eval.runner import Job, TrackerConfig, run_job

    folder, boxes = _video_folder(tmp_path / "v")
    images = tmp_path / "i"
    (images / "img").mkdir(parents=True)
    for k, f in enumerate(_decoded(folder / "clip.avi")):
        cv2.imwrite(str(images / "img" / f"{k + 1:04d}.png"), f)
    write_groundtruth(images / "groundtruth_rect.txt", boxes)
    cfg = TrackerConfig("meanshift", "meanshift")
    a = run_job(Job(cfg, str(folder), "v", 11, "tre"))
    b = run_job(Job(cfg, str(images), "i", 11, "tre"))
    assert a["start_frame"] == b["start_frame"] > 1
    assert a["boxes"] == b["boxes"] and a["auc"] == b["auc"]
