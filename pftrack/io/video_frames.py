"""A folder holding one video file and its ground truth as a sequence like any other (:func:`read_video_folder`),
its frames addressed one by one.

A :class:`VideoFrame` names frame ``index`` (from 0) of a video.  :func:`read_video_frame` decodes it; reading
the frames in order, as the evaluation does, decodes the video once from start to end (the capture is kept open
and positioned after the last frame read); any other order seeks.
"""

from __future__ import annotations

import functools
import threading
from pathlib import Path
from typing import NamedTuple

import cv2
import numpy as np

from ..errors import SourceError
from .quiet import quiet_opencv
from .sequence import (Sequence, _absent_rows, _pad_gt, _vot_rows, _warn_rows, list_images, read_meta,
                       read_number_rows)

__all__ = ["VIDEO_EXTENSIONS", "VideoFrame", "count_frames", "read_video_folder", "read_video_frame", "single_video"]

VIDEO_EXTENSIONS = {".mp4", ".avi", ".mov", ".mkv", ".m4v", ".mpg", ".mpeg", ".wmv", ".webm", ".flv", ".3gp", ".ts"}


class VideoFrame(NamedTuple):
    """Frame ``index`` (from 0) of the video file ``video``."""

    video: Path
    index: int

    @property
    def name(self) -> str:
        return f"{self.video.name}#{self.index + 1}"

    def __str__(self) -> str:
        return f"{self.video} (frame {self.index + 1})"


def count_frames(video: Path) -> int:
    """The number of frames a video decodes to (counted by reading it: a container's stated count can be wrong);
    0 when it cannot be opened.  Remembered per file, size and modification time: an evaluation reads the same
    sequence once per job."""
    try:
        st = Path(video).stat()
    except OSError:
        return 0
    return _count_frames(str(video), st.st_size, st.st_mtime_ns)


@functools.lru_cache(maxsize=256)
def _count_frames(video: str, size: int, mtime_ns: int) -> int:
    with quiet_opencv():
        cap = cv2.VideoCapture(str(video))
    try:
        if not cap.isOpened():
            return 0
        n = 0
        while cap.grab():
            n += 1
        return n
    finally:
        cap.release()


class _Reader(threading.local):
    """One open capture per thread: the video, the capture and the index of the frame it reads next."""

    video: Path | None = None
    cap: cv2.VideoCapture | None = None
    next_index: int = 0


_reader = _Reader()


def read_video_frame(frame: VideoFrame) -> np.ndarray | None:
    """Decode one frame (BGR); None when it cannot be read."""
    r = _reader
    if r.cap is None or r.video != frame.video:
        if r.cap is not None:
            r.cap.release()
        with quiet_opencv():
            r.cap = cv2.VideoCapture(str(frame.video))
        r.video, r.next_index = frame.video, 0
        if not r.cap.isOpened():
            r.cap, r.video = None, None
            return None
    if frame.index != r.next_index:
        r.cap.set(cv2.CAP_PROP_POS_FRAMES, float(frame.index))
    ok, img = r.cap.read()
    r.next_index = frame.index + 1
    return img if ok else None


def single_video(folder: Path) -> Path | None:
    """The video file of a folder that holds exactly one and no images (itself, ``img/`` or ``color/``), else None."""
    try:
        videos = [p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in VIDEO_EXTENSIONS]
    except OSError:
        return None
    if len(videos) != 1 or any((folder / sub).is_dir() and list_images(folder / sub) for sub in ("img", "color")):
        return None
    return None if list_images(folder) else videos[0]


def _video_groundtruth(folder: Path) -> Path | None:
    """A video folder's ground-truth file: the first ``groundtruth_rect*.txt`` (OTB), else ``groundtruth.txt``."""
    otb = sorted(folder.glob("groundtruth_rect*.txt"))
    if otb:
        return otb[0]
    return folder / "groundtruth.txt" if (folder / "groundtruth.txt").is_file() else None


def read_video_folder(path: str | Path, *, count: bool = True) -> Sequence:
    """A folder holding one video file (:func:`single_video`) and, optionally, its ground truth
    (:func:`_video_groundtruth`; OTB's ``x,y,w,h`` rows or VOT's boxes or polygons; NaN rows and ``meta.json``'s
    ``hidden`` frames are absent).  ``count=False`` skips counting the frames (a decode of the whole video): the
    sequence then has no frames, only its ground truth, for a reader that streams the video itself."""
    path = Path(path)
    video = single_video(path)
    if video is None:
        raise SourceError(f"{path}: not a folder holding one video file and no images")
    n = count_frames(video) if count else 0
    if count and n == 0:
        raise SourceError(f"{video}: cannot open as a video, or contains no readable frames")
    gt_file = _video_groundtruth(path)
    meta = read_meta(path)
    boxes = polys = absent = None
    if gt_file is not None:
        boxes, polys = (_vot_rows(gt_file) if gt_file.name == "groundtruth.txt"
                        else (np.array(read_number_rows(gt_file, widths=(4,)), dtype=np.float64).reshape(-1, 4), None))
        if count:
            _warn_rows(path.name, boxes.shape[0], n, "frames")
            absent = _absent_rows(boxes, n, meta, path)
            boxes = _pad_gt(boxes, n)
    return Sequence(path.name, "video", path, [VideoFrame(video, i) for i in range(n)], groundtruth=boxes,
                    polygons=polys, absent=absent, meta=meta)
