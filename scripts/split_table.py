"""Per-split table of one `pftrack eval` run on the development sequences (GUIDE §8 tune / report split).

    python scripts/split_table.py reports/bench-all/results.csv

Prints a Markdown table: per tracker, the mean OTB AUC over the tune sequences and over the
report sequences, the lost flag's recall and false-lost rate, and the median update fps over
all sequences with the ratio to OpenCV CSRT's median fps in the same run.  The defaults of
pftrack's trackers were chosen on the tune sequences only; the report column is the figure
that says how they do on video they were not selected on.
"""

from __future__ import annotations

import csv
import statistics
import sys
from collections import defaultdict

TUNE = ("otb_crossing", "otb_couple", "vot_bag", "otb_dragonbaby", "davis16_dog")
REPORT = ("otb_motorrolling", "tld_pedestrian2", "davis16_blackswan", "davis16_car-shadow")


def _mean(v):
    return sum(v) / len(v) if v else float("nan")


def main(path: str) -> None:
    with open(path, encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    cell = defaultdict(lambda: defaultdict(list))
    for r in rows:
        seq = r["sequence"]
        split = "tune" if seq in TUNE else "report" if seq in REPORT else None
        if split is None:
            continue
        c = cell[r["tracker"]]
        c[split].append(float(r["auc"]))
        for key in ("lost_recall", "false_lost"):
            if r.get(key) not in ("", None):
                c[key].append(float(r[key]))
        c["fps"].append(float(r["fps"]))
    csrt = statistics.median(cell["opencv-csrt"]["fps"]) if cell.get("opencv-csrt") else float("nan")
    order = sorted(cell, key=lambda t: -_mean(cell[t]["report"]))
    print("| tracker | tune AUC (5 seq.) | report AUC (4 seq.) | lost recall | false-lost | median fps | × CSRT |")
    print("|---|---|---|---|---|---|---|")
    for t in order:
        c = cell[t]
        fps = statistics.median(c["fps"])
        print(f"| `{t}` | {_mean(c['tune']):.3f} | {_mean(c['report']):.3f} | {_mean(c['lost_recall']):.3f} | "
              f"{_mean(c['false_lost']):.3f} | {fps:.0f} | {fps / csrt:.1f} |")


if __name__ == "__main__":
    main(sys.argv[1])
