"""``switching``: local feature-selecting mean shift, switched to a global covariance search when
the local similarity collapses (book ch. 6 §5; Wang & Yagi, "Switching local and covariance
matching for efficient object tracking").

Local mode is :class:`~pftrack.trackers.fs_meanshift.FSMeanShift`'s step.  Every frame the
local window's foreground region covariance is also compared (Eq. 30) with the covariance model
(the Log-Euclidean mean of the last ``history`` confident covariances, Eq. 31).  The tracker
switches to the global search (:func:`pftrack.cues.covariance_search.search`, foreground pixels
only: the back-projection of the selected features above ``fg_threshold``, ch06.md §1.6, P7) when
(ch06.md §1.10; the chapter sketches the detectors, ours are marked proposed):

1. **occlusion**: the local distance ``d = sqrt(1 - rho)`` exceeds ``mu + 3 sigma`` of the
   confident frames' distances (the chapter's "3 sigma from the mean", online, without labels); by
   default (``occlusion_take``) a candidate more than half a box away then takes over only if its
   covariance matches the model better than the local window's;
2. **sudden motion** (proposed): mean shift hits its iteration cap, or the back-projection mass
   in the converged window falls below ``sudden_mass`` of its running mean;
3. **distraction** (proposed; off by default): every ``distraction_every`` frames the global search runs as a
   check; a window more than half a box away whose covariance distance is lower than the local
   one by ``distraction_margin`` sigmas takes over.

A global result is accepted when its covariance distance is within ``mu_LE + 3 sigma_LE`` of the
confident frames'; otherwise the target is judged absent: ``lost`` is raised (after
``lost_frames`` frames), both models freeze, and the global search runs on every frame until a
window passes both the covariance and the local test.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..cues import covariance as cv
from ..cues import covariance_search as cs
from ..cues import feature_selection as fs
from ..cues.intensity import is_gray
from ..filtering.dynamics import reappearance_log_prior
from ..filtering.loss import confidence
from ..filtering.running_threshold import RunningThreshold
from ..geometry import Box
from ..params import param
from .base import TrackState
from .fs_meanshift import FSMeanShift, FSMeanShiftParams


@dataclass(frozen=True, kw_only=True)
class SwitchingParams(FSMeanShiftParams):
    predict: bool = param(True, doc=(
        "Start the local mean shift from the constant-velocity extrapolation of the last confident local frame "
        "(see fs-meanshift). Chosen on the tune split: mean AUC 0.511 vs 0.497 without (55 sequences, paired "
        "difference +0.014 +- 0.011), and 1.4x the update rate, as fewer frames switch to the global search."))
    features: Literal["porikli9", "first_order"] = param("porikli9", doc=(
        "Covariance features z of Eq. 27 (restored from Porikli 2006; see the covariance tracker)."))
    history: int = param(10, ge=1, le=200, doc="T of Eq. 31: confident covariances averaged into the model.")
    foreground: Literal["mask", "soft", "none"] = param("none", doc=(
        "Pixels entering the covariances (L6093-6096): 'mask' those whose back-projection is >= fg_threshold, "
        "'soft' weighted by it, 'none' all (Porikli's)."))
    fg_threshold: float = param(0.5, gt=0, le=1, doc="tau_fg on the normalised back-projection (ch06.md §1.6).")
    scales: tuple[float, ...] = param((1 / 1.1, 1.0, 1.1), doc="Window scales of the global search (§1.9).")
    coarse_side: int = param(8, ge=3, le=64, doc="Coarse level: the target's smaller side spans about this many px.")
    coarse_stride: int = param(2, ge=1, le=8, doc="Stride of the coarse lattice, in coarse pixels.")
    refine_top: int = param(6, ge=1, le=50, doc="Coarse windows refined (spread over the scales).")
    refine_side: int = param(32, ge=8, le=1024, doc="Refinement/model decimation (see the covariance tracker).")
    sudden_mass: float = param(0.0, ge=0, le=1, doc=(
        "Sudden motion (proposed, ch06.md §1.10): the window's mean back-projection below this fraction of its "
        "running mean (e.g. 0.3), or the iteration cap reached. 0 (default, chosen on the tune split: higher AUC "
        "and re-acquisition) disables it; occlusion and distraction still switch."))
    distraction_every: int = param(0, ge=0, le=1000, doc=(
        "Frames between distraction checks (proposed: 10); 0 (default) disables them. Chosen on the tune split: "
        "the check every 10 frames did not raise AUC (0.493 vs 0.497 without) and cost 20-40 % of the speed."))
    distraction_margin: float = param(1.0, ge=0, doc=(
        "A distant global window takes over when its covariance distance is lower by this many sigma_LE."))
    search_prior: float = param(0.0, ge=0, le=1, doc=(
        "Where a lost or occluded target reappears (proposed; fusion-pf's search_prior): among the global "
        "candidates that pass the covariance and local tests, the one of highest posterior odds is taken, the "
        "local test's log-likelihood ratio plus log((1 - e) A N(x; m, s^2 I) + e) capped at 0, with m the "
        "constant-velocity prediction from the last confident local frame, s half the box's mean side times "
        "(0.5 + 0.1 k) after k frames, A the frame's area and e this value (the chance of reappearing anywhere). "
        "0 (the chapter's rule): the first candidate by covariance distance that passes."))
    occlusion_take: Literal["any", "closer"] = param("closer", doc=(
        "On an occlusion alarm, which verified global candidate replaces the local window. 'any': the first "
        "(the chapter's switch). 'closer' (pftrack's default): one more than half a box away only when its "
        "covariance distance (Eq. 30) to the model is lower than the local window's, since the local window may "
        "still hold the partly covered target and a look-alike elsewhere can pass the colour test. Chosen on the "
        "tune split (5 real, 8 PETS people, 10 grey copies, 5 initial boxes each): mean AUC 0.435 against 0.432, "
        "tracking 48.5 % against 48.3 %, no group lower; the synthetic scenes unchanged."))
    ambiguity: float = param(0.1, ge=0, doc=(
        "A ratio test on the global search (pftrack's addition, after Lowe's ratio test; 0 turns it off): on an "
        "occlusion alarm, a verified candidate more than half a box from the local window does not take over when "
        "another refined window at least one box side away from it has a covariance distance (Eq. 30) below "
        "(1 + this) times its own: among look-alikes the search cannot tell which one is the target, and the "
        "local window keeps it (the alarm counts towards `lost`). Chosen on the tune split (5 real, 8 PETS "
        "people, 10 grey copies, 5 initial boxes each): mean AUC 0.444 and tracking 49.6 % against 0.435 and "
        "48.5 % without; 0.02-0.5 all gave 0.442-0.445; the tune synthetic scenes unchanged but teleport "
        "(0.577 -> 0.597)."))
    le_sigma: float = param(3.0, gt=0, doc="A global result is accepted within mu_LE + this x sigma_LE.")
    le_floor: float = param(0.05, ge=0, doc="Floor on sigma_LE.")


def takes_over(reason: str | None, *, far: bool, global_le: float, local_le: float, global_rho: float,
               local_rho: float, occlusion_take: str = "closer", distraction_bar: float = 0.0) -> bool:
    """Does a verified global candidate replace the local window (ch06.md §1.10)?

    ``reason`` is what started the search: ``"occlusion"`` (the chapter's switch; with ``occlusion_take=
    "closer"`` a ``far`` candidate must also be nearer the covariance model than the local window),
    ``"motion"`` (a sudden-motion alarm: the local result was not rejected, so the candidate must score a
    higher rho) or None (a distraction check: a far candidate better by ``distraction_bar`` in covariance
    distance and by rho)."""
    if reason == "occlusion":
        return occlusion_take == "any" or not far or global_le < local_le
    if reason == "motion":
        return global_rho > local_rho
    return far and global_le < local_le - distraction_bar and global_rho > local_rho


def ambiguous(candidates: np.ndarray, centre, size, distance: float, ratio: float) -> bool:
    """``ambiguity``'s ratio test: does a candidate window (rows ``x, y, w, h, distance``) whose centre is at
    least one box side (the smaller of ``size``) from ``centre`` have a covariance distance within
    ``(1 + ratio) * distance``? Always False for ``ratio <= 0``."""
    if ratio <= 0:
        return False
    cand = np.asarray(candidates, dtype=np.float64).reshape(-1, 5)
    centres = cand[:, :2] + cand[:, 2:4] / 2
    away = np.hypot(*(centres - np.asarray(centre, dtype=np.float64)).T) >= min(size)
    return bool(np.any(away & (cand[:, 4] <= distance * (1.0 + ratio))))


class Switching(FSMeanShift):
    """Local mean shift / global covariance matching switcher (deterministic)."""

    name = "switching"
    Params = SwitchingParams

    def _init_at(self, frame: np.ndarray, box: Box) -> TrackState:
        st = super()._init_at(frame, box)
        p = self.params
        self.gray = is_gray(frame)
        self.pitch = cs.pitch_for(box[2:], p.refine_side)
        self.scales = cs.derivative_scales(frame, kind=p.features, gray=self.gray)
        C = self._window_cov(frame, np.asarray(box, dtype=np.float64), weights=None)
        if C is None:
            C = np.eye(len(cv.feature_names(p.features, gray=self.gray)))
        self.cov_history: deque[np.ndarray] = deque([C], maxlen=p.history)
        self._set_cov_model()
        self.le_thresh = RunningThreshold(window=p.threshold_window, k=p.le_sigma, sd_floor=p.le_floor)
        self.mass_stats = RunningThreshold(window=p.threshold_window, seed=3)
        self.mode = "local"
        self.n_global = 0
        self.last_box = tuple(float(v) for v in box)
        self._frame_shape = frame.shape[:2]  # the working resolution's (the base class keeps the input's)
        self._seen = None  # (frame index, centre, velocity) of the last confident local frame (search_prior)
        return st

    # -- covariance helpers ------------------------------------------------------------------------
    def _level(self, frame: np.ndarray, weights: np.ndarray | None, *, rescale: bool = False) -> cs.Level:
        p = self.params
        if rescale:
            self.scales = cs.derivative_scales(frame, kind=p.features, gray=self.gray)
        if self.pitch > 1:
            return cs.Level.build(frame, self.pitch, kind=p.features, gray=self.gray, weights=weights)
        return cs.Level(frame, 1, self.scales, None if weights is None else weights.astype(np.float32))

    def _window_cov(self, frame, box, weights) -> np.ndarray | None:
        p = self.params
        lv = self._level(frame, weights)
        return cs.window_covariance(lv, box, kind=p.features, gray=self.gray)

    def _set_cov_model(self) -> None:
        self.cov_model = cv.SPDModel.from_log(cv.spd_log(np.stack(self.cov_history)).mean(axis=0))

    def _weights_from(self, pw: np.ndarray) -> np.ndarray | None:
        p = self.params
        if p.foreground == "none":
            return None
        if p.foreground == "soft":
            return pw
        return (pw >= p.fg_threshold).astype(np.float32)

    def _local_weights(self, frame: np.ndarray) -> np.ndarray | None:
        """Frame-sized foreground weights from the local back-projection (zero outside its region)."""
        if self.params.foreground == "none":
            return None
        joint, (x0, y0), pw = self._last_region
        full = np.zeros(frame.shape[:2], np.float32)
        full[y0:y0 + pw.shape[0], x0:x0 + pw.shape[1]] = self._weights_from(pw)
        return full

    def _global_weights(self, frame: np.ndarray) -> np.ndarray | None:
        p = self.params
        if p.foreground == "none":
            return None
        idx, sizes = self._pair_index(self.pair)
        bins = self._bins(frame, self.pair)
        joint = fs.joint_index(bins, tuple(range(len(idx))), sizes)
        pd = fs.division_histogram(self.H_m, fs.joint_histogram(joint, self._n_joint), delta=p.delta)
        return self._weights_from(fs.backproject(pd, joint))

    def _global(self, frame: np.ndarray) -> cs.SearchResult:
        p = self.params
        self.n_global += 1
        weights = self._global_weights(frame)
        lv = self._level(frame, weights, rescale=True)
        res = cs.search(frame, self.cov_model, tuple(self.size), kind=p.features, gray=self.gray,
                        refine_pitch=self.pitch, refine_level=lv, weights=weights, scale_factors=tuple(p.scales),
                        coarse_side=p.coarse_side, coarse_stride=p.coarse_stride, refine_top=p.refine_top)
        if not np.isfinite(res.distance) and weights is not None:
            # a stale feature pair can leave no window with enough foreground (ch06.md P7): all pixels
            lv = self._level(frame, None)
            res = cs.search(frame, self.cov_model, tuple(self.size), kind=p.features, gray=self.gray,
                            refine_pitch=self.pitch, refine_level=lv, scale_factors=tuple(p.scales),
                            coarse_side=p.coarse_side, coarse_stride=p.coarse_stride, refine_top=p.refine_top)
        return res

    # -- the switching loop ------------------------------------------------------------------------
    def _accept(self, distance: float) -> bool:
        return bool(np.isfinite(distance)) and (not self.le_thresh.ready or distance <= self.le_thresh.threshold)

    def _verify(self, frame: np.ndarray, res: cs.SearchResult):
        """The first global candidate (by covariance distance) that passes the covariance test and, after a
        local mean shift from it, the local test: ``(centre, size, rho, H_c, d, d_le)`` or None.  With
        ``search_prior`` every candidate is verified and the one of highest posterior odds is taken.

        The global search proposes and the local tracker verifies, so a window whose covariance merely
        resembles the model (a weak test on small or plain targets) does not capture the tracker."""
        prior = self.params.search_prior > 0 and self._seen is not None
        best, best_odds = None, -np.inf
        for x, y, w, h, dist in res.candidates:
            if not self._accept(dist):
                break  # sorted by distance
            size = np.array([w, h])
            c, rho, H_c, _, _ = self._local(frame, np.array([x + w / 2, y + h / 2]), size)
            if self._passes(rho):
                found = c, size, rho, H_c, float(np.sqrt(max(1.0 - rho, 0.0))), float(dist)
                if not prior:
                    return found
                odds = self.loss.evaluate(rho) + float(self._log_prior(c))
                if odds > best_odds:
                    best, best_odds = found, odds
        return best

    def _log_prior(self, centre: np.ndarray) -> float:
        """``search_prior``'s log prior odds of a candidate centre (see the parameter)."""
        k0, c0, v0 = self._seen
        k = self.frame_index - k0
        fh, fw = self._frame_shape
        sd = 0.25 * float(self.size[0] + self.size[1]) * (0.5 + 0.1 * k)
        return float(reappearance_log_prior(np.asarray(centre)[None], c0 + k * v0, sd, fw * fh,
                                            self.params.search_prior)[0])

    def _update_at(self, frame: np.ndarray) -> TrackState:
        p = self.params
        self._new_frame(frame)
        if self.lost:
            return self._recover(frame)
        (c, rho, H_c, it, mass), size = self._local_step(frame)
        d = float(np.sqrt(max(1.0 - rho, 0.0)))
        occluded, confident, score = self._occlusion_test(rho, c, size)
        sudden = p.sudden_mass > 0 and (it >= p.max_iterations or (
            self.mass_stats.ready and mass < p.sudden_mass * self.mass_stats.mean))
        box = np.array([c[0] - size[0] / 2, c[1] - size[1] / 2, size[0], size[1]])
        C_loc = self._window_cov(frame, box, self._local_weights(frame))
        d_le = float(self.cov_model.distance(C_loc[None])[0]) if C_loc is not None else np.inf
        reason = "occlusion" if occluded else "motion" if sudden else None
        check = (reason is None and p.distraction_every > 0 and self.frame_index % p.distraction_every == 0
                 and self.le_thresh.ready)
        self.mode = "local"
        self.miss = 0 if reason is None else self.miss
        if reason is not None or check:
            res = self._global(frame)
            found = self._verify(frame, res)
            if found is not None:
                gc, gsize, grho, gH, gd, gdist = found
                far = bool(np.hypot(*(gc - c)) > 0.5 * min(size))
                # ``ambiguity``: among look-alikes a far candidate does not take over on an occlusion alarm
                doubtful = far and reason == "occlusion" and ambiguous(res.candidates, gc, gsize, gdist, p.ambiguity)
                if not doubtful and takes_over(reason, far=far, global_le=gdist, local_le=d_le, global_rho=grho,
                                               local_rho=rho, occlusion_take=p.occlusion_take,
                                               distraction_bar=p.distraction_margin * self.le_thresh.sd):
                    if reason is None:
                        reason = "distraction"
                    c, size, rho, H_c, d, d_le = gc, gsize, grho, gH, gd, gdist
                    self.mode = "global"
                    self.miss = 0
            if reason is not None and self.mode != "global":
                if not occluded:
                    reason = None  # a sudden-motion alarm the search did not confirm: keep the local result
                else:
                    self.miss += 1
        self.lost = self.miss >= p.lost_frames
        prev = self.c
        if not self.lost:
            self.c, self.size = np.asarray(c, dtype=np.float64), np.asarray(size, dtype=np.float64)
        self.rho, self.d, self.iterations = rho, d, it
        self.vel = np.zeros(2)  # extrapolate (predict) only from a confident local frame
        if self.mode == "global":
            score = confidence(self.loss.evaluate(rho))
        elif confident and reason is None:
            self.vel = self.c - prev
            self._seen = (self.frame_index, self.c.copy(), self.vel.copy())
            self._learn(frame, d_le, C_loc, H_c, mass)
        return self._state(score=score, info={"pair": self.pair, "d": d, "d_le": d_le, "mode": self.mode,
                                              "switch": reason, "llr": self.loss.llr,
                                              "le_threshold": self.le_thresh.threshold})

    def _learn(self, frame, d_le, C_loc, H_c, mass) -> None:
        """Confident local frame: statistics, covariance model (Eq. 31), H_m (Eq. 21), reselection."""
        p = self.params
        self.mass_stats.push(mass)
        if C_loc is not None and np.isfinite(d_le):
            self.le_thresh.push(d_le)
            self.cov_history.append(C_loc)
            self._set_cov_model()
        self._update_model(frame, H_c)
        if p.reselect_every and self.frame_index % p.reselect_every == 0:
            self._reselect(frame)

    def _recover(self, frame: np.ndarray) -> TrackState:
        """While lost: the local tracker keeps following its mode (the box it reports) and the global
        search runs every frame; the loss ends when a candidate passes the covariance and local tests."""
        res = self._global(frame)
        self.mode = "global"
        found = self._verify(frame, res)
        c, rho, H_c, _, _ = self._local(frame, self.c, self.size)  # the target may reappear where it was left
        if found is None or rho >= found[2]:
            self.c, self.rho = c, rho
            ok = self._passes(rho)
        else:
            self.c, self.size, self.rho = found[0], found[1], found[2]
            ok = True
        self.d = float(np.sqrt(max(1.0 - self.rho, 0.0)))
        self.vel = np.zeros(2)
        if ok:
            self.lost, self.miss = False, 0
            self.loss.acquire(self.rho)
        return self._state(score=confidence(self.loss.evaluate(self.rho)),
                           info={"pair": self.pair, "d_le": res.distance, "mode": "global",
                                 "switch": "recovered" if ok else "absent"})
