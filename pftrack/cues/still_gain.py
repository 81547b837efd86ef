"""A frame's gain against a reference frame, measured on a still view (``color_normalize="still"``).

An exposure that settles, or lights that come on, scale every channel of the frame by a factor. On a still view the
same pixel holds the same surface in both frames, so the log-ratio of its levels is that factor's log, up to noise
and to what moved (the target, passers-by): the median of the log-ratios over a lattice of pixels is the gain, and
their median absolute deviation (MAD) says whether the view was still. A moving camera puts other surfaces under the
same pixels and spreads the log-ratios (MAD 0.17-0.22 on hand-held development sequences, 0.02-0.03 on a still one,
docs/robustness.md), so the estimate is taken only when the MAD is small, and held otherwise. Measured against the
reference, not multiplied up from frame to frame, it accumulates no bias.

Both statistics come from a histogram of the log-ratios (``HIST_BINS`` bins over ``[-SPAN, SPAN]``), so the cost is one
pass over the lattice whatever its size (about 1 600 pixels a channel on an 854 x 480 frame with a stride of 16).
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import njit

#: Levels at or below ``LOW`` or at or above ``HIGH`` are dark noise or clipped, and do not count.
LOW, HIGH = 12, 240
#: Log-ratios counted in ``HIST_BINS`` bins of about 0.01 over ``[-SPAN, SPAN]`` (a gain from 1/20 to 20).
SPAN = 3.0
HIST_BINS = 601  # odd: a log-ratio of 0 (no change) falls at a bin centre
#: :func:`frame_jump` read as a jump of the light (``cast_jump``) only when every channel's MAD is at most this: a
#: hand-held camera's consecutive frames read 0.02-0.29, a fast swing 0.5 (docs/rules/cast_jump_rule.txt)
JUMP_MAX_MAD = 0.4

_LOG = np.log(np.maximum(np.arange(256, dtype=np.float64), 1.0))


def reference_lattice(frame: np.ndarray, stride: int = 16) -> np.ndarray:
    """The reference's lattice ``frame[::stride, ::stride]`` of a BGR uint8 frame, contiguous."""
    return np.ascontiguousarray(frame[::stride, ::stride])


@njit
def _log_ratio_hist(ref, frame, stride, lo, hi, span, log_table, hist):
    nb = hist.shape[1]
    scale = nb / (2.0 * span)
    for j in range(ref.shape[0]):
        for i in range(ref.shape[1]):
            for c in range(3):
                a = ref[j, i, c]
                b = frame[j * stride, i * stride, c]
                if a > lo and a < hi and b > lo and b < hi:
                    k = int((log_table[b] - log_table[a] + span) * scale)
                    if 0 <= k < nb:
                        hist[c, k] += 1
    return hist


@njit
def _median_and_mad(h, span, max_mad, out):
    """Median and MAD (bin centres) of the values counted in ``h`` over ``[-span, span]``, and their number, into
    ``out``; the walk for the MAD stops once it passes ``max_mad`` (then ``out[1]`` is above it)."""
    nb = h.shape[0]
    n = 0
    for k in range(nb):
        n += h[k]
    out[2] = n
    if n == 0:
        out[0], out[1] = 0.0, math.inf
        return out
    half = (n + 1) // 2
    width = 2.0 * span / nb
    cum = 0
    k = 0
    while k < nb:
        cum += h[k]
        if cum >= half:
            break
        k += 1
    out[0] = -span + (k + 0.5) * width
    inside = h[k]
    d = 0
    while inside < half and d < nb:
        d += 1
        if d * width > max_mad:
            break
        if k - d >= 0:
            inside += h[k - d]
        if k + d < nb:
            inside += h[k + d]
    out[1] = d * width
    return out


def still_gain(ref: np.ndarray, frame: np.ndarray, *, stride: int = 16, max_mad: float = 0.1,
               min_pixels: int = 100) -> np.ndarray | None:
    """Per-channel gain ``(3,)`` of ``frame`` against the reference lattice ``ref`` (:func:`reference_lattice` of
    the reference frame, same ``stride``), or None when the view was not still (a channel's log-ratios have a MAD
    above ``max_mad``), too few pixels counted, or the frame's size does not match."""
    if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
        return None
    rows, cols = (frame.shape[0] + stride - 1) // stride, (frame.shape[1] + stride - 1) // stride
    if (rows, cols) != ref.shape[:2]:
        return None
    hist = _log_ratio_hist(ref, frame, int(stride), LOW, HIGH, SPAN, _LOG, np.zeros((3, HIST_BINS), np.int64))
    gains = np.empty(3)
    stats = np.empty(3)
    for c in range(3):
        _median_and_mad(hist[c], SPAN, float(max_mad), stats)
        if stats[2] < min_pixels or stats[1] > max_mad:
            return None
        gains[c] = math.exp(stats[0])
    return gains


def frame_jump(prev: np.ndarray, lattice: np.ndarray, *, max_mad: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Per-channel median log-ratio ``(3,)`` of a frame's lattice against the previous frame's (both
    :func:`reference_lattice` of BGR uint8 frames, same stride), and the MADs ``(3,)`` (the walk stops just above
    ``max_mad``). Channels with no pixel counted read 0 and MAD inf.

    A white balance that switches between the two frames scales each channel by its own factor: the medians are
    their logs and differ between channels (a chromatic jump); camera motion and walkers spread the log-ratios
    about 0 without moving the channels' medians apart."""
    hist = _log_ratio_hist(prev, lattice, 1, LOW, HIGH, SPAN, _LOG, np.zeros((3, HIST_BINS), np.int64))
    med, mad, stats = np.zeros(3), np.full(3, np.inf), np.empty(3)
    for c in range(3):
        _median_and_mad(hist[c], SPAN, float(max_mad), stats)
        if stats[2] > 0:
            med[c], mad[c] = stats[0], stats[1]
    return med, mad
