"""Covariance matching: scoring windows against a model, coarse-to-fine search, and a batched
particle likelihood (book ch. 6 §4.2; ``shared/book/ch06.md`` §1.9).

The search of Porikli, Tuzel & Meer (2006) is exhaustive; its scales and stride are not
given.  Ours (ch06.md §1.9, proposed):

1. **coarse**: the region is decimated (area averaging) by ``f = max(1, min(w, h) // coarse_side)``
   so the target spans about ``coarse_side`` pixels across; every window of the target's size
   times ``{1/1.1, 1, 1.1}`` on a ``coarse_stride`` lattice of that image is scored (one batched
   eigen-decomposition);
2. **refine**: around the ``refine_top`` best coarse windows (after suppressing near-duplicates),
   full-resolution windows on a lattice of step ``~f/2`` are scored, then the best one's
   neighbourhood at stride 1.

All windows are scored by Eq. 30, ``||log C_window - log C_model||_F``, after the
standardisation of :func:`pftrack.cues.covariance.standardize`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .covariance import (EPS, IntegralCovariance, covariance_features, feature_scales, le_distance, spd_log,
                         standardize)


def frame_scales(frame: np.ndarray, *, kind: str, gray: bool) -> np.ndarray:
    """The standardisation scales of a whole frame at full resolution (:func:`feature_scales`)."""
    z = covariance_features(frame, kind=kind, gray=gray)
    return feature_scales(z, gray=gray)


def window_grid(region: tuple[int, int, int, int], size: tuple[int, int], stride: int) -> np.ndarray:
    """``(K, 4)`` int windows ``(x0, y0, x1, y1)`` of ``size = (w, h)`` inside ``region``
    ``(x0, y0, x1, y1)`` on a ``stride`` lattice (the last row/column flush with the region)."""
    rx0, ry0, rx1, ry1 = region
    w, h = size
    if rx1 - rx0 < w or ry1 - ry0 < h:
        return np.empty((0, 4), dtype=np.int64)
    xs = np.arange(rx0, rx1 - w + 1, stride)
    ys = np.arange(ry0, ry1 - h + 1, stride)
    if xs[-1] != rx1 - w:
        xs = np.append(xs, rx1 - w)
    if ys[-1] != ry1 - h:
        ys = np.append(ys, ry1 - h)
    X, Y = np.meshgrid(xs, ys)
    X, Y = X.ravel(), Y.ravel()
    return np.stack([X, Y, X + w, Y + h], axis=1).astype(np.int64)


def window_distances(icov: IntegralCovariance, boxes: np.ndarray, L_model: np.ndarray, scales: np.ndarray, *,
                     pitch: float = 1.0, min_fraction: float = 0.3, eps: float = EPS) -> np.ndarray:
    """Eq. 30 for each window (``inf`` where the window's weight is below ``min_fraction`` of its
    area or ``d + 1`` pixels).  ``pitch`` converts window sizes to frame pixels (decimated images)."""
    if len(boxes) == 0:
        return np.empty(0)
    C, W = icov.cov(boxes)
    sizes = (boxes[:, 2:] - boxes[:, :2]).astype(np.float64)
    area = sizes[:, 0] * sizes[:, 1]
    ok = (W >= icov.d + 1) & (W >= min_fraction * area) & np.all(np.isfinite(C), axis=(1, 2))
    out = np.full(len(boxes), np.inf)
    if np.any(ok):
        Cs = standardize(C[ok], sizes[ok] * pitch, scales, eps=eps)
        out[ok] = le_distance(spd_log(Cs), L_model)
    return out


def model_log(frame: np.ndarray, box: tuple[float, float, float, float], *, kind: str, gray: bool,
              scales: np.ndarray, weights: np.ndarray | None = None, eps: float = EPS) -> np.ndarray | None:
    """``log`` of the standardised covariance of the window nearest to ``box`` (None if empty)."""
    x0, y0, x1, y1 = _int_window(box)
    h, w = frame.shape[:2]
    x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, w), min(y1, h)
    if x1 - x0 < 2 or y1 - y0 < 2:
        return None
    ic = _integral(frame, (x0, y0, x1, y1), kind=kind, gray=gray, weights=weights)
    C, W = ic.cov(np.array([[x0, y0, x1, y1]]))
    if not np.all(np.isfinite(C)) or W[0] < ic.d + 1:
        return None
    return spd_log(standardize(C, np.array([[x1 - x0, y1 - y0]]), scales, eps=eps))[0]


def _int_window(box) -> tuple[int, int, int, int]:
    x, y, w, h = box
    return int(round(x)), int(round(y)), int(round(x + w)), int(round(y + h))


@dataclass(frozen=True)
class SearchResult:
    box: tuple[float, float, float, float]
    distance: float
    n_windows: int
    candidates: np.ndarray  # (k, 5): x, y, w, h, distance of the refined candidates, best first


def _suppress(boxes: np.ndarray, dist: np.ndarray, k: int, radius: float) -> np.ndarray:
    """Indices of up to ``k`` best windows whose centres are at least ``radius`` apart."""
    order = np.argsort(dist, kind="stable")
    order = order[np.isfinite(dist[order])]
    centres = 0.5 * (boxes[:, :2] + boxes[:, 2:])
    keep: list[int] = []
    for i in order:
        if all(np.hypot(*(centres[i] - centres[j])) >= radius for j in keep):
            keep.append(int(i))
            if len(keep) >= k:
                break
    return np.array(keep, dtype=np.int64)


def search(frame: np.ndarray, L_model: np.ndarray, size: tuple[float, float], *, kind: str, gray: bool,
           scales_full: np.ndarray, region: tuple[int, int, int, int] | None = None,
           weights: np.ndarray | None = None, scale_factors: tuple[float, ...] = (1 / 1.1, 1.0, 1.1),
           coarse_side: int = 8, coarse_stride: int = 2, refine_top: int = 10, eps: float = EPS) -> SearchResult:
    """Coarse-to-fine covariance search for the window nearest (Eq. 30) to the model ``L_model``.

    ``region`` (frame integers ``x0, y0, x1, y1``; default the whole frame) bounds the search;
    ``weights`` (frame-sized, optional) is a foreground weight or mask multiplying every pixel.
    """
    fh, fw = frame.shape[:2]
    rx0, ry0, rx1, ry1 = region if region is not None else (0, 0, fw, fh)
    rx0, ry0, rx1, ry1 = max(0, rx0), max(0, ry0), min(fw, rx1), min(fh, ry1)
    w, h = size
    f = max(1, int(min(w, h) // coarse_side))
    n_windows = 0
    # --- coarse level
    sub = frame[ry0:ry1, rx0:rx1]
    cw, ch = max(1, (rx1 - rx0) // f), max(1, (ry1 - ry0) // f)
    small = cv2.resize(sub, (cw, ch), interpolation=cv2.INTER_AREA) if f > 1 else sub
    z = covariance_features(small, kind=kind, gray=gray, origin=(rx0, ry0), pitch=f)
    scales_c = feature_scales(z, gray=gray)
    m = None
    if weights is not None:
        ws = weights[ry0:ry1, rx0:rx1].astype(np.float32)
        m = cv2.resize(ws, (cw, ch), interpolation=cv2.INTER_AREA) if f > 1 else ws
    ic = IntegralCovariance(z, m)
    cand_boxes, cand_dist = [], []
    for s in scale_factors:
        ww = max(2, int(round(w * s / f)))
        hh = max(2, int(round(h * s / f)))
        b = window_grid((0, 0, cw, ch), (ww, hh), coarse_stride)
        dist = window_distances(ic, b, L_model, scales_c, pitch=f, eps=eps)
        n_windows += len(b)
        # back to frame coordinates, full-resolution size of this scale
        fb = np.empty_like(b)
        fb[:, 0] = rx0 + b[:, 0] * f
        fb[:, 1] = ry0 + b[:, 1] * f
        fb[:, 2] = fb[:, 0] + int(round(w * s))
        fb[:, 3] = fb[:, 1] + int(round(h * s))
        cand_boxes.append(fb)
        cand_dist.append(dist)
    if not cand_boxes or sum(len(b) for b in cand_boxes) == 0:
        return SearchResult((float(rx0), float(ry0), float(w), float(h)), math.inf, 0, np.empty((0, 5)))
    # the best few of each scale (a sub-window of the target can beat a misaligned coarse window of
    # the right scale, so the scales do not compete before refinement)
    boxes = np.concatenate(cand_boxes)
    dist = np.concatenate(cand_dist)
    per_scale = max(1, int(math.ceil(refine_top / len(scale_factors))))
    keep, offset = [], 0
    for b, d in zip(cand_boxes, cand_dist):
        keep.append(offset + _suppress(b, d, per_scale, 0.25 * min(w, h)))
        offset += len(b)
    keep = np.concatenate(keep)
    if keep.size == 0:
        return SearchResult((float(rx0), float(ry0), float(w), float(h)), math.inf, n_windows, np.empty((0, 5)))
    # --- refinement at full resolution around each kept window
    r = f * coarse_stride
    step = max(1, int(math.ceil(r / 4)))
    refined = []
    for i in keep:
        bx0, by0, bx1, by1 = boxes[i]
        bw, bh = bx1 - bx0, by1 - by0
        reg = (max(bx0 - r, 0), max(by0 - r, 0), min(bx1 + r, fw), min(by1 + r, fh))
        best = _refine(frame, reg, (bw, bh), step, L_model, kind=kind, gray=gray, scales=scales_full,
                       weights=weights, eps=eps)
        n_windows += best[2]
        if step > 1 and math.isfinite(best[1]):
            x0, y0 = best[0][:2]
            reg2 = (max(x0 - step, 0), max(y0 - step, 0), min(x0 + bw + step, fw), min(y0 + bh + step, fh))
            b2 = _refine(frame, reg2, (bw, bh), 1, L_model, kind=kind, gray=gray, scales=scales_full,
                         weights=weights, eps=eps)
            n_windows += b2[2]
            if b2[1] <= best[1]:
                best = b2
        refined.append((*best[0], best[1]))
    refined = np.unique(np.array(refined, dtype=np.float64), axis=0)
    refined = refined[np.argsort(refined[:, 4], kind="stable")]
    bx0, by0, bx1, by1, d = refined[0]
    cands = np.column_stack([refined[:, 0], refined[:, 1], refined[:, 2] - refined[:, 0],
                             refined[:, 3] - refined[:, 1], refined[:, 4]])
    return SearchResult((float(bx0), float(by0), float(bx1 - bx0), float(by1 - by0)), float(d), n_windows, cands)


def _refine(frame, region, size, stride, L_model, *, kind, gray, scales, weights, eps):
    x0, y0, x1, y1 = (int(v) for v in region)
    ic = _integral(frame, (x0, y0, x1, y1), kind=kind, gray=gray, weights=weights)
    b = window_grid((x0, y0, x1, y1), (int(size[0]), int(size[1])), stride)
    if len(b) == 0:
        return (x0, y0, x0 + int(size[0]), y0 + int(size[1])), math.inf, 0
    dist = window_distances(ic, b, L_model, scales, eps=eps)
    k = int(np.argmin(dist))
    return tuple(int(v) for v in b[k]), float(dist[k]), len(b)


def particle_distances(frame: np.ndarray, boxes: np.ndarray, L_model: np.ndarray, *, kind: str, gray: bool,
                       scales: np.ndarray, weights: np.ndarray | None = None, eps: float = EPS) -> np.ndarray:
    """Eq. 30 for a batch of particle boxes ``(N, 4)`` ``(x, y, w, h)``: one integral image over the
    region they reach, one batched eigen-decomposition — a likelihood other trackers can fuse
    (e.g. ``exp(-d^2 / (2 sigma^2))``)."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    fh, fw = frame.shape[:2]
    win = np.stack([np.round(b[:, 0]), np.round(b[:, 1]), np.round(b[:, 0] + b[:, 2]),
                    np.round(b[:, 1] + b[:, 3])], axis=1).astype(np.int64)
    win[:, [0, 2]] = np.clip(win[:, [0, 2]], 0, fw)
    win[:, [1, 3]] = np.clip(win[:, [1, 3]], 0, fh)
    x0, y0 = int(win[:, 0].min()), int(win[:, 1].min())
    x1, y1 = int(win[:, 2].max()), int(win[:, 3].max())
    if x1 - x0 < 2 or y1 - y0 < 2:
        return np.full(len(b), np.inf)
    ic = _integral(frame, (x0, y0, x1, y1), kind=kind, gray=gray, weights=weights)
    return window_distances(ic, win, L_model, scales, eps=eps)


def _integral(frame, region, *, kind, gray, weights, margin: int = 2) -> IntegralCovariance:
    """Integral covariance over ``region`` plus a ``margin`` (so derivative filters at the region's
    edge see real pixels, as they do inside a larger search)."""
    fh, fw = frame.shape[:2]
    x0, y0, x1, y1 = region
    px0, py0, px1, py1 = max(x0 - margin, 0), max(y0 - margin, 0), min(x1 + margin, fw), min(y1 + margin, fh)
    z = covariance_features(frame[py0:py1, px0:px1], kind=kind, gray=gray, origin=(px0, py0))
    m = None if weights is None else weights[py0:py1, px0:px1]
    return IntegralCovariance(z, m, origin=(px0, py0))
