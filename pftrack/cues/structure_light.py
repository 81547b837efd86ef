"""The structural cue on grey input under light that varies across the target.

:class:`~pftrack.cues.structure.StructureCue` correlates grey patches by zero-mean NCC, which
is blind to a gain and an offset *over the patch*.  A lamp or a shadow edge that lights one
side of a large target more than the other is neither: the patch's layout of grey levels
changes, the NCC falls, and on a grey frame the histogram cue has no colour left to hold the
target either (docs/robustness.md, the grey face proxy).

:class:`LitStructure` keeps two structural cues with the same interface as ``StructureCue``:

* one on the **self-quotient image** of the frame (:class:`~pftrack.cues.illumination.QuotientImage`,
  ``Q = I / (G_sigma * I)``), in which a light that is smooth at the scale ``sigma`` cancels;
* one on the **grey levels** as they are, which keep what the quotient divides out with the
  light: the target's own shading at scales above ``sigma``, and its contrast against a bright
  spot of about that size (a small walker passing a lamp).

A box's score is the better of its two correlations, each with its own references (anchor and
running mean, each updated by its own gate).  The histogram cue and the search are not
changed: they see the grey levels (unlike ``illumination="quotient"``, which transforms the
frame for every cue).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from .illumination import QuotientImage
from .structure import StructureCue

__all__ = ["LitStructure"]


class LitStructure:
    """Two :class:`StructureCue` s, on the self-quotient image and on the grey levels; a box scores the larger
    NCC (``mode="both"``), or the quotient's alone (``mode="quotient"``).

    The quotient image is computed once per frame, on first use after :meth:`new_frame`.
    """

    def __init__(self, template_pixels: int = 256, *, weighting: str = "kernel", sigma: float = 0.1,
                 mode: str = "both", gray_of: Callable[[np.ndarray], np.ndarray] | None = None):
        if mode not in ("both", "quotient"):
            raise ValueError(f"mode must be 'both' or 'quotient', got {mode!r}")
        self.quotient = StructureCue(template_pixels, weighting=weighting)
        self.levels = StructureCue(template_pixels, weighting=weighting) if mode == "both" else None
        # one grey channel: the structural cue reads the same numbers as from three equal ones, a third of the bytes
        self._q = QuotientImage(sigma, bgr=False)
        self._gray_of = gray_of  # the tracker's grey image of a frame, converted once per frame (None: convert here)
        self._frame: np.ndarray | None = None  # the frame whose quotient image is cached
        self._qframe: np.ndarray | None = None

    @property
    def ready(self) -> bool:
        return self.quotient.ready

    @property
    def shape(self) -> tuple[int, int]:
        return self.quotient.shape

    @property
    def shares_gray(self) -> bool:
        """Does the quotient image start from the caller's grey image of each frame (``gray_of``)?"""
        return self._gray_of is not None

    @property
    def sigma(self) -> float:
        """The scale of the self-quotient image (a fraction of the frame's larger side)."""
        return self._q.sigma

    def _qf(self, frame: np.ndarray) -> np.ndarray:
        if self._frame is not frame:
            gray = self._gray_of(frame) if self._gray_of is not None else None
            self._frame, self._qframe = frame, self._q(frame, gray=gray)
        return self._qframe

    def new_frame(self) -> None:
        self._frame = self._qframe = None
        self.quotient.new_frame()
        if self.levels is not None:
            self.levels.new_frame()

    def init(self, frame: np.ndarray, ellipse) -> None:
        self.new_frame()
        self.quotient.init(self._qf(frame), ellipse)
        if self.levels is not None:
            self.levels.init(frame, ellipse)

    def scores(self, frame: np.ndarray, roi, ellipses: np.ndarray) -> np.ndarray:
        s = self.quotient.scores(self._qf(frame), roi, ellipses)
        if self.levels is not None:
            s = np.maximum(s, self.levels.scores(frame, roi, ellipses))
        return s

    def size_scores(self, frame: np.ndarray, ellipse, ratios, *, anchor_only: bool = False) -> list[float]:
        """:meth:`StructureCue.size_scores`, the larger of the two cues' at each size (as :meth:`scores`)."""
        s = self.quotient.size_scores(self._qf(frame), ellipse, ratios, anchor_only=anchor_only)
        if self.levels is not None:
            s = [max(a, b) for a, b in zip(s, self.levels.size_scores(frame, ellipse, ratios, anchor_only=anchor_only))]
        return s

    def update(self, frame: np.ndarray, ellipse, rate: float, anchor_gate: float = -1.0) -> bool:
        changed = self.quotient.update(self._qf(frame), ellipse, rate, anchor_gate)
        if self.levels is not None:
            changed = self.levels.update(frame, ellipse, rate, anchor_gate) or changed
        return changed

    def proposals(self, frame: np.ndarray, half_axes: tuple[float, float], k: int) -> tuple[np.ndarray, np.ndarray]:
        """The quotient cue's proposals (:meth:`StructureCue.proposals`)."""
        return self.quotient.proposals(self._qf(frame), half_axes, k)
