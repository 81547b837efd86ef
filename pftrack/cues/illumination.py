"""Local illumination normalisation of grey frames: the self-quotient image.

A grey target lit by a lamp that moves, or passing from shade into light, changes its
grey levels by a gain that varies slowly over the image.  Global histogram
equalisation (:func:`pftrack.cues.intensity.equalization_lut`) undoes a gain that is the
same everywhere, not one that differs between the target and the rest of the frame.

The self-quotient image (Wang, Li & Wang, "Face recognition under varying lighting
conditions using self quotient image", FG 2004; a single-scale Retinex, Land 1977,
Jobson et al. 1997) divides each pixel by a smoothed version of the image:

    Q(x) = I(x) / (G_sigma * I)(x)

Under the Lambertian model ``I = R L`` with an illumination ``L`` that is smooth at the
scale ``sigma``, ``G_sigma * I ≈ L (G_sigma * R)``, so ``Q ≈ R / (G_sigma * R)``: the
light cancels and what is left is the reflectance relative to its surroundings.

:func:`illumination_quotient` returns ``I S_mean / S`` with ``S = G_sigma * I``: the quotient
scaled back to the frame's mean level ``S_mean`` (a uniform gain is left for the grey
features' global equalisation).  Dividing out only half of the light, ``I (S_mean / S)^0.5``,
kept too little of the gain under a drifting lamp (docs/robustness.md).

The price: whatever varies at scales above ``sigma`` is divided out too, the scene's own
bright and dark areas included, so a patch of background can come to resemble the target
more than it did (docs/robustness.md measures both sides).

Speed: the smoothing is taken on a block-averaged copy (``block`` x ``block`` pixels per
cell, then a Gaussian of ``sigma / block`` cells), and the reciprocal is brought back to
full resolution by one bilinear resize and one saturating multiply into kept buffers
(:class:`QuotientImage`): about 0.2 ms for a 480 x 360 frame on one core.
"""

from __future__ import annotations

import cv2
import numpy as np

from .intensity import to_gray

__all__ = ["QuotientImage", "illumination_quotient"]


class QuotientImage:
    """:func:`illumination_quotient` with its full-size intermediate images kept between calls (a tracker calls
    it on every frame of one size)."""

    def __init__(self, sigma: float = 0.1, *, block: int = 16, bgr: bool = True):
        self.sigma = float(sigma)
        self.block = max(1, int(block))
        self.bgr = bool(bgr)  # False: the quotient as a 2-D grey image (no copy into three channels)
        self._gain: np.ndarray | None = None
        self._q: np.ndarray | None = None

    def __call__(self, frame: np.ndarray) -> np.ndarray:
        gray = to_gray(frame)
        h, w = gray.shape
        k = max(1, min(self.block, w, h))  # a frame smaller than a block is one cell per pixel row or column
        sw, sh = w // k, h // k
        # exact k x k block means of the largest whole-block part (OpenCV's fast integer-factor path); the
        # strip of fewer than k pixels left over at the right and bottom is covered by the bilinear resize
        small = cv2.resize(gray[:sh * k, :sw * k], (sw, sh), interpolation=cv2.INTER_AREA).astype(np.float32)
        s = self.sigma * max(h, w) / k
        if s > 0:
            small = cv2.GaussianBlur(small, (0, 0), s, borderType=cv2.BORDER_REFLECT)
        small = np.maximum(small, np.float32(1.0))
        inv = np.float32(small.mean()) / small  # S_mean / S: the frame's mean level is kept
        if self._gain is None or self._gain.shape != (h, w):
            self._gain = np.empty((h, w), np.float32)
            self._q = np.empty((h, w), np.uint8)
        # bilinear from the cells' centres (OpenCV's resize mapping) over the whole-block part, and the last
        # column and row repeated over the strip of fewer than k pixels left at the right and bottom
        W, H = sw * k, sh * k
        cv2.resize(inv, (W, H), dst=self._gain[:H, :W], interpolation=cv2.INTER_LINEAR)
        if W < w:
            self._gain[:H, W:] = self._gain[:H, W - 1:W]
        if H < h:
            self._gain[H:] = self._gain[H - 1:H]
        cv2.multiply(gray, self._gain, dst=self._q, dtype=cv2.CV_8U)
        return cv2.cvtColor(self._q, cv2.COLOR_GRAY2BGR) if self.bgr else self._q


def illumination_quotient(frame: np.ndarray, sigma: float = 0.1, *, block: int = 16) -> np.ndarray:
    """The self-quotient image of a grey (or BGR, converted to grey) frame, as a BGR ``uint8`` frame.

    ``sigma`` is the std of the Gaussian illumination estimate as a fraction of the frame's
    larger side; ``block`` the side of the cells the estimate is taken on.  Levels saturate at 255.  Each output channel holds the
    same grey levels, so the result stays a grey frame for
    :func:`~pftrack.cues.intensity.is_gray`.
    """
    return QuotientImage(sigma, block=block)(frame)
