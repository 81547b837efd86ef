"""The compiled colour coefficients (``cues.color._ellipse_rho_numba``) against a plain Python transcription of the
sums they run, bit for bit: each ellipse's pixels row by row, the kernel weight advanced along a row by finite
differences, even and odd pixels in two accumulators, then the bins in ascending order."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pftrack._numba import numba_enabled
from pftrack.cues.color import ellipse_rho

pytestmark = pytest.mark.skipif(not numba_enabled(), reason="a property of the compiled kernel")


def _rho_reference(bins, x0, y0, e, kernel, sqrt_q, half):
    """``(rho, total)`` of one ellipse ``e`` (image coordinates) over ``bins`` (top-left pixel ``(x0, y0)``)."""
    hgt, wid = bins.shape
    n_bins = sqrt_q.size
    acc0, acc1 = [0.0] * n_bins, [0.0] * n_bins
    cx, cy, hx, hy = float(e[0]) - x0, float(e[1]) - y0, float(e[2]), float(e[3])
    if hx > 0.0 and hy > 0.0:
        ihx2, ihy2 = 1.0 / (hx * hx), 1.0 / (hy * hy)
        ia2 = 1.0 / (hx * hx + hy * hy)
        scale = ia2 if kernel == 0 else ihx2
        dd = -2.0 * scale
        for j in range(max(0, math.ceil(cy - hy - 0.5)), min(hgt - 1, math.floor(cy + hy - 0.5)) + 1):
            dy = j + 0.5 - cy
            ry = dy * dy * ihy2
            inside = [i for i in range(wid) if (i + 0.5 - cx) * (i + 0.5 - cx) * ihx2 + ry <= 1.0]
            if not inside:
                continue
            a, b = inside[0], inside[-1]
            off = half if half > 0 and dy > 0.0 else 0  # two-part histograms: the rows below the centre
            base = 1.0 - dy * dy * ia2 if kernel == 0 else 1.0 - dy * dy * ihy2
            dx = a + 0.5 - cx
            w0 = base - dx * dx * scale
            d0 = -(2.0 * dx + 1.0) * scale
            i = a
            while i < b:
                acc0[int(bins[j, i]) + off] += w0
                w1 = w0 + d0
                acc1[int(bins[j, i + 1]) + off] += w1
                w0 = w1 + d0 + dd
                d0 += 2.0 * dd
                i += 2
            if i == b:
                acc0[int(bins[j, i]) + off] += w0
    s = total = 0.0
    for u in range(n_bins):
        if acc0[u] == 0.0 and acc1[u] == 0.0:
            continue
        h = acc0[u] + acc1[u]
        if h > 0.0:
            s += math.sqrt(h) * float(sqrt_q[u])
            total += h
    if total > 0.0:
        return min(s / math.sqrt(total), 1.0), total
    return 0.0, total


@pytest.mark.parametrize("kernel", ["nummiaro", "epanechnikov"])
@pytest.mark.parametrize("parts", [1, 2])
@pytest.mark.parametrize("crowd", ["particles", "sparse"])
def test_compiled_rho_equals_its_plain_transcription_bit_for_bit(kernel, parts, crowd):
    """Both ways the kernel finds the bins to sum (the region's bins when the ellipses cover it many times over,
    the groups of bins each ellipse marked when they are few), both kernels, one- and two-part histograms, ellipses
    reaching past the region's border, degenerate ones, and runs of equal bins (the accumulators' reason)."""
    rng = np.random.default_rng(17 + parts)
    n_bins = 512
    bins = rng.integers(0, n_bins // parts, (48, 64)).astype(np.uint16)
    bins[10:30, 20:44] = 7  # a flat patch: runs of one bin
    q = rng.random(n_bins)
    sqrt_q = np.sqrt(q / q.sum())
    x0, y0 = 13, -5
    if crowd == "particles":
        ell = np.column_stack([rng.uniform(x0 - 5, x0 + 70, 60), rng.uniform(y0 - 5, y0 + 55, 60),
                               rng.uniform(6, 30, 60), rng.uniform(6, 30, 60)])
    else:
        ell = np.column_stack([rng.uniform(x0, x0 + 64, 6), rng.uniform(y0, y0 + 48, 6), rng.uniform(3, 9, 6),
                               rng.uniform(3, 9, 6)])  # covering less than the region: the marked groups
    ell[0, 2] = 0.0  # no pixels
    ell[1] = (x0 + 20.5, y0 + 19.5, 1.0, 1.0)  # pixel centres on the boundary (the exact test's rows)
    rho, tot = ellipse_rho(bins, x0, y0, ell, sqrt_q, kernel=kernel, backend="numba", parts=parts)
    k = 0 if kernel == "nummiaro" else 1
    half = n_bins // 2 if parts == 2 else 0
    for n, e in enumerate(ell):
        r, t = _rho_reference(bins, x0, y0, e, k, sqrt_q, half)
        assert (rho[n], tot[n]) == (r, t), n
    assert tot[0] == 0.0 and rho[0] == 0.0
    assert np.count_nonzero(tot > 0) >= len(ell) - 1
