"""Single-object sequences cut from a MOTChallenge annotation (pftrack.io.person_sequences)."""

from __future__ import annotations

import cv2
import numpy as np

from pftrack.io.datasets import read_sequence
from pftrack.io.person_sequences import in_view_frames, person_sequences, write_otb

# frame, id, x, y, w, h, conf: person 1 on frames 1-4 (leaves), person 2 on 2-6 with frame 4 missing, person 3
# on frame 6 only
GT = np.array([
    [1, 1, 10, 10, 5, 8, 1], [2, 1, 12, 10, 5, 8, 1], [3, 1, 14, 10, 5, 8, 1], [4, 1, 16, 10, 5, 8, 1],
    [2, 2, 30, 5, 6, 9, 1], [3, 2, 29, 5, 6, 9, 1], [5, 2, 27, 5, 6, 9, 1], [6, 2, 26, 5, 6, 9, 1],
    [6, 3, 1, 1, 4, 4, 1],
], dtype=float)


def _mot_folder(tmp_path, gt: np.ndarray, n: int):
    """A MOTChallenge folder of ``n`` 48 x 40 frames with the annotation ``gt``."""
    src = tmp_path / "mot"
    (src / "img1").mkdir(parents=True)
    (src / "gt").mkdir()
    for k in range(1, n + 1):
        cv2.imwrite(str(src / "img1" / f"{k:06d}.jpg"), np.full((40, 48, 3), 20 * k, np.uint8))
    np.savetxt(src / "gt" / "gt.txt", gt, delimiter=",", fmt="%g")
    (src / "seqinfo.ini").write_text(f"[Sequence]\nname=mot\nimDir=img1\nframeRate=7\nseqLength={n}\n"
                                     "imWidth=48\nimHeight=40\nimExt=.jpg\n", encoding="utf-8")
    return src


def test_person_sequences_run_from_the_first_frame_to_the_range_end_with_absences():
    people = person_sequences(GT, 1, 6, min_frames=2)
    assert [p.identity for p in people] == [1, 2]  # person 3 has one frame
    one, two = people
    assert one.frames.tolist() == [1, 2, 3, 4, 5, 6]
    np.testing.assert_array_equal(one.boxes[3], [16, 10, 5, 8])
    assert np.isnan(one.boxes[4:]).all() and one.absent == 2  # walked out after frame 4
    assert two.frames.tolist() == [2, 3, 4, 5, 6]
    assert np.isnan(two.boxes[2]).all() and two.absent == 1  # a gap inside the track is absent too
    # a range that cuts the tracks: person 1 keeps frames 3-4 and is absent on 5
    cut = person_sequences(GT, 3, 5, min_frames=2)
    assert [(p.identity, p.frames.tolist(), p.absent) for p in cut] == [(1, [3, 4, 5], 1), (2, [3, 4, 5], 1)]
    assert person_sequences(GT, 1, 6, min_frames=5) == []


def test_write_otb_gives_a_sequence_pftrack_reads(tmp_path):
    seq = read_sequence(_mot_folder(tmp_path, GT, 6))
    person = person_sequences(seq.mot_gt, 1, 6, min_frames=2)[1]
    out = write_otb(seq, person, tmp_path / "otb" / "id2", credit="test data")
    sot = read_sequence(out)
    assert len(sot.frames) == 5
    assert all(p.is_symlink() for p in sot.frames)
    # frame k of the folder is source frame 2 + k - 1
    assert cv2.imread(str(sot.frames[0]))[0, 0, 0] == cv2.imread(str(seq.frames[1]))[0, 0, 0]
    gt = sot.groundtruth
    np.testing.assert_allclose(gt[0], [30, 5, 6, 9])
    assert np.isnan(gt[2]).all()
    assert "source frames 2-6" in (out / "ATTRIBUTION.md").read_text(encoding="utf-8")


def test_frames_without_a_box_while_the_person_is_still_in_view():
    """A track that ends at the border (PETS): moved on at its last velocity, the box keeps >= 10 % of its area
    in the 48 px wide image for a while; those frames are in view, the later ones absent."""
    boxes = np.full((12, 4), np.nan)
    boxes[:4] = [[30, 10, 6, 8], [32, 10, 6, 8], [34, 10, 6, 8], [36, 10, 6, 8]]  # 2 px per frame, right edge at 42
    view = in_view_frames(boxes, 48, 40)
    # frame k (k >= 4) puts the box at x = 36 + 2 (k - 3): in frame while x < 48 - 0.6 = 47.4, i.e. up to k = 8
    assert view.tolist() == [False] * 4 + [True] * 5 + [False] * 3
    # a gap inside the track is covered from both ends; a box that stands still stays in view
    still = np.full((6, 4), np.nan)
    still[:2] = still[5] = [20, 10, 6, 8]
    assert in_view_frames(still, 48, 40).tolist() == [False, False, True, True, True, False]
    # entering: the frames before the first box, moved back at the first velocity
    enter = np.full((5, 4), np.nan)
    enter[3:] = [[2, 10, 6, 8], [5, 10, 6, 8]]
    assert in_view_frames(enter, 48, 40).tolist() == [False, True, True, False, False]
    assert not in_view_frames(np.full((3, 4), np.nan), 48, 40).any()


def test_in_view_frames_are_written_as_unannotated_and_not_scored_as_absent(tmp_path):
    # one walker leaving through the right edge at 4 px per frame, annotated until its box's right side is at x = 40
    gt = np.array([[k, 5, 24 + 4 * (k - 1), 10, 8, 10, 1] for k in range(1, 4)] +
                  [[k, 6, 5, 20, 6, 8, 1] for k in range(1, 9)], dtype=float)
    seq = read_sequence(_mot_folder(tmp_path, gt, 8))
    person = person_sequences(seq.mot_gt, 1, 8, min_frames=2, frame_size=(48, 40))[0]
    assert person.identity == 5 and person.in_view.tolist() == [False] * 3 + [True] * 3 + [False] * 2
    assert person.absent == 2
    out = write_otb(seq, person, tmp_path / "otb" / "id5")
    sot = read_sequence(out)
    assert np.isnan(sot.groundtruth[3:]).all()
    assert sot.absent.tolist() == [False] * 6 + [True] * 2


def test_a_malformed_unannotated_list_is_a_format_error(tmp_path):
    import json

    import pytest

    from pftrack.errors import FormatError

    folder = tmp_path / "s"
    (folder / "img").mkdir(parents=True)
    for k in range(1, 4):
        cv2.imwrite(str(folder / "img" / f"{k:04d}.jpg"), np.zeros((8, 8, 3), np.uint8))
    (folder / "groundtruth_rect.txt").write_text("1,1,4,4\nNaN,NaN,NaN,NaN\nNaN,NaN,NaN,NaN\n", encoding="utf-8")
    (folder / "meta.json").write_text(json.dumps({"unannotated": [2]}), encoding="utf-8")
    assert read_sequence(folder).absent.tolist() == [False, False, True]
    (folder / "meta.json").write_text(json.dumps({"unannotated": ["2"]}), encoding="utf-8")
    with pytest.raises(FormatError, match="unannotated"):
        read_sequence(folder)
