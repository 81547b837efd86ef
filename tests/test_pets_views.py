"""scripts/make_pets_views.py: single-person sequences of a MOT recording seen through narrower views."""

import importlib.util
from pathlib import Path

import numpy as np

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "make_pets_views.py"


def _module():
    spec = importlib.util.spec_from_file_location("make_pets_views", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_windows_cover_the_four_sides():
    w = _module().windows(768, 576)
    assert w["left"] == (0, 0, 422, 576) and w["right"] == (346, 0, 422, 576)
    assert w["top"] == (0, 0, 768, 317) and w["bottom"] == (0, 259, 768, 317)


def test_a_walker_leaving_a_window_is_absent_once_mostly_out_and_unannotated_after_the_track_ends():
    mod = _module()
    # one person, 20 x 40 px, walking up 5 px a frame from y = 300 (frames 1-60); the MOT track ends at frame 60
    rows = [[f, 7, 100.0, 300.0 - 5.0 * (f - 1), 20.0, 40.0] for f in range(1, 61)]
    gt = np.array(rows)
    window = (0, 200, 400, 200)  # y 200..400: the walker leaves through its top edge
    (pid, frames, boxes, unannotated), = mod.person_views(gt, 1, 80, window, min_frames=10)
    assert pid == 7 and frames[0] == 1 and frames[-1] == 80
    assert np.allclose(boxes[0], [100.0, 100.0, 20.0, 40.0])  # window pixels
    # frame 21: top at y = 200 -> 0 in the window, whole box inside; frame 25: 20 px of 40 inside, clipped
    assert np.allclose(boxes[24], [100.0, 0.0, 20.0, 20.0])
    present = np.isfinite(boxes).all(axis=1)
    # present while at least 10 % (4 px) of the box is inside: the top at y <= 200 - 36 is the last, frame 28
    assert present[:28].all() and not present[28:].any()
    assert not unannotated[:60].any()   # annotated (out of the window): absent, not unannotated
    assert not unannotated[60:].any()   # after the track ends, moved on, the box stays out of the window


def test_a_track_that_ends_inside_the_window_leaves_unannotated_frames_and_a_late_start_is_skipped():
    mod = _module()
    gt = np.array([[f, 3, 50.0 + 2.0 * f, 60.0, 20.0, 40.0] for f in range(1, 41)])
    (_, _, boxes, unannotated), = mod.person_views(gt, 1, 60, (0, 0, 400, 200), min_frames=10)
    assert np.isfinite(boxes[:40]).all() and not np.isfinite(boxes[40:]).any()
    assert unannotated[40:].all()  # the walker, moved on at its speed, is still in view: neither absent nor scored
    # a person who is never 90 % inside before the range ends with fewer than min_frames inside gives nothing
    late = np.array([[f, 4, 395.0, 60.0, 20.0, 40.0] for f in range(1, 61)])
    assert mod.person_views(late, 1, 60, (0, 0, 400, 200), min_frames=10) == []
