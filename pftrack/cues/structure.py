"""A structural cue for colour particle filters: normalised cross-correlation of small grey patches.

Colour histograms discard where the colours are; a grey target under changing light
has almost no colour to describe.  This cue keeps the layout: every particle's box is
resampled to a small grey patch (about ``template_pixels`` pixels, the box's aspect)
and compared with a reference patch by the zero-mean normalised cross-correlation of
book ch. 14 (eq. NCC, ``pftrack.cues.template``):

    r(B) = sum (p - mean p)(t - mean t) / sqrt(sum (p - mean p)^2 * sum (t - mean t)^2)  in [-1, 1]

``r`` is invariant to a gain and an offset of the grey levels, so a global
illumination drift leaves it unchanged (ch. 14's reason for preferring NCC to SAD).
Optional per-pixel weights (:func:`kernel_weights`) make it a weighted NCC.

Speed: the region the particles cover (with a margin, so that the estimate's box later in
the frame finds it too) is block-averaged once per frame to about the patch resolution
(:func:`reduce_region`, :mod:`pftrack.cues.reduced_region`: exact block means for small blocks, a
spread subset of each block's pixels for large ones, so the cost does not grow with the box), and one
compiled pass (:func:`ncc_reduced`) samples every box bilinearly and accumulates its NCC
with every reference.  Without Numba the same is one
``cv2.remap`` for all boxes and a matrix product.

The reference is the first frame's patch, updated by a gated running mean (the
caller decides when; :meth:`StructureCue.update` can also refuse patches that no
longer resemble the first one), with the first patch kept as an anchor: the score is
the larger of the correlations with the anchor and with the running reference, so a
bad update cannot wipe out what the target looked like at the start (the drift
problem of template trackers, ch. 14 §4).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .._numba import numba_enabled
from ..geometry import inside_cells
from .ncc_kernels import _ncc_boxes, _ncc_one
from .reduced_region import Reduced, box_bounds, gray_region, reduce_region, reduced_for, reduction_factor
from .structure_search import propose_centres

__all__ = ["Reduced", "StructureCue", "box_bounds", "gray_region", "kernel_weights", "ncc_reduced", "ncc_scores",
           "patch_shape", "reduce_region", "reduction_factor", "sample_boxes", "sample_reduced", "standardize",
           "weighted_templates"]


def patch_shape(w: float, h: float, pixels: int) -> tuple[int, int]:
    """``(ph, pw)`` of a patch with about ``pixels`` pixels and the aspect of a ``w`` x ``h`` box (each >= 4)."""
    w, h = max(float(w), 1.0), max(float(h), 1.0)
    a = math.sqrt(pixels / (w * h))
    return max(4, int(round(h * a))), max(4, int(round(w * a)))


def _maps(red: Reduced, ell: np.ndarray, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Sampling coordinates (reduced-image pixel indices) of every box's patch: two ``(N, ph*pw)`` arrays."""
    ph, pw = shape
    n = ell.shape[0]
    u, v = _grid(shape)  # -1..1 across the box
    k = float(red.k)
    if n == 1:  # one box (the estimate's patch): the same numbers with fewer temporaries
        e = ell[0]
        mx1 = ((e[0] - red.x0) / k - 0.5 + u * (e[2] / k)).astype(np.float32)
        my1 = ((e[1] - red.y0) / k - 0.5 + v * (e[3] / k)).astype(np.float32)
        mx = np.empty((ph, pw), np.float32)
        my = np.empty((ph, pw), np.float32)
        mx[:] = mx1
        my[:] = my1[:, None]
        return mx.reshape(1, -1), my.reshape(1, -1)
    cx = (ell[:, 0] - red.x0) / k - 0.5
    cy = (ell[:, 1] - red.y0) / k - 0.5
    mx = np.empty((n, ph, pw), np.float32)
    my = np.empty((n, ph, pw), np.float32)
    mx[...] = (cx[:, None] + u[None, :] * (ell[:, 2:3] / k))[:, None, :]
    my[...] = (cy[:, None] + v[None, :] * (ell[:, 3:4] / k))[:, :, None]
    return mx.reshape(n, ph * pw), my.reshape(n, ph * pw)


def sample_reduced(red: Reduced, ellipses: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Every ellipse's bounding box ``(cx, cy, hx, hy)`` bilinearly sampled from a reduced region to
    ``shape`` grey pixels: ``(N, ph*pw)`` float32 (pixels outside the region repeat its border)."""
    ell = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
    ph, pw = shape
    if ell.shape[0] == 0:
        return np.empty((0, ph * pw), dtype=np.float32)
    mx, my = _maps(red, ell, shape)
    return cv2.remap(red.gray.astype(np.float32, copy=False), mx, my, cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_REPLICATE)


def sample_boxes(frame: np.ndarray, roi: tuple[int, int, int, int], ellipses: np.ndarray,
                 shape: tuple[int, int]) -> np.ndarray:
    """Every ellipse's bounding box resampled to ``shape`` grey pixels: ``(N, ph*pw)`` float32.

    The part of ``roi`` the boxes cover is block-averaged by :func:`reduction_factor`
    (a low-pass filter before sampling), then one bilinear remap samples all boxes.
    """
    ell = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
    if ell.shape[0] == 0:
        return np.empty((0, shape[0] * shape[1]), dtype=np.float32)
    return sample_reduced(reduced_for(frame, roi, ell, shape), ell, shape)


def kernel_weights(shape: tuple[int, int], kind: str = "kernel") -> np.ndarray:
    """Per-pixel weights of a ``(ph, pw)`` patch, mean 1: ``"kernel"`` is the Epanechnikov profile
    ``max(0, 1 - u^2 - v^2)`` of the ellipse inscribed in the box (the colour cue's region and kernel,
    Nummiaro et al. Eq. 2: the box's corners are background); ``"uniform"`` is 1."""
    ph, pw = shape
    if kind == "uniform":
        return np.ones(ph * pw)
    u = ((np.arange(pw) + 0.5) / pw - 0.5) * 2.0
    v = ((np.arange(ph) + 0.5) / ph - 0.5) * 2.0
    w = np.maximum(1.0 - u[None, :] ** 2 - v[:, None] ** 2, 0.0).ravel()
    return w * (w.size / w.sum())


def standardize(patches: np.ndarray, floor: float = 1.0, weights: np.ndarray | None = None) -> np.ndarray:
    """Weighted zero-mean, unit-norm rows ``sqrt(w) (p - mean_w p) / norm`` (``(N, P)`` float32; ``weights``
    of mean 1, default uniform).  Rows flatter than ``floor`` grey levels of std stay near 0."""
    p = np.asarray(patches, dtype=np.float32)
    n = p.shape[1]
    if weights is None:
        z = p - p.mean(axis=1, keepdims=True)
    else:
        w = np.asarray(weights, dtype=np.float32)
        z = (p - (p @ w)[:, None] / np.float32(n)) * np.sqrt(w)[None, :]
    norm = np.sqrt(np.einsum("ij,ij->i", z, z) + np.float32(floor * floor * n))
    return z / norm[:, None]


def ncc_scores(patches: np.ndarray, templates: np.ndarray, floor: float = 1.0,
               weights: np.ndarray | None = None) -> np.ndarray:
    """Best (weighted) NCC of each patch ``(N, P)`` over templates standardised by :func:`standardize` with the
    same weights ``(K, P)``: ``(N,)`` float64.

    The small std floor of :func:`standardize` makes a flat patch score ~0 instead of an
    undefined 0/0 (a flat patch carries no structure)."""
    z = standardize(patches, floor, weights)
    t = np.atleast_2d(np.asarray(templates, dtype=np.float32))
    return np.max(z @ t.T, axis=1).astype(np.float64)


def ratio_pairs(ratios) -> list[tuple[float, float]]:
    """Half-axis ratios as ``(rx, ry)`` float pairs: a number ``r`` is ``(r, r)``, a pair is kept."""
    out = []
    for r in ratios:
        if type(r) is float:  # the common case, without np.ndim's cost
            out.append((r, r))
        elif np.ndim(r):
            out.append((float(r[0]), float(r[1])))
        else:
            out.append((float(r), float(r)))
    return out


_GRIDS: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}
_NO_WEIGHTS = np.empty(0)


def _grid(shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """``(u, v)``: the patch's sample positions across the box, -1..1 (cached per shape)."""
    g = _GRIDS.get(shape)
    if g is None:
        ph, pw = shape
        g = _GRIDS[shape] = (((np.arange(pw) + 0.5) / pw - 0.5) * 2.0, ((np.arange(ph) + 0.5) / ph - 0.5) * 2.0)
    return g


def weighted_templates(templates: np.ndarray, weights: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """``(T, w)`` for :func:`ncc_reduced`'s compiled pass: the standardised templates times ``sqrt(w)`` and
    the weights (empty for uniform ones)."""
    t = np.atleast_2d(np.asarray(templates, dtype=np.float64))
    if weights is None or np.all(np.asarray(weights) == 1.0):
        return np.ascontiguousarray(t), np.empty(0)
    w = np.asarray(weights, dtype=np.float64)
    return np.ascontiguousarray(t * np.sqrt(w)[None, :]), w


def ncc_reduced(red: Reduced, ellipses: np.ndarray, shape: tuple[int, int], templates: np.ndarray,
                floor: float = 1.0, weights: np.ndarray | None = None, *,
                prepared: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """:func:`ncc_scores` of :func:`sample_reduced`'s patches, compiled in one pass when Numba is enabled
    (``prepared``: :func:`weighted_templates` of the templates and weights, to skip that step)."""
    ell = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
    if ell.shape[0] == 0:
        return np.empty(0)
    if not numba_enabled():
        return ncc_scores(sample_reduced(red, ell, shape), templates, floor, weights)
    u, v = _grid(shape)
    tw, w = prepared if prepared is not None else weighted_templates(templates, weights)
    out = np.empty(ell.shape[0])
    _ncc_boxes(red.levels_for(ell.shape[0] * u.size * v.size), ell, float(red.x0), float(red.y0), float(red.k), u, v,
               tw, w, float(floor) ** 2, out)
    return out


class StructureCue:
    """Reference patches (an anchor and a running mean) and batched NCC scores of particle boxes.

    Within one frame the block-averaged grey region is computed once and reused by every
    later call whose boxes it covers (the estimate after the particles); call
    :meth:`new_frame` before each frame.
    """

    def __init__(self, template_pixels: int = 256, anchor: bool = True, weighting: str = "kernel"):
        self.template_pixels = int(template_pixels)
        self.anchor = bool(anchor)
        self.weighting = weighting
        self.weights = np.ones(0)
        self.shape = (0, 0)
        self._first: np.ndarray | None = None
        self._run: np.ndarray | None = None
        self._templates: np.ndarray | None = None
        self._first_std: np.ndarray | None = None
        self._reduced: Reduced | None = None
        self._prepared: tuple[np.ndarray, np.ndarray] | None = None
        self._first_prepared: tuple[np.ndarray, np.ndarray] | None = None
        self._last: tuple | None = None
        self._consts: tuple | None = None  # the weights' conversions for _refresh

    @property
    def ready(self) -> bool:
        """Has a reference been taken (:meth:`init`)?"""
        return self._templates is not None

    def new_frame(self) -> None:
        """Forget the previous frame's reduced region (and the estimate's scores on it)."""
        self._reduced = None
        self._last = None

    def init(self, frame: np.ndarray, ellipse) -> None:
        e = np.asarray(ellipse, dtype=np.float64).reshape(1, 4)
        self.new_frame()
        self.shape = patch_shape(2 * e[0, 2], 2 * e[0, 3], self.template_pixels)
        self.weights = kernel_weights(self.shape, self.weighting)
        patch = self.patch(frame, e[0])
        self._first = patch
        self._first_std = standardize(patch[None, :], weights=self.weights)  # constant: standardised once
        self._first_prepared = None
        self._consts = None
        self._run = patch.copy()
        self._refresh()

    def _region(self, frame: np.ndarray, roi, ell: np.ndarray) -> Reduced:
        """This frame's reduced region if it covers the ellipses' boxes, else a new one within ``roi`` (None: the
        boxes' own bounding rectangle)."""
        red = self._reduced
        if red is None or not red.covers(ell):
            red = self._reduced = reduced_for(frame, roi, ell, self.shape, pad_blocks=2)
        return red

    def patch(self, frame: np.ndarray, ellipse) -> np.ndarray:
        """The grey patch of one ellipse's box, ``(ph*pw,)`` float32."""
        e = np.asarray(ellipse, dtype=np.float64).reshape(1, 4)
        return sample_reduced(self._region(frame, None, e), e, self.shape)[0]

    def _refresh(self) -> None:
        """Standardise the running reference and prepare the templates for the compiled NCC: the numbers of
        :func:`standardize` and :func:`weighted_templates`, with the weights' conversions and the anchor's row
        (constant after :meth:`init`) computed once."""
        w = self.weights
        c = self._consts
        if c is None or c[0] is not w:
            w32 = np.asarray(w, dtype=np.float32)
            uniform = self.weighting == "uniform" or bool(np.all(np.asarray(w) == 1.0))
            w64 = np.asarray(w, dtype=np.float64)
            sqrt64 = np.sqrt(w64)
            first = None
            if self.anchor and self._first_std is not None:
                f64 = self._first_std.astype(np.float64)
                first = f64 if uniform else f64 * sqrt64[None, :]
            c = self._consts = (w, w32, np.sqrt(w32), uniform, w64, sqrt64, first)
        _, w32, sqrt32, uniform, w64, sqrt64, first = c
        p = self._run[None, :] if self._run.dtype == np.float32 else self._run[None, :].astype(np.float32)
        n = p.shape[1]
        z = (p - (p @ w32)[:, None] / np.float32(n)) * sqrt32[None, :]  # standardize(p, weights=w)
        run = z / np.sqrt(np.einsum("ij,ij->i", z, z) + np.float32(n))[:, None]
        self._templates = np.concatenate([run, self._first_std]) if self.anchor else run
        run64 = run.astype(np.float64)
        if not uniform:
            run64 *= sqrt64[None, :]
        tw = np.concatenate([run64, first]) if self.anchor else run64
        self._prepared = (tw, _NO_WEIGHTS if uniform else w64)
        self._last = None  # the cached correlations were with the old reference

    def scores(self, frame: np.ndarray, roi: tuple[int, int, int, int], ellipses: np.ndarray) -> np.ndarray:
        """NCC in [-1, 1] of every ellipse's box with the reference (the best of anchor and running mean).

        A single ellipse (the estimate) keeps its correlation with each reference until the next frame, for
        :meth:`update` of the same ellipse."""
        ell = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
        if ell.shape[0] == 0:
            return np.empty(0)
        red = self._region(frame, roi, ell)
        if ell.shape[0] == 1 and numba_enabled():
            return np.array([self._one(red, ell)[0]])
        return ncc_reduced(red, ell, self.shape, self._templates, weights=self.weights, prepared=self._prepared)

    def visible_score(self, frame: np.ndarray, ellipse) -> float | None:
        """NCC of the part of one ellipse's box inside the frame with the same part of the references (the best of
        anchor and running mean), or None when the box is inside the frame or less than 2 x 2 of its patch's pixels
        are: outside the frame a patch repeats the frame's border, which the references do not."""
        cx, cy, hx, hy = (float(x) for x in np.asarray(ellipse, dtype=np.float64).reshape(4))
        fh, fw = frame.shape[:2]
        ph, pw = self.shape
        cols, rows = inside_cells(cx - hx, cx + hx, pw, fw), inside_cells(cy - hy, cy + hy, ph, fh)
        if (cols.all() and rows.all()) or cols.sum() < 2 or rows.sum() < 2:
            return None
        part = np.ix_(rows, cols)
        w = self.weights.reshape(ph, pw)[part].ravel()
        if w.sum() <= 0:
            return None
        w = w * (w.size / w.sum())
        refs = [self._run] + ([self._first] if self.anchor else [])
        t = standardize(np.stack([r.reshape(ph, pw)[part].ravel() for r in refs]), weights=w)
        return float(ncc_scores(self.patch(frame, (cx, cy, hx, hy)).reshape(ph, pw)[part].ravel()[None, :], t,
                                weights=w)[0])

    def size_scores(self, frame: np.ndarray, ellipse, ratios, *, anchor_only: bool = False) -> list[float]:
        """NCC of the box of ``ellipse`` ``(cx, cy, hx, hy)`` at each of the half-axis ``ratios`` (same centre) with
        the reference, as :meth:`scores` gives them: one compiled call per size on this frame's region (a size
        search after the estimate, three sizes a frame, where building a batch cost more than scoring it).  A ratio
        may be a pair ``(rx, ry)``, one per half-axis (a search of the box's shape).  ``anchor_only``: with the
        first frame's reference alone (when the cue keeps one), not the better of it and the running mean."""
        cx, cy, hx, hy = (float(x) for x in ellipse)
        pairs = ratio_pairs(ratios)
        tw, w = self._prepared
        anchored = anchor_only and self.anchor and tw.shape[0] > 1
        if anchored:
            tw = tw[-1:]  # the anchor is the last reference
        if not numba_enabled():
            e = np.array([[cx, cy, hx * rx, hy * ry] for rx, ry in pairs])
            if not anchored:
                return self.scores(frame, None, e).tolist()
            red = self._region(frame, None, e)
            return ncc_reduced(red, e, self.shape, self._templates[-1:], weights=self.weights,
                               prepared=(tw, w)).tolist()
        top_x, top_y = max([rx for rx, _ in pairs]), max([ry for _, ry in pairs])
        red = self._region(frame, None, np.array([[cx, cy, hx * top_x, hy * top_y]]))
        u, v = _grid(self.shape)
        gray = red.levels_for(u.size * v.size)
        dots = np.empty(tw.shape[0])
        e = np.empty(4)
        out = []
        for rx, ry in pairs:
            e[0], e[1], e[2], e[3] = cx, cy, hx * rx, hy * ry
            out.append(float(_ncc_one(gray, e, float(red.x0), float(red.y0), float(red.k), u, v, tw, w, 1.0, dots)))
        return out

    def _one(self, red: Reduced, ell: np.ndarray) -> tuple[float, np.ndarray]:
        """``(best NCC, NCC per reference)`` of one ellipse ``(1, 4)``, computed once per frame and reference
        (compiled path)."""
        key = (red, *ell[0].tolist())
        if self._last is not None and self._last[0] == key:
            return self._last[1]
        tw, w = self._prepared
        dots = np.empty(tw.shape[0])
        u, v = _grid(self.shape)
        best = _ncc_one(red.levels_for(u.size * v.size), ell[0], float(red.x0), float(red.y0), float(red.k), u, v, tw,
                        w, 1.0, dots)
        self._last = (key, (best, dots))
        return self._last[1]

    def proposals(self, frame: np.ndarray, half_axes: tuple[float, float], k: int) -> tuple[np.ndarray, np.ndarray]:
        """Centres ``(m, 2)`` of the ``k`` best separated matches of the references (running mean and anchor)
        over the whole frame for a box of ``half_axes``, and their NCC (:mod:`pftrack.cues.structure_search`)."""
        if self._run is None:
            return np.empty((0, 2)), np.empty(0)
        refs = [self._run] + ([self._first] if self.anchor and self._first is not None else [])
        return propose_centres(frame, np.stack([r.reshape(self.shape) for r in refs]), half_axes, k)

    def update(self, frame: np.ndarray, ellipse, rate: float, anchor_gate: float = -1.0) -> bool:
        """Blend the estimate's patch into the running reference: ``t <- (1 - rate) t + rate p``.

        With ``anchor_gate`` > -1 the patch is blended only when its NCC with the first
        frame's patch is at least ``anchor_gate`` (the drift correction of template trackers:
        a reference that no longer resembles the start is not followed further).  Returns
        whether the reference changed."""
        if rate <= 0 or self._run is None:
            return False
        e = np.asarray(ellipse, dtype=np.float64).reshape(1, 4)
        red = self._region(frame, None, e)
        if anchor_gate > -1.0:
            if numba_enabled() and self.anchor:  # the anchor is the last reference: scored with the estimate
                anchor_ncc = self._one(red, e)[1][-1]
            else:
                if self._first_prepared is None:
                    self._first_prepared = weighted_templates(self._first_std, self.weights)
                anchor_ncc = ncc_reduced(red, e, self.shape, self._first_std, weights=self.weights,
                                         prepared=self._first_prepared)[0]
            if anchor_ncc < anchor_gate:
                return False
        # OpenCV's remap (1/32-pixel weights), not the scoring kernel's exact bilinear: on the camouflage
        # scenes the exact patch raised a false loss on 1 of 24 seeds (0 of 24 with remap)
        patch = sample_reduced(red, e, self.shape)[0]
        self._run = (1.0 - rate) * self._run + rate * patch
        self._refresh()
        return True
