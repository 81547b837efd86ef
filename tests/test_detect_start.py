"""Starting a tracker from a detector instead of a box: ``track_source(..., detect=True)`` and ``pftrack track
--detect``, for a camera or stream where no box is known beforehand."""

from __future__ import annotations

import csv

import numpy as np
import pytest

import pftrack
from pftrack.cli import main
from pftrack.geometry import iou
from pftrack.io import open_source
from pftrack.pipeline import track_source
from pftrack.synth import simple_scene
from pftrack.synth.scenes import export_otb


@pytest.fixture(scope="module")
def scene_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("detect") / "simple"
    export_otb(simple_scene(0, n_frames=50), out)
    return out


def test_track_source_waits_for_the_first_detection_and_starts_on_it(scene_dir):
    src = open_source(scene_dir)
    gt = np.asarray(src.sequence.groundtruth, float)
    seen = []

    def detector(frame):  # nothing on the first four frames, then the true box
        seen.append(1)
        k = len(seen)
        return [] if k <= 4 else [[*gt[k - 1], 1.0]]

    tracker = pftrack.create_tracker("color-pf", seed=0, detector=detector)
    states = [st for _, _, st in track_source(src, tracker, detect=True)]
    assert len(states) == 50
    assert all(st.lost for st in states[:4]) and not states[4].lost
    assert np.allclose(states[4].box, gt[4])
    assert np.mean([iou(st.box, g) for st, g in zip(states[5:], gt[5:])]) > 0.7


def test_track_detect_starts_on_a_moving_object(scene_dir, tmp_path, capsys):
    out = tmp_path / "t.csv"
    argv = ["track", str(scene_dir), "--detect", "mog2", "--tracker", "color-pf", "--quiet", "--out", str(out)]
    assert main(argv) == 0
    with out.open() as fh:
        rows = list(csv.DictReader(fh))
    gt = np.asarray(open_source(scene_dir).sequence.groundtruth, float)
    assert len(rows) == 50 and rows[0]["lost"] == "1"
    found = [r for r in rows if r["lost"] == "0"]
    assert found and int(found[0]["frame"]) < 40  # MOG2 learns the background for a few frames first
    first = int(found[0]["frame"])
    ious = [iou([float(r[k]) for k in "xywh"], gt[int(r["frame"]) - 1]) for r in rows[first - 1:]]
    assert np.mean(ious) > 0.4 and min(ious) > 0.2   # on the target from the detection on


@pytest.mark.parametrize("argv, said", [
    (["--detect", "mog2", "--box", "1,2,3,4"], "--detect starts from a detection"),
    (["--detect", "hog", "--tracker", "opencv-csrt"], "cannot start from a detector"),
])
def test_detect_refuses_a_box_and_trackers_without_a_detector(scene_dir, tmp_path, capsys, argv, said):
    out = tmp_path / "t.csv"
    assert main(["track", str(scene_dir), *argv, "--quiet", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and said in err[0] and not out.exists()
