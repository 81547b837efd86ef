"""Object detectors behind one protocol: ``detector(frame) -> (K, 5) array of x, y, w, h, score``.

* ``motion`` — the moving-object detector of the book *Object Tracking*, ch. 1: grey
  level ``Y = 0.3R + 0.59G + 0.11B``, median filter, reduced resolution (block
  averaging), three-frame differencing, threshold, closing, connected components and a
  minimum area.  The book differences frame ``k`` with ``k-1`` and ``k+1``; to detect
  online without a frame of latency we AND the differences of frame ``k`` with ``k-1``
  and ``k-2``, which isolates the object at its position in frame ``k`` the same way
  (the background uncovered since ``k-1`` equals frame ``k-2`` there and drops out).
* ``mog2`` — OpenCV's Gaussian-mixture background subtraction (``createBackgroundSubtractorMOG2``)
  with shadow detection: shadow pixels (127) are discarded (on grey frames, where MOG2 cannot tell a shadow from
  a dark object, with their own threshold: ``grey_shadow_threshold``), then opening/closing, connected
  components and a minimum area.
* ``hog`` — OpenCV's built-in HOG + linear SVM people detector (Dalal & Triggs), no downloads.
* any callable with the same signature, wrapped by :func:`as_detector`.

Boxes are in full-resolution image coordinates; ``score`` is in [0, 1].  The
blob detectors also keep the foreground mask of the last frame in
``detector.foreground = (mask, scale)`` (``mask`` at 1/``scale`` resolution), which
``multi-pf`` uses as a likelihood cue.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import cv2
import numpy as np

from ..cues.foreground import GREY_SHADOW_THRESHOLD, Foreground, apply_levels, dark_levels
from ..errors import ParameterError
from ..frames import as_bgr_uint8
from ..params import Params, param

Detector = Callable[[np.ndarray], np.ndarray]


def _components(mask: np.ndarray, scale: float, min_area: float, max_area_fraction: float = 0.5,
                split_aspect: float = 0.0) -> np.ndarray:
    """Bounding boxes (full-resolution) of the connected components of a binary mask.

    With ``split_aspect > 0`` (the expected width/height of one object, e.g. 0.4 for
    standing people), a blob at least 32 px tall and wider than 1.6 times that is
    split into ``round(width / (split_aspect * height))`` (at most 3) side-by-side
    boxes: people walking together form one foreground blob.
    """
    n, _, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    h, w = mask.shape
    out = []
    for k in range(1, n):
        x, y, bw, bh, area = stats[k]
        full_area = area * scale * scale
        if full_area < min_area or bw * bh > max_area_fraction * w * h:
            continue
        fill = min(1.0, area / float(bw * bh))
        for b in split_wide((x * scale, y * scale, bw * scale, bh * scale), split_aspect):
            out.append((*b, fill))
    return np.array(out, dtype=np.float64).reshape(-1, 5)


def split_wide(box, aspect: float, min_height: float = 32.0) -> list[tuple[float, float, float, float]]:
    """A blob box ``(x, y, w, h)`` in pixels as ``round(w / (aspect h))`` (at most 3) side-by-side boxes when
    it is at least ``min_height`` tall and wider than 1.6 ``aspect h`` (people walking together form one
    blob); otherwise the box itself.  ``aspect`` 0 never splits.  Only blobs tall enough to be whole
    objects are split: a wide, flat blob is a fragment (legs, a shadow), not several objects."""
    x, y, w, h = (float(v) for v in box)
    parts = 1
    if aspect > 0 and w > 1.6 * aspect * h and h >= min_height:
        parts = min(3, max(1, int(round(w / (aspect * h)))))
    pw = w / parts
    return [(x + i * pw, y, pw, h) for i in range(parts)]


@dataclass(frozen=True, kw_only=True)
class MotionDetectorParams(Params):
    downscale: int = param(2, ge=1, le=16, doc=(
        "Block-averaging factor of the reduced resolution (book ch. 1: 320x240 down to 160x120, 80x60 or 40x30)."))
    median: int = param(3, ge=1, le=15, doc="Median filter aperture (odd; 1 disables). The book does not give it.")
    threshold: int = param(12, ge=1, le=255, doc="Threshold T on the grey-level differences (not given in the book).")
    closing: int = param(7, ge=1, le=51, doc="Size of the closing (dilate then erode) element, in reduced pixels.")
    min_area: float = param(300.0, ge=0, doc="Minimum blob area in full-resolution pixels (not given in the book).")
    split_aspect: float = param(0.0, ge=0, le=10, doc=(
        "Expected width/height of one object (0.4 for people); wider blobs are split (0: never)."))


class MotionDetector:
    """Three-frame differencing on reduced-resolution grey images (book ch. 1)."""

    Params = MotionDetectorParams

    def __init__(self, params: MotionDetectorParams | None = None):
        self.foreground = None
        self.params = params or MotionDetectorParams()
        p = self.params
        if p.median % 2 == 0:
            raise ParameterError("parameter 'median' must be odd")
        self._hist: list[np.ndarray] = []
        self._kernel = cv2.getStructuringElement(cv2.MORPH_RECT, (p.closing, p.closing))

    def _grey(self, frame: np.ndarray) -> np.ndarray:
        p = self.params
        b, g, r = cv2.split(frame.astype(np.float32))
        y = 0.3 * r + 0.59 * g + 0.11 * b
        if p.downscale > 1:
            h, w = y.shape
            y = cv2.resize(y, (w // p.downscale, h // p.downscale), interpolation=cv2.INTER_AREA)
        y = np.clip(y, 0, 255).astype(np.uint8)
        if p.median > 1:
            y = cv2.medianBlur(y, p.median)
        return y

    def __call__(self, frame: np.ndarray) -> np.ndarray:
        p = self.params
        g = self._grey(as_bgr_uint8(frame))
        self._hist.append(g)
        if len(self._hist) > 3:
            self._hist.pop(0)
        if len(self._hist) < 3:
            self.foreground = None
            return np.zeros((0, 5))
        f2, f1, f0 = self._hist
        d1 = cv2.absdiff(f0, f1) > p.threshold
        d2 = cv2.absdiff(f0, f2) > p.threshold
        mask = (d1 & d2).astype(np.uint8) * 255
        mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, self._kernel)
        self.foreground = (mask, float(p.downscale))
        return _components(mask, float(p.downscale), p.min_area, split_aspect=p.split_aspect)


@dataclass(frozen=True, kw_only=True)
class MOG2DetectorParams(Params):
    history: int = param(500, ge=1, doc=(
        "Frames of history of the background model; longer keeps standing people in the foreground longer."))
    var_threshold: float = param(16.0, gt=0, doc="Mahalanobis threshold of MOG2 (OpenCV default 16).")
    downscale: int = param(2, ge=1, le=16, doc="Run the subtractor on a frame reduced by this factor (speed).")
    opening: int = param(3, ge=1, le=51, doc="Opening element size (reduced pixels): removes speckle.")
    closing: int = param(9, ge=1, le=51, doc="Closing element size (reduced pixels): joins body parts.")
    min_area: float = param(400.0, ge=0, doc="Minimum blob area in full-resolution pixels.")
    learning_rate: float = param(-1.0, ge=-1, le=1, doc="MOG2 learning rate (-1: automatic, 1/history).")
    split_aspect: float = param(0.0, ge=0, le=10, doc=(
        "Expected width/height of one object (0.4 for people); wider blobs are split (0: never)."))
    dark_stretch: float = param(0.0, ge=0, le=8, doc=(
        "A dark camera: when the first frame's bright end (its 99.5th percentile, pftrack.cues.quantize.level_gain) "
        "needs a gain of at least this to reach level 255, every reduced frame is multiplied by that gain (at most 8) "
        "before MOG2, whose floor on each pixel's variance would otherwise hide a person's contrast, which falls with "
        "the light while the floor does not. 0: never."))
    dark_denoise: float = param(0.0, ge=0, le=255, doc=(
        "Under dark_stretch, a camera's noise is stretched with its frames. When the first reduced frame's noise "
        "(pftrack.cues.foreground.noise_sigma) times the gain exceeds this many grey levels, every reduced frame is "
        "smoothed by a 3 x 3 Gaussian before the stretch (its noise falls to about a third). 0: never (multi-pf "
        "passes 8.66 = sqrt(75), pftrack.cues.foreground.DARK_NOISE_LIMIT: the spread of MOG2's ceiling on a "
        "pixel's variance, above which the noise is more than its background model can learn)."))
    grey_shadow_threshold: float = param(GREY_SHADOW_THRESHOLD, ge=0, le=1, doc=(
        "MOG2's shadow threshold on grey frames, where its shadow test cannot tell a cast shadow from an object up "
        "to twice as dark as the ground (it has no colour to compare): a darker pixel is a shadow only when its "
        "brightness is at least this fraction of the background's. 1: no shadows on grey frames; 0.5: OpenCV's "
        "threshold, as on colour frames; 0.85 chosen on the tune data (pftrack.cues.foreground)."))


class MOG2Detector:
    """Background subtraction with shadow removal and morphology."""

    Params = MOG2DetectorParams

    def __init__(self, params: MOG2DetectorParams | None = None):
        self.foreground = None
        self.gain: float | None = None  # dark_stretch's gain, set on the first frame
        self.denoise = False  # dark_denoise: the stretched frames are smoothed, set on the first frame
        self.params = params or MOG2DetectorParams()
        p = self.params
        self._sub = Foreground(p.history, p.var_threshold, grey_shadow_threshold=p.grey_shadow_threshold)
        self._open = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (p.opening, p.opening))
        self._close = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (p.closing, p.closing))

    def _reduced(self, frame: np.ndarray) -> np.ndarray:
        f = as_bgr_uint8(frame)
        d = self.params.downscale
        f = cv2.resize(f, (f.shape[1] // d, f.shape[0] // d), interpolation=cv2.INTER_AREA) if d > 1 else f
        if self.gain is None:  # the first frame decides (dark_stretch, dark_denoise)
            self.gain, self.denoise = dark_levels(f, self.params.dark_stretch, self.params.dark_denoise)
        return apply_levels(f, self.gain, self.denoise)

    def prime(self, frames) -> None:
        """Start the background from the first ``frames`` of the stream, their moving pixels replaced by the
        per-pixel median (:meth:`pftrack.cues.foreground.Foreground.prime`)."""
        self._sub.prime([self._reduced(f) for f in frames])

    def __call__(self, frame: np.ndarray) -> np.ndarray:
        p = self.params
        f = self._reduced(frame)
        mask = self._sub.apply(f, p.learning_rate) * np.uint8(255)  # MOG2's shadows are background on colour frames
        mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, self._open)
        mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, self._close)
        self.foreground = (mask, float(p.downscale))
        return _components(mask, float(p.downscale), p.min_area, split_aspect=p.split_aspect)


@dataclass(frozen=True, kw_only=True)
class HOGDetectorParams(Params):
    resize: float = param(1.25, ge=0.25, le=4, doc=(
        "Resize the frame by this factor before detection: >1 finds people smaller than the 64x128 window's "
        "96-pixel person, <1 is faster."))
    hit_threshold: float = param(0.0, doc="SVM score threshold of detectMultiScale.")
    scale: float = param(1.05, gt=1, le=2, doc="Pyramid scale step of detectMultiScale.")
    stride: int = param(8, ge=1, le=32, doc="Window stride (pixels).")
    person_width: float = param(0.5, gt=0, le=1, doc=(
        "Width of the person inside a detection window (INRIA windows: 64 px wide around a ~32-px person); "
        "boxes are shrunk to it so they match tight ground truth."))
    person_height: float = param(0.75, gt=0, le=1, doc="Height of the person inside a window (96 of 128 px).")
    nms_iou: float = param(0.5, gt=0, le=1, doc="Non-maximum suppression overlap of the (shrunk) boxes.")


class HOGDetector:
    """OpenCV's default HOG people detector (64x128 window), boxes shrunk to the person."""

    Params = HOGDetectorParams

    def __init__(self, params: HOGDetectorParams | None = None):
        self.params = params or HOGDetectorParams()
        self._hog = cv2.HOGDescriptor()
        self._hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())

    def __call__(self, frame: np.ndarray) -> np.ndarray:
        p = self.params
        f = as_bgr_uint8(frame)
        if p.resize != 1.0:
            f = cv2.resize(f, (int(round(f.shape[1] * p.resize)), int(round(f.shape[0] * p.resize))),
                           interpolation=cv2.INTER_LINEAR if p.resize > 1 else cv2.INTER_AREA)
        rects, weights = self._hog.detectMultiScale(f, hitThreshold=p.hit_threshold, winStride=(p.stride, p.stride),
                                                    scale=p.scale)
        if len(rects) == 0:
            return np.zeros((0, 5))
        r = np.asarray(rects, dtype=np.float64) / p.resize
        w = np.asarray(weights, dtype=np.float64).reshape(-1)
        cx, cy = r[:, 0] + r[:, 2] / 2, r[:, 1] + r[:, 3] / 2
        bw, bh = r[:, 2] * p.person_width, r[:, 3] * p.person_height
        boxes = np.column_stack([cx - bw / 2, cy - bh / 2, bw, bh])
        score = 1.0 / (1.0 + np.exp(-w))
        keep = nms(boxes, score, p.nms_iou)
        return np.column_stack([boxes[keep], score[keep]])


def nms(boxes: np.ndarray, scores: np.ndarray, iou_threshold: float) -> np.ndarray:
    """Greedy non-maximum suppression; indices of the kept boxes, best first."""
    from ..geometry import iou_matrix

    order = np.argsort(-scores, kind="stable")
    keep: list[int] = []
    m = iou_matrix(boxes, boxes)
    suppressed = np.zeros(len(boxes), bool)
    for i in order:
        if suppressed[i]:
            continue
        keep.append(int(i))
        suppressed |= m[i] > iou_threshold
    return np.array(keep, dtype=int)


DETECTORS = {"motion": MotionDetector, "mog2": MOG2Detector, "hog": HOGDetector}


def create_detector(name: str, **params) -> Detector:
    """A registered detector by name, with validated parameters."""
    try:
        cls = DETECTORS[name]
    except KeyError:
        raise ParameterError(f"unknown detector '{name}'; choose from {', '.join(DETECTORS)}") from None
    return cls(cls.Params.from_mapping(params))


def as_detector(fn) -> Detector:
    """Wrap any callable ``frame -> boxes`` (rows of 4 or 5 numbers) into the protocol."""
    if isinstance(fn, str):
        return create_detector(fn)
    if not callable(fn):
        raise ParameterError("a detector is a registered name or a callable frame -> boxes")

    def call(frame: np.ndarray) -> np.ndarray:
        out = fn(frame)
        rows = []
        for det in out if out is not None else []:
            det = [float(v) for v in det]
            if len(det) >= 4 and det[2] > 0 and det[3] > 0 and all(np.isfinite(det[:4])):
                rows.append(det[:4] + [det[4] if len(det) > 4 else 1.0])
        return np.array(rows, dtype=np.float64).reshape(-1, 5)

    return call
