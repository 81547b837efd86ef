"""OpenCV's classical trackers behind the pftrack protocol, for comparison.

``opencv-csrt``, ``opencv-kcf``, ``opencv-mil`` (``cv2.Tracker*``) and
``opencv-mosse``, ``opencv-medianflow``, ``opencv-tld`` (``cv2.legacy``), from
``opencv-contrib-python-headless``.  A peer's ``ok=False`` maps to ``lost=True``
and its last box is kept.  They have no particles and no meaningful score (1
while tracking, 0 when lost).

``camshift`` is the classical hue back-projection baseline (Bradski 1998): a
hue histogram of the initial box (pixels with enough saturation and value), its
back-projection in every frame and ``cv2.CamShift`` from the previous window.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
from dataclasses import dataclass

import cv2
import numpy as np

from ..errors import BoxError
from ..geometry import Box, clip_box
from ..params import Params, param
from .base import Tracker, TrackState

_FACTORIES = {
    "csrt": lambda: cv2.TrackerCSRT_create(),
    "kcf": lambda: cv2.TrackerKCF_create(),
    "mil": lambda: cv2.TrackerMIL_create(),
    "mosse": lambda: cv2.legacy.TrackerMOSSE_create(),
    "medianflow": lambda: cv2.legacy.TrackerMedianFlow_create(),
    "tld": lambda: cv2.legacy.TrackerTLD_create(),
}
_LEGACY = {"mosse", "medianflow", "tld"}
# MIL and TLD draw random numbers: OpenCV's (cv::theRNG, which MIL's sampler copies when it is built) and the C
# library's rand() (MIL's Haar features). Neither is reset between runs, so unseeded a run's result depended on what
# had run before it in the process. Both are seeded from the tracker's own generator before the tracker is built:
# a seed gives the same run whatever came before, and they count as stochastic (pftrack eval runs them per seed).
_RANDOM = {"mil", "tld"}
# OpenCV's MIL never returns from init/update on boxes of 4 x 4, 2 x 10 or 1 x 30 pixels (measured with OpenCV 4.x);
# 4 x 5, 3 x 8 and 5 x 5 work. Boxes under 25 pixels or 3 pixels a side are refused with a clear error rather than
# a hang (3 x 8 among them: the rule is kept simple).
_MIL_MIN_SIDE, _MIL_MIN_AREA = 3, 25
# OpenCV's legacy TLD slows down steeply as the box shrinks (measured with OpenCV 4.x on a 640 x 480 frame, one update:
# 0.28 s at 10 x 10, 1.1 s at 5 x 5, 3.2 s at 3 x 3, 76 s at 1 x 1, after an 11.7 s init): boxes under 5 pixels a
# side are refused with a clear error rather than a run that seems to hang.
_TLD_MIN_SIDE = 5


@functools.lru_cache(maxsize=1)
def _libc():
    """The C library, for ``srand``; None where it is not found by name (then only OpenCV's state is seeded)."""
    name = ctypes.util.find_library("c")
    try:
        return ctypes.CDLL(name) if name else None
    except OSError:
        return None


def seed_native_random(seed: int) -> None:
    """Seed the random state OpenCV's MIL and TLD draw from: OpenCV's own (this thread's) and the C library's."""
    cv2.setRNGSeed(int(seed))
    libc = _libc()
    if libc is not None:
        libc.srand(ctypes.c_uint(int(seed) & 0xFFFFFFFF))


def opencv_available(kind: str) -> bool:
    try:
        _FACTORIES[kind]()
        return True
    except Exception:
        return False


@dataclass(frozen=True, kw_only=True)
class OpenCVParams(Params):
    """OpenCV's trackers run with their library defaults."""


class OpenCVTracker(Tracker):
    """Adapter around one ``cv2`` tracker."""

    Params = OpenCVParams
    stochastic = False
    kind = "csrt"

    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        if self.kind in _RANDOM:  # before the tracker is built (see _RANDOM)
            seed_native_random(int(self.rng.integers(0, 2**31 - 1)))
        self._cv = _FACTORIES[self.kind]()
        h, w = frame.shape[:2]
        bx = clip_box(np.asarray(box), w, h)
        if self.kind in _LEGACY:
            rect = tuple(float(v) for v in bx)
        else:
            x, y = int(round(bx[0])), int(round(bx[1]))
            rect = (x, y, max(1, int(round(bx[0] + bx[2])) - x), max(1, int(round(bx[1] + bx[3])) - y))
            if self.kind == "mil" and (min(rect[2:]) < _MIL_MIN_SIDE or rect[2] * rect[3] < _MIL_MIN_AREA):
                raise BoxError(f"{self.name}: box {rect[2]}x{rect[3]} is too small for OpenCV's MIL tracker, which "
                               f"hangs on boxes under about 5x5 pixels; give a box of at least 5x5")
        if self.kind == "tld" and min(w, h) < 50:
            # OpenCV's legacy TLD crashes the process (a segmentation fault) or never returns on small frames (seen on
            # 40 x 30 with a 30 x 20 box, and on frames under 50 px with a box that fills them): refuse it instead
            raise BoxError(f"{self.name}: OpenCV's TLD crashes or hangs on frames under 50 px on a side (this one is "
                           f"{w}x{h}); use another tracker")
        if self.kind == "tld" and min(rect[2:]) < _TLD_MIN_SIDE:
            raise BoxError(f"{self.name}: box {rect[2]:g}x{rect[3]:g} is too small for OpenCV's TLD, which takes "
                           f"seconds to minutes a frame on boxes under {_TLD_MIN_SIDE}x{_TLD_MIN_SIDE} pixels; give a "
                           f"box of at least {_TLD_MIN_SIDE}x{_TLD_MIN_SIDE} or use another tracker")
        if self.kind == "tld" and min(rect[2:]) < 21 and (rect[2] >= w - 0.5 or rect[3] >= h - 0.5):
            # OpenCV's legacy TLD crashes the process (a segmentation fault) on such a box: refuse it instead
            raise BoxError(f"{self.name}: OpenCV's TLD crashes on a box that spans the whole frame one way and is "
                           f"20 px or less the other ({rect[2]:g}x{rect[3]:g} in a {w}x{h} frame); shrink it by a "
                           f"pixel or widen it")
        try:
            res = self._cv.init(frame, rect)
        except cv2.error as exc:  # e.g. MIL on a box that fills the frame: no room for its samples
            reason = _cv_reason(exc)
            raise BoxError(f"{self.name}: OpenCV's tracker cannot start on box {rect} in a {w}x{h} frame "
                           f"({reason})") from None
        if res is False:  # legacy API returns a bool
            raise RuntimeError(f"{self.name}: OpenCV refused to initialise on box {box}")
        self._last = tuple(float(v) for v in box)
        return TrackState(box=self._last, score=1.0, lost=False)

    def _update(self, frame: np.ndarray) -> TrackState:
        try:
            ok, rect = self._cv.update(frame)
        except cv2.error as exc:  # e.g. CSRT on a box of a few pixels at the frame's corner: its window is empty
            return TrackState(box=self._last, score=0.0, lost=True, info={"error": _cv_reason(exc)})
        rect = tuple(float(v) for v in rect)
        if ok and rect[2] > 0 and rect[3] > 0 and all(np.isfinite(rect)):
            self._last = rect
            return TrackState(box=rect, score=1.0, lost=False)
        return TrackState(box=self._last, score=0.0, lost=True)


def _cv_reason(exc: cv2.error) -> str:
    """The check an OpenCV error reports as failed, on one line, without OpenCV's source path."""
    return " ".join(str(exc).split()).split("error: ", 1)[-1].split(") ", 1)[-1] or "cv2.error"


def _make(kind: str, label: str) -> type[OpenCVTracker]:
    return type(f"OpenCV{kind.upper()}", (OpenCVTracker,), {"kind": kind, "name": label,
                                                           "stochastic": kind in _RANDOM})


OPENCV_TRACKERS = {f"opencv-{k}": _make(k, f"opencv-{k}") for k in _FACTORIES}


@dataclass(frozen=True, kw_only=True)
class CamShiftParams(Params):
    """CamShift on the hue back-projection (OpenCV sample defaults)."""

    hue_bins: int = param(16, ge=2, le=180, doc="Bins of the hue histogram.")
    min_saturation: int = param(60, ge=0, le=255, doc="Pixels with lower saturation are ignored (hue unreliable).")
    min_value: int = param(32, ge=0, le=255, doc="Pixels with lower value (brightness) are ignored.")
    max_iterations: int = param(10, ge=1, le=1000, doc="Mean-shift iterations per frame.")
    epsilon: float = param(1.0, gt=0, doc="Stop when the window moves less than this (pixels).")


class CamShift(Tracker):
    """Hue back-projection + ``cv2.CamShift`` (a classic colour baseline)."""

    name = "camshift"
    Params = CamShiftParams
    stochastic = False

    def _mask(self, hsv):
        p = self.params
        return cv2.inRange(hsv, (0, p.min_saturation, p.min_value), (180, 255, 255))

    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        p = self.params
        h, w = frame.shape[:2]
        bx = clip_box(np.asarray(box), w, h)
        x, y = int(bx[0]), int(bx[1])
        x2, y2 = max(x + 1, int(round(bx[0] + bx[2]))), max(y + 1, int(round(bx[1] + bx[3])))
        hsv = cv2.cvtColor(frame[y:y2, x:x2], cv2.COLOR_BGR2HSV)
        hist = cv2.calcHist([hsv], [0], self._mask(hsv), [p.hue_bins], [0, 180])
        cv2.normalize(hist, hist, 0, 255, cv2.NORM_MINMAX)
        self._hist = hist
        self._window = (x, y, x2 - x, y2 - y)
        self._last = tuple(float(v) for v in box)
        return TrackState(box=self._last, score=1.0, lost=False)

    def _update(self, frame: np.ndarray) -> TrackState:
        p = self.params
        hsv = cv2.cvtColor(frame, cv2.COLOR_BGR2HSV)
        prob = cv2.calcBackProject([hsv], [0], self._hist, [0, 180], 1)
        prob &= self._mask(hsv)
        crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, p.max_iterations, p.epsilon)
        _, window = cv2.CamShift(prob, self._window, crit)
        x, y, w, h = (int(v) for v in window)
        if w <= 0 or h <= 0:
            return TrackState(box=self._last, score=0.0, lost=True)
        self._window = (x, y, w, h)
        region = prob[y:y + h, x:x + w]
        score = float(region.mean() / 255.0) if region.size else 0.0
        self._last = (float(x), float(y), float(w), float(h))
        return TrackState(box=self._last, score=score, lost=False)
