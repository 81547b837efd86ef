"""Features for grey frames: equalised intensity x gradient orientation.

On a grey frame (a monochrome camera, or all three channels equal) an RGB
histogram collapses onto its diagonal: 8 of its 512 bins are used, the target
and the background look alike, and the appearance condition of Nummiaro et al.
loses its meaning.  The colour trackers then describe a pixel instead by

* its **intensity after global histogram equalisation** of the frame (the rank
  of its grey level in the frame), which a global, monotonic illumination change
  leaves almost unchanged, in ``n_intensity`` bins; and
* the **orientation of its intensity gradient** (3x3 Sobel on the equalised
  image), in ``n_orientation`` bins over ``[0, 2 pi)``, or a "flat" bin when the
  gradient magnitude is below ``gradient_threshold``: a structure cue that a
  gain change does not move at all.

The joint bin is ``i_bin * (n_orientation + 1) + o_bin``: the histogram has
``n_intensity * (n_orientation + 1)`` bins and plugs into the same kernel
histogram and Bhattacharyya machinery as the colour bins.

:func:`is_gray` decides from the input which features a cue uses.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .._numba import njit, numba_enabled
from ..frames import bgr_view, grey_origin
from .gray_kernels import exact_gray_available, gray_bins, lattice_levels_gradients
from .lk import ncc as patch_ncc


def _coloured_count_numpy(frame: np.ndarray, stride: int, tolerance: int, limit: int) -> int:
    s = frame[::stride, ::stride].astype(np.int16)
    d = np.maximum(np.abs(s[..., 0] - s[..., 1]), np.abs(s[..., 1] - s[..., 2]))
    return min(int(np.count_nonzero(d > tolerance)), limit)


@njit(cache=True)
def _coloured_count_numba(frame, stride, tolerance, limit):  # pragma: no cover - compiled
    h, w = frame.shape[0], frame.shape[1]
    count = 0
    for y in range(0, h, stride):
        for x in range(0, w, stride):
            b = np.int32(frame[y, x, 0])
            g = np.int32(frame[y, x, 1])
            r = np.int32(frame[y, x, 2])
            if abs(b - g) > tolerance or abs(g - r) > tolerance:
                count += 1
                if count >= limit:  # enough colour seen: a colour frame is told after its first coloured samples
                    return count
    return count


def is_gray(frame: np.ndarray, *, tolerance: int = 2, stride: int = 4) -> bool:
    """True when a BGR frame carries no colour: at most 1 % of a ``stride`` lattice's pixels has a channel more than
    ``tolerance`` from another.

    A 2-D array is grey by definition.  JPEG compression of a grey source leaves channel differences of a level or
    two.  Compiled with an early exit, so that a colour frame costs a few microseconds.
    """
    if frame.ndim == 2 or frame.shape[2] == 1:
        return True
    h, w = frame.shape[:2]
    n = ((h + stride - 1) // stride) * ((w + stride - 1) // stride)
    limit = n // 100 + 1  # more coloured pixels than 1 % of the lattice: a colour frame
    if numba_enabled():
        return _coloured_count_numba(frame, stride, tolerance, limit) < limit
    return _coloured_count_numpy(frame, stride, tolerance, limit) < limit


def to_gray(region: np.ndarray) -> np.ndarray:
    """uint8 grey of a BGR or grey region (contiguous)."""
    if region.ndim == 2:
        return np.ascontiguousarray(region)
    if region.shape[2] == 1:
        return np.ascontiguousarray(region[..., 0])
    return cv2.cvtColor(bgr_view(region), cv2.COLOR_BGR2GRAY)


def equalization_lut(frame: np.ndarray, *, stride: int = 4, gray: np.ndarray | None = None) -> np.ndarray:
    """``(256,)`` uint8 lookup table of global histogram equalisation, from a ``stride`` lattice.

    The table maps a grey level to its rank in the frame (the cumulative
    histogram), scaled to ``[0, 255]``; it is monotonic, so structure is kept.
    ``gray``: the frame's grey image, when it is at hand (the same table, from its lattice).
    """
    if gray is None and frame.ndim == 2:
        gray = frame
    if gray is not None and gray.dtype == np.uint8 and gray.size and numba_enabled():
        return _equalization_lut_compiled(gray, int(stride))
    sub = to_gray(_lattice(frame, stride)) if gray is None else np.ascontiguousarray(gray[::stride, ::stride])
    if sub.dtype == np.uint8 and sub.size:  # OpenCV's histogram: the same counts, 3x faster than np.bincount
        hist = cv2.calcHist([sub], [0], None, [256], [0, 256]).ravel().astype(np.float64)
    else:
        hist = np.bincount(sub.ravel(), minlength=256).astype(np.float64)
    cdf = np.cumsum(hist)
    total = cdf[-1]
    if total <= 0:
        return np.arange(256, dtype=np.uint8)
    # mid-rank of each level, so a flat frame maps to the middle grey rather than to 255
    mid = (cdf - 0.5 * hist) / total
    return np.clip(np.round(mid * 255.0), 0, 255).astype(np.uint8)


@njit(cache=True)
def _equalization_lut_compiled(gray, stride):
    """:func:`equalization_lut` of a 2-D uint8 image in one pass: the histogram of its ``stride`` lattice, read
    in place, and the mid-rank table, with the NumPy path's float64 operations in its order (the same table)."""
    hist = np.zeros(256, np.float64)
    for y in range(0, gray.shape[0], stride):
        row = gray[y]
        for x in range(0, gray.shape[1], stride):
            hist[row[x]] += 1.0
    cdf = np.empty(256, np.float64)
    acc = 0.0
    for v in range(256):
        acc += hist[v]
        cdf[v] = acc
    out = np.empty(256, np.uint8)
    total = cdf[255]
    if total <= 0:
        for v in range(256):
            out[v] = v
        return out
    for v in range(256):
        r = np.rint((cdf[v] - 0.5 * hist[v]) / total * 255.0)
        out[v] = np.uint8(min(max(r, 0.0), 255.0))
    return out


#: From this lattice pitch on, the grey features are computed on the 3x3 neighbourhoods of the lattice points only
#: (9 / pitch^2 of the region's pixels) instead of on the whole region; from pitch 4 on already for regions of
#: at least ``_LARGE_REGION`` pixels, whose whole-region float gradients no longer fit the cache (a whole
#: 640 x 360 frame took 1.1-1.7 ms that way, its neighbourhoods at pitch 4 0.25-0.65 ms; a 260 x 240 region at
#: pitch 4 was faster whole).
_NEIGHBOURHOOD_PITCH = 5
_LARGE_REGION = 1 << 17
_OFFSETS = np.array([-1, 0, 1])


@njit
def _gather(frame, rows, cols, nc, out):
    """``out[i, j] = frame[rows[i], cols[j]]`` of a frame given as its ``(H, W * nc)`` rows of ``nc`` channels;
    ``out`` is ``(len(rows), len(cols) * nc)``."""
    for i in range(rows.shape[0]):
        src = frame[rows[i]]
        dst = out[i]
        if nc == 3:  # unrolled: 4-7x faster than the loop over channels
            for j in range(cols.shape[0]):
                c = cols[j] * 3
                dst[3 * j] = src[c]
                dst[3 * j + 1] = src[c + 1]
                dst[3 * j + 2] = src[c + 2]
        else:
            for j in range(cols.shape[0]):
                c = cols[j] * nc
                for k in range(nc):
                    dst[j * nc + k] = src[c + k]
    return out


def _lattice(frame: np.ndarray, stride: int) -> np.ndarray:
    """``frame[::stride, ::stride]`` as a contiguous array (compiled gather for a contiguous 3-channel frame: NumPy
    copies the strided 3-byte pixels several times slower)."""
    if stride > 1 and numba_enabled() and frame.ndim == 3 and frame.shape[2] == 3 and frame.flags.c_contiguous:
        fh, fw = frame.shape[:2]
        rows, cols = np.arange(0, fh, stride), np.arange(0, fw, stride)
        out = _gather(frame.reshape(fh, fw * 3), rows, cols, 3, np.empty((rows.size, cols.size * 3), frame.dtype))
        return out.reshape(rows.size, cols.size, 3)
    return np.ascontiguousarray(frame[::stride, ::stride])


def _lattice_gradients(frame: np.ndarray, roi: tuple[int, int, int, int], pitch: int, lut: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The equalised grey level and its 3x3 Sobel gradient at every ``pitch``-th pixel of ``roi``, from the
    lattice points' 3x3 neighbourhoods alone: they are gathered side by side (rows and columns beyond the frame
    repeat its edge, as the whole-region computation's replicated border does), converted and filtered, and
    the centres kept.  A 3x3 Sobel at a centre reads only its own neighbourhood, so the numbers are those of
    the whole-region computation."""
    x0, y0, x1, y1 = roi
    fh, fw = frame.shape[:2]
    ys = np.arange(y0, min(y1, fh), pitch)
    xs = np.arange(x0, min(x1, fw), pitch)
    rows = np.clip((ys[:, None] + _OFFSETS).ravel(), 0, fh - 1)
    cols = np.clip((xs[:, None] + _OFFSETS).ravel(), 0, fw - 1)
    if numba_enabled() and frame.flags.c_contiguous:
        nc = frame.shape[2] if frame.ndim == 3 else 1
        sub = _gather(frame.reshape(fh, fw * nc), rows, cols, nc, np.empty((rows.size, cols.size * nc), frame.dtype))
        sub = sub.reshape((rows.size, cols.size) + frame.shape[2:])
    else:
        sub = frame[rows[:, None], cols[None, :]]
    g = cv2.LUT(to_gray(sub), lut)
    dx, dy = _sobel3(g)
    return g[1::3, 1::3], dx[1::3, 1::3], dy[1::3, 1::3]


def _sobel3(g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The 3x3 Sobel derivatives ``(d/dx, d/dy)`` of a ``uint8`` image with replicated border, ``int16``: the
    numbers of ``cv2.Sobel(g, cv2.CV_32F, ..., ksize=3)`` (integers, |d| <= 1020), both from one pass of
    ``cv2.spatialGradient`` (3-14x faster than two float Sobel filters on target-sized regions; tested equal)."""
    return cv2.spatialGradient(g, ksize=3, borderType=cv2.BORDER_REPLICATE)


def quantize_gray(frame: np.ndarray, roi: tuple[int, int, int, int], pitch: int, lut: np.ndarray, *,
                  n_intensity: int, n_orientation: int, gradient_threshold: float,
                  out: np.ndarray | None = None) -> np.ndarray:
    """Joint intensity/orientation bin of every ``pitch``-th pixel of ``roi = (x0, y0, x1, y1)``.

    ``x0, y0`` must already be multiples of ``pitch``.  The gradient is computed on
    the full-resolution region grown by one pixel (so the region's border pixels
    have true gradients), then sampled on the lattice.  Returns ``(h, w)`` uint16.
    """
    x0, y0, x1, y1 = roi
    fh, fw = frame.shape[:2]
    grey = grey_origin(frame)
    if grey is not None:  # a BGR frame made from a grey image: its one channel, the same levels (v, v, v) -> v
        frame = grey
    if (pitch >= 3 and frame.dtype == np.uint8 and frame.flags.c_contiguous
            and (frame.ndim == 2 or frame.shape[2] in (1, 3)) and exact_gray_available()):
        # compiled, the same numbers: each lattice point converts and filters its own 3x3 neighbourhood
        # (pftrack.cues.gray_kernels; 1.5-2x faster than the OpenCV steps below at pitch 8)
        g, dx, dy = lattice_levels_gradients(frame, np.arange(y0, min(y1, fh), pitch),
                                             np.arange(x0, min(x1, fw), pitch), lut)
    elif pitch >= _NEIGHBOURHOOD_PITCH or (pitch >= 4 and (min(x1, fw) - x0) * (min(y1, fh) - y0) >= _LARGE_REGION):
        g, dx, dy = _lattice_gradients(frame, roi, pitch, lut)
    else:
        gx0, gy0, gx1, gy1 = max(x0 - 1, 0), max(y0 - 1, 0), min(x1 + 1, fw), min(y1 + 1, fh)
        g = cv2.LUT(to_gray(frame[gy0:gy1, gx0:gx1]), lut)
        dx, dy = _sobel3(g)
        sl = (slice(y0 - gy0, y1 - gy0, pitch), slice(x0 - gx0, x1 - gx0, pitch))
        g, dx, dy = g[sl], dx[sl], dy[sl]
    mag, ang = cv2.cartToPolar(dx.astype(np.float32, copy=False), dy.astype(np.float32, copy=False))
    h, w = g.shape
    if out is None:
        out = np.empty((h, w), dtype=np.uint16)
    if numba_enabled():
        return gray_bins(g, mag, ang, n_intensity, n_orientation, gradient_threshold, out)
    ob = (ang * np.float32(n_orientation / (2.0 * math.pi))).astype(np.int32)
    ob[ob >= n_orientation] = 0  # the angle 2 pi wraps to 0
    ob[mag < gradient_threshold] = n_orientation  # the "flat" bin
    ib = (g.astype(np.int32) * n_intensity) >> 8
    np.add(ib * (n_orientation + 1), ob, out=out, casting="unsafe")
    return out


# ------------------------------------------------------------------------------ colour frames under changing light

@njit(cache=True)
def _lattice_medians(frame, stride, out):
    """Each channel's median over the ``stride`` lattice of a uint8 ``(H, W, C)`` frame, from its histogram: the
    mean of the sorted values at positions ``(n - 1) // 2`` and ``n // 2`` (:func:`channel_levels`'s numbers)."""
    h, w, nc = frame.shape
    counts = np.zeros((nc, 256), np.int64)
    n = 0
    for y in range(0, h, stride):
        for x in range(0, w, stride):
            for c in range(nc):
                counts[c, frame[y, x, c]] += 1
            n += 1
    t_lo = (n - 1) // 2
    t_hi = n // 2
    for c in range(nc):
        cum = 0
        lo = -1
        for v in range(256):  # the first level with more than t pixels at or below it
            cum += counts[c, v]
            if lo < 0 and cum > t_lo:
                lo = v
            if cum > t_hi:
                out[c] = (float(lo) + float(v)) / 2.0
                break
    return out


def channel_levels(frame: np.ndarray, *, stride: int = 4) -> np.ndarray:
    """Robust per-channel level of a BGR frame: the median of a ``stride`` lattice, ``(3,)`` float (for 8-bit
    frames from each channel's histogram: the same numbers as ``np.median``, several times faster; compiled for
    a 3-D frame when Numba is on)."""
    if (numba_enabled() and frame.ndim == 3 and frame.dtype == np.uint8 and frame.shape[0] > 0
            and frame.shape[1] > 0):
        return np.maximum(_lattice_medians(frame, int(stride), np.empty(frame.shape[2])), 1.0)
    sub = frame[::stride, ::stride].reshape(-1, frame.shape[2] if frame.ndim == 3 else 1)
    n = sub.shape[0]
    if sub.dtype != np.uint8 or n == 0:
        return np.maximum(np.median(sub, axis=0).astype(np.float64), 1.0)
    out = np.empty(sub.shape[1])
    for c in range(sub.shape[1]):
        cum = np.cumsum(np.bincount(sub[:, c], minlength=256))
        # the sorted values at positions (n - 1) // 2 and n // 2: the smallest levels with more pixels at or below
        lo, hi = np.searchsorted(cum, ((n - 1) // 2, n // 2), side="right")
        out[c] = (float(lo) + float(hi)) / 2.0
    return np.maximum(out, 1.0)


def light_levels(frame: np.ndarray, mode: str = "frame") -> np.ndarray:
    """The light of a BGR frame as the relit search reads it: the frame's channel levels (``"frame"``, ``(3,)``), or
    those of each block of a 3 x 3 grid (``"blocks"`` and ``"still"``, ``(9, 3)``; :func:`light_gain`)."""
    if mode == "frame":
        return channel_levels(frame, stride=16)
    h, w = frame.shape[:2]
    return np.stack([channel_levels(frame[i * h // 3:(i + 1) * h // 3, j * w // 3:(j + 1) * w // 3], stride=8)
                     for i in range(3) for j in range(3)])


def light_gain(reference: np.ndarray, current: np.ndarray, *, tol: float = 0.05, share: float = 2 / 3,
               still: np.ndarray | None = None) -> np.ndarray | None:
    """Per-channel gain ``(3,)`` that brings the light ``current`` back to ``reference`` (:func:`light_levels`).

    For whole-frame levels, their ratio. For blocks, the median of the blocks' ratios, and only when at least
    ``share`` of the blocks agree with it within ``tol`` in every channel: a change of the light moves the whole
    view alike, while something passing through one part of it (a car, a walker) moves that part alone, and is
    not a change of the light (None).  With ``still`` (``(B,)`` bool, :func:`still_blocks`), only the blocks whose
    layout is unchanged are read, and ``share`` of all the blocks must be such and agree: a camera that moves
    changes the layout of every block, whatever their levels do."""
    r = np.asarray(reference, np.float64) / np.asarray(current, np.float64)
    if r.ndim == 1:
        return r
    need = share * len(r)
    if still is not None:
        r = r[np.asarray(still, dtype=bool)]
        if len(r) == 0 or len(r) < need:
            return None
    g = np.median(r, axis=0)
    agree = np.all(np.abs(r / g - 1.0) <= tol, axis=1)
    return g if float(agree.sum()) >= need else None


#: :func:`still_blocks`: a block whose thumbnail correlates at least this much with the reference's keeps its layout.
STILL_NCC = 0.8


def light_thumbnail(frame: np.ndarray) -> np.ndarray:
    """A grey thumbnail of a frame at 1/8 of its size (at least 9 x 9 pixels), float64: the layout that
    :func:`still_blocks` compares, blind to the fine texture and noise a change of the light leaves alone."""
    g = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY) if frame.ndim == 3 else frame
    h, w = g.shape[:2]
    return cv2.resize(g, (max(w // 8, 9), max(h // 8, 9)), interpolation=cv2.INTER_AREA).astype(np.float64)


def still_blocks(reference: np.ndarray, current: np.ndarray, *, ncc: float = STILL_NCC) -> np.ndarray:
    """``(9,)`` bool: which blocks of a 3 x 3 grid of two thumbnails (:func:`light_thumbnail`, same shape) keep their
    layout, their normalised correlation at least ``ncc``.  The correlation ignores a gain and an offset, so a
    change of the light leaves a block still; a moving camera, or something passing through the block, does not.
    A flat block (no layout to compare) is not still."""
    if reference is None:
        return np.zeros(9, dtype=bool)
    a, b = np.asarray(reference, np.float64), np.asarray(current, np.float64)
    if a.shape != b.shape:
        return np.zeros(9, dtype=bool)
    h, w = a.shape
    out = np.zeros(9, dtype=bool)
    for i in range(3):
        for j in range(3):
            rows, cols = slice(i * h // 3, (i + 1) * h // 3), slice(j * w // 3, (j + 1) * w // 3)
            out[3 * i + j] = patch_ncc(a[None, rows, cols], b[None, rows, cols])[0] >= ncc  # flat: 0
    return out


def frame_light_gain(levels: np.ndarray, thumb: np.ndarray | None, frame: np.ndarray, mode: str = "frame"
                     ) -> np.ndarray | None:
    """The gain that brings ``frame``'s light back to a reference read by :func:`light_levels` (``levels``) and, for
    ``mode="still"``, :func:`light_thumbnail` (``thumb``): :func:`light_gain`, over the still blocks in that mode."""
    still = still_blocks(thumb, light_thumbnail(frame)) if mode == "still" else None
    return light_gain(levels, light_levels(frame, mode), still=still)


def gain_maps(reference: np.ndarray, current: np.ndarray) -> np.ndarray:
    """``(3, 256)`` uint8 maps that undo a per-channel gain (von Kries adaptation to a reference frame).

    A global illumination change scales each channel by a factor; dividing by the
    ratio of the channel levels now and in the reference frame brings the colours
    back, so a colour model learnt in the reference frame still matches.
    """
    g = np.asarray(reference, np.float64) / np.asarray(current, np.float64)
    v = np.arange(256, dtype=np.float64)
    return np.clip(np.round(v[None, :] * g[:, None]), 0, 255).astype(np.uint8)


def channel_equalization_maps(frame: np.ndarray, *, stride: int = 4) -> np.ndarray:
    """``(3, 256)`` uint8 maps: global histogram equalisation of each channel (ranks, see :func:`equalization_lut`)."""
    return np.stack([equalization_lut(np.ascontiguousarray(frame[::stride, ::stride, c]), stride=1)
                     for c in range(3)])


def shifted_rho(hist: np.ndarray, sqrt_q: np.ndarray, n_intensity: int, n_orientation: int, k: int) -> np.ndarray:
    """Bhattacharyya coefficients of grey-feature histograms ``hist`` ``(N, B)`` (each normalised; ``B = n_intensity
    (n_orientation + 1)``, the joint bins of :func:`quantize_gray`) with a model ``sqrt(q)``, the best over the
    model's intensity bins shifted by ``-k .. k`` (orientation kept; the bins shifted past an end are dropped).

    A target whose own light changed while it was unseen, as a grey target walking out of a shadow does, keeps the
    layout of its grey levels and gradients but moves them up or down the intensity axis; the frame's equalisation
    does not undo a gain on the target alone.  ``k = 0`` gives the plain coefficients."""
    h = np.sqrt(np.clip(np.asarray(hist, dtype=np.float64), 0.0, None)).reshape(len(hist), n_intensity, -1)
    q = np.asarray(sqrt_q, dtype=np.float64).reshape(n_intensity, -1)
    best = np.einsum("nij,ij->n", h, q)
    for s in range(1, int(k) + 1):
        if s >= n_intensity:
            break
        best = np.maximum(best, np.einsum("nij,ij->n", h[:, s:], q[:-s]))  # the target got brighter by s bins
        best = np.maximum(best, np.einsum("nij,ij->n", h[:, :-s], q[s:]))  # darker
    return np.minimum(best, 1.0)
