"""The likelihood and background half of the colour particle filters
(:class:`~pftrack.trackers.color_pf.ColorParticleFilter`): the samples' ellipses, their Bhattacharyya coefficients
with the target model (Nummiaro et al., Eq. 6), Eq. 10's weights in the log domain, and the background statistics
of the appearance condition (Eqs. 13-15) that the loss test takes as its absent half."""

from __future__ import annotations

import math

import numpy as np

from ..cues.color import reachable_roi
from ..cues.intensity import frame_light_gain, light_levels, light_thumbnail
from ..filtering.dynamics import HX, HY, X, Y
from ..geometry import background_grid

__all__ = ["LikelihoodMixin"]


class LikelihoodMixin:
    """Eqs. 6, 10 and 13-15 of the colour particle filters (a mixin of
    :class:`~pftrack.trackers.color_pf.ColorParticleFilter`; see there)."""

    # ------------------------------------------------------------------ likelihood
    def _ellipses(self, states: np.ndarray) -> np.ndarray:
        n = states.shape[0]
        if self._ell.shape[0] != n:
            self._ell = np.empty((n, 4))
        ell = self._ell  # columns X, Y, HX, HY (two slice copies: np.take with out= buffers a copy)
        ell[:, 0:2] = states[:, X:Y + 1]
        ell[:, 2:4] = states[:, HX:HY + 1]
        return ell

    def _rho(self, frame: np.ndarray, ellipses: np.ndarray, roi=None, *, cells: bool = False):
        """Bhattacharyya coefficients and kernel masses of a batch of ellipses, plus the features. ``cells`` (with
        the whole frame as ``roi``): only what the ellipses read is quantised where that is less
        (:meth:`~pftrack.cues.histogram_cue.ColorCue.prepare_cells`; the same coefficients)."""
        h, w = self._shape
        if roi is None:
            roi = reachable_roi(ellipses, w, h)
        pitch = self.cue.step_for(ellipses)
        feats = self.cue.prepare_cells(frame, pitch, ellipses) if cells else None
        if feats is None:
            feats = self.cue.prepare(frame, roi, pitch)
        rho, tot = self._cue_rho(feats, ellipses)
        return rho, tot, feats

    def _cue_rho(self, feats, ellipses: np.ndarray):
        """Bhattacharyya coefficients and kernel masses of a batch on prepared features; with the quotient
        model (``grey_histogram="both"``) the better of the two coefficients."""
        rho, tot = self.cue.rho(feats, ellipses, self._sqrt_q)
        if self._lit is not None and self.mode == "tracking":  # the search scores the grey levels alone
            rho = np.maximum(rho, self._lit.rho(feats.roi, feats.pitch, ellipses))
        return rho, tot

    def _sigma2(self, rho: np.ndarray, tot: np.ndarray) -> float:
        """sigma^2 of Eq. 10: the parameter, or with ``adaptive_sigma`` d_min^2 / 2 over the batch (book ch. 4)."""
        if not self.params.adaptive_sigma:
            return self.params.sigma ** 2
        valid = tot > 0
        dmin = float((1.0 - rho)[valid].min()) if valid.any() else 1.0
        return max(dmin / 2.0, 1e-6)

    def _log_lik(self, rho: np.ndarray, tot: np.ndarray, s2: float | None = None) -> np.ndarray:
        """Eq. 10 in the log domain, ``-(1 - rho) / (2 sigma^2)`` (``s2`` given: that sigma^2)."""
        ll = (rho - 1.0) / (2.0 * (self._sigma2(rho, tot) if s2 is None else s2))  # = -(1 - rho) / (2 s2), exactly
        ll[tot <= 0] = -np.inf  # the ellipse has no pixel in the image: zero likelihood
        return ll

    def _pi(self, rho: float) -> float:
        s = self.params.sigma
        return math.exp(-(1.0 - rho) / (2 * s * s)) / (math.sqrt(2 * math.pi) * s)

    def _threshold(self) -> float:
        return self.bg_mu + self.params.appearance_k * self.bg_sd

    # ------------------------------------------------------------------ background
    def _background_stats(self, frame: np.ndarray, exclude: np.ndarray | None) -> None:
        """mu and sigma of rho over background ellipses (Eqs. 13-14)."""
        h, w = self._shape
        ell = background_grid(w, h, *self.size, self.params.background_positions, exclude)
        if ell.shape[0] < 2:
            return  # nothing left that is background: keep the previous statistics
        # The background histograms are computed exactly like the samples' (a subsampled frame would
        # shift mu and sigma and with them the appearance threshold).
        rho, tot, _ = self._rho(frame, ell, roi=(0, 0, w, h), cells=True)
        if self._raw_check is not None:
            self._raw_check.set_background(self._raw, ell)
        if self._structure_check is not None:
            self._structure_check.set_background(self._structure_frame(frame), ell)
        if np.count_nonzero(tot > 0) >= 2:
            # Eqs. 13-14, with a floor on the spread so a non-discriminative scene cannot collapse it
            self.loss.set_background(self._loss_scores(frame, ell[tot > 0], rho[tot > 0], (0, 0, w, h)))
            self.bg_mu = self.loss.app_mu
            self.bg_sd = self.loss.app_sd
        self._since_bg = 0
        if self.params.relit_search != "off" and frame.ndim == 3 and self.cue.color_space == "rgb":
            self._seen_levels = light_levels(frame, self.params.relit_gain)  # the light while the target is seen
            if self.params.relit_gain == "still":
                self._seen_thumb = light_thumbnail(frame)  # and the view's layout then (relit_gain="still")

    def _frame_gain(self, frame: np.ndarray, ref: np.ndarray):
        """The frame's gain against the light ``ref`` kept above (``frame_light_gain``), read once a frame: the
        search's refined layer and its rival test score more samples on the same frame."""
        c = self._gain_cache
        if c is None or c[0] != self.frame_index or c[1] is not ref:
            c = self._gain_cache = (self.frame_index, ref,
                                    frame_light_gain(ref, self._seen_thumb, frame, self.params.relit_gain))
        return c[2]
