"""What a right box size is worth to ``cotrain-pf``: runs with the ground-truth size put into the box and the
particles after every frame (the position stays the filter's), against plain runs.

    python scripts/cotrain_size_oracle.py reports/split/tune_real/* reports/split/tune_pets/* --seeds 3

Prints per sequence the mean over seeds of the success AUC (IoU thresholds 0, 0.05, ..., 1) without and
with the size oracle. A diagnostic (docs/cotrain.md, "The size"), not a tracker.
"""

from __future__ import annotations

import argparse

import numpy as np

from pftrack.eval.metrics import success_curve
from pftrack.frames import as_bgr_uint8
from pftrack.geometry import iou
from pftrack.io.datasets import read_sequence
from pftrack.io.sources import read_image
from pftrack.trackers.registry import create_tracker


def run(frames, gt, box0, seed: int, oracle: bool) -> float:
    t = create_tracker("cotrain-pf", seed=seed)
    t.init(frames[0], box0)
    ious = []
    for k in range(1, len(frames)):
        s = t.update(frames[k])
        g = gt[k]
        if not np.all(np.isfinite(g)):
            continue
        ious.append(float(iou(np.array(s.box), g)))
        if oracle:  # the true size (the first box's aspect), at the filter's centre
            sc = np.sqrt(g[2] * g[3] / (t.size0[0] * t.size0[1]))
            t.particles[:, 2] = sc
            x, y, w, h = t.box
            w2, h2 = t.size0[0] * sc, t.size0[1] * sc
            t.box = (x + w / 2 - w2 / 2, y + h / 2 - h2 / 2, w2, h2)
    return float(np.mean(success_curve(np.array(ious))))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sequences", nargs="+")
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()
    rows = []
    for spec in args.sequences:
        seq = read_sequence(spec)
        i0 = seq.init_index
        frames = [as_bgr_uint8(read_image(f)) for f in seq.frames[i0:]]
        gt = seq.groundtruth[i0:]
        plain = np.mean([run(frames, gt, seq.init_box, s, False) for s in range(args.seeds)])
        orac = np.mean([run(frames, gt, seq.init_box, s, True) for s in range(args.seeds)])
        rows.append((plain, orac))
        print(f"{seq.name:28s} {plain:.3f} -> {orac:.3f}", flush=True)
    r = np.array(rows)
    print(f"{'mean':28s} {r[:, 0].mean():.3f} -> {r[:, 1].mean():.3f}")


if __name__ == "__main__":
    main()
