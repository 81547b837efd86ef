"""How a tracker holds the size of a perturbed first box (OTB's SRE starts; docs/results.md, "A first box drawn off
the target").

For each sequence, tracker and start (``-1``: the ground-truth box; 0-11: the perturbations of
:func:`pftrack.eval.jobs.perturbed_box`, 8-11 the scales 0.8, 0.9, 1.1, 1.2) it prints the tracked box's side
relative to the target's (the square root of the area ratio) at the 5th, 20th and 50th tracked frame and the last,
its median over the frames where the target is annotated, and the mean IoU.

    python scripts/sre_size.py reports/split/tune_real/otb_crossing reports/split/tune_real/otb_couple \\
        --trackers fusion-pf,color-pf,opencv-csrt --starts -1,8,11
"""

from __future__ import annotations

import argparse

import numpy as np

from pftrack.geometry import iou


def size_run(frames, gt: np.ndarray, tracker: str, start: int) -> tuple[np.ndarray, float]:
    """The tracked side over the target's on every annotated frame after the first, and the mean IoU there, from
    the ground-truth box (``start`` -1) or SRE perturbation ``start`` (the run's seed, as ``pftrack eval``)."""
    import pftrack
    from pftrack.eval.jobs import perturbed_box

    h, w = frames[0].shape[:2]
    box = tuple(float(v) for v in gt[0]) if start < 0 else perturbed_box(gt[0], start, (w, h))
    t = pftrack.create_tracker(tracker, seed=max(start, 0))
    t.init(frames[0], box)
    ratios, ious = [], []
    for frame, g in zip(frames[1:], gt[1:]):
        st = t.update(frame)
        if np.all(np.isfinite(g)) and g[2] > 0 and g[3] > 0:
            ratios.append(np.sqrt(st.box[2] * st.box[3] / (g[2] * g[3])))
            ious.append(float(iou(st.box, g)))
    return np.asarray(ratios), float(np.mean(ious)) if ious else float("nan")


def main(argv=None) -> int:
    from pftrack.io.sources import open_source

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sequences", nargs="+", help="OTB-style sequence folders (the first box must be annotated)")
    ap.add_argument("--trackers", default="fusion-pf,color-pf,opencv-csrt")
    ap.add_argument("--starts", default="-1,8,11", help="comma-separated: -1 the ground truth, 0-11 SRE's boxes")
    args = ap.parse_args(argv)
    starts = [int(k) for k in args.starts.split(",")]
    for path in args.sequences:
        src = open_source(path)
        frames = [f for _, f in src.numbered()]
        gt = np.asarray(src.sequence.groundtruth, dtype=float)
        for k in starts:
            for name in args.trackers.split(","):
                r, m = size_run(frames, gt, name, k)
                at = " ".join(f"{r[min(j, len(r) - 1)]:.2f}" for j in (4, 19, 49, len(r) - 1)) if len(r) else "-"
                print(f"{src.name.rstrip('/').split('/')[-1]:18s} start {k:2d} {name:12s} side ratio at 5/20/50/end: "
                      f"{at}  median {np.median(r) if len(r) else float('nan'):.2f}  mean IoU {m:.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
