"""Frame validation and conversion to OpenCV BGR ``uint8`` (GUIDE §7).

Everything that enters a tracker passes :func:`as_bgr_uint8`:

* ``(H, W)`` or ``(H, W, 1)`` grayscale → converted to BGR; the BGR frame remembers the grey image it was made
  from (:func:`grey_origin`), so that a tracker's grey features need not convert it back;
* ``(H, W, 4)`` BGRA → alpha dropped;
* ``uint16`` → scaled to 8 bits (``v >> 8``), as OpenCV does when it saves 16-bit
  data to 8-bit formats;
* floating point in ``[0, 1]`` (scikit-image's and OpenCV's convention for float images) → ``round(255 v)``;
* other integer types (an image that went through NumPy arithmetic) with every value in ``[0, 255]`` → as 8 bits;
* any other dtype, values out of those ranges (or not finite), shape or an empty image →
  :class:`~pftrack.errors.FrameError`.
"""

from __future__ import annotations

import math
import weakref

import cv2
import numpy as np

from .errors import FrameError


#: id of a BGR frame made from a grey image -> (weak reference to that frame, the grey image)
_GREY_ORIGINS: dict[int, tuple[weakref.ReferenceType, np.ndarray]] = {}


def bgr_view(region: np.ndarray) -> np.ndarray:
    """``region`` (a 3-channel image) as OpenCV can read it without a copy: itself when each row's pixels and
    channels are adjacent in memory (any row step, as in a rectangle cut from a frame), else a contiguous copy. A
    rectangle of a large frame costs OpenCV's conversions no copy this way (the same numbers)."""
    a = region
    if (a.ndim == 3 and a.strides[2] == a.itemsize and a.strides[1] == a.itemsize * a.shape[2]
            and a.strides[0] >= a.strides[1] * a.shape[1]):
        return a
    return np.ascontiguousarray(a)


def _from_grey(gray: np.ndarray, fresh: bool) -> np.ndarray:
    """BGR of the contiguous uint8 grey image ``gray``, remembering a copy of ``gray`` (``gray`` itself when
    ``fresh``: made here, so nobody else can change it) as its origin.  Exact both ways: OpenCV's fixed-point grey
    weights sum to one, so the grey of a BGR pixel ``(v, v, v)`` is ``v``."""
    bgr = cv2.cvtColor(gray, cv2.COLOR_GRAY2BGR)
    key = id(bgr)
    _GREY_ORIGINS[key] = (weakref.ref(bgr, lambda _ref, key=key: _GREY_ORIGINS.pop(key, None)),
                          gray if fresh else gray.copy())
    return bgr


def grey_origin(frame: np.ndarray) -> np.ndarray | None:
    """The uint8 grey image that :func:`as_bgr_uint8` made the BGR ``frame`` from, or None (a colour source, or
    any other array).  Valid while ``frame`` is unchanged: a frame drawn into in place no longer matches it."""
    entry = _GREY_ORIGINS.get(id(frame))
    if entry is None or entry[0]() is not frame:
        return None
    return entry[1]


def _float_to_uint8(frame: np.ndarray, where: str) -> np.ndarray:
    """``round(255 v)`` of a float image whose values all lie in ``[0, 1]``, or FrameError."""
    lo, hi = float(frame.min()), float(frame.max())
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise FrameError(f"{where}: the {frame.dtype} image holds NaN or infinite values")
    if lo < 0.0 or hi > 1.0:
        raise FrameError(f"{where}: {frame.dtype} values {lo:g}..{hi:g} lie outside [0, 1] (scale a float image to "
                         "[0, 1], or give uint8)")
    return np.rint(frame * 255.0).astype(np.uint8)


def as_bgr_uint8(frame, *, where: str = "frame") -> np.ndarray:
    """Return ``frame`` as a C-contiguous ``(H, W, 3)`` uint8 BGR array, or raise FrameError."""
    if not isinstance(frame, np.ndarray):
        raise FrameError(f"{where}: expected a NumPy image array, got {type(frame).__name__}")
    if frame.size == 0 or frame.ndim not in (2, 3) or frame.shape[0] == 0 or frame.shape[1] == 0:
        raise FrameError(f"{where}: empty or malformed image of shape {frame.shape}")
    fresh = frame.dtype != np.uint8  # converted here: no other holder
    if frame.dtype == np.uint16:
        frame = (frame >> 8).astype(np.uint8)
    elif frame.dtype == np.bool_:
        frame = frame.astype(np.uint8) * 255
    elif frame.dtype.kind == "f":
        frame = _float_to_uint8(frame, where)
    elif frame.dtype.kind in "iu" and frame.dtype != np.uint8:
        lo, hi = int(frame.min()), int(frame.max())
        if lo < 0 or hi > 255:
            raise FrameError(f"{where}: {frame.dtype} values {lo}..{hi} lie outside 0..255 (give uint8, uint16, "
                             "or floats in [0, 1])")
        frame = frame.astype(np.uint8)
    elif frame.dtype != np.uint8:
        raise FrameError(f"{where}: unsupported pixel type {frame.dtype} (expected uint8, uint16 or float in [0, 1])")
    if frame.ndim == 2:
        gray = np.ascontiguousarray(frame)
        return _from_grey(gray, fresh or gray is not frame)
    channels = frame.shape[2]
    if channels == 3:
        return np.ascontiguousarray(frame)
    if channels == 1:
        gray = np.ascontiguousarray(frame[:, :, 0])
        return _from_grey(gray, fresh or not np.shares_memory(gray, frame))
    if channels == 4:
        return cv2.cvtColor(np.ascontiguousarray(frame), cv2.COLOR_BGRA2BGR)
    raise FrameError(f"{where}: unsupported number of channels {channels} (expected 1, 3 or 4)")
