"""The pixel rows of an upright ellipse, for the kernel histograms of :mod:`pftrack.cues.color`.

Pixel ``(i, j)`` (centre ``(i + 0.5, j + 0.5)``) belongs to the ellipse ``(cx, cy, hx, hy)`` when
``(dx / hx)^2 + (dy / hy)^2 <= 1``.  Each row's span follows from a square root; the exact test decides the
rows whose ends lie within rounding error of a pixel centre.
"""

from __future__ import annotations

import math

from .._numba import njit


#: A row's analytic span (from a square root) is trusted when both its ends lie further than ``_SNAP`` pixels
#: from a pixel centre and ``1 - ry`` exceeds ``_GRAZE``: rounding moves them by far less (~1e-12 px for
#: half-axes below 10^4; near the ellipse's top and bottom the root amplifies the error of ``ry``, hence
#: the second bound).  Other rows take the exact test of :func:`_row_span`.
_SNAP = 1e-5
_GRAZE = 1e-4


@njit(inline="always")
def _row_spans(cx, cy, hx, hy, j_lo, n_rows, wid, span_a, span_b, fix):
    """Pixel spans ``[span_a[r], span_b[r]]`` of rows ``j_lo + r`` inside the ellipse, exactly those of
    :func:`_row_span` (clipped to ``[0, wid - 1]``).  The analytic spans are computed for all rows first (a
    branch-free loop the compiler vectorises); only rows whose ends lie within rounding error of a pixel
    centre are redone with the exact test (almost never)."""
    ihx2 = 1.0 / (hx * hx)
    ihy2 = 1.0 / (hy * hy)
    n_fix = 0
    for r in range(n_rows):
        dy = j_lo + r + 0.5 - cy
        slack = 1.0 - dy * dy * ihy2
        half = hx * math.sqrt(max(slack, 0.0))
        t_a = cx - half - 0.5
        t_b = cx + half - 0.5
        fa = math.ceil(t_a)
        fb = math.floor(t_b)
        span_a[r] = max(int(fa), 0)
        span_b[r] = min(int(fb), wid - 1)
        da = fa - t_a
        db = t_b - fb
        trusted = (slack > _GRAZE) & (da > _SNAP) & (da < 1.0 - _SNAP) & (db > _SNAP) & (db < 1.0 - _SNAP)
        fix[r] = not trusted
        n_fix += 0 if trusted else 1
    if n_fix == 0:
        return
    for r in range(n_rows):
        if fix[r]:
            dy = j_lo + r + 0.5 - cy
            ry = dy * dy * ihy2
            if ry > 1.0:
                span_a[r] = 1
                span_b[r] = 0
            else:
                span_a[r], span_b[r] = _row_span(cx, hx, ihx2, ry, 0, wid - 1)


@njit
def _row_span(cx, hx, ihx2, ry, lo, hi):
    """Pixel indices [a, b] of one row inside the ellipse: exactly the i with dx^2/hx^2 + ry <= 1."""
    half = hx * math.sqrt(max(1.0 - ry, 0.0))
    a = int(math.ceil(cx - half - 0.5))
    b = int(math.floor(cx + half - 0.5))
    # the analytic span can be off by one pixel through rounding: fix it with the exact test
    while a <= b and (a + 0.5 - cx) * (a + 0.5 - cx) * ihx2 + ry > 1.0:
        a += 1
    while (a - 1 + 0.5 - cx) * (a - 1 + 0.5 - cx) * ihx2 + ry <= 1.0:
        a -= 1
    while b >= a and (b + 0.5 - cx) * (b + 0.5 - cx) * ihx2 + ry > 1.0:
        b -= 1
    while (b + 1 + 0.5 - cx) * (b + 1 + 0.5 - cx) * ihx2 + ry <= 1.0:
        b += 1
    return max(a, lo), min(b, hi)
