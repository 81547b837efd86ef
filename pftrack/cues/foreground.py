"""Foreground masks by background subtraction (OpenCV's MOG2), with its shadow test only where it can work.

MOG2 labels a pixel *shadow* (value 127) rather than foreground (255) when it is a darker copy of the background:
its brightness relative to the background's lies between ``tau`` (0.5) and 1, and its colour is the
background's (small colour distortion; Prati et al.'s test, as in OpenCV). The second condition is what tells a
cast shadow from a dark object. A grey frame has no colour, so the condition holds for every object that is
darker than the ground behind it by less than a factor of two, and such objects vanish with the shadows: a
mid-grey walker or car on light pavement is never detected.

:class:`Foreground` keeps OpenCV's threshold (``tau`` = 0.5) on colour frames and applies ``grey_shadow_threshold``
on grey frames (every channel equal, :func:`pftrack.cues.intensity.is_gray`), where shadows and dark objects
cannot be told apart by colour: a pixel is then a shadow only when its brightness ratio to the background is at
least that threshold. 1 drops the shadow label on grey frames (every darker pixel is foreground, cast shadows
join the objects); 0.5 is OpenCV's behaviour (objects up to twice as dark as the ground are lost).

MOG2 starts from the first frame it sees and learns fast at first, so the objects of the first frames become
background, and their ghosts stay in the model for hundreds of frames (on the PETS tune frames, 0.00-0.26 of the
walkers' boxes were foreground over the first 20 frames, 0.39 after frame 80). :meth:`Foreground.prime` starts the
model from a few frames instead, with their moving pixels replaced by the per-pixel median
(:func:`still_frames`): a bootstrap of the background in the manner of the scene-initialisation methods (a
temporal median where the scene is still).
"""

from __future__ import annotations

import cv2
import numpy as np

from .intensity import is_gray
from .noise import noise_sigma
from .quantize import level_gain

__all__ = ["BOOTSTRAP_DIFF", "GREY_SHADOW_THRESHOLD", "OPENCV_SHADOW_THRESHOLD", "PACK_ROWS", "Foreground",
           "pack_strips", "still_frames"]

OPENCV_SHADOW_THRESHOLD = 0.5  # MOG2's default tau
# chosen on the tune data (grey PETS frames 1-200 for multi-pf and both tripwires, grey synthetic traffic seeds
# 0-2; docs/mot.md): 0.5 / 0.7 / 0.85 / 1 gave multi-pf MOTA 0.275 / 0.471 / 0.472 / 0.255 and the trackerless
# tripwire's mean F1 over the three families 0.533 / 0.567 / 0.611 / 0.611
GREY_SHADOW_THRESHOLD = 0.85

#: A pixel more than this many grey levels from its temporal median (in any channel) is moving (:func:`still_frames`).
BOOTSTRAP_DIFF = 25


def still_frames(frames, diff: float = BOOTSTRAP_DIFF) -> np.ndarray:
    """The frames ``(K, H, W[, C])`` with each pixel that lies more than ``diff`` levels from the per-pixel median of
    the K frames (in any channel) replaced by that median: the scene with what moved through it taken out, and
    the camera's noise kept where it stood still."""
    st = np.asarray(frames)
    med = np.median(st, axis=0).astype(st.dtype)
    dev = np.abs(st.astype(np.int32) - med.astype(np.int32))
    moving = dev.max(axis=-1, keepdims=True) > diff if st.ndim == 4 else dev > diff
    return np.where(moving, med[None], st)


#: MOG2's ceiling on a pixel's variance (OpenCV's default varMax, grey levels squared): noise with a larger spread is
#: more than its background model can learn
MOG2_VAR_MAX = 75.0
#: the default noise limit of ``dark_denoise`` (pftrack mot's detector, the tripwire): sqrt(MOG2_VAR_MAX), 8.66 levels
DARK_NOISE_LIMIT = round(float(np.sqrt(MOG2_VAR_MAX)), 2)


def dark_levels(frame: np.ndarray, stretch: float, denoise: float) -> tuple[float, bool]:
    """``(gain, smooth)`` for a camera whose first frame is ``frame`` (BGR or grey): the level gain that brings its
    bright end to 255 (:func:`~pftrack.cues.quantize.level_gain`) when it is at least ``stretch`` (else 1; ``stretch``
    0: never), and whether the frame's noise (:func:`noise_sigma`) times that gain exceeds ``denoise`` levels
    (``denoise`` 0: never). The ``dark_stretch`` and ``dark_denoise`` of pftrack mot's detector and of the
    tripwire; :func:`apply_levels` applies them to every frame."""
    if stretch <= 0:
        return 1.0, False
    f = cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR) if frame.ndim == 2 else frame
    g = level_gain(f)
    if g < stretch:
        return 1.0, False
    return g, denoise > 0 and noise_sigma(f) * g > denoise


def apply_levels(frame: np.ndarray, gain: float, smooth: bool) -> np.ndarray:
    """``frame`` smoothed by a 3 x 3 Gaussian when ``smooth``, then multiplied by ``gain`` (saturated to uint8);
    the frame itself when ``gain`` is 1 (:func:`dark_levels`)."""
    if gain == 1.0:
        return frame
    return cv2.convertScaleAbs(cv2.GaussianBlur(frame, (3, 3), 0) if smooth else frame, alpha=gain)


#: the rows of the strips into which :class:`Foreground`'s rectangles are cut to be laid side by side for one model
PACK_ROWS = 8


def pack_strips(rects, rows: int = PACK_ROWS) -> np.ndarray:
    """``(n, 5)`` int: the rectangles ``(y0, y1, x0, x1)`` cut into strips of at most ``rows`` rows, each with the
    column ``a`` at which it starts when the strips are laid side by side in one image of ``rows`` rows (strips
    of fewer rows leave the rest of their columns unused)."""
    out, a = [], 0
    for y0, y1, x0, x1 in rects:
        for y in range(y0, y1, rows):
            out.append((y, min(y + rows, y1), x0, x1, a))
            a += x1 - x0
    return np.asarray(out, dtype=np.int64).reshape(-1, 5)


def _foreground_only(mask: np.ndarray) -> np.ndarray:
    """1 where MOG2's ``mask`` says foreground (255), 0 for background (0) and shadow (127)."""
    return cv2.threshold(mask, 254, 1, cv2.THRESH_BINARY)[1]


class Foreground:
    """MOG2 with shadow detection, whose shadow threshold on grey frames is ``grey_shadow_threshold``.

    ``apply(frame)`` returns a uint8 mask (1 foreground, 0 background or shadow) and updates the background model,
    as ``BackgroundSubtractorMOG2.apply`` does; ``grey`` says whether the last frame was taken as grey.

    ``rects``: the rectangles ``(y0, y1, x0, x1)`` of the frame where the mask is wanted (None: all of it); the mask
    is 0 elsewhere. MOG2 models each pixel on its own, so a pixel inside a rectangle gets the label it gets when the
    whole frame is modelled, at the cost of the rectangles' pixels only. The rectangles are cut into strips of
    :data:`PACK_ROWS` rows laid side by side in one image (:func:`pack_strips`), so that one call of one model
    labels them all: a band along an oblique wire is some sixty rectangles, whose calls cost about a tenth of the
    model's time.

    ``scale``: MOG2 models the frame reduced by this factor (block means, ``(w // scale, h // scale)``; ``rects`` are
    then in the reduced frame's pixels), and the mask is brought back to the frame's size by nearest neighbour. With
    ``rects``, only their blocks of ``scale`` x ``scale`` pixels are reduced (a last row or column of pixels that fills
    no whole block is left out, as background).

    ``rate_k``: on its n-th frame MOG2 learns at 1 / min(rate_k n, history) (OpenCV's own schedule is rate_k = 2,
    which is left to OpenCV); a larger value starts more slowly, so that a slow object is not taken into the
    background within the first seconds.

    ``model``: "mog2", or "mog": OpenCV contrib's Gaussian mixture of KaewTraKulPong and Bowden
    (BackgroundSubtractorMOG; ``history``, 5 mixtures, ``mog_ratio`` of the weight as background, OpenCV's automatic
    learning rate), which has no shadow test (``grey_shadow_threshold`` and ``rate_k`` apply to MOG2 only). Each
    pixel is modelled on its own, as with MOG2.
    """

    def __init__(self, history: int = 500, var_threshold: float = 16.0, *,
                 grey_shadow_threshold: float = GREY_SHADOW_THRESHOLD, rects=None, scale: int = 1,
                 rate_k: float = 2.0, model: str = "mog2", mog_ratio: float = 0.7):
        if model not in ("mog2", "mog"):
            raise ValueError(f"model must be 'mog2' or 'mog', got {model!r}")
        if not 0.0 < mog_ratio <= 1.0:
            raise ValueError(f"mog_ratio must be in (0, 1], got {mog_ratio}")
        if not 0.0 <= grey_shadow_threshold <= 1.0:
            raise ValueError(f"grey_shadow_threshold must be in [0, 1], got {grey_shadow_threshold}")
        if int(scale) < 1:
            raise ValueError(f"scale must be >= 1, got {scale}")
        if rate_k <= 0:
            raise ValueError(f"rate_k must be > 0, got {rate_k}")
        self.scale = int(scale)
        self.rate_k, self.history, self.frames = float(rate_k), int(history), 0  # frames: those applied so far
        self.grey_shadow_threshold = float(grey_shadow_threshold)
        self.rects = None if rects is None else [tuple(int(v) for v in r) for r in rects]
        if self.rects is not None and not self.rects:
            raise ValueError("rects is empty: give None for the whole frame")
        self.model = model
        strips = pack_strips(self.rects) if self.rects is not None else np.zeros((0, 5), np.int64)
        self._strips = [tuple(r) for r in strips.tolist()]
        self._width = int(strips[-1, 4] + strips[-1, 3] - strips[-1, 2]) if len(strips) else 0
        self._packed: np.ndarray | None = None  # the strips side by side, (PACK_ROWS, width[, C])
        if model == "mog":
            m = cv2.bgsegm.createBackgroundSubtractorMOG(int(history), 5, float(mog_ratio))
        else:
            m = cv2.createBackgroundSubtractorMOG2(history=int(history), varThreshold=float(var_threshold),
                                                   detectShadows=True)
            m.setShadowThreshold(OPENCV_SHADOW_THRESHOLD)
        self._model = m  # one model: the rectangles' strips are labelled in one image
        self.grey = False

    def apply(self, frame: np.ndarray, learning_rate: float = -1.0, out: np.ndarray | None = None) -> np.ndarray:
        """The mask of ``frame`` (see the class). ``out`` (with ``rects`` only): a uint8 array of the frame's size into
        which the rectangles' labels are written, the rest of it left as it is; returned."""
        if out is not None and self.rects is None:
            raise ValueError("out is for a model of rects only")
        if out is not None and (out.shape != frame.shape[:2] or out.dtype != np.uint8):
            raise ValueError(f"out must be uint8 of shape {frame.shape[:2]}, got {out.dtype} {out.shape}")
        # a lattice of every 16th pixel is enough to tell a grey frame (about 1700 pixels of a 768 x 576 frame)
        grey = (self.model == "mog2" and self.grey_shadow_threshold != OPENCV_SHADOW_THRESHOLD
                and is_gray(frame, stride=16))
        if grey != self.grey:
            self._model.setShadowThreshold(self.grey_shadow_threshold if grey else OPENCV_SHADOW_THRESHOLD)
            self.grey = grey
        self.frames += 1
        if learning_rate < 0 and self.rate_k != 2.0 and self.model == "mog2":
            learning_rate = 1.0 / min(self.rate_k * self.frames, self.history)
        h, w = frame.shape[:2]
        k = self.scale
        if self.rects is not None:
            return self._apply_strips(frame, learning_rate, out)
        if k > 1:
            frame = cv2.resize(frame, (max(w // k, 1), max(h // k, 1)), interpolation=cv2.INTER_AREA)
        out = _foreground_only(self._model.apply(frame, learningRate=learning_rate))
        return out if k == 1 else cv2.resize(out, (w, h), interpolation=cv2.INTER_NEAREST)

    def _apply_strips(self, frame: np.ndarray, learning_rate: float, out: np.ndarray | None = None) -> np.ndarray:
        """The mask of ``rects``: their strips copied side by side, labelled by one call of the model, and put back.
        With ``scale`` k, the strips' pixels of the frame (k times their rows and columns) are copied and reduced
        together (block means of k x k), and each label covers its block."""
        k = self.scale
        shape = (k * PACK_ROWS, k * self._width) + frame.shape[2:]
        if self._packed is None or self._packed.shape != shape or self._packed.dtype != frame.dtype:
            self._packed = np.zeros(shape, frame.dtype)  # unused rows of short strips stay 0 (always background)
        buf = self._packed
        strips = self._strips
        for y0, y1, x0, x1, a in strips:
            buf[:k * (y1 - y0), k * a:k * (a + x1 - x0)] = frame[k * y0:k * y1, k * x0:k * x1]
        small = buf if k == 1 else cv2.resize(buf, (self._width, PACK_ROWS), interpolation=cv2.INTER_AREA)
        mask = _foreground_only(self._model.apply(small, learningRate=learning_rate))
        if k > 1:
            mask = cv2.resize(mask, (k * self._width, k * PACK_ROWS), interpolation=cv2.INTER_NEAREST)
        if out is None:
            out = np.zeros(frame.shape[:2], np.uint8)
        for y0, y1, x0, x1, a in strips:
            out[k * y0:k * y1, k * x0:k * x1] = mask[:k * (y1 - y0), k * a:k * (a + x1 - x0)]
        return out

    def prime(self, frames, diff: float = BOOTSTRAP_DIFF) -> None:
        """Start the background model from ``frames`` (a few seconds of the stream, before it is processed) with
        their moving pixels replaced by the per-pixel median (:func:`still_frames`)."""
        if len(frames) == 0:
            return
        for f in still_frames(frames, diff):
            self.apply(f)
