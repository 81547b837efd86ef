"""Slivers refused at the frame's edge: are they the target, and what does the loss test say of them?

    python scripts/sliver_probe.py reports/split/tune_views reports/split/tune_exits --seeds 0,1 \
        --json reports/sliver_probe.json

Runs ``fusion-pf`` (``--param KEY=VALUE`` to change it) over the single-target sequences of each folder. On every
search frame whose best candidate passes the loss test, has enough supporting samples, and lies less than
``acquire_in_frame`` inside the frame, it records the fused log-likelihood ratio (with the position prior, as
the acquisition test computes it), the in-frame share, each cue's score as a z-score against the target's and the
background's history, and whether the candidate is the target (its box cut to the frame overlaps the ground truth
at IoU >= 0.3). It prints those figures' 10th, 50th and 90th percentiles for the target and for the rest, by
folder. Diagnosis only: it chooses nothing (``docs/rules/acquire_sliver_llr_rule.txt`` quotes its tune figures).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pftrack import create_tracker  # noqa: E402
from pftrack.cli.common import parse_seeds  # noqa: E402
from pftrack.geometry import ellipse_to_box, in_frame_fraction, iou, visible_box  # noqa: E402
from pftrack.io.datasets import read_sequence  # noqa: E402
from pftrack.params import parse_param_assignments  # noqa: E402


def probe_sequence(path: Path, seed: int, params: dict) -> list[dict]:
    """The refused slivers of one run of ``fusion-pf`` on the sequence at ``path``."""
    seq = read_sequence(path)
    frames = [cv2.imread(str(f), cv2.IMREAD_COLOR) for f in seq.frames]
    h, w = frames[0].shape[:2]
    gt = seq.groundtruth
    tracker = create_tracker("fusion-pf", seed=seed, params=params)
    cls = type(tracker)
    original = cls._choose
    found: list[dict] = []

    def choose(self, frame, c, supporters):
        p = self.params
        need = min(p.acquire_samples, p.kickoff_fraction * p.n_particles + 1)
        ok, llr = self.loss.would_acquire(c.s_best, c.lp)
        box = ellipse_to_box(c.ell[c.best])
        inside = in_frame_fraction(tuple(box), w, h)
        if ok and (c.near & supporters).sum() >= need and inside < p.acquire_in_frame:
            g = gt[self.frame_index]
            present = bool(np.all(np.isfinite(g)))
            seen = visible_box(tuple(box), w, h) or tuple(box)  # the part inside the frame
            overlap = float(iou(seen, tuple(g))) if present else 0.0
            s = np.asarray(c.s_best, dtype=float)
            m = self.loss.members
            found.append({
                "sequence": path.name, "seed": seed, "frame": int(self.frame_index), "llr": float(llr),
                "inside": float(inside), "scores": s.tolist(),
                "z_target": [float((s[k] - m[k].mu_t) / max(m[k].sd_t, 1e-9)) for k in range(len(m))],
                "z_background": [float((s[k] - m[k].mu_b) / max(m[k].sd_b, 1e-9)) for k in range(len(m))],
                "iou": overlap, "target": overlap >= 0.3})
        return original(self, frame, c, supporters)

    cls._choose = choose
    try:
        tracker.init(frames[0], tuple(gt[0]))
        for f in frames[1:]:
            tracker.update(f)
    finally:
        cls._choose = original
    return found


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+", type=Path, help="folders of single-target sequences (OTB layout)")
    ap.add_argument("--seeds", default="0,1")
    ap.add_argument("--param", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--json", type=Path, help="write every record here")
    args = ap.parse_args(argv)
    params = parse_param_assignments(args.param)
    seeds = parse_seeds(args.seeds)
    records = []
    for folder in args.folders:
        rows = []
        for path in sorted(p for p in folder.iterdir() if p.is_dir()):
            for seed in seeds:
                rows.extend(probe_sequence(path, seed, params))
        records.extend(rows)
        print(f"{folder}: {len(rows)} refused slivers")
        for label, group in (("target", [r for r in rows if r["target"]]),
                             ("other", [r for r in rows if not r["target"]])):
            if not group:
                continue
            a = np.array([[r["llr"], r["inside"], *r["z_target"], *r["z_background"]] for r in group])
            q = np.percentile(a, [10, 50, 90], axis=0)
            print(f"  {label} ({len(group)}): fused ratio {q[0, 0]:.1f} / {q[1, 0]:.1f} / {q[2, 0]:.1f}, "
                  f"in frame {q[0, 1]:.2f} / {q[1, 1]:.2f} / {q[2, 1]:.2f} (p10 / p50 / p90)")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(records))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
