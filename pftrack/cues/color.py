"""Kernel-weighted colour histograms over ellipses (Nummiaro et al., §3).

The colour distribution of the upright elliptic region with centre ``y`` and
half-axes ``Hx, Hy`` is (Eq. 3–4)::

    p^(u)_y = f * sum_i k(||y - x_i|| / a) * delta[h(x_i) - u],   f = 1 / sum_i k(||y - x_i|| / a)

over the pixels ``x_i`` of the region, with ``k(r) = 1 - r^2`` for ``r < 1`` (Eq. 2)
and ``a = sqrt(Hx^2 + Hy^2)``.  ``h`` maps a colour to its bin: RGB with 8x8x8
bins, or HSV with 8x8x4 (less sensitive to V).

Speed (GUIDE §3): the region that the particles can reach is quantised to bin
indices **once per frame** (:meth:`ColorCue.prepare`); the histograms of all ``N``
ellipses are then accumulated in one pass (:func:`ellipse_histograms`), compiled
with Numba or, without it, as one vectorised ``bincount`` over
``(particle, bin)`` pairs.  Both paths visit the same pixels in the same order
and give the same numbers.

Pixel convention: pixel ``(i, j)`` has its centre at ``(i + 0.5, j + 0.5)``; it
belongs to the ellipse when ``(dx/Hx)^2 + (dy/Hy)^2 <= 1`` for ``(dx, dy)`` the
offset of its centre from the ellipse centre.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from .._numba import njit, np_sum, numba_enabled
from .color_reference import _ellipse_hist_numpy
from .ellipse_rows import _row_spans
from .quantize import make_lut, quantize

KERNELS = {"nummiaro": 0, "epanechnikov": 1}
KernelName = Literal["nummiaro", "epanechnikov"]
ColorSpace = Literal["rgb", "hsv"]
DEFAULT_BINS = {"rgb": (8, 8, 8), "hsv": (8, 8, 4)}


# --------------------------------------------------------------------------- histograms

_ONE = np.uint64(1)
_TWO = np.uint64(2)


@njit
def _pixel_span(c, h, n_pixels):
    """First and last pixel index whose centre can lie within ``c ± h`` (clipped)."""
    lo = max(0, int(math.ceil(c - h - 0.5)))
    hi = min(n_pixels - 1, int(math.floor(c + h - 0.5)))
    return lo, hi


@njit(inline="always")
def _accumulate_rows(bins, cx, cy, hx, kernel, ia2, ihy2, acc0, acc1, mark, j_lo, r0, r1, span_a, span_b, off):
    """The rows ``r0 <= r < r1`` (``j_lo + r`` in ``bins``) of :func:`_accumulate_ellipse`, marking bin ``u + off``
    for a pixel of bin ``u``."""
    marking = mark.shape[0] > 0
    scale = ia2 if kernel == 0 else 1.0 / (hx * hx)
    dd = -2.0 * scale
    for r in range(r0, r1):
        a = span_a[r]
        b = span_b[r]
        if a > b:
            continue
        j = j_lo + r
        dy = j + 0.5 - cy
        dy2 = dy * dy
        row = bins[j]
        base = 1.0 - dy2 * ia2 if kernel == 0 else 1.0 - dy2 * ihy2
        dx = a + 0.5 - cx
        w0 = base - dx * dx * scale  # weight of pixel i
        d0 = -(2.0 * dx + 1.0) * scale  # w(i + 1) - w(i)
        if marking:
            for t in range(a, b + 1):
                mark[(row[t] + off) >> 3] = 1
        i = np.uint64(a)  # unsigned: Numba's indexing skips its test for a negative index
        bu = np.uint64(b)
        while i < bu:
            acc0[row[i]] += w0
            w1 = w0 + d0
            acc1[row[i + _ONE]] += w1
            w0 = w1 + d0 + dd
            d0 += 2.0 * dd
            i += _TWO
        if i == bu:
            acc0[row[i]] += w0


@njit(inline="always")
def _accumulate_ellipse(bins, cx, cy, hx, hy, kernel, acc0, acc1, mark, spans, half):
    """Add the kernel weights of one ellipse's pixels to ``acc0 + acc1`` (each (n_bins,)); with ``mark`` not
    empty, also set ``mark[u >> 3]`` for every bin ``u`` touched (groups of 8 bins, for a scan to skip the rest).
    ``spans``: (3, bins.shape[0]) int64 scratch for the rows' pixel spans.  ``half`` > 0 (two-part histograms):
    the pixels of the rows below the centre (``dy > 0``) go to bin ``u + half`` instead of ``u`` (a second pass
    over those rows with the accumulators' upper halves, so that one part keeps the loop as it was).

    Even and odd pixels of a row go to two separate histograms so that runs of the
    same bin do not serialise on one memory location, and the weight, a quadratic
    in the pixel index, is advanced by finite differences along the row.
    """
    hgt, wid = bins.shape
    if not (hx > 0.0 and hy > 0.0):
        return
    ihy2 = 1.0 / (hy * hy)
    ia2 = 1.0 / (hx * hx + hy * hy)
    j_lo = max(0, int(math.ceil(cy - hy - 0.5)))
    j_hi = min(hgt - 1, int(math.floor(cy + hy - 0.5)))
    n_rows = j_hi - j_lo + 1
    if n_rows <= 0:
        return
    span_a = spans[0]
    span_b = spans[1]
    _row_spans(cx, cy, hx, hy, j_lo, n_rows, wid, span_a, span_b, spans[2])
    if half == 0:
        _accumulate_rows(bins, cx, cy, hx, kernel, ia2, ihy2, acc0, acc1, mark, j_lo, 0, n_rows, span_a, span_b, 0)
        return
    split = 0  # the rows at or above the centre (j + 0.5 - cy <= 0) come first
    while split < n_rows and j_lo + split + 0.5 - cy <= 0.0:
        split += 1
    _accumulate_rows(bins, cx, cy, hx, kernel, ia2, ihy2, acc0, acc1, mark, j_lo, 0, split, span_a, span_b, 0)
    _accumulate_rows(bins, cx, cy, hx, kernel, ia2, ihy2, acc0[half:], acc1[half:], mark, j_lo, split, n_rows,
                     span_a, span_b, half)


@njit
def _ellipse_hist_numba(bins, x0, y0, ell, kernel, out, totals, acc, half):
    n_part = ell.shape[0]
    n_bins = out.shape[1]
    no_mark = np.empty(0, np.uint8)
    spans = np.empty((3, bins.shape[0]), np.int64)
    for n in range(n_part):
        _accumulate_ellipse(bins, ell[n, 0] - x0, ell[n, 1] - y0, ell[n, 2], ell[n, 3], kernel, acc[0], acc[1], no_mark,
                            spans, half)
        total = 0.0
        for u in range(n_bins):
            h = acc[0, u] + acc[1, u]
            if h < 0.0:
                h = 0.0  # rounding at the epanechnikov boundary
            out[n, u] = h
            total += h
            acc[0, u] = 0.0
            acc[1, u] = 0.0
        totals[n] = total
        if total > 0.0:
            inv = 1.0 / total
            for u in range(n_bins):
                out[n, u] *= inv
    return out


@njit
def _present_bins(bins, n_bins, half, out):
    """The bin indices that occur in ``bins``, ascending, in ``out[:m]`` (with ``half`` > 0, each also
    ``half`` higher: two-part histograms); returns ``m``."""
    seen = np.zeros(n_bins, np.uint8)
    h, w = bins.shape
    for j in range(h):
        row = bins[j]
        for i in range(w):
            seen[row[i]] = 1
    if half > 0:
        for u in range(half):
            if seen[u]:
                seen[u + half] = 1
    m = 0
    for u in range(n_bins):
        if seen[u]:
            out[m] = u
            m += 1
    return m


@njit(inline="always")
def _rho_from_acc(acc0, acc1, sqrt_q, u):
    """Bin ``u``'s terms of rho: ``(sqrt(h_u) sqrt(q_u), h_u)`` of ``h = acc0 + acc1``, resetting both (zeros for an
    empty bin; a tiny negative sum is rounding at the kernel's boundary: an empty bin too)."""
    a0 = acc0[u]
    a1 = acc1[u]
    if a0 == 0.0 and a1 == 0.0:
        return 0.0, 0.0
    acc0[u] = 0.0
    acc1[u] = 0.0
    h = a0 + a1
    if h > 0.0:
        return math.sqrt(h) * sqrt_q[u], h
    return 0.0, 0.0


@njit
def _ellipse_rho_numba(bins, x0, y0, ell, kernel, sqrt_q, rho, totals, acc, half):
    """Fused kernel: the Bhattacharyya coefficient of every ellipse's histogram with q.

    ``acc`` (2, n_bins) must be zero on entry and is zero on exit.  Normalisation is
    folded into the coefficient: rho = sum_u sqrt(h_u) sqrt(q_u) / sqrt(sum_u h_u).

    No fastmath: the summation order must not depend on how the code was compiled or cached.
    The sums run over the bins in ascending order and skip empty ones (most of them: an ellipse
    touches a few dozen of 512), which gives the same sums bit for bit as a scan of every bin, since
    the others would add exact zeros.  Which bins can be non-zero is known in one of two ways,
    whichever reads fewer pixels: the bins that occur in the region (one pass over it, when the
    ellipses cover it many times over, as a particle set does), or the groups of 8 bins each
    ellipse touched (marked while accumulating, when they are sparse in a large region: the
    background grid, the search samples).
    """
    acc0 = acc[0]
    acc1 = acc[1]
    n_bins = sqrt_q.shape[0]
    covered = 0.0
    for n in range(ell.shape[0]):
        covered += 4.0 * max(ell[n, 2], 0.0) * max(ell[n, 3], 0.0)
    by_region = bins.shape[0] * bins.shape[1] <= covered
    present = np.empty(n_bins if by_region else 0, np.uint64)  # unsigned: no negative-index test when read
    m = _present_bins(bins, n_bins, half, present) if by_region else 0
    mark = np.zeros(0 if by_region else (n_bins + 7) >> 3, np.uint8)
    spans = np.empty((3, bins.shape[0]), np.int64)
    for n in range(ell.shape[0]):
        _accumulate_ellipse(bins, ell[n, 0] - x0, ell[n, 1] - y0, ell[n, 2], ell[n, 3], kernel, acc0, acc1, mark,
                            spans, half)
        total = 0.0
        s = 0.0
        if by_region:
            for t in range(m):
                a, h = _rho_from_acc(acc0, acc1, sqrt_q, present[t])
                s += a
                total += h
        else:
            for g in range(mark.shape[0]):
                if mark[g] == 0:
                    continue
                mark[g] = 0
                for u in range(g << 3, min((g << 3) + 8, n_bins)):
                    a, h = _rho_from_acc(acc0, acc1, sqrt_q, u)
                    s += a
                    total += h
        totals[n] = total
        if total > 0.0:
            r = s / math.sqrt(total)
            rho[n] = 1.0 if r > 1.0 else r
        else:
            rho[n] = 0.0
    return rho


def _half(n_bins: int, parts: int) -> int:
    """The first bin of the lower part (0: one part)."""
    if parts == 1:
        return 0
    if parts != 2 or n_bins % 2:
        raise ValueError(f"parts must be 1, or 2 with an even number of bins; got {parts} parts of {n_bins} bins")
    return n_bins // 2


def ellipse_rho(bins: np.ndarray, x0: int, y0: int, ellipses: np.ndarray, sqrt_q: np.ndarray, *,
                kernel: KernelName = "nummiaro", out: np.ndarray | None = None, totals: np.ndarray | None = None,
                backend: str | None = None, _scratch: np.ndarray | None = None, parts: int = 1
                ) -> tuple[np.ndarray, np.ndarray]:
    """Bhattacharyya coefficients ``rho[p_n, q]`` of ``N`` ellipses without storing their histograms
    (``parts``: see :func:`ellipse_histograms`).

    Same result as ``bhattacharyya_coefficient(ellipse_histograms(...)[0], q)``
    (to floating-point rounding, < 1e-12): the compiled path fuses accumulation and
    comparison and visits only the bins an ellipse touches, which makes it several
    times faster than materialising ``N x m`` histograms.
    """
    ell = np.ascontiguousarray(ellipses, dtype=np.float64).reshape(-1, 4)
    n = ell.shape[0]
    if out is None:
        out = np.empty(n)
    if totals is None:
        totals = np.empty(n)
    sq = np.ascontiguousarray(sqrt_q, dtype=np.float64)
    half = _half(sq.size, parts)
    use_numba = numba_enabled() if backend is None else backend == "numba"
    if use_numba:
        acc = _scratch if _scratch is not None else np.zeros((2, sq.size))
        _ellipse_rho_numba(bins, int(x0), int(y0), ell, KERNELS[kernel], sq, out, totals, acc, half)
    else:
        h = np.empty((n, sq.size))
        _ellipse_hist_numpy(bins, int(x0), int(y0), ell, KERNELS[kernel], h, totals, half)
        np.sqrt(h, out=h)
        np.clip((h * sq).sum(axis=1), 0.0, 1.0, out=out)
    return out, totals


def ellipse_histograms(bins: np.ndarray, x0: int, y0: int, ellipses: np.ndarray, n_bins: int, *,
                       kernel: KernelName = "nummiaro", out: np.ndarray | None = None,
                       totals: np.ndarray | None = None, backend: str | None = None, parts: int = 1
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Normalised kernel-weighted histograms of ``N`` ellipses over quantised pixels.

    Parameters
    ----------
    bins : (h, w) int array of bin indices of a region whose top-left pixel is ``(x0, y0)``.
    ellipses : (N, 4) ``(cx, cy, hx, hy)`` in image coordinates.
    kernel : ``"nummiaro"`` — ``k(||d|| / a)``, ``a = sqrt(Hx^2 + Hy^2)`` (Eq. 2–3), or
        ``"epanechnikov"`` — ``1 - r^2`` with ``r`` the ellipse-normalised radius.
    backend : ``"numba"``, ``"numpy"`` or None (Numba when enabled).
    parts : 1, or 2 for a two-part histogram (Pérez et al., ECCV 2002; Okuma et al., ECCV 2004): the pixels of
        the rows above the ellipse's centre (``dy <= 0``) count in bins ``0 .. n_bins/2 - 1``, those below in
        ``n_bins/2 ..``, so that the layout of the colours (a walker's jacket over their trousers) is kept.  The
        kernel is symmetric about the centre, so each part holds about half of the mass, and the
        Bhattacharyya coefficient of two such histograms is about the mean of the two parts' coefficients.

    Returns
    -------
    hist : (N, n_bins) float64, each row sums to 1 (rows of ellipses with no
        pixel inside the region are all zero).
    totals : (N,) the kernel mass ``1 / f`` of each ellipse (0 when empty).
    """
    ell = np.ascontiguousarray(ellipses, dtype=np.float64).reshape(-1, 4)
    n = ell.shape[0]
    if out is None:
        out = np.empty((n, n_bins), dtype=np.float64)
    if totals is None:
        totals = np.empty(n, dtype=np.float64)
    k = KERNELS[kernel]
    half = _half(n_bins, parts)
    use_numba = numba_enabled() if backend is None else backend == "numba"
    if use_numba:
        _ellipse_hist_numba(bins, int(x0), int(y0), ell, k, out, totals, np.zeros((2, n_bins)), half)
    else:
        _ellipse_hist_numpy(bins, int(x0), int(y0), ell, k, out, totals, half)
    return out, totals


def kernel_weights(offsets: np.ndarray, hx: float, hy: float, *, kernel: KernelName = "nummiaro") -> np.ndarray:
    """Kernel weight ``k`` of pixel offsets ``(dx, dy)`` from an ellipse centre (Eq. 2).

    Zero outside the ellipse.  With ``kernel="nummiaro"``, ``k = 1 - (||d|| / a)^2``,
    ``a = sqrt(hx^2 + hy^2)``.
    """
    d = np.asarray(offsets, dtype=np.float64)
    dx, dy = d[..., 0], d[..., 1]
    r2e = dx * dx / (hx * hx) + dy * dy / (hy * hy)
    if kernel == "nummiaro":
        w = 1.0 - (dx * dx + dy * dy) / (hx * hx + hy * hy)
    else:
        w = 1.0 - r2e
    return np.where((r2e <= 1.0) & (w > 0), w, 0.0)


@njit
def _blend_model_numba(q, p, alpha, out_q, out_sqrt):
    for u in range(q.shape[0]):
        out_q[u] = (1.0 - alpha) * q[u] + alpha * p[u]
    s = np_sum(out_q)
    n = q.shape[0]
    for u in range(n):
        out_q[u] = out_q[u] / s if s > 0 else 1.0 / n
        out_sqrt[u] = math.sqrt(out_q[u])


def normalized_model(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A target model ``q`` scaled to unit mass (uniform if empty), and its square root: ``(q, sqrt(q))``."""
    q = np.asarray(q, dtype=np.float64)
    s = q.sum()
    q = q / s if s > 0 else np.full_like(q, 1.0 / q.size)
    return q, np.sqrt(q)


def model_rho(p: np.ndarray, sqrt_q: np.ndarray) -> float:
    """Bhattacharyya coefficient (Eq. 6) of one normalised histogram ``p`` with a model given as ``sqrt(q)``,
    clipped to [0, 1]; an element-wise sum, not BLAS, so the result does not depend on the BLAS thread count."""
    return min(max(float((np.sqrt(p) * sqrt_q).sum()), 0.0), 1.0)


def blend_model(q: np.ndarray, p: np.ndarray, alpha: float) -> tuple[np.ndarray, np.ndarray]:
    """The model update of Nummiaro et al. (Eq. 12), ``q <- (1 - alpha) q + alpha p``, renormalised (uniform if
    empty), and its square root: ``(q, sqrt(q))`` as new arrays; the compiled path gives NumPy's numbers."""
    if numba_enabled():
        out_q, out_sqrt = np.empty(q.shape[0]), np.empty(q.shape[0])
        _blend_model_numba(np.asarray(q, np.float64), np.asarray(p, np.float64), float(alpha), out_q, out_sqrt)
        return out_q, out_sqrt
    t = (1.0 - alpha) * q + alpha * p
    s = t.sum()
    t = t / s if s > 0 else np.full_like(t, 1.0 / t.size)
    return t, np.sqrt(t)


_WARM = False


def warmup() -> None:
    """Compile the kernels once per process (cached on disk by Numba) so timing excludes JIT."""
    global _WARM
    if _WARM or not numba_enabled():
        return
    img = np.zeros((4, 4, 3), np.uint8)
    lut = make_lut("rgb", (8, 8, 8))
    bins = quantize(img, lut)
    ell = np.array([[2.0, 2.0, 1.5, 1.5]])
    for k in KERNELS:
        ellipse_histograms(bins, 0, 0, ell, 512, kernel=k)
        ellipse_rho(bins, 0, 0, ell, np.ones(512), kernel=k)
    _WARM = True


def ellipse_pixels(bins: np.ndarray, x0: int, y0: int, ellipse) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pixel centres ``(xs, ys)`` (image coordinates) and bin indices of the pixels inside one ellipse."""
    cx, cy, hx, hy = (float(v) for v in ellipse)
    hgt, wid = bins.shape
    lcx, lcy = cx - x0, cy - y0
    i_lo, i_hi = _pixel_span(lcx, hx, wid)
    j_lo, j_hi = _pixel_span(lcy, hy, hgt)
    if i_hi < i_lo or j_hi < j_lo or hx <= 0 or hy <= 0:
        e = np.empty(0)
        return e, e, np.empty(0, dtype=np.int32)
    ii = np.arange(i_lo, i_hi + 1)
    jj = np.arange(j_lo, j_hi + 1)
    dx = ii + 0.5 - lcx
    dy = jj + 0.5 - lcy
    inside = (dx[None, :] * dx[None, :] * (1.0 / (hx * hx)) + (dy[:, None] * dy[:, None]) * (1.0 / (hy * hy))) <= 1.0
    jv, iv = np.nonzero(inside)
    return ii[iv] + 0.5 + x0, jj[jv] + 0.5 + y0, bins[jj[jv], ii[iv]]


# --------------------------------------------------------------------------- similarity

def bhattacharyya_coefficient(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``rho[p, q] = sum_u sqrt(p_u q_u)`` (Eq. 6), batched over leading axes of ``p``."""
    p = np.asarray(p, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    rho = np.sum(np.sqrt(np.clip(p, 0, None) * np.clip(q, 0, None)), axis=-1)
    return np.clip(rho, 0.0, 1.0)


def bhattacharyya_distance(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``d = sqrt(1 - rho[p, q])`` (Eq. 7)."""
    return np.sqrt(1.0 - bhattacharyya_coefficient(p, q))


# --------------------------------------------------------------------------- regions

def reachable_roi(ellipses: np.ndarray, width: int, height: int, margin: int = 1) -> tuple[int, int, int, int]:
    """Integer region ``(x0, y0, x1, y1)`` (exclusive end) that covers every ellipse, clipped to the image."""
    e = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
    x0 = int(math.floor(float((e[:, 0] - e[:, 2]).min()))) - margin
    y0 = int(math.floor(float((e[:, 1] - e[:, 3]).min()))) - margin
    x1 = int(math.ceil(float((e[:, 0] + e[:, 2]).max()))) + margin
    y1 = int(math.ceil(float((e[:, 1] + e[:, 3]).max()))) + margin
    x0 = min(max(x0, 0), width)
    y0 = min(max(y0, 0), height)
    x1 = min(max(x1, x0), width)
    y1 = min(max(y1, y0), height)
    return x0, y0, x1, y1
