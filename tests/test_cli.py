"""The command line: the happy path and every bad-input case exits with code 2 and one line."""

import sys

import cv2
import numpy as np
import pytest

from pftrack.cli import main
from pftrack.io import read_track_csv
from pftrack.synth import Scene, simple_scene


@pytest.fixture(scope="module")
def clip(tmp_path_factory):
    d = tmp_path_factory.mktemp("clip")
    scene = Scene(simple_scene(0, n_frames=20))
    path = d / "clip.avi"
    vw = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 20, (320, 240))
    for f in scene.frames():
        vw.write(f)
    vw.release()
    box = ",".join(f"{v:.2f}" for v in scene.groundtruth(0)[0])
    return path, box


def one_line_error(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("pftrack: error:"), err
    assert "Traceback" not in err[0]
    return err[0]


def test_track_writes_one_row_per_frame(clip, tmp_path, capsys):
    path, box = clip
    out = tmp_path / "t.csv"
    video = tmp_path / "v.mp4"
    rc = main(["track", str(path), "--box", box, "--out", str(out), "--video-out", str(video), "--quiet",
               "--param", "n_particles=50"])
    assert rc == 0
    rows = read_track_csv(out)
    assert rows.shape == (20, 7) and rows[:, 0].tolist() == list(range(1, 21))
    assert video.stat().st_size > 0
    assert "20 frames tracked" in capsys.readouterr().err


def test_json_lines_carry_the_trackers_scalar_info(clip, tmp_path):
    """Every line is JSON with the box, score and flag, and the scalar entries of the state's info: the tracker's
    mode and the loss test's ratio for fusion-pf."""
    import json

    path, box = clip
    out = tmp_path / "t.jsonl"
    assert main(["track", str(path), "--box", box, "--out", str(tmp_path / "t.csv"), "--json-out", str(out),
                 "--quiet"]) == 0
    lines = [json.loads(line) for line in out.read_text().splitlines()]
    assert len(lines) == 20 and lines[0]["frame"] == 1 and len(lines[5]["box"]) == 4
    assert lines[5]["info"]["mode"] == "tracking" and isinstance(lines[5]["info"]["llr"], float)


def test_json_lines_keep_lists_of_words_and_drop_arrays():
    """A search frame's refusals (``vetoes``, a list of reasons) reach the JSON Lines; arrays and other objects do
    not, and a non-finite number is written as null."""
    from pftrack.cli.track import scalar_info

    info = {"mode": "searching", "vetoes": ["unique", "leaving"], "llr": float("nan"), "n": np.int64(3),
            "mask": np.zeros((2, 2)), "centre": [1.0, 2.0]}
    assert scalar_info(info) == {"mode": "searching", "vetoes": ["unique", "leaving"], "llr": None, "n": 3}


@pytest.mark.parametrize("args, needle", [
    (["track", "MISSING.mp4", "--box", "1,1,5,5"], "no such file"),
    (["track", "{clip}", "--box", "1,1,0,5"], "zero or negative size"),
    (["track", "{clip}", "--box", "900,900,5,5"], "outside"),
    (["track", "{clip}", "--box", "1,2,three,4"], "X,Y,W,H"),
    (["track", "{clip}"], "initial box"),
    (["track", "{clip}", "--box", "1,1,5,5", "--tracker", "nope"], "unknown tracker"),
    (["track", "{clip}", "--box", "1,1,5,5", "--param", "bogus=1"], "unknown parameter"),
    (["track", "{clip}", "--box", "1,1,5,5", "--tracker", "opencv-csrt", "--param", "sigma=1"], "takes no parameters"),
    (["track", "{clip}", "--box", "1,1,5,5", "--param", "n_particles=0"], "n_particles"),
    (["track", "{clip}", "--box", "1,1,5,5", "--param", "sigma=abc"], "sigma"),
    (["track", "{clip}", "--box", "1,1,5,5", "--param", "novalue"], "KEY=VALUE"),
    (["track", "{fake}", "--box", "1,1,5,5"], "cannot open"),
    (["track", "{empty}", "--box", "1,1,5,5"], "no images"),
    (["track", "{clip}", "--box", "1,1,5,5", "--out", "{blocked}"], "cannot"),
    (["list", "nope"], "unknown tracker"),
    (["track", "{clip}", "--box", "1,1,5,5", "--seed", "-1"], "a seed is an integer >= 0"),
    (["mot", "{clip}", "--seed", "x"], "a seed is an integer >= 0"),
    (["calibrate-sim", "--random-scene", "-3"], "a seed is an integer >= 0"),
])
def test_bad_input_exits_2(args, needle, clip, tmp_path, capsys):
    fake = tmp_path / "fake.mp4"
    fake.write_text("not a video")
    (tmp_path / "empty").mkdir()
    (tmp_path / "blocker").write_text("x")
    subs = {"clip": str(clip[0]), "fake": str(fake), "empty": str(tmp_path / "empty"),
            "blocked": str(tmp_path / "blocker" / "x.csv")}
    args = [a.format(**subs) for a in args]
    if args[0] == "track" and "--out" not in args:
        args += ["--out", str(tmp_path / "o.csv")]
    try:
        rc = main(args + (["--quiet"] if args[0] == "track" else []))
    except SystemExit as exc:  # argparse's own checks (an argument's type) exit from the parser
        rc = exc.code
    assert rc == 2
    assert needle in one_line_error(capsys)


def test_a_negative_seed_is_refused_by_the_api():
    from pftrack.errors import ParameterError
    from pftrack.trackers import create_tracker

    for bad in (-1, 1.5, "3", True):
        with pytest.raises(ParameterError, match="seed must be an integer"):
            create_tracker("color-pf", seed=bad)
    assert create_tracker("color-pf", seed=0) is not None


def test_an_unknown_parameter_is_told_in_a_short_line():
    """A misspelt parameter gets its close matches; another one names the parameters when there are few, and points
    to ``pftrack list`` when there are many (not a line of a hundred names)."""
    from pftrack.errors import ParameterError
    from pftrack.trackers import create_tracker

    with pytest.raises(ParameterError, match="did you mean n_particles"):
        create_tracker("color-pf", num_particles=5)
    with pytest.raises(ParameterError) as err:
        create_tracker("color-pf", nosuch=1)
    assert "pftrack list" in str(err.value) and len(str(err.value)) < 120
    with pytest.raises(ParameterError, match="valid: enlarge, flat_fallback, lost_frames"):
        create_tracker("template", nosuch=1)


def test_a_tracker_named_by_anything_but_a_string_is_a_parameter_error():
    """``create_tracker`` given a spec object or a list instead of a name says so (not difflib's TypeError)."""
    from pftrack.errors import ParameterError
    from pftrack.trackers import create_tracker
    from pftrack.trackers.registry import list_trackers

    for bad in (list_trackers()[0], ["color-pf"], 3):
        with pytest.raises(ParameterError, match="named by a string"):
            create_tracker(bad)


def test_missing_camera_is_one_line_on_the_terminal(tmp_path, capfd):
    # OpenCV's backends write their own warnings straight to the process's stderr when a device fails to open
    assert main(["track", "97", "--box", "1,1,5,5", "--out", str(tmp_path / "o.csv"), "--quiet"]) == 2
    err = [line for line in capfd.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1 and "camera 97" in err[0]


def test_unwritable_video_is_one_line_on_the_terminal(clip, tmp_path, capfd):
    out = ["--out", str(tmp_path / "o.csv"), "--video-out", str(tmp_path / "v.xyz"), "--quiet"]
    assert main(["track", str(clip[0]), "--box", "1,1,5,5", *out]) == 2
    err = [line for line in capfd.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1 and "cannot write a video as '.xyz'" in err[0]  # refused before the run starts
    assert not (tmp_path / "o.csv").exists()


def test_corrupt_frame_keeps_earlier_rows(tmp_path, capsys):
    d = tmp_path / "frames"
    d.mkdir()
    scene = Scene(simple_scene(1, n_frames=6))
    for t, f in enumerate(scene.frames()):
        cv2.imwrite(str(d / f"{t:03d}.png"), f)
    (d / "004.png").write_bytes(b"broken")
    box = ",".join(str(v) for v in scene.groundtruth(0)[0])
    out = tmp_path / "t.csv"
    assert main(["track", str(d), "--box", box, "--out", str(out), "--quiet"]) == 2
    assert "frame 5" in one_line_error(capsys)
    assert read_track_csv(out)[:, 0].tolist() == [1, 2, 3, 4]
    with pytest.warns(UserWarning, match=r"skipping unreadable frame 5 \(004\.png\)"):
        assert main(["track", str(d), "--box", box, "--out", str(out), "--quiet", "--skip-bad-frames"]) == 0
    assert read_track_csv(out)[:, 0].tolist() == [1, 2, 3, 4, 6]
    assert "(1 unreadable frame skipped)" in capsys.readouterr().err


def test_track_a_single_image_reports_no_speed(tmp_path, capsys):
    """One image is an initialisation and no update: the summary says so instead of printing 'nan fps'."""
    scene = Scene(simple_scene(1, n_frames=1))
    img = tmp_path / "one.png"
    cv2.imwrite(str(img), scene.frames()[0])
    box = ",".join(str(v) for v in scene.groundtruth(0)[0])
    out = tmp_path / "t.csv"
    assert main(["track", str(img), "--box", box, "--out", str(out), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "1 frame tracked" in err and "no update to time" in err and "nan" not in err
    assert read_track_csv(out)[:, 0].tolist() == [1]


def test_usage_errors_exit_2(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["track"])
    assert exc.value.code == 2
    with pytest.raises(SystemExit) as exc:
        main(["frobnicate"])
    assert exc.value.code == 2


def test_list(capsys):
    assert main(["list"]) == 0
    assert "color-pf" in capsys.readouterr().out
    assert main(["list", "color-pf"]) == 0
    assert "kickoff_fraction" in capsys.readouterr().out


def test_demo_runs_on_bundled_clip(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path / "demo"), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "OTB success AUC" in out
    rows = read_track_csv(tmp_path / "demo" / "track.csv")
    assert rows.shape == (120, 7)
    assert (tmp_path / "demo" / "track.mp4").stat().st_size > 10_000
    auc = float(out.split("AUC")[1].split()[0])
    assert auc > 0.4  # the bundled clip is tracked, not just processed


def test_seed_lists_parse_ranges_and_single_values():
    from pftrack.cli.common import parse_seeds

    assert parse_seeds("0-3") == [0, 1, 2, 3]
    assert parse_seeds("1,4,7") == [1, 4, 7]
    assert parse_seeds("100") == [100]
    assert parse_seeds("100, 200-202") == [100, 200, 201, 202]
    for bad in ("", "5-1", "a", "-3", "1-"):
        with pytest.raises(ValueError):
            parse_seeds(bad)


def test_coordinates_may_start_with_a_minus_sign(clip, tmp_path, capsys):
    """A box or line that starts left of or above the frame is written as argparse would take for an option
    (``--box -5,...``); the command line attaches it to its option instead of failing with a usage error."""
    from pftrack.cli import attach_negative_values

    assert attach_negative_values(["tripwire", "v", "--line", "-50,120;400,120", "--out", "e.csv"]) == [
        "tripwire", "v", "--line=-50,120;400,120", "--out", "e.csv"]
    assert attach_negative_values(["track", "v", "--box", "-.5,2,3,4"]) == ["track", "v", "--box=-.5,2,3,4"]
    assert attach_negative_values(["track", "v", "--box", "-h"]) == ["track", "v", "--box", "-h"]  # an option
    path, box = clip
    x, y, w, h = (float(v) for v in box.split(","))
    out = tmp_path / "t.csv"
    rc = main(["track", str(path), "--box", f"{-2.0},{y},{x + w + 2.0},{h}", "--out", str(out), "--quiet",
               "--param", "n_particles=50"])
    assert rc == 0, capsys.readouterr().err
    assert read_track_csv(out).shape == (20, 7)


def test_the_reproduce_command_leaves_out_the_output_options(monkeypatch):
    from pftrack.cli.common import reproduce_command

    monkeypatch.setattr(sys, "argv", ["/somewhere/bin/pftrack", "eval", "my data", "--doc", "out.md", "--seeds", "3",
                                      "--doc=other.md", "--trackers", "color-pf[n_particles=50]"])
    assert reproduce_command(drop=("--doc",)) == ("pftrack eval 'my data' --seeds 3 "
                                                  "--trackers 'color-pf[n_particles=50]'")
    monkeypatch.setattr(sys, "argv", ["python", "-m", "pftrack"])  # not the installed command: no line to give
    assert reproduce_command() is None
