"""Working resolution for trackers whose cost grows with the target's pixels: frames are reduced to
k x k block means (OpenCV's exact area path) with the integer k that leaves the initial box between
``max_pixels`` and 4 ``max_pixels`` pixels, and the tracker works on the reduced frames."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np

from ..geometry import Box
from .base import TrackState


WORKING_RESOLUTION_DOC = (
    "Working resolution: when the initial box has more than 4x this many pixels, every frame is reduced to the "
    "means of k x k blocks, with the integer k that leaves the box 1-4x this many pixels, and the tracker runs on "
    "the reduced frames; 0: full resolution (the chapter). The cost of a frame grows with the target's pixels.")


class WorkingResolution:
    """Mixin: :meth:`_set_resolution` at init, :meth:`_zoomed` for every frame, :meth:`_to_frame` for results."""

    _k: int = 1
    _work_size: tuple[int, int] = (0, 0)

    def _set_resolution(self, frame: np.ndarray, box: Box, max_pixels: int) -> tuple[float, float, float, float]:
        """Choose ``k`` for ``box`` (0 ``max_pixels``: full resolution) and return the box in reduced pixels."""
        fh, fw = frame.shape[:2]
        area = float(box[2]) * float(box[3])
        k = max(1, int((area / max_pixels) ** 0.5)) if max_pixels > 0 else 1
        self._k = k = min(k, max(1, min(fw, fh) // 8))
        self._work_size = (fw // k, fh // k)
        z = 1.0 / k
        x, y, w, h = (float(v) for v in box)
        return x * z, y * z, w * z, h * z

    def _zoomed(self, frame: np.ndarray) -> np.ndarray:
        k = self._k
        if k == 1:
            return frame
        w, h = self._work_size
        return cv2.resize(frame[:h * k, :w * k], (w, h), interpolation=cv2.INTER_AREA)

    def _to_frame(self, v):
        """Lengths or coordinates in reduced pixels -> frame pixels (divided by the zoom 1/k, the arithmetic
        the tracks were validated with, rather than multiplied by k)."""
        return v / (1.0 / self._k)

    def _box_to_frame(self, box) -> tuple[float, float, float, float]:
        """An ``(x, y, w, h)`` box in reduced pixels -> frame pixels."""
        return tuple(float(self._to_frame(float(v))) for v in box)


class ReducedFrames(WorkingResolution):
    """Mixin for trackers that run wholly on the reduced frames: they implement ``_init_at(frame, box)``
    and ``_update_at(frame) -> TrackState`` in reduced pixels, with ``params.max_pixels``."""

    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        zbox = self._set_resolution(frame, box, self.params.max_pixels)
        self._init_at(self._zoomed(frame), zbox)
        return TrackState(box=tuple(float(x) for x in box), score=1.0, lost=False)

    def _update(self, frame: np.ndarray) -> TrackState:
        st = self._update_at(self._zoomed(frame))
        return dataclasses.replace(st, box=self._box_to_frame(st.box))
