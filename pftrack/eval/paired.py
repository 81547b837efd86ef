"""Paired differences of AUC between trackers, sequence by sequence.

A mean AUC over a set of sequences says which tracker scored more; it does not say whether the gap is larger
than what the choice of sequences makes it. Every tracker of one ``pftrack eval`` run sees the same sequences, so
the comparison can be paired: per sequence, the difference of the two trackers' AUC (each the mean over its
seeds), then the mean of those differences, its standard error, how many sequences each side wins, and the
Wilcoxon signed-rank test of the differences (two-sided; SciPy's ``scipy.stats.wilcoxon``). The summary and the
HTML report compare every tracker with one reference: the OpenCV peer of the speed ratios when it is in the run,
else the first tracker named.
"""

from __future__ import annotations

import html
import math
from typing import NamedTuple

import numpy as np

__all__ = ["PairedDiff", "paired_auc", "paired_html", "paired_markdown", "paired_reference", "paired_rows"]

#: Fewer sequences than this give no test (the signed-rank test's smallest two-sided p with 5 pairs is 0.0625).
MIN_PAIRS = 6


class PairedDiff(NamedTuple):
    """``b - a`` over the sequences both scored: their number, the mean difference and its standard error, the
    sequences where ``b`` scored higher and lower, and the signed-rank test's two-sided p (NaN when untestable)."""

    n: int
    mean: float
    se: float
    better: int
    worse: int
    p: float


def paired_auc(agg: dict, a: str, b: str) -> PairedDiff:
    """The paired AUC difference of tracker ``b`` over tracker ``a`` in :func:`~pftrack.eval.report.aggregate`'s
    output (its per-sequence means over seeds)."""
    cell = agg["cell"]
    d = []
    for s in agg["sequences"]:
        x, y = cell.get((a, s), {}).get("auc"), cell.get((b, s), {}).get("auc")
        if x is not None and y is not None and math.isfinite(x) and math.isfinite(y):
            d.append(y - x)
    n = len(d)
    if n == 0:
        return PairedDiff(0, float("nan"), float("nan"), 0, 0, float("nan"))
    v = np.asarray(d)
    se = float(v.std(ddof=1) / math.sqrt(n)) if n > 1 else float("nan")
    p = float("nan")
    if n >= MIN_PAIRS and np.any(v != 0):
        from scipy.stats import wilcoxon

        p = float(wilcoxon(v, zero_method="wilcox", alternative="two-sided").pvalue)
    return PairedDiff(n, float(v.mean()), se, int((v > 0).sum()), int((v < 0).sum()), p)


def paired_reference(trackers: list[str], peer: str | None) -> str | None:
    """The tracker the others are compared with: the speed peer when there is one, else the first; None for fewer
    than two trackers."""
    if len(trackers) < 2:
        return None
    return peer if peer in trackers else trackers[0]


def paired_rows(agg: dict, reference: str, order: list[str]) -> list[list[str]]:
    """One row per tracker but the reference: name, sequences, mean difference, standard error, better / worse,
    p (formatted)."""
    rows = []
    for t in order:
        if t == reference:
            continue
        r = paired_auc(agg, reference, t)
        se = "–" if not math.isfinite(r.se) else f"{r.se:.3f}"
        rows.append([t, str(r.n), _signed(r.mean), se, f"{r.better} / {r.worse}", _p(r.p)])
    return rows


def paired_markdown(agg: dict, reference: str, order: list[str]) -> list[str]:
    """The summary's section of paired differences against ``reference``."""
    lines = [f"## Paired AUC differences against `{reference}`", "",
             "Per sequence each tracker's AUC (mean over seeds) minus the reference's; the mean of those differences, "
             "its standard error, the sequences won and lost, and the two-sided Wilcoxon signed-rank p (from "
             f"{MIN_PAIRS} sequences on).", "",
             "| " + " | ".join(_HEAD) + " |", "|" + "---|" * len(_HEAD)]
    lines += [f"| `{r[0]}` | " + " | ".join(r[1:]) + " |" for r in paired_rows(agg, reference, order)]
    return lines + [""]


_HEAD = ("tracker", "sequences", "mean difference", "standard error", "better / worse", "p")


def paired_html(agg: dict, reference: str, order: list[str]) -> str:
    """The HTML report's table of paired differences against ``reference``."""
    e = html.escape
    head = "".join(f"<th>{h}</th>" for h in _HEAD)
    body = "".join("<tr>" + "".join(f"<td>{e(c)}</td>" for c in row) + "</tr>"
                   for row in paired_rows(agg, reference, order))
    return f"<h2>Paired AUC differences against {e(reference)}</h2><table><tr>{head}</tr>{body}</table>"


def _signed(v: float) -> str:
    return "–" if not math.isfinite(v) else f"{v:+.3f}"


def _p(v: float) -> str:
    return "–" if not math.isfinite(v) else (f"{v:.3f}" if v >= 0.001 else f"{v:.1e}")
