"""Crossings from tracks (the conventional tripwire and the ground truth) and event scoring (book ch. 10).

* :func:`track_crossings` — the tracker-based tripwire ("CFT", ch10.md §1.6): each track's
  foot point (bottom centre of its box) goes through the hysteresis state machine of
  :func:`~.geometry.crossings_of_track`; tracks seen on fewer than ``min_frames`` frames
  (unconfirmed) are ignored, and every track is its own object.
* :func:`match_events` — one-to-one matching of detected and ground-truth events of the same
  direction within ``tol`` frames (Hungarian on |Δframe|); accuracy = TP / GT (Eq. 8),
  precision = TP / detections, F1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from .geometry import Crossing, crossings_of_track

__all__ = ["EventScore", "match_events", "track_crossings"]


def track_crossings(mot_rows: np.ndarray, polyline: np.ndarray, *, hysteresis: float = 5.0, min_frames: int = 3,
                    stride: int = 1, point: str = "foot") -> list[Crossing]:
    """Crossings of every track of MOT rows ``frame,id,x,y,w,h,...``: of the boxes' foot points (bottom
    centre; people and vehicles seen obliquely) or centres (``point="centre"``; top-down views).  With
    ``stride`` only frames ``1, 1+stride, …`` are seen (a lower frame rate)."""
    rows = np.asarray(mot_rows, dtype=np.float64)
    out: list[Crossing] = []
    if len(rows) == 0:
        return out
    if stride > 1:
        rows = rows[((rows[:, 0].astype(int) - 1) % stride) == 0]
    for tid in np.unique(rows[:, 1]).astype(int):
        r = rows[rows[:, 1] == tid]
        r = r[np.argsort(r[:, 0])]
        if len(r) < min_frames:
            continue
        bottom = r[:, 3] + (r[:, 5] if point == "foot" else r[:, 5] / 2.0)
        foot = np.stack([r[:, 2] + r[:, 4] / 2.0, bottom], axis=1)
        out += crossings_of_track(r[:, 0], foot, polyline, hysteresis=hysteresis, track=int(tid))
    return sorted(out, key=lambda c: c.frame)


@dataclass(frozen=True)
class EventScore:
    gt: int
    detected: int
    tp: int

    @property
    def fp(self) -> int:
        return self.detected - self.tp

    @property
    def accuracy(self) -> float:
        """Eq. 8: TP / GT."""
        return self.tp / self.gt if self.gt else float("nan")

    @property
    def precision(self) -> float:
        return self.tp / self.detected if self.detected else float("nan")

    @property
    def f1(self) -> float:
        return 2 * self.tp / (self.gt + self.detected) if self.gt + self.detected else float("nan")

    def row(self) -> dict:
        return {"gt": self.gt, "det": self.detected, "tp": self.tp, "fp": self.fp, "accuracy": self.accuracy,
                "precision": self.precision, "f1": self.f1}


def match_events(detected, truth, *, tol: float = 10.0) -> EventScore:
    """One-to-one matching of ``(frame, direction)`` pairs: same direction, ``|Δframe| ≤ tol``."""
    det = np.asarray([(float(f), int(d)) for f, d in detected], dtype=np.float64).reshape(-1, 2)
    gt = np.asarray([(float(f), int(d)) for f, d in truth], dtype=np.float64).reshape(-1, 2)
    tp = 0
    for direction in (-1, 1):
        a, b = det[det[:, 1] == direction, 0], gt[gt[:, 1] == direction, 0]
        if len(a) == 0 or len(b) == 0:
            continue
        cost = np.abs(a[:, None] - b[None, :])
        big = 1e6
        cost = np.where(cost <= tol, cost, big)
        ri, ci = linear_sum_assignment(cost)
        tp += int(np.sum(cost[ri, ci] < big))
    return EventScore(len(gt), len(det), tp)
