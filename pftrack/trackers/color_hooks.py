"""The extension points of the colour particle filters (:class:`~pftrack.trackers.color_pf.ColorParticleFilter`),
with their defaults: the dynamics a subclass supplies, and the further cues, models and tests it may add."""

from __future__ import annotations

import numpy as np

from ..cues.illumination import QuotientImage
from ..cues.structure_hog import BestStructure
from ..cues.structure_light import LitStructure
from ..filtering.dynamics import HX, HY, X, Y
from ..filtering.particles import ParticleSet
from ..filtering.seir import seir
from .raw_check import illumination_stages

__all__ = ["ColorHooks", "fused_supporters"]

#: with fused cues, the search samples supporting a candidate are those within this log-likelihood of the best
SUPPORT_LOG_MARGIN = 3.0


def fused_supporters(log_lik: np.ndarray) -> np.ndarray:
    """The search samples that look like the target when several cues are fused: those whose likelihood is within a
    factor e^3 of the best one's (the colour threshold alone would veto a target that only the structure sees)."""
    return log_lik >= np.max(log_lik) - SUPPORT_LOG_MARGIN


class ColorHooks:
    """Default hooks of :class:`~pftrack.trackers.color_pf.ColorParticleFilter` (a mixin; see there)."""

    def _propagate(self, states: np.ndarray) -> tuple[float, float, float, float]:
        """Move the samples with the dynamic model (in place); return the region their ellipses cover."""
        raise NotImplementedError

    def _step_std(self, est: np.ndarray) -> np.ndarray:
        """``(D,)`` one-step std of the dynamic model's noise on the centre and half-axes (``X, Y, HX, HY``;
        other entries 0) around the state ``est``: the scale of SEIR's mutation."""
        raise NotImplementedError

    def _initial_state(self, ellipse) -> np.ndarray:
        """A state at rest on an ellipse ``(cx, cy, hx, hy)``."""
        state = np.zeros(self.dim)
        state[[X, Y, HX, HY]] = ellipse
        return state

    def _clip_states(self, states: np.ndarray) -> None:
        """Bound the sizes of samples placed by the search (in place)."""
        np.clip(states[:, HX:HY + 1], self.params.min_half_axis, None, out=states[:, HX:HY + 1])

    def _shared_quotient(self):
        """A cached self-quotient image ``frame -> image`` for the second grey histogram: that of the structural
        check of ``grey_check="fused"`` when it sees the same frames at the same scale (``illumination_sigma``);
        otherwise its own, started from the tracker's one grey conversion of each frame (``_frame_gray``, which the
        equalisation table then shares); none under ``illumination="quotient"``."""
        if self._quotient is not None:
            return None
        cue = self._check_lit()
        if cue is not None and cue.sigma == self.params.illumination_sigma:
            return cue._qf
        q = QuotientImage(self.params.illumination_sigma, bgr=False)
        self._own_quotient = True
        return lambda frame: q(frame, gray=self._frame_gray(frame))

    def _extra_log_lik(self, frame: np.ndarray, states: np.ndarray, log_lik: np.ndarray,
                       roi: tuple[int, int, int, int], feats) -> np.ndarray:
        """Further log-likelihood terms multiplied into the colour likelihood (default: the structural cue of
        ``grey_check="fused"`` on grey input, else none).

        ``feats`` is the quantised region ``roi`` (shared with the colour cue)."""
        check = self._fused_check
        if check is not None:
            return log_lik + check.log_lik(self._structure_frame(frame), roi, self._ellipses(states))
        return log_lik

    def _seir(self, frame: np.ndarray, ps: ParticleSet, log_lik: np.ndarray, rho: np.ndarray, tot: np.ndarray,
              roi: tuple[int, int, int, int], feats):
        """Book ch. 3's SEIR loop on the weighted particles (``resampler='seir'``).

        New particles are scored with the same cues on the same prepared region; the likelihood's
        sigma is the one this frame's weighting used (with ``adaptive_sigma`` it is frozen at the
        batch's d_min, so that the new particles do not change the scale)."""
        p = self.params
        est = ps._mean
        std = p.seir_mutation * self._step_std(est)
        s2 = self._sigma2(rho, tot)

        def score(states: np.ndarray) -> np.ndarray:
            self._clip_states(states)
            r, t = self._cue_rho(feats, self._ellipses(states))
            return self._extra_log_lik(frame, states, self._log_lik(r, t, s2), roi, feats)

        states, ll, info = seir(ps.states, log_lik, score, self.rng, mutation_std=std)
        ps.states[:] = states
        ps.set_log_likelihood(ll)
        return info

    def _loss_scores(self, frame: np.ndarray, ellipses: np.ndarray, rho: np.ndarray,
                     roi: tuple[int, int, int, int]):
        """The scores the loss test sees for a batch of ellipses (default: the colour ``rho``).

        A subclass with further cues returns ``(M, C)`` scores in [0, 1] for a
        :class:`~pftrack.filtering.loss.FusedLoss`, as ``grey_check="fused"`` does on grey input."""
        check = self._fused_check
        if check is not None:
            return check.loss_scores(self._structure_frame(frame), roi, ellipses, rho)
        return rho

    def _appearance_pass(self, rho: np.ndarray, threshold: float, log_lik: np.ndarray) -> np.ndarray:
        """Which search samples look like the target: the appearance condition ``rho > mu + 2 sigma`` (Eq. 15).

        With the fused cues of ``grey_check="fused"``, as in ``fusion-pf``: :func:`fused_supporters`."""
        if self._fused_check is not None:
            return fused_supporters(log_lik)
        return rho > threshold

    def _search_log_lik(self, frame: np.ndarray, states: np.ndarray, log_lik: np.ndarray, feats) -> np.ndarray:
        """Further log-likelihood terms for the search's samples (default: the structural cue of
        ``grey_check="fused"`` on grey input with ``grey_search_structure``, as every tracked particle has it; else
        none)."""
        check = self._fused_check
        if check is not None and self.params.grey_search_structure:
            return log_lik + check.log_lik(self._structure_frame(frame), feats.roi, self._ellipses(states))
        return log_lik

    def _update_models(self, frame: np.ndarray, estimate: np.ndarray, feats, rho_e: float) -> None:
        """Called when the colour model update gate passes (hook for further adaptive models)."""

    def _after_estimate(self, frame: np.ndarray, estimate: np.ndarray) -> None:
        """Called with the new mean state after each tracked frame (default: the size search of
        ``grey_scale_search`` with the structural cue of ``grey_check="fused"`` on grey input)."""
        check = self._fused_check
        step = self.params.grey_scale_search
        if step > 0 and check is not None:
            self._scale_size(estimate, check.scale_factor(self._structure_frame(frame), estimate[[X, Y, HX, HY]], step))

    def _scale_size(self, estimate: np.ndarray, k: float) -> None:
        """Multiply the half-axes of the estimate and of every particle by ``k`` (in place; a size search's step)."""
        if k != 1.0:
            estimate[HX] *= k
            estimate[HY] *= k
            self.ps.scale_columns(HX, HY + 1, k)

    def _on_frame(self, frame: np.ndarray) -> None:
        """Called at the end of every update (tracking or searching)."""

    # ------------------------------------------------------------------ grey input
    @property
    def _fused_check(self):
        """The structural check of ``grey_check="fused"`` when it is on (grey input), else None."""
        check = self._structure_check
        return check if check is not None and check.fused else None

    def _transform_input(self, frame: np.ndarray, *, first: bool) -> np.ndarray:
        """Grey input with ``illumination="quotient"``: the self-quotient image (decided on the first frame)."""
        if first:
            self._quotient, self._raw_check = illumination_stages(self.params, frame)
        if self._quotient is None:
            return frame
        self._raw = frame
        if self._raw_check is not None:
            self._raw_check.new_frame()
        return self._quotient(frame)

    def _check_lit(self) -> LitStructure | None:
        """The grey-patch cue (levels and quotient image) of the fused structural check, alone or as the first of
        ``grey_check_features="both"``; None without one."""
        check = self._fused_check
        cue = check.cue if check is not None else None
        if isinstance(cue, BestStructure):
            cue = cue.primary
        return cue if isinstance(cue, LitStructure) else None

    def _grey_shared(self) -> bool:
        """Grey input whose self-quotient image starts from the tracker's grey conversion of each frame
        (``_frame_gray``): the equalisation table then starts from it too."""
        lit = self._check_lit()
        return self.cue.color_space == "gray" and (self._own_quotient or (lit is not None and lit.shares_gray))

    def _wants_grey_check(self) -> bool:
        """Does this input get the structural check at re-acquisition (``grey_check`` on grey input)?"""
        p = self.params
        return p.grey_check != "off" and p.loss_test == "likelihood" and self.cue.color_space == "gray"

    def _drop_structure_check(self) -> None:
        """No structural check (yet): the histogram's own loss test again if ``grey_check="fused"`` replaced it."""
        self._structure_check = None
        if self._plain_loss is not None:
            self.loss, self._plain_loss = self._plain_loss, None

    def _structure_frame(self, frame: np.ndarray) -> np.ndarray:
        """The frame the structural check sees: the untransformed one under the self-quotient illumination."""
        return self._raw if self._quotient is not None and self._raw is not None else frame
