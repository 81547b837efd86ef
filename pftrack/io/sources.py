"""Frame sources: video files, image folders, OTB/VOT/MOTChallenge sequences, cameras and network streams.

>>> for frame in pftrack.open_source("clip.mp4"):     # doctest: +SKIP
...     state = tracker.update(frame)

Every source yields validated BGR ``uint8`` frames (GUIDE §7): grayscale and
BGRA frames are converted, 16-bit frames are scaled to 8 bits, a frame whose
size differs from the first raises :class:`~pftrack.errors.FrameError`, and an
unreadable frame raises it too unless ``skip_bad_frames=True`` (the frame is
then skipped and counted in :attr:`FrameSource.skipped`).  Frame numbers start at 1.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Iterator

import cv2
import numpy as np

from ..errors import FrameError, SourceError
from ..frames import as_bgr_uint8
from . import streams
from .datasets import (IMAGE_EXTENSIONS, VIDEO_EXTENSIONS, Sequence, detect_layout, mot_target, otb_targets, read_otb,
                       read_sequence)
from .prefetch import default_depth, prefetch
from .quiet import quiet_opencv
from .video_frames import VideoFrame, read_video_folder, read_video_frame, single_video


def read_image(path: Path | VideoFrame) -> np.ndarray | None:
    """Decode an image file (any bit depth, alpha kept), or one frame of a video; None when it cannot be decoded."""
    if isinstance(path, VideoFrame):
        return read_video_frame(path)
    try:
        data = np.fromfile(str(path), dtype=np.uint8)
    except OSError:
        return None
    if data.size == 0:
        return None
    return cv2.imdecode(data, cv2.IMREAD_UNCHANGED)


class FrameSource:
    """Base class of all sources; iterate it for frames or call :meth:`numbered`."""

    kind = "source"
    #: a camera or live stream: no length, not read ahead, not readable twice from the start
    live = False

    def __init__(self, name: str, *, skip_bad_frames: bool = False):
        self.name = name
        self.skip_bad_frames = skip_bad_frames
        self.fps: float | None = None
        self.size: tuple[int, int] | None = None  # (width, height) once known
        self.sequence: Sequence | None = None
        self.skipped: list[int] = []
        #: frames decoded ahead on a second thread (pftrack.io.prefetch); 0 reads in the caller's thread (the
        #: default on one CPU)
        self.prefetch = default_depth()
        self._reading: Iterator | None = None

    # -- overridden by subclasses -------------------------------------------------------
    def _raw(self, start: int = 1) -> Iterator[tuple[int, np.ndarray | None, str]]:
        """Yield ``(number, image or None, description)`` from frame number ``start`` on (the frames before it are
        passed over without being decoded where the source allows)."""
        raise NotImplementedError

    def __len__(self) -> int:
        raise TypeError(f"{self.kind} source has no known length")

    @property
    def length(self) -> int | None:
        try:
            return len(self)
        except TypeError:
            return None

    # -- common ---------------------------------------------------------------------
    @property
    def groundtruth(self) -> np.ndarray | None:
        return None if self.sequence is None else self.sequence.groundtruth

    @property
    def init_box(self):
        return None if self.sequence is None else self.sequence.init_box

    @property
    def init_number(self) -> int:
        """The number (from 1) of the frame whose ground truth gives :attr:`init_box` (1 without ground truth)."""
        return 1 if self.sequence is None else self.sequence.init_index + 1

    def numbered(self, start: int = 1) -> Iterator[tuple[int, np.ndarray]]:
        """Yield ``(frame_number, frame)`` with numbers from 1, skipped frames left out; from frame ``start`` on
        (the frames before it are not decoded from an image folder, and only grabbed from a video)."""
        self._reading = raw = prefetch(self._raw(max(int(start), 1)), depth=self.prefetch)
        try:
            yield from self._checked(raw)
        finally:
            raw.close()
            self._reading = None

    def _checked(self, raw) -> Iterator[tuple[int, np.ndarray]]:
        for number, img, desc in raw:
            if img is None:
                if self.skip_bad_frames:
                    self.skipped.append(number)
                    warnings.warn(f"skipping unreadable frame {number} ({desc})", stacklevel=2)
                    continue
                raise FrameError(f"frame {number} ({desc}): cannot be decoded", index=number)
            try:
                frame = as_bgr_uint8(img, where=f"frame {number} ({desc})")
            except FrameError:
                if self.skip_bad_frames:
                    self.skipped.append(number)
                    continue
                raise
            h, w = frame.shape[:2]
            if self.size is None:
                self.size = (w, h)
            elif self.size != (w, h):
                raise FrameError(f"frame {number} ({desc}): size {w}x{h} differs from the first frame's "
                                 f"{self.size[0]}x{self.size[1]}", index=number)
            yield number, frame

    def __iter__(self) -> Iterator[np.ndarray]:
        for _, frame in self.numbered():
            yield frame

    def close(self) -> None:
        if self._reading is not None:  # stop the reading thread before the decoder goes away
            self._reading.close()
            self._reading = None

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class ImageFolderSource(FrameSource):
    """Frames from a list of image files (a folder, or an OTB/VOT/MOT sequence)."""

    kind = "images"

    def __init__(self, files: list[Path], name: str, *, sequence: Sequence | None = None,
                 skip_bad_frames: bool = False):
        super().__init__(name, skip_bad_frames=skip_bad_frames)
        if not files:
            raise SourceError(f"{name}: folder has no images")
        self.files = list(files)
        self.sequence = sequence
        if sequence is not None:
            self.fps = sequence.fps

    def __len__(self) -> int:
        return len(self.files)

    def _raw(self, start: int = 1):
        for i, path in enumerate(self.files[start - 1:], start=start):
            yield i, read_image(path), path.name


class VideoSource(FrameSource):
    """Frames decoded from a video file, a camera or a network stream (``rtsp://``, ``http://``, ...) by OpenCV.

    ``live`` is true for a camera, a live-stream protocol (:data:`pftrack.io.streams.LIVE_SCHEMES`) and a URL whose
    frame count is not known: its frames are read in the caller's thread (frames read ahead would be stale), it has
    no length, and it cannot be read twice from the start.

    ``reconnect``: a live stream URL whose feed breaks off is opened again, up to this many times in a row (waits
    of :data:`pftrack.io.streams.RECONNECT_WAIT_S`, doubling up to 8 of them; a frame read resets the count); its
    frames keep being numbered on, and the numbers of the first frames after each new connection are kept in
    ``reconnected``. 0 (the default): the feed's end is the source's end."""

    kind = "video"

    def __init__(self, target: str | int, name: str, *, skip_bad_frames: bool = False, reconnect: int = 0):
        super().__init__(name, skip_bad_frames=skip_bad_frames)
        self.target = target
        self.reconnect = int(reconnect)
        self.reconnected: list[int] = []
        url = isinstance(target, str) and streams.is_url(target)
        with quiet_opencv():  # OpenCV's own warnings on a failed open would precede our one-line error
            self.cap = streams.open_capture(target) if url else cv2.VideoCapture(target)
        where = streams.redact(target) if url else (target if isinstance(target, str) else name)
        # (a folder's video is named by its own file; a URL's password is not printed)
        if not self.cap.isOpened():
            self.cap.release()
            if url:
                raise SourceError(f"{where}: cannot open the stream (unreachable, refused, or an unsupported protocol "
                                  "or codec)")
            what = "camera" if isinstance(target, int) else "video"
            raise SourceError(f"{where}: cannot open as a {what} (not a video, unsupported codec or device missing)")
        ok, first = self.cap.read()
        if not ok or first is None:
            self.cap.release()
            raise SourceError(f"{where}: contains no readable frames")
        self._first: np.ndarray | None = first
        fps = self.cap.get(cv2.CAP_PROP_FPS)
        self.fps = float(fps) if fps and np.isfinite(fps) and fps > 0 else None
        count = int(self.cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
        self.live = isinstance(target, int) or (url and (streams.is_live(target) or count <= 0))
        self._count = count if count > 0 and not self.live else None
        if self.live:
            self.prefetch = 0  # frames read ahead would be stale

    def __len__(self) -> int:
        if self._count is None:
            raise TypeError("a live source (camera or stream) has no known length")
        return self._count

    def _raw(self, start: int = 1):
        number = 0
        if self._first is not None:
            number += 1
            first, self._first = self._first, None
            if start <= 1:
                yield number, first, "video frame"
        while number + 1 < start:  # passed over: grabbed, not converted
            if not self.cap.grab():
                return
            number += 1
        tries = 0  # tries to open the stream again since the last frame read
        while True:
            ok, img = self.cap.read()
            if not ok:
                if not (self.live and isinstance(self.target, str)) or tries >= self.reconnect:  # a live URL
                    return
                self._reopen(tries)
                tries += 1
                continue
            if tries:
                self.reconnected.append(number + 1)
                tries = 0
            number += 1
            yield number, img, "video frame"

    def _reopen(self, attempt: int) -> None:
        """A live stream URL's feed broke off: wait, then open it again (a failed open leaves a closed capture,
        whose next read fails)."""
        self.cap.release()
        streams.wait_before_reconnect(attempt)
        with quiet_opencv():
            self.cap = streams.open_capture(self.target)

    def close(self) -> None:
        super().close()
        self.cap.release()


def open_source(spec: str | int | Path, *, skip_bad_frames: bool = False, target: int | None = None,
                reconnect: int = 0) -> FrameSource:
    """Open a video file, image folder, OTB/VOT/MOTChallenge folder, camera index or network stream URL
    (``rtsp://``, ``rtmp://``, ``http(s)://``, ``udp://``, ... : whatever OpenCV's FFmpeg reads; see
    :mod:`pftrack.io.streams`).

    ``target`` picks the ground truth of one of several targets: the ``N`` of an OTB folder's
    ``groundtruth_rect.N.txt``, or a track id of a MOTChallenge folder's ``gt/gt.txt``
    (:func:`~pftrack.io.datasets.mot_target`).

    Raises :class:`~pftrack.errors.SourceError` with one line naming the problem:
    missing path, empty folder, unreadable video, unknown format, a target the source does not have.
    ``reconnect``: how many times in a row a live stream URL whose feed breaks off is opened again
    (:class:`VideoSource`; other sources ignore it).
    """
    camera = isinstance(spec, int) or (isinstance(spec, str) and spec.strip().isdigit())
    if isinstance(spec, str) and streams.is_url(spec):
        spec = spec.strip()
        if target is not None:
            raise SourceError(f"{streams.redact(spec)}: a target (--target) picks one of an OTB folder's annotated "
                              "targets or a track of a MOTChallenge folder's ground truth; a stream has neither")
        return VideoSource(spec, streams.redact(spec), skip_bad_frames=skip_bad_frames, reconnect=reconnect)
    path = None if camera else Path(spec)
    if path is not None and not path.exists():
        raise SourceError(f"{path}: no such file or folder")
    if target is not None and (path is None or not (path.is_dir() and detect_layout(path) in ("otb", "mot"))):
        raise SourceError(f"{spec}: a target (--target) picks one of an OTB folder's annotated targets or a track of "
                          "a MOTChallenge folder's ground truth; this source is neither")
    if path is None:
        index = int(spec)
        return VideoSource(index, f"camera {index}", skip_bad_frames=skip_bad_frames)
    if path.is_dir():
        layout = detect_layout(path)
        if layout is None:
            raise SourceError(f"{path}: folder has no images and no single video file")
        if target is not None:
            seq = _target_sequence(path, layout, int(target))
            return ImageFolderSource(seq.frames, str(path), sequence=seq, skip_bad_frames=skip_bad_frames)
        if layout == "video":  # streamed: the ground truth is read (first), the frames are not counted ahead
            seq = read_video_folder(path, count=False)
            source = VideoSource(str(single_video(path)), str(path), skip_bad_frames=skip_bad_frames)
            source.sequence = seq
            return source
        seq = read_sequence(path)
        return ImageFolderSource(seq.frames, str(path), sequence=seq if layout != "frames" else None,
                                 skip_bad_frames=skip_bad_frames)
    suffix = path.suffix.lower()
    if suffix in IMAGE_EXTENSIONS:
        return ImageFolderSource([path], str(path), skip_bad_frames=skip_bad_frames)
    if suffix not in VIDEO_EXTENSIONS:
        warnings.warn(f"{path}: unknown extension {suffix!r}, trying to open it as a video", stacklevel=2)
    return VideoSource(str(path), str(path), skip_bad_frames=skip_bad_frames)


def _target_sequence(path: Path, layout: str, target: int) -> Sequence:
    """The sequence of one target of an OTB folder (its ``groundtruth_rect.N.txt``; ``1`` is also the only target
    of a folder with one ``groundtruth_rect.txt``) or of a MOTChallenge folder (a ground-truth track id)."""
    if layout == "mot":
        return mot_target(read_sequence(path), target)
    targets = otb_targets(path)
    if not targets and target == 1:
        return read_otb(path)
    if target not in targets:
        have = ", ".join(str(t) for t in targets) if targets else "1 (one groundtruth_rect.txt)"
        raise SourceError(f"{path}: no target {target}; its targets are {have}")
    return read_otb(path, target=target)
