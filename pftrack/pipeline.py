"""Running a single-object tracker over a source: the loop shared by the CLI, the demo and the API.

>>> from pftrack.pipeline import track_source
>>> for number, frame, state in track_source(source, tracker, box):   # doctest: +SKIP
...     print(number, state.box)

Data flows one way: source → tracker → the caller, which writes sinks.  The
frame's decode time is excluded from :attr:`TrackRun.update_seconds`.
"""

from __future__ import annotations

import contextlib
import signal
import time
from dataclasses import dataclass, field
from typing import Iterator

import numpy as np

from .errors import BoxError
from .io.datasets import track_ids_text
from .io.sources import FrameSource
from .trackers.base import Tracker, TrackState


@dataclass
class TrackRun:
    """Timing of a run, filled in while :func:`track_source` iterates."""

    frames: int = 0
    update_seconds: float = 0.0
    total_seconds: float = 0.0
    update_times: list[float] = field(default_factory=list)

    @property
    def update_fps(self) -> float:
        n = max(self.frames - 1, 0)
        return n / self.update_seconds if self.update_seconds > 0 and n else float("nan")

    @property
    def end_to_end_fps(self) -> float:
        return self.frames / self.total_seconds if self.total_seconds > 0 else float("nan")


def track_source(source: FrameSource, tracker: Tracker, box=None, *, run: TrackRun | None = None,
                 keep_times: bool = False, detect: bool = False) -> Iterator[tuple[int, np.ndarray, TrackState]]:
    """Initialise ``tracker`` on the first frame with ``box`` and track through the rest.

    ``box`` defaults to the source's first ground-truth box (OTB/VOT folders, a MOTChallenge folder's track picked
    with ``open_source(..., target=ID)``); tracking then starts on that box's frame, as the benchmarks' one-pass
    protocol does, and the frames before it are passed over (not decoded from an image folder).
    With ``detect`` the tracker starts from its detector instead (``tracker.init_detect``: the first frame's best
    detection, or, without one, lost states until a detection appears).
    Yields ``(frame_number, frame, state)`` for every frame from the first tracked one on.
    """
    run = run if run is not None else TrackRun()
    start = 1
    if detect:
        box = None
    elif box is None:
        box = source.init_box
        if box is None:
            raise BoxError(missing_box_message(source))
        start = source.init_number
    t_start = time.perf_counter()
    first = True
    for number, frame in source.numbered(start):
        t0 = time.perf_counter()
        if first:
            state = tracker.init_detect(frame) if detect else tracker.init(frame, box)
        else:
            state = tracker.update(frame)
        dt = time.perf_counter() - t0
        if not first:
            run.update_seconds += dt
            if keep_times:
                run.update_times.append(dt)
        first = False
        run.frames += 1
        run.total_seconds = time.perf_counter() - t_start
        yield number, frame, state
    run.total_seconds = time.perf_counter() - t_start


def missing_box_message(source: FrameSource) -> str:
    """The one-line error for a source without an initial box: what to give instead."""
    seq = source.sequence
    if seq is not None and seq.mot_gt is not None and len(seq.mot_gt):
        return (f"{source.name}: give an initial box (--box X,Y,W,H) or a ground-truth track to start from "
                f"(--target ID; {track_ids_text(seq.mot_gt)})")
    return f"{source.name}: give an initial box (--box X,Y,W,H); the source has no ground truth"


class StopRequest:
    """Set by SIGINT / SIGTERM inside :func:`interrupt_on_sigterm`; checked between frames."""

    def __init__(self) -> None:
        self.signum: int | None = None

    def __bool__(self) -> bool:
        return self.signum is not None

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if a stop was requested (call at a safe point, e.g. between frames)."""
        if self.signum is not None:
            raise KeyboardInterrupt(f"signal {self.signum}")


@contextlib.contextmanager
def interrupt_on_sigterm():
    """Defer SIGINT and SIGTERM to the next frame boundary inside the block.

    The first signal only sets the yielded :class:`StopRequest`; the loop calls
    ``stop.check()`` after each frame, which raises ``KeyboardInterrupt`` there, so a
    signal never lands inside compiled code (where it can surface as a ``SystemError``)
    or halfway through writing a row.  A second signal interrupts at once.
    """
    stop = StopRequest()

    def _handler(signum, frame):  # noqa: ARG001
        if stop.signum is not None:
            raise KeyboardInterrupt(f"signal {signum}")
        stop.signum = signum

    try:
        previous = {s: signal.signal(s, _handler) for s in (signal.SIGINT, signal.SIGTERM)}
    except ValueError:  # not in the main thread
        yield stop
        return
    try:
        yield stop
    finally:
        for s, h in previous.items():
            signal.signal(s, h)
