"""``ssim-pf`` and ``hybrid-ssim-pf``: particle filters with a structural-similarity likelihood (book ch. 2).

Book *Object Tracking*, ch. 2 (``shared/seeds/002_*`` lines 754-1953; ``shared/book/ch02.md``):

* **SSIM-PF** (Table 2): state ``(x, y, s)`` (plus an angle with ``rotation``), random walk
  ``x_k = x_{k-1} + v``, ``v ~ N(0, Q)`` (26)-(27); each particle's region, of size
  ``s (w0, h0)``, is resampled to the reference size and compared with the **fixed**
  reference patch by MSSIM (21); ``D = (1 - S)/2`` (25) and ``L ∝ exp(-D^2 / D_min^2)`` (29);
  posterior-mean estimate (9); systematic resampling when ``N_eff <= N_thr`` (Table 1).
* The chapter's comparison cues run in the very same filter (``cue``): colour, edges, or
  colour & edges (product of likelihoods), on the same patches — Table 5's set-up.
* **Hybrid SSIM-PF-DSSIM** (Table 4): every predicted particle is moved by the DSSIM ascent
  (position only); the weight uses the alpha = 0.5 mixture proposal (40)-(42), literally
  (``proposal="literal"``: the optimised particle is used as if drawn from the mixture) or
  as a proper importance sampler (``"mixture_sample"``: draw from the mixture, then weight).
* The loss test of :mod:`pftrack.filtering.loss` on the estimate's MSSIM against the MSSIM
  at background positions gives ``lost`` (not in the chapter).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..cues import patch_histograms as ph
from ..cues import ssim as S
from ..cues import ssim_ascent as A
from ..cues import template as T
from ..errors import ParameterError
from ..filtering.loss import LossDetector, confidence
from ..filtering.particles import ParticleSet
from ..filtering.resampling import systematic
from ..geometry import Box
from ..params import param
from .base import Tracker, TrackState
from .ssim_common import (
    SSIMTemplateParams,
    background_grid,
    reference_shape,
    smoothed_gray,
)

Cue = Literal["ssim", "color", "edges", "color+edges", "ncc", "morph_normed"]


@dataclass(frozen=True, kw_only=True)
class SSIMPFParams(SSIMTemplateParams):
    """Parameters of ``ssim-pf`` (book ch. 2, Table 2; values the text leaves open are ch02.md §2's)."""

    n_particles: int = param(100, ge=1, le=100_000, doc="N (ch. 2: 100 in the speed test, 20 in the hybrid test).")
    cue: Cue = param("ssim", doc=(
        "Likelihood cue on the particles' patches: 'ssim' (MSSIM, eq. 21), or the chapter's comparators "
        "'color' (Nummiaro RGB 8x8x8), 'edges' (gradient-orientation histogram), 'color+edges' (product); "
        "or book ch. 14's template criteria 'ncc' and 'morph_normed' (D = (1 - score)/2: the template tracker's "
        "particle-filter mode); all through eq. (29)."))
    statistics: Literal["local", "global"] = param("global", doc=(
        "SSIM statistics: 'local' is the chapter's MSSIM (11x11 Gaussian windows, Wang 2004); 'global' uses "
        "the whole region's mean, variance and covariance (eqs. 18-20, as in DSSIM): a wider peak, more "
        "tolerant to deformation. Default 'global', selected on the tune split (docs/ssim.md); the chapter's "
        "experiments use 'local'."))
    position_noise: float = param(4.0, gt=0, le=200, doc=(
        "sigma_x = sigma_y of Q (eq. 27), px at a 320-px-wide frame, scaled by width/320 (ch02.md §2, proposed: "
        "the text gives no value). Larger follows faster motion with a flatter posterior."))
    scale_noise: float = param(0.02, ge=0, le=1, doc="sigma_s of Q (eq. 27): relative scale change per frame.")
    rotation: bool = param(False, doc="Add the in-plane angle to the state (the chapter's rotation extension).")
    angle_noise: float = param(2.0, ge=0, le=90, doc="sigma of the angle's random walk (degrees) with rotation.")
    resample_threshold: float = param(0.5, gt=0, le=1, doc="N_thr / N: resample when N_eff <= N_thr (Table 1).")
    d_floor: float = param(1e-3, gt=0, le=1, doc="Floor on D_min of eq. (29), so a perfect match gives no NaN.")
    search_fraction: float = param(0.2, ge=0, le=1, doc=(
        "While lost, the filter keeps running and this share of its particles is re-drawn uniformly over the "
        "frame each frame to re-acquire the target."))


@dataclass(frozen=True, kw_only=True)
class HybridSSIMPFParams(SSIMPFParams):
    """Parameters of ``hybrid-ssim-pf`` (Table 4)."""

    n_particles: int = param(20, ge=1, le=100_000, doc="N (ch. 2's hybrid experiment: 20).")
    alpha: float = param(0.5, ge=0, le=1, doc="alpha of the mixture proposal (41): weight of the DSSIM component.")
    max_iter: int = param(10, ge=0, le=100, doc="DSSIM iterations per particle (ch02.md: 10 in the hybrid).")
    proposal: Literal["literal", "mixture_sample"] = param("literal", doc=(
        "'literal': the DSSIM-optimised particle weighted by eqs. (40)-(42) as printed; 'mixture_sample': with "
        "probability alpha draw from N(x_opt, Q), else keep the prediction, then weight (a proper importance "
        "sampler; ch02.md P9)."))

    def validate(self) -> None:
        if self.rotation:
            raise ParameterError("hybrid-ssim-pf moves position only (DSSIM has no angle): rotation is not available")


class SSIMPF(Tracker):
    """SSIM particle filter (Table 2) with the chapter's comparison cues and a loss test."""

    name = "ssim-pf"
    Params = SSIMPFParams

    def __init__(self, params: SSIMPFParams | None = None, *, rng=None, seed=None):
        super().__init__(params, rng=rng, seed=seed)
        p = self.params
        self.dim = 4 if p.rotation else 3
        self.state_names = ("x", "y", "s", "angle")[: self.dim]
        self.loss = LossDetector(lost_frames=p.lost_frames, reacquire_margin=p.reacquire_margin,
                                 sd_floor_target=p.score_sd_floor, sd_floor_background=p.score_sd_floor)

    # ------------------------------------------------------------------ observation
    def _scaled(self, states: np.ndarray) -> np.ndarray:
        """States in patch-sampling form: scale relative to the reference patch's pixels."""
        st = np.array(states[:, : self.dim], dtype=np.float64)
        st[:, 2] *= self.pix_scale
        if self.dim == 4:
            st[:, 3] = np.deg2rad(st[:, 3])
        return st

    def _distances(self, frame: np.ndarray, gray: np.ndarray, states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per-state dissimilarity D for the likelihood (29), and the MSSIM (for the loss test)."""
        cue = self.params.cue
        sc = self._scaled(states)
        if cue == "ssim":
            stack = S.sample_stack(gray, sc, self.tshape) if self.dim == 3 else \
                np.ascontiguousarray(S.sample_patches(gray, sc, self.tshape).transpose(1, 2, 0))
            s = S.ssim_stack(stack, self.template) if self.params.statistics == "local" else \
                S.ssim_global_stack(stack, self.template)
            return S.dissimilarity(s), s
        g = S.sample_patches(gray, sc, self.tshape)
        if cue in ("ncc", "morph_normed"):
            score = T.batch_scores(g, self.template, cue)
            return (1.0 - score) / 2.0, None
        d2 = np.zeros(len(states))
        if "color" in cue:
            c = S.sample_patches(frame, sc, self.tshape)
            d2 += ph.bhattacharyya_distance(ph.color_histograms(c), self.ref_color) ** 2
        if "edges" in cue:
            d2 += ph.bhattacharyya_distance(ph.edge_histograms(g), self.ref_edges) ** 2
        return np.sqrt(d2), None

    def _log_lik(self, d: np.ndarray) -> np.ndarray:
        return S.log_likelihood_dmin(d, floor=self.params.d_floor)

    # ------------------------------------------------------------------ init
    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        p = self.params
        x, y, w, h = box
        # pix_scale: frame pixels per reference pixel at s = 1
        self.tshape, self.pix_scale = reference_shape(w, h, p.template_pixels)
        self.size0 = (float(w), float(h))
        gray = self._gray(frame)
        centre = np.array([x + w / 2.0, y + h / 2.0, 1.0, 0.0][: self.dim])
        self.template = S.sample_patches(gray, self._scaled(centre[None, :]), self.tshape)[0]
        if "color" in p.cue:
            self.ref_color = ph.color_histograms(S.sample_patches(frame, self._scaled(centre[None, :]), self.tshape))[0]
        if "edges" in p.cue:
            self.ref_edges = ph.edge_histograms(self.template[None])[0]
        n = p.n_particles
        self.ps = ParticleSet(np.tile(centre, (n, 1)))
        self.estimate = centre.copy()
        self._since_bg = 0
        self._last_box = tuple(float(v) for v in box)
        self.loss.reset(1.0, sd=p.history_prior_sd)
        self._background(frame, gray)
        return self._state(box, 1.0, False, {"mode": "init", "ssim": 1.0})

    def _background(self, frame, gray) -> None:
        """Scores at background positions (a grid away from the target): the loss test's absent hypothesis."""
        fh, fw = self._shape
        size = (self.size0[0] * self.estimate[2], self.size0[1] * self.estimate[2])
        pos = background_grid(fw, fh, self.estimate[:2], size, self.params.background_positions)
        st = np.zeros((len(pos), self.dim))
        st[:, :2], st[:, 2] = pos, self.estimate[2]
        if len(st) >= 2:
            d, _ = self._distances(frame, gray, st)
            self.loss.set_background(1.0 - 2.0 * d)  # scores on S's scale: S = 1 - 2 D
        self._since_bg = 0

    # ------------------------------------------------------------------ update
    def _noise(self) -> np.ndarray:
        p = self.params
        sxy = p.position_noise * self._shape[1] / 320.0
        sd = [sxy, sxy, p.scale_noise]
        if self.dim == 4:
            sd.append(p.angle_noise)
        return np.array(sd)

    def _propagate(self, states: np.ndarray) -> None:
        p = self.params
        states += self.rng.normal(0.0, 1.0, states.shape) * self._noise()
        fh, fw = self._shape
        np.clip(states[:, 0], 0.0, fw, out=states[:, 0])
        np.clip(states[:, 1], 0.0, fh, out=states[:, 1])
        np.clip(states[:, 2], p.min_scale, p.max_scale, out=states[:, 2])

    def _weights(self, frame, gray, states) -> tuple[np.ndarray, np.ndarray]:
        """Log-likelihoods of the (propagated) states; hook for the hybrid's proposal."""
        d, _ = self._distances(frame, gray, states)
        return self._log_lik(d), states

    def _update(self, frame: np.ndarray) -> TrackState:
        p = self.params
        gray = self._gray(frame)
        ps = self.ps
        self._prev = ps.states.copy()  # x_{k-1}, for the hybrid's proposal density
        self._propagate(ps.states)
        lost_before = self.loss.lost
        if lost_before and p.search_fraction > 0:
            # while lost the filter keeps running, and a share of its particles searches the whole frame
            m = max(1, int(round(p.search_fraction * ps.n)))
            idx = self.rng.choice(ps.n, m, replace=False)
            fh, fw = self._shape
            ps.states[idx, 0] = self.rng.uniform(0, fw, m)
            ps.states[idx, 1] = self.rng.uniform(0, fh, m)
            self._prev[idx] = ps.states[idx]
        loglik, moved = self._weights(frame, gray, ps.states)
        ps.states[:] = moved
        ok = ps.set_log_likelihood(loglik, accumulate=not lost_before)
        est = ps._mean.copy()
        if lost_before:  # the candidate is the best particle, not a mean over scattered searchers
            est = ps.states[int(np.argmax(ps.w))].copy()
        self.estimate = est
        d_e, s_e = self._distances(frame, gray, est[None, :])
        score_s = float(1.0 - 2.0 * d_e[0]) if ok else float("nan")
        if lost_before:
            lost = not self.loss.acquire(score_s)
            conf = confidence(self.loss.llr)
        else:
            lost, conf = self.loss.step(score_s)
        info = {"mode": "lost" if lost else "tracking", "ssim": float(s_e[0]) if s_e is not None else float("nan"),
                "llr": self.loss.llr, "ess": ps._ess}
        if not lost and self.loss.confident(score_s):
            if p.template_update > 0:
                patch = S.sample_patches(gray, self._scaled(est[None, :]), self.tshape)[0]
                self.template = (1.0 - p.template_update) * self.template + p.template_update * patch
            self._since_bg += 1
            if self._since_bg >= p.background_interval:
                self._background(frame, gray)
        if lost_before or ps._ess <= p.resample_threshold * ps.n:
            ps.resample(systematic(ps.w, self.rng))
        box = self._box(est)
        if lost:
            return self._state(self._last_box, min(conf, 0.5), True, info)
        self._last_box = box
        return self._state(box, conf, False, info)

    # ------------------------------------------------------------------ output
    def _gray(self, frame: np.ndarray) -> np.ndarray:
        return smoothed_gray(frame, self.params.smooth)

    def _box(self, st: np.ndarray) -> tuple[float, float, float, float]:
        w, h = self.size0[0] * st[2], self.size0[1] * st[2]
        return (float(st[0] - w / 2.0), float(st[1] - h / 2.0), float(w), float(h))

    def _state(self, box, score, lost, info, particles=None, weights=None) -> TrackState:
        if particles is None:
            particles, weights = self.ps.states, self.ps.w
        return TrackState(box=tuple(float(v) for v in box), score=float(score), lost=bool(lost),
                          particles=particles.copy(), weights=np.array(weights, dtype=np.float64),
                          state_names=self.state_names, info=info)


class HybridSSIMPF(SSIMPF):
    """Hybrid SSIM-PF-DSSIM (Table 4): DSSIM moves every predicted particle; mixture-proposal weights."""

    name = "hybrid-ssim-pf"
    Params = HybridSSIMPFParams

    def _weights(self, frame, gray, states):
        p = self.params
        # DSSIM on the sampled reference grid: positions in frame pixels, scale in reference pixels
        if p.max_iter > 0:
            gx, gy = A.image_gradients(gray)
            opt = A.dssim_ascent_batch(gray, gx, gy, self.template.astype(np.float64), self._scaled(states),
                                       max_iter=p.max_iter)
        else:
            opt = np.column_stack([states[:, :2], np.zeros((len(states), 2))])
        x_opt = opt[:, :2]
        prior_mean = self._prev[:, :2]  # the random walk's mean: x_{k-1}
        sd = self._noise()[:2]
        new = states.copy()
        if p.proposal == "literal":
            new[:, :2] = x_opt
        elif p.alpha > 0:
            take = self.rng.random(len(states)) < p.alpha
            new[take, :2] = x_opt[take] + self.rng.normal(0.0, 1.0, (int(take.sum()), 2)) * sd
        d, _ = self._distances(frame, gray, new)
        loglik = self._log_lik(d)

        def log_n(x, mu):
            z = (x - mu) / sd
            return -0.5 * np.sum(z * z, axis=1) - np.sum(np.log(sd)) - math.log(2 * math.pi)

        lp = log_n(new[:, :2], prior_mean)  # p(x~ | x_{k-1})
        if p.alpha <= 0:  # the proposal is the prior: the correction p/q is exactly 1
            self.dssim_iterations = float(opt[:, 3].mean())
            return loglik, new
        if p.alpha >= 1:
            lq = log_n(new[:, :2], x_opt)
        else:
            lq = np.logaddexp(math.log(p.alpha) + log_n(new[:, :2], x_opt), math.log(1 - p.alpha) + lp)
        self.dssim_iterations = float(opt[:, 3].mean())
        return loglik + lp - lq, new
