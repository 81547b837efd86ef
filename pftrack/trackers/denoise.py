"""``denoise`` for the colour particle filters: a noisy camera's frames smoothed before the tracker sees them.

A camera at night with its gain turned up keeps its range of levels but adds heavy noise. The noise spreads the
target's colours over neighbouring histogram bins and breaks up the gradients of the structural cue, most on a
small target, and the search then fails to take it back after a loss (docs/robustness.md, "A bright but noisy
camera"). One frame cannot tell noise from fine texture; two can (:func:`pftrack.cues.noise.temporal_noise`).
So the decision waits for the first update: when the noise that differs between the first two frames exceeds
``denoise`` levels, the tracker starts again on the smoothed first frame with the random state it had at ``init``,
as if every frame had been smoothed from the start, and each frame from then on goes through a
``denoise_kernel`` x ``denoise_kernel`` Gaussian. Otherwise nothing changes and nothing is kept.
"""

from __future__ import annotations

import copy

import numpy as np

from ..cues.noise import smooth, temporal_noise
from ..frames import as_bgr_uint8

__all__ = ["NoiseGateMixin"]


class NoiseGateMixin:
    """Mixin for a :class:`~pftrack.trackers.base.Tracker` whose parameters have ``denoise`` (levels; 0: off) and
    ``denoise_kernel``; it must come before every mixin that overrides ``init`` or ``update``."""

    #: (first frame, box, random state at init) until the first update decides
    _noise_first: tuple[np.ndarray, object, dict] | None = None
    #: the smoothing kernel in use (0: none)
    _smooth_kernel: int = 0
    #: the noise read between the first two frames (None before the first update or with denoise off)
    noise_level: float | None = None

    def init(self, frame, box):
        self._smooth_kernel = 0
        self._noise_first = None
        self.noise_level = None
        if float(getattr(self.params, "denoise", 0.0) or 0.0) > 0:
            first = as_bgr_uint8(frame, where="init frame")
            self._noise_first = (first.copy(), box, copy.deepcopy(self.rng.bit_generator.state))
        return super().init(frame, box)

    def update(self, frame):
        pending, self._noise_first = self._noise_first, None
        if pending is not None and self._shape is not None:
            frame = self._check_frame(frame)
            first, box, state = pending
            self.noise_level = temporal_noise(first, frame)
            if self.noise_level > self.params.denoise:
                self.rng.bit_generator.state = state
                super().init(smooth(first, self.params.denoise_kernel), box)
                self._smooth_kernel = int(self.params.denoise_kernel)
        if self._smooth_kernel:
            frame = smooth(self._check_frame(frame), self._smooth_kernel)
        return super().update(frame)

    @property
    def denoised(self) -> bool:
        """Are the frames being smoothed (decided at the first update)?"""
        return bool(self._smooth_kernel)
