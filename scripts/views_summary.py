"""The lost flag on the PETS views, pooled over their absent frames, from a ``pftrack eval`` results.csv.

    pftrack eval reports/views_tune/* reports/views_tune_more/* --trackers fusion-pf,color-pf --seeds 3 \
        --report reports/views_eval
    python scripts/views_summary.py reports/views_eval/results.csv

The views (``scripts/make_pets_views.py``) are single-person sequences in which the person leaves a window and
often comes back. ``pftrack eval`` gives each run's lost recall (the share of its absent frames with the flag up)
and the mean of those over runs. A run with 5 absent frames then weighs as much as one with 150, so the figures of
docs/robustness.md pool instead: the flag-up frames over all absent frames of all runs, for each tracker, and for
the windows of each share (``_left_`` is a 55 % window, the default of make_pets_views; ``_left40_`` a 40 % one).
Also the mean AUC over runs and the reappearances re-acquired within 15 frames.
"""

from __future__ import annotations

import argparse
import csv
import re
from collections import defaultdict

_SHARE = re.compile(r"_(?:left|right|top|bottom)(\d*)_f")


def share_of(sequence: str) -> str:
    """The window share of a view's name, in percent (``"55"`` when not named); ``"other"`` for other names."""
    m = _SHARE.search(sequence)
    if m is None:
        return "other"
    return m.group(1) or "55"


def _float(value: str | None) -> float | None:
    return None if value in (None, "") else float(value)


def pooled(rows: list[dict]) -> dict[str, dict]:
    """Per tracker: ``recall`` (pooled), ``absent`` frames, ``by_share`` (share -> (recall, absent)), ``auc``
    (mean over runs), ``runs``, ``reacquired`` and ``reappearances``. Runs with an error are left out."""
    acc: dict[str, dict] = defaultdict(lambda: {"up": 0.0, "absent": 0, "shares": defaultdict(lambda: [0.0, 0]),
                                                "auc": [], "reacquired": 0, "reappearances": 0})
    for r in rows:
        if r.get("error"):
            continue
        a = acc[r["tracker"]]
        auc = _float(r.get("auc"))
        if auc is not None:
            a["auc"].append(auc)
        absent, recall = _float(r.get("absent_frames")), _float(r.get("lost_recall"))
        if absent and recall is not None:
            n = round(absent)
            a["up"] += recall * n
            a["absent"] += n
            s = a["shares"][share_of(r["sequence"])]
            s[0] += recall * n
            s[1] += n
        a["reacquired"] += int(_float(r.get("reacquired")) or 0)
        a["reappearances"] += int(_float(r.get("reappearances")) or 0)
    out = {}
    for tracker, a in acc.items():
        out[tracker] = {
            "recall": a["up"] / a["absent"] if a["absent"] else float("nan"),
            "absent": a["absent"],
            "by_share": {k: (v[0] / v[1], v[1]) for k, v in sorted(a["shares"].items()) if v[1]},
            "auc": sum(a["auc"]) / len(a["auc"]) if a["auc"] else float("nan"),
            "runs": len(a["auc"]),
            "reacquired": a["reacquired"],
            "reappearances": a["reappearances"],
        }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results", help="results.csv of a pftrack eval run over view folders")
    args = ap.parse_args()
    with open(args.results, newline="") as f:
        rows = list(csv.DictReader(f))
    table = pooled(rows)
    shares = sorted({s for t in table.values() for s in t["by_share"]})
    head = f"{'tracker':40s} {'pooled':>7s} " + " ".join(f"{s + ' %' if s != 'other' else s:>8s}" for s in shares)
    print(head + f" {'absent':>7s} {'AUC':>6s} {'runs':>5s}  re-acquired")
    for tracker, t in table.items():
        cells = " ".join(f"{t['by_share'][s][0]:8.3f}" if s in t["by_share"] else f"{'':8s}" for s in shares)
        print(f"{tracker:40s} {t['recall']:7.3f} {cells} {t['absent']:7d} {t['auc']:6.3f} {t['runs']:5d}  "
              f"{t['reacquired']} / {t['reappearances']}")


if __name__ == "__main__":
    main()
