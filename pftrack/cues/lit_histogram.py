"""A second grey histogram model, on the self-quotient image, beside a tracker's model of the grey levels.

On grey input the colour trackers describe the target by a histogram of equalised intensity x gradient
orientation (:class:`~pftrack.cues.histogram_cue.ColorCue`).  Global equalisation undoes a gain that is the
same over the whole frame, not a lamp or a shadow edge that lights the target differently from the rest.
The self-quotient image (:mod:`pftrack.cues.illumination`) divides such a light out, but it also divides out
the scene's own shading, and used alone it cost the colour trackers their re-acquisitions among grey clutter
(docs/robustness.md).

:class:`LitHistogram` keeps both: the tracker's model of the grey levels, and this one of the quotient
image, each learned on the same confident frames.  A particle scores the better of its two Bhattacharyya
coefficients, the rule :class:`~pftrack.cues.structure_light.LitStructure` applies to the structural cue of
``fusion-pf``.  A target whose grey levels a lamp changed still matches on the quotient; a target on a flat
background keeps the contrast of its own grey level.

The quotient image is computed once per frame, when first asked for, and the quantised features once per
region (the tracker's region of the particles, or the search's).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from .color import blend_model, model_rho, normalized_model
from .histogram_cue import ColorCue, ColorFeatures
from .illumination import QuotientImage

__all__ = ["LitHistogram"]


class LitHistogram:
    """The grey histogram model of the self-quotient image (see the module docstring)."""

    def __init__(self, *, sigma: float, gray_bins, kernel: str, max_pixels: int, gradient_threshold: float,
                 quotient: Callable[[np.ndarray], np.ndarray] | None = None, parts: int = 1):
        self.cue = ColorCue("gray", None, kernel, max_pixels, gray_bins=tuple(gray_bins),
                            gradient_threshold=gradient_threshold, parts=parts)
        # ``quotient``: another cue's cached self-quotient image of the same frames and scale (fusion-pf's
        # LitStructure), so that it is computed once per frame for both
        self.quotient = quotient if quotient is not None else QuotientImage(sigma, bgr=False)
        self.q: np.ndarray | None = None
        self.sqrt_q: np.ndarray | None = None
        self._frame: np.ndarray | None = None
        self._image: np.ndarray | None = None  # this frame's quotient image, once computed
        self._feats: tuple[tuple, ColorFeatures] | None = None  # ((roi, pitch), features) of the last region
        self._p_e: np.ndarray | None = None  # the estimate's histogram (normalised), for learn()

    def new_frame(self, frame: np.ndarray) -> None:
        """A new frame (its quotient image is computed when first needed)."""
        self._frame = frame
        self._image = None
        self._feats = None
        self._p_e = None

    def image(self) -> np.ndarray:
        """This frame's self-quotient image (2-D ``uint8``); the cue's equalisation table is taken from it."""
        if self._image is None:
            self._image = self.quotient(self._frame)
            self.cue.new_frame(self._image)
        return self._image

    def init(self, frame: np.ndarray, ellipse) -> None:
        """Take the model from one ellipse of the first frame."""
        self.new_frame(frame)
        self.q, self.sqrt_q = normalized_model(self.cue.histogram(self.image(), ellipse))

    def _features(self, roi: tuple[int, int, int, int], pitch: int) -> ColorFeatures:
        key = (tuple(int(v) for v in roi), int(pitch))
        if self._feats is None or self._feats[0] != key:
            self._feats = (key, self.cue.prepare(self.image(), key[0], key[1]))
        return self._feats[1]

    def rho(self, roi: tuple[int, int, int, int], pitch: int, ellipses: np.ndarray) -> np.ndarray:
        """Bhattacharyya coefficients of a batch of ellipses with the quotient model, on the region ``roi``
        quantised at ``pitch`` (the lattice of the tracker's own features; a new array)."""
        r, _ = self.cue.rho(self._features(roi, pitch), ellipses, self.sqrt_q, reuse=False)
        return r

    def estimate_rho(self, roi: tuple[int, int, int, int], pitch: int, ellipse: np.ndarray) -> float:
        """The estimate's coefficient; its histogram is kept for :meth:`learn`."""
        hist, tot = self.cue.histograms(self._features(roi, pitch), np.asarray(ellipse).reshape(1, 4), reuse=False)
        if tot[0] <= 0:
            self._p_e = None
            return 0.0
        self._p_e = hist[0]  # normalised by the kernel histogram (its sum is 1)
        return model_rho(self._p_e, self.sqrt_q)

    def learn(self, alpha: float) -> None:
        """Blend the estimate's histogram of this frame into the model (Eqs. 11-12's update)."""
        if self._p_e is not None and alpha > 0:
            self.q, self.sqrt_q = blend_model(self.q, self._p_e, alpha)
