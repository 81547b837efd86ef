"""``fs-meanshift``: mean shift on the back-projection of the two most discriminative features,
reselected online (book ch. 6 §3; Collins, Liu & Leordeanu 2005; Wang & Yagi 2008).

Per frame (ch06.md §1.11, local mode):

1. the two selected features are binned over the search region (the box x ``search_scale``);
   the target model ``H_m`` divided by the region's histogram (Eq. 18) is back-projected;
2. damped mean shift on that weight image (Eqs. 19-20), at most 15 iterations; by default
   (``refine_radius``) the mode is then moved to the centre of highest ``rho`` on a small grid
   around it (the mode of the back-projection leans towards the target's most discriminative part);
3. the Bhattacharyya coefficient ``rho`` of the candidate's kernel histogram against ``H_m`` and
   its distance ``d = sqrt(1 - rho)`` (Eqs. 13-14);
4. the occlusion test (``occlusion_test``): by default the project's two-class loss test on
   ``rho`` (the target's history against the ``rho`` of 8 background windows around the box,
   :mod:`pftrack.filtering.loss`), the online stand-in for the chapter's Gaussian fitted to
   occluded frames; ``sigma`` is the spec's ``mu + 3 sigma`` of confident distances.  On
   confident frames the model is updated, ``H_m = (1 - s) H_i + s H_c`` (Eq. 21) with ``s`` the
   NCC of the current and initial grey patches;
5. every ``reselect_every`` frames the candidate features are re-ranked by their variance
   ratio (Eq. 12) and only the second one is replaced (§3.3.2); by default (``partner``) the
   second is ranked by the variance ratio of its joint histogram with the first, so that it is
   not a copy of the first (on grey frames R, G, B and ``Ieq`` are one intensity).

``lost`` is raised after ``lost_frames`` consecutive occluded frames; the tracker keeps following
its mode (the local tracker has no recovery: that is what ``switching`` adds).  The box size is fixed unless
``scale_step > 0`` (the chapter has no scale step in local mode, P11).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import cv2
import numpy as np

from ..cues import feature_selection as fs
from ..cues.intensity import equalization_lut, to_gray
from ..filtering.loss import LossDetector, confidence
from ..filtering.running_threshold import RunningThreshold
from ..geometry import Box
from ..params import Params, param
from .base import Tracker, TrackState
from .working_resolution import WORKING_RESOLUTION_DOC, WorkingResolution


@dataclass(frozen=True, kw_only=True)
class FSMeanShiftParams(Params):
    candidates: tuple[str, ...] = param(fs.FEATURES + ("Ieq",), doc=(
        "Candidate features (§1.1): the chapter's R, G, B, H, S, r, g, orient, plus 'Ieq' (the grey level after the "
        "frame's histogram equalisation, robust to lighting changes; chosen on the tune split, where it lifted "
        "switching's grey+lighting AUC from 0.26 to 0.32). candidates=R/G/B/H/S/r/g/orient is the literal chapter."))
    bins: int = param(12, ge=2, le=64, doc=(
        "m, bins per feature (ch. 6 L5504, L5541; orientation gets a 13th flat bin)."))
    n_features: int = param(2, ge=1, le=3, doc=(
        "Features in the joint histogram (Eq. 16). The chapter uses 2; 1 or 3 'gave worse performances' (C6.4)."))
    partner: Literal["single", "joint"] = param("joint", doc=(
        "How the features after the first are ranked. 'single': by their own variance ratio (Eq. 12, the chapter). "
        "'joint' (pftrack's default): by the variance ratio of the joint histogram with the first feature (Eq. 16's "
        "pair), so the second feature adds information instead of repeating the first (on grey frames R, G, B and "
        "Ieq are one intensity). Chosen on the tune split (55 sequences): switching 0.574 vs 0.511 (paired +0.063 "
        "+- 0.025), fs-meanshift 0.477 vs 0.438; the camouflage scenes 0.575 vs 0.163 (switching)."))
    reselect_every: int = param(10, ge=0, le=1000, doc=(
        "Frames between re-rankings by the variance ratio (Eq. 12); the chapter says 8-12. 0 never reselects."))
    replace: Literal["second", "all"] = param("second", doc=(
        "'second': only the second feature is replaced (§3.3.2, claim C6.5); 'all': take the new top pair."))
    delta: float = param(1e-3, gt=0, lt=1, doc="delta_L, the floor of Eq. 11's ratio (Collins et al. 2005).")
    llr_clip: float = param(1.0, gt=0, doc="The clamp of Eq. 11's log-likelihood ratio to [-1, 1].")
    grad_threshold: float = param(64.0, ge=0, doc=(
        "T_D of Eq. 6 in Scharr units (a unit ramp is 32): weaker gradients go to the flat orientation bin."))
    refine_radius: int = param(2, ge=0, le=10, doc=(
        "After mean shift, move to the centre of highest rho (Eqs. 13-14) on a grid of +-refine_radius steps "
        "(pftrack's addition; 0: the chapter's mode). Mean shift on the back-projection leans towards the target's "
        "most discriminative part. Chosen on the tune split (55 sequences): switching 0.641 vs 0.574 (paired +0.067 "
        "+- 0.021), fs-meanshift 0.588 vs 0.477 (+0.111 +- 0.027); on 67 fresh synthetic scenes of neither split "
        "switching +0.073 +- 0.021. A radius of 1 at steps of a tenth of the box: +0.033."))
    refine_step: float = param(0.05, gt=0, le=0.5, doc=(
        "Grid step of refine_radius, as a fraction of the box (>= 1 px)."))
    search_scale: float = param(2.5, ge=1.2, le=6, doc="R_b of Eq. 17: the search region is the box times this.")
    ring_inner: float = param(1.1, ge=1, le=3, doc="Background ring for Eq. 12: from the box times this ...")
    ring_outer: float = param(2.0, ge=1.2, le=5, doc="... to the box times this (ch06.md §1.3, proposed).")
    max_iterations: int = param(15, ge=1, le=100, doc="Mean-shift iterations (L5922: fewer than 15).")
    epsilon: float = param(0.5, gt=0, doc="Stop when the damped step is below this many pixels.")
    damping: float = param(0.5, gt=0, le=1, doc="Eq. 20: y1 <- y0 + damping (centroid - y0); the chapter's 1/2.")
    model_update: Literal["weighted", "fixed", "pooled"] = param("weighted", doc=(
        "'weighted': Eq. 21 H_m = (1 - s) H_i + s H_c with s = NCC(initial, current) (claim C6.6); 'fixed': H_m = "
        "H_i; 'pooled': Collins' H_m = (H_i + H_c)/2."))
    scale_step: float = param(0.0, ge=0, lt=0.5, doc=(
        "0: fixed size (the chapter). > 0: also try sizes (1 +- step) and keep the best rho, smoothed with gamma 0.1 "
        "(as meanshift)."))
    max_pixels: int = param(2000, ge=0, le=10_000_000, doc=WORKING_RESOLUTION_DOC + (
        " Chosen on the tune split (55 sequences): at 2000 the mean AUC equals full "
        "resolution's (fs-meanshift 0.438, paired +0.0001 +- 0.0003; switching 0.511, +0.0002 +- 0.0001; 1000 "
        "and 500 within 0.004), and davis16_dog runs at 505 instead of 92 fps (fs-meanshift)."))
    predict: bool = param(False, doc=(
        "Start each frame's mean shift from the position extrapolated by the last confident frame's displacement "
        "(constant velocity) instead of the last position (the chapter). Mean shift only climbs to the nearest "
        "mode, and its damped steps (Eq. 20) leave a moving target's centre behind."))
    occlusion_test: Literal["llr", "sigma"] = param("llr", doc=(
        "When the local result counts as occluded (and the model is not updated). 'llr' (default): the two-class "
        "test of pftrack.filtering.loss on rho, target history vs the rho of background windows around the box: the "
        "online stand-in for the chapter's Gaussian fitted to occluded frames' similarities (L6195-6198). 'sigma': "
        "d above mu + threshold_sigma x sigma of the confident frames' d (ch06.md §1.10 'online'); it deadlocks "
        "when the target's appearance drifts (the model stops updating, d stays high)."))
    background_offset: float = param(1.0, gt=0, le=5, doc=(
        "'llr': background windows sit this many box sizes from the box, at the 8 compass points."))
    reacquire_margin: float = param(1.0, ge=0, le=20, doc="'llr': LLR needed to count a frame as confident again.")
    score_sd_floor: float = param(0.03, gt=0, le=1, doc="'llr': floor of the target and background rho spreads.")
    threshold_window: int = param(30, ge=5, le=1000, doc="Confident frames in the online threshold's statistics.")
    threshold_sigma: float = param(3.0, gt=0, doc="The threshold is mu + this x sigma of d (L6197: 3 sigma).")
    threshold_floor: float = param(0.02, ge=0, doc="Floor on sigma of d.")
    lost_frames: int = param(3, ge=1, le=1000, doc="Consecutive frames above the threshold before lost is raised.")


class FSMeanShift(WorkingResolution, Tracker):
    """Local mode of the switching tracker: feature-selecting mean shift (deterministic)."""

    name = "fs-meanshift"
    Params = FSMeanShiftParams
    stochastic = False

    # -- working resolution (max_pixels): _init_at / _update_at (and the subclasses') see reduced frames ----
    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        zbox = self._set_resolution(frame, box, self.params.max_pixels)
        st = self._init_at(self._zoomed(frame), zbox)
        return TrackState(box=tuple(float(v) for v in box), score=st.score, lost=st.lost, info=st.info)

    def _update(self, frame: np.ndarray) -> TrackState:
        return self._update_at(self._zoomed(frame))

    # -- initialisation ------------------------------------------------------------------------
    def _init_at(self, frame: np.ndarray, box: Box) -> TrackState:
        p = self.params
        x, y, w, h = box
        self.c = np.array([x + w / 2.0, y + h / 2.0])
        self.size = np.array([float(w), float(h)])
        fh, fw = frame.shape[:2]
        bad = [f for f in p.candidates if f not in fs.FEATURES + fs.EXTRA_FEATURES]
        if bad or len(set(p.candidates)) < p.n_features:
            raise ValueError(f"candidates: unknown or too few features {p.candidates!r}")
        self.candidates = tuple(p.candidates)
        self._new_frame(frame)
        # the initial neighbourhood (object + ring), binned for every candidate feature, kept for H_i
        reg = self._region(self.c, self.size * p.ring_outer, fw, fh)
        x0, y0, x1, y1 = reg
        self._init_bins = self._bins(frame[y0:y1, x0:x1], self.candidates)
        self._init_origin = (x0, y0)
        self._init_kernel = fs.epanechnikov(y1 - y0, x1 - x0, self.c[0] - x0, self.c[1] - y0, w / 2, h / 2)
        obj, ring = fs.ring_masks((y1 - y0, x1 - x0), box, inner=p.ring_inner, outer=p.ring_outer, origin=(x0, y0))
        self.pair = self._choose(self._init_bins, obj, ring, None)
        self._set_pair(self.pair, current=None)
        self._tshape = _template_shape(w, h)
        self._init_patch = self._patch(frame, self.c, self.size)
        self.thresh = RunningThreshold(window=p.threshold_window, k=p.threshold_sigma, sd_floor=p.threshold_floor)
        self.loss = LossDetector(lost_frames=p.lost_frames, reacquire_margin=p.reacquire_margin,
                                 sd_floor_target=p.score_sd_floor, sd_floor_background=p.score_sd_floor)
        self.miss = 0
        self.lost = False
        self.vel = np.zeros(2)  # displacement of the last confident frame (used with predict)
        self.rho = 1.0
        self.d = 0.0
        self.iterations = 0
        return TrackState(box=tuple(float(v) for v in box), score=1.0, lost=False, info={"pair": self.pair})

    def _new_frame(self, frame: np.ndarray) -> None:
        # the equalisation table of "Ieq" is computed on the first use in this frame (most frames bin other features)
        self._frame, self._eq_lut = frame, None

    def _bins(self, region: np.ndarray, names) -> np.ndarray:
        p = self.params
        if self._eq_lut is None and "Ieq" in names:
            self._eq_lut = equalization_lut(self._frame)
        return fs.bin_images(region, names, bins=p.bins, grad_threshold=p.grad_threshold, eq_lut=self._eq_lut)

    @staticmethod
    def _region(c, extent, fw, fh) -> tuple[int, int, int, int]:
        x0 = int(np.floor(c[0] - extent[0] / 2))
        y0 = int(np.floor(c[1] - extent[1] / 2))
        x1 = int(np.ceil(c[0] + extent[0] / 2))
        y1 = int(np.ceil(c[1] + extent[1] / 2))
        return max(x0, 0), max(y0, 0), min(max(x1, 1), fw), min(max(y1, 1), fh)

    def _pair_index(self, pair) -> tuple[tuple[int, ...], tuple[int, ...]]:
        idx = tuple(self.candidates.index(f) for f in pair)
        sizes = tuple(fs.n_bins(f, self.params.bins) for f in pair)
        return idx, sizes

    def _choose(self, bins: np.ndarray, obj: np.ndarray, ring: np.ndarray, previous) -> tuple[str, ...]:
        """The features to use (§3.3.2): the first by Eq. 12 alone (or kept), the others by ``partner``."""
        p = self.params
        ranking, self.vr = fs.rank_features(bins, obj, ring, self.candidates, n=p.bins, delta=p.delta, clip=p.llr_clip)
        pair = fs.select_pair(previous, ranking, k=p.n_features, replace=p.replace)
        if p.partner == "joint" and len(pair) > 1:
            partners, _ = fs.rank_partners(bins, obj, ring, self.candidates, pair[0], n=p.bins, delta=p.delta,
                                           clip=p.llr_clip)
            pair = (pair[0], *partners[:p.n_features - 1])
        return pair

    def _set_pair(self, pair, current: np.ndarray | None) -> None:
        """Select ``pair``: H_i from the stored initial crop; H_m from H_i and the current histogram."""
        self.pair = tuple(pair)
        idx, sizes = self._pair_index(pair)
        self._sizes = sizes
        self._n_joint = int(np.prod(sizes))
        joint0 = fs.joint_index(self._init_bins, idx, sizes)
        self.H_i = fs.joint_histogram(joint0, self._n_joint, self._init_kernel)
        self.H_m = self.H_i.copy() if current is None else current

    def _patch(self, frame: np.ndarray, c, size) -> np.ndarray:
        """The grey NCC patch of the box of ``size`` at ``c`` (only the box's pixels are converted to grey)."""
        w, h = size
        x0, y0 = int(round(c[0] - w / 2)), int(round(c[1] - h / 2))
        fh, fw = frame.shape[:2]
        x1, y1 = min(max(x0 + int(round(w)), 1), fw), min(max(y0 + int(round(h)), 1), fh)
        x0, y0 = min(max(x0, 0), x1 - 1), min(max(y0, 0), y1 - 1)
        crop = to_gray(frame[y0:y1, x0:x1])
        return cv2.resize(crop, self._tshape[::-1], interpolation=cv2.INTER_AREA).astype(np.float32)

    # -- one local step ----------------------------------------------------------------------------
    def _local(self, frame: np.ndarray, start: np.ndarray, size: np.ndarray):
        """Mean shift from ``start`` at ``size``: returns ``(centre, rho, H_c, iterations, mass)``."""
        p = self.params
        fh, fw = frame.shape[:2]
        x0, y0, x1, y1 = self._region(start, size * p.search_scale, fw, fh)
        idx, sizes = self._pair_index(self.pair)
        bins = self._bins(frame[y0:y1, x0:x1], self.pair)
        joint = fs.joint_index(bins, tuple(range(len(idx))), sizes)
        zeta_b = fs.joint_histogram(joint, self._n_joint)
        pw = fs.backproject(fs.division_histogram(self.H_m, zeta_b, delta=p.delta), joint)
        c, it, mass = fs.weighted_meanshift(pw, start, size / 2, origin=(x0, y0), max_iter=p.max_iterations,
                                            eps=p.epsilon, damping=p.damping)
        if p.refine_radius > 0:
            c = fs.refine_centre(joint, self.H_m, (x0, y0), c, size, radius=p.refine_radius, step=p.refine_step)
        H_c = self._kernel_hist(joint, (x0, y0), c, size)
        rho = float(np.sum(np.sqrt(H_c * self.H_m)))
        self._last_region = (joint, (x0, y0), pw)
        return c, rho, H_c, it, mass

    def _kernel_hist(self, joint, origin, c, size) -> np.ndarray:
        """Kernel-weighted joint histogram (Eq. 16) of the ellipse of ``size`` at ``c`` (pixels of ``joint``
        only: a window partly outside the region uses its inside part)."""
        i0, j0, i1, j1, cx, cy = fs.kernel_window(joint.shape, c[0] - origin[0], c[1] - origin[1], size[0], size[1])
        if i1 <= i0 or j1 <= j0:
            return np.zeros(self._n_joint)
        return fs.kernel_histogram(joint, self._n_joint, (i0, j0, i1, j1), cx, cy, size[0] / 2, size[1] / 2)

    def _background_rho(self, c, size) -> np.ndarray:
        """rho of the model at the 8 windows ``background_offset`` box sizes around ``c`` (last region)."""
        joint, origin, _ = self._last_region
        off = self.params.background_offset
        centres = [(c[0] + dx * off * size[0] - origin[0], c[1] + dy * off * size[1] - origin[1])
                   for dx in (-1, 0, 1) for dy in (-1, 0, 1) if dx or dy]
        rho = fs.kernel_rhos_at(joint, self.H_m, np.array(centres), size[0], size[1])
        return rho[np.isfinite(rho)]

    def _passes(self, rho: float) -> bool:
        """Would a candidate with this rho count as the target (no state change)?"""
        if self.params.occlusion_test == "sigma":
            return not self.thresh.exceeds(float(np.sqrt(max(1.0 - rho, 0.0))))
        return self.loss.evaluate(rho) > self.params.reacquire_margin

    def _occlusion_test(self, rho: float, c, size) -> tuple[bool, bool, float]:
        """``(occluded, confident, score)`` of the local result (see ``occlusion_test``)."""
        p = self.params
        d = float(np.sqrt(max(1.0 - rho, 0.0)))
        if p.occlusion_test == "sigma":
            bad = self.thresh.exceeds(d)
            if not bad:
                self.thresh.push(d)
            return bad, not bad, rho
        bg = self._background_rho(c, size)
        if bg.size:
            self.loss.set_background(bg)
        self.loss.step(rho)
        return self.loss.llr < 0.0, self.loss.confident(rho), confidence(self.loss.llr)

    def _local_step(self, frame: np.ndarray):
        p = self.params
        start = self.c + self.vel if p.predict else self.c
        best = self._local(frame, start, self.size)
        size = self.size
        if p.scale_step > 0:
            for f in (1.0 - p.scale_step, 1.0 + p.scale_step):
                cand = self._local(frame, start, self.size * f)
                if cand[1] > best[1] + 1e-12:
                    best, size = cand, self.size * f
            size = 0.1 * size + 0.9 * self.size  # Comaniciu's gamma = 0.1, as meanshift
        return best, size

    def _update_model(self, frame: np.ndarray, H_c: np.ndarray) -> None:
        p = self.params
        if p.model_update == "fixed":
            self.H_m = self.H_i
        elif p.model_update == "pooled":
            self.H_m = 0.5 * (self.H_i + H_c)
        else:
            cur = self._patch(frame, self.c, self.size)
            s = float(cv2.matchTemplate(cur, self._init_patch, cv2.TM_CCOEFF_NORMED)[0, 0])
            s = min(max(s if np.isfinite(s) else 0.0, 0.0), 1.0)
            self.H_m = (1.0 - s) * self.H_i + s * H_c
            self.similarity = s

    def _reselect(self, frame: np.ndarray) -> None:
        p = self.params
        fh, fw = frame.shape[:2]
        x0, y0, x1, y1 = self._region(self.c, self.size * p.ring_outer, fw, fh)
        bins = self._bins(frame[y0:y1, x0:x1], self.candidates)
        box = (self.c[0] - self.size[0] / 2, self.c[1] - self.size[1] / 2, self.size[0], self.size[1])
        obj, ring = fs.ring_masks((y1 - y0, x1 - x0), box, inner=p.ring_inner, outer=p.ring_outer, origin=(x0, y0))
        pair = self._choose(bins, obj, ring, self.pair)
        if pair != self.pair:
            idx, sizes = self._pair_index(pair)
            joint = fs.joint_index(bins, idx, sizes)
            self._set_pair(pair, current=None)
            H_c = self._kernel_hist(joint, (x0, y0), self.c, self.size)
            self._update_model(frame, H_c)

    # -- protocol ----------------------------------------------------------------------------------
    def _update_at(self, frame: np.ndarray) -> TrackState:
        p = self.params
        self._new_frame(frame)
        (c, rho, H_c, it, mass), size = self._local_step(frame)
        prev = self.c
        self.c, self.size = c, np.asarray(size, dtype=np.float64)
        self.rho, self.iterations = rho, it
        self.d = float(np.sqrt(max(1.0 - rho, 0.0)))
        occluded, confident, score = self._occlusion_test(rho, c, self.size)
        self.miss = self.miss + 1 if occluded else 0
        self.lost = self.miss >= p.lost_frames
        self.vel = np.asarray(c - prev, dtype=np.float64) if confident else np.zeros(2)
        if confident:
            self._update_model(frame, H_c)
            if p.reselect_every and self.frame_index % p.reselect_every == 0:
                self._reselect(frame)
        return self._state(score=score, info={"pair": self.pair, "d": self.d, "rho": rho, "iterations": it,
                                              "llr": self.loss.llr})

    def _state(self, *, info: dict, score: float | None = None) -> TrackState:
        """The state in frame coordinates (the tracker works at the reduced resolution of max_pixels)."""
        w, h = self._to_frame(self.size[0]), self._to_frame(self.size[1])
        fh, fw = self._shape
        cx = float(np.clip(self._to_frame(self.c[0]), 0, fw))
        cy = float(np.clip(self._to_frame(self.c[1]), 0, fh))
        box = (cx - w / 2, cy - h / 2, float(w), float(h))
        return TrackState(box=box, score=float(np.clip(self.rho if score is None else score, 0, 1)), lost=self.lost,
                          info=info)


def _template_shape(w: float, h: float, pixels: int = 1024) -> tuple[int, int]:
    """(rows, cols) of the NCC patch: the box's aspect with about ``pixels`` pixels (at most its own)."""
    f = min(1.0, float(np.sqrt(pixels / max(w * h, 1.0))))
    return max(4, int(round(h * f))), max(4, int(round(w * f)))
