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
(:class:`QuotientImage`; the block means and the multiply compiled, with OpenCV's numbers): about 0.17 ms for an
854 x 480 frame on one core.
"""

from __future__ import annotations

import cv2
import numpy as np

from .._numba import njit, numba_enabled
from ..frames import grey_origin
from .intensity import to_gray

__all__ = ["QuotientImage", "block_means_gray", "illumination_quotient"]


@njit(cache=True)
def _block_means_gray(gray, k, sw, sh, out):
    """``out[j, i]``: the mean of the ``k x k`` block of the 2-D ``uint8`` image ``gray`` whose top-left pixel is
    ``(i k, j k)``, as OpenCV's integer-factor area resize gives it (the float32 sum times the float32 ``1/k^2``,
    rounded to nearest, ties to even), as float32.  Each band of ``k`` rows is summed column by column first (a
    vectorised pass), then its columns by blocks: 3-4x faster than ``cv2.resize(..., INTER_AREA)`` at ``k = 16``."""
    inv = np.float32(1.0) / np.float32(k * k)
    n = sw * k
    acc = np.empty(n, np.int32)
    for j in range(sh):
        row = gray[j * k]
        for c in range(n):
            acc[c] = row[c]
        for r in range(j * k + 1, j * k + k):
            row = gray[r]
            for c in range(n):
                acc[c] += row[c]
        for i in range(sw):
            s = 0
            for c in range(i * k, i * k + k):
                s += acc[c]
            out[j, i] = np.rint(np.float32(s) * inv)
    return out


@njit(cache=True)
def _scale_levels(gray, gain, out):
    """``out = saturate(round(float32(gray) * gain))`` (to nearest, ties to even): ``cv2.multiply(gray, gain,
    dst=out, dtype=cv2.CV_8U)`` for a 2-D ``uint8`` image and a float32 gain, the same numbers, about 3x faster."""
    h, w = gray.shape
    lo = np.float32(0.0)
    hi = np.float32(255.0)
    for y in range(h):
        g = gray[y]
        a = gain[y]
        o = out[y]
        for x in range(w):
            o[x] = np.uint8(min(max(np.rint(np.float32(g[x]) * a[x]), lo), hi))
    return out


def block_means_gray(gray: np.ndarray, k: int) -> np.ndarray:
    """The ``k x k`` block means of the largest whole-block part of a 2-D ``uint8`` image, float32: the numbers of
    ``cv2.resize(gray[:sh k, :sw k], (sw, sh), interpolation=cv2.INTER_AREA).astype(np.float32)`` (compiled for
    ``k > 2`` when Numba is on; tested equal for k = 3 ... 39)."""
    h, w = gray.shape
    sw, sh = w // k, h // k
    if numba_enabled() and gray.dtype == np.uint8 and k > 2:  # OpenCV's 2 x 2 path rounds in integers
        return _block_means_gray(np.ascontiguousarray(gray), int(k), sw, sh, np.empty((sh, sw), np.float32))
    return cv2.resize(gray[:sh * k, :sw * k], (sw, sh), interpolation=cv2.INTER_AREA).astype(np.float32)


class QuotientImage:
    """:func:`illumination_quotient` with its full-size intermediate images kept between calls (a tracker calls
    it on every frame of one size)."""

    def __init__(self, sigma: float = 0.1, *, block: int = 16, bgr: bool = True):
        self.sigma = float(sigma)
        self.block = max(1, int(block))
        self.bgr = bool(bgr)  # False: the quotient as a 2-D grey image (no copy into three channels)
        self._gain: np.ndarray | None = None
        self._q: np.ndarray | None = None

    def __call__(self, frame: np.ndarray, *, gray: np.ndarray | None = None) -> np.ndarray:
        """The self-quotient image of ``frame`` (``gray``: its grey image, when the caller has it already)."""
        if gray is None:  # a BGR frame made from a grey image: that image (read only here), the same levels
            gray = grey_origin(frame)
        if gray is None:
            gray = to_gray(frame)
        h, w = gray.shape
        k = max(1, min(self.block, w, h))  # a frame smaller than a block is one cell per pixel row or column
        sw, sh = w // k, h // k
        # exact k x k block means of the largest whole-block part (OpenCV's fast integer-factor path); the
        # strip of fewer than k pixels left over at the right and bottom is covered by the bilinear resize
        small = block_means_gray(gray, k)
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
        if numba_enabled() and gray.dtype == np.uint8:
            _scale_levels(gray, self._gain, self._q)
        else:
            cv2.multiply(gray, self._gain, dst=self._q, dtype=cv2.CV_8U)
        return cv2.cvtColor(self._q, cv2.COLOR_GRAY2BGR) if self.bgr else self._q


def illumination_quotient(frame: np.ndarray, sigma: float = 0.1, *, block: int = 16) -> np.ndarray:
    """The self-quotient image of a grey (or BGR, converted to grey) frame, as a BGR ``uint8`` frame.

    ``sigma`` is the std of the Gaussian illumination estimate as a fraction of the frame's
    larger side; ``block`` the side of the cells the estimate is taken on.  Levels saturate at 255.  Each output
    channel holds the same grey levels, so the result stays a grey frame for
    :func:`~pftrack.cues.intensity.is_gray`.
    """
    return QuotientImage(sigma, block=block)(frame)
