"""``multi-pf``: colour particle filters for several targets (Sugandi et al.) with detection-driven life cycle.

B. Sugandi, H. Kim, J. K. Tan, S. Ishikawa, "A color-based particle filter for
multiple objects tracking in outdoor environment" — ``shared/seeds/001_*.txt``.

Per target ``l`` (of ``L``): a colour model ``q_l`` (RGB 8x8x8 kernel histogram, Eqs. 5–9)
and particles with state ``(x, y, vx, vy, w, h, vw, vh)`` — position, speed, box size and its
rate — under constant-velocity dynamics (Eq. 4).  Each frame:

1. **Detections** (``motion`` frame differencing, ``mog2`` background subtraction, ``hog``
   people detector, or any callable) are associated one-to-one with the tracks' predicted
   boxes by IoU and colour (Hungarian assignment).  With occlusion handling, a detection
   that covers several distinct targets' predicted boxes is a merged blob of targets
   occluding each other: unless one member fits it alone (it is in front and takes it), it
   is the detection of none, so no box is pulled over the whole group; the members without
   a detection stay reported for up to ``max_occluded`` frames and follow their own colours
   with their sizes frozen until the blob splits.
2. **Weights**: colour likelihood (Eq. 10) times, when the track has a detection this frame,
   a Gaussian term around the detected box; all targets' samples form one pool, and the
   weights are **normalised per target to 1/L** (Eq. 11) so that no target absorbs the
   others' samples (``normalize="global"`` normalises the pool as a whole — the ablation).
3. **Predicted occlusion** (§3.7, optional: ``occlusion_predict``): when two predicted
   centres are closer than ``R`` (Eq. 15), the target whose maximum sample likelihood fell
   most below its recent history is the occluded one.  While occluded its adaptation rates
   are 0 (it moves at constant velocity), its samples are propagated but not resampled, and
   neither its colour model nor its size is updated.  It leaves the state when the
   occlusion is no longer predicted or its likelihood recovers.
4. **Estimate** with adaptation rates (Eq. 12):
   ``x = (1 - a_x)(x + vx) + a_x x_meas``, ``vx = (1 - a_v) vx + a_v (x - x_prev)``, and
   likewise for the size.
5. **Model update** gated by the expected likelihood ``lambda = (1 - a_u) lambda + a_u pi_est``
   (Eqs. 13–14): ``q = (1 - a_q) q + a_q p_est`` when ``pi_est > lambda`` and not occluded.
6. **Life cycle**: a detection that no track explains for ``birth_frames`` consecutive frames
   becomes a confirmed track with a new identity (identities are never reused); a track
   dies after ``max_misses`` frames without a detection (``max_occluded`` while occluded)
   or when it leaves the image.

Every threshold is a documented parameter (``MultiPFParams``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import cv2
import numpy as np

from ..cues.color import reachable_roi, warmup
from ..cues.contrast import (
    box_counts,
    contrast_scores,
    foreground_lut,
    probability_integral,
)
from ..cues.histogram_cue import ColorCue, ColorFeatures
from ..cues.still_gain import frame_undo
from ..errors import ParameterError
from ..frames import as_bgr_uint8
from ..geometry import in_frame_fraction as _inside_fraction
from ..geometry import iou_matrix
from .detectors import as_detector, create_detector
from .identify import IdentityMemory, person_features
from .multi_params import MultiPFParams
from .read_ahead import ReadAhead
from .track_state import Candidate as _Candidate
from .track_state import Track as _Track
from .track_state import box_to_state as _box_to_state
from .track_state import cut_features as _cut
from .track_state import ellipses as _ellipses
from .track_state import gate_merged_detections
from .track_state import mark_occlusions
from .track_state import state_boxes as _state_boxes

STATE_NAMES = ("x", "y", "vx", "vy", "w", "h", "vw", "vh")


@dataclass
class TrackOutput:
    """One reported target in one frame."""

    track_id: int
    box: tuple[float, float, float, float]
    score: float
    occluded: bool


class MultiPF(ReadAhead):
    """Multi-target colour particle filter (see the module docstring)."""

    name = "multi-pf"
    Params = MultiPFParams

    def __init__(self, params: MultiPFParams | None = None, *, seed: int | None = None,
                 rng: np.random.Generator | None = None, detector_fn: Callable | None = None):
        self.params = params or MultiPFParams()
        p = self.params
        self.rng = rng if rng is not None else np.random.default_rng(seed)
        if detector_fn is not None:
            self.detector = as_detector(detector_fn)
        else:
            extra = {"split_aspect": p.object_aspect} if p.detector in ("mog2", "motion") else {}
            extra |= {"grey_shadow_threshold": p.grey_shadow_threshold, "dark_stretch": p.dark_stretch,
                      "dark_denoise": p.dark_denoise} if p.detector == "mog2" else {}
            self.detector = create_detector(p.detector, **extra)
        # frames the caller reads ahead for prime() (a detector that learns a background)
        self.bootstrap_frames = p.bootstrap_frames if hasattr(self.detector, "prime") else 0
        self._group_merges = p.group_merges == "on" or (
            p.group_merges == "auto" and (detector_fn is not None or p.detector != "motion"))
        self.cue = ColorCue("rgb", (8, 8, 8), "nummiaro", p.max_pixels)
        warmup()
        self.tracks: list[_Track] = []
        self.candidates: list[_Candidate] = []
        self.next_id = 1
        self.identities = IdentityMemory(threshold=self.params.identify_threshold, memory=self.params.identify_memory)
        self.frame_index = 0
        self._shape: tuple[int, int] | None = None
        # frames with their jumps of the light undone (cast_jump, light_jump)
        self._cast = frame_undo(p)

    # ------------------------------------------------------------------ helpers
    def _histogram(self, frame: np.ndarray, box, stored: ColorFeatures | None = None) -> np.ndarray:
        """Colour histogram of a box's ellipse (:meth:`ColorCue.histogram`); its region is cut from ``stored``
        when that covers it."""
        st = _box_to_state(box)
        e = _ellipses(st[None, :])
        feats = None
        if stored is not None:
            h, w = self._shape
            feats = _cut(stored, reachable_roi(e, w, h), self.cue.step_for(e), self._shape)
        if feats is None:
            return self.cue.histogram(frame, e[0])
        hist, _ = self.cue.histograms(feats, e, reuse=False)
        return hist[0]

    def _rho(self, frame: np.ndarray, states: np.ndarray, sqrt_q: np.ndarray, margin: float = 0.0,
             stored: ColorFeatures | None = None, own: bool = False):
        """Colour coefficients of a batch of states, and the quantised region (with ``margin`` x size around),
        cut from ``stored`` (this frame's features of a larger region) when that covers it.  The region's bins
        are the cue's shared buffer, valid until its next ``prepare``, unless ``own`` (then a new array)."""
        h, w = self._shape
        ell = _ellipses(states)
        mx = 2 * margin * float(ell[:, 2].max()) + 1
        my = 2 * margin * float(ell[:, 3].max()) + 1
        x0 = int(max(math.floor(float((ell[:, 0] - ell[:, 2]).min()) - mx), 0))
        y0 = int(max(math.floor(float((ell[:, 1] - ell[:, 3]).min()) - my), 0))
        x1 = int(min(math.ceil(float((ell[:, 0] + ell[:, 2]).max()) + mx), w))
        y1 = int(min(math.ceil(float((ell[:, 1] + ell[:, 3]).max()) + my), h))
        roi, pitch = (x0, y0, max(x1, x0), max(y1, y0)), self.cue.step_for(ell)
        feats = _cut(stored, roi, pitch, self._shape)
        if feats is None:
            feats = self.cue.prepare(frame, roi, pitch)
            if own:
                feats = ColorFeatures(feats.bins.copy(), feats.x0, feats.y0, feats.pitch)
        rho, tot = self.cue.rho(feats, ell, sqrt_q, reuse=False)
        return rho, tot, feats

    def _contrast_model(self, feats, tr: _Track, box, rate: float | None) -> None:
        obj, sur = box_counts(feats.bins, feats.x0, feats.y0, box, self.cue.n_bins, ring=self.params.ring,
                              pitch=feats.pitch)
        if obj.sum() <= 0:
            return
        if rate is None or tr.obj is None:
            tr.obj, tr.sur = obj, sur
        else:
            tr.obj = (1 - rate) * tr.obj + rate * obj * (tr.obj.sum() / obj.sum())
            if sur.sum() > 0 and tr.sur.sum() > 0:
                tr.sur = (1 - rate) * tr.sur + rate * sur * (tr.sur.sum() / sur.sum())
        tr.lut = foreground_lut(tr.obj, tr.sur)

    def _new_track(self, frame: np.ndarray, box, velocity=(0.0, 0.0)) -> _Track:
        p = self.params
        q = self._histogram(frame, box)
        st = _box_to_state(box)
        st[2:4] = velocity
        parts = np.tile(st, (p.n_particles, 1))
        tid = None
        if p.identify:
            h, w = frame.shape[:2]
            tid = self.identities.recall(person_features(frame, box), self.frame_index, w, h)
        tr = _Track(self.next_id if tid is None else tid, st, parts, q, np.sqrt(q))
        if p.contrast_gain > 0:
            _, _, feats = self._rho(frame, st[None, :], tr.sqrt_q, margin=p.ring)
            self._contrast_model(feats, tr, box, None)
        if tid is None:
            self.next_id += 1
        return tr

    def _noise(self, n: int, w: float, h: float) -> np.ndarray:
        p = self.params
        std = np.array([p.position_noise * w, p.position_noise * h, p.velocity_noise * w, p.velocity_noise * h,
                        p.size_noise * w, p.size_noise * h, p.size_rate_noise * w, p.size_rate_noise * h])
        return self.rng.standard_normal((n, 8)) * std

    # ------------------------------------------------------------------ the frame
    def update(self, frame: np.ndarray) -> list[TrackOutput]:
        """Process one frame; returns the reported targets."""
        frame = as_bgr_uint8(frame, where=f"frame {self.frame_index + 1}")
        h, w = frame.shape[:2]
        if self._shape is None:
            self._shape = (h, w)
        elif self._shape != (h, w):
            from ..errors import FrameError

            raise FrameError(f"frame {self.frame_index + 1}: size {w}x{h} differs from the first frame's "
                             f"{self._shape[1]}x{self._shape[0]}", index=self.frame_index + 1)
        self.frame_index += 1
        p = self.params
        if self._cast is not None:
            frame = self._cast(frame)
        dets = self.detector(frame)
        dets = dets[(dets[:, 2] >= p.min_size) & (dets[:, 3] >= p.min_size)] if len(dets) else dets
        fg = getattr(self.detector, "foreground", None) if p.foreground_gain > 0 else None
        fg_ii = fg_scale = None
        if fg is not None:
            fg_ii = cv2.integral((fg[0] > 0).astype(np.float32)).astype(np.float64)
            fg_scale = fg[1]
        # 1. predict every track (constant velocity) and associate detections
        for tr in self.tracks:
            tr.age += 1
            tr.feats = None
            pred = tr.state.copy()
            pred[0:2] += pred[2:4]
            pred[4:6] += pred[6:8]
            tr.pred = pred
        used = self._associate(frame, dets)
        # 2. propagate, weigh
        for tr in self.tracks:
            n = tr.particles.shape[0]
            if n == 0:
                continue
            s = tr.particles
            s[:, 0:2] += s[:, 2:4]
            s[:, 4:6] += s[:, 6:8]
            s += self._noise(n, max(tr.state[4], p.min_size), max(tr.state[5], p.min_size))
            if tr.det is not None and p.detection_proposal > 0:
                k = int(round(p.detection_proposal * n))
                if k:
                    d = _box_to_state(tr.det[:4])
                    pick = self.rng.choice(n, size=k, replace=False)
                    s[pick, 0:2] = d[0:2]
                    s[pick, 4:6] = d[4:6]
                    s[pick] += self._noise(k, d[4], d[5]) * np.array([0.5, 0.5, 0, 0, 0.5, 0.5, 0, 0])
            np.maximum(s[:, 4:6], p.min_size, out=s[:, 4:6])
            rho, tot, feats = self._rho(frame, s, tr.sqrt_q, margin=p.ring if p.contrast_gain > 0 else 0.0, own=True)
            tr.feats = feats  # this frame's region of the track: the estimate's features are cut from it
            ll = -(1.0 - rho) / (2.0 * p.sigma ** 2)
            ll[tot <= 0] = -np.inf
            colour_max = float(np.exp(np.max(ll))) if np.isfinite(ll).any() else 0.0
            if p.contrast_gain > 0 and tr.lut is not None:
                ii = probability_integral(feats.bins, tr.lut)
                ll = ll + p.contrast_gain * contrast_scores(ii, feats.x0, feats.y0, _state_boxes(s), ring=p.ring,
                                                            pitch=feats.pitch)
            if fg_ii is not None:
                ll = ll + p.foreground_gain * contrast_scores(fg_ii, 0, 0, _state_boxes(s) / fg_scale, ring=p.ring,
                                                              outside=0.0)
            if tr.det is not None:
                d = tr.det
                dcx, dcy = d[0] + d[2] / 2, d[1] + d[3] / 2
                z = (((s[:, 0] - dcx) / d[2]) ** 2 + ((s[:, 1] - dcy) / d[3]) ** 2
                     + ((s[:, 4] - d[2]) / d[2]) ** 2 + ((s[:, 5] - d[3]) / d[3]) ** 2)
                ll = ll - z / (2.0 * p.detection_sigma ** 2)
            tr.log_lik = ll
            tr.max_lik = colour_max
        # 3. occlusion reasoning (Eq. 15 and §3.7)
        if p.occlusion and p.occlusion_predict:
            self._occlusions()
        # 4. weights (Eq. 11), resampling of the non-occluded pool, estimates (Eq. 12), model updates (Eqs. 13-14)
        self._weigh_and_resample()
        for tr in self.tracks:
            self._estimate(frame, tr)
        # 5. life cycle
        if p.identify:
            for tr in self.tracks:
                if tr.det is not None:
                    tr.features = person_features(frame, tr.box)
        self._births(frame, dets, used)
        self._deaths()
        out = []
        for tr in self.tracks:
            if tr.misses <= p.report_misses or tr.grouped or (tr.occluded and p.report_occluded):
                out.append(TrackOutput(tr.id, tuple(float(v) for v in tr.box), float(tr.score), tr.occluded))
        return out

    def _associate(self, frame: np.ndarray, dets: np.ndarray) -> np.ndarray:
        """One-to-one association of detections with the tracks' predicted boxes (sets ``track.det``).

        Hungarian assignment on ``(1 - IoU) + appearance_weight * (1 - rho)`` among the pairs with
        ``IoU >= match_iou``; rho is the Bhattacharyya coefficient between the track's colour model and
        the detection's histogram.  Occluded tracks take part: a detection ends their occlusion.
        Returns the mask of the detections used.
        """
        p = self.params
        used = np.zeros(len(dets), bool)
        for tr in self.tracks:
            tr.det = None
            tr.grouped = False
        live = list(self.tracks)
        if not len(dets) or not live:
            return used
        from scipy.optimize import linear_sum_assignment

        pred_boxes = _state_boxes(np.array([t.pred for t in live]))
        m = iou_matrix(pred_boxes, dets[:, :4])
        gate = m >= p.match_iou
        if p.occlusion and self._group_merges and len(live) > 1:
            grouped = gate_merged_detections(pred_boxes, dets[:, :4], m, gate, used, p.group_cover, p.group_fit,
                                             p.match_iou)
            for i, g in grouped.items():
                live[i].grouped = g
        if not gate.any():
            return used
        cost = 1.0 - m
        if p.appearance_weight > 0:  # the colour term of the detections some track may take (the others cost 1e6)
            cols = np.flatnonzero(gate.any(axis=0))
            sq = np.sqrt(np.stack([self._histogram(frame, dets[j, :4]) for j in cols]))
            # no BLAS: reproducible
            rho = (np.stack([t.sqrt_q for t in live])[:, None, :] * sq[None, :, :]).sum(axis=-1)
            cost[:, cols] = cost[:, cols] + p.appearance_weight * (1.0 - rho)
        rows, cols = linear_sum_assignment(np.where(gate, cost, 1e6))
        for r, c in zip(rows, cols):
            if gate[r, c]:
                live[r].det = dets[c]
                used[c] = True
        return used

    def _occlusions(self) -> None:
        mark_occlusions(self.tracks, self.params.occlusion_radius, self.params.occlusion_drop)

    def _weigh_and_resample(self) -> None:
        p = self.params
        active = [t for t in self.tracks if not t.occluded and t.particles.shape[0] > 0]
        if not active:
            return
        L = len(active)
        logs = []
        for t in active:
            ll = t.log_lik
            if p.normalize == "per-target":
                m = np.max(ll) if np.isfinite(ll).any() else 0.0
                w = np.exp(ll - m) if np.isfinite(ll).any() else np.ones_like(ll)
                w = w / w.sum() / L  # Eq. 11: each target's weights sum to 1/L
                logs.append(np.log(np.maximum(w, 1e-300)))
            else:
                logs.append(ll)
        pool = np.concatenate(logs)
        # each target's samples are one block of the pool: bounds[k]:bounds[k + 1]
        bounds = np.cumsum([0] + [t.particles.shape[0] for t in active])
        finite = np.isfinite(pool)
        pool = np.where(finite, pool, -np.inf)
        m = np.max(pool[finite]) if finite.any() else 0.0
        wts = np.where(finite, np.exp(pool - m), 0.0)
        if wts.sum() <= 0:
            wts = np.ones_like(wts)
        wts /= wts.sum()
        # estimates from each target's own (normalised) weights before resampling
        for k, t in enumerate(active):
            wk = wts[bounds[k]:bounds[k + 1]]
            t.meas = ((wk / wk.sum())[:, None] * t.particles).sum(axis=0) if wk.sum() > 0 else t.pred.copy()
        total = int(bounds[-1])
        u = (np.arange(total) + self.rng.random()) / total  # systematic over the pool
        idx = np.searchsorted(np.cumsum(wts), u, side="left")
        np.minimum(idx, total - 1, out=idx)
        states = np.concatenate([t.particles for t in active])
        # idx is sorted (systematic resampling), so each target's new samples are one block of it too
        cut = np.searchsorted(idx, bounds, side="left")
        for k, t in enumerate(active):
            t.particles = states[idx[cut[k]:cut[k + 1]]]

    def _estimate(self, frame: np.ndarray, tr: _Track) -> None:
        p = self.params
        prev = tr.state
        if tr.occluded or not hasattr(tr, "meas"):
            # occluded: adaptation rates are 0, constant velocity, no size or model update
            tr.state = tr.pred.copy()
            tr.state[4:6] = prev[4:6]
            tr.occluded_frames += 1
            tr.misses += 1
            if hasattr(tr, "meas"):
                del tr.meas
            return
        meas = tr.meas
        del tr.meas
        st = tr.pred.copy()
        st[0:2] = (1 - p.alpha_x) * tr.pred[0:2] + p.alpha_x * meas[0:2]
        st[2:4] = (1 - p.alpha_v) * prev[2:4] + p.alpha_v * (st[0:2] - prev[0:2])
        if tr.grouped and tr.det is None:
            st[4:6], st[6:8] = prev[4:6], 0.0  # a group's blob says nothing of each member's size
        else:
            st[4:6] = (1 - p.alpha_w) * tr.pred[4:6] + p.alpha_w * meas[4:6]
            st[6:8] = (1 - p.alpha_vw) * prev[6:8] + p.alpha_vw * (st[4:6] - prev[4:6])
        st[4:6] = np.maximum(st[4:6], p.min_size)
        tr.state = st
        tr.occluded_frames = 0
        # gated model update (Eqs. 13-14)
        est = st[None, :]
        # the estimate's own region (its bins must outlive the histogram below, which quantises again)
        rho, tot, feats = self._rho(frame, est, tr.sqrt_q, margin=p.ring if p.contrast_gain > 0 else 0.0,
                                    stored=tr.feats, own=True)
        pi_est = math.exp(-(1.0 - float(rho[0])) / (2 * p.sigma ** 2)) if tot[0] > 0 else 0.0
        tr.score = float(rho[0]) if tot[0] > 0 else 0.0
        if tr.lam is None:
            tr.lam = pi_est
        elif pi_est > tr.lam and p.alpha_q > 0:
            q = (1 - p.alpha_q) * tr.q + p.alpha_q * self._histogram(frame, _state_boxes(est)[0], feats)
            tr.q = q / q.sum()
            tr.sqrt_q = np.sqrt(tr.q)
            if p.contrast_gain > 0:
                self._contrast_model(feats, tr, _state_boxes(est)[0], p.alpha_q)
        tr.lam = (1 - p.alpha_u) * tr.lam + p.alpha_u * pi_est
        tr.misses = 0 if tr.det is not None else tr.misses + 1
        tr.hist_max = tr.max_lik if tr.hist_max is None else (
            (1 - p.history_rate) * tr.hist_max + p.history_rate * tr.max_lik)

    def _births(self, frame: np.ndarray, dets: np.ndarray, used: np.ndarray) -> None:
        p = self.params
        free = dets[~used] if len(dets) else dets
        if len(free) and self.tracks:
            explained = iou_matrix(free[:, :4], np.array([t.box for t in self.tracks])).max(axis=1) > p.match_iou
            free = free[~explained]
        matched_cands: list[_Candidate] = []
        remaining = list(range(len(free)))
        if self.candidates and len(free):
            m = iou_matrix(np.array([c.box for c in self.candidates]), free[:, :4])
            for ci, c in enumerate(self.candidates):
                j = int(np.argmax(m[ci])) if m.shape[1] else -1
                if j >= 0 and m[ci, j] >= p.match_iou and j in remaining:
                    remaining.remove(j)
                    c.box = free[j, :4].copy()
                    c.hits += 1
                    matched_cands.append(c)
        new_cands = []
        for c in matched_cands:
            if c.hits >= p.birth_frames:
                center = c.box[:2] + c.box[2:] / 2
                vel = (center - c.first_center) / max(c.hits - 1, 1)
                self.tracks.append(self._new_track(frame, c.box, vel))
            else:
                new_cands.append(c)
        for j in remaining:
            b = free[j, :4].copy()
            if p.birth_frames <= 1:
                self.tracks.append(self._new_track(frame, b))
            else:
                new_cands.append(_Candidate(b, 1, b[:2] + b[2:] / 2))
        self.candidates = new_cands

    def _deaths(self) -> None:
        p = self.params
        h, w = self._shape
        keep = []
        for tr in self.tracks:
            inside = _inside_fraction(tr.box, w, h)
            limit = p.max_occluded if (tr.occluded or tr.grouped) else p.max_misses
            if inside < p.exit_fraction or tr.misses > limit or not np.all(np.isfinite(tr.state)):
                if p.identify:
                    self.identities.remember(tr.id, tr.features, self.frame_index)
                continue
            keep.append(tr)
        self.tracks = keep


MULTI_TRACKERS = {"multi-pf": MultiPF}


def create_multi_tracker(name: str = "multi-pf", *, seed: int | None = None, detector_fn=None, **params) -> MultiPF:
    """A multi-target tracker by name with validated parameters.

    ``detector`` (a parameter) names a built-in detector; ``detector_fn`` is any
    callable ``frame -> boxes`` used instead.
    """
    try:
        cls = MULTI_TRACKERS[name]
    except KeyError:
        raise ParameterError(
            f"unknown multi-target tracker '{name}'; choose from {', '.join(MULTI_TRACKERS)}") from None
    return cls(cls.Params.from_mapping(params), seed=seed, detector_fn=detector_fn)
