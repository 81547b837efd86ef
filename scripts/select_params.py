"""Select a tracker's parameters by leave-one-sequence-out (LOSO) cross-validation.

Usage (from the repository root)::

    python scripts/select_params.py DATA... --tracker fusion-pf --grid "contrast_gain=10,20" \\
        --grid "contrast_alpha=0.02,0.05" --seeds 3 --report reports/fusion-grid --out docs/fusion-pf-selection.md

Every combination of the grid values is run on every sequence (OTB one-pass,
``--seeds`` seeds, cached in ``--report`` so an interrupted run resumes).  For each
sequence in turn, the combination with the best mean AUC on the *other* sequences
is chosen and its AUC on the held-out sequence recorded: the mean of those
held-out AUCs estimates how the selection procedure does on a sequence it has
not seen.  The final choice is the combination with the best mean AUC on all
sequences.  Nothing is tuned per sequence.
"""

from __future__ import annotations

import argparse
import itertools
import os
import sys
from collections import defaultdict

import numpy as np

from pftrack.eval.runner import Runner, TrackerConfig, build_jobs
from pftrack.io.datasets import discover_sequences


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("data", nargs="+")
    ap.add_argument("--tracker", required=True)
    ap.add_argument("--grid", action="append", default=[], help="KEY=V1,V2,... (repeatable)")
    ap.add_argument("--fixed", action="append", default=[], help="KEY=VALUE applied to every combination")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--report", required=True)
    ap.add_argument("--out", help="write the Markdown result here")
    args = ap.parse_args(argv)

    keys, values = [], []
    for g in args.grid:
        k, v = g.split("=", 1)
        keys.append(k)
        values.append([x for x in v.split(",") if x])
    fixed = [tuple(f.split("=", 1)) for f in args.fixed]
    combos = [tuple(zip(keys, vals)) for vals in itertools.product(*values)] or [()]
    configs = []
    for combo in combos:
        params = tuple(fixed) + tuple(combo)
        label = args.tracker + ("[" + ";".join(f"{k}={v}" for k, v in params) + "]" if params else "")
        configs.append(TrackerConfig(label, args.tracker, params))
    seqs = [s for d in args.data for s in discover_sequences(d) if s.groundtruth is not None]
    jobs = build_jobs(seqs, configs, seeds=args.seeds, protocol="ope")
    records = Runner(report_dir=args.report, workers=args.workers, progress=True).run(jobs)

    auc: dict[tuple[str, str], list[float]] = defaultdict(list)
    for r in records:
        auc[(r["tracker"], r["sequence"])].append(r["auc"])
    names = [s.name for s in seqs]
    labels = [c.label for c in configs]
    table = np.array([[np.mean(auc[(c, s)]) for s in names] for c in labels])  # configs x sequences

    lines = [f"# Parameter selection for `{args.tracker}` (leave-one-sequence-out)", "",
             "Command:", "", "```", "python scripts/select_params.py " + " ".join(sys.argv[1:]), "```", "",
             f"{len(labels)} combinations x {len(names)} sequences x {args.seeds} seeds (OTB one-pass AUC, mean "
             "over seeds).", "", "## Held-out results", "",
             "| held-out sequence | chosen on the other sequences | held-out AUC | best possible on it |",
             "|---|---|---|---|"]
    held = []
    for j, s in enumerate(names):
        others = np.delete(table, j, axis=1).mean(axis=1)
        i = int(np.argmax(others))
        held.append(table[i, j])
        lines.append(f"| {s} | `{labels[i]}` | {table[i, j]:.3f} | {table[:, j].max():.3f} |")
    lines += ["", f"**LOSO estimate of the AUC on an unseen sequence: {np.mean(held):.3f}** "
                  f"(mean of the held-out AUCs).", ""]
    best = int(np.argmax(table.mean(axis=1)))
    lines += ["## All combinations (mean AUC over sequences)", "",
              "| combination | mean AUC | " + " | ".join(names) + " |", "|" + "---|" * (len(names) + 2)]
    for i in np.argsort(-table.mean(axis=1)):
        mark = " **(chosen)**" if i == best else ""
        lines.append(f"| `{labels[i]}`{mark} | {table[i].mean():.3f} | "
                     + " | ".join(f"{v:.3f}" for v in table[i]) + " |")
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        with open(args.out, "w", encoding="utf-8") as fh:
            fh.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
