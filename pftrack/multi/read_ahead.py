"""Reading the first frames ahead to start a detector's background from them (``multi-pf``'s ``bootstrap_frames``)."""

from __future__ import annotations

import itertools
import time
from collections import deque
from collections.abc import Iterator
from typing import Callable

from ..cues.still_gain import frame_undo
from ..frames import as_bgr_uint8


class ReadAhead:
    """:meth:`prime` and :meth:`read_ahead` of :class:`~pftrack.multi.tracker.MultiPF` (its ``detector``,
    ``params`` and ``bootstrap_frames``)."""

    def prime(self, frames) -> None:
        """Before the first update: start the detector's background from the first frames of the stream (read ahead
        by the caller, ``bootstrap_frames`` of them); a detector without a background ignores it."""
        if hasattr(self.detector, "prime") and len(frames):
            undo = frame_undo(self.params)
            if undo is not None:  # with their own jumps undone (update reads them again)
                frames = [undo(as_bgr_uint8(f)) for f in frames]
            self.detector.prime(frames)

    def read_ahead(self, items: Iterator, frame_of: Callable = lambda item: item) -> tuple[Iterator, float]:
        """``bootstrap_frames``: read that many of ``items`` ahead and :meth:`prime` the detector from their frames
        (``frame_of(item)``). Returns the items again, those read ahead first (each released once handed on), and
        the seconds the priming took (counted as update time by the callers)."""
        if not self.bootstrap_frames:
            return items, 0.0
        items = iter(items)
        ahead = deque(itertools.islice(items, self.bootstrap_frames))
        t0 = time.perf_counter()
        self.prime([frame_of(item) for item in ahead])
        seconds = time.perf_counter() - t0

        def replay():
            while ahead:
                yield ahead.popleft()
            yield from items

        return replay(), seconds
