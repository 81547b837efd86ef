"""Per kind and per nuisance: the figures of a ``pftrack eval`` run over the photo scenes (docs/robustness.md,
"A second scene family, cut from photographs").

Usage: python scripts/photo_summary.py REPORT_DIR SCENE_DIR [SCENE_DIR ...]

REPORT_DIR holds the run's ``results.csv``; each SCENE_DIR holds scene folders written by ``pftrack synth photo-vanish``
or ``photo-leave`` (their ``meta.json`` says what was drawn). Prints, per tracker:
- per kind: the mean AUC, lost recall and false-lost rate (means over scenes of the means over run seeds) and the
  reappearances re-acquired within 15 frames (summed over runs);
- per nuisance, with and without it: re-acquired and mean AUC (means over runs).
"""

from __future__ import annotations

import csv
import json
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

#: name -> test on a scene's meta.json
NUISANCES = {
    "lamp": lambda m: bool(m["nuisances"]["lamp"]),
    "grey": lambda m: bool(m["gray"]),
    "two or three look-alikes": lambda m: m["nuisances"]["lookalikes"] >= 2,
    "a channel's gain above 1.3": lambda m: max(m["nuisances"]["gain_end"]) > 1.3,
    "a channel's gain below 0.7": lambda m: min(m["nuisances"]["gain_end"]) < 0.7,
    "JPEG": lambda m: m["nuisances"]["jpeg"] > 0,
}


def _num(v: str) -> float:
    return float(v) if v not in ("", None) else float("nan")


def _count(runs: list[dict], key: str) -> int:
    """The sum of an integer column over runs (empty cells count 0)."""
    return sum(int(float(r[key])) for r in runs if r[key] not in ("", None))


def main(argv: list[str]) -> int:
    if len(argv) < 2:
        print(next(line for line in __doc__.splitlines() if line.startswith("Usage")), file=sys.stderr)
        return 2
    rows = list(csv.DictReader(open(Path(argv[0]) / "results.csv", encoding="utf-8")))
    metas = {m.parent.name: json.loads(m.read_text(encoding="utf-8"))
             for d in argv[1:] for m in Path(d).glob("*/meta.json")}
    rows = [r for r in rows if r["sequence"] in metas]
    if not rows:
        print("no run of the results is a scene of the folders given", file=sys.stderr)
        return 2
    for tracker in sorted({r["tracker"] for r in rows}):
        mine = [r for r in rows if r["tracker"] == tracker]
        print(tracker)
        for kind in sorted({metas[r["sequence"]]["kind"] for r in mine}):
            runs = [r for r in mine if metas[r["sequence"]]["kind"] == kind]
            by_seq = defaultdict(list)
            for r in runs:
                by_seq[r["sequence"]].append(r)

            def scene_mean(key: str) -> float:
                return float(np.nanmean([np.nanmean([_num(r[key]) for r in v]) for v in by_seq.values()]))

            print(f"  {kind:13s} AUC {scene_mean('auc'):.3f}, lost recall {scene_mean('lost_recall'):.3f}, "
                  f"false-lost {scene_mean('false_lost'):.3f}, re-acquired {_count(runs, 'reacquired')} of "
                  f"{_count(runs, 'reappearances')} ({len(by_seq)} scenes)")
        for name, test in NUISANCES.items():
            parts = []
            for has in (True, False):
                runs = [r for r in mine if test(metas[r["sequence"]]) == has]
                auc = np.mean([_num(r["auc"]) for r in runs]) if runs else float("nan")
                parts.append(f"{'with' if has else 'without'}: re-acquired {_count(runs, 'reacquired')} of "
                             f"{_count(runs, 'reappearances')}, AUC {auc:.3f} ({len(runs)} runs)")
            print(f"  {name:27s} " + "; ".join(parts))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
