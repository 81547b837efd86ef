"""The block-averaged grey region that the structural cue samples its patches from (:mod:`pftrack.cues.structure`).

The region the particles cover (with a margin, so that the estimate's box later in the frame finds it
too) is reduced once per frame to about the patch resolution: exact ``k x k`` block means for small
blocks, a spread subset of each block's pixels for large ones, so that the cost does not grow with the
box.  The grey levels stay integers (uint8 for 8-bit frames); :meth:`Reduced.levels_for` gives the
compiled NCC a float64 copy when that is cheaper to read.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .._numba import njit, numba_enabled
from ..frames import bgr_view, grey_origin


def gray_region(frame: np.ndarray, roi: tuple[int, int, int, int]) -> np.ndarray:
    """Grey levels of ``frame[y0:y1, x0:x1]`` (BGR or grey input), in the frame's dtype (uint8 for frames)."""
    x0, y0, x1, y1 = roi
    sub = frame[y0:y1, x0:x1]
    if sub.ndim == 3 and sub.shape[2] == 3:
        sub = cv2.cvtColor(bgr_view(sub), cv2.COLOR_BGR2GRAY)
    elif sub.ndim == 3:
        sub = sub[..., 0]
    return np.ascontiguousarray(sub)


@njit(cache=True)
def _bounds(ell):
    """``(min x0, min y0, max x1, max y1)`` of the boxes of ellipses ``(N, 4)`` ``(cx, cy, hx, hy)``."""
    x0 = y0 = math.inf
    x1 = y1 = -math.inf
    for i in range(ell.shape[0]):
        x0 = min(x0, ell[i, 0] - ell[i, 2])
        y0 = min(y0, ell[i, 1] - ell[i, 3])
        x1 = max(x1, ell[i, 0] + ell[i, 2])
        y1 = max(y1, ell[i, 1] + ell[i, 3])
    return x0, y0, x1, y1


@njit(cache=True)
def _mean_half_axes(ell):
    sx = 0.0
    sy = 0.0
    for i in range(ell.shape[0]):
        sx += ell[i, 2]
        sy += ell[i, 3]
    return sx / ell.shape[0], sy / ell.shape[0]


def box_bounds(ell: np.ndarray) -> tuple[float, float, float, float]:
    """``(min x0, min y0, max x1, max y1)`` of the boxes of ellipses ``(N, 4)`` (compiled when Numba is on)."""
    if numba_enabled():
        return _bounds(ell)
    return (float(np.min(ell[:, 0] - ell[:, 2])), float(np.min(ell[:, 1] - ell[:, 3])),
            float(np.max(ell[:, 0] + ell[:, 2])), float(np.max(ell[:, 1] + ell[:, 3])))


class Reduced:
    """A grey, block-averaged copy of a frame region: reduced pixel ``(j, i)`` averages the ``k x k`` block
    whose top-left frame pixel is ``(x0 + i k, y0 + j k)`` (``gray``: integer grey levels, uint8 for 8-bit
    frames; the kernels read them as exact floats).  ``frame_size`` ``(W, H)`` is the frame's, when
    known: a region that reaches the frame's edge (to within a block) covers whatever lies beyond it."""

    __slots__ = ("_gray64", "frame_size", "gray", "k", "x0", "y0")

    def __init__(self, gray: np.ndarray, x0: int, y0: int, k: int, frame_size: tuple[int, int] | None = None):
        self.gray, self.x0, self.y0, self.k, self.frame_size = gray, x0, y0, k, frame_size
        self._gray64: np.ndarray | None = None

    def levels_for(self, samples: int) -> np.ndarray:
        """The grey levels to sample ``samples`` times from: a float64 copy (made once; the compiled NCC reads it
        about 30 % faster than 8-bit levels, with the same numbers) unless the region is much larger than the
        samples (a whole-frame region for the background statistics), where the copy would cost more."""
        if self._gray64 is None:
            if self.gray.size > 4 * samples:
                return self.gray
            self._gray64 = self.gray.astype(np.float64)
        return self._gray64

    def covers(self, ell: np.ndarray) -> bool:
        """Do the boxes of the ellipses ``(N, 4)`` lie in the region (a box sampled from it then equals one
        sampled from a region computed for it, up to the blocks' alignment)?"""
        h, w = self.gray.shape
        x1, y1 = self.x0 + w * self.k, self.y0 + h * self.k
        lo_x, lo_y = self.x0, self.y0
        if self.frame_size is not None:  # the frame's edges: a recomputed region could not reach further
            fw, fh = self.frame_size
            lo_x = -math.inf if self.x0 <= 0 else lo_x
            lo_y = -math.inf if self.y0 <= 0 else lo_y
            x1 = math.inf if x1 + self.k > fw else x1
            y1 = math.inf if y1 + self.k > fh else y1
        cx, cy, hx, hy = ell[0].tolist() if ell.shape[0] == 1 else (math.nan,) * 4
        if math.isfinite(cx + cy + hx + hy):  # one box (the estimate's): its bounds in Python, cheaper than a call
            bx0, by0, bx1, by1 = cx - hx, cy - hy, cx + hx, cy + hy
        else:
            bx0, by0, bx1, by1 = box_bounds(ell)
        return bool(bx0 >= lo_x and by0 >= lo_y and bx1 <= x1 and by1 <= y1)


@njit(cache=True)
def _block_sums(rows, x0, y0, k, ow, oh, acc, out):
    """Sums of the ``k x k`` blocks of a BGR uint8 frame given as its ``(H, W*3)`` rows, block ``(i, j)`` with
    top-left pixel ``(x0 + i k, y0 + j k)``: ``out`` ``(oh, ow*3)`` int32.  Each band of k rows is summed
    column by column first (a vectorised pass into ``acc``, ``(ow*k*3,)`` int32), then its columns by blocks."""
    n = ow * k * 3
    c0 = x0 * 3
    for j in range(oh):
        r0 = y0 + j * k
        src = rows[r0, c0:c0 + n]
        for t in range(n):
            acc[t] = src[t]
        for r in range(1, k):
            src = rows[r0 + r, c0:c0 + n]
            for t in range(n):
                acc[t] += src[t]
        o = out[j]
        for i in range(ow * 3):
            o[i] = 0
        for q in range(k):
            for i in range(ow):
                p = (i * k + q) * 3
                o[3 * i] += acc[p]
                o[3 * i + 1] += acc[p + 1]
                o[3 * i + 2] += acc[p + 2]
    return out


def block_means(frame: np.ndarray, x0: int, y0: int, w: int, h: int, k: int) -> np.ndarray:
    """``cv2.resize(frame[y0:y0 + h, x0:x0 + w], (w // k, h // k), interpolation=cv2.INTER_AREA)``, the same
    numbers: for a BGR uint8 frame and 3 <= k < 8 dividing w and h, compiled block sums rounded as OpenCV's
    integer-factor area resize rounds them (the float32 sum times the float32 1/k^2, to nearest, ties to
    even), 1.7-1.9x faster than its generic path there; OpenCV's own resize otherwise."""
    if (3 <= k < 8 and w % k == 0 and h % k == 0 and numba_enabled() and frame.ndim == 3 and frame.shape[2] == 3
            and frame.dtype == np.uint8 and frame.flags.c_contiguous):
        ow, oh = w // k, h // k
        sums = _block_sums(frame.reshape(frame.shape[0], -1), int(x0), int(y0), int(k), ow, oh,
                           np.empty(ow * k * 3, np.int32), np.empty((oh, ow * 3), np.int32))
        mean = sums.astype(np.float32)
        mean *= np.float32(1.0) / np.float32(k * k)
        return np.rint(mean, out=mean).astype(np.uint8).reshape(oh, ow, 3)
    return cv2.resize(frame[y0:y0 + h, x0:x0 + w], (w // k, h // k), interpolation=cv2.INTER_AREA)


def reduction_factor(ellipses: np.ndarray, shape: tuple[int, int]) -> int:
    """The integer block size that makes the mean box span about the patch size (>= 1)."""
    ell = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
    ph, pw = shape
    if ell.shape[0] == 1:  # one box (the estimate): no array reductions
        mx, my = float(ell[0, 2]), float(ell[0, 3])
    elif numba_enabled():
        mx, my = _mean_half_axes(ell)
    else:
        mx, my = float(ell[:, 2].mean()), float(ell[:, 3].mean())
    return max(1, int(math.floor(min(2.0 * mx / pw, 2.0 * my / ph))))


def reduce_region(frame: np.ndarray, roi: tuple[int, int, int, int], k: int) -> Reduced:
    """Grey levels of ``frame[roi]`` averaged over ``k x k`` blocks: exact block means (an integer-factor area
    resize of the 8-bit frame, then the grey conversion of the small image) for k < 8, a spread subset of each
    block's pixels for larger blocks."""
    x0, y0, x1, y1 = (int(v) for v in roi)
    k = max(1, int(k))
    w = max(1, (x1 - x0) // k) * k
    h = max(1, (y1 - y0) // k) * k
    w, h = min(w, frame.shape[1] - x0), min(h, frame.shape[0] - y0)
    grey = grey_origin(frame)
    if grey is not None:  # a BGR frame made from a grey image: the same steps on its one channel, the same numbers
        return Reduced(_reduce_grey(grey[y0:y0 + h, x0:x0 + w], k), x0, y0, k if k > 1 and w >= k and h >= k else 1,
                       (int(frame.shape[1]), int(frame.shape[0])))
    sub = frame[y0:y0 + h, x0:x0 + w]
    if k >= 8 and w >= k and h >= k:
        sub = _sampled_blocks(sub, k)
    elif k > 1 and w >= k and h >= k:
        sub = block_means(frame, x0, y0, w, h, k)  # exact block means
    else:
        k = 1
    return Reduced(gray_region(sub, (0, 0, sub.shape[1], sub.shape[0])), x0, y0, k,
                   (int(frame.shape[1]), int(frame.shape[0])))


def _sampled_blocks(sub: np.ndarray, k: int) -> np.ndarray:
    """Blocks of ``k >= 8`` pixels of ``sub`` (whole blocks, any number of channels) averaged over a subset of their
    pixels, so that the cost stays bounded by the patch resolution, not the target's size (a coarse area filter is
    enough for a 16x16 NCC patch): a bilinear resize by a factor f in [2, 8) to 2^J times the output size averages 2
    pixels per cell and direction, and J exact halvings average the cells: 2^(J+1) >= k/4 samples per block and
    direction, spread over it (on a 624 x 416 region, 6.8x faster than an area resize of a strided lattice at k = 8,
    1.7x at k = 16)."""
    h, w = sub.shape[:2]
    levels = max(1, int(math.log2(k)) - 2)
    ow, oh = w // k, h // k
    sub = cv2.resize(sub, (ow << levels, oh << levels), interpolation=cv2.INTER_LINEAR)
    for j in range(levels - 1, -1, -1):
        sub = cv2.resize(sub, (ow << j, oh << j), interpolation=cv2.INTER_LINEAR)
    return sub


def _reduce_grey(sub: np.ndarray, k: int) -> np.ndarray:
    """:func:`reduce_region`'s reduction of a grey region ``sub`` (whole blocks of ``k``): OpenCV's resizes on one
    channel give each channel's numbers of the BGR path, and the grey of ``(v, v, v)`` is ``v`` (tested)."""
    h, w = sub.shape
    if k >= 8 and w >= k and h >= k:
        return _sampled_blocks(sub, k)
    if k > 1 and w >= k and h >= k:
        return cv2.resize(sub, (w // k, h // k), interpolation=cv2.INTER_AREA)
    return sub.copy()  # its own array, as the BGR path's conversion makes one


def _box_roi(ell: np.ndarray, width: int, height: int) -> tuple[int, int, int, int]:
    bx0, by0, bx1, by1 = box_bounds(ell)
    x0 = int(math.floor(bx0)) - 1
    y0 = int(math.floor(by0)) - 1
    x1 = int(math.ceil(bx1)) + 1
    y1 = int(math.ceil(by1)) + 1
    x0, y0 = min(max(x0, 0), max(width - 1, 0)), min(max(y0, 0), max(height - 1, 0))
    return x0, y0, max(min(x1, width), x0 + 1), max(min(y1, height), y0 + 1)


def reduced_for(frame: np.ndarray, roi, ell: np.ndarray, shape: tuple[int, int], pad_blocks: int = 0) -> Reduced:
    """The reduced region (block size :func:`reduction_factor` for patches of ``shape``) of the boxes' bounding
    rectangle within ``roi`` (None: the rectangle itself), widened by ``pad_blocks`` blocks on every side (so that
    later boxes of the same frame near these, the estimate's, are covered too)."""
    k = reduction_factor(ell, shape)
    pad = pad_blocks * k
    bx0, by0, bx1, by1 = _box_roi(ell, frame.shape[1], frame.shape[0])
    if roi is None:
        roi = (bx0, by0, bx1, by1)
    x0, y0 = max(roi[0], bx0 - pad, 0), max(roi[1], by0 - pad, 0)
    x1, y1 = max(min(roi[2], bx1 + pad), x0 + 1), max(min(roi[3], by1 + pad), y0 + 1)
    return reduce_region(frame, (x0, y0, x1, y1), k)
