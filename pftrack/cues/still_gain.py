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

The same log-ratios between consecutive frames read a jump of the light (``cast_jump``, ``light_jump``;
:func:`frame_jump`, :class:`JumpReader`, :class:`CastUndo`): a white balance that switches moves the channels' medians
apart, lamps switched on or off move them together, and camera motion spreads the log-ratios without moving the
medians. The jumps read are multiplied into a gain that the colour bins or the frames undo. A switch between colour
and grey (a night mode) reads as no jump; between grey frames a grey camera's lamps read as a common jump only where
asked (``grey=True``: ``light_jump_grey`` of pftrack mot and the tripwire). ``clip_fill`` gives a level clipped by a
brightening jump the level seen there before it (:class:`CastUndo`).
"""

from __future__ import annotations

import math

import cv2
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
#: ... and every channel has at least this many lattice pixels within (LOW, HIGH): a view whose blue is clipped almost
#: everywhere (a saturated sky) reads a "jump" from a handful of pixels (one on tld_pedestrian2); 253 or more on
#: every frame of the tune sequences
JUMP_MIN_PIXELS = 100

_LOG = np.log(np.maximum(np.arange(256, dtype=np.float64), 1.0))


def pair_bins(lo: int = LOW, hi: int = HIGH, span: float = SPAN, bins: int = HIST_BINS) -> np.ndarray:
    """``(256, 256)`` int16: the histogram bin of the log-ratio ``log b - log a`` of levels ``a`` (reference) and
    ``b`` (frame), -1 where either level is at or outside ``(lo, hi)`` or the ratio outside ``[-span, span]``. The
    kernels look each pair up instead of computing it (the same float expression, evaluated once here)."""
    scale = bins / (2.0 * span)
    k = ((_LOG[None, :] - _LOG[:, None] + span) * scale).astype(np.int64)
    levels = np.arange(256)
    ok = ((levels > lo) & (levels < hi))[:, None] & ((levels > lo) & (levels < hi))[None, :] & (k >= 0) & (k < bins)
    return np.where(ok, k, -1).astype(np.int16)


_PAIR_BINS = pair_bins()


def reference_lattice(frame: np.ndarray, stride: int = 16) -> np.ndarray:
    """The reference's lattice ``frame[::stride, ::stride]`` of a BGR uint8 frame, contiguous."""
    return np.ascontiguousarray(frame[::stride, ::stride])


@njit
def _log_ratio_hist(ref, frame, stride, pairs, hist):
    """Count the log-ratios of ``frame``'s lattice (every ``stride``-th pixel) against ``ref`` in ``hist`` (3 rows),
    each pair of levels looked up in ``pairs`` (:func:`pair_bins`)."""
    for j in range(ref.shape[0]):
        for i in range(ref.shape[1]):
            for c in range(3):
                k = pairs[ref[j, i, c], frame[j * stride, i * stride, c]]
                if k >= 0:
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
    hist = _log_ratio_hist(ref, frame, int(stride), _PAIR_BINS, np.zeros((3, HIST_BINS), np.int64))
    gains = np.empty(3)
    stats = np.empty(3)
    for c in range(3):
        _median_and_mad(hist[c], SPAN, float(max_mad), stats)
        if stats[2] < min_pixels or stats[1] > max_mad:
            return None
        gains[c] = math.exp(stats[0])
    return gains


@njit
def _jump(prev, frame, stride, span, pairs, hist, cur, min_chroma, max_mad, min_pixels, out):
    """:func:`frame_jump` in one call: the log-ratios of ``frame``'s lattice (every ``stride``-th pixel, copied into
    ``cur``) against ``prev`` counted in ``hist``; ``out[0]`` the channels' medians (0 for a channel with fewer than
    ``min_pixels`` counted), ``out[1]`` their MADs, walked only when the chromatic jump reaches ``min_chroma`` (else,
    and for such a channel, inf); ``out[2]`` the pixels counted."""
    hist[:] = 0
    _log_ratio_hist(prev, frame, stride, pairs, hist)
    for j in range(prev.shape[0]):
        for i in range(prev.shape[1]):
            for c in range(3):
                cur[j, i, c] = frame[j * stride, i * stride, c]
    stats = np.empty(3)
    for c in range(3):
        _median_and_mad(hist[c], span, 0.0, stats)
        out[0, c] = stats[0] if stats[2] >= min_pixels and stats[2] > 0 else 0.0
        out[1, c] = math.inf
        out[2, c] = stats[2]
    if out[0].max() - out[0].min() >= min_chroma:
        for c in range(3):
            if out[2, c] >= min_pixels and out[2, c] > 0:
                _median_and_mad(hist[c], span, max_mad, stats)
                out[1, c] = stats[1]
    return out


class JumpReader:
    """:func:`frame_jump` frame after frame, with its buffers kept: :meth:`read` compares a frame with the one
    before and returns its medians and MADs ``(2, 3)`` (MADs inf unless the chromatic jump reaches ``min_chroma`` or
    the channels' mean median reaches ``min_light`` in size, for a channel with fewer than ``min_pixels`` counted, and
    when either frame is grey; with ``grey`` only when one frame is grey and the other not, so that lamps switched
    on a grey camera read as a common jump; None for the first frame or a frame of another size)."""

    def __init__(self, stride: int = 16, min_chroma: float = 0.0, max_mad: float = 1.0,
                 min_pixels: int = JUMP_MIN_PIXELS, min_light: float = math.inf, grey: bool = False):
        self.stride, self.min_chroma, self.max_mad = int(stride), float(min_chroma), float(max_mad)
        self.min_pixels, self.min_light, self.grey = int(min_pixels), float(min_light), bool(grey)
        self._hist = np.zeros((3, HIST_BINS), np.int64)
        self._prev: np.ndarray | None = None
        self._cur: np.ndarray | None = None
        self._greys: list[bool | None] = [None, None]  # whether _prev, _cur are grey, found once per lattice
        self._out = np.zeros((3, 3))

    def reset(self, frame: np.ndarray | None) -> None:
        """Start again from ``frame`` (None: no previous frame)."""
        self._prev = None if frame is None else reference_lattice(frame, self.stride)
        self._cur = None if frame is None else np.empty_like(self._prev)
        self._greys = [None, None]

    def read(self, frame: np.ndarray) -> np.ndarray | None:
        s = self.stride
        shape = ((frame.shape[0] + s - 1) // s, (frame.shape[1] + s - 1) // s)
        if self._prev is None or self._prev.shape[:2] != shape or frame.ndim != 3 or frame.dtype != np.uint8:
            self.reset(frame if frame.ndim == 3 and frame.dtype == np.uint8 else None)
            return None
        light = math.isfinite(self.min_light)  # a common jump of the light is read too: every MAD walked
        out = _jump(self._prev, frame, s, SPAN, _PAIR_BINS, self._hist, self._cur,
                    -math.inf if light else self.min_chroma, self.max_mad, self.min_pixels, self._out)
        m0, m1, m2 = out[0].tolist()  # three floats: Python's arithmetic is cheaper than NumPy's reductions here
        candidate = max(m0, m1, m2) - min(m0, m1, m2) >= self.min_chroma or abs((m0 + m1 + m2) / 3) >= self.min_light
        self._prev, self._cur = self._cur, self._prev
        self._greys = [None, self._greys[0]]
        if candidate and _refused(self._is_grey(1), self._is_grey(0), self.grey):
            out[1] = math.inf
        return out[:2]

    def _is_grey(self, which: int) -> bool:
        """Whether the last frame's lattice (0) or the one before (1) is grey: found once per lattice."""
        g = self._greys[which]
        if g is None:
            g = self._greys[which] = _grey_lattice(self._prev if which == 0 else self._cur)
        return g

    @property
    def lattice(self) -> np.ndarray | None:
        """A contiguous copy of the last frame's lattice (every ``stride``-th pixel) once a frame was read, else
        None."""
        return self._prev

    def switched(self) -> bool:
        """Whether the camera switched between colour and grey (a night mode) between the last two frames read."""
        if self._prev is None or self._cur is None:
            return False
        return self._is_grey(0) != self._is_grey(1)


def _refused(prev_grey: bool, cur_grey: bool, grey: bool) -> bool:
    """Whether no jump can be read between two frames, from whether each is grey: a camera switching between colour
    and grey (a night mode) is not a jump of the light, and grey frames are read only with ``grey``."""
    return prev_grey != cur_grey or (prev_grey and not grey)


def _grey_lattice(lat: np.ndarray, tolerance: int = 2) -> bool:
    """A lattice of a grey frame: at most 1 % of its pixels with a channel more than ``tolerance`` levels from
    another (as :func:`pftrack.cues.intensity.is_gray`)."""
    a = lat.astype(np.int16)
    spread = np.maximum(np.abs(a[..., 0] - a[..., 1]), np.abs(a[..., 1] - a[..., 2]))
    return int(np.count_nonzero(spread > tolerance)) <= spread.size // 100


def frame_jump(prev: np.ndarray, lattice: np.ndarray, *, max_mad: float = 1.0, min_pixels: int = JUMP_MIN_PIXELS,
               grey: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Per-channel median log-ratio ``(3,)`` of a frame's lattice against the previous frame's (both
    :func:`reference_lattice` of BGR uint8 frames, same stride), and the MADs ``(3,)`` (the walk stops just above
    ``max_mad``). A channel with fewer than ``min_pixels`` counted (levels clipped or dark in most of the view) reads
    0 and MAD inf; every MAD is inf when either frame is grey (with ``grey``: only when one frame is grey and the
    other is not, a camera switching to or from a night mode; between two grey frames the channels' medians are
    equal, so lamps switched on or off read as a common jump and nothing as a chromatic one).

    A white balance that switches between the two frames scales each channel by its own factor: the medians are
    their logs and differ between channels (a chromatic jump); camera motion and walkers spread the log-ratios
    about 0 without moving the channels' medians apart."""
    out = _jump(prev, lattice, 1, SPAN, _PAIR_BINS, np.zeros((3, HIST_BINS), np.int64), np.empty_like(prev),
                -math.inf, float(max_mad), int(min_pixels), np.zeros((3, 3)))
    if _refused(_grey_lattice(prev), _grey_lattice(lattice), grey):
        out[1] = math.inf
    return out[0].copy(), out[1].copy()


class CastUndo:
    """A frame with the white balance jumps read so far undone (``cast_jump`` of a whole-frame pipeline: ``pftrack
    mot``'s background subtraction and colour models). Call it on every frame in order: a frame whose chromatic jump
    against the previous one (:class:`JumpReader`) is at least ``threshold``, or with ``light`` > 0 whose channels'
    mean median log-ratio is at least ``light`` in size (lamps switched on or off: every channel at once), every
    channel's MAD at most ``JUMP_MAX_MAD``, multiplies a per-channel gain by the jump's; each frame is returned
    divided by that gain (a per-channel table, cv2.LUT), or as it is while the gain is within ``dead_zone`` of 1.
    ``threshold`` 0 reads no chromatic jump. Between grey frames nothing is read, or with ``grey`` the common jump;
    when the camera switches between colour and grey (a night mode) the cast read so far is dropped and the light's
    part kept (a grey frame undone channel by channel would no longer be grey).

    ``clip_fill``: a level clipped at 255 in a channel the jumps brightened (gain above 1) is only known to be at least
    255 / gain once undone; it takes the level seen at that pixel just before the last jump when that is higher (the
    image passed to :meth:`undo` before it; the same part of the frame on every call). Without it a bright background
    clipped by lamps switched on stays flat at 255 / gain, and a background model takes it for foreground."""

    def __init__(self, threshold: float, *, light: float = 0.0, dead_zone: float = 0.05, grey: bool = False,
                 clip_fill: bool = False):
        if not (threshold >= 0 and light >= 0 and threshold + light > 0):
            raise ValueError(f"threshold and light must be >= 0, one of them > 0, got {threshold!r}, {light!r}")
        self.threshold = float(threshold) if threshold > 0 else math.inf
        self.light = float(light) if light > 0 else math.inf
        self.dead_zone = float(dead_zone)
        self.reader = JumpReader(min_chroma=self.threshold, max_mad=JUMP_MAX_MAD, min_light=self.light, grey=grey)
        self.gain = np.ones(3)
        self._lut: np.ndarray | None = None
        self.clip_fill = bool(clip_fill)
        # clip_fill: copies of the last image undone and of the one before the last jump (two buffers, swapped)
        self._last: np.ndarray | None = None
        self._ref: np.ndarray | None = None

    def reset(self, frame: np.ndarray | None = None) -> None:
        """Start again: the next frame is compared with ``frame`` (None: read none), the gain is 1."""
        self.reader.reset(frame)
        self.gain = np.ones(3)
        self._lut = None
        self._last = self._ref = None

    def read(self, frame: np.ndarray) -> bool:
        """Compare ``frame`` with the previous one and take in its jump, if any (then True)."""
        r = self.reader.read(frame)
        if r is None:
            return False
        med, mad = r
        m0, m1, m2 = med.tolist()
        g = self.gain
        if (g[0] != g[1] or g[1] != g[2]) and self.reader.switched():
            # a grey night mode has no white balance: the cast read so far goes, the light's common part stays
            self._set_gain(np.full(3, math.exp(float(np.log(self.gain).mean()))))
            self._ref = None
        chroma, common = max(m0, m1, m2) - min(m0, m1, m2), abs((m0 + m1 + m2) / 3)
        if (chroma < self.threshold and common < self.light) or max(mad.tolist()) > JUMP_MAX_MAD:
            return False
        self._ref, self._last = self._last, self._ref  # the frame before the jump; its buffer is reused below
        self._set_gain(self.gain * np.exp(med))
        return True

    def _set_gain(self, gain: np.ndarray) -> None:
        """Take ``gain`` and its table (none while every channel is within the dead zone of 1)."""
        self.gain = gain
        self._lut = None if np.all(np.abs(gain - 1.0) < self.dead_zone) else undo_lut(gain)

    def undo(self, image: np.ndarray) -> np.ndarray:
        """``image`` (the frame, or a part of it) divided by the gain read so far; itself while there is none."""
        if self._lut is None or image.ndim != 3:
            out = image
        else:
            out = cv2.LUT(image, self._lut)
            if self.clip_fill and self._ref is not None and self._ref.shape == image.shape:
                _fill_clipped(image, out, self._ref, self.gain > 1.0 + self.dead_zone)
        if self.clip_fill:  # a copy: the caller may draw on its frame
            if self._last is None or self._last.shape != out.shape:
                self._last = np.empty_like(out)
            np.copyto(self._last, out)
        return out

    def __call__(self, frame: np.ndarray) -> np.ndarray:
        self.read(frame)
        return self.undo(frame)


def _fill_clipped(raw: np.ndarray, out: np.ndarray, ref: np.ndarray, channels: np.ndarray) -> None:
    """In ``out`` (``raw`` undone), each brightened channel's levels clipped at 255 in ``raw`` raised to ``ref``'s
    where that is higher (in place). OpenCV's saturating arithmetic on whole frames: 0.3 ms at 768 x 576, against
    6 ms for NumPy's masked maximum."""
    mask = cv2.compare(raw, 254, cv2.CMP_GT)  # 255 where clipped
    if not channels.all():
        mask[..., ~channels] = 0
    gap = cv2.subtract(cv2.max(out, ref), out)  # how far ref is above out, 0 elsewhere
    cv2.add(out, cv2.bitwise_and(gap, mask), dst=out)


def cast_undo(cast_jump: float, light_jump: float = 0.0, light_jump_grey: bool = False,
              clip_fill: bool = False) -> CastUndo | None:
    """The :class:`CastUndo` of a pipeline's ``cast_jump``, ``light_jump``, ``light_jump_grey`` and ``clip_fill``
    parameters, or None when both jumps are 0."""
    if cast_jump <= 0 and light_jump <= 0:
        return None
    return CastUndo(cast_jump, light=light_jump, grey=light_jump_grey, clip_fill=clip_fill)


def frame_undo(params) -> CastUndo | None:
    """:func:`cast_undo` of a whole-frame pipeline's parameters (``pftrack mot``'s, the tripwire's): their
    ``cast_jump``, ``light_jump``, ``light_jump_grey`` and ``clip_fill``."""
    return cast_undo(params.cast_jump, params.light_jump, params.light_jump_grey, params.clip_fill)


def undo_lut(gain: np.ndarray) -> np.ndarray:
    """The ``(1, 256, 3)`` uint8 table (cv2.LUT) that divides each channel's levels by ``gain`` (rounded, clipped)."""
    v = np.arange(256, dtype=np.float64)[:, None] / np.asarray(gain, np.float64)[None, :]
    return np.clip(np.rint(v), 0, 255).astype(np.uint8)[None, :, :]
