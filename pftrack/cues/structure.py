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

Speed: the region the particles cover is block-averaged once per frame to about the
patch resolution (:func:`reduce_region`: an integer-factor area resize of the 8-bit
frame, then the grey conversion of the small image; no aliasing however large the
box), and one compiled pass (:func:`ncc_reduced`) samples every box bilinearly and
accumulates its NCC with every reference.  Without Numba the same is one
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

from .._numba import njit, numba_enabled


def patch_shape(w: float, h: float, pixels: int) -> tuple[int, int]:
    """``(ph, pw)`` of a patch with about ``pixels`` pixels and the aspect of a ``w`` x ``h`` box (each >= 4)."""
    w, h = max(float(w), 1.0), max(float(h), 1.0)
    a = math.sqrt(pixels / (w * h))
    return max(4, int(round(h * a))), max(4, int(round(w * a)))


def gray_region(frame: np.ndarray, roi: tuple[int, int, int, int]) -> np.ndarray:
    """float32 grey levels of ``frame[y0:y1, x0:x1]`` (BGR or grey input)."""
    x0, y0, x1, y1 = roi
    sub = frame[y0:y1, x0:x1]
    if sub.ndim == 3 and sub.shape[2] == 3:
        sub = cv2.cvtColor(np.ascontiguousarray(sub), cv2.COLOR_BGR2GRAY)
    elif sub.ndim == 3:
        sub = sub[..., 0]
    return sub.astype(np.float32)


class Reduced:
    """A grey, block-averaged copy of a frame region: reduced pixel ``(j, i)`` averages the ``k x k`` block
    whose top-left frame pixel is ``(x0 + i k, y0 + j k)``."""

    __slots__ = ("gray", "x0", "y0", "k")

    def __init__(self, gray: np.ndarray, x0: int, y0: int, k: int):
        self.gray, self.x0, self.y0, self.k = gray, x0, y0, k

    def covers(self, ell: np.ndarray) -> bool:
        h, w = self.gray.shape
        return bool(np.all(ell[:, 0] - ell[:, 2] >= self.x0) and np.all(ell[:, 1] - ell[:, 3] >= self.y0)
                    and np.all(ell[:, 0] + ell[:, 2] <= self.x0 + w * self.k)
                    and np.all(ell[:, 1] + ell[:, 3] <= self.y0 + h * self.k))


def reduction_factor(ellipses: np.ndarray, shape: tuple[int, int]) -> int:
    """The integer block size that makes the mean box span about the patch size (>= 1)."""
    ell = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
    ph, pw = shape
    f = min(2.0 * float(ell[:, 2].mean()) / pw, 2.0 * float(ell[:, 3].mean()) / ph)
    return max(1, int(math.floor(f)))


def reduce_region(frame: np.ndarray, roi: tuple[int, int, int, int], k: int) -> Reduced:
    """Grey levels of ``frame[roi]`` averaged over ``k x k`` blocks (integer-factor area resize first, on the
    8-bit frame, then the grey conversion of the small image)."""
    x0, y0, x1, y1 = (int(v) for v in roi)
    k = max(1, int(k))
    w = max(1, (x1 - x0) // k) * k
    h = max(1, (y1 - y0) // k) * k
    w, h = min(w, frame.shape[1] - x0), min(h, frame.shape[0] - y0)
    sub = frame[y0:y0 + h, x0:x0 + w]
    if k > 1 and w >= k and h >= k:
        # large blocks average a 4 x 4 lattice of their pixels: the cost stays bounded by the
        # patch resolution, not the target's size (a coarse area filter is enough for a 16x16 NCC patch)
        step = k // 4 if k >= 8 else 1
        if step > 1:
            sub = sub[::step, ::step]
        sub = cv2.resize(sub, (w // k, h // k), interpolation=cv2.INTER_AREA)
    else:
        k = 1
    return Reduced(gray_region(sub, (0, 0, sub.shape[1], sub.shape[0])), x0, y0, k)


def _maps(red: Reduced, ell: np.ndarray, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Sampling coordinates (reduced-image pixel indices) of every box's patch: two ``(N, ph*pw)`` arrays."""
    ph, pw = shape
    n = ell.shape[0]
    u = ((np.arange(pw) + 0.5) / pw - 0.5) * 2.0  # -1..1 across the box
    v = ((np.arange(ph) + 0.5) / ph - 0.5) * 2.0
    k = float(red.k)
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
    return cv2.remap(red.gray, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def sample_boxes(frame: np.ndarray, roi: tuple[int, int, int, int], ellipses: np.ndarray,
                 shape: tuple[int, int]) -> np.ndarray:
    """Every ellipse's bounding box resampled to ``shape`` grey pixels: ``(N, ph*pw)`` float32.

    The part of ``roi`` the boxes cover is block-averaged by :func:`reduction_factor`
    (a low-pass filter before sampling), then one bilinear remap samples all boxes.
    """
    ell = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
    if ell.shape[0] == 0:
        return np.empty((0, shape[0] * shape[1]), dtype=np.float32)
    return sample_reduced(_reduced_for(frame, roi, ell, shape), ell, shape)


def _reduced_for(frame, roi, ell, shape) -> Reduced:
    bx0, by0, bx1, by1 = _box_roi(ell, frame.shape[1], frame.shape[0])
    x0, y0 = max(roi[0], bx0), max(roi[1], by0)
    x1, y1 = max(min(roi[2], bx1), x0 + 1), max(min(roi[3], by1), y0 + 1)
    return reduce_region(frame, (x0, y0, x1, y1), reduction_factor(ell, shape))


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


@njit(cache=True)
def _ncc_boxes(gray, cx, cy, sx, sy, u, v, tmpl, wts, floor2, out):
    """Bilinear sampling (border replicated) of every box's patch and its best weighted NCC, in one pass:
    ``r = sum p T / sqrt(sum w (p - mean_w p)^2 + floor2 P)`` with ``T = sqrt(w) t~`` (``sum sqrt(w) t~ = 0``
    for a standardised template ``t~``, so the patch's mean drops out of the numerator)."""
    h, w = gray.shape
    n = cx.shape[0]
    ph, pw = v.shape[0], u.shape[0]
    kt = tmpl.shape[0]
    npix = ph * pw
    dots = np.empty(kt)
    xi = np.empty(pw, np.int64)
    xf = np.empty(pw)
    for i in range(n):
        # column indices and weights once per box (border replicated by clamping)
        for b in range(pw):
            x = min(max(cx[i] + u[b] * sx[i], 0.0), w - 1.0)
            x0 = min(int(x), max(w - 2, 0))
            xi[b] = x0
            xf[b] = x - x0 if w > 1 else 0.0
        s1 = 0.0
        s2 = 0.0
        for q in range(kt):
            dots[q] = 0.0
        dx = 1 if w > 1 else 0
        for a in range(ph):
            y = min(max(cy[i] + v[a] * sy[i], 0.0), h - 1.0)
            y0 = min(int(y), max(h - 2, 0))
            fy = y - y0 if h > 1 else 0.0
            y1 = y0 + 1 if h > 1 else y0
            for b in range(pw):
                x0 = xi[b]
                fx = xf[b]
                g00 = gray[y0, x0]
                g10 = gray[y1, x0]
                top = g00 + fx * (gray[y0, x0 + dx] - g00)
                bot = g10 + fx * (gray[y1, x0 + dx] - g10)
                val = top + fy * (bot - top)
                k = a * pw + b
                wv = wts[k] * val
                s1 += wv
                s2 += wv * val
                for q in range(kt):
                    dots[q] += val * tmpl[q, k]
        var = s2 - s1 * s1 / npix
        if var < 0.0:
            var = 0.0
        norm = math.sqrt(var + floor2 * npix)
        best = dots[0]
        for q in range(1, kt):
            if dots[q] > best:
                best = dots[q]
        out[i] = best / norm


def ncc_reduced(red: Reduced, ellipses: np.ndarray, shape: tuple[int, int], templates: np.ndarray,
                floor: float = 1.0, weights: np.ndarray | None = None) -> np.ndarray:
    """:func:`ncc_scores` of :func:`sample_reduced`'s patches, compiled in one pass when Numba is enabled."""
    ell = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
    if ell.shape[0] == 0:
        return np.empty(0)
    if not numba_enabled():
        return ncc_scores(sample_reduced(red, ell, shape), templates, floor, weights)
    ph, pw = shape
    k = float(red.k)
    u = ((np.arange(pw) + 0.5) / pw - 0.5) * 2.0
    v = ((np.arange(ph) + 0.5) / ph - 0.5) * 2.0
    out = np.empty(ell.shape[0])
    w = np.ones(ph * pw) if weights is None else np.asarray(weights, dtype=np.float64)
    _ncc_boxes(red.gray, (ell[:, 0] - red.x0) / k - 0.5, (ell[:, 1] - red.y0) / k - 0.5, ell[:, 2] / k,
               ell[:, 3] / k, u, v, np.atleast_2d(np.asarray(templates, dtype=np.float64)) * np.sqrt(w)[None, :], w,
               float(floor) ** 2, out)
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

    @property
    def ready(self) -> bool:
        """Has a reference been taken (:meth:`init`)?"""
        return self._templates is not None

    def new_frame(self) -> None:
        """Forget the previous frame's reduced region."""
        self._reduced = None

    def init(self, frame: np.ndarray, ellipse) -> None:
        e = np.asarray(ellipse, dtype=np.float64).reshape(1, 4)
        self.new_frame()
        self.shape = patch_shape(2 * e[0, 2], 2 * e[0, 3], self.template_pixels)
        self.weights = kernel_weights(self.shape, self.weighting)
        patch = self.patch(frame, e[0])
        self._first = patch
        self._first_std = standardize(patch[None, :], weights=self.weights)  # constant: standardised once
        self._run = patch.copy()
        self._refresh()

    def _region(self, frame: np.ndarray, roi, ell: np.ndarray) -> Reduced:
        red = self._reduced
        if red is None or not red.covers(ell):
            red = self._reduced = _reduced_for(frame, roi, ell, self.shape)
        return red

    def patch(self, frame: np.ndarray, ellipse) -> np.ndarray:
        """The grey patch of one ellipse's box, ``(ph*pw,)`` float32."""
        e = np.asarray(ellipse, dtype=np.float64).reshape(1, 4)
        red = self._region(frame, _box_roi(e, frame.shape[1], frame.shape[0]), e)
        return sample_reduced(red, e, self.shape)[0]

    def _refresh(self) -> None:
        run = standardize(self._run[None, :], weights=self.weights)
        self._templates = np.concatenate([run, self._first_std]) if self.anchor else run

    def scores(self, frame: np.ndarray, roi: tuple[int, int, int, int], ellipses: np.ndarray) -> np.ndarray:
        """NCC in [-1, 1] of every ellipse's box with the reference (the best of anchor and running mean)."""
        ell = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
        if ell.shape[0] == 0:
            return np.empty(0)
        return ncc_reduced(self._region(frame, roi, ell), ell, self.shape, self._templates, weights=self.weights)

    def update(self, frame: np.ndarray, ellipse, rate: float, anchor_gate: float = -1.0) -> bool:
        """Blend the estimate's patch into the running reference: ``t <- (1 - rate) t + rate p``.

        With ``anchor_gate`` > -1 the patch is blended only when its NCC with the first
        frame's patch is at least ``anchor_gate`` (the drift correction of template trackers:
        a reference that no longer resembles the start is not followed further).  Returns
        whether the reference changed."""
        if rate <= 0 or self._run is None:
            return False
        patch = self.patch(frame, ellipse)
        if anchor_gate > -1.0 and ncc_scores(patch[None, :], self._first_std, weights=self.weights)[0] < anchor_gate:
            return False
        self._run = (1.0 - rate) * self._run + rate * patch
        self._refresh()
        return True


def _box_roi(ell: np.ndarray, width: int, height: int) -> tuple[int, int, int, int]:
    x0 = int(math.floor(np.min(ell[:, 0] - ell[:, 2]))) - 1
    y0 = int(math.floor(np.min(ell[:, 1] - ell[:, 3]))) - 1
    x1 = int(math.ceil(np.max(ell[:, 0] + ell[:, 2]))) + 1
    y1 = int(math.ceil(np.max(ell[:, 1] + ell[:, 3]))) + 1
    x0, y0 = min(max(x0, 0), max(width - 1, 0)), min(max(y0, 0), max(height - 1, 0))
    return x0, y0, max(min(x1, width), x0 + 1), max(min(y1, height), y0 + 1)
