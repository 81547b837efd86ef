"""Result sinks: CSV, MOTChallenge text, JSON Lines and annotated video.

Every text sink writes whole rows and flushes after each one, so a crash or an
interruption keeps every row already produced and never leaves half a row.
Output paths are checked (and their parent folders created) before any work
starts: :func:`prepare_output` raises :class:`~pftrack.errors.OutputError` with
one line when a path cannot be written.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, TextIO

import cv2
import numpy as np

from ..errors import FormatError, OutputError
from .quiet import quiet_opencv

CSV_HEADER = "frame,x,y,w,h,score,lost"


def prepare_output(path: str | Path, *, within: str | Path | None = None) -> Path:
    """Check that ``path`` can be written (creating its parent folders).

    With ``within``, the resolved path must stay inside that folder.
    """
    p = Path(path)
    if within is not None:
        root = Path(within).resolve()
        try:
            p.resolve().relative_to(root)
        except ValueError:
            raise OutputError(f"{path}: refusing to write outside {within}") from None
    if p.exists() and p.is_dir():
        raise OutputError(f"{path}: is a folder, expected a file path")
    parent = p.parent if str(p.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"{path}: cannot create folder {parent} ({exc.strerror or exc})") from None
    if not os.access(parent, os.W_OK):
        raise OutputError(f"{path}: folder {parent} is not writable")
    if p.exists() and not os.access(p, os.W_OK):
        raise OutputError(f"{path}: file is not writable")
    return p


def _open_text(path: str | Path) -> TextIO:
    p = prepare_output(path)
    try:
        return open(p, "w", encoding="utf-8", newline="\n")
    except OSError as exc:
        raise OutputError(f"{path}: cannot open for writing ({exc.strerror or exc})") from None


def _fmt(v: float, nd: int) -> str:
    if not math.isfinite(v):
        return "nan"
    s = f"{v:.{nd}f}"
    return "0" if s in ("-0", "-0." + "0" * nd) else s.rstrip("0").rstrip(".") if "." in s else s


class _TextSink:
    def __init__(self, path: str | Path):
        self.path = Path(path)
        self._fh: TextIO | None = _open_text(path)
        self.rows = 0

    def _write(self, line: str) -> None:
        if self._fh is None:
            raise OutputError(f"{self.path}: sink is closed")
        self._fh.write(line + "\n")
        self._fh.flush()
        self.rows += 1

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class CsvTrackSink(_TextSink):
    """Single-target results: ``frame,x,y,w,h,score,lost`` (frame numbers from 1)."""

    def __init__(self, path: str | Path):
        super().__init__(path)
        self._write(CSV_HEADER)
        self.rows = 0

    def write(self, frame: int, box, score: float, lost: bool) -> None:
        x, y, w, h = (float(v) for v in box)
        self._write(f"{int(frame)},{_fmt(x, 3)},{_fmt(y, 3)},{_fmt(w, 3)},{_fmt(h, 3)},{_fmt(float(score), 5)},"
                    f"{int(bool(lost))}")

    def write_state(self, frame: int, state) -> None:
        self.write(frame, state.box, state.score, state.lost)


class MotSink(_TextSink):
    """Multi-target results in MOTChallenge text: ``frame,id,x,y,w,h,score,-1,-1,-1``."""

    def write(self, frame: int, track_id: int, box, score: float) -> None:
        x, y, w, h = (float(v) for v in box)
        self._write(f"{int(frame)},{int(track_id)},{_fmt(x, 2)},{_fmt(y, 2)},{_fmt(w, 2)},{_fmt(h, 2)},"
                    f"{_fmt(float(score), 4)},-1,-1,-1")


class JsonLinesSink(_TextSink):
    """One JSON object per line (``.jsonl``): streamable and valid after any prefix of lines."""

    def write(self, record: dict[str, Any]) -> None:
        self._write(json.dumps(record, separators=(",", ":"), allow_nan=False, default=_json_default))


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"cannot serialise {type(o).__name__}")


def read_track_csv(path: str | Path) -> np.ndarray:
    """Read a ``frame,x,y,w,h,score,lost`` file back as an ``(n, 7)`` float array."""
    p = Path(path)
    lines = p.read_text(encoding="utf-8").splitlines()
    if not lines or lines[0].strip() != CSV_HEADER:
        raise FormatError(f"{path}: expected header {CSV_HEADER!r}")
    out = []
    for i, ln in enumerate(lines[1:], start=2):
        if not ln.strip():
            continue
        parts = ln.split(",")
        if len(parts) != 7:
            raise FormatError(f"{path}:{i}: expected 7 values, got {len(parts)}")
        try:
            out.append([float(v) for v in parts])
        except ValueError:
            raise FormatError(f"{path}:{i}: expected numbers") from None
    return np.array(out, dtype=np.float64).reshape(-1, 7)


#: the codec written for each video file extension (OpenCV's FFmpeg writer)
VIDEO_FOURCC = {".mp4": "mp4v", ".m4v": "mp4v", ".mov": "mp4v", ".mkv": "mp4v", ".avi": "MJPG", ".wmv": "WMV2"}


def prepare_video_output(path: str | Path, fourcc: str | None = None) -> Path:
    """:func:`prepare_output` for an annotated video, whose extension must name a format it can be written in
    (:data:`VIDEO_FOURCC`) unless a codec is given."""
    p = prepare_output(path)
    if fourcc is None and p.suffix.lower() not in VIDEO_FOURCC:
        raise OutputError(f"{path}: cannot write a video as {p.suffix or 'a file without extension'!r}; "
                          f"use {', '.join(sorted(VIDEO_FOURCC))}")
    return p


class VideoSink:
    """Annotated video writer; the file is opened on the first frame and finalised by :meth:`close`."""

    def __init__(self, path: str | Path, fps: float | None = None, fourcc: str | None = None):
        self.path = prepare_video_output(path, fourcc)
        self.fps = float(fps) if fps and fps > 0 else 25.0
        self.fourcc = fourcc or VIDEO_FOURCC[self.path.suffix.lower()]
        self._writer: cv2.VideoWriter | None = None
        self._size: tuple[int, int] | None = None
        self.frames = 0

    def write(self, frame: np.ndarray) -> None:
        h, w = frame.shape[:2]
        if self._writer is None:
            with quiet_opencv():
                self._writer = cv2.VideoWriter(str(self.path), cv2.VideoWriter_fourcc(*self.fourcc), self.fps, (w, h))
            if not self._writer.isOpened():
                self._writer = None
                raise OutputError(f"{self.path}: cannot open a {self.fourcc} video writer")
            self._size = (w, h)
        elif (w, h) != self._size:
            frame = cv2.resize(frame, self._size)
        self._writer.write(frame)
        self.frames += 1

    def close(self) -> None:
        if self._writer is not None:
            self._writer.release()
            self._writer = None

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()
