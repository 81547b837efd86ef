"""Multi-object metrics through py-motmetrics (GUIDE §4).

We do not re-implement CLEAR-MOT or identity metrics: hypotheses and ground truth
are fed frame by frame to ``motmetrics.MOTAccumulator`` with the IoU distance
(``1 - IoU``, matches only when IoU >= 0.5), and the summary gives MOTA, MOTP,
IDF1, ID switches, fragmentations, mostly tracked / lost, and HOTA when the
installed motmetrics provides it.

Compatibility: py-motmetrics 1.4.0 (its latest release) calls ``np.asfarray``,
which NumPy 2 removed.  :func:`import_motmetrics` restores that one name, in
this one documented place, before importing motmetrics; the parity test pins
the numbers on motmetrics' own TUD-Campus data.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

METRICS = ["mota", "motp", "idf1", "num_switches", "num_fragmentations", "mostly_tracked", "mostly_lost",
           "num_false_positives", "num_misses", "num_objects", "num_unique_objects", "precision", "recall"]


def import_motmetrics():
    """Import motmetrics, restoring ``np.asfarray`` on NumPy 2 if it is missing."""
    if not hasattr(np, "asfarray"):
        np.asfarray = lambda a, dtype=np.float64: np.asarray(a, dtype=dtype)  # type: ignore[attr-defined]
    import motmetrics

    return motmetrics


@dataclass(frozen=True)
class MOTScores:
    mota: float
    motp: float  # mean (1 - IoU) of matches, motmetrics' convention (lower is better)
    idf1: float
    num_switches: int
    num_fragmentations: int
    mostly_tracked: int
    mostly_lost: int
    num_false_positives: int
    num_misses: int
    num_objects: int
    num_unique_objects: int
    precision: float
    recall: float
    hota: float | None = None
    id_rate: float = float("nan")  # book ch. 1 Table 1: matched detections that carry their person's identity

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def accumulate(gt: np.ndarray, hyp: np.ndarray, *, iou_threshold: float = 0.5, frames=None):
    """Build a ``MOTAccumulator`` from MOTChallenge rows (``frame,id,x,y,w,h,...``).

    Ground-truth rows with ``conf == 0`` (column 7) are ignored, as in the
    MOTChallenge evaluation of boxes marked "not to be considered".
    """
    mm = import_motmetrics()
    gt = np.asarray(gt, dtype=np.float64).reshape(-1, max(6, np.asarray(gt).shape[-1] if np.size(gt) else 6))
    hyp = np.asarray(hyp, dtype=np.float64).reshape(-1, max(6, np.asarray(hyp).shape[-1] if np.size(hyp) else 6))
    if gt.shape[1] > 6:
        gt = gt[gt[:, 6] != 0]
    acc = mm.MOTAccumulator(auto_id=False)
    if frames is None:
        frames = np.union1d(gt[:, 0], hyp[:, 0]).astype(int)
    for f in frames:
        g = gt[gt[:, 0] == f]
        h = hyp[hyp[:, 0] == f]
        dist = mm.distances.iou_matrix(g[:, 2:6], h[:, 2:6], max_iou=1.0 - iou_threshold)
        acc.update(g[:, 1].astype(int).tolist(), h[:, 1].astype(int).tolist(), dist, frameid=int(f))
    return acc


def identification_rate(acc) -> float:
    """Book ch. 1, Table 1: the fraction of matched detections whose hypothesis identity is the one that
    person carries most often (its "right" identity); NaN without matches."""
    ev = acc.mot_events
    # one row per matched detection: MATCH, or SWITCH (motmetrics adds TRANSFER/ASCEND/MIGRATE rows that
    # describe the same switch again)
    ev = ev[ev["Type"].isin(["MATCH", "SWITCH"]) & ev["OId"].notna() & ev["HId"].notna()]
    if len(ev) == 0:
        return float("nan")
    pairs = ev[["OId", "HId"]].astype(float).to_numpy()
    right = 0
    for oid in np.unique(pairs[:, 0]):
        hids = pairs[pairs[:, 0] == oid, 1]
        _, counts = np.unique(hids, return_counts=True)
        right += int(counts.max())
    return right / len(pairs)


def mot_scores(gt: np.ndarray, hyp: np.ndarray, *, iou_threshold: float = 0.5, frames=None) -> MOTScores:
    """MOT metrics of hypotheses against ground truth (MOTChallenge rows)."""
    mm = import_motmetrics()
    acc = accumulate(gt, hyp, iou_threshold=iou_threshold, frames=frames)
    mh = mm.metrics.create()
    summary = mh.compute(acc, metrics=METRICS, name="seq")
    row = summary.loc["seq"]
    hota = None
    if "hota" in getattr(mh, "names", []) or "hota_alpha" in getattr(mh, "names", []):
        try:  # newer motmetrics releases
            hota = float(mh.compute(acc, metrics=["hota_alpha"], name="seq").loc["seq"].iloc[0])
        except Exception:  # pragma: no cover - depends on the installed version
            hota = None

    def f(k):
        v = row[k]
        return float(v) if np.isfinite(v) else float("nan")

    return MOTScores(mota=f("mota"), motp=f("motp"), idf1=f("idf1"), num_switches=int(row["num_switches"]),
                     num_fragmentations=int(row["num_fragmentations"]), mostly_tracked=int(row["mostly_tracked"]),
                     mostly_lost=int(row["mostly_lost"]), num_false_positives=int(row["num_false_positives"]),
                     num_misses=int(row["num_misses"]), num_objects=int(row["num_objects"]),
                     num_unique_objects=int(row["num_unique_objects"]), precision=f("precision"),
                     recall=f("recall"), hota=hota, id_rate=identification_rate(acc))
