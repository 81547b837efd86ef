"""``graphcut``: an object tracked as a segmentation mask by graph cuts (book ch. 9).

Book *Object Tracking*, ch. 9 (``shared/book/ch09.md``).  Every frame:

1. the region of interest is the bounding box of the previous mask dilated by ``r`` pixels
   (``r = max(r_min, 1.5 |v| + 0.05 sqrt(area))``, L8713-8724); outside the dilated mask is hard background;
2. the graph of :mod:`.graphcut` is built on the ROI and cut (temporal seeding from the previous mask);
3. if more than 2 % of the dilated region's border ends inside the cut, ``r`` is doubled and the cut repeated
   (at most twice).

The histograms come from the first mask (``init`` runs GrabCut in the box, or takes a mask with
:meth:`GraphCutTracker.init_mask`), and are blended with rate ``alpha`` when the area changes by less than
30 %.  ``lost`` when the mask vanishes, collapses below ``lost_area`` of the initial area, or loses its colour
support (``lost_support``); while lost the whole frame is cut without temporal seeds on a coarse grid, and
tracking resumes when a component of at least 30 % of the last good area, with enough support, appears.
``info["mask"]`` is the full-frame boolean mask.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Literal

import cv2
import numpy as np

from ..geometry import Box
from ..params import Params, param
from ..trackers.base import Tracker, TrackState
from . import graphcut as G


@dataclass(frozen=True, kw_only=True)
class GraphCutParams(Params):
    """Parameters of ``graphcut`` (ch. 9; defaults of ch09.md §2, lam, boundary, r_min and alpha chosen on the tune
    sequence davis16_dog)."""

    lam: float = param(2.0, ge=0, le=1e4, doc="Weight lambda of the regional term in E = lam R + B (Eq. 3).")
    boundary: Literal["exp", "linear", "bj"] = param("exp", doc=(
        "n-link weight: exp(-|p-q|) (Eq. 8), 1-|p-q|/3 (Eq. 7), or Boykov-Jolly exp(-beta|p-q|^2)/dist."))
    bins: int = param(16, ge=2, le=64, doc="Colour histogram bins per RGB channel.")
    r_min: float = param(20.0, ge=1, le=500, doc=(
        "Smallest ROI dilation in pixels at 640 px width (scaled with the width); ch09.md proposes 10, 20 re-cuts less "
        "often at the same accuracy on davis16_dog."))
    alpha: float = param(0.0, ge=0, le=1, doc=(
        "Histogram update rate (0 = the chapter's fixed model; 0.05 drifted into the background on davis16_dog: J 0.61 "
        "against 0.69)."))
    bkg_distance: bool = param(True, doc="Symmetric temporal seeding: also the distance transform of the background.")
    soft_seeds: bool = param(True, doc=(
        "Seed from the distance transform (Table 3); False = hard seeds on the previous mask."))
    lost_area: float = param(0.1, gt=0, le=1, doc=(
        "Lost when the mask's area falls below this fraction of the initial area."))
    lost_support: float = param(0.25, ge=0, le=1, doc=(
        "Lost when the mask's colour support (mean object-histogram value H_obj/max over its pixels) falls below "
        "this fraction of the first mask's: the temporal seeds alone can hold a mask on a frame that no longer "
        "shows the object."))
    backend: Literal["scipy", "pymaxflow"] = param("scipy", doc=(
        "Max-flow solver: SciPy's Dinic (BSD) or PyMaxflow (GPL, optional)."))
    max_pixels: int = param(60000, ge=0, le=100_000_000, doc=(
        "Speed bound: a ROI with more pixels is cut on a grid scaled down to this many pixels and the mask "
        "scaled back (0 = always full resolution)."))


def dilate_by(mask: np.ndarray, r: float) -> np.ndarray:
    """Pixels within Euclidean distance ``r`` of the mask (a disc dilation, via one distance transform)."""
    if not mask.any():
        return mask.copy()
    d = cv2.distanceTransform((~mask).astype(np.uint8), cv2.DIST_L2, 5)
    return d <= r


def largest_component(mask: np.ndarray) -> np.ndarray:
    n, lab, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
    if n <= 1:
        return np.zeros_like(mask, bool)
    k = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    return lab == k


#: the seed of OpenCV's random state before the first mask's GrabCut (its k-means++ start)
GRABCUT_SEED = 0


def grabcut_init(frame: np.ndarray, box) -> np.ndarray:
    """The first mask: GrabCut in the box (5 iterations), as ch09.md §1.4 proposes; the box itself where GrabCut
    finds less than 4 foreground pixels or has no background to learn from (a box covering the whole frame)."""
    h, w = frame.shape[:2]
    x, y, bw, bh = (round(v) for v in box)
    x, y = max(x, 0), max(y, 0)
    bw, bh = max(min(bw, w - x), 2), max(min(bh, h - y), 2)
    mask = np.zeros((h, w), np.uint8)
    bgd, fgd = np.zeros((1, 65), np.float64), np.zeros((1, 65), np.float64)
    if bw * bh < w * h:  # GrabCut learns its background model outside the box: none when the box is the frame
        # its colour models start from k-means++ on OpenCV's random state, which carries over from whatever ran
        # before in the thread: seeded, the same box gives the same first mask
        cv2.setRNGSeed(GRABCUT_SEED)
        cv2.grabCut(frame, mask, (x, y, bw, bh), bgd, fgd, 5, cv2.GC_INIT_WITH_RECT)
    m = (mask == cv2.GC_FGD) | (mask == cv2.GC_PR_FGD)
    if m.sum() < 4:
        m = np.zeros((h, w), bool)
        m[y:y + bh, x:x + bw] = True
    return largest_component(m)


class GraphCutTracker(Tracker):
    name = "graphcut"
    Params = GraphCutParams
    stochastic = False

    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        return self.init_mask(frame, grabcut_init(frame, box), _validated=True)

    def init_mask(self, frame: np.ndarray, mask: np.ndarray, _validated: bool = False) -> TrackState:
        """Start from a given first mask (the semi-supervised protocol of DAVIS)."""
        if not _validated:
            from ..errors import InputError
            from ..frames import as_bgr_uint8

            frame = as_bgr_uint8(frame, where="init frame")
            if mask.shape[:2] != frame.shape[:2]:
                raise InputError(f"mask size {mask.shape[1]}x{mask.shape[0]} differs from the frame's "
                                 f"{frame.shape[1]}x{frame.shape[0]}")
            if not np.any(mask):
                raise InputError("the first mask is empty")
            self._shape = frame.shape[:2]
            self.frame_index = 0
        p = self.params
        self.mask = mask.astype(bool)
        bins = G.color_bins(frame, p.bins)
        self.H_obj = G.color_hist(bins, self.mask, p.bins)
        ring = dilate_by(self.mask, 15) & ~self.mask
        self.H_bkg = G.color_hist(bins, ring if ring.any() else ~self.mask, p.bins)
        self.area0 = self.last_area = float(self.mask.sum())
        self.support0 = max(self._support(bins, self.mask), 1e-12)
        self.velocity = np.zeros(2)
        self.centre = self._centroid(self.mask)
        self.lost = False
        self.timing = {}
        return self._state(frame, bins)

    def _support(self, bins, mask) -> float:
        if not mask.any():
            return 0.0
        return float(np.mean(self.H_obj[bins[mask]]) / max(self.H_obj.max(), 1e-12))

    @staticmethod
    def _centroid(mask) -> np.ndarray:
        ys, xs = np.nonzero(mask)
        return np.array([xs.mean(), ys.mean()]) if len(xs) else np.zeros(2)

    def _cut_roi(self, frame, bins_full, r: float):
        p = self.params
        h, w = frame.shape[:2]
        shifted = self.mask
        if np.any(self.velocity):
            M = np.float32([[1, 0, self.velocity[0]], [0, 1, self.velocity[1]]])
            shifted = cv2.warpAffine(self.mask.astype(np.uint8), M, (w, h), flags=cv2.INTER_NEAREST).astype(bool)
            shifted |= self.mask
        allowed = dilate_by(shifted, r)
        ys, xs = np.nonzero(allowed)
        y0, y1 = max(ys.min() - 1, 0), min(ys.max() + 2, h)
        x0, x1 = max(xs.min() - 1, 0), min(xs.max() + 2, w)
        sl = (slice(y0, y1), slice(x0, x1))
        img, bins, prev, allow = frame[sl], bins_full[sl], self.mask[sl], allowed[sl]
        npx = img.shape[0] * img.shape[1]
        f = np.sqrt(p.max_pixels / npx) if (p.max_pixels and npx > p.max_pixels) else 1.0
        roi_shape = img.shape[:2]
        if f < 1.0:                       # cut on a coarser grid, scale the mask back
            size = (max(round(img.shape[1] * f), 4), max(round(img.shape[0] * f), 4))
            img = cv2.resize(img, size, interpolation=cv2.INTER_AREA)
            bins = G.color_bins(img, p.bins)
            prev = cv2.resize(prev.astype(np.uint8), size, interpolation=cv2.INTER_NEAREST).astype(bool)
            allow = cv2.resize(allow.astype(np.uint8), size, interpolation=cv2.INTER_NEAREST).astype(bool)
        t0 = time.perf_counter()
        Ro, Rb = G.regional(bins, self.H_obj, self.H_bkg)
        nl = G.nlink_weights(img, p.boundary)
        K = G.hard_capacity(nl, img.shape[:2])
        hard_bkg = ~allow        # the ROI's border lies outside the dilated mask unless it is the frame's edge
        if p.soft_seeds:
            Do, Db = G.seed_maps(prev)
            cs, ct = G.tlink_caps(Ro, Rb, p.lam, Do, Db if p.bkg_distance else None, hard_bkg, None, K)
        else:
            inner = cv2.erode(prev.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
            cs, ct = G.tlink_caps(Ro, Rb, p.lam, None, None, hard_bkg | (~prev & ~allow), inner, K)
        t1 = time.perf_counter()
        cut = G.min_cut(cs, ct, nl, p.backend)
        t2 = time.perf_counter()
        self.timing = {"build_ms": 1000 * (t1 - t0), "cut_ms": 1000 * (t2 - t1), "roi_pixels": int(npx),
                       "graph_pixels": int(img.shape[0] * img.shape[1])}
        if f < 1.0:
            cut = cv2.resize(cut.astype(np.float32), roi_shape[::-1], interpolation=cv2.INTER_LINEAR) > 0.5
            allow = allowed[sl]
        full = np.zeros((h, w), bool)
        full[sl] = cut & allow
        border = allow & ~cv2.erode(allow.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
        ring = border & ~self._frame_edge(sl, (h, w), roi_shape)
        touches = int(np.count_nonzero(cut & ring)) > 0.02 * max(int(np.count_nonzero(ring)), 1)
        return full, touches

    @staticmethod
    def _frame_edge(sl, shape, roi_shape) -> np.ndarray:
        e = np.zeros(roi_shape, bool)
        if sl[0].start == 0:
            e[0, :] = True
        if sl[0].stop == shape[0]:
            e[-1, :] = True
        if sl[1].start == 0:
            e[:, 0] = True
        if sl[1].stop == shape[1]:
            e[:, -1] = True
        return e

    def _update(self, frame: np.ndarray) -> TrackState:
        p = self.params
        w = frame.shape[1]
        bins = G.color_bins(frame, p.bins)
        if self.lost:
            return self._reacquire(frame, bins)
        area = max(float(self.mask.sum()), 1.0)
        r = max(p.r_min * w / 640.0, np.ceil(1.5 * np.linalg.norm(self.velocity) + 0.05 * np.sqrt(area)))
        self.recuts = 0
        for attempt in range(3):
            new, touches = self._cut_roi(frame, bins, r)
            if not touches:
                break
            r *= 2
            self.recuts = attempt + 1
        new = largest_component(new)
        a = float(new.sum())
        if a < p.lost_area * self.area0 or a == 0 or self._support(bins, new) < p.lost_support * self.support0:
            self.lost = True
            return self._state(frame, bins)
        c = self._centroid(new)
        self.velocity = c - self.centre
        self.centre = c
        if p.alpha > 0 and abs(a - self.last_area) < 0.3 * self.last_area:
            self.H_obj = (1 - p.alpha) * self.H_obj + p.alpha * G.color_hist(bins, new, p.bins)
            ring = dilate_by(new, 15) & ~new
            if ring.any():
                self.H_bkg = (1 - p.alpha) * self.H_bkg + p.alpha * G.color_hist(bins, ring, p.bins)
        self.mask, self.last_area = new, a
        return self._state(frame, bins)

    def _reacquire(self, frame, bins) -> TrackState:
        """While lost: cut the whole frame without temporal seeds, on a grid of at most a quarter of ``max_pixels``
        (without seeds the max flow is several times slower per node, and a coarse blob is enough to resume),
        and resume on a large enough component with enough colour support."""
        p = self.params
        h, w = frame.shape[:2]
        img, b = frame, bins
        budget = p.max_pixels // 4
        f = np.sqrt(budget / (h * w)) if (budget and h * w > budget) else 1.0
        if f < 1.0:
            img = cv2.resize(frame, (max(round(w * f), 4), max(round(h * f), 4)), interpolation=cv2.INTER_AREA)
            b = G.color_bins(img, p.bins)
        Ro, Rb = G.regional(b, self.H_obj, self.H_bkg)
        nl = G.nlink_weights(img, p.boundary)
        cs, ct = G.tlink_caps(Ro, Rb, p.lam)
        cut = G.min_cut(cs, ct, nl, p.backend)
        if f < 1.0:
            cut = cv2.resize(cut.astype(np.float32), (w, h), interpolation=cv2.INTER_LINEAR) > 0.5
        comp = largest_component(cut)
        if comp.sum() >= 0.3 * self.last_area and self._support(bins, comp) >= p.lost_support * self.support0:
            self.mask, self.lost = comp, False
            self.centre, self.velocity = self._centroid(comp), np.zeros(2)
        return self._state(frame, bins)

    def _state(self, frame, bins) -> TrackState:
        m = self.mask
        ys, xs = np.nonzero(m)
        if len(xs):
            box = (float(xs.min()), float(ys.min()), float(xs.max() - xs.min() + 1), float(ys.max() - ys.min() + 1))
            Ro, Rb = G.regional(bins[ys, xs], self.H_obj, self.H_bkg)
            score = float(np.mean(Ro / np.maximum(Ro + Rb, 1e-12)))
        else:
            box, score = (0.0, 0.0, 1.0, 1.0), 0.0
        return TrackState(box=box, score=0.0 if self.lost else score, lost=self.lost,
                          info={"mask": m.copy(), "recuts": getattr(self, "recuts", 0), **self.timing})


REGISTRY_ENTRIES = [
    ("graphcut", GraphCutTracker,
     ("The object as a segmentation mask: graph cut of colour-histogram t-links and contrast n-links on a ROI "
      "around the dilated previous mask, seeded by its distance transform (book ch. 9); info['mask']"), {}),
]
