"""Compiled kernels of the structural cue (:mod:`pftrack.cues.structure`): bilinear sampling of a box's patch
from a block-averaged grey region and its normalised cross-correlation with one or more templates, in one pass.

Every box's sums run over its samples in one fixed order, so a box scores the same alone or in a batch (no
fastmath: the order of the sums is part of the result).
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import njit


@njit(cache=True)
def _sample_row(y, h):
    """Row indices and weight of a bilinear sample at row ``y`` (border replicated)."""
    y = min(max(y, 0.0), h - 1.0)
    y0 = min(int(y), max(h - 2, 0))
    fy = y - y0 if h > 1 else 0.0
    y1 = y0 + 1 if h > 1 else y0
    return y0, y1, fy


@njit(cache=True)
def _columns(cx, sx, u, w, xi, xf):
    """Column indices and weights of a box's bilinear samples (border replicated by clamping)."""
    for b in range(u.shape[0]):
        x = min(max(cx + u[b] * sx, 0.0), w - 1.0)
        x0 = min(int(x), max(w - 2, 0))
        xi[b] = x0
        xf[b] = x - x0 if w > 1 else 0.0


@njit(cache=True)
def _rows(cy, sy, v, h, yi, yf):
    """Row indices and weights of a box's bilinear samples (border replicated by clamping)."""
    for a in range(v.shape[0]):
        y0, _, fy = _sample_row(cy + v[a] * sy, h)
        yi[a] = y0
        yf[a] = fy


@njit(cache=True)
def _bilinear(gray, y0, y1, x0, x1, fx, fy):
    """The bilinear sample between rows ``y0, y1`` and columns ``x0, x1`` at fractions ``fx, fy``."""
    g00 = float(gray[y0, x0])
    g10 = float(gray[y1, x0])
    top = g00 + fx * (float(gray[y0, x1]) - g00)
    bot = g10 + fx * (float(gray[y1, x1]) - g10)
    return top + fy * (bot - top)


@njit(cache=True)
def _best_of(s1, s2, npix, floor2, dots):
    """The NCC with each template (``dots`` holds the dot products on entry, the correlations on exit) from the
    patch's weighted sum ``s1`` and sum of squares ``s2``; returns the best."""
    var = s2 - s1 * s1 / npix
    if var < 0.0:
        var = 0.0
    norm = math.sqrt(var + floor2 * npix)
    best = -math.inf
    for q in range(dots.shape[0]):
        dots[q] = dots[q] / norm
        if dots[q] > best:
            best = dots[q]
    return best


@njit(cache=True)
def _box_ncc(gray, cx, cy, sx, sy, u, v, tmpl, wts, floor2, xi, xf, yi, yf, dots):
    """One box of :func:`_ncc_boxes` (centre ``cx, cy`` and half-sizes ``sx, sy`` in reduced pixels): its NCC
    with every template in ``dots`` (``(K,)``); returns the best.  ``xi, xf, yi, yf``: scratch for the
    samples' column and row indices and weights."""
    h, w = gray.shape
    ph, pw = v.shape[0], u.shape[0]
    kt = tmpl.shape[0]
    uniform = wts.shape[0] == 0
    dx, dy = (1 if w > 1 else 0), (1 if h > 1 else 0)  # to the second column and row of a sample
    t0, t1 = tmpl[0], tmpl[kt - 1]
    _columns(cx, sx, u, w, xi, xf)
    _rows(cy, sy, v, h, yi, yf)
    s1 = 0.0
    s2 = 0.0
    d0 = 0.0
    d1 = 0.0
    for q in range(kt):
        dots[q] = 0.0
    k = 0
    for a in range(ph):
        y0 = yi[a]
        y1 = y0 + dy
        fy = yf[a]
        for b in range(pw):
            x0 = xi[b]
            val = _bilinear(gray, y0, y1, x0, x0 + dx, xf[b], fy)
            wv = val if uniform else wts[k] * val
            s1 += wv
            s2 += wv * val
            if kt <= 2:
                d0 += val * t0[k]
                d1 += val * t1[k]
            else:
                for q in range(kt):
                    dots[q] += val * tmpl[q, k]
            k += 1
    if kt <= 2:
        dots[0] = d0
        dots[kt - 1] = d1
    return _best_of(s1, s2, ph * pw, floor2, dots)


@njit(cache=True)
def _ncc_boxes(gray, ell, x0, y0, k, u, v, tmpl, wts, floor2, out):
    """Bilinear sampling (border replicated) of every box's patch and its best weighted NCC, in one pass:
    ``r = sum p T / sqrt(sum w (p - mean_w p)^2 + floor2 P)`` with ``T = sqrt(w) t~`` (``sum sqrt(w) t~ = 0``
    for a standardised template ``t~``, so the patch's mean drops out of the numerator).  ``wts`` of length 0
    means uniform weights; one or two templates (the usual running reference and anchor) keep their dot
    products in registers.  ``gray`` may hold any numeric type (float64 is read fastest)."""
    dots = np.empty(tmpl.shape[0])
    xi = np.empty(u.shape[0], np.int64)
    xf = np.empty(u.shape[0])
    yi = np.empty(v.shape[0], np.int64)
    yf = np.empty(v.shape[0])
    for i in range(ell.shape[0]):
        out[i] = _box_ncc(gray, (ell[i, 0] - x0) / k - 0.5, (ell[i, 1] - y0) / k - 0.5, ell[i, 2] / k,
                          ell[i, 3] / k, u, v, tmpl, wts, floor2, xi, xf, yi, yf, dots)


@njit(cache=True)
def _ncc_one(gray, e, x0, y0, k, u, v, tmpl, wts, floor2, dots):
    """:func:`_ncc_boxes` of one ellipse ``e`` ``(4,)``, keeping its NCC with each template (``dots``)."""
    xi = np.empty(u.shape[0], np.int64)
    xf = np.empty(u.shape[0])
    yi = np.empty(v.shape[0], np.int64)
    yf = np.empty(v.shape[0])
    return _box_ncc(gray, (e[0] - x0) / k - 0.5, (e[1] - y0) / k - 0.5, e[2] / k, e[3] / k, u, v, tmpl, wts,
                    floor2, xi, xf, yi, yf, dots)
