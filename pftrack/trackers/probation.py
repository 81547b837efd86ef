"""Probation after a weak re-acquisition (pftrack's addition to the colour particle filters' search, §6).

A lost tracker re-acquires when its best search candidate passes the loss test's acquisition condition
(:meth:`pftrack.filtering.loss.LossDetector.acquire`).  On the tune split's reappearance scenes most of the
events that were never re-acquired had one cause: *during* the absence the search took a look-alike, with a
log-likelihood ratio just above the margin, and the tracker then followed it confidently.  Its models and
score histories learned the look-alike within a few frames, so when the target came back, nothing was
looking for it any more (docs/robustness.md, "`fusion-pf` doubts a weak re-acquisition").

Probation is the classical answer of detect-and-verify trackers: an acquisition is a hypothesis until the
evidence confirms it.  An acquisition whose fused ratio is below ``probation_llr`` starts a probation of at
most ``probation_frames`` frames, during which

* the tracker follows the candidate and reports it (the flag is down), but learns nothing from it: neither
  the appearance models nor the score histories move, so the candidate's ratio keeps measuring it against the
  target as last seen;
* the search goes on beside the tracking, on every ``probation_interval``-th frame (its samples kept from one
  search to the next, the loss's position prior, the candidate's neighbourhood left out), and a candidate
  elsewhere that passes the acquisition test with a ratio ``probation_margin`` above the followed one's
  posterior odds takes over (its own probation starting if it is weak too);
* probation ends, and learning resumes, on the first frame whose ratio reaches ``probation_llr``, or after
  ``probation_frames`` frames; a loss ends it too (at the next search), and the search resumes as before;
* with ``probation_lost_llr`` > 0, a frame on probation whose ratio is below it reports the target absent
  (``lost``, score at most 0.5) while the candidate is followed: a look-alike acquired after a real exit keeps
  the flag up until the evidence confirms it (:meth:`ProbationMixin._doubtful`).

A tracked frame on probation says so in ``state.info["probation"]``.  On by default for ``fusion-pf`` only
(``FusionPFParams``): on ``color-pf`` it made no measurable difference.
"""

from __future__ import annotations

import numpy as np

from ..filtering.dynamics import HX, HY, X, Y
from ..filtering.loss import confidence
from ..geometry import ellipse_to_box
from .base import TrackState

_ELL_COLS = np.array([X, Y, HX, HY])


class ProbationMixin:
    """Probation after a weak acquisition, for :class:`pftrack.trackers.color_pf.ColorParticleFilter`."""

    _probation_left: int = 0
    _probation_exit: bool = False  # the probation's acquisition followed an exit through the frame's edge

    @property
    def on_probation(self) -> bool:
        """Is the tracker following a weakly acquired candidate without learning from it?"""
        return self._probation_left > 0

    def _begin_probation(self, lost_at, *, exited: bool | None = None) -> None:
        """Called on an acquisition: probation when its ratio is below ``probation_llr``.  ``lost_at``: where and
        how the target was last seen clearly (the search's position prior and prediction), kept for the search
        beside the track."""
        p = self.params
        if exited is not None:  # a switch during probation keeps the first acquisition's
            self._probation_exit = exited
        weak = p.probation_llr > 0 and p.probation_frames > 0 and p.loss_test == "likelihood"
        self._probation_left = int(p.probation_frames) if weak and self.loss.llr < p.probation_llr else 0
        self.loss.frozen = self._probation_left > 0
        if self._probation_left:
            self._lost_at = lost_at

    def _doubtful(self) -> bool:
        """Is this frame on probation with a ratio below ``probation_lost_llr`` (reported absent)?"""
        p = self.params
        t = p.probation_lost_llr
        return (t > 0 and self._probation_left > 0 and self.loss.llr < t
                and (self._probation_exit or not p.probation_lost_exit_only))

    def _as_reported(self, score: float) -> tuple[float, bool]:
        """``(score, lost)`` of a followed candidate: a doubtful frame (:meth:`_doubtful`) is reported absent, its
        score at most 0.5."""
        doubt = self._doubtful()
        return (min(score, 0.5) if doubt else score), doubt

    def _end_probation(self) -> None:
        self._probation_left = 0
        self.loss.frozen = False

    def _probation_step(self, frame: np.ndarray, e_ell: np.ndarray) -> TrackState | None:
        """After a tracked frame on probation that did not end in a loss (a loss ends it in ``_search``): end it,
        or search beside the track and switch to a clearly better candidate (returns its state), or go on (None)."""
        p = self.params
        if self.loss.llr >= p.probation_llr:
            self._end_probation()
            return None
        self._probation_left -= 1
        if self._probation_left <= 0:
            self._end_probation()
            return None
        if (p.probation_frames - self._probation_left) % p.probation_interval:
            return None  # the search beside the track runs on every probation_interval-th frame
        # the followed candidate's posterior odds: its ratio and the search's prior at its position
        prior = self._position_log_prior(self.estimate.reshape(1, -1))
        tracked = float(self.loss.llr) + (0.0 if prior is None else float(prior[0]))
        c = self._search_candidates(frame, exclude=e_ell[0])
        if not np.isfinite(c.loglik[c.best]):
            return None
        ok, llr = self.loss.would_acquire(c.s_best, c.lp)
        cluster = c.near & (c.tot > 0)
        if not ok or llr < tracked + p.probation_margin or not cluster.any():
            return None
        # the candidate takes over: tracking restarts on it, with the acquisition's ratio
        lost_at, search_states, search_loglik = self._lost_at, self._search_states, self._search_loglik
        self._start_tracking(c.states[cluster], c.loglik[cluster])
        self._search_states, self._search_loglik = search_states, search_loglik  # the search beside goes on
        self.loss.llr = llr
        self._begin_probation(lost_at)
        est = self.estimate
        box = tuple(float(v) for v in ellipse_to_box(est[_ELL_COLS]))
        self.last_box = box
        self.size = self._confident_size = (float(est[HX]), float(est[HY]))
        score, lost = self._as_reported(confidence(llr))
        return self._state(box=box, score=score, lost=lost,
                           info={"mode": "acquired", "probation": self.on_probation, "switched": True})
