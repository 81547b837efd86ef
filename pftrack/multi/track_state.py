"""Per-track state of ``multi-pf`` and the small array helpers on it (states, boxes, ellipses, regions).

Pure functions on arrays and a plain record per track; :mod:`pftrack.multi.tracker` holds the filter.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..cues.histogram_cue import ColorFeatures
from ..geometry import intersection_area, iou_matrix


@dataclass
class Track:
    """One target of the filter: its estimate, particles, colour model and life-cycle counters."""

    id: int
    state: np.ndarray  # (8,) estimate x, y, vx, vy, w, h, vw, vh
    particles: np.ndarray  # (N, 8)
    q: np.ndarray
    sqrt_q: np.ndarray
    lam: float | None = None
    hist_max: float | None = None
    occluded: bool = False
    grouped: bool = False  # inside a merged detection this frame
    misses: int = 0
    occluded_frames: int = 0
    age: int = 0
    features: object = None  # ch. 1 identification features at the last detection
    score: float = 0.0
    det: np.ndarray | None = None
    log_lik: np.ndarray | None = None
    max_lik: float = 0.0
    obj: np.ndarray | None = None  # object / surround colour counts of the contrast cue
    sur: np.ndarray | None = None
    lut: np.ndarray | None = None
    feats: object = None  # this frame's quantised region of the particles (ColorFeatures, own bins)

    @property
    def box(self) -> np.ndarray:
        x, y, w, h = self.state[0], self.state[1], self.state[4], self.state[5]
        return np.array([x - w / 2, y - h / 2, w, h])


@dataclass
class Candidate:
    box: np.ndarray
    hits: int = 1
    first_center: np.ndarray = field(default_factory=lambda: np.zeros(2))


def box_to_state(box) -> np.ndarray:
    x, y, w, h = (float(v) for v in box)
    return np.array([x + w / 2, y + h / 2, 0.0, 0.0, w, h, 0.0, 0.0])


def state_boxes(states: np.ndarray) -> np.ndarray:
    out = np.empty((states.shape[0], 4))
    out[:, 0] = states[:, 0] - states[:, 4] / 2
    out[:, 1] = states[:, 1] - states[:, 5] / 2
    out[:, 2] = states[:, 4]
    out[:, 3] = states[:, 5]
    return out


def cover_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Fraction of each box of ``a`` (x, y, w, h) that lies inside each box of ``b``."""
    return intersection_area(a[:, None, :], b[None, :, :]) / np.maximum(a[:, None, 2] * a[:, None, 3], 1e-9)


def gate_merged_detections(pred_boxes: np.ndarray, dets: np.ndarray, m: np.ndarray, gate: np.ndarray,
                           used: np.ndarray, group_cover: float, group_fit: float, match_iou: float
                           ) -> dict[int, bool]:
    """Occlusion handling for merged blobs (``multi-pf``): a detection (``dets`` ``(M, 4)``) that covers several
    distinct targets' predicted boxes (``pred_boxes``, ``(L, 4)``; at least ``group_cover`` of each inside it) is
    gated (``gate``, ``(L, M)``, in place) to the member that fits it alone (in front: IoU ``m`` at least
    ``group_fit``), if any, and otherwise removed from the assignment and marked ``used`` (in place) so that it
    starts no track. Returns, for each member of such a blob, whether it is ``grouped`` (behind the blob's front
    member, or in a blob with none), the last blob deciding for a target in several."""
    inside = cover_matrix(pred_boxes, dets) >= group_cover
    grouped: dict[int, bool] = {}
    if not (inside.sum(axis=0) >= 2).any():
        return grouped
    pair_iou = iou_matrix(pred_boxes, pred_boxes)
    for j in np.flatnonzero(inside.sum(axis=0) >= 2):
        members = np.flatnonzero(inside[:, j])
        if pair_iou[np.ix_(members, members)].min() >= 0.5:
            continue  # one target tracked twice (a duplicate about to die), not a group
        fit = m[members, j]
        front = members[int(np.argmax(fit))] if fit.max() >= group_fit else -1
        if front < 0:
            used[j] = True  # no member explains the blob alone: the detection of none
        gate[:, j] = False
        if front >= 0:
            gate[front, j] = m[front, j] >= match_iou  # the one in front; the others are behind it
        for i in members:
            grouped[int(i)] = bool(i != front)
    return grouped


def ellipses(states: np.ndarray) -> np.ndarray:
    out = np.empty((states.shape[0], 4))
    out[:, 0:2] = states[:, 0:2]
    out[:, 2] = states[:, 4] / 2
    out[:, 3] = states[:, 5] / 2
    return out


def cut_features(stored: ColorFeatures | None, roi: tuple[int, int, int, int], pitch: int,
         shape: tuple[int, int]) -> ColorFeatures | None:
    """The features :meth:`ColorCue.prepare` would give for ``roi`` at ``pitch``, cut from ``stored`` (the same
    frame's features of a larger region on the same lattice), or None when ``stored`` does not cover them.

    Quantisation is per pixel, so the cut holds the same bins; its origin is the one ``prepare`` would choose,
    so the kernels see the same coordinates."""
    if stored is None or stored.pitch != pitch:
        return None
    h, w = shape
    x0, y0, x1, y1 = roi
    x0 -= x0 % pitch
    y0 -= y0 % pitch
    nh, nw = len(range(y0, min(y1, h), pitch)), len(range(x0, min(x1, w), pitch))
    r0, c0 = (y0 - stored.y0) // pitch, (x0 - stored.x0) // pitch
    sh, sw = stored.bins.shape
    if nh <= 0 or nw <= 0 or r0 < 0 or c0 < 0 or r0 + nh > sh or c0 + nw > sw:
        return None
    return ColorFeatures(np.ascontiguousarray(stored.bins[r0:r0 + nh, c0:c0 + nw]), x0, y0, pitch)


def mark_occlusions(tracks: list, radius: float, drop: float) -> None:
    """Sugandi et al.'s occlusion reasoning on the tracks' predictions (in place): of two tracks predicted closer
    than ``radius`` times their mean width, the one whose likelihood fell most below its own history (below
    ``drop`` times it) and that has no detection is behind, ``occluded``; a track stops being occluded when no
    other is predicted near it, its likelihood recovers, or a detection is associated with it."""
    n = len(tracks)
    predicted = [False] * n
    for i in range(n):
        for j in range(i + 1, n):
            a, b = tracks[i], tracks[j]
            r = radius * 0.5 * (a.pred[4] + b.pred[4])
            if (a.pred[0] - b.pred[0]) ** 2 + (a.pred[1] - b.pred[1]) ** 2 < r * r:
                predicted[i] = predicted[j] = True
                # the one whose likelihood fell most below its history is behind
                ra = a.max_lik / a.hist_max if a.hist_max else 1.0
                rb = b.max_lik / b.hist_max if b.hist_max else 1.0
                behind, r_behind = (a, ra) if ra < rb else (b, rb)
                if r_behind < drop and behind.det is None:
                    behind.occluded = True
    for i, tr in enumerate(tracks):
        if tr.occluded:
            recovered = tr.hist_max and tr.max_lik >= drop * tr.hist_max
            if not predicted[i] or recovered or tr.det is not None:
                tr.occluded = False
