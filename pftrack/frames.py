"""Frame validation and conversion to OpenCV BGR ``uint8`` (GUIDE §7).

Everything that enters a tracker passes :func:`as_bgr_uint8`:

* ``(H, W)`` or ``(H, W, 1)`` grayscale → converted to BGR;
* ``(H, W, 4)`` BGRA → alpha dropped;
* ``uint16`` → scaled to 8 bits (``v >> 8``), as OpenCV does when it saves 16-bit
  data to 8-bit formats;
* any other dtype, shape or an empty image → :class:`~pftrack.errors.FrameError`.
"""

from __future__ import annotations

import cv2
import numpy as np

from .errors import FrameError


def as_bgr_uint8(frame, *, where: str = "frame") -> np.ndarray:
    """Return ``frame`` as a C-contiguous ``(H, W, 3)`` uint8 BGR array, or raise FrameError."""
    if not isinstance(frame, np.ndarray):
        raise FrameError(f"{where}: expected a NumPy image array, got {type(frame).__name__}")
    if frame.size == 0 or frame.ndim not in (2, 3) or frame.shape[0] == 0 or frame.shape[1] == 0:
        raise FrameError(f"{where}: empty or malformed image of shape {frame.shape}")
    if frame.dtype == np.uint16:
        frame = (frame >> 8).astype(np.uint8)
    elif frame.dtype == np.bool_:
        frame = frame.astype(np.uint8) * 255
    elif frame.dtype != np.uint8:
        raise FrameError(f"{where}: unsupported pixel type {frame.dtype} (expected uint8 or uint16)")
    if frame.ndim == 2:
        return cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
    channels = frame.shape[2]
    if channels == 3:
        return np.ascontiguousarray(frame)
    if channels == 1:
        return cv2.cvtColor(np.ascontiguousarray(frame[:, :, 0]), cv2.COLOR_GRAY2BGR)
    if channels == 4:
        return cv2.cvtColor(np.ascontiguousarray(frame), cv2.COLOR_BGRA2BGR)
    raise FrameError(f"{where}: unsupported number of channels {channels} (expected 1, 3 or 4)")
