"""The pure NumPy path of the colour histograms over ellipses (:mod:`pftrack.cues.color`), used without Numba and
as the compiled kernels' reference in the tests: one vectorised ``bincount`` over ``(particle, bin)`` pairs, the same
pixels and weights as the kernels."""

from __future__ import annotations

import numpy as np

__all__ = ["_ellipse_hist_numpy"]


def _ellipse_hist_numpy(bins, x0, y0, ell, kernel, out, totals, half=0):
    """Reference path: one ``bincount`` over (particle, bin) pairs, no Python loop over particles."""
    n_part = ell.shape[0]
    hgt, wid = bins.shape
    n_bins = out.shape[1]
    cx = ell[:, 0] - x0
    cy = ell[:, 1] - y0
    hx = ell[:, 2]
    hy = ell[:, 3]
    ok = (hx > 0) & (hy > 0)
    hx_s = np.where(ok, hx, 1.0)
    hy_s = np.where(ok, hy, 1.0)
    i_lo = np.maximum(0, np.ceil(cx - hx - 0.5)).astype(np.int64)
    i_hi = np.minimum(wid - 1, np.floor(cx + hx - 0.5)).astype(np.int64)
    j_lo = np.maximum(0, np.ceil(cy - hy - 0.5)).astype(np.int64)
    j_hi = np.minimum(hgt - 1, np.floor(cy + hy - 0.5)).astype(np.int64)
    span_i = np.where(ok, i_hi - i_lo + 1, 0)
    span_j = np.where(ok, j_hi - j_lo + 1, 0)
    wmax = int(max(span_i.max(initial=0), 0))
    hmax = int(max(span_j.max(initial=0), 0))
    out[:] = 0.0
    totals[:] = 0.0
    if wmax == 0 or hmax == 0:
        return out
    ii = i_lo[:, None] + np.arange(wmax)[None, :]  # (N, wmax)
    jj = j_lo[:, None] + np.arange(hmax)[None, :]  # (N, hmax)
    vi = np.arange(wmax)[None, :] < span_i[:, None]
    vj = np.arange(hmax)[None, :] < span_j[:, None]
    dx = ii + 0.5 - cx[:, None]
    dy = jj + 0.5 - cy[:, None]
    ihx2 = 1.0 / (hx_s * hx_s)
    ihy2 = 1.0 / (hy_s * hy_s)
    ia2 = 1.0 / (hx_s * hx_s + hy_s * hy_s)
    dy2 = dy * dy
    ry = dy2 * ihy2[:, None]  # (N, hmax)
    dxx = dx * dx
    r2e = dxx[:, None, :] * ihx2[:, None, None] + ry[:, :, None]  # (N, hmax, wmax)
    inside = (r2e <= 1.0) & vi[:, None, :] & vj[:, :, None] & (ry <= 1.0)[:, :, None]
    if kernel == 0:
        wgt = 1.0 - (dxx[:, None, :] + dy2[:, :, None]) * ia2[:, None, None]
    else:
        wgt = 1.0 - r2e
    inside &= wgt > 0.0
    wgt = np.where(inside, wgt, 0.0)
    jc = np.clip(jj, 0, hgt - 1)
    ic = np.clip(ii, 0, wid - 1)
    b = bins[jc[:, :, None], ic[:, None, :]]  # (N, hmax, wmax)
    sel = inside.ravel()
    flat_w = wgt.ravel()[sel]
    pidx = np.broadcast_to(np.arange(n_part)[:, None, None], inside.shape).ravel()[sel]
    if half > 0:  # two-part histograms: the rows below the centre count in the bins from ``half`` on
        b = b + np.where(dy > 0.0, half, 0)[:, :, None]
    flat = pidx * n_bins + b.ravel()[sel]
    hist = np.bincount(flat, weights=flat_w, minlength=n_part * n_bins).reshape(n_part, n_bins)
    tot = np.bincount(pidx, weights=flat_w, minlength=n_part)
    totals[:] = tot
    pos = tot > 0
    out[pos] = hist[pos] * (1.0 / tot[pos])[:, None]
    return out
