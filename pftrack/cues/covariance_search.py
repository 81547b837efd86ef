"""Covariance matching: scoring windows against a model, coarse-to-fine search, and a batched
particle likelihood (book ch. 6 §4.2; ``shared/book/ch06.md`` §1.9).

The search of Porikli, Tuzel & Meer (2006) is exhaustive; its scales and stride are not
given.  Ours (ch06.md §1.9, proposed):

1. **coarse**: the region is decimated (area averaging) by ``f = max(1, min(w, h) // coarse_side)``
   so the target spans about ``coarse_side`` pixels across; every window of the target's size
   times ``{1/1.1, 1, 1.1}`` on a ``coarse_stride`` lattice of that image is scored (one batched
   eigen-decomposition);
2. **refine**: around the ``refine_top`` best coarse windows (after suppressing near-duplicates,
   per scale), windows at the model's pitch (full resolution for targets up to ``2 x 32`` px across,
   decimated above, so the cost does not grow with the target's area) on a lattice of step about
   a quarter of the coarse stride are scored, then the best one's neighbourhood at stride 1.

All windows are scored by the model's distance (:class:`~pftrack.cues.covariance.SPDModel`: Eq. 30,
``||log C_window - log C_model||_F``, or Eq. 28 for an affine-invariant model), after the
standardisation of :func:`pftrack.cues.covariance.standardize`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .covariance import EPS, IntegralCovariance, SPDModel, covariance_features, region_covariance, standardize


def pitch_for(size: tuple[float, float], side: int) -> int:
    """Integer decimation that makes the smaller side of ``size`` about ``side`` pixels (at least 1)."""
    return max(1, int(min(size) // side))


def derivative_scales(image: np.ndarray, *, kind: str, gray: bool) -> np.ndarray:
    """The standardisation scales of :func:`pftrack.cues.covariance.feature_scales` for a whole
    image, from float32 derivative images only (fast)."""
    g = (cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image).astype(np.float32)
    orders = [(1, 0), (0, 1)] + ([(2, 0), (0, 2)] if kind == "porikli9" else [])
    n_colour = 1 if gray else 3
    s = np.ones(2 + n_colour + len(orders))
    s[2:2 + n_colour] = 255.0
    for k, (dx, dy) in enumerate(orders):
        s[2 + n_colour + k] = max(float(np.abs(cv2.Sobel(g, cv2.CV_32F, dx, dy, ksize=1)).std()), 1.0)
    return s


@dataclass
class Level:
    """A frame decimated by an integer ``pitch`` (area averaging), with its foreground weights and
    standardisation scales; windows at this level are in its own pixel units."""

    image: np.ndarray
    pitch: int
    scales: np.ndarray
    weights: np.ndarray | None = None

    @classmethod
    def build(cls, frame: np.ndarray, pitch: int, *, kind: str, gray: bool,
              weights: np.ndarray | None = None) -> "Level":
        fh, fw = frame.shape[:2]
        size = (max(1, fw // pitch), max(1, fh // pitch))
        img = frame if pitch == 1 else cv2.resize(frame, size, interpolation=cv2.INTER_AREA)
        wts = None
        if weights is not None:
            wts = weights.astype(np.float32)
            if pitch > 1:
                wts = cv2.resize(wts, size, interpolation=cv2.INTER_AREA)
        return cls(img, pitch, derivative_scales(img, kind=kind, gray=gray), wts)

    def to_level(self, box) -> tuple[int, int, int, int]:
        """Frame ``(x, y, w, h)`` -> level window ``(x0, y0, x1, y1)`` (integers, clipped)."""
        return tuple(int(v) for v in self.to_level_batch(np.asarray(box, dtype=np.float64).reshape(1, 4))[0])

    def to_level_batch(self, boxes: np.ndarray) -> np.ndarray:
        """:meth:`to_level` for ``(N, 4)`` frame boxes at once: ``(N, 4)`` int64 windows."""
        b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4) / self.pitch
        hh, ww = self.image.shape[:2]
        x0, y0 = np.round(b[:, 0]).astype(np.int64), np.round(b[:, 1]).astype(np.int64)
        x1 = x0 + np.maximum(2, np.round(b[:, 2]).astype(np.int64))
        y1 = y0 + np.maximum(2, np.round(b[:, 3]).astype(np.int64))
        return np.stack([np.maximum(x0, 0), np.maximum(y0, 0), np.minimum(x1, ww), np.minimum(y1, hh)], axis=1)

    def integral(self, region: tuple[int, int, int, int], *, kind: str, gray: bool,
                 margin: int = 2) -> IntegralCovariance:
        """Integral covariance over a level ``region`` plus a ``margin`` (so derivative filters at the
        region's edge see real pixels, as they do inside a larger search)."""
        hh, ww = self.image.shape[:2]
        x0, y0, x1, y1 = region
        px0, py0, px1, py1 = max(x0 - margin, 0), max(y0 - margin, 0), min(x1 + margin, ww), min(y1 + margin, hh)
        z = covariance_features(self.image[py0:py1, px0:px1], kind=kind, gray=gray, origin=(px0, py0))
        m = None if self.weights is None else self.weights[py0:py1, px0:px1]
        return IntegralCovariance(z, m, origin=(px0, py0))


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


def window_distances(icov: IntegralCovariance, boxes: np.ndarray, model: SPDModel, scales: np.ndarray, *,
                     min_fraction: float = 0.3, eps: float = EPS) -> np.ndarray:
    """The model's distance (Eq. 30 or 28) for each window (``inf`` where the window's weight is below
    ``min_fraction`` of its area or ``d + 1`` pixels)."""
    if len(boxes) == 0:
        return np.empty(0)
    C, W = icov.cov(boxes)
    sizes = (boxes[:, 2:] - boxes[:, :2]).astype(np.float64)
    area = sizes[:, 0] * sizes[:, 1]
    ok = (W >= icov.d + 1) & (W >= min_fraction * area) & np.all(np.isfinite(C), axis=(1, 2))
    out = np.full(len(boxes), np.inf)
    if np.any(ok):
        Cs = standardize(C[ok], sizes[ok], scales, eps=eps)
        out[ok] = model.distance(Cs)
    return out


def window_covariance(level: Level, box, *, kind: str, gray: bool, eps: float = EPS,
                      margin: int = 2) -> np.ndarray | None:
    """The standardised covariance of the level window nearest to the frame ``box`` (None if empty).

    One window needs no integral images: the features of the window plus ``margin`` (as
    :meth:`Level.integral` computes them, so derivatives at the window's edge see real pixels), then the
    weighted covariance of the window's pixels, centred on their weighted mean (two passes)."""
    win = level.to_level(box)
    x0, y0, x1, y1 = win
    if x1 - x0 < 2 or y1 - y0 < 2:
        return None
    hh, ww = level.image.shape[:2]
    px0, py0, px1, py1 = max(x0 - margin, 0), max(y0 - margin, 0), min(x1 + margin, ww), min(y1 + margin, hh)
    z = covariance_features(level.image[py0:py1, px0:px1], kind=kind, gray=gray, origin=(px0, py0))
    d = z.shape[-1]
    zw = z[y0 - py0:y1 - py0, x0 - px0:x1 - px0].reshape(-1, d).astype(np.float64)
    m = np.ones(zw.shape[0]) if level.weights is None else level.weights[y0:y1, x0:x1].astype(np.float64).ravel()
    W = float(m.sum())
    if not W >= d + 1:  # too little weight for a d x d covariance
        return None
    C = region_covariance(zw, m)
    if not np.all(np.isfinite(C)):
        return None
    return standardize(C[None], np.array([[x1 - x0, y1 - y0]]), level.scales, eps=eps)[0]


@dataclass(frozen=True)
class SearchResult:
    box: tuple[float, float, float, float]
    distance: float
    n_windows: int
    candidates: np.ndarray  # (k, 5): x, y, w, h, distance of the refined candidates, best first


def _suppress(centres: np.ndarray, dist: np.ndarray, k: int, radius: float) -> np.ndarray:
    """Indices of up to ``k`` best windows whose centres are at least ``radius`` apart."""
    order = np.argsort(dist, kind="stable")
    order = order[np.isfinite(dist[order])]
    keep: list[int] = []
    for i in order:
        if all(np.hypot(*(centres[i] - centres[j])) >= radius for j in keep):
            keep.append(int(i))
            if len(keep) >= k:
                break
    return np.array(keep, dtype=np.int64)


def search(frame: np.ndarray, model: SPDModel, size: tuple[float, float], *, kind: str, gray: bool,
           refine_pitch: int = 1, region: tuple[int, int, int, int] | None = None,
           weights: np.ndarray | None = None, scale_factors: tuple[float, ...] = (1 / 1.1, 1.0, 1.1),
           coarse_side: int = 8, coarse_stride: int = 2, refine_top: int = 6, eps: float = EPS,
           refine_level: Level | None = None, seeds=(), coarse_budget: int = 0) -> SearchResult:
    """Coarse-to-fine covariance search for the window nearest to ``model``.

    ``region`` (frame integers ``x0, y0, x1, y1``; default the whole frame) bounds the search;
    ``weights`` (frame-sized, optional) is a foreground weight or mask multiplying every pixel.
    The refinement runs at ``refine_pitch`` (the pitch the model was built at; a prebuilt
    ``refine_level`` of that pitch may be passed) around the best coarse windows and around every frame box
    ``(x, y, w, h)`` of ``seeds`` (the last box, say: the coarse level's covariances are not the model's, and on
    grey input, with one intensity channel, their ranking can miss the target altogether).  Boxes are returned in
    frame pixels. ``coarse_budget`` (> 0) bounds the coarse level's pixels: the region is decimated at least so far
    that it holds no more than that many (a small or thin target in a large frame would otherwise give a coarse level
    of full resolution and tens of thousands of windows a scale); 0 sets no bound.
    """
    fh, fw = frame.shape[:2]
    rx0, ry0, rx1, ry1 = region if region is not None else (0, 0, fw, fh)
    rx0, ry0, rx1, ry1 = max(0, rx0), max(0, ry0), min(fw, rx1), min(fh, ry1)
    w, h = size
    f = max(pitch_for(size, coarse_side), refine_pitch)
    if coarse_budget > 0:
        f = max(f, int(math.ceil(math.sqrt((rx1 - rx0) * (ry1 - ry0) / coarse_budget))))
    none = SearchResult((float(rx0), float(ry0), float(w), float(h)), math.inf, 0, np.empty((0, 5)))
    if rx1 - rx0 < 2 * f or ry1 - ry0 < 2 * f:
        return none
    # --- coarse level over the region
    coarse = Level.build(frame[ry0:ry1, rx0:rx1], f, kind=kind, gray=gray,
                         weights=None if weights is None else weights[ry0:ry1, rx0:rx1])
    ch, cw = coarse.image.shape[:2]
    ic = coarse.integral((0, 0, cw, ch), kind=kind, gray=gray, margin=0)
    cand_boxes, cand_dist = [], []
    n_windows = 0
    for s in scale_factors:
        b = window_grid((0, 0, cw, ch), (max(2, int(round(w * s / f))), max(2, int(round(h * s / f)))),
                        coarse_stride)
        cand_dist.append(window_distances(ic, b, model, coarse.scales, eps=eps))
        n_windows += len(b)
        fb = np.empty((len(b), 4), dtype=np.float64)  # frame (x, y, w, h) at this scale
        fb[:, 0] = rx0 + b[:, 0] * f
        fb[:, 1] = ry0 + b[:, 1] * f
        fb[:, 2] = w * s
        fb[:, 3] = h * s
        cand_boxes.append(fb)
    if n_windows == 0:
        return none
    # the best few of each scale (a sub-window of the target can beat a misaligned coarse window of
    # the right scale, so the scales do not compete before refinement)
    per_scale = max(1, int(math.ceil(refine_top / len(scale_factors))))
    kept = []
    for b, d in zip(cand_boxes, cand_dist):
        centres = np.column_stack([b[:, 0] + b[:, 2] / 2, b[:, 1] + b[:, 3] / 2])
        for i in _suppress(centres, d, per_scale, 0.25 * min(w, h)):
            kept.append(b[i])
    kept.extend(np.asarray(sd, dtype=np.float64) for sd in seeds)
    if not kept:
        return SearchResult(none.box, math.inf, n_windows, none.candidates)
    # --- refinement at the model's pitch around each kept window
    lv = refine_level if refine_level is not None else Level.build(frame, refine_pitch, kind=kind, gray=gray,
                                                                     weights=weights)
    r = max(1, int(math.ceil(f * coarse_stride / refine_pitch)))
    step = max(1, int(math.ceil(r / 4)))
    refined = []
    for fb in kept:
        win = lv.to_level(fb)
        best, dist, n = _refine(lv, win, r, step, model, kind=kind, gray=gray, eps=eps)
        n_windows += n
        refined.append((*best, dist))
    refined = np.unique(np.array(refined, dtype=np.float64), axis=0)
    refined = refined[np.argsort(refined[:, 4], kind="stable")]
    if step > 1 and math.isfinite(refined[0, 4]):
        best, dist, n = _refine(lv, tuple(int(v) for v in refined[0, :4]), step, 1, model, kind=kind, gray=gray,
                                eps=eps)
        n_windows += n
        if dist <= refined[0, 4]:
            refined[0] = (*best, dist)
    p = lv.pitch
    cands = np.column_stack([refined[:, 0] * p, refined[:, 1] * p, (refined[:, 2] - refined[:, 0]) * p,
                             (refined[:, 3] - refined[:, 1]) * p, refined[:, 4]])
    return SearchResult(tuple(float(v) for v in cands[0, :4]), float(cands[0, 4]), n_windows, cands)


def _refine(lv: Level, win, r: int, stride: int, model, *, kind, gray, eps):
    """Best window of ``win``'s size within ``+-r`` level pixels of it, on a ``stride`` lattice."""
    hh, ww = lv.image.shape[:2]
    x0, y0, x1, y1 = win
    bw, bh = x1 - x0, y1 - y0
    reg = (max(x0 - r, 0), max(y0 - r, 0), min(x1 + r, ww), min(y1 + r, hh))
    b = window_grid(reg, (bw, bh), stride)
    if len(b) == 0:
        return (x0, y0, x1, y1), math.inf, 0
    ic = lv.integral(reg, kind=kind, gray=gray)
    dist = window_distances(ic, b, model, lv.scales, eps=eps)
    k = int(np.argmin(dist))
    return tuple(int(v) for v in b[k]), float(dist[k]), len(b)


def particle_distances(level: Level, boxes: np.ndarray, model: SPDModel, *, kind: str, gray: bool,
                       eps: float = EPS) -> np.ndarray:
    """The model's distance for a batch of frame boxes ``(N, 4)`` ``(x, y, w, h)``: one integral image
    over the level region they reach, one batched eigen-decomposition — a likelihood other trackers
    can fuse (e.g. ``exp(-d^2 / (2 sigma^2))``)."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    win = level.to_level_batch(b)
    x0, y0 = int(win[:, 0].min()), int(win[:, 1].min())
    x1, y1 = int(win[:, 2].max()), int(win[:, 3].max())
    if x1 - x0 < 2 or y1 - y0 < 2:
        return np.full(len(b), np.inf)
    ic = level.integral((x0, y0, x1, y1), kind=kind, gray=gray)
    return window_distances(ic, win, model, level.scales, eps=eps)
