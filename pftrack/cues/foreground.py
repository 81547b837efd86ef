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
"""

from __future__ import annotations

import cv2
import numpy as np

from .intensity import is_gray

__all__ = ["GREY_SHADOW_THRESHOLD", "OPENCV_SHADOW_THRESHOLD", "Foreground"]

OPENCV_SHADOW_THRESHOLD = 0.5  # MOG2's default tau
# chosen on the tune data (grey PETS frames 1-200 for multi-pf and both tripwires, grey synthetic traffic seeds
# 0-2; docs/mot.md): 0.5 / 0.7 / 0.85 / 1 gave multi-pf MOTA 0.275 / 0.471 / 0.472 / 0.255 and the trackerless
# tripwire's mean F1 over the three families 0.533 / 0.567 / 0.611 / 0.611
GREY_SHADOW_THRESHOLD = 0.85


class Foreground:
    """MOG2 with shadow detection, whose shadow threshold on grey frames is ``grey_shadow_threshold``.

    ``apply(frame)`` returns a uint8 mask (1 foreground, 0 background or shadow) and updates the background model,
    as ``BackgroundSubtractorMOG2.apply`` does; ``grey`` says whether the last frame was taken as grey.
    """

    def __init__(self, history: int = 500, var_threshold: float = 16.0, *,
                 grey_shadow_threshold: float = GREY_SHADOW_THRESHOLD):
        if not 0.0 <= grey_shadow_threshold <= 1.0:
            raise ValueError(f"grey_shadow_threshold must be in [0, 1], got {grey_shadow_threshold}")
        self.grey_shadow_threshold = float(grey_shadow_threshold)
        self.subtractor = cv2.createBackgroundSubtractorMOG2(history=int(history), varThreshold=float(var_threshold),
                                                             detectShadows=True)
        self.subtractor.setShadowThreshold(OPENCV_SHADOW_THRESHOLD)
        self.grey = False

    def apply(self, frame: np.ndarray, learning_rate: float = -1.0) -> np.ndarray:
        # a lattice of every 16th pixel is enough to tell a grey frame (about 1700 pixels of a 768 x 576 frame)
        grey = self.grey_shadow_threshold != OPENCV_SHADOW_THRESHOLD and is_gray(frame, stride=16)
        if grey != self.grey:
            self.subtractor.setShadowThreshold(self.grey_shadow_threshold if grey else OPENCV_SHADOW_THRESHOLD)
            self.grey = grey
        return (self.subtractor.apply(frame, learningRate=learning_rate) == 255).astype(np.uint8)
