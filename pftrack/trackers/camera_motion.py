"""Samples moved with the camera (``camera_motion``): a mixin of the colour particle filters.

Each tracked frame the camera's translation since the previous frame is read from the two frames' integral
projections (:mod:`pftrack.cues.camera_shift`) and added to every sample's position before the dynamics (Eq. 9 of
Nummiaro et al.) spread them. A hand-held camera or a low frame rate moves the whole view by more than the dynamics'
noise; a static camera gives no shift, and nothing is spread wider, so a target leaving the view is not replaced by
a look-alike further off (``docs/robustness.md``, "The same targets at a lower frame rate").
"""

from __future__ import annotations

import numpy as np

from ..cues.camera_shift import camera_shift, frame_profiles, lattice_step
from ..filtering.dynamics import X, Y


class CameraMotionMixin:
    """Keeps the previous frame's projections and the shift of the current frame (``params.camera_motion``)."""

    _camera_prev: tuple[np.ndarray, np.ndarray] | None = None
    _camera_move: tuple[float, float] = (0.0, 0.0)

    _camera_rows: np.ndarray | None = None  # the samples moved on the last frame (camera_adapt)
    _camera_level: float = 1.0  # the share of the samples moved (camera_adapt: learnt)

    def _camera_start(self, frame: np.ndarray) -> None:
        """Take the first frame's projections (on ``init``)."""
        self._camera_move = (0.0, 0.0)
        self._camera_prev = frame_profiles(frame, self._camera_step(frame)) if self.params.camera_motion else None
        self._camera_rows = None
        self._camera_level = float(self.params.camera_share)

    def _camera_step(self, frame: np.ndarray) -> int:
        """The lattice step of the projections (``camera_samples``)."""
        h, w = frame.shape[:2]
        return lattice_step(h, w, self.params.camera_samples)

    def _camera_frame(self, frame: np.ndarray) -> None:
        """Read this frame's shift from the last frame's projections (every frame, so that the shift is always
        that of one frame); it is applied only when the samples are propagated."""
        if not self.params.camera_motion:
            return
        if self._camera_rows is not None:
            self._camera_learn()
        step = self._camera_step(frame)
        cur = frame_profiles(frame, step)
        move = (0.0, 0.0)
        if self._camera_prev is not None:
            h, w = frame.shape[:2]
            f = self.params.camera_max_shift
            move = camera_shift(self._camera_prev, cur, max_shift=(f * w, f * h), step=step)
        self._camera_prev, self._camera_move = cur, move

    def _camera_apply(self, states: np.ndarray) -> None:
        """Move the samples' centres by this frame's shift (in place); with ``camera_share`` < 1 only that share of
        them, spread evenly over the set (no random draw: a still camera leaves the generator's stream as it was)."""
        dx, dy = self._camera_move
        if not (dx or dy):
            return
        share = self._camera_level if self.params.camera_adapt > 0 else self.params.camera_share
        rows = slice(None) if share >= 1.0 else camera_rows(len(states), share)
        if self.params.camera_adapt > 0 and share < 1.0:
            self._camera_rows = rows
        if dx:
            states[rows, X] += dx
        if dy:
            states[rows, Y] += dy

    def _camera_learn(self) -> None:
        """``camera_adapt``: move the share of moved samples toward the weight the last frame's moved samples took
        (the likelihood's verdict on "the target moved with the view" against "it stayed in the image")."""
        rows, self._camera_rows = self._camera_rows, None
        ps = getattr(self, "ps", None)
        if ps is None or self.mode != "tracking" or rows.size == 0 or rows[-1] >= len(ps.w):
            return
        p = self.params
        mass = float(ps.w[rows].sum())
        level = (1.0 - p.camera_adapt) * self._camera_level + p.camera_adapt * mass
        self._camera_level = min(max(level, p.camera_share_min), p.camera_share)


def camera_rows(n: int, share: float) -> np.ndarray:
    """The indices of ``share`` of ``n`` samples spread evenly: ``k`` is taken when ``floor((k + 1) share)``
    exceeds ``floor(k share)`` (every other one at 0.5)."""
    k = np.arange(n)
    return np.flatnonzero(np.floor((k + 1) * share) > np.floor(k * share))
