"""scripts/make_pets_views.py: single-person sequences of a MOT recording (or a single-target sequence) seen through
narrower views."""

import numpy as np

from .conftest import load_script


def _module():
    return load_script("make_pets_views")


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


def test_a_single_target_folder_is_cut_into_windows_with_its_exits(tmp_path, monkeypatch):
    """An OTB folder works as identity 1: a 20 x 40 target walks right at 5 px a frame across a 200 x 100 view; in
    the left window (110 px wide) it is present while 10 % of its box is inside and absent after, and the windows'
    frames are the crops."""
    import cv2
    import sys

    src = tmp_path / "toy_walk"
    (src / "img").mkdir(parents=True)
    boxes = []
    for f in range(40):
        img = np.full((100, 200, 3), 90, np.uint8)
        x = 10.0 + 5.0 * f
        img[30:70, int(x):int(x) + 20] = (20, 40, 200)
        cv2.imwrite(str(src / "img" / f"{f + 1:04d}.png"), img)
        boxes.append(f"{x},30,20,40")
    (src / "groundtruth_rect.txt").write_text("\n".join(boxes) + "\n")
    out = tmp_path / "exits"
    monkeypatch.setattr(sys, "argv", ["make_pets_views.py", str(src), "--out", str(out), "--min-frames", "5"])
    _module().main()
    left = out / "toy_walk_left_f1-40_id1"
    gt = np.genfromtxt(left / "groundtruth_rect.txt", delimiter=",")
    assert gt.shape == (40, 4)
    # frame k (0-based) spans x = 10 + 5k .. 30 + 5k: 5 px of 20 inside the 110 px window at k = 19, none at 20
    present = np.isfinite(gt).all(axis=1)
    assert present[:20].all() and not present[20:].any()
    assert np.allclose(gt[19], [105.0, 30.0, 5.0, 40.0])  # clipped to the window
    crop = cv2.imread(str(sorted((left / "img").iterdir())[0]))
    assert crop.shape[:2] == (100, 110)
    target = crop[40, 12:28].astype(int) - np.array([20, 40, 200])  # the target in the first crop (JPEG, q 95)
    assert np.abs(target).max() <= 12
    assert "toy_walk" in (left / "ATTRIBUTION.md").read_text() and "PETS" not in (left / "ATTRIBUTION.md").read_text()
