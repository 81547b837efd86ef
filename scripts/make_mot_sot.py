"""Single-object sequences (OTB layout) from a MOTChallenge folder: one per person, for the SOT splits.

    python scripts/make_mot_sot.py ../shared/data/pets09_s2l1_dev --frames 1-200 --out reports/split/tune_pets
    python scripts/make_mot_sot.py ../shared/data/pets09_s2l1_dev --frames 201-400 --out reports/split/report_pets

GUIDE §8 puts the PETS frames 1-200 in the tune split and 201-400 in the report split. This turns each
half into small pedestrians among similar people, the case a colour tracker finds hardest, with real
absences: a person who walks out of the view has ``NaN`` ground truth from then on, as in TLD files.

The selection is fixed in advance and never looks at a tracker's result: every identity with at least
``--min-frames`` annotated frames in the range gives one sequence. It starts at the identity's first
annotated frame in the range and runs to the range's end, so the frames after the person has left are
absent frames. A gap inside a track (none in PETS S2.L1) is absent too. The frames are symbolic links to
the source images; ``ATTRIBUTION.md`` keeps the source's credit.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from pftrack.io.datasets import read_sequence


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
    gt = seq.mot_gt
    out = Path(args.out)
    stem = Path(args.mot).name.split("_")[0]
    made = []
    for pid in np.unique(gt[:, 1]).astype(int):
        rows = gt[(gt[:, 1] == pid) & (gt[:, 0] >= lo) & (gt[:, 0] <= hi)]
        if len(rows) < args.min_frames:
            continue
        first = int(rows[:, 0].min())
        name = f"{stem}_f{lo}-{hi}_id{pid}"
        dest = out / name
        (dest / "img").mkdir(parents=True, exist_ok=True)
        boxes = {int(r[0]): r[2:6] for r in rows}
        lines = []
        for k, number in enumerate(range(first, hi + 1)):
            link = dest / "img" / f"{k + 1:04d}{seq.frames[number - 1].suffix}"
            if link.is_symlink() or link.exists():
                link.unlink()
            os.symlink(os.path.relpath(seq.frames[number - 1].resolve(), link.parent), link)
            b = boxes.get(number)
            lines.append("NaN,NaN,NaN,NaN" if b is None else ",".join(f"{v:.2f}" for v in b))
        (dest / "groundtruth_rect.txt").write_text("\n".join(lines) + "\n", encoding="utf-8")
        (dest / "ATTRIBUTION.md").write_text(
            f"Person {pid} of {Path(args.mot).name}, frames {first}-{hi} (frame k of this folder is frame "
            f"{first} + k - 1 of the source). PETS 2009 benchmark data, University of Reading; ground truth: "
            "Anton Milan's annotations (milanton.de), converted to MOTChallenge format.\n", encoding="utf-8")
        made.append(f"{name} ({len(lines)} frames, {len(lines) - len(rows)} absent)")
    print(f"{len(made)} sequences -> {out}: " + ", ".join(made))


if __name__ == "__main__":
    main()
