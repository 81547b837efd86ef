"""Grey levels of the part of a frame a cue reads.

A cue that needs grey levels only where the particles can reach converts that rectangle of each frame, not the
whole of it (GUIDE §3: touch only the pixels the estimate can reach).  The levels are :func:`cv2.cvtColor`'s,
pixel for pixel; a frame made from a grey image gives that image's levels without a conversion.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ..frames import grey_origin
from .lk import gray_of

__all__ = ["GreyPatch", "as_patch", "grey_patch"]


@dataclass(frozen=True)
class GreyPatch:
    """A rectangle of a frame's grey image: ``img[0, 0]`` is pixel ``(x0, y0)`` of a ``frame_w`` × ``frame_h``
    frame.  The flow needs the grey levels only where the particles can reach, so a tracker converts that much
    of each frame (:func:`grey_patch`), not the whole of it."""

    img: np.ndarray
    x0: int = 0
    y0: int = 0
    frame_w: int = -1
    frame_h: int = -1

    @classmethod
    def whole(cls, gray: np.ndarray) -> "GreyPatch":
        return cls(gray, 0, 0, gray.shape[1], gray.shape[0])

    def covers(self, x0: int, y0: int, x1: int, y1: int) -> bool:
        return (self.x0 <= x0 and self.y0 <= y0 and x1 <= self.x0 + self.img.shape[1]
                and y1 <= self.y0 + self.img.shape[0])

    def view(self, x0: int, y0: int, x1: int, y1: int) -> np.ndarray:
        return self.img[y0 - self.y0: y1 - self.y0, x0 - self.x0: x1 - self.x0]


def as_patch(gray) -> GreyPatch:
    return gray if isinstance(gray, GreyPatch) else GreyPatch.whole(gray)


def grey_patch(frame: np.ndarray, roi: tuple[int, int, int, int] | None = None, margin: int = 0) -> GreyPatch:
    """The grey levels of ``frame`` (BGR or grey) on ``roi`` grown by ``margin`` px and cut to the frame (the
    whole frame when ``roi`` is None): ``cv2.cvtColor``'s levels on those pixels, converted alone."""
    fh, fw = frame.shape[:2]
    if roi is None:
        x0, y0, x1, y1 = 0, 0, fw, fh
    else:
        x0, y0 = max(int(roi[0]) - margin, 0), max(int(roi[1]) - margin, 0)
        x1, y1 = min(int(roi[2]) + margin, fw), min(int(roi[3]) + margin, fh)
        x1, y1 = max(x1, x0), max(y1, y0)
    if frame.ndim == 3 and frame.shape[2] == 3 and grey_origin(frame) is None:
        img = cv2.cvtColor(frame[y0:y1, x0:x1], cv2.COLOR_BGR2GRAY)  # a colour frame: only the rectangle
    else:
        img = gray_of(frame)[y0:y1, x0:x1]  # grey levels at hand (a grey frame, or a BGR frame made from one)
    return GreyPatch(img, x0, y0, fw, fh)
