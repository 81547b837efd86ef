"""Single-object sequences cut from a MOTChallenge annotation (pftrack.io.person_sequences)."""

from __future__ import annotations

import cv2
import numpy as np

from pftrack.io.datasets import read_sequence
from pftrack.io.person_sequences import person_sequences, write_otb

# frame, id, x, y, w, h, conf: person 1 on frames 1-4 (leaves), person 2 on 2-6 with frame 4 missing, person 3
# on frame 6 only
GT = np.array([
    [1, 1, 10, 10, 5, 8, 1], [2, 1, 12, 10, 5, 8, 1], [3, 1, 14, 10, 5, 8, 1], [4, 1, 16, 10, 5, 8, 1],
    [2, 2, 30, 5, 6, 9, 1], [3, 2, 29, 5, 6, 9, 1], [5, 2, 27, 5, 6, 9, 1], [6, 2, 26, 5, 6, 9, 1],
    [6, 3, 1, 1, 4, 4, 1],
], dtype=float)


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
    src = tmp_path / "mot"
    (src / "img1").mkdir(parents=True)
    (src / "gt").mkdir()
    for k in range(1, 7):
        cv2.imwrite(str(src / "img1" / f"{k:06d}.jpg"), np.full((40, 48, 3), 20 * k, np.uint8))
    np.savetxt(src / "gt" / "gt.txt", GT, delimiter=",", fmt="%g")
    (src / "seqinfo.ini").write_text("[Sequence]\nname=mot\nimDir=img1\nframeRate=7\nseqLength=6\n"
                                     "imWidth=48\nimHeight=40\nimExt=.jpg\n", encoding="utf-8")
    seq = read_sequence(src)
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
