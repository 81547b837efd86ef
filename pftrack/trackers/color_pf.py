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
(:meth:`ColorPF.init_detect`).

Loss detection (``loss_test``): by default the two-class test of
:mod:`pftrack.filtering.loss` on the estimate's ``rho`` (the appearance condition's
background statistics as its absent half, the target's own score history as the
other, with hysteresis); ``loss_test="appearance"`` is the paper's test (fewer than
``b N`` samples pass for ``lost_frames`` frames).  When lost, the tracker returns to
initialisation mode, reports ``lost=True`` and re-acquires the target when it
reappears.  On grey input the features are equalised intensity x gradient
orientation (:mod:`pftrack.cues.intensity`, ``color_space="auto"``).

Options from the book *Object Tracking*, ch. 4 (``shared/seeds/book-notes.md``):
``adaptive_sigma`` (``sigma^2 = d_min^2 / 2``), ``update_gate="lambda"``
(``lambda <- (1 - alpha_u) lambda + alpha_u pi_est``, update when ``pi_est > lambda``)
and ``search_method="variance"`` (uniform initialisation, tracking declared when
the particle-position variance falls below a threshold).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Sequence

import numpy as np

from ..cues.color import blend_model, model_rho, normalized_model, warmup
from ..cues.histogram_cue import ColorCue
from ..cues.illumination import QuotientImage
from ..cues.lit_histogram import LitHistogram
from ..errors import ParameterError
from ..filtering.dynamics import HX, HY, VX, VY, ConstantVelocityScale, X, Y
from ..filtering.loss import LossDetector, toward_background
from ..filtering.particles import ParticleSet
from ..filtering.resampling import get_resampler
from ..geometry import Box, box_to_ellipse, displacement_rate, ellipse_box, in_frame_fraction
from .base import Tracker, TrackState
from .camera_motion import CameraMotionMixin
from .color_hooks import ColorHooks
from .color_likelihood import LikelihoodMixin
from .color_params import ColorModelParams
from .color_pf_params import ColorPFParams
from .color_search import SearchMixin
from .denoise import NoiseGateMixin
from .distractors import DistractorMemory, score_gradual
from .entering import EnteringMixin
from .input_switch import InputSwitchMixin
from .persistence import PersistenceMixin
from .probation import ProbationMixin
from .static_lookalikes import SceneReference, SceneTestMixin
from .structure_check import StructureCheck, fused_loss
from .vetoes import VetoMixin
from .raw_check import RawGreyCheck

__all__ = ["ColorModelParams", "ColorPF", "ColorPFParams", "ColorParticleFilter"]

Detector = Callable[[np.ndarray], Sequence]
_ELL_COLS = np.array([X, Y, HX, HY])


class ColorParticleFilter(NoiseGateMixin, InputSwitchMixin, LikelihoodMixin, SearchMixin, VetoMixin, ProbationMixin,
                          PersistenceMixin, SceneTestMixin, EnteringMixin, ColorHooks, Tracker):
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
        self.cue = ColorCue(p.color_space, tuple(p.bins) or None, p.kernel, p.max_pixels,
                            gray_bins=tuple(p.gray_bins), gradient_threshold=p.gradient_threshold,
                            normalize=p.color_normalize, parts=p.histogram_parts, dark_stretch=p.dark_stretch,
                            dark_percentile=p.dark_percentile, haze_stretch=p.haze_stretch,
                            cast_jump=p.cast_jump, light_jump=p.light_jump)
        self.loss = LossDetector(lost_frames=p.lost_frames, reacquire_margin=p.reacquire_margin,
                                 history_rate=p.history_rate, sd_floor_target=p.score_sd_floor,
                                 sd_floor_background=p.score_sd_floor, learn_z=p.history_z,
                                 acquire_z=p.reacquire_z, acquire_llr=p.reacquire_llr)
        self.resampler = get_resampler("systematic" if p.resampler == "seir" else p.resampler)
        if detector is not None and not callable(detector):
            raise ParameterError("detector must be a callable frame -> boxes")
        self.detector = detector
        self._quotient: QuotientImage | None = None  # illumination="quotient" on grey input (decided by init)
        self._raw_check: RawGreyCheck | None = None  # its re-acquisition check on the untransformed frames
        self._structure_check: StructureCheck | None = None  # grey_check on grey input
        self._plain_loss: LossDetector | None = None  # the histogram's test while grey_check="fused" replaces it
        self._raw: np.ndarray | None = None  # the untransformed frame
        # look-alikes met during a loss
        self._distractors = DistractorMemory(p.distractor_frames, p.lost_frames, p.distractor_follow)
        # a confident frame: the scene's look-alikes (static_ncc)
        self._scene = SceneReference(p.static_ncc, p.static_quarters, p.static_leave_refresh)
        warmup()
        self._reset()

    # ------------------------------------------------------------------ state
    def _reset(self) -> None:
        self._own_quotient = False  # the quotient histogram's image starts from _frame_gray (color_hooks)
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
        self._confident_size = (0.0, 0.0)  # half-axes when the loss test was last confident
        self._confident_sizes: deque = deque()  # (frame index, hx, hy) of the recent confident estimates
        self._confident_motion = None  # (frame index, position, velocity) when last confident
        self._lost_at = None  # the same, for the current loss (search prediction)
        self._distractors.clear()
        self._scene.clear()
        self._confident_track: deque = deque(maxlen=6)  # (frame index, x, y) of the last confident estimates
        self._score_track: deque = deque(maxlen=8)  # (frame index, score) of the last tracked frames
        self._loss_falling = False  # the score was already falling at the current loss (distractor_gradual)
        self._exit_velocity = (0.0, 0.0)  # their mean displacement per frame when the loss was declared
        self._seen_levels: np.ndarray | None = None  # channel levels while the target was seen (relit_search)
        self._seen_thumb: np.ndarray | None = None  # and the view's grey thumbnail then (relit_gain="still")
        self._gain_cache = None  # (frame index, reference levels, gain) of the relit search's reading
        self._relit_at = -1  # the frame whose search was scored on the relit frame (relit_search)
        self.regions: np.ndarray | None = None
        self._search_states: np.ndarray | None = None
        self._search_loglik: np.ndarray | None = None
        self._search_since = 0  # frame index at which the current search began
        self._last_search: TrackState | None = None  # its latest result (re-reported between searches)
        # (frame index, grey frame) of the last frames while searching an exit strip (.vetoes)
        self._search_grays: deque = deque(maxlen=max(1, int(self.params.reenter_resident)))
        self._gray_now: tuple | None = None  # (frame index, grey image, frame): this frame's grey image, once converted
        self._vetoed: list = []  # (frame index, centre, shift) of the candidates reenter_outward refused lately
        self._edge_seen: deque = deque(maxlen=max(1, self.params.reenter_memory))  # (frame, cx, cy) mostly outside
        self._ambiguous_until = -1  # acquire_unique_hold: no acquisition up to this frame
        self._sliver: tuple | None = None  # acquire_sliver_frames: (frame index, streak, box in the frame)
        self._ell = np.empty((0, 4))
        self._lit: LitHistogram | None = None  # grey_histogram="both" on grey input (decided by _init)

    def _set_model(self, q: np.ndarray) -> None:
        self.q, self._sqrt_q = normalized_model(q)

    def _learn_model(self, p_e: np.ndarray) -> None:
        """Eq. 12's update with the estimate's histogram ``p_e``, and of the quotient model beside it."""
        self.q, self._sqrt_q = blend_model(self.q, p_e, self.params.alpha)
        if self._lit is not None:
            self._lit.learn(self.params.alpha)

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
        self._end_probation()
        self.miss = 0
        self.loss.miss = 0
        self.loss.lost = False
        self._lost_at = None
        self._loss_falling = False
        self._distractors.clear()
        self._persist_reset()
        self._confident_track.clear()  # a velocity is measured within one stretch of tracking
        self._confident_sizes.clear()
        self._search_states = None
        self._search_loglik = None
        self._last_search = None

    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        first = self.frame_index == 0 or self.mode == "detecting"  # a box given, not one of the tracker's restarts
        self._reset()
        self.cue.adapt_to(frame)  # grey features on grey input ("auto")
        self.cue.new_frame(frame)
        ell = box_to_ellipse(box)
        p = self.params
        if self._raw_check is not None:
            self._raw_check.init(self._raw, ell)
        self._drop_structure_check()
        if self._wants_grey_check():
            # its quotient image starts from the frame's grey image, converted once (the frames it sees are these)
            self._structure_check = StructureCheck.for_params(
                p, gray_of=self._frame_gray if self._structure_frame(frame) is frame else None)
            self._structure_check.init(self._structure_frame(frame), ell)
            if self._structure_check.fused:
                self._plain_loss, self.loss = self.loss, fused_loss(p)
        if p.grey_histogram == "both" and self.cue.color_space == "gray" and self._quotient is None:
            # after the structural check: its self-quotient image of the same frames may be shared
            self._lit = LitHistogram(sigma=p.illumination_sigma, gray_bins=p.gray_bins, kernel=p.kernel,
                                     max_pixels=p.max_pixels, gradient_threshold=p.gradient_threshold,
                                     quotient=self._shared_quotient(), parts=p.histogram_parts)
            self._lit.init(frame, ell)
        self.loss.reset(1.0)
        self._set_model(self.cue.histogram(frame, ell))
        self.size = (float(ell[2]), float(ell[3]))
        self._confident_size = self.size
        state = self._initial_state(ell)
        self._start_tracking(np.tile(state, (self.params.n_particles, 1)))
        self._background_stats(frame, ell)
        self.last_box = tuple(float(v) for v in box)
        self.last_score = 1.0
        self._entering_start(frame, box if first else None)  # a first box at the frame's edge (.entering)
        return self._state(box=self.last_box, score=1.0, lost=False)

    def _resume_search(self) -> None:
        """Search on from the next frame, as after a declared loss (``input_switch`` started again on an earlier
        frame while the target was lost)."""
        self.mode = "searching"
        self.loss.lost = True
        self.last_score = 0.0
        self._search_states = None
        self._search_since = self.frame_index
        self._last_search = None

    # ------------------------------------------------------------------ update
    def _update(self, frame: np.ndarray) -> TrackState:
        # on grey input with a self-quotient image each frame, both start from one grey conversion of the frame
        self.cue.new_frame(frame, gray=self._frame_gray(frame) if self._grey_shared() else None)
        if self._lit is not None:
            self._lit.new_frame(frame)
        if self._structure_check is not None:
            self._structure_check.new_frame()
        if self.mode == "tracking":
            state = self._track(frame)
            if self._entering is not None:
                state = self._entering_step(frame, state)
        elif self.mode == "detecting":
            box = self._best_detection(frame)
            state = (self._state(box=(0.0, 0.0, 0.0, 0.0), score=0.0, lost=True) if box is None
                     else self._init(frame, box))
        elif self._search_due():
            state = self._search(frame)
            # kept for the frames between searches, while the search goes on
            self._last_search = state if self.mode == "searching" else None
        else:
            state = self._waiting_state()
        self._keep_search_gray(frame)  # the frames while the search is confined to an exit strip (.vetoes)
        self._on_frame(frame)
        return state

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
        seir_info = self._seir(frame, ps, log_lik, rho, tot, roi, feats) if p.resampler == "seir" and ok else None
        # (5) estimate
        self.estimate = est = ps._mean.copy()
        self._after_estimate(frame, est)
        e_ell = est[_ELL_COLS].reshape(1, 4)
        hist_e, tot_e = self.cue.histograms(feats, e_ell)
        p_e = hist_e[0].copy()
        rho_e = model_rho(p_e, self._sqrt_q) if tot_e[0] > 0 else 0.0
        if self._lit is not None and tot_e[0] > 0:
            rho_e = max(rho_e, self._lit.estimate_rho(feats.roi, feats.pitch, e_ell))
        cx, cy, hx, hy = e_ell[0].tolist()
        box = ellipse_box(cx, cy, hx, hy)
        # appearance condition (Eq. 15) -> lost detection (§6)
        thr = self._threshold()
        n_pass = int(np.count_nonzero(rho > thr))
        info = {"mode": "tracking", "n_pass": n_pass, "threshold": thr, "rho": rho_e}
        if self._probation_left:
            info["probation"] = True  # following a weak acquisition without learning from it (.probation)
        # a target leaving the view still matches on its last visible sliver: out of view, it is reported absent
        inside = in_frame_fraction(box, fw, fh) if p.min_in_frame > 0 or p.edge_share > 0 or p.reenter_memory else 1.0
        if p.reenter_memory and inside < 0.5:
            self._edge_seen.append((self.frame_index, cx, cy))
        out = inside < p.min_in_frame
        if out:
            info["out_of_view"] = True
        if seir_info is not None:
            info["ess"], info["loops"] = seir_info.ess, seir_info.loops
        if p.loss_test == "likelihood":
            # two-class test on the estimate's score with hysteresis (pftrack.filtering.loss)
            s_e = self._loss_scores(frame, e_ell, np.array([rho_e]), roi)[0]
            if p.edge_share > 0:  # the box's part outside the frame counts as background
                s_e = toward_background(self.loss, s_e, inside / p.edge_share)
            lost_now, score = self.loss.step(s_e if ok and tot_e[0] > 0 else float("nan"))
            if p.distractor_gradual == "scores":
                self._score_track.append((self.frame_index, score))
            self.miss = self.loss.miss
            confident = self.loss.confident(s_e)
            info["llr"] = self.loss.llr
        else:
            if not ok or n_pass < p.kickoff_fraction * n:
                self.miss += 1
            else:
                self.miss = 0
            lost_now, score = self.miss >= p.lost_frames or not ok, rho_e
            confident = self.miss == 0
        confident = confident and not out and not self._probation_left  # no learning from a sliver, or on probation
        if p.search and not lost_now and not out and self._on_scene(frame, box, confident):  # the scene's
            lost_now, confident, info["on_scene"] = True, False, True
        if confident:
            self.cue.confirm(p.normalize_rate)
            if self._raw_check is not None:
                self._raw_check.learn(self._raw, e_ell)
            if self._structure_check is not None:
                self._structure_check.learn(self._structure_frame(frame), e_ell)
            self._confident_size = (float(est[HX]), float(est[HY]))
            if p.search_size_frames:
                sizes = self._confident_sizes
                sizes.append((self.frame_index, *self._confident_size))
                while sizes[0][0] <= self.frame_index - p.search_size_frames:
                    sizes.popleft()
            self._confident_motion = (self.frame_index, est[[X, Y]].copy(), est[[VX, VY]].copy())
            self._confident_track.append((self.frame_index, float(est[X]), float(est[Y])))
            self._keep_scene(frame, box)
        if p.search and lost_now:
            # search at the size the target had when last seen clearly (a target that is leaving the
            # frame or being covered shrinks the estimate on its way out)
            self.size = self._confident_size if p.loss_test == "likelihood" else (float(est[HX]), float(est[HY]))
            if p.search_size_frames and p.loss_test == "likelihood" and self._confident_sizes:
                _, hx, hy = max(self._confident_sizes, key=lambda s: s[1] * s[2])
                self.size = (hx, hy)
            self.mode = "searching"
            self.loss.lost = True
            self._lost_at = self._confident_motion
            self._loss_falling = (p.distractor_gradual == "scores" and self._lost_at is not None
                                  and score_gradual(self._score_track, self._lost_at[0]))
            self._exit_velocity = displacement_rate(self._confident_track)
            self._search_states = None
            self._search_since = self.frame_index
            self._last_search = None
            return self._state(box=self.last_box or box, score=min(score, 0.5) if p.loss_test == "likelihood"
                               else score, lost=True, info={**info, "mode": "lost"})
        if not p.search:
            self.loss.lost = False
        # (6) model update (Eqs. 11-12), the loss test's own confidence, or the book's lambda gate
        if ok and tot_e[0] > 0 and p.alpha > 0:
            gate = p.update_gate
            if gate == "confident" and p.loss_test != "likelihood":
                gate = "threshold"
            if (gate == "confident" and confident) or (gate == "threshold" and rho_e > p.update_rho):
                self._learn_model(p_e)
                self._update_models(frame, est, feats, rho_e)
            elif gate == "lambda":
                pi_e = self._pi(rho_e)
                if self.lam is None:
                    self.lam = pi_e
                else:
                    if pi_e > self.lam and self.miss == 0:
                        self._learn_model(p_e)
                    self.lam = (1.0 - p.lambda_rate) * self.lam + p.lambda_rate * pi_e
        if p.background_interval and confident:
            self._since_bg += 1
            if self._since_bg >= p.background_interval:
                self.size = (float(est[HX]), float(est[HY]))
                self._background_stats(frame, e_ell[0])
        if self._probation_left and p.search and (switched := self._probation_step(frame, e_ell)):
            return switched
        if self.miss == 0:
            self.last_box = box
        self.last_score = rho_e
        if self._doubtful():  # on probation, its ratio below probation_lost_llr: followed, reported absent
            out = info["doubtful"] = True
        if out:  # reported absent, tracked on (out of view: the target comes back where it left, no search)
            return self._state(box=box, score=min(score, 0.5), lost=True, info=info)
        return self._state(box=box, score=score, lost=False, info=info)

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


class ColorPF(CameraMotionMixin, ColorParticleFilter):
    """The adaptive colour-based particle filter (see the module docstring)."""

    name = "color-pf"
    Params = ColorPFParams
    state_names = ConstantVelocityScale.state_names

    def __init__(self, params: ColorPFParams | None = None, *, rng=None, seed=None,
                 detector: Detector | None = None):
        super().__init__(params, rng=rng, seed=seed, detector=detector)
        p = self.params
        self.dynamics = ConstantVelocityScale(min_half_axis=p.min_half_axis, max_scale_rate=p.max_scale_rate,
                                              scale_damping=p.scale_damping, wide_fraction=p.wide_fraction,
                                              wide_factor=p.wide_factor, mix_fraction=p.mix_fraction,
                                              mix_factors=self._mix_factors(), velocity_step=p.velocity_step)

    def _mix_factors(self) -> np.ndarray | None:
        """``mix_fraction``: the second model's noise over the first's, per state component (position and velocity;
        1 for the size); None when off."""
        p = self.params
        if p.mix_fraction <= 0:
            return None
        f = np.ones(self.dim)
        f[[X, Y]] = p.mix_position_noise / p.position_noise if p.position_noise > 0 else 1.0
        f[[VX, VY]] = p.mix_velocity_noise / p.velocity_noise if p.velocity_noise > 0 else 1.0
        return f

    def _noise_std(self, hx: float, hy: float) -> np.ndarray:
        p = self.params
        hx, hy = float(hx), float(hy)  # Python floats: the same numbers without NumPy scalars' cost
        hbar = 0.5 * (hx + hy)
        pos = max(p.position_noise * hbar, p.min_noise_px)
        vel = p.velocity_noise * hbar
        rate = p.scale_rate_noise
        if self.cue.color_space == "gray":
            if p.grey_scale_rate_noise is not None:
                rate = p.grey_scale_rate_noise
            if p.grey_velocity_noise is not None:
                vel = p.grey_velocity_noise * hbar
        return np.array([pos, pos, vel, vel, p.size_noise * hx, p.size_noise * hy, rate])

    def _step_std(self, est: np.ndarray) -> np.ndarray:
        std = np.zeros(self.dim)
        std[_ELL_COLS] = self._noise_std(est[HX], est[HY])[_ELL_COLS]
        return std

    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        self._camera_start(frame)
        return super()._init(frame, box)

    def _update(self, frame: np.ndarray) -> TrackState:
        self._camera_frame(frame)
        return super()._update(frame)

    def _propagate(self, states: np.ndarray) -> tuple[float, float, float, float]:
        est = self.estimate
        fh, fw = self._shape
        p = self.params
        if p.camera_motion:
            self._camera_apply(states)
        if p.grey_velocity_step is not None:
            self.dynamics.velocity_step = p.grey_velocity_step if self.cue.color_space == "gray" else p.velocity_step
        return self.dynamics.propagate(states, self._noise_std(est[HX], est[HY]), self.rng, frame_size=(fw, fh))

    def _clip_states(self, states: np.ndarray) -> None:
        self.dynamics.clip(states)
