"""The vetoes of a search candidate, and the next candidate when one is vetoed (colour trackers' search).

While the target is lost the search tests its best candidate for acquisition (:mod:`.color_search`). A
candidate that would end the loss can still be refused, as another object of the target's appearance:

- ``reenter_outward``: after the target left the view, a candidate of the exit strip moving out through that
  edge (:meth:`VetoMixin._leaving`);
- ``reenter_resident``: after the target left the view, a candidate that was inside the view all the while the
  target was out (:meth:`VetoMixin._resident`);
- ``reenter_min_llr``: while the search is confined to the exit strip, a candidate whose ratio is below it
  (:meth:`VetoMixin._weak_reentry`);
- the raw-colour check and the grey structure check (:mod:`.raw_check`, :mod:`.structure_check`): their own
  evidence calls the candidate background;
- the distractor memory (:mod:`.distractors`): a look-alike met beyond the target's reach early in the loss;
- ``acquire_unique``: another candidate elsewhere passes the acquisition test too (:meth:`VetoMixin._rival`). Two
  look-alikes qualify, so neither is taken on that frame, and the next best is not tried (it would be the rival);
  with ``acquire_unique_hold`` = k, nor on the k frames after it. A candidate already refused on the frame, or a
  look-alike the distractor memory follows, has left the ranking and is not a rival. Two options (off): a rival
  sample that fails is scored again on a fixed grid around it (``acquire_unique_refine``), and a rival counts only
  within a margin of the candidate's ratio (``acquire_unique_margin``).

A refused best candidate used to end the frame's search, and the samples that ranked below it were never
tested. Traced on the grey tune scene ``exit-019`` (``color-pf`` and ``fusion-pf``, seed 0): a look-alike
walking out through the left edge ranks first on every frame of the target's return through that edge, is
refused as leaving each time, and the target, ranked below it, is not taken within the 15 frames. (Passed over,
the target there is still below the acquisition bar while half outside the view: the retries change few
re-acquisitions, docs/robustness.md.)

With ``search_retries`` = k the samples near a refused candidate (within two half-axes each way) leave the
ranking, and the next best candidate that is not the scene (:meth:`~.static_lookalikes.SceneTestMixin.
_skip_scene`) is tested in the same way, up to k more a frame. The acquisition itself is unchanged: the
chosen candidate must end the loss by the same test, with the same supporters, as the first would have.
Nothing changes on a frame whose best candidate is not refused.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from ..cues.template import patch_shift, trace_back
from ..filtering.dynamics import HX, HY, X, Y
from ..geometry import clip_box, ellipse_to_box, in_frame_fraction, iou

__all__ = ["RESIDENT_CORE", "RESIDENT_IN_FRAME", "Acquisition", "VetoMixin", "near_mask", "search_rank"]

#: ``reenter_resident``: the share of a candidate's box inside the view on every frame of its trace that makes it
#: an object that stayed in view
RESIDENT_IN_FRAME = 0.9
#: ``reenter_resident``: the share of the candidate's half-axes that is traced (its central part)
RESIDENT_CORE = 0.5
#: ``acquire_unique_refine``: the offsets, in half-axes, at which a rival's neighbourhood is scored again, coarse
#: then fine around the best coarse one (the search's samples are about a half-axis apart, and its likelihood peak
#: is narrower than the target)
RIVAL_GRID = np.array([(dx, dy) for dx in (-1.0, -0.5, 0.0, 0.5, 1.0) for dy in (-1.0, -0.5, 0.0, 0.5, 1.0)])
RIVAL_STEPS = (1.0, 0.25)


class SearchCandidates(NamedTuple):
    """The samples of one search (states, ellipses, colour scores, pixel totals, log-likelihoods, the scored
    region) and its best candidate: index, log prior, the samples near it, its loss-test scores."""

    states: np.ndarray
    ell: np.ndarray
    rho: np.ndarray
    tot: np.ndarray
    loglik: np.ndarray
    roi: tuple
    best: int
    lp: float
    near: np.ndarray
    s_best: np.ndarray
    n_keep: int
    rank: np.ndarray | None = None     # the samples' ranking (refused and scene candidates at -inf)
    scores: Callable | None = None     # scores(i): sample i's loss-test scores and log prior


class Acquisition(NamedTuple):
    """The candidate a search frame settled on: its index, loss-test scores and log prior, the samples near it,
    the supporters (``cluster``) it would start tracking from, whether it ends the loss, whether a veto
    refused a candidate on this frame, and why (``vetoes``: for each candidate refused in turn, ``"unique"`` for a
    rival or a hold of ``acquire_unique``, else the reason :meth:`VetoMixin._vetoed_by` gave)."""

    best: int
    s_best: np.ndarray
    lp: float
    near: np.ndarray
    cluster: np.ndarray
    found: bool
    vetoes: tuple[str, ...] = ()

    @property
    def vetoed(self) -> bool:
        """Did a veto refuse a candidate on this frame?"""
        return bool(self.vetoes)


def near_mask(states: np.ndarray, centre_xy, size: tuple[float, float]) -> np.ndarray:
    """The samples within two half-axes (each way) of ``centre_xy``: those belonging to one candidate. ``states``:
    states or ellipses, the centre in their first two columns."""
    hx, hy = size
    return (np.abs(states[:, X] - centre_xy[0]) < 2 * hx) & (np.abs(states[:, Y] - centre_xy[1]) < 2 * hy)


def search_rank(loglik: np.ndarray, prior: np.ndarray | None, tot: np.ndarray) -> np.ndarray:
    """The search samples' ranking: log-likelihood plus the position log prior (when there is one), ``-inf`` for a
    sample with no pixel in the frame (kernel mass ``tot`` 0)."""
    return np.where(tot > 0, loglik if prior is None else loglik + prior, -np.inf)


class VetoMixin:
    """:meth:`_vetoed_by` and :meth:`_choose` for :class:`~.color_pf.ColorParticleFilter`'s search."""

    def _leaving(self, frame: np.ndarray, ell: np.ndarray) -> bool:
        """``reenter_outward``: is a candidate of the exit strip (ellipse ``ell``) moving out through the edge the
        target left by, faster than ``reenter_outward`` times the speed the target left with (at least 1 px per
        frame)?  Its motion is its patch's shift since the previous frame (normalised correlation within three
        exit speeds, at least 8 px).  When that is unknown (a flat patch, no match, a sliver at the edge), a
        candidate where an object vetoed on the previous frame has moved to is that object; otherwise unknown
        motion vetoes nothing. Several candidates of one frame may be asked. With ``reenter_along``, a candidate
        moving along that edge faster than that many exit speeds, and over twice as fast as across it, is passing
        by and vetoed too (its patch then searched within its half-width as well)."""
        k = self.params.reenter_outward
        prev = self._search_grays[-1] if self._search_grays else None
        strip = self._exit_strip() if k > 0 and prev is not None else None
        if strip is None or self.frame_index - prev[0] != 1:
            return False
        speed = self._exit_speed()
        along_k = self.params.reenter_along
        radius = max(8, math.ceil(3.0 * speed), math.ceil(float(ell[2])) if along_k > 0 else 0)
        d = patch_shift(prev[1], self._frame_gray(frame), ellipse_to_box(ell), radius)
        # the objects refused on the previous frame (and those of this one, kept for the next)
        self._vetoed = [v for v in self._vetoed if v[0] >= self.frame_index - 1]
        if d is None:
            return any(v[0] == self.frame_index - 1 and np.all(np.abs(ell[:2] - v[1] - v[2]) <= np.asarray(self.size))
                       for v in self._vetoed)
        outward = (-d[0], d[0], -d[1], d[1])[strip[0]]
        along = abs(d[1]) if strip[0] < 2 else abs(d[0])  # reenter_along: passing by along the edge
        if outward > k * speed or (along_k > 0 and along > along_k * speed and along > 2.0 * abs(outward)):
            self._vetoed.append((self.frame_index, np.array(ell[:2], dtype=np.float64), d))
            return True
        return False

    def _exit_speed(self) -> float:
        """The speed the target left with, in px per frame, at least 1 (the patch searches' scale)."""
        return max(math.hypot(*self._exit_velocity), 1.0)

    def _keep_search_gray(self, frame: np.ndarray) -> None:
        """Keep this frame's grey image while the search is confined to an exit strip (the last
        ``reenter_resident`` frames, at least one, consecutive); forget them otherwise."""
        p = self.params
        grays = self._search_grays
        if (self.mode == "searching" and (p.reenter_outward > 0 or p.reenter_resident > 0)
                and self._exit_strip() is not None):
            if grays and grays[-1][0] != self.frame_index - 1:
                grays.clear()
            grays.append((self.frame_index, self._frame_gray(frame)))
        else:
            grays.clear()

    def _resident(self, frame: np.ndarray, ell: np.ndarray) -> bool:
        """``reenter_resident``: was a candidate (ellipse ``ell``) inside the view all the while the target was
        out?  Its box is traced back frame by frame through the grey frames kept since the search began in the
        exit strip (at most ``reenter_resident`` of them): the box's central part (:data:`RESIDENT_CORE` of its
        half-axes, mostly the object rather than the still scene around it) found again in the frame before by
        normalised correlation, within three exit speeds (at least 8 px, and ``reenter_resident_reach`` half-widths
        of the candidate), and the box moved with it. A target coming back entered through an edge since it left,
        so its trace reaches the border; a candidate whose box stays at least :data:`RESIDENT_IN_FRAME` inside the
        view on every frame back to the oldest kept is another object. A trace that is lost (a flat patch, no
        match) refuses nothing."""
        grays = self._search_grays
        strip = self._exit_strip() if self.params.reenter_resident > 0 and grays else None
        if strip is None or grays[-1][0] != self.frame_index - 1:
            return False
        fh, fw = self._shape
        box = ellipse_to_box(ell)
        if in_frame_fraction(tuple(box), fw, fh) < RESIDENT_IN_FRAME:
            return False
        core = ellipse_to_box(np.array([*ell[:2], *(RESIDENT_CORE * np.asarray(ell[2:4]))]))
        radius = max(8, math.ceil(3.0 * self._exit_speed()), math.ceil(self.params.reenter_resident_reach * ell[2]))
        for b in trace_back((g for _, g in reversed(grays)), self._frame_gray(frame), box, core, radius):
            if b is None or in_frame_fraction(tuple(b), fw, fh) < RESIDENT_IN_FRAME:
                return False
        return True

    def _weak_reentry(self, llr: float) -> bool:
        """``reenter_min_llr``: is a candidate of the exit strip, with acquisition ratio ``llr``, too weak?"""
        k = self.params.reenter_min_llr
        return k > 0 and llr < k and self._exit_strip() is not None

    def _vetoed_by(self, frame: np.ndarray, ell: np.ndarray, llr: float = math.inf) -> str | None:
        """The veto that refuses candidate ``ell`` (``(4,)``, acquisition ratio ``llr``), or ``None``."""
        if self._weak_reentry(llr):
            return "weak"
        if self._leaving(frame, ell):
            return "leaving"
        if self._resident(frame, ell):
            return "resident"
        if self._raw_check is not None and self._raw_check.vetoes(self._raw, ell):
            return "raw"
        check = self._structure_check
        if check is not None and check.vetoes(self._structure_frame(frame), ell):
            return "structure"
        if self._distractors.vetoes(ell[:2], self.frame_index, self._lost_at, self.size, self._search_since,
                                    self._confident_track, falling=self._loss_falling):
            return "distractor"
        return None

    def _rival_sample(self, frame: np.ndarray, c, best: int) -> tuple[int, tuple] | None:
        """The best-ranked sample of search ``c`` beyond two half-axes (each way) of sample ``best``, the still scene
        skipped, and its ``c.scores`` (loss-test scores, log prior); ``None`` when there is none."""
        if c.rank is None:
            return None
        rank = np.where(near_mask(c.states, c.states[best, X:Y + 1], self.size), -np.inf, c.rank)
        if not np.isfinite(rank).any():
            return None
        j, s = self._skip_scene(frame, c.ell, rank, int(np.argmax(rank)), c.scores)
        return (j, s) if np.isfinite(rank[j]) else None

    def _rival(self, frame: np.ndarray, c, best: int, llr: float | None = None) -> bool:
        """``acquire_unique``: does a candidate of search ``c`` elsewhere than sample ``best`` (:meth:`_rival_sample`)
        pass the acquisition test too? With ``acquire_unique_margin`` and the candidate's ratio ``llr``, only a rival
        whose ratio comes that close counts."""
        found = self._rival_sample(frame, c, best)
        if found is None:
            return False
        j, s = found
        if self._close(*s, llr):
            return True
        return bool(self.params.acquire_unique_refine and self._rival_refined(frame, c, j, llr))

    def _close(self, s, lp: float, llr: float | None) -> bool:
        """Does a rival with loss-test scores ``s`` and log prior ``lp`` pass the acquisition test, within
        ``acquire_unique_margin`` of the candidate's ratio ``llr`` (when both are set)?"""
        ok, r = self.loss.would_acquire(s, lp)
        m = self.params.acquire_unique_margin
        return bool(ok and (m <= 0 or llr is None or r >= llr - m))

    def _rival_refined(self, frame: np.ndarray, c, j: int, llr: float | None = None) -> bool:
        """``acquire_unique_refine``: does a position of :data:`RIVAL_GRID` around sample ``j`` of search ``c`` pass
        the acquisition test, at the coarse spacing or then at the fine one around the best coarse position? The
        candidate's own peak was refined by the search's second layer; a look-alike that only a sample off its
        centre reached is given the same chance, on a fixed grid (no random draw). The search's result buffers
        are restored afterwards (the cue reuses them)."""
        centre = c.states[j]
        kept = (c.rho.copy(), c.tot.copy())
        try:
            for step in RIVAL_STEPS:
                st = np.repeat(centre[None, :], len(RIVAL_GRID), axis=0)
                st[:, X] += step * RIVAL_GRID[:, 0] * st[:, HX]
                st[:, Y] += step * RIVAL_GRID[:, 1] * st[:, HY]
                self._clip_states(st)
                ell = np.ascontiguousarray(st[:, [X, Y, HX, HY]])
                rho, tot, feats = self._search_rho(frame, ell)
                rho, tot = rho.copy(), tot.copy()
                loglik = self._search_log_lik(frame, st, self._log_lik(rho, tot), feats)
                prior = self._position_log_prior(st)
                rank = search_rank(loglik, prior, tot)
                if not np.isfinite(rank).any():
                    return False
                k = int(np.argmax(rank))
                s = self._loss_scores(frame, ell[k:k + 1], rho[k:k + 1], feats.roi)[0]
                if self._close(s, 0.0 if prior is None else float(prior[k]), llr):
                    return True
                centre = st[k]
            return False
        finally:
            c.rho[:], c.tot[:] = kept

    def _in_frame_enough(self, ell: np.ndarray, g: float) -> bool:
        """Does at least ``g`` (``acquire_in_frame``) of the box of candidate ellipse ``ell`` lie inside the frame, or,
        in the first ``acquire_early_frames`` frames of a search after an exit, ``acquire_in_frame_early``? With
        ``acquire_sliver_frames``, a candidate with less inside passes when the search has found it at one place
        on that many search frames in a row (:meth:`_persistent_sliver`)."""
        p = self.params
        box = ellipse_to_box(ell)
        share = in_frame_fraction(tuple(box), self._shape[1], self._shape[0])
        if share >= g:
            return True
        if (share >= p.acquire_in_frame_early and p.acquire_early_frames > 0
                and self.frame_index - self._search_since <= p.acquire_early_frames
                and self._exit_strip() is not None):
            return True
        return p.acquire_sliver_frames > 0 and self._persistent_sliver(box)

    def _persistent_sliver(self, box: np.ndarray) -> bool:
        """``acquire_sliver_frames`` = K: has the best candidate passed the loss test with too little of its box in
        the frame on K search frames in a row (at most 2 frames apart), each overlapping the last (IoU >= 0.3 of
        the boxes cut to the frame)? Counted once a frame, for the frame's first such candidate."""
        last = self._sliver
        if last is not None and last[0] == self.frame_index:
            return False
        cut = clip_box(box, self._shape[1], self._shape[0])
        streak = 1
        if (last is not None and 0 < self.frame_index - last[0] <= 2 and last[0] >= self._search_since
                and float(iou(cut, last[2])) >= 0.3):
            streak = last[1] + 1
        self._sliver = (self.frame_index, streak, cut)
        return streak >= self.params.acquire_sliver_frames

    def _choose(self, frame: np.ndarray, c, supporters: np.ndarray) -> Acquisition:
        """The candidate of search ``c`` (:class:`~.color_search.SearchCandidates`) to acquire, if any.

        ``supporters``: the samples whose appearance passes (and that have pixels). A candidate is tested by
        the loss test (:meth:`loss.would_acquire`) when enough supporters lie near it, then by the vetoes; a
        refused candidate gives way to the next best, ``search_retries`` times; one with less than
        ``acquire_in_frame`` of its box inside the frame (:meth:`_in_frame_enough`) ends the choice for this frame.
        The loss test is then run once (:meth:`loss.acquire`) on the candidate chosen, or on the first when none
        would end the loss, so the loss's state moves exactly one frame."""
        p = self.params
        need = min(p.acquire_samples, p.kickoff_fraction * p.n_particles + 1)
        best, s_best, lp, near = c.best, c.s_best, c.lp, c.near
        first = (best, s_best, lp, near)
        rank = c.rank
        retries = int(p.search_retries)
        reasons: list[str] = []
        g = p.acquire_in_frame
        for attempt in range(retries + 1):
            cluster = near & supporters
            if cluster.sum() < need:
                break
            ok, llr = self.loss.would_acquire(s_best, lp)
            if not ok:
                break
            if g > 0 and not (p.acquire_sliver_llr > 0 and llr >= p.acquire_sliver_llr) \
                    and not self._in_frame_enough(c.ell[best], g):
                break
            if p.acquire_unique and (self.frame_index <= self._ambiguous_until or self._rival(frame, c, best, llr)):
                # two look-alikes (on this frame, or within acquire_unique_hold frames): no candidate is taken (the
                # next would be the rival)
                if self.frame_index > self._ambiguous_until:
                    self._ambiguous_until = self.frame_index + int(p.acquire_unique_hold)
                reasons.append("unique")
                break
            reason = self._vetoed_by(frame, c.ell[best], llr)
            if reason is None:
                self.loss.acquire(s_best, lp)
                return Acquisition(best, s_best, lp, near, cluster, True, tuple(reasons))
            reasons.append(reason)
            if attempt == retries or rank is None:
                break
            rank[near] = -np.inf  # the refused candidate's samples leave the ranking
            if not np.isfinite(rank).any():
                break
            best, (s_best, lp) = self._skip_scene(frame, c.ell, rank, int(np.argmax(rank)), c.scores)
            near = near_mask(c.states, c.states[best, X:Y + 1], self.size)
        # nothing acquired: the loss test counts the frame on the first candidate, as it always has
        best, s_best, lp, near = first
        cluster = near & supporters
        if cluster.sum() >= need:
            if self.loss.acquire(s_best, lp):
                self.loss.lost = True  # acquire() ended the loss; a veto refused the candidate
        else:
            self.loss.unseen_frame()  # no candidate to test: the frame still counts unseen
        return Acquisition(best, s_best, lp, near, cluster, False, tuple(reasons))
