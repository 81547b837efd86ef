"""Real exits and returns: single-person sequences of PETS 2009 S2.L1 seen through narrower views.

    python scripts/make_pets_views.py ../shared/data/pets09_s2l1_dev --frames 1-200 --out reports/views_tune
    python scripts/make_pets_views.py ../shared/data/pets09_s2l1_dev --frames 201-400 --out reports/views_report
    python scripts/make_pets_views.py reports/split/tune_real/otb_crossing --out reports/exits_tune

A single-target folder (OTB, VOT) works the same way, its target as identity 1 (``--frames`` defaults to all):
exits of one target from a less crowded scene. Its frames without a box are treated as PETS's (below): unscored
where the box before or after, moved on, would still be in the window.

The PETS view is wide, and few of its walkers leave it within a half (one in frames 1-200). Issue #14 asks for the
lost flag on a pedestrian who leaves the view, and for the re-acquisition of one who comes back. This script cuts
four fixed windows from the frames (the left and right 55 %, the top and bottom 55 %; fixed before any tracker was
run on them) and turns every person into one sequence per window in which they are seen, so walkers leave a window
and often come back into it, among other walkers in similar clothes, on real video:

* a sequence starts at the person's first frame in the range with at least 90 % of their box inside the window
  (and a box at least 16 px tall), and runs to the range's end;
* the ground truth is the box clipped to the window while at least 10 % of it is inside (the synthetic scenes'
  threshold for a present target), ``NaN`` (absent) when less is;
* frames on which PETS has no box for the person but the box before or after, moved on at its velocity, would still
  be 10 % inside the window are ``unannotated`` in ``meta.json`` (neither absent nor scored), written by the same
  :func:`pftrack.io.person_sequences.write_otb` as ``scripts/make_mot_sot.py``;
* a person needs at least ``--min-frames`` (30) frames inside the window from that start on.

Each window's frames are written once (JPEG, quality 95) beside ``--out``, in ``OUT_frames/``; the sequences
link to them.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np

from pftrack.geometry import in_frame_fraction
from pftrack.io.datasets import Sequence, read_sequence
from pftrack.io.person_sequences import IN_VIEW_FRACTION, PersonSequence, in_view_frames, write_otb

CREDIT = ("PETS 2009 benchmark data, University of Reading; ground truth: Anton Milan's annotations "
          "(milanton.de), converted to MOTChallenge format.")
START_FRACTION = 0.9  # the first box must be this much inside the window
MIN_HEIGHT = 16.0


def windows(width: int, height: int, share: float = 0.55) -> dict[str, tuple[int, int, int, int]]:
    """The four views ``x0, y0, w, h``: left, right, top and bottom ``share`` of the frame (55 %)."""
    w, h = int(round(share * width)), int(round(share * height))
    return {"left": (0, 0, w, height), "right": (width - w, 0, w, height),
            "top": (0, 0, width, h), "bottom": (0, height - h, width, h)}


def clip_box(b: np.ndarray, w: int, h: int) -> np.ndarray:
    x0, y0 = max(b[0], 0.0), max(b[1], 0.0)
    x1, y1 = min(b[0] + b[2], float(w)), min(b[1] + b[3], float(h))
    return np.array([x0, y0, x1 - x0, y1 - y0])


def person_views(gt: np.ndarray, first: int, last: int, window: tuple[int, int, int, int], min_frames: int):
    """``(identity, frames, boxes, unannotated)`` per person seen in ``window`` (frames 1-based, boxes in window
    pixels, ``NaN`` while absent)."""
    x0, y0, ww, wh = window
    out = []
    for pid in np.unique(gt[:, 1]).astype(int):
        rows = gt[(gt[:, 1] == pid) & (gt[:, 0] >= first) & (gt[:, 0] <= last)]
        if len(rows) == 0:
            continue
        rows = rows[np.argsort(rows[:, 0])]
        raw = np.full((last - first + 1, 4), np.nan)   # window pixels, unclipped, NaN where PETS has no box
        raw[rows[:, 0].astype(int) - first] = rows[:, 2:6] - np.array([x0, y0, 0.0, 0.0])
        frac = np.array([in_frame_fraction(tuple(b), ww, wh) if np.isfinite(b).all() else 0.0 for b in raw])
        inside = frac >= IN_VIEW_FRACTION
        if np.count_nonzero(inside) < min_frames:
            continue
        ok = np.flatnonzero((frac >= START_FRACTION) & (raw[:, 3] >= MIN_HEIGHT))
        if ok.size == 0:
            continue
        s = int(ok[0])
        if np.count_nonzero(inside[s:]) < min_frames:
            continue
        boxes = np.full((len(raw) - s, 4), np.nan)
        for k in range(s, len(raw)):
            if inside[k]:
                boxes[k - s] = clip_box(raw[k], ww, wh)
        unannotated = in_view_frames(raw[s:], ww, wh) & ~np.isfinite(raw[s:]).all(axis=1)
        out.append((pid, np.arange(first + s, last + 1), boxes, unannotated))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mot", help="a MOTChallenge sequence folder (img1/, gt/gt.txt), or a single-target one")
    ap.add_argument("--frames", help="frame range, 1-based and inclusive, e.g. 1-200 (default: all)")
    ap.add_argument("--min-frames", type=int, default=30)
    ap.add_argument("--share", type=float, default=0.55,
                    help="each window's share of the frame's width or height (0.55; other shares give other exits "
                         "from the same frames, named with the share)")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    if not 0.1 <= args.share < 1.0:
        ap.error("--share must be in [0.1, 1)")
    tag = "" if args.share == 0.55 else f"{int(round(100 * args.share))}"
    seq = read_sequence(args.mot)
    lo, hi = (int(v) for v in args.frames.split("-")) if args.frames else (1, len(seq.frames))
    hi = min(hi, len(seq.frames))
    first = cv2.imread(str(seq.frames[0]))
    out = Path(args.out)
    gt, stem = seq.mot_gt, Path(args.mot).name.split("_")[0]
    if gt is None:  # one target: its ground truth as identity 1, named after its folder
        if seq.groundtruth is None:
            ap.error(f"{args.mot}: no ground truth")
        ok = np.flatnonzero(np.isfinite(seq.groundtruth).all(axis=1))
        gt = np.column_stack([ok + 1.0, np.ones(ok.size), seq.groundtruth[ok]])
        stem = Path(args.mot).name
    made = []
    for name, win in windows(first.shape[1], first.shape[0], args.share).items():
        name += tag
        x0, y0, ww, wh = win
        frames_dir = out.with_name(out.name + "_frames") / f"{stem}_{name}_f{lo}-{hi}"
        frames_dir.mkdir(parents=True, exist_ok=True)
        for n in range(lo, hi + 1):
            dst = frames_dir / f"{n:06d}.jpg"
            if not dst.exists():
                img = cv2.imread(str(seq.frames[n - 1]))
                cv2.imwrite(str(dst), img[y0:y0 + wh, x0:x0 + ww], [cv2.IMWRITE_JPEG_QUALITY, 95])
        # the window's frames, indexed by source frame number as write_otb reads them (those before lo unused)
        crop = Sequence(name=seq.name, kind="frames", path=frames_dir,
                        frames=[frames_dir / f"{n:06d}.jpg" for n in range(1, hi + 1)])
        where = f"window x={x0}..{x0 + ww}, y={y0}..{y0 + wh}"
        for pid, numbers, boxes, unannotated in person_views(gt, lo, hi, win, args.min_frames):
            person = PersonSequence(pid, numbers, boxes, unannotated)
            credit = CREDIT if seq.mot_gt is not None else f"Source: {Path(args.mot).name}, under its own licence."
            dest = write_otb(crop, person, out / f"{stem}_{name}_f{lo}-{hi}_id{pid}",
                             credit=f"In the {where}. {credit}")
            made.append(f"{dest.name} ({len(numbers)} frames, {person.absent} absent)")
    print(f"{len(made)} sequences -> {out}:\n  " + "\n  ".join(made))


if __name__ == "__main__":
    main()
