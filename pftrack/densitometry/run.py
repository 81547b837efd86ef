"""``pftrack densitometry``: track the segment, translate the line, write the densitometric curve row by row."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..cues.ssim import to_gray
from ..errors import BoxError
from ..io.sinks import _fmt, _TextSink
from .profile import (
    background_line,
    densitometric_area,
    profile_along,
    translate_line,
    vessel_edges,
)

HEADER = "frame,dx,dy,x1,y1,x2,y2,A,d1,d2,mean,min,score,lost"


class DensitometrySink(_TextSink):
    """``frame,dx,dy,x1,y1,x2,y2,A,d1,d2,mean,min,score,lost`` per frame (frames from 1), flushed per row."""

    def __init__(self, path: str | Path):
        super().__init__(path)
        self._write(HEADER)
        self.rows = 0

    def write(self, frame: int, offset, line, area: float, d1: int, d2: int, prof: np.ndarray, score: float,
              lost: bool) -> None:
        vals = [_fmt(float(v), 3) for v in (*offset, *line)]
        self._write(f"{int(frame)},{','.join(vals)},{_fmt(area, 5)},{int(d1)},{int(d2)},"
                    f"{_fmt(float(prof.mean()), 3)},{_fmt(float(prof.min()), 3)},{_fmt(float(score), 5)},"
                    f"{int(bool(lost))}")


def check_line(line, width: int, height: int) -> np.ndarray:
    """A line ``(x1, y1, x2, y2)`` of finite coordinates inside the image and of positive length."""
    arr = np.asarray(line, dtype=np.float64).ravel()
    if arr.size != 4 or not np.all(np.isfinite(arr)):
        raise BoxError(f"line must be X1,Y1,X2,Y2 (4 finite numbers), got {line!r}")
    text = ",".join(f"{v:g}" for v in arr)
    if np.hypot(arr[2] - arr[0], arr[3] - arr[1]) < 2:
        raise BoxError(f"line {text} is shorter than 2 pixels")
    xs, ys = arr[[0, 2]], arr[[1, 3]]
    if xs.min() < 0 or ys.min() < 0 or xs.max() > width - 1 or ys.max() > height - 1:
        raise BoxError(f"line {text} is outside the {width}x{height} image")
    return arr


def measure(gray: np.ndarray, line, *, width: int = 1, background: str = "II") -> tuple[float, int, int, np.ndarray]:
    """``A`` of eq. (1), the edges and the profile along one line of one grey frame."""
    prof = profile_along(gray, line, width=width)
    bg = background_line(prof, method="II")
    d1, d2 = vessel_edges(prof, bg)
    if background != "II":
        bg = background_line(prof, method=background, edges=(d1, d2))
        d1, d2 = vessel_edges(prof, bg)
    return densitometric_area(prof, bg, d1, d2), d1, d2, prof


def run_densitometry(frames, tracker, box, line, sink: DensitometrySink, *, width: int = 1, background: str = "II",
                     on_frame=None, write_first: bool = True) -> int:
    """Track ``box`` with ``tracker`` through ``frames`` (an iterable of ``(number, frame)``), translate
    ``line`` with the box's displacement from the first frame, and write one row per frame.

    ``on_frame(number, frame, state, line)`` is called after each row (for a video sink).  With
    ``write_first=False`` the first frame only initialises (its row was written by an earlier pass).
    Returns the number of rows written.
    """
    count = 0
    c0 = None
    skip = not write_first
    for number, frame in frames:
        if c0 is None:
            h, w = frame.shape[:2]
            line = check_line(line, w, h)
            state = tracker.init(frame, box)
            c0 = np.array([state.box[0] + state.box[2] / 2, state.box[1] + state.box[3] / 2])
        else:
            state = tracker.update(frame)
        c = np.array([state.box[0] + state.box[2] / 2, state.box[1] + state.box[3] / 2])
        offset = c - c0
        moved = translate_line(line, offset)
        if skip:  # the first frame of this pass only initialises (an earlier pass wrote its row)
            skip = False
            continue
        area, d1, d2, prof = measure(to_gray(frame), moved, width=width, background=background)
        sink.write(number, offset, moved, area, d1, d2, prof, state.score, state.lost)
        if on_frame is not None:
            on_frame(number, frame, state, moved)
        count += 1
    return count
