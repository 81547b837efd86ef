"""One target of a folder with several: ``pftrack track --target`` (a MOTChallenge track, or one of a multi-target
OTB folder's), tracked from its first annotated frame; a source whose ground truth starts late is tracked from there;
bad targets exit 2 with one line. ``pftrack eval --people``: a MOTChallenge folder cut into one single-object
sequence per person, in memory, as ``scripts/make_mot_sot.py`` writes them."""

import cv2
import numpy as np
import pytest

from pftrack.cli import main
from pftrack.errors import SourceError
from pftrack.io import read_track_csv
from pftrack.io.datasets import write_groundtruth, write_mot_groundtruth, write_seqinfo
from pftrack.io.sources import open_source
from pftrack.pipeline import track_source
from pftrack.trackers.registry import create_tracker

N = 16


def _frames(n=N, w=160, h=120):
    """A red square moving right and a green one moving down over grey noise (boxes per frame for each)."""
    rng = np.random.default_rng(3)
    frames, red, green = [], [], []
    for t in range(n):
        f = (rng.random((h, w, 3)) * 40 + 90).astype(np.uint8)
        rx, gy = 10 + 3 * t, 5 + 2 * t
        f[60:80, rx:rx + 20] = (40, 40, 210)
        f[gy:gy + 20, 120:140] = (40, 200, 40)
        frames.append(f)
        red.append((rx, 60, 20, 20))
        green.append((120, gy, 20, 20))
    return frames, np.array(red, float), np.array(green, float)


@pytest.fixture(scope="module")
def mot_folder(tmp_path_factory):
    """A MOTChallenge folder: track 4 (red) on every frame, track 9 (green) from frame 6 on."""
    frames, red, green = _frames()
    d = tmp_path_factory.mktemp("mot") / "two"
    (d / "img1").mkdir(parents=True)
    (d / "gt").mkdir()
    for t, f in enumerate(frames, 1):
        cv2.imwrite(str(d / "img1" / f"{t:06d}.png"), f)
    rows = [[t, 4, *red[t - 1], 1, 1, 1] for t in range(1, N + 1)]
    rows += [[t, 9, *green[t - 1], 1, 1, 1] for t in range(6, N + 1)]
    write_mot_groundtruth(d / "gt" / "gt.txt", np.array(rows, dtype=np.float64))
    write_seqinfo(d, name="two", fps=10, length=N, width=160, height=120, ext=".png")
    return d, red, green


@pytest.fixture(scope="module")
def otb_folder(tmp_path_factory):
    """An OTB folder with two annotated targets (groundtruth_rect.1.txt: red, .2.txt: green, from frame 4)."""
    frames, red, green = _frames()
    d = tmp_path_factory.mktemp("otb") / "Pair"
    (d / "img").mkdir(parents=True)
    for t, f in enumerate(frames, 1):
        cv2.imwrite(str(d / "img" / f"{t:04d}.jpg"), f)
    late = green.copy()
    late[:3] = np.nan
    write_groundtruth(d / "groundtruth_rect.1.txt", red)
    write_groundtruth(d / "groundtruth_rect.2.txt", late)
    return d, red, late


def test_a_mot_track_starts_on_its_first_frame(mot_folder):
    d, red, green = mot_folder
    src = open_source(d, target=9)
    assert src.init_box == tuple(green[5]) and src.init_number == 6
    assert np.isnan(src.groundtruth[:5]).all() and np.allclose(src.groundtruth[5:], green[5:])
    numbers = [n for n, _, _ in track_source(src, create_tracker("color-pf", seed=0))]
    assert numbers == list(range(6, N + 1))


def test_track_cli_follows_the_picked_target(mot_folder, otb_folder, tmp_path):
    for (d, _, _), target, truth, first in ((mot_folder, 9, mot_folder[2], 6), (mot_folder, 4, mot_folder[1], 1),
                                            (otb_folder, 2, otb_folder[2], 4)):
        out = tmp_path / f"{d.name}{target}.csv"
        assert main(["track", str(d), "--target", str(target), "--out", str(out), "--quiet"]) == 0
        rows = read_track_csv(out)
        assert rows[0, 0] == first and rows[-1, 0] == N
        centre = rows[:, 1:3] + rows[:, 3:5] / 2
        want = truth[first - 1:, :2] + truth[first - 1:, 2:] / 2
        assert np.max(np.linalg.norm(centre - want, axis=1)) < 8  # on the picked square, not the other one


def test_ground_truth_that_starts_late_is_tracked_from_there(otb_folder, tmp_path):
    """Without --target an OTB folder gives its first target; a ground truth whose first rows are NaN starts the
    tracker on its first box's frame, as the one-pass protocol of `pftrack eval` does."""
    d, red, late = otb_folder
    src = open_source(d, target=2)
    states = list(track_source(src, create_tracker("color-pf", seed=0)))
    assert states[0][0] == 4 and states[0][2].box == pytest.approx(tuple(late[3]))
    assert open_source(d).init_box == tuple(red[0])


@pytest.mark.parametrize("source, args, needle", [
    ("mot", [], "--target ID; 2 tracks: ids 4, 9"),
    ("mot", ["--target", "5"], "no ground-truth track 5"),
    ("mot", ["--target", "-1"], "a target id is an integer >= 0"),
    ("otb", ["--target", "3"], "no target 3; its targets are 1, 2"),
    ("frames", ["--target", "1"], "this source is neither"),
    ("mot", ["--target", "4", "--box", "1,1,9,9"], "give one of them"),
])
def test_bad_targets_exit_2_with_one_line(mot_folder, otb_folder, source, args, needle, tmp_path, capsys):
    d = {"mot": mot_folder[0], "otb": otb_folder[0], "frames": mot_folder[0] / "img1"}[source]
    out = tmp_path / "t.csv"
    try:
        rc = main(["track", str(d), "--out", str(out), "--quiet", *args])
    except SystemExit as exc:  # argparse's own checks (an argument's type) exit from the parser
        rc = exc.code
    assert rc == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0] and err[0].startswith("pftrack: error:"), err
    assert not out.exists()  # nothing written for a run that cannot start


def test_a_video_whose_ground_truth_starts_late_is_tracked_from_there(tmp_path):
    """A folder holding a video and its ground truth (streamed, frames grabbed up to the first box's frame)."""
    frames, red, _ = _frames()
    d = tmp_path / "clip"
    d.mkdir()
    vw = cv2.VideoWriter(str(d / "clip.avi"), cv2.VideoWriter_fourcc(*"MJPG"), 10, (160, 120))
    for f in frames:
        vw.write(f)
    vw.release()
    late = red.copy()
    late[:4] = np.nan
    write_groundtruth(d / "groundtruth_rect.txt", late)
    out = tmp_path / "v.csv"
    assert main(["track", str(d), "--out", str(out), "--quiet"]) == 0
    rows = read_track_csv(out)
    assert rows[:, 0].tolist() == list(range(5, N + 1))
    assert rows[0, 1:5] == pytest.approx(late[4], abs=0.01)
    centre = rows[:, 1:3] + rows[:, 3:5] / 2
    assert np.max(np.linalg.norm(centre - (late[4:, :2] + late[4:, 2:] / 2), axis=1)) < 8


def test_open_source_refuses_a_target_of_a_camera_or_video():
    with pytest.raises(SourceError, match="neither"):
        open_source(0, target=1)


def test_people_of_a_mot_folder_match_the_written_folders(mot_folder, tmp_path):
    """People in memory (eval --people) and the OTB folders of scripts/make_mot_sot.py agree frame for frame."""
    from pftrack.io.datasets import read_otb, read_sequence
    from pftrack.io.person_sequences import people_of, person_sequences, write_otb

    d, red, green = mot_folder
    seq = read_sequence(d)
    people = people_of(seq, min_frames=5)
    assert [p.name for p in people] == ["two.4", "two.9"] and [p.target for p in people] == [4, 9]
    assert len(people[1].frames) == N - 5 and people[1].frames[0].name == "000006.png"
    assert np.allclose(people[1].groundtruth, green[5:])
    assert [p.name for p in people_of(seq, min_frames=N - 4)] == ["two.4"]  # track 9 has N - 5 boxes
    for person, p in zip(person_sequences(seq.mot_gt, 1, N, min_frames=5, frame_size=(160, 120)), people):
        back = read_otb(write_otb(seq, person, tmp_path / p.name))
        assert np.array_equal(np.isnan(back.groundtruth), np.isnan(p.groundtruth))
        assert np.allclose(np.nan_to_num(back.groundtruth), np.nan_to_num(p.groundtruth), atol=0.01)
        assert np.array_equal(back.absent, p.absent) and back.meta.get("unannotated") == p.meta.get("unannotated")


def test_a_person_whose_annotation_stops_in_view_is_not_absent(tmp_path):
    """Track 9 is annotated on frames 6-10 only, while the green square stays in view: those later frames are
    unannotated (neither absent nor scored). Track 4's square (x = 7 + 3 t on frame t, 20 px wide, a 160 px image) is
    annotated while wholly inside (frames 1-44), partly in view on frames 45-50 (unannotated, as PETS tracks end at
    the border), and absent from frame 51, when less than a tenth of it would be inside."""
    from pftrack.io.datasets import read_sequence
    from pftrack.io.person_sequences import people_of

    frames, red, green = _frames(n=60)
    d = tmp_path / "cut"
    (d / "img1").mkdir(parents=True)
    (d / "gt").mkdir()
    for t, f in enumerate(frames, 1):
        cv2.imwrite(str(d / "img1" / f"{t:06d}.png"), f)
    rows = [[t, 4, *red[t - 1], 1, 1, 1] for t in range(1, 50) if red[t - 1, 0] + 20 <= 160]
    rows += [[t, 9, *green[t - 1], 1, 1, 1] for t in range(6, 11)]
    write_mot_groundtruth(d / "gt" / "gt.txt", np.array(rows, dtype=np.float64))
    write_seqinfo(d, name="cut", fps=10, length=60, width=160, height=120, ext=".png")
    four, nine = people_of(read_sequence(d), min_frames=5)
    assert not nine.absent[:5].any() and nine.meta["unannotated"][0] == 6  # frame 11 of the source
    assert np.all(np.isfinite(four.groundtruth[:44])) and np.isnan(four.groundtruth[44:]).all()
    assert four.meta["unannotated"] == [45, 46, 47, 48, 49, 50]
    assert np.flatnonzero(four.absent).tolist() == list(range(50, 60))


def test_eval_people_runs_one_sequence_per_person(mot_folder, tmp_path, capsys):
    import csv

    d, _, _ = mot_folder
    report = tmp_path / "r"
    assert main(["eval", str(d), "--trackers", "color-pf", "--people", "5", "--workers", "1", "--quiet",
                 "--report", str(report)]) == 0
    with open(report / "results.csv", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert sorted((r["sequence"], int(r["frames"])) for r in rows) == [("two.4", N), ("two.9", N - 5)]
    assert all(float(r["auc"]) > 0.5 for r in rows)  # each square followed from its own first box
    capsys.readouterr()
    assert main(["eval", str(d), "--trackers", "multi-pf", "--protocol", "mot", "--people", "--quiet"]) == 2
    assert "--people" in capsys.readouterr().err
