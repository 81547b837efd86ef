"""A structural cue for colour particle filters: normalised cross-correlation of small grey patches.

Colour histograms discard where the colours are; a grey target under changing light
has almost no colour to describe.  This cue keeps the layout: every particle's box is
resampled to a small grey patch (about ``template_pixels`` pixels, the box's aspect)
and compared with a reference patch by the zero-mean normalised cross-correlation of
book ch. 14 (eq. NCC, ``pftrack.cues.template``):

    r(B) = sum (p - mean p)(t - mean t) / sqrt(sum (p - mean p)^2 * sum (t - mean t)^2)  in [-1, 1]

``r`` is invariant to a gain and an offset of the grey levels, so a global
illumination drift leaves it unchanged (ch. 14's reason for preferring NCC to SAD),
and it is cheap: one ``cv2.resize`` of the particles' region to the patch resolution
(area averaging: no aliasing however large the box), one ``cv2.remap`` for all
particles, then a matrix-vector product.

The reference is the first frame's patch, updated by a gated running mean (the
caller decides when), with the first patch kept as an anchor: the score is the larger
of the correlations with the anchor and with the running reference, so a bad update
cannot wipe out what the target looked like at the start (the drift problem of
template trackers, ch. 14 §4).
"""

from __future__ import annotations

import math

import cv2
import numpy as np


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


def sample_boxes(frame: np.ndarray, roi: tuple[int, int, int, int], ellipses: np.ndarray,
                 shape: tuple[int, int]) -> np.ndarray:
    """Every ellipse's bounding box ``(cx, cy, hx, hy)`` resampled to ``shape`` grey pixels: ``(N, ph*pw)`` float32.

    The region ``roi`` is first reduced by area averaging so that the smallest box spans
    about the patch size (a low-pass filter before sampling), then one bilinear remap
    samples all boxes.  Pixels outside the region repeat its border.
    """
    ell = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
    n = ell.shape[0]
    ph, pw = shape
    if n == 0:
        return np.empty((0, ph * pw), dtype=np.float32)
    # only the part of the region the boxes cover is converted and reduced
    bx0, by0, bx1, by1 = _box_roi(ell, frame.shape[1], frame.shape[0])
    x0, y0 = max(roi[0], bx0), max(roi[1], by0)
    x1, y1 = max(min(roi[2], bx1), x0 + 1), max(min(roi[3], by1), y0 + 1)
    gray = gray_region(frame, (x0, y0, x1, y1))
    # reduce so a patch pixel covers about one region pixel for the smallest box
    f = max(1.0, min(float(np.min(2.0 * ell[:, 2])) / pw, float(np.min(2.0 * ell[:, 3])) / ph))
    if f > 1.25 and gray.shape[0] > 1 and gray.shape[1] > 1:
        gw, gh = max(1, int(round(gray.shape[1] / f))), max(1, int(round(gray.shape[0] / f)))
        sx, sy = gray.shape[1] / gw, gray.shape[0] / gh
        gray = cv2.resize(gray, (gw, gh), interpolation=cv2.INTER_AREA)
    else:
        sx = sy = 1.0
    # patch pixel centres as fractions of the box, in region-reduced pixel coordinates
    u = ((np.arange(pw, dtype=np.float64) + 0.5) / pw - 0.5) * 2.0  # -1..1 across the box
    v = ((np.arange(ph, dtype=np.float64) + 0.5) / ph - 0.5) * 2.0
    cx = (ell[:, 0] - x0) / sx - 0.5
    cy = (ell[:, 1] - y0) / sy - 0.5
    mx = (cx[:, None] + u[None, :] * (ell[:, 2:3] / sx)).astype(np.float32)  # (N, pw)
    my = (cy[:, None] + v[None, :] * (ell[:, 3:4] / sy)).astype(np.float32)  # (N, ph)
    mapx = np.ascontiguousarray(np.broadcast_to(mx[:, None, :], (n, ph, pw))).reshape(n * ph, pw)
    mapy = np.ascontiguousarray(np.broadcast_to(my[:, :, None], (n, ph, pw))).reshape(n * ph, pw)
    out = cv2.remap(gray, mapx, mapy, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return out.reshape(n, ph * pw)


def standardize(patches: np.ndarray, floor: float = 1.0) -> np.ndarray:
    """Zero-mean, unit-norm rows (``(N, P)`` float32).  Rows flatter than ``floor`` grey levels of std stay near 0."""
    p = np.asarray(patches, dtype=np.float32)
    z = p - p.mean(axis=1, keepdims=True)
    norm = np.sqrt(np.einsum("ij,ij->i", z, z) + np.float32(floor * floor * p.shape[1]))
    return z / norm[:, None]


def ncc_scores(patches: np.ndarray, templates: np.ndarray) -> np.ndarray:
    """Best NCC of each patch ``(N, P)`` over one or more standardised templates ``(K, P)``: ``(N,)`` float64.

    The small std floor of :func:`standardize` makes a flat patch score ~0 instead of an
    undefined 0/0 (a flat patch carries no structure)."""
    z = standardize(patches)
    t = np.atleast_2d(np.asarray(templates, dtype=np.float32))
    return np.max(z @ t.T, axis=1).astype(np.float64)


class StructureCue:
    """Reference patches (an anchor and a running mean) and batched NCC scores of particle boxes."""

    def __init__(self, template_pixels: int = 256, anchor: bool = True):
        self.template_pixels = int(template_pixels)
        self.anchor = bool(anchor)
        self.shape = (0, 0)
        self._first: np.ndarray | None = None
        self._run: np.ndarray | None = None
        self._templates: np.ndarray | None = None
        self._last: tuple[np.ndarray, np.ndarray] | None = None  # (ellipse, patch) of the last single-box call

    @property
    def ready(self) -> bool:
        """Has a reference been taken (:meth:`init`)?"""
        return self._templates is not None

    def init(self, frame: np.ndarray, ellipse) -> None:
        e = np.asarray(ellipse, dtype=np.float64).reshape(1, 4)
        self.shape = patch_shape(2 * e[0, 2], 2 * e[0, 3], self.template_pixels)
        patch = self.patch(frame, e[0])
        self._first = patch
        self._run = patch.copy()
        self._refresh()

    def patch(self, frame: np.ndarray, ellipse) -> np.ndarray:
        e = np.asarray(ellipse, dtype=np.float64).reshape(1, 4)
        roi = _box_roi(e, frame.shape[1], frame.shape[0])
        return sample_boxes(frame, roi, e, self.shape)[0]

    def _refresh(self) -> None:
        ts = [self._run] + ([self._first] if self.anchor else [])
        self._templates = standardize(np.stack(ts))

    def scores(self, frame: np.ndarray, roi: tuple[int, int, int, int], ellipses: np.ndarray) -> np.ndarray:
        """NCC in [-1, 1] of every ellipse's box with the reference (the best of anchor and running mean)."""
        patches = sample_boxes(frame, roi, ellipses, self.shape)
        if len(patches) == 1:  # an estimate: :meth:`update` may reuse its patch
            self._last = (np.array(ellipses, dtype=np.float64).ravel(), patches[0])
        return ncc_scores(patches, self._templates)

    def update(self, frame: np.ndarray, ellipse, rate: float) -> None:
        """Blend the estimate's patch into the running reference: ``t <- (1 - rate) t + rate p``."""
        if rate <= 0 or self._run is None:
            return
        e = np.asarray(ellipse, dtype=np.float64).ravel()
        last = self._last
        patch = last[1] if last is not None and np.array_equal(last[0], e) else self.patch(frame, e)
        self._run = (1.0 - rate) * self._run + rate * patch
        self._refresh()


def _box_roi(ell: np.ndarray, width: int, height: int) -> tuple[int, int, int, int]:
    x0 = int(math.floor(np.min(ell[:, 0] - ell[:, 2]))) - 1
    y0 = int(math.floor(np.min(ell[:, 1] - ell[:, 3]))) - 1
    x1 = int(math.ceil(np.max(ell[:, 0] + ell[:, 2]))) + 1
    y1 = int(math.ceil(np.max(ell[:, 1] + ell[:, 3]))) + 1
    x0, y0 = min(max(x0, 0), max(width - 1, 0)), min(max(y0, 0), max(height - 1, 0))
    return x0, y0, max(min(x1, width), x0 + 1), max(min(y1, height), y0 + 1)
