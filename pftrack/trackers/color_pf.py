"""``color-pf``: the adaptive colour-based particle filter of Nummiaro, Koller-Meier & Van Gool.

K. Nummiaro, E. Koller-Meier, L. Van Gool, "An adaptive color-based particle
filter", Image and Vision Computing 21 (2003) — ``shared/seeds/004_*.txt``.

One iteration (Fig. 2):

1. **select** ``N`` samples from ``S_{t-1}`` with probability ``pi_{t-1}``
   (cumulative sums + binary search, or another resampler);
2. **propagate** each with the first-order model ``s_t = A s_{t-1} + w`` (Eq. 9);
3. **observe**: the kernel-weighted colour histogram of each sample's ellipse
   (Eq. 3) and its Bhattacharyya coefficient with the target model (Eq. 6);
4. **weight**: ``pi ∝ exp(-(1 - rho) / (2 sigma^2))`` (Eq. 10), kept in the log domain;
5. **estimate** the mean state ``E[S] = sum pi s`` (Eq. 1);
6. **update** the target model ``q <- (1 - alpha) q + alpha p_E[S]`` when
   ``pi_E[S] > pi_T`` (Eqs. 11–12).

Initialisation (§6) is manual (a box), automatic from a known histogram
(:meth:`ColorPF.init_auto`; samples over the frame or at entry regions, tracking
starts when more than ``b N`` samples satisfy the appearance condition
``rho > mu + 2 sigma`` of Eqs. 13–15), or by a detector callable
(:meth:`ColorPF.init_detect`).  The same appearance condition marks the target
lost when too few samples pass for ``lost_frames`` frames; the tracker then
returns to initialisation mode, reports ``lost=True`` and re-acquires the target
when it reappears.

Options from the book *Object Tracking*, ch. 4 (``shared/seeds/book-notes.md``):
``adaptive_sigma`` (``sigma^2 = d_min^2 / 2``), ``update_gate="lambda"``
(``lambda <- (1 - alpha_u) lambda + alpha_u pi_est``, update when ``pi_est > lambda``)
and ``search_method="variance"`` (uniform initialisation, tracking declared when
the particle-position variance falls below a threshold).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Literal, Sequence

import numpy as np

from ..cues.color import ColorCue, reachable_roi, warmup
from ..errors import ParameterError
from ..filtering.dynamics import HX, HY, VX, VY, X, Y, ConstantVelocityScale
from ..filtering.particles import ParticleSet
from ..filtering.resampling import get_resampler
from ..frames import as_bgr_uint8
from ..geometry import Box, box_to_ellipse, ellipse_to_box, validate_box
from ..params import Params, param
from .base import Tracker, TrackState

Detector = Callable[[np.ndarray], Sequence]
_ELL_COLS = np.array([X, Y, HX, HY])


@dataclass(frozen=True, kw_only=True)
class ColorModelParams(Params):
    """Colour model, weighting, model update and appearance-condition parameters shared by the colour PFs."""

    n_particles: int = param(100, ge=1, le=1_000_000, doc=(
        "N, the number of samples (§4, Fig. 2; the paper uses 100). More samples: a smoother, more "
        "accurate estimate at linear cost."))
    color_space: Literal["rgb", "hsv"] = param("rgb", doc=(
        "Colour space of h(x) (§3): 'rgb' (8x8x8 bins) or 'hsv' (8x8x4 bins, less sensitive to V)."))
    bins: tuple[int, ...] = param((), ge=1, le=256, doc=(
        "Bins per channel; empty for the paper's 8,8,8 (RGB) or 8,8,4 (HSV). Fewer bins: more tolerant "
        "to noise and lighting, less discriminative."))
    kernel: Literal["nummiaro", "epanechnikov"] = param("nummiaro", doc=(
        "Pixel weighting inside the ellipse: 'nummiaro' is k(||y-x||/a) = 1 - r^2 with "
        "a = sqrt(Hx^2 + Hy^2) (Eqs. 2-3); 'epanechnikov' normalises r by the ellipse itself."))
    max_pixels: int = param(1500, ge=0, le=10_000_000, doc=(
        "Speed bound for large targets: an ellipse with more pixels than this is sampled on a regular "
        "lattice (pitch ceil(sqrt(area / max_pixels)), anchored to the image grid) instead of at every "
        "pixel. 1500 leaves targets up to ~44x44 px exact; measured on the dev set, 0 (every pixel, Eq. 3 "
        "literally), 4000 and 1500 give the same accuracy (docs/color-pf.md)."))
    sigma: float = param(0.1, gt=0, le=10, doc=(
        "sigma of the weighting pi ∝ exp(-(1 - rho)/(2 sigma^2)) (Eq. 10). Smaller: sharper weights, "
        "faster collapse onto the best sample; larger: flatter posterior."))
    adaptive_sigma: bool = param(False, doc=(
        "Book ch. 4 variant: set sigma^2 = d_min^2 / 2 each frame from the smallest Bhattacharyya "
        "distance among the samples, so the likelihood adapts to how well the best sample matches."))
    min_half_axis: float = param(2.0, ge=0.5, le=1000, doc="Smallest half-axis a sample may have (pixels).")
    resampler: Literal["multinomial", "systematic", "stratified", "residual"] = param("multinomial", doc=(
        "Selection step (Fig. 2, step 1): 'multinomial' is the paper's cumulative sums + binary search."))
    resample_ess: float = param(1.0, gt=0, le=1, doc=(
        "Resample when N_eff < resample_ess * N. 1 resamples every frame, as in Fig. 2."))
    alpha: float = param(0.05, ge=0, le=1, doc=(
        "alpha of the model update q <- (1 - alpha) q + alpha p_E[S] (Eq. 12); 0 disables adaptation. "
        "The paper leaves it open; larger adapts faster but drifts more easily."))
    update_gate: Literal["threshold", "lambda", "never"] = param("threshold", doc=(
        "When to update the model: 'threshold' is Eq. 11 (pi_E[S] > pi_T); 'lambda' is the book's "
        "ch. 4 running gate lambda = (1 - alpha_u) lambda + alpha_u pi_est; 'never' keeps the first model."))
    update_rho: float = param(0.8, ge=0, le=1, doc=(
        "pi_T of Eq. 11, stated as the Bhattacharyya coefficient rho_T it corresponds to: since pi (Eq. 10) "
        "increases with rho, pi_E > pi_T <=> rho_E > rho_T. Stated on rho so it does not move with sigma."))
    lambda_rate: float = param(0.1, gt=0, le=1, doc="alpha_u of the 'lambda' update gate (book ch. 4).")
    kickoff_fraction: float = param(0.1, gt=0, le=1, doc=(
        "b, the kick-off fraction (§6): tracking starts when more than b*N samples satisfy the "
        "appearance condition, and the target is lost when fewer do for lost_frames frames."))
    appearance_k: float = param(2.0, ge=0, le=10, doc=(
        "The appearance condition rho > mu + k sigma_bg (Eq. 15; k = 2 gives ~95 % confidence that a "
        "sample is not background)."))
    lost_frames: int = param(3, ge=1, le=1000, doc=(
        "'A couple of frames' (§6): consecutive frames with too few passing samples before the target "
        "is declared lost."))
    background_positions: int = param(100, ge=4, le=100_000, doc=(
        "At most this many ellipses on a grid over the background give mu and sigma_bg (Eqs. 13-14)."))
    background_interval: int = param(10, ge=0, le=100_000, doc=(
        "Recompute the background statistics every this many frames while tracking (0: only at "
        "initialisation), so they follow the adapting model and a moving camera."))
    search: bool = param(True, doc=(
        "Detect loss with the appearance condition and search for the target (initialisation mode). "
        "False: always track, never report lost."))
    search_particles: int = param(0, ge=0, le=1_000_000, doc=(
        "Samples used while searching; 0 chooses enough to place about one sample per target-sized "
        "cell of the frame (between N and 10 N)."))
    search_keep: float = param(0.5, ge=0, lt=1, doc=(
        "Fraction of search samples drawn from the previous search posterior; the rest are spread "
        "uniformly (stratified) over the frame or the entry regions."))
    search_method: Literal["appearance", "variance"] = param("appearance", doc=(
        "Acquisition test: 'appearance' (Eq. 15 with the kick-off fraction b), or the book's ch. 4 "
        "'variance' test (particle-position variance below variance_threshold)."))
    variance_threshold: float = param(10.0, gt=0, doc=(
        "Book ch. 4: tracking is declared when the weighted variance of the particle positions (px^2, "
        "mean of x and y) falls below this value."))
    detector_interval: int = param(1, ge=1, le=100_000, doc=(
        "While searching with a detector, run it every this many frames."))

    def validate(self) -> None:
        if self.bins and len(self.bins) != 3:
            raise ParameterError(f"parameter 'bins' must have 3 values (one per channel), got {self.bins}")


@dataclass(frozen=True, kw_only=True)
class ColorPFParams(ColorModelParams):
    """Parameters of ``color-pf``; defaults follow Nummiaro et al. where the paper gives them."""

    position_noise: float = param(0.2, ge=0, le=10, doc=(
        "Std of the Gaussian noise w on x and y (Eq. 9), as a fraction of the mean half-axis "
        "(scale-invariant). The paper leaves it open."))
    velocity_noise: float = param(0.1, ge=0, le=10, doc=(
        "Std of the noise on the velocity (vx, vy) per frame, as a fraction of the mean half-axis."))
    size_noise: float = param(0.0, ge=0, le=1, doc=(
        "Std of independent noise on the half-axes Hx, Hy, as a fraction of each half-axis. 0 (default) "
        "changes the size only through adot, which keeps the aspect ratio."))
    scale_rate_noise: float = param(0.005, ge=0, le=1, doc=(
        "Std of the noise on the scale-change rate adot (1/frame): about 0.5 % size change per frame."))
    scale_damping: float = param(0.0, ge=0, le=1, doc=(
        "Factor kappa on the scale-change rate (adot_t = kappa adot_{t-1} + w). 1 is the paper's literal "
        "constant scale change; colour histograms observe scale weakly, so a persistent rate drifts the "
        "size away (measured on the dev set: docs/color-pf.md). The default 0 makes the size a random "
        "walk, as in Perez et al. and Kristan et al."))
    max_scale_rate: float = param(0.05, ge=0, le=1, doc=(
        "Bound on |adot|: at most this relative size change per frame from the deterministic part."))
    min_noise_px: float = param(1.0, ge=0, le=100, doc=(
        "Floor (pixels) for the position noise, so that tiny targets still explore."))


class ColorParticleFilter(Tracker):
    """A colour-histogram particle filter with the machinery of Nummiaro et al.

    Subclasses choose the state layout and dynamics (:meth:`_propagate`) and may
    multiply further likelihoods in (:meth:`_extra_log_lik`) and react to the new
    estimate (:meth:`_after_estimate`).  The columns ``x, y`` (0, 1), ``vx, vy``
    (2, 3) and ``hx, hy`` (4, 5) are common to every layout.
    """

    Params = ColorModelParams
    state_names: tuple[str, ...] = ConstantVelocityScale.state_names

    def __init__(self, params: ColorModelParams | None = None, *, rng=None, seed=None,
                 detector: Detector | None = None):
        super().__init__(params, rng=rng, seed=seed)
        p = self.params
        self.dim = len(self.state_names)
        self.cue = ColorCue(p.color_space, tuple(p.bins) or None, p.kernel, p.max_pixels)
        self.resampler = get_resampler(p.resampler)
        if detector is not None and not callable(detector):
            raise ParameterError("detector must be a callable frame -> boxes")
        self.detector = detector
        warmup()
        self._reset()

    # ------------------------------------------------------------------ state
    def _reset(self) -> None:
        self.q: np.ndarray | None = None
        self._sqrt_q: np.ndarray | None = None
        self.ps: ParticleSet | None = None
        self.estimate = np.zeros(self.dim)
        self.mode = "tracking"
        self.miss = 0
        self.bg_mu = 0.0
        self.bg_sd = 0.0
        self._since_bg = 0
        self.last_box: Box | None = None
        self.last_score = 0.0
        self.lam: float | None = None
        self.size = (0.0, 0.0)  # half-axes used while searching
        self.regions: np.ndarray | None = None
        self._search_states: np.ndarray | None = None
        self._search_loglik: np.ndarray | None = None
        self._ell = np.empty((0, 4))

    def _set_model(self, q: np.ndarray) -> None:
        q = np.asarray(q, dtype=np.float64)
        s = q.sum()
        self.q = q / s if s > 0 else np.full_like(q, 1.0 / q.size)
        self._sqrt_q = np.sqrt(self.q)

    # ------------------------------------------------------------------ likelihood
    def _ellipses(self, states: np.ndarray) -> np.ndarray:
        n = states.shape[0]
        if self._ell.shape[0] != n:
            self._ell = np.empty((n, 4))
        np.take(states, _ELL_COLS, axis=1, out=self._ell)
        return self._ell

    def _rho(self, frame: np.ndarray, ellipses: np.ndarray, roi=None):
        """Bhattacharyya coefficients and kernel masses of a batch of ellipses, plus the features."""
        h, w = self._shape
        if roi is None:
            roi = reachable_roi(ellipses, w, h)
        feats = self.cue.prepare(frame, roi, self.cue.step_for(ellipses))
        rho, tot = self.cue.rho(feats, ellipses, self._sqrt_q)
        return rho, tot, feats

    def _log_lik(self, rho: np.ndarray, tot: np.ndarray) -> np.ndarray:
        d2 = 1.0 - rho
        if self.params.adaptive_sigma:
            valid = tot > 0
            dmin = float(d2[valid].min()) if valid.any() else 1.0
            s2 = max(dmin / 2.0, 1e-6)
        else:
            s2 = self.params.sigma ** 2
        ll = -d2 / (2.0 * s2)
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
        hx, hy = self.size
        cap = self.params.background_positions
        nx = max(1, min(int(w / max(hx, 1.0)), int(math.ceil(math.sqrt(cap * w / max(h, 1))))))
        ny = max(1, min(int(h / max(hy, 1.0)), int(math.ceil(cap / nx))))
        xs = (np.arange(nx) + 0.5) * (w / nx)
        ys = (np.arange(ny) + 0.5) * (h / ny)
        gx, gy = np.meshgrid(xs, ys)
        ell = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, hx), np.full(gx.size, hy)])
        if exclude is not None:
            ex = exclude
            far = (np.abs(ell[:, 0] - ex[0]) >= hx + ex[2]) | (np.abs(ell[:, 1] - ex[1]) >= hy + ex[3])
            ell = ell[far]
        if ell.shape[0] < 2:
            return  # nothing left that is background: keep the previous statistics
        # The background histograms are computed exactly like the samples' (a subsampled frame would
        # shift mu and sigma and with them the appearance threshold).
        rho, tot, _ = self._rho(frame, ell, roi=(0, 0, w, h))
        rho = rho[tot > 0]
        if rho.size >= 2:
            self.bg_mu = float(rho.mean())
            self.bg_sd = float(rho.std())
        self._since_bg = 0

    # ------------------------------------------------------------------ init
    def _start_tracking(self, states: np.ndarray, log_lik: np.ndarray | None = None) -> None:
        n = self.params.n_particles
        if states.shape[0] != n:
            w = np.ones(states.shape[0]) if log_lik is None else np.exp(log_lik - np.max(log_lik))
            idx = self.resampler(w / w.sum(), self.rng)
            idx = idx[self.rng.integers(0, idx.size, n)] if idx.size != n else idx
            states = states[idx]
        states = np.array(states, dtype=np.float64)
        states[:, VX:VY + 1] = 0.0
        states[:, HY + 1:] = 0.0
        self.ps = ParticleSet(states)
        self.estimate = self.ps._mean.copy()
        self.mode = "tracking"
        self.miss = 0
        self._search_states = None
        self._search_loglik = None

    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        self._reset()
        ell = box_to_ellipse(box)
        self._set_model(self.cue.histogram(frame, ell))
        self.size = (float(ell[2]), float(ell[3]))
        state = self._initial_state(ell)
        self._start_tracking(np.tile(state, (self.params.n_particles, 1)))
        self._background_stats(frame, ell)
        self.last_box = tuple(float(v) for v in box)
        self.last_score = 1.0
        return self._state(box=self.last_box, score=1.0, lost=False)

    def init_auto(self, frame: np.ndarray, histogram: np.ndarray, size: tuple[float, float], *,
                  regions: Sequence[Sequence[float]] | None = None) -> TrackState:
        """Automatic initialisation from a known target histogram (§6).

        Parameters
        ----------
        histogram : the target model ``q`` (any non-negative array with ``cue.n_bins``
            entries; it is normalised).
        size : expected ``(w, h)`` of the target in pixels.
        regions : optional entry regions ``(x, y, w, h)`` where the target is expected
            to appear (doors, image borders); by default samples cover the whole frame.

        The tracker starts in initialisation mode and reports ``lost=True`` until more
        than ``b N`` samples satisfy the appearance condition (Eq. 15).
        """
        frame = as_bgr_uint8(frame, where="init frame")
        hist = np.asarray(histogram, dtype=np.float64).ravel()
        if hist.size != self.cue.n_bins or not np.all(np.isfinite(hist)) or hist.min() < 0 or hist.sum() <= 0:
            raise ParameterError(f"histogram must have {self.cue.n_bins} finite non-negative values with a positive sum")
        w, h = (float(v) for v in size)
        if not (w > 0 and h > 0 and math.isfinite(w) and math.isfinite(h)):
            raise ParameterError(f"size must be a positive (w, h), got {size!r}")
        self._shape = frame.shape[:2]
        self.frame_index = 0
        self._reset()
        self._set_model(hist)
        self.size = (w / 2.0, h / 2.0)
        if regions is not None:
            fh, fw = self._shape
            self.regions = np.array([validate_box(r, fw, fh) for r in regions], dtype=np.float64).reshape(-1, 4)
        self._background_stats(frame, None)
        self.mode = "searching"
        return self._search(frame)

    def init_detect(self, frame: np.ndarray) -> TrackState:
        """Initialise from the tracker's detector: the highest-scoring detection becomes the target.

        Without a detection the tracker waits (``lost=True``) and runs the detector on
        the following frames until one appears.
        """
        if self.detector is None:
            raise ParameterError("init_detect needs a detector (create_tracker(..., detector=callable))")
        frame = as_bgr_uint8(frame, where="init frame")
        self._shape = frame.shape[:2]
        self.frame_index = 0
        self._reset()
        box = self._best_detection(frame)
        if box is not None:
            return self._init(frame, box)
        self.mode = "detecting"
        return self._state(box=(0.0, 0.0, 0.0, 0.0), score=0.0, lost=True)

    def _detections(self, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        out = self.detector(frame)
        boxes, scores = [], []
        for det in out if out is not None else []:
            det = [float(v) for v in det]
            if len(det) < 4:
                continue
            x, y, w, h = det[:4]
            if w > 0 and h > 0 and all(math.isfinite(v) for v in det[:4]):
                boxes.append((x, y, w, h))
                scores.append(det[4] if len(det) > 4 else 1.0)
        return np.array(boxes, dtype=np.float64).reshape(-1, 4), np.array(scores, dtype=np.float64)

    def _best_detection(self, frame: np.ndarray) -> Box | None:
        boxes, scores = self._detections(frame)
        fh, fw = frame.shape[:2]
        for i in np.argsort(-scores, kind="stable"):
            try:
                return validate_box(boxes[i], fw, fh)
            except ValueError:
                continue
        return None

    # ------------------------------------------------------------------ update
    def _update(self, frame: np.ndarray) -> TrackState:
        if self.mode == "tracking":
            state = self._track(frame)
        elif self.mode == "detecting":
            box = self._best_detection(frame)
            state = (self._state(box=(0.0, 0.0, 0.0, 0.0), score=0.0, lost=True) if box is None
                     else self._init(frame, box))
        else:
            state = self._search(frame)
        self._on_frame(frame)
        return state

    # ------------------------------------------------------------------ hooks
    def _propagate(self, states: np.ndarray) -> tuple[float, float, float, float]:
        """Move the samples with the dynamic model (in place); return the region their ellipses cover."""
        raise NotImplementedError

    def _initial_state(self, ellipse) -> np.ndarray:
        """A state at rest on an ellipse ``(cx, cy, hx, hy)``."""
        state = np.zeros(self.dim)
        state[[X, Y, HX, HY]] = ellipse
        return state

    def _clip_states(self, states: np.ndarray) -> None:
        """Bound the sizes of samples placed by the search (in place)."""
        np.clip(states[:, HX:HY + 1], self.params.min_half_axis, None, out=states[:, HX:HY + 1])

    def _extra_log_lik(self, frame: np.ndarray, states: np.ndarray, log_lik: np.ndarray,
                       roi: tuple[int, int, int, int], feats) -> np.ndarray:
        """Further log-likelihood terms multiplied into the colour likelihood (default: none).

        ``feats`` is the quantised region ``roi`` (shared with the colour cue)."""
        return log_lik

    def _update_models(self, frame: np.ndarray, estimate: np.ndarray, feats, rho_e: float) -> None:
        """Called when the colour model update gate passes (hook for further adaptive models)."""

    def _after_estimate(self, frame: np.ndarray, estimate: np.ndarray) -> None:
        """Called with the new mean state after each tracked frame."""

    def _on_frame(self, frame: np.ndarray) -> None:
        """Called at the end of every update (tracking or searching)."""

    def _track(self, frame: np.ndarray) -> TrackState:
        p = self.params
        ps = self.ps
        n = ps.n
        fh, fw = self._shape
        # (1) select
        if p.resample_ess >= 1.0 or ps._ess < p.resample_ess * n:
            ps.resample(self.resampler(ps.w, self.rng))
        # (2) propagate
        x0, y0, x1, y1 = self._propagate(ps.states)
        # (3) observe (the region the particles can reach is quantised once)
        ell = self._ellipses(ps.states)
        roi = (min(max(int(math.floor(x0)) - 1, 0), fw), min(max(int(math.floor(y0)) - 1, 0), fh),
               max(min(int(math.ceil(x1)) + 1, fw), 0), max(min(int(math.ceil(y1)) + 1, fh), 0))
        rho, tot, feats = self._rho(frame, ell, roi)
        # (4) weight
        log_lik = self._extra_log_lik(frame, ps.states, self._log_lik(rho, tot), roi, feats)
        ok = ps.set_log_likelihood(log_lik, accumulate=p.resample_ess < 1.0)
        # (5) estimate
        self.estimate = est = ps._mean.copy()
        self._after_estimate(frame, est)
        e_ell = est[_ELL_COLS].reshape(1, 4)
        hist_e, tot_e = self.cue.histograms(feats, e_ell)
        p_e = hist_e[0].copy()
        # element-wise sums, not BLAS: results must not depend on the BLAS thread count of the process
        rho_e = float(np.clip(np.sum(np.sqrt(p_e) * self._sqrt_q), 0.0, 1.0)) if tot_e[0] > 0 else 0.0
        box = tuple(float(v) for v in ellipse_to_box(est[_ELL_COLS]))
        # appearance condition (Eq. 15) -> lost detection (§6)
        thr = self._threshold()
        n_pass = int(np.count_nonzero(rho > thr))
        if not ok or n_pass < p.kickoff_fraction * n:
            self.miss += 1
        else:
            self.miss = 0
        info = {"mode": "tracking", "n_pass": n_pass, "threshold": thr}
        if p.search and (self.miss >= p.lost_frames or not ok):
            self.size = (float(est[HX]), float(est[HY]))
            self.mode = "searching"
            self._search_states = None
            return self._state(box=self.last_box or box, score=rho_e, lost=True, info={**info, "mode": "lost"})
        # (6) model update (Eqs. 11-12) or the book's lambda gate
        if ok and tot_e[0] > 0 and p.alpha > 0:
            if p.update_gate == "threshold":
                if rho_e > p.update_rho:
                    self._set_model((1.0 - p.alpha) * self.q + p.alpha * p_e)
                    self._update_models(frame, est, feats, rho_e)
            elif p.update_gate == "lambda":
                pi_e = self._pi(rho_e)
                if self.lam is None:
                    self.lam = pi_e
                else:
                    if pi_e > self.lam and self.miss == 0:
                        self._set_model((1.0 - p.alpha) * self.q + p.alpha * p_e)
                    self.lam = (1.0 - p.lambda_rate) * self.lam + p.lambda_rate * pi_e
        if p.background_interval and self.miss == 0:
            self._since_bg += 1
            if self._since_bg >= p.background_interval:
                self.size = (float(est[HX]), float(est[HY]))
                self._background_stats(frame, e_ell[0])
        if self.miss == 0:
            self.last_box = box
        self.last_score = rho_e
        return self._state(box=box, score=rho_e, lost=False, info=info)

    # ------------------------------------------------------------------ search
    def _n_search(self) -> int:
        p = self.params
        if p.search_particles:
            return p.search_particles
        fh, fw = self._shape
        hx, hy = self.size
        area = fw * fh if self.regions is None else float(np.sum(self.regions[:, 2] * self.regions[:, 3]))
        cells = int(math.ceil(area / max(4.0 * hx * hy, 1.0)))
        return int(min(max(cells, p.n_particles), 10 * p.n_particles))

    def _uniform_positions(self, m: int) -> np.ndarray:
        """``m`` stratified positions over the frame (or the entry regions)."""
        rng = self.rng
        if self.regions is None:
            fh, fw = self._shape
            boxes = np.array([[0.0, 0.0, fw, fh]])
        else:
            boxes = self.regions
        areas = boxes[:, 2] * boxes[:, 3]
        # split m among the regions in proportion to their area (largest remainder)
        share = m * areas / areas.sum()
        counts = np.floor(share).astype(int)
        counts[np.argsort(-(share - counts))[: m - counts.sum()]] += 1
        out = []
        for (x, y, w, h), c in zip(boxes, counts):
            if c <= 0:
                continue
            nx = max(1, int(round(math.sqrt(c * w / h))))
            ny = max(1, int(math.ceil(c / nx)))
            cell = rng.permutation(nx * ny)[:c]
            cx = (cell % nx + rng.random(c)) * (w / nx) + x
            cy = (cell // nx + rng.random(c)) * (h / ny) + y
            out.append(np.column_stack([cx, cy]))
        return np.concatenate(out) if out else np.empty((0, 2))

    def _search(self, frame: np.ndarray) -> TrackState:
        """Initialisation mode (§6): spread samples, test the appearance condition, re-acquire."""
        p = self.params
        n_s = self._n_search()
        hx, hy = self.size
        states = np.zeros((n_s, self.dim))
        n_keep = 0
        if self._search_states is not None and p.search_keep > 0:
            n_keep = int(round(p.search_keep * n_s))
            w = np.exp(self._search_loglik - self._search_loglik.max())
            idx = self.resampler(w / w.sum(), self.rng)[:n_keep]
            if idx.size < n_keep:
                idx = idx[self.rng.integers(0, idx.size, n_keep)]
            states[:n_keep] = self._search_states[idx]
            spread = max(p.position_noise * 0.5 * (hx + hy), p.min_noise_px) * 2.0
            states[:n_keep, X:Y + 1] += self.rng.normal(0.0, spread, (n_keep, 2))
            states[:n_keep, HX:HY + 1] *= np.exp(self.rng.normal(0.0, 0.05, (n_keep, 1)))
        n_new = n_s - n_keep
        states[n_keep:, X:Y + 1] = self._uniform_positions(n_new)
        scale = np.exp(self.rng.normal(0.0, 0.1, (n_new, 1)))
        states[n_keep:, HX] = hx * scale[:, 0]
        states[n_keep:, HY] = hy * scale[:, 0]
        self._clip_states(states)
        ell = self._ellipses(states)
        rho, tot, _ = self._rho(frame, ell)
        loglik = self._log_lik(rho, tot)
        if not np.isfinite(loglik).any():
            loglik = np.zeros_like(loglik)
        self._search_states = states
        self._search_loglik = loglik
        thr = self._threshold()
        best = int(np.argmax(np.where(tot > 0, rho, -1.0)))
        # samples belonging to the best candidate: within one target size of it
        near = (np.abs(states[:, X] - states[best, X]) < 2 * hx) & (np.abs(states[:, Y] - states[best, Y]) < 2 * hy)
        found = False
        if p.search_method == "appearance":
            cluster = near & (rho > thr) & (tot > 0)
            found = cluster.sum() > p.kickoff_fraction * p.n_particles
        else:
            cluster = near & (tot > 0)
            lw = np.where(cluster, loglik, -np.inf)
            ww = np.exp(lw - lw.max())
            ww /= ww.sum()
            pos = states[:, X:Y + 1]
            mean = (ww[:, None] * pos).sum(axis=0)
            var = float(np.mean((ww[:, None] * (pos - mean) ** 2).sum(axis=0)))
            found = n_keep > 0 and var < p.variance_threshold and rho[best] > thr
        if not found and self.detector is not None and self.frame_index % p.detector_interval == 0:
            boxes, _ = self._detections(frame)
            if boxes.shape[0]:
                d_ell = box_to_ellipse(boxes)
                d_rho, d_tot, _ = self._rho(frame, d_ell)
                d_rho = np.where(d_tot > 0, d_rho, -1.0)
                k = int(np.argmax(d_rho))
                if d_rho[k] > thr:
                    self.size = (float(d_ell[k, 2]), float(d_ell[k, 3]))
                    state = self._initial_state(d_ell[k])
                    self._start_tracking(np.tile(state, (p.n_particles, 1)))
                    box = tuple(float(v) for v in boxes[k])
                    self.last_box = box
                    return self._state(box=box, score=float(d_rho[k]), lost=False,
                                       info={"mode": "acquired", "threshold": thr})
        info = {"mode": "searching", "n_pass": int(np.count_nonzero(rho > thr)), "threshold": thr}
        if found:
            self._start_tracking(states[cluster], loglik[cluster])
            est = self.estimate
            box = tuple(float(v) for v in ellipse_to_box(est[_ELL_COLS]))
            self.last_box = box
            self.size = (float(est[HX]), float(est[HY]))
            return self._state(box=box, score=float(rho[best]), lost=False, info={**info, "mode": "acquired"})
        box = self.last_box
        if box is None:
            box = tuple(float(v) for v in ellipse_to_box(ell[best]))
        return self._state(box=box, score=float(max(rho[best], 0.0)), lost=True, info=info,
                           particles=states, weights=np.exp(loglik - loglik.max()))

    # ------------------------------------------------------------------ output
    def _state(self, *, box, score, lost, info=None, particles=None, weights=None) -> TrackState:
        if particles is None and self.ps is not None:
            particles = self.ps.states
            weights = self.ps.w
        elif weights is not None:
            weights = weights / weights.sum()
        return TrackState(box=tuple(float(v) for v in box), score=float(score), lost=bool(lost),
                          particles=None if particles is None else particles.copy(),
                          weights=None if weights is None else np.array(weights, dtype=np.float64),
                          state_names=self.state_names, info=info or {})


class ColorPF(ColorParticleFilter):
    """The adaptive colour-based particle filter (see the module docstring)."""

    name = "color-pf"
    Params = ColorPFParams
    state_names = ConstantVelocityScale.state_names

    def __init__(self, params: ColorPFParams | None = None, *, rng=None, seed=None,
                 detector: Detector | None = None):
        super().__init__(params, rng=rng, seed=seed, detector=detector)
        p = self.params
        self.dynamics = ConstantVelocityScale(min_half_axis=p.min_half_axis, max_scale_rate=p.max_scale_rate,
                                              scale_damping=p.scale_damping)

    def _noise_std(self, hx: float, hy: float) -> np.ndarray:
        p = self.params
        hbar = 0.5 * (hx + hy)
        pos = max(p.position_noise * hbar, p.min_noise_px)
        vel = p.velocity_noise * hbar
        return np.array([pos, pos, vel, vel, p.size_noise * hx, p.size_noise * hy, p.scale_rate_noise])

    def _propagate(self, states: np.ndarray) -> tuple[float, float, float, float]:
        est = self.estimate
        fh, fw = self._shape
        return self.dynamics.propagate(states, self._noise_std(est[HX], est[HY]), self.rng, frame_size=(fw, fh))

    def _clip_states(self, states: np.ndarray) -> None:
        self.dynamics.clip(states)
