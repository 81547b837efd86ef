"""Single-object sequences (OTB layout) from a MOTChallenge folder: one per person, for the SOT splits.

    python scripts/make_mot_sot.py ../shared/data/pets09_s2l1_dev --frames 1-200 --out reports/split/tune_pets
    python scripts/make_mot_sot.py ../shared/data/pets09_s2l1_dev --frames 201-400 --out reports/split/report_pets

GUIDE §8 puts the PETS frames 1-200 in the tune split and 201-400 in the report split. This turns each
half into small pedestrians among similar people, the case a colour tracker finds hardest, with real
absences: a person who walks out of the view has ``NaN`` ground truth from then on, as in TLD files.

The selection is fixed in advance and never looks at a tracker's result: every identity with at least
``--min-frames`` annotated frames in the range gives one sequence (pftrack.io.person_sequences). It starts
at the identity's first annotated frame in the range and runs to the range's end, so the frames after the
person has left are absent frames, except those on which the person is still (partly) in view: a PETS track
ends as the walker reaches the border, and those frames are listed as ``unannotated`` in ``meta.json``
(neither absent nor scored). The frames are symbolic links to the source images.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2

from pftrack.io.datasets import read_sequence
from pftrack.io.person_sequences import person_sequences, write_otb

PETS_CREDIT = ("PETS 2009 benchmark data, University of Reading; ground truth: Anton Milan's annotations "
               "(milanton.de), converted to MOTChallenge format.")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mot", help="a MOTChallenge sequence folder (img1/, gt/gt.txt)")
    ap.add_argument("--frames", required=True, help="frame range, 1-based and inclusive, e.g. 1-200")
    ap.add_argument("--min-frames", type=int, default=30, help="fewest annotated frames of a person in the range")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    seq = read_sequence(args.mot)
    if seq.mot_gt is None or len(seq.mot_gt) == 0:
        raise SystemExit(f"{args.mot}: no MOT ground truth")
    lo, hi = (int(v) for v in args.frames.split("-"))
    hi = min(hi, len(seq.frames))
    stem = Path(args.mot).name.split("_")[0]
    credit = PETS_CREDIT if stem.startswith("pets") else ""
    made = []
    first = cv2.imread(str(seq.frames[0]))
    if first is None:
        raise SystemExit(f"{seq.frames[0]}: unreadable frame")
    size = (first.shape[1], first.shape[0])
    for person in person_sequences(seq.mot_gt, lo, hi, min_frames=args.min_frames, frame_size=size):
        name = f"{stem}_f{lo}-{hi}_id{person.identity}"
        write_otb(seq, person, Path(args.out) / name, credit=credit)
        unannotated = int(person.in_view.sum()) if person.in_view is not None else 0
        made.append(f"{name} ({len(person.frames)} frames, {person.absent} absent, {unannotated} in view unannotated)")
    print(f"{len(made)} sequences -> {args.out}: " + ", ".join(made))


if __name__ == "__main__":
    main()
