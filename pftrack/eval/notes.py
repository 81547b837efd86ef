"""The sentences under an evaluation's summary table (``summary.md`` and ``index.html`` alike): the speed ratio to
an OpenCV peer read two stricter ways, and the lost flag's rates pooled over frames."""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

__all__ = ["lost_notes", "pooled_lost_rates", "sequence_speed_ratios", "speed_notes", "speed_peer",
           "strict_speed_ratios"]


def _num(v) -> float:
    return float("nan") if v is None else float(v)


def speed_peer(trackers: list[str]) -> str | None:
    """The OpenCV tracker that speed ratios are taken against: CSRT when it is in the run, else the first OpenCV
    tracker; None without one (or without another tracker to compare)."""
    opencv = [t for t in trackers if t.startswith("opencv-")]
    if not opencv or len(opencv) == len(trackers):
        return None
    return "opencv-csrt" if "opencv-csrt" in opencv else opencv[0]


def _upper_median(values: list[float]) -> float:
    v = sorted(x for x in values if math.isfinite(x))
    return v[len(v) // 2] if v else float("nan")


def strict_speed_ratios(records: list[dict], peer: str) -> dict[str, float]:
    """Each tracker's upper median update rate over all its (sequence, seed) runs, divided by the peer's: a
    reading that no single slow or fast sequence moves, and that never averages two middle values."""
    rates: dict[str, list[float]] = defaultdict(list)
    for r in records:
        rates[r["tracker"]].append(_num(r.get("fps")))
    ref = _upper_median(rates.get(peer, []))
    return {t: _ratio(_upper_median(v), ref) for t, v in rates.items()}


def sequence_speed_ratios(agg: dict, peer: str) -> dict[str, tuple[float, float, float]]:
    """Each tracker's ratio to the peer sequence by sequence (the median fps over seeds of each, on the sequences both
    ran): ``(lowest, median, highest)``, NaN where no sequence has both rates.  The peer's cost may depend on the
    target (CSRT's on its size) while the tracker's does not, and then the ratio of the two medians hides a spread
    that this reading shows."""
    out = {}
    for t in agg["trackers"]:
        r = [_ratio(agg["cell"][(t, s)]["fps"], agg["cell"][(peer, s)]["fps"]) for s in agg["sequences"]
             if (t, s) in agg["cell"] and (peer, s) in agg["cell"]]
        r = [x for x in r if math.isfinite(x)]
        out[t] = (min(r), float(np.median(r)), max(r)) if r else (float("nan"),) * 3
    return out


def speed_notes(records: list[dict], agg: dict, peer: str, order: list[str]) -> list[str]:
    """The two sentences under a table with a ``× peer`` column: the strict reading and the ratio sequence by
    sequence, for the trackers of ``order`` other than the peer (summary.md and index.html alike)."""
    strict = strict_speed_ratios(records, peer)
    per = sequence_speed_ratios(agg, peer)
    others = [t for t in order if t != peer]
    return [f"× {peer}: the ratio of the median fps in this run. The strictest reading, the upper median of all "
            "(sequence, seed) update rates of each tracker against the same of the peer's: "
            + ", ".join(f"`{t}` {strict[t]:.1f}×" for t in others) + ".",
            "Sequence by sequence (each tracker's median fps over the peer's on the same sequence), lowest, median "
            "and highest: " + ", ".join(f"`{t}` {per[t][0]:.1f}×, {per[t][1]:.1f}×, {per[t][2]:.1f}×"
                                        for t in others) + "."]


def _ratio(a: float, b: float) -> float:
    return a / b if math.isfinite(b) and b > 0 else float("nan")


def pooled_lost_rates(records: list[dict]) -> dict[str, dict[str, float]]:
    """Per tracker, the lost flag's two rates over the frames of all its runs, each frame counted once: ``recall``
    (flagged of the ``absent`` frames) and ``false`` (flagged of the ``covered`` frames, IoU >= 0.5).  The summary
    table's rates are means over sequences, where a run with two covered frames weighs as much as one with two
    hundred; these are the rates of the frames themselves.  A rate is NaN where a run that has one does not say
    how many frames it is of (a record from before ``covered_frames`` was kept), or where no run has such frames."""
    # per tracker: flagged absent frames, absent frames, flagged covered frames, covered frames; and per rate,
    # whether a run gave it without its count (then that pooled rate is unknown)
    acc: dict[str, list[float]] = defaultdict(lambda: [0.0, 0.0, 0.0, 0.0])
    unknown: dict[str, set[int]] = defaultdict(set)
    for r in records:
        a = acc[r["tracker"]]
        for rate, n, i in (("lost_recall", "absent_frames", 0), ("false_lost", "covered_frames", 2)):
            v, m = _num(r.get(rate)), r.get(n)
            if not math.isfinite(v):
                continue
            if m is None:
                unknown[r["tracker"]].add(i)
                continue
            a[i] += round(v * int(m))
            a[i + 1] += int(m)
    out: dict[str, dict[str, float]] = {}
    for t, (hits, absent, false, covered) in acc.items():
        out[t] = {"recall": hits / absent if absent and 0 not in unknown[t] else float("nan"), "absent": absent,
                  "false": false / covered if covered and 2 not in unknown[t] else float("nan"), "covered": covered}
    return out


def lost_notes(records: list[dict], order: list[str]) -> list[str]:
    """The sentence under a one-pass table: the lost flag's rates pooled over frames (:func:`pooled_lost_rates`),
    for the trackers of ``order`` with any absent or covered frame; none when no tracker has one."""
    pooled = pooled_lost_rates(records)
    parts = []
    for t in order:
        p = pooled.get(t)
        if p is None or not (p["absent"] or p["covered"]):
            continue
        rec = f"{p['recall']:.3f} of {int(p['absent'])}" if math.isfinite(p["recall"]) else "–"
        fal = f"{p['false']:.3f} of {int(p['covered'])}" if math.isfinite(p["false"]) else "–"
        parts.append(f"`{t}` {rec} / {fal}")
    if not parts:
        return []
    return ["Pooled over the frames of all runs, each frame counted once (lost recall of the absent frames / "
            "false-lost rate of the frames with IoU >= 0.5): " + ", ".join(parts) + "."]
