"""Compiled grey features (:func:`pftrack.cues.intensity.quantize_gray`): the equalised grey level and its 3x3 Sobel
gradient at the lattice points of a region, in one pass over the frame, with OpenCV's numbers.

The OpenCV path converts the region (or the lattice points' 3x3 neighbourhoods) to grey, maps it through the
equalisation table, filters it with ``cv2.spatialGradient`` and then bins the lattice points, about ten array
operations a region.  Here each lattice point reads its own 3x3 neighbourhood (rows and columns beyond the frame
repeat its edge, as the replicated border does): for lattices of pitch 3 or more, whose neighbourhoods do not
overlap, that is 1.5-2x faster; denser lattices keep OpenCV's vectorised steps, which were faster there.  The grey
conversion is OpenCV's fixed-point ``COLOR_BGR2GRAY``; :func:`exact_gray_available` checks it against the installed
OpenCV once per process, and the callers keep OpenCV's path where it differs.  The angle stays OpenCV's
(``cv2.cartToPolar``, an approximation that is not reproduced here); :func:`gray_bins` bins the points in one pass
for every pitch.
"""

from __future__ import annotations

import cv2
import numpy as np

from .._numba import njit, numba_enabled

__all__ = ["exact_gray_available", "gray_bins", "lattice_levels_gradients"]

# OpenCV's BGR -> grey for 8-bit pixels: (3735 B + 19235 G + 9798 R + 2^14) >> 15 (checked at run time)
_CB, _CG, _CR, _SHIFT = 3735, 19235, 9798, 15
_EXACT: bool | None = None


def exact_gray_available() -> bool:
    """Do the compiled kernels apply here: Numba on, and the fixed-point grey conversion equal to the installed
    OpenCV's on a probe of every grey level and 2^16 random colours (checked once per process)?"""
    global _EXACT
    if not numba_enabled():
        return False
    if _EXACT is None:
        rng = np.random.default_rng(0)
        probe = np.concatenate([np.repeat(np.arange(256, dtype=np.uint8)[:, None], 3, axis=1),
                                rng.integers(0, 256, (1 << 16, 3)).astype(np.uint8)]).reshape(1, -1, 3)
        b, g, r = (probe[0, :, c].astype(np.int64) for c in range(3))
        mine = (_CB * b + _CG * g + _CR * r + (1 << (_SHIFT - 1))) >> _SHIFT
        _EXACT = bool(np.array_equal(mine, cv2.cvtColor(probe, cv2.COLOR_BGR2GRAY)[0].astype(np.int64)))
    return _EXACT


@njit(cache=True, inline="always")
def _store(n, i, j, g, dx, dy):
    """The centre of a 3x3 neighbourhood ``n`` (row-major, 9 levels) and its Sobel derivatives, at ``(i, j)``."""
    g[i, j] = n[4]
    dx[i, j] = (n[2] + 2 * n[5] + n[8]) - (n[0] + 2 * n[3] + n[6])
    dy[i, j] = (n[6] + 2 * n[7] + n[8]) - (n[0] + 2 * n[1] + n[2])


@njit(cache=True)
def _sparse3(rows, fh, fw, ys, xs, lut, g, dx, dy):
    """Per lattice point of a BGR frame (rows of ``W * 3`` bytes): its 3x3 neighbourhood's equalised grey levels
    (edges repeated), the centre and the Sobel derivatives."""
    n = np.empty(9, np.int32)
    for i in range(ys.shape[0]):
        y = ys[i]
        ra, rb, rc = rows[max(y - 1, 0)], rows[y], rows[min(y + 1, fh - 1)]
        for j in range(xs.shape[0]):
            x = xs[j]
            c0, c1, c2 = 3 * max(x - 1, 0), 3 * x, 3 * min(x + 1, fw - 1)
            k = 0
            for r in (ra, rb, rc):
                for c in (c0, c1, c2):
                    n[k] = lut[(_CB * np.int32(r[c]) + _CG * np.int32(r[c + 1]) + _CR * np.int32(r[c + 2])
                                + (1 << (_SHIFT - 1))) >> _SHIFT]
                    k += 1
            _store(n, i, j, g, dx, dy)


@njit(cache=True)
def _sparse1(rows, fh, fw, ys, xs, lut, g, dx, dy):
    """:func:`_sparse3` of a one-channel frame (the self-quotient image). One kernel for both ran slower here: 43
    against 36 µs on an 854 x 480 image at pitch 8 when branching on the channel count inside the loop, 40 when
    given the pixel's conversion as a compiled function (and 68 against 63 µs on a BGR frame)."""
    n = np.empty(9, np.int32)
    for i in range(ys.shape[0]):
        y = ys[i]
        ra, rb, rc = rows[max(y - 1, 0)], rows[y], rows[min(y + 1, fh - 1)]
        for j in range(xs.shape[0]):
            x = xs[j]
            c0, c1, c2 = max(x - 1, 0), x, min(x + 1, fw - 1)
            k = 0
            for r in (ra, rb, rc):
                for c in (c0, c1, c2):
                    n[k] = lut[r[c]]
                    k += 1
            _store(n, i, j, g, dx, dy)


def lattice_levels_gradients(frame: np.ndarray, ys: np.ndarray, xs: np.ndarray, lut: np.ndarray
                             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(g, dx, dy)`` at the lattice points ``ys x xs`` (inside the frame) of a contiguous 8-bit BGR or grey frame:
    the equalised grey level (int32) and its 3x3 Sobel derivatives on the equalised image with a replicated border
    (float32 integers), as the OpenCV path computes them.  Each point converts its own 3x3 neighbourhood: meant for
    lattices of pitch 3 or more, whose neighbourhoods do not overlap."""
    fh, fw = frame.shape[:2]
    nc = frame.shape[2] if frame.ndim == 3 else 1
    g = np.empty((ys.size, xs.size), np.int32)
    dx = np.empty((ys.size, xs.size), np.float32)
    dy = np.empty((ys.size, xs.size), np.float32)
    if ys.size and xs.size:
        kernel = _sparse3 if nc == 3 else _sparse1
        kernel(frame.reshape(fh, fw * nc), fh, fw, ys.astype(np.int64), xs.astype(np.int64), lut.astype(np.int32),
               g, dx, dy)
    return g, dx, dy


@njit(cache=True)
def _bins(g, mag, ang, n_intensity, n_orientation, scale, threshold, out):
    for i in range(g.shape[0]):
        for j in range(g.shape[1]):
            ob = np.int32(ang[i, j] * scale)
            if ob >= n_orientation:
                ob = 0  # the angle 2 pi wraps to 0
            if mag[i, j] < threshold:
                ob = n_orientation  # the "flat" bin
            ib = (g[i, j] * n_intensity) >> 8
            out[i, j] = ib * (n_orientation + 1) + ob
    return out


def gray_bins(g: np.ndarray, mag: np.ndarray, ang: np.ndarray, n_intensity: int, n_orientation: int,
              gradient_threshold: float, out: np.ndarray) -> np.ndarray:
    """The joint intensity/orientation bins of :func:`~pftrack.cues.intensity.quantize_gray` from the levels and
    ``cv2.cartToPolar``'s magnitude and angle (float32, compared and scaled in float32 as NumPy does)."""
    return _bins(g, mag, ang, int(n_intensity), int(n_orientation), np.float32(n_orientation / (2.0 * np.pi)),
                 np.float32(gradient_threshold), out)
