"""Re-acquisition by persistence: a changed target that the search keeps finding in one place (``persist_frames``).

The colour trackers declare a loss when the target's scores fall below their histories, and re-acquire a candidate
only when the loss test takes it for the target as last seen. A target whose appearance changed (a head that turns,
a body that rotates, a camera that pans over it) can then stay in view while every acquisition test refuses it: its
structure scores sit a few spreads below a history learned before the change. On grey copies of real sequences this
kept both trackers searching on most frames while the search's best candidate covered the target
(docs/robustness.md, "Stuck searches on grey copies of real sequences").

The rule: while searching, the best candidate of each search is followed. It counts toward a streak when
- its first cue (the colour or grey histogram) calls it the target rather than the background (ratio > 0), and no cue
  scores it more than ``z_max`` spreads below its own history (:func:`plausible`);
- it lies within one half-axis of the previous search's best candidate, or starts the streak within
  :data:`START_RADIUS` half-axes of where the target was lost.

After ``frames`` such searches in a row, the tracker starts afresh on the candidate (new models and histories), unless
the candidate's grey patch is unchanged since the streak began (:func:`.static_lookalikes.unchanged_patch`): a still
piece of the scene near the place of a loss (an occluder's edge) persists too, and a target that changed while it
moved does not stay unchanged. The rule is for a target lost in view: after the target left the view (the search
confined to the strip along the edge it left by, ``reenter_border``), a look-alike walking out there persists as well.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..cues.lk import gray_of
from ..geometry import ellipse_to_box
from .static_lookalikes import unchanged_patch

__all__ = ["PersistenceMixin", "START_RADIUS", "plausible", "streak_step"]

#: a streak starts within this many half-axes of where the target was lost (the target changed in place)
START_RADIUS = 3.0
#: the still test's correlation when the tracker has no background test of its own (``static_ncc`` = 0)
STILL_NCC = 0.8


def plausible(loss, s, z_max: float) -> bool:
    """Does the candidate with loss-test scores ``s`` look like the target at all? Its first cue's ratio favours the
    target over the background, and no cue scores it more than ``z_max`` spreads below that cue's history.

    ``loss`` is a :class:`~pftrack.filtering.loss.FusedLoss` (``members``, one per cue) or a single
    :class:`~pftrack.filtering.loss.LossDetector`."""
    members = getattr(loss, "members", None) or [loss]
    v = np.asarray(s, dtype=np.float64).ravel()
    if v.size == 1 and len(members) > 1:
        v = np.repeat(v, len(members))
    if not math.isfinite(v[0]) or members[0].evaluate(float(v[0])) <= 0.0:
        return False
    return all(not math.isfinite(x) or (x - m.mu_t) / m.sd_t > -z_max for m, x in zip(members, v.tolist()))


def streak_step(streak: tuple[int, float, float] | None, centre, size, lost_at, ok: bool
                ) -> tuple[int, float, float] | None:
    """The streak ``(count, x, y)`` after one more search whose best candidate is at ``centre``.

    ``size`` is the half-axes ``(hx, hy)`` the search looks for, ``lost_at`` where the target was lost (None: no
    streak can start), ``ok`` whether the candidate is :func:`plausible`. The streak goes on when the candidate lies
    within one half-axis of the last one, starts again at 1 within :data:`START_RADIUS` half-axes of ``lost_at``,
    and ends otherwise."""
    if not ok:
        return None
    x, y = float(centre[0]), float(centre[1])
    hx, hy = float(size[0]), float(size[1])
    if streak is not None and abs(x - streak[1]) <= hx and abs(y - streak[2]) <= hy:
        return streak[0] + 1, x, y
    if lost_at is not None and abs(x - lost_at[0]) <= START_RADIUS * hx and abs(y - lost_at[1]) <= START_RADIUS * hy:
        return 1, x, y
    return None


class PersistenceMixin:
    """The stateful side of the rule for :class:`~pftrack.trackers.color_pf.ColorParticleFilter`'s search."""

    _persist: tuple[int, float, float] | None = None
    _persist_gray: np.ndarray | None = None

    def _persist_reset(self) -> None:
        self._persist = None
        self._persist_gray = None

    def _persist_step(self, frame: np.ndarray, ellipse: np.ndarray, s_best):
        """One search without an acquisition, its best candidate ``ellipse`` with scores ``s_best``: the state of a
        fresh start on the candidate when its streak is complete, else None."""
        p = self.params
        if p.persist_frames <= 0 or p.loss_test != "likelihood" or self._exit_strip() is not None:
            return None  # off, or the target left the view: what persists at its edge is someone else
        lost_at = None if self._lost_at is None else self._lost_at[1]
        ok = plausible(self.loss, s_best, p.persist_z)
        streak = streak_step(self._persist, ellipse[:2], self.size, lost_at, ok)
        if streak is not None and streak[0] == 1:
            self._persist_gray = gray_of(np.ascontiguousarray(self._structure_frame(frame)))
        self._persist = streak
        if streak is None or streak[0] < max(p.persist_frames, 2):  # the still test compares two search frames
            return None
        gray0 = self._persist_gray
        self._persist_reset()
        box = tuple(float(v) for v in ellipse_to_box(np.asarray(ellipse, dtype=np.float64)[:4]))
        still = p.static_ncc if p.static_ncc > 0 else STILL_NCC
        if gray0 is not None and unchanged_patch(self._structure_frame(frame), box, gray0, still, self._scene.noise,
                                                 self._scene.quarters):
            return None  # the same patch of the scene as when the streak began: not a target that changed
        state = self._init(frame, box)
        return replace(state, info={**(state.info or {}), "mode": "acquired", "persist": True})
