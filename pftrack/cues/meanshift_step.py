"""The mean-shift step of Comaniciu, Ramesh & Meer on quantised features: the weighted centroid of an ellipse's
pixels, ``y1 = sum_i x_i w_i / sum_i w_i`` with ``w_i = ratio[bin(x_i)]`` (``ratio_u = sqrt(q_u / p_u(y0))``).

:func:`shift_sums` gives ``(sum w, sum x w, sum y w)`` over the pixels whose centres lie inside the ellipse
(:func:`pftrack.cues.color.ellipse_pixels`' pixel set, in its row-major order).  Compiled, it visits the pixels
without building the coordinate arrays, and sums as NumPy does (:func:`pftrack._numba.np_sum`, pairwise), so the
step is the same to the last bit as the NumPy reference below.
"""

from __future__ import annotations

import numpy as np

from .._numba import njit, np_sum, numba_enabled
from .color import _pixel_span, ellipse_pixels

__all__ = ["shift_sums"]


@njit(cache=True)
def _shift_sums(bins, x0, y0, cx, cy, hx, hy, ratio):
    hgt, wid = bins.shape
    lcx, lcy = cx - x0, cy - y0
    i_lo, i_hi = _pixel_span(lcx, hx, wid)
    j_lo, j_hi = _pixel_span(lcy, hy, hgt)
    if i_hi < i_lo or j_hi < j_lo or hx <= 0 or hy <= 0:
        return 0, 0.0, 0.0, 0.0
    ax = 1.0 / (hx * hx)
    ay = 1.0 / (hy * hy)
    cap = (i_hi - i_lo + 1) * (j_hi - j_lo + 1)
    w = np.empty(cap)
    xw = np.empty(cap)
    yw = np.empty(cap)
    n = 0
    for j in range(j_lo, j_hi + 1):
        dy = j + 0.5 - lcy
        ty = (dy * dy) * ay
        yc = j + 0.5 + y0
        row = bins[j]
        for i in range(i_lo, i_hi + 1):
            dx = i + 0.5 - lcx
            if dx * dx * ax + ty <= 1.0:
                wi = ratio[row[i]]
                w[n] = wi
                xw[n] = (i + 0.5 + x0) * wi
                yw[n] = yc * wi
                n += 1
    return n, np_sum(w[:n]), np_sum(xw[:n]), np_sum(yw[:n])


def shift_sums(bins: np.ndarray, x0: int, y0: int, ellipse, ratio: np.ndarray) -> tuple[int, float, float, float]:
    """``(n, sum w, sum x w, sum y w)`` over the ``n`` pixels of ``bins`` (a region whose top-left pixel is
    ``(x0, y0)``) whose centres lie inside ``ellipse`` ``(cx, cy, hx, hy)``, with ``w = ratio[bin]`` and ``(x, y)``
    the pixel centres in image coordinates."""
    cx, cy, hx, hy = (float(v) for v in ellipse)
    r = np.ascontiguousarray(ratio, dtype=np.float64)
    if numba_enabled():
        n, sw, sx, sy = _shift_sums(np.ascontiguousarray(bins), int(x0), int(y0), cx, cy, hx, hy, r)
        return int(n), float(sw), float(sx), float(sy)
    xs, ys, b = ellipse_pixels(bins, x0, y0, (cx, cy, hx, hy))
    if xs.size == 0:
        return 0, 0.0, 0.0, 0.0
    w = r[b]
    return int(xs.size), float(w.sum()), float(np.sum(xs * w)), float(np.sum(ys * w))
