"""`pftrack synth`: the point-tracking scenes of book ch. 7 written through the command line, and its bad input
refused with exit code 2 and one line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pftrack.cli import main


def test_occluder_and_stereo_rail_scenes_come_out_as_the_point_commands_read_them(tmp_path, capsys):
    assert main(["synth", "occluder", "--seeds", "3", "--out", str(tmp_path / "occ")]) == 0
    scene = tmp_path / "occ" / "occluder-003"
    meta = json.loads((scene / "meta.json").read_text())
    truth = np.loadtxt(scene / "points_gt.csv", delimiter=",", skiprows=1)
    assert len(list((scene / "img").iterdir())) == int(truth[:, 0].max())  # one truth row per frame and point
    out = tmp_path / "p.csv"
    assert main(["points", str(scene), "--points", meta["points"], "--out", str(out), "--quiet"]) == 0
    assert len(out.read_text().splitlines()) == 1 + len(truth)

    assert main(["synth", "stereo-rail", "--seeds", "3", "--out", str(tmp_path / "rail")]) == 0
    rail = tmp_path / "rail" / "stereo-rail-003"
    meta = json.loads((rail / "meta.json").read_text())
    assert len(list((rail / "left").iterdir())) == len(list((rail / "right").iterdir())) > 0
    out = tmp_path / "s.csv"
    assert main(["stereo", str(rail / "left"), str(rail / "right"), "--calib", str(rail / "calib.json"), "--points",
                 meta["points"], "--out", str(out), "--quiet"]) == 0
    assert out.read_text().splitlines()[0].startswith("frame,point")
    capsys.readouterr()


@pytest.mark.parametrize("argv, message", [
    (["simple", "--seeds", "2-1"], "--seeds must look like"),
    (["simple", "--seeds", "x"], "--seeds must look like"),
    (["simple", "--seeds", "1", "--frames", "1-20"], "--frames and --strip apply to twocam scenes"),
    (["twocam", "--seeds", "1"], "twocam scenes need --source"),
])
def test_bad_synth_input_is_one_line_and_exit_code_2(argv, message, tmp_path, capsys):
    assert main(["synth", *argv, "--out", str(tmp_path / "out")]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1 and message in err[0]
