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

:func:`illumination_quotient` returns ``I (S_mean / S)^gamma`` with ``S = G_sigma * I``: the
quotient scaled back to the frame's mean level ``S_mean`` (a uniform gain is left for the
grey features' global equalisation), and with ``gamma < 1`` only part of the local light
divided out.

The price: whatever varies at scales above ``sigma`` is divided out too, the scene's own
bright and dark areas included, so a patch of background can come to resemble the target
more than it did (docs/robustness.md measures both sides).

Speed: the smoothing is taken on a block-averaged copy (``block`` x ``block`` pixels per
cell, then a Gaussian of ``sigma / block`` cells), and the reciprocal is brought back to
full resolution by one bilinear resize and one saturating multiply, about 0.25 ms for a
640 x 480 frame on one core.
"""

from __future__ import annotations

import cv2
import numpy as np

from .intensity import to_gray

__all__ = ["illumination_quotient"]


def illumination_quotient(frame: np.ndarray, sigma: float = 0.1, *, strength: float = 1.0, block: int = 16) -> np.ndarray:
    """The self-quotient image of a grey (or BGR, converted to grey) frame, as a BGR ``uint8`` frame.

    ``sigma`` is the std of the Gaussian illumination estimate as a fraction of the frame's
    larger side; ``strength`` is gamma (see the module docstring).  Levels saturate at 255.
    Each output channel holds the same grey levels, so the result stays a grey frame for
    :func:`~pftrack.cues.intensity.is_gray`.
    """
    gray = to_gray(frame)
    h, w = gray.shape
    k = max(1, int(block))
    sw, sh = max(1, w // k), max(1, h // k)
    small = cv2.resize(gray, (sw, sh), interpolation=cv2.INTER_AREA).astype(np.float32)
    s = float(sigma) * max(h, w) / k
    if s > 0:
        small = cv2.GaussianBlur(small, (0, 0), s, borderType=cv2.BORDER_REFLECT)
    small = np.maximum(small, np.float32(1.0))
    inv = np.float32(small.mean()) / small  # L_mean / L: the frame's mean level is kept
    if strength != 1.0:
        inv = np.power(inv, np.float32(strength))
    gain = cv2.resize(inv, (w, h), interpolation=cv2.INTER_LINEAR)
    q = cv2.multiply(gray, gain, dtype=cv2.CV_8U)
    return cv2.cvtColor(q, cv2.COLOR_GRAY2BGR)
