"""Compiled kernels of the structural cue (:mod:`pftrack.cues.structure`): bilinear sampling of a box's patch
from a block-averaged grey region and its normalised cross-correlation with one or more templates, in one pass.

Every box's sums run over its samples in one fixed order, so a box scores the same alone or in a batch (no
fastmath: the order of the sums is part of the result).

A box's work is split in three steps, each inlined into the loop over the boxes: the samples' column and row
indices and weights, the bilinear samples into a buffer, and the sums over that buffer.  The indices are held as
unsigned integers, for which Numba's indexing skips its test for negative indices, and the sums run in a loop of
their own, so that the four running sums of the usual case (uniform weights, one or two templates) are the whole
loop.  The arithmetic of every sample and the order of every sum are those of a box sampled and summed in one
loop (``tests/test_structure_fusion.py`` checks them bit for bit against a plain Python transcription).
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import njit


@njit(cache=True, inline="always")
def _sample_grid(cx, cy, sx, sy, u, v, h, w, xu, xf, yu, yf):
    """Column and row indices (``xu``, ``yu``: uint64) and weights (``xf``, ``yf``) of a box's bilinear samples
    at ``cx + u sx``, ``cy + v sy`` (border replicated by clamping: the last index is at most ``w - 2``)."""
    for b in range(u.shape[0]):
        x = min(max(cx + u[b] * sx, 0.0), w - 1.0)
        x0 = min(int(x), max(w - 2, 0))
        xu[b] = x0
        xf[b] = x - x0 if w > 1 else 0.0
    for a in range(v.shape[0]):
        y = min(max(cy + v[a] * sy, 0.0), h - 1.0)
        y0 = min(int(y), max(h - 2, 0))
        yu[a] = y0
        yf[a] = y - y0 if h > 1 else 0.0


@njit(cache=True, inline="always")
def _sample_patch(gray, xu, xf, yu, yf, vals):
    """The bilinear samples of the grid (:func:`_sample_grid`), row by row, into ``vals``."""
    h, w = gray.shape
    dx = np.uint64(1 if w > 1 else 0)  # to the second column and row of a sample
    dy = np.uint64(1 if h > 1 else 0)
    pw = xu.shape[0]
    k = 0
    for a in range(yu.shape[0]):
        y0 = yu[a]
        y1 = y0 + dy
        fy = yf[a]
        for b in range(pw):
            x0 = xu[b]
            x1 = x0 + dx
            fx = xf[b]
            g00 = float(gray[y0, x0])
            g10 = float(gray[y1, x0])
            top = g00 + fx * (float(gray[y0, x1]) - g00)
            bot = g10 + fx * (float(gray[y1, x1]) - g10)
            vals[k] = top + fy * (bot - top)
            k += 1


@njit(cache=True, inline="always")
def _norm(s1, s2, npix, floor2):
    """The NCC's denominator from the patch's weighted sum ``s1`` and sum of squares ``s2``."""
    var = s2 - s1 * s1 / npix
    if var < 0.0:
        var = 0.0
    return math.sqrt(var + floor2 * npix)


@njit(cache=True)
def _patch_ncc_any(vals, tmpl, wts, floor2, dots):
    """:func:`_patch_ncc` with weights or more than two templates (kept out of its loop: a branch of its own
    there slows the usual case by a tenth)."""
    n = vals.shape[0]
    kt = tmpl.shape[0]
    s1 = 0.0
    s2 = 0.0
    best = -math.inf
    uniform = wts.shape[0] == 0
    for q in range(kt):
        dots[q] = 0.0
    for k in range(n):
        val = vals[k]
        wv = val if uniform else wts[k] * val
        s1 += wv
        s2 += wv * val
        for q in range(kt):
            dots[q] += val * tmpl[q, k]
    norm = _norm(s1, s2, n, floor2)
    for q in range(kt):
        dots[q] = dots[q] / norm
        if dots[q] > best:
            best = dots[q]
    return best


@njit(cache=True, inline="always")
def _patch_ncc(vals, tmpl, t0, t1, wts, floor2, dots):
    """The best NCC of the samples ``vals`` with the templates (:func:`_ncc_boxes`; ``t0, t1``: the first and the
    last of them); ``dots`` keeps the NCC with each one.  Of equal correlations the first is returned; a NaN is
    never the best (all NaN give -inf)."""
    n = vals.shape[0]
    kt = tmpl.shape[0]
    s1 = 0.0
    s2 = 0.0
    best = -math.inf
    if wts.shape[0] == 0 and kt <= 2:  # the usual case: four running sums
        d0 = 0.0
        d1 = 0.0
        for k in range(n):
            val = vals[k]
            s1 += val
            s2 += val * val
            d0 += val * t0[k]
            d1 += val * t1[k]
        norm = _norm(s1, s2, n, floor2)
        r0 = d0 / norm
        r1 = d1 / norm
        dots[0] = r0
        dots[kt - 1] = r1
        if r0 > best:
            best = r0
        if r1 > best:
            best = r1
        return best
    return _patch_ncc_any(vals, tmpl, wts, floor2, dots)


@njit(cache=True, inline="always")
def _box_ncc(gray, cx, cy, sx, sy, u, v, tmpl, t0, t1, wts, floor2, xu, xf, yu, yf, vals, dots):
    """One box of :func:`_ncc_boxes` (centre ``cx, cy`` and half-sizes ``sx, sy`` in reduced pixels): its NCC with
    every template in ``dots``; returns the best.  ``xu, xf, yu, yf, vals``: scratch."""
    h, w = gray.shape
    _sample_grid(cx, cy, sx, sy, u, v, h, w, xu, xf, yu, yf)
    _sample_patch(gray, xu, xf, yu, yf, vals)
    return _patch_ncc(vals, tmpl, t0, t1, wts, floor2, dots)


@njit(cache=True)
def _ncc_boxes(gray, ell, x0, y0, k, u, v, tmpl, wts, floor2, out):
    """Bilinear sampling (border replicated) of every box's patch and its best weighted NCC, in one pass:
    ``r = sum p T / sqrt(sum w (p - mean_w p)^2 + floor2 P)`` with ``T = sqrt(w) t~`` (``sum sqrt(w) t~ = 0``
    for a standardised template ``t~``, so the patch's mean drops out of the numerator).  ``wts`` of length 0
    means uniform weights.  ``gray`` may hold any numeric type (float64 is read fastest)."""
    dots = np.empty(tmpl.shape[0])
    xu = np.empty(u.shape[0], np.uint64)
    xf = np.empty(u.shape[0])
    yu = np.empty(v.shape[0], np.uint64)
    yf = np.empty(v.shape[0])
    vals = np.empty(u.shape[0] * v.shape[0])
    t0, t1 = tmpl[0], tmpl[tmpl.shape[0] - 1]
    for i in range(ell.shape[0]):
        out[i] = _box_ncc(gray, (ell[i, 0] - x0) / k - 0.5, (ell[i, 1] - y0) / k - 0.5, ell[i, 2] / k, ell[i, 3] / k,
                          u, v, tmpl, t0, t1, wts, floor2, xu, xf, yu, yf, vals, dots)


@njit(cache=True)
def _ncc_one(gray, e, x0, y0, k, u, v, tmpl, wts, floor2, dots):
    """:func:`_ncc_boxes` of one ellipse ``e`` ``(4,)``, keeping its NCC with each template (``dots``)."""
    xu = np.empty(u.shape[0], np.uint64)
    xf = np.empty(u.shape[0])
    yu = np.empty(v.shape[0], np.uint64)
    yf = np.empty(v.shape[0])
    vals = np.empty(u.shape[0] * v.shape[0])
    t0, t1 = tmpl[0], tmpl[tmpl.shape[0] - 1]
    return _box_ncc(gray, (e[0] - x0) / k - 0.5, (e[1] - y0) / k - 0.5, e[2] / k, e[3] / k, u, v, tmpl, t0, t1, wts,
                    floor2, xu, xf, yu, yf, vals, dots)
