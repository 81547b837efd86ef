"""SIFT keypoint sets, ratio-test matching and RANSAC similarity (book ch. 5, §4.1 and §5.1).

Book *Object Tracking*, ch. 5 (``shared/seeds/002_*`` lines 3595-5369; specification
``shared/book/ch05.md`` §1.2), Tracker A of Khan & Gu's hybrid:

* **(1)** SIFT features ``{p, sigma, phi, descriptor}`` in the search area: exactly OpenCV's
  ``SIFT_create().detectAndCompute`` — :func:`detect`;
* nearest-neighbour matching in Euclidean distance with Lowe's ratio test (0.8; the chapter's
  value was "empirically determined"), at most one current keypoint per stored point —
  :func:`match`;
* **(2)** the similarity ``[x~; y~] = [[x, -y, 1, 0], [y, x, 0, 1]] [b cos t, b sin t, dx, dy]^T``
  fitted by RANSAC: ``cv2.estimateAffinePartial2D`` (deterministic for a fixed match order:
  OpenCV seeds its RNG with a constant) — :func:`ransac_similarity`, :func:`similarity_params`;
* **(16)** the foreground weights: +2 for RANSAC inliers, -1 for matched outliers, the median of
  both for new points; the ``L_F`` heaviest kept — :func:`update_foreground_weights`,
  :func:`keep_heaviest`; the background set keeps its ``L_B`` newest points — :func:`keep_newest`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np


@dataclass
class PointSet:
    """Stored keypoints: positions in current-frame coordinates, descriptors, weights and ages."""

    xy: np.ndarray = field(default_factory=lambda: np.empty((0, 2), np.float32))
    desc: np.ndarray = field(default_factory=lambda: np.empty((0, 128), np.float32))
    weight: np.ndarray = field(default_factory=lambda: np.empty(0))
    age: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))

    def __len__(self) -> int:
        return int(self.xy.shape[0])

    def subset(self, idx) -> "PointSet":
        return PointSet(self.xy[idx], self.desc[idx], self.weight[idx], self.age[idx])

    @staticmethod
    def concat(*sets: "PointSet") -> "PointSet":
        sets = [s for s in sets if len(s)]
        if not sets:
            return PointSet()
        return PointSet(np.concatenate([s.xy for s in sets]).astype(np.float32),
                        np.concatenate([s.desc for s in sets]).astype(np.float32),
                        np.concatenate([s.weight for s in sets]), np.concatenate([s.age for s in sets]))


_SIFT = None


def sift():
    """A shared ``cv2.SIFT`` with OpenCV's defaults (contrast 0.04, edge 10, sigma 1.6)."""
    global _SIFT
    if _SIFT is None:
        _SIFT = cv2.SIFT_create()
    return _SIFT


def detect(gray: np.ndarray, region: tuple[int, int, int, int], *, mask: np.ndarray | None = None,
           max_points: int = 0, upsample: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """SIFT keypoints and descriptors inside ``region = (x0, y0, x1, y1)`` of a grey frame.

    ``upsample > 1`` enlarges the region first (cubic), so a small target yields enough
    keypoints; positions are returned in frame pixels either way.  Returns
    ``(xy (n, 2) float32 frame coordinates, desc (n, 128) float32)``, sorted by position (so
    matching and RANSAC see a deterministic order).
    """
    x0, y0, x1, y1 = region
    crop = gray[y0:y1, x0:x1]
    if crop.size == 0 or min(crop.shape) < 8:
        return np.empty((0, 2), np.float32), np.empty((0, 128), np.float32)
    if upsample > 1.0:
        crop = cv2.resize(crop, None, fx=upsample, fy=upsample, interpolation=cv2.INTER_CUBIC)
    kps, desc = sift().detectAndCompute(crop, mask)
    if desc is None or not kps:
        return np.empty((0, 2), np.float32), np.empty((0, 128), np.float32)
    # OpenCV's pt is in pixel-index units (pixel centres at integers)
    xy = (np.array([k.pt for k in kps], dtype=np.float32) + 0.5) / np.float32(upsample) - 0.5
    xy += np.array([x0, y0], np.float32)
    if max_points and len(kps) > max_points:
        resp = np.array([k.response for k in kps])
        keep = np.sort(np.argsort(-resp, kind="stable")[:max_points])
        xy, desc = xy[keep], desc[keep]
    order = np.lexsort((xy[:, 0], xy[:, 1]))
    return xy[order], desc[order].astype(np.float32)


def match(query: np.ndarray, train: np.ndarray, *, ratio: float = 0.8) -> tuple[np.ndarray, np.ndarray]:
    """Ratio-test nearest neighbours of ``query`` descriptors among ``train`` ones.

    Returns ``(qi, ti)`` index arrays, one pair per stored (train) point at most (the closer
    query wins), sorted by ``(qi, ti)``.
    """
    if len(query) == 0 or len(train) == 0:
        return np.empty(0, np.int64), np.empty(0, np.int64)
    bf = cv2.BFMatcher(cv2.NORM_L2)
    if len(train) == 1:
        ms = bf.match(query, train)
        pairs = [(m.queryIdx, m.trainIdx, m.distance) for m in ms]
    else:
        pairs = [(m[0].queryIdx, m[0].trainIdx, m[0].distance) for m in bf.knnMatch(query, train, k=2)
                 if len(m) == 2 and m[0].distance < ratio * m[1].distance]
    if not pairs:
        return np.empty(0, np.int64), np.empty(0, np.int64)
    arr = np.array(pairs, dtype=np.float64)
    q, t, dist = arr[:, 0].astype(np.int64), arr[:, 1].astype(np.int64), arr[:, 2]
    # one query per stored point: the closest (ties: the lower query index)
    order = np.lexsort((q, dist, t))
    _, first = np.unique(t[order], return_index=True)
    keep = order[first]
    qi, ti = q[keep], t[keep]
    order = np.lexsort((ti, qi))
    return qi[order], ti[order]


def ransac_similarity(src: np.ndarray, dst: np.ndarray, *, threshold: float = 3.0, max_iters: int = 2000,
                      confidence: float = 0.99) -> tuple[np.ndarray | None, np.ndarray]:
    """Eq. 2 by RANSAC: ``(M (2, 3) [[a, -b, dx], [b, a, dy]] or None, inlier mask)``; needs >= 2 pairs."""
    if len(src) < 2:
        return None, np.zeros(len(src), bool)
    M, inl = cv2.estimateAffinePartial2D(np.asarray(src, np.float32).reshape(-1, 1, 2),
                                         np.asarray(dst, np.float32).reshape(-1, 1, 2), method=cv2.RANSAC,
                                         ransacReprojThreshold=threshold, maxIters=max_iters,
                                         confidence=confidence, refineIters=10)
    if M is None:
        return None, np.zeros(len(src), bool)
    return M, inl.ravel().astype(bool)


def similarity_params(M: np.ndarray) -> tuple[float, float, float, float]:
    """``(beta, theta, dx, dy)`` of a similarity ``[[a, -b, dx], [b, a, dy]]``."""
    a, b = float(M[0, 0]), float(M[1, 0])
    return float(np.hypot(a, b)), float(np.arctan2(b, a)), float(M[0, 2]), float(M[1, 2])


def similarity_matrix(beta: float, theta: float, dx: float, dy: float) -> np.ndarray:
    c, s = beta * np.cos(theta), beta * np.sin(theta)
    return np.array([[c, -s, dx], [s, c, dy]])


def transform_points(M: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Apply a 2x3 transform to ``(n, 2)`` points."""
    pts = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
    return (pts @ M[:, :2].T + M[:, 2]).astype(np.float32)


def similarity_between(c0, h0, theta0, c1, h1, theta1) -> np.ndarray:
    """The similarity mapping a rotated box (centre ``c0``, long side ``h0``, angle ``theta0``) onto another."""
    beta = h1 / max(h0, 1e-9)
    dtheta = theta1 - theta0
    R = similarity_matrix(beta, dtheta, 0.0, 0.0)
    t = np.asarray(c1, dtype=np.float64) - R[:, :2] @ np.asarray(c0, dtype=np.float64)
    R[:, 2] = t
    return R


def update_foreground_weights(w_inliers: np.ndarray, w_outliers: np.ndarray, n_new: int
                              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eq. 16: inliers +2, matched outliers -1, new points the median of both groups (0 if empty)."""
    wa = np.asarray(w_inliers, dtype=np.float64) + 2.0
    wb = np.asarray(w_outliers, dtype=np.float64) - 1.0
    both = np.concatenate([wa, wb])
    w0 = float(np.median(both)) if both.size else 0.0
    return wa, wb, np.full(n_new, w0)


def keep_heaviest(ps: PointSet, cap: int) -> PointSet:
    """The ``cap`` heaviest points (ties: the older point first, then the stored order)."""
    if len(ps) <= cap:
        return ps
    order = np.lexsort((np.arange(len(ps)), -ps.age, -ps.weight))
    return ps.subset(np.sort(order[:cap]))


def keep_newest(ps: PointSet, cap: int) -> PointSet:
    """The ``cap`` newest points (smallest age; ties: the later-added point)."""
    if len(ps) <= cap:
        return ps
    order = np.lexsort((-np.arange(len(ps)), ps.age))
    return ps.subset(np.sort(order[:cap]))


def points_in_rotated_box(xy: np.ndarray, cx: float, cy: float, h: float, w: float, theta: float,
                          scale: float = 1.0) -> np.ndarray:
    """Bool per point: inside the rotated rectangle (long side ``h`` along ``theta``) scaled by ``scale``."""
    d = np.asarray(xy, dtype=np.float64).reshape(-1, 2) - np.array([cx, cy])
    u = d @ np.array([np.cos(theta), np.sin(theta)])
    v = d @ np.array([-np.sin(theta), np.cos(theta)])
    return (np.abs(u) <= scale * h / 2) & (np.abs(v) <= scale * w / 2)


def points_in_ellipse(xy: np.ndarray, cx: float, cy: float, h: float, w: float, theta: float) -> np.ndarray:
    """Bool per point: inside the ellipse inscribed in the rotated rectangle (the human FG option)."""
    d = np.asarray(xy, dtype=np.float64).reshape(-1, 2) - np.array([cx, cy])
    u = d @ np.array([np.cos(theta), np.sin(theta)])
    v = d @ np.array([-np.sin(theta), np.cos(theta)])
    return (u / max(h / 2, 1e-9)) ** 2 + (v / max(w / 2, 1e-9)) ** 2 <= 1.0
