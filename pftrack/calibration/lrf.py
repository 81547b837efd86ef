"""People and robot tracking with a horizontal laser range finder (book ch. 12 §3.2, ch12.md §1.3).

Background subtraction of the static scan, clustering of consecutive foreground beams, the centre
correction of Eq. (1) (the sensor sees only the near edge of a body), human/robot classification by
the number of clusters (legs), and constant-velocity Kalman tracks with a gated Hungarian association.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

from ..filtering.kalman import KalmanFilter
from .sim import beam_angles


@dataclass(frozen=True)
class LrfParams:
    """Defaults of ch12.md §2 (``proposed`` where the text gives none)."""

    margin: float = 0.10            # foreground if r < r_bg - margin
    gap: float = 0.10               # split consecutive foreground points farther apart
    min_points: int = 3             # smaller clusters are discarded (L10519)
    d_robot: float = 0.15           # Eq. (1) offset for the robot (L10552)
    d_human: float = 0.06           # Eq. (1) offset for a leg (L10552)
    group: float = 0.45             # clusters closer than this form one object (two legs)
    gate: float = 0.5               # association gate (m)
    q: float = 0.5                  # white-acceleration noise (m^2/s^3)
    sigma: float = 0.03             # measurement noise (m)
    vote: int = 10                  # majority vote over the last scans (human if 2 clusters)
    max_missed: int = 5


def background_model(scans: np.ndarray) -> np.ndarray:
    """Per-beam median range over scans of the empty room."""
    return np.median(np.asarray(scans, float), axis=0)


def foreground(ranges: np.ndarray, r_bg: np.ndarray, margin: float = 0.10) -> np.ndarray:
    return np.asarray(ranges) < np.asarray(r_bg) - margin


def cluster_scan(points: np.ndarray, mask: np.ndarray, gap: float = 0.10, min_points: int = 3,
                 drop_edges: bool = True) -> list[np.ndarray]:
    """Split runs of consecutive foreground beams where neighbouring points are ``> gap`` apart.

    With ``drop_edges`` a cluster that touches the first or last beam is discarded: the body is only
    partly in the field of view and its centroid (hence Eq. 1) is biased by up to its radius."""
    idx = np.flatnonzero(mask)
    if len(idx) == 0:
        return []
    p = points[idx]
    brk = (np.diff(idx) > 1) | (np.linalg.norm(np.diff(p, axis=0), axis=1) > gap)
    starts = np.r_[0, np.flatnonzero(brk) + 1]
    ends = np.r_[starts[1:], len(idx)]
    last = len(mask) - 1
    return [p[s:e] for s, e in zip(starts, ends) if e - s >= min_points
            and not (drop_edges and (idx[s] == 0 or idx[e - 1] == last))]


def object_center(cluster_xy: np.ndarray, d: float) -> np.ndarray:
    """Eq. (1): push the cluster centroid away from the sensor by ``d`` along the line of sight."""
    c = np.asarray(cluster_xy, float).reshape(-1, 2).mean(0)
    a = np.arctan2(c[1], c[0])
    return c + d * np.array([np.cos(a), np.sin(a)])


def group_clusters(clusters: list[np.ndarray], p: LrfParams) -> list[tuple[np.ndarray, int]]:
    """Objects as (centre, number of clusters): clusters whose centroids lie within ``p.group`` are one
    object (a person's two legs); a one-cluster object is centred with the robot's offset."""
    if not clusters:
        return []
    cent = np.array([c.mean(0) for c in clusters])
    label = np.arange(len(clusters))
    for i in range(len(clusters)):            # single-link merge (a handful of clusters per scan)
        for j in range(i + 1, len(clusters)):
            if np.linalg.norm(cent[i] - cent[j]) < p.group:
                label[label == label[j]] = label[i]
    out = []
    for lab in np.unique(label):
        members = [clusters[k] for k in np.flatnonzero(label == lab)]
        if len(members) == 1:
            out.append((object_center(members[0], p.d_robot), 1))
        else:
            out.append((np.mean([object_center(m, p.d_human) for m in members], 0), len(members)))
    return out


@dataclass
class Track:
    id: int
    kf: KalmanFilter
    steps: list = field(default_factory=list)
    xy: list = field(default_factory=list)
    counts: list = field(default_factory=list)
    missed: int = 0

    def kind(self, vote: int) -> str:
        c = self.counts[-vote:]
        return "human" if sum(n >= 2 for n in c) * 2 >= len(c) else "robot"


def _cv_filter(xy, dt, p: LrfParams) -> KalmanFilter:
    F = np.eye(4)
    F[0, 2] = F[1, 3] = dt
    q1 = p.q * np.array([[dt ** 3 / 3, dt ** 2 / 2], [dt ** 2 / 2, dt]])
    Q = np.zeros((4, 4))
    Q[np.ix_([0, 2], [0, 2])] = q1
    Q[np.ix_([1, 3], [1, 3])] = q1
    H = np.zeros((2, 4))
    H[0, 0] = H[1, 1] = 1
    return KalmanFilter(F, H, Q, np.eye(2) * p.sigma ** 2, np.r_[xy, 0, 0],
                        np.diag([p.sigma ** 2, p.sigma ** 2, 1.0, 1.0]))


class LrfTracker:
    """Tracks in the sensor's own frame; :meth:`step` takes one scan."""

    def __init__(self, r_bg: np.ndarray, dt: float, params: LrfParams = LrfParams()):
        self.r_bg = np.asarray(r_bg, float)
        self.dt = dt
        self.p = params
        self.tracks: list[Track] = []
        self.finished: list[Track] = []
        self._next = 0
        a = beam_angles()
        self._cos, self._sin = np.cos(a), np.sin(a)

    def detect(self, ranges: np.ndarray) -> list[tuple[np.ndarray, int]]:
        pts = np.stack([ranges * self._cos, ranges * self._sin], 1)
        cl = cluster_scan(pts, foreground(ranges, self.r_bg, self.p.margin), self.p.gap, self.p.min_points)
        return group_clusters(cl, self.p)

    def step(self, k: int, ranges: np.ndarray) -> None:
        objs = self.detect(ranges)
        for t in self.tracks:
            t.kf.predict()
        used = set()
        if self.tracks and objs:
            pred = np.array([t.kf.x[:2] for t in self.tracks])
            z = np.array([o[0] for o in objs])
            cost = np.linalg.norm(pred[:, None] - z[None], axis=2)
            rows, cols = linear_sum_assignment(cost)
            for r, c in zip(rows, cols):
                if cost[r, c] <= self.p.gate:
                    tr = self.tracks[r]
                    tr.kf.update(z[c])
                    tr.steps.append(k)
                    tr.xy.append(tr.kf.x[:2].copy())
                    tr.counts.append(objs[c][1])
                    tr.missed = -1
                    used.add(c)
        keep = []
        for t in self.tracks:
            t.missed += 1
            (keep if t.missed <= self.p.max_missed else self.finished).append(t)
        self.tracks = keep
        for c, (xy, n) in enumerate(objs):
            if c not in used:
                t = Track(self._next, _cv_filter(xy, self.dt, self.p), [k], [np.asarray(xy, float)], [n])
                self._next += 1
                self.tracks.append(t)

    def all_tracks(self) -> list[Track]:
        return self.finished + self.tracks


def track_robot(bg_scans: np.ndarray, scans: np.ndarray, dt: float, params: LrfParams = LrfParams()):
    """Run the tracker over a scan sequence; returns (steps, local xy) of the tracks classified as robot,
    and every track."""
    trk = LrfTracker(background_model(bg_scans), dt, params)
    for k, r in enumerate(scans):
        trk.step(k, r)
    tracks = trk.all_tracks()
    steps, xy = [], []
    for t in tracks:
        if len(t.steps) >= params.vote and t.kind(len(t.counts)) == "robot":
            steps += t.steps
            xy += t.xy
    order = np.argsort(steps, kind="stable")
    return np.asarray(steps, int)[order], np.asarray(xy, float).reshape(-1, 2)[order], tracks
