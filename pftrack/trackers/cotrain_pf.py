"""``cotrain-pf``: a particle filter on co-trained online-boosting confidence maps, with SEIR (book ch. 3).

Book *Object Tracking*, ch. 3 (``shared/seeds/002_*`` lines 1954-2717; ``shared/book/ch03.md``).
Per frame (ch03.md §1.8):

1. predict the particles ``(x, y, s)`` by a random walk (Eq. 4; the scale is ch03.md P10's extension);
2. the candidate region: the last box enlarged by ``margin`` on each side, united with the
   particles' boxes, resampled so that the target covers about ``work_area`` pixels;
3. the 13 per-pixel features (a grey-input set on grey frames) and the two online real-AdaBoost
   confidence maps (:mod:`pftrack.cues.boosting`), each re-centred by its calibrated offset, mixed
   with a frozen copy of the first frame's classifiers (``anchor``) and opened; fused by sum of
   log-odds (``fusion="sum"``) or by the chapter's vote (:func:`pftrack.cues.cotrain.fuse`);
4. the likelihood of each particle's box on the object map: ``likelihood="window"`` is the
   chapter's Eq. 13 (windowed sum of positive confidence times a Gaussian gate);
   ``"contrast"`` (default) is the map's mean over the box's centre minus its mean over the ring
   around the box, times ``contrast_gain`` in the log domain, times the same gate; plus (``colour_weight``,
   not in the chapter) color-pf's kernel histogram term on the box's ellipse;
5. SEIR (Algorithm 3, :func:`pftrack.filtering.seir.seir`) or plain resampling;
6. the weighted-mean estimate (with ``scale_search="ncc"``, its size then chosen among three by NCC of grey
   patches, :mod:`pftrack.cues.scale_search`); its contrast relative to the running median is the score;
7. retraining of both classifiers when the score passes ``update_gate`` (positives from the box's
   core, chosen per ``label_mode``; negatives from outside the enlarged box, class-balanced) and of the
   colour histogram (``colour_rate``), and
   the lost flag when it stays below ``lost_gate`` for ``lost_frames`` frames;
8. while lost, before step 1, the whole frame is searched with the colour term's model (``lost_search="frame"``,
   not in the chapter, :mod:`pftrack.trackers.frame_search`): a unique, steady best place moves the particles, the
   gate's centre and the box there.

Every change from the chapter is measured on the tune split in docs/cotrain.md.
"""

from __future__ import annotations

import copy
from collections import deque

import cv2
import numpy as np

from ..cues import cotrain as ct
from ..cues.color import blend_model, reachable_roi
from ..cues.histogram_cue import ColorCue
from ..cues.intensity import is_gray
from ..cues.scale_search import search_scale
from ..cues.structure import StructureCue
from ..filtering.particles import effective_sample_size, weights_from_log
from ..filtering.resampling import multinomial, systematic
from ..filtering.seir import seir
from ..geometry import Box, box_to_ellipse
from .base import Tracker, TrackState
from .color_params import ColorModelParams
from .cotrain_params import CoTrainPFParams
from .frame_search import Persistence, Residents, exit_scan, frame_candidate

__all__ = ["CoTrainPF", "CoTrainPFParams"]

#: color-pf's colour-model defaults (colour space, grey bins, kernel, ...) for the colour term
_COLOUR_DEFAULTS = ColorModelParams()


class CoTrainPF(Tracker):
    """Co-trained boosting particle filter (book ch. 3)."""

    name = "cotrain-pf"
    Params = CoTrainPFParams
    state_names = ("x", "y", "s")
    # grey features once the input turns grey, chosen on the tune data (docs/rules/grey_restart_rule.txt): the tune
    # real sequences' 20 copies that turn grey, mean AUC 0.561 against 0.524, false-lost pooled 0.005 against 0.023
    grey_restart = 1

    # ------------------------------------------------------------------ regions and maps
    def _region(self, frame_shape, boxes: np.ndarray) -> tuple[int, int, int, int]:
        """The candidate region C_k (integer frame pixels, x0, y0, x1, y1)."""
        fh, fw = frame_shape[:2]
        x, y, w, h = self.box
        m = self.params.margin
        x0, y0, x1, y1 = x - m * w, y - m * h, x + (1 + m) * w, y + (1 + m) * h
        if boxes is not None and len(boxes):
            x0 = min(x0, boxes[:, 0].min())
            y0 = min(y0, boxes[:, 1].min())
            x1 = max(x1, (boxes[:, 0] + boxes[:, 2]).max())
            y1 = max(y1, (boxes[:, 1] + boxes[:, 3]).max())
        x0, y0 = int(np.clip(np.floor(x0), 0, fw - 1)), int(np.clip(np.floor(y0), 0, fh - 1))
        x1, y1 = int(np.clip(np.ceil(x1), x0 + 1, fw)), int(np.clip(np.ceil(y1), y0 + 1, fh))
        return x0, y0, x1, y1

    def _maps(self, frame: np.ndarray, region) -> dict:
        x0, y0, x1, y1 = region
        f = self.f
        crop = frame[y0:y1, x0:x1]
        if f < 1.0:
            size = (max(round((x1 - x0) * f), 3), max(round((y1 - y0) * f), 3))
            crop = cv2.resize(crop, size, interpolation=cv2.INTER_AREA)
        feats = self.co.features(crop, gray=self.gray, texture=self.params.texture)
        conf_c, conf_t, fused = self.co.maps(feats, opening=self.params.opening, anchor=self.anchor,
                                             anchor_weight=self.params.anchor)
        fx, fy = crop.shape[1] / (x1 - x0), crop.shape[0] / (y1 - y0)
        if self.params.fusion == "sum":
            obj = 1.0 / (1.0 + np.exp(-np.clip(conf_c + conf_t, -30, 30)))
        else:
            obj = (fused > 0).astype(np.float64)
        src = obj if self.params.likelihood == "contrast" else np.maximum(fused, 0)
        return {"region": region, "scale": (fx, fy), "feats": feats, "conf_c": conf_c, "conf_t": conf_t,
                "fused": fused, "obj": obj, "ii": ct.integral(src.astype(np.float64))}

    def _to_map(self, m: dict, boxes: np.ndarray) -> np.ndarray:
        x0, y0 = m["region"][:2]
        fx, fy = m["scale"]
        b = np.asarray(boxes, dtype=np.float64)
        return np.column_stack([(b[:, 0] - x0) * fx, (b[:, 1] - y0) * fy, b[:, 2] * fx, b[:, 3] * fy])

    def _boxes(self, states: np.ndarray) -> np.ndarray:
        w = states[:, 2] * self.size0[0]
        h = states[:, 2] * self.size0[1]
        return np.column_stack([states[:, 0] - w / 2, states[:, 1] - h / 2, w, h])

    def _contrast(self, m: dict, boxes: np.ndarray) -> np.ndarray:
        ii = m["ii"] if self.params.likelihood == "contrast" else ct.integral(m["obj"])
        return ct.contrast_scores(ii, self._to_map(m, boxes), ring=self.params.ring, inner=self.params.inner)[0]

    def _log_lik(self, m: dict, states: np.ndarray) -> np.ndarray:
        p = self.params
        mb = self._to_map(m, self._boxes(states))
        if p.likelihood == "contrast":
            ll = p.contrast_gain * ct.contrast_scores(m["ii"], mb, ring=p.ring, inner=p.inner)[0]
        else:  # Eq. 13: l(X) = window sum of max(conf, 0) + eps_l
            s, _ = ct.box_sums(m["ii"], mb)
            ll = np.log(np.maximum(s, 0.0) + 1e-6)
        if self.ccue is not None:
            rho = self._colour_rho(states)
            ll = ll - p.colour_weight * (1.0 - rho) / (2.0 * p.colour_sigma ** 2)
        if p.gate_sigma > 0:
            sg = p.gate_sigma * max(self.box[2], self.box[3]) * (p.lost_spread if self.lost else 1.0)
            d2 = ((states[:, 0] - self.mu[0]) ** 2 + (states[:, 1] - self.mu[1]) ** 2) / (sg * sg)
            ll = ll - 0.5 * d2
        return ll

    def _ellipses(self, states: np.ndarray) -> np.ndarray:
        return np.column_stack([states[:, 0], states[:, 1], states[:, 2] * (self.size0[0] / 2),
                                states[:, 2] * (self.size0[1] / 2)])

    def _colour_frame(self, frame: np.ndarray) -> None:
        """A new frame for the colour term (its features are quantised on first use)."""
        if self.ccue is not None:
            self.ccue.new_frame(frame)
            self._frame, self._cfeats = frame, None

    def _colour_rho(self, states: np.ndarray) -> np.ndarray:
        """Bhattacharyya coefficients of the particles' ellipses with the colour model.  The frame is quantised
        once per frame over a region covering the ellipses (again, wider, only if SEIR's offspring leave it)."""
        ell = self._ellipses(states)
        h, w = self._frame.shape[:2]
        x0, y0, x1, y1 = reachable_roi(ell, w, h)
        if self._cfeats is None:
            pitch = self.ccue.step_for(ell)
        else:
            a0, b0, a1, b1 = self._croi
            if a0 <= x0 and b0 <= y0 and x1 <= a1 and y1 <= b1:
                return self.ccue.rho(self._cfeats, ell, self._sqrt_q, reuse=False)[0]
            x0, y0, x1, y1 = min(x0, a0), min(y0, b0), max(x1, a1), max(y1, b1)
            pitch = self._cfeats.pitch
        self._cfeats, self._croi = self.ccue.prepare(self._frame, (x0, y0, x1, y1), pitch), (x0, y0, x1, y1)
        return self.ccue.rho(self._cfeats, ell, self._sqrt_q, reuse=False)[0]

    def _colour_update(self, box) -> None:
        """Blend the colour model with the histogram of ``box`` at ``colour_rate`` (Nummiaro et al. Eq. 12)."""
        h = self.ccue.histogram(self._frame, box_to_ellipse(box))
        if h.sum() > 0:
            self._q, self._sqrt_q = blend_model(self._q, h / h.sum(), self.params.colour_rate)

    # ------------------------------------------------------------------ training
    def _masks(self, m: dict, box) -> tuple[np.ndarray, np.ndarray]:
        """Core ellipse of the box and the negatives (outside the box enlarged by 20 %), in map pixels."""
        hh, ww = m["fused"].shape
        bx, by, bw, bh = self._to_map(m, np.array([box]))[0]
        yy, xx = np.ogrid[0:hh, 0:ww]
        cx, cy = bx + bw / 2 - 0.5, by + bh / 2 - 0.5
        c = self.params.core
        core = ((xx - cx) / max(c * bw / 2, 0.5)) ** 2 + ((yy - cy) / max(c * bh / 2, 0.5)) ** 2 <= 1.0
        neg = (np.abs(xx - cx) > 0.6 * bw) | (np.abs(yy - cy) > 0.6 * bh)
        return core, neg

    def _learn(self, m: dict, box, *, first: bool = False) -> None:
        p = self.params
        core, neg = self._masks(m, box)
        if not neg.any() or not core.any():
            return
        if first or p.label_mode == "self":
            pos_c = pos_t = core
        elif p.label_mode == "cross":
            pos_c, pos_t = core & (m["conf_t"] > 0), core & (m["conf_c"] > 0)
        elif p.label_mode == "fused":  # the core pixels that the fused map calls object (Algorithm 2)
            pos_c = pos_t = core & (m["obj"] > p.label_confidence)
        else:  # 'blob': the best blob's most confident half, the chapter's literal rule
            blob = ct.best_blob(np.where(core, m["fused"], 0.0))
            if blob is None:
                pos_c = pos_t = np.zeros_like(core)
            else:
                v = m["fused"][blob.mask]
                pos_c = pos_t = blob.mask & (m["fused"] >= np.median(v))
        bal = None if first else p.min_negatives
        self.co.learn_view("colour", m["feats"], pos_c, neg, max_each=p.max_samples, balance=bal,
                           calibrate=p.calibrate)
        self.co.learn_view("texture", m["feats"], pos_t, neg, max_each=p.max_samples, balance=bal,
                           calibrate=p.calibrate)

    def confidence_map(self) -> tuple[np.ndarray, tuple[int, int, int, int]] | None:
        """The last frame's fused object map in ``[0, 1]`` and its region ``(x0, y0, x1, y1)`` in frame pixels
        (for display: ``pftrack track --show-map``)."""
        m = getattr(self, "last_maps", None)
        return None if m is None else (m["obj"], m["region"])

    # ------------------------------------------------------------------ protocol
    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        p = self.params
        self.co = ct.CoTrainer(n_selectors=p.n_selectors, colour_blocks=p.colour_blocks, ltp_t=p.ltp_t,
                               error_weighting=p.error_weighting, eps=p.eps, replace=p.replace,
                               forgetting=p.forgetting, rng=self.rng)
        x, y, w, h = (float(v) for v in box)
        self.gray = p.grey_features == "on" or (p.grey_features == "auto" and is_gray(frame))
        self.box = (x, y, w, h)
        self.size0 = (w, h)
        self.f = min(1.0, float(np.sqrt(p.work_area / max(w * h, 1.0))))
        self.mu = np.array([x + w / 2, y + h / 2])
        self.lost, self.miss = False, 0
        self._persist = Persistence(p.lost_search_frames, 0.25 * (w + h))
        self._residents = Residents(p.lost_search_resident)
        self.anchor = None
        self.ccue = None
        if p.colour_weight > 0:
            c = _COLOUR_DEFAULTS
            self.ccue = ColorCue(c.color_space, None, c.kernel, p.colour_pixels, gray_bins=tuple(c.gray_bins),
                                 gradient_threshold=c.gradient_threshold, normalize=c.color_normalize)
            self.ccue.adapt_to(frame)
            self._colour_frame(frame)
            q = self.ccue.histogram(frame, box_to_ellipse(self.box))
            self._q = q / max(q.sum(), 1e-12)
            self._sqrt_q = np.sqrt(self._q)
        m = self._maps(frame, self._region(frame.shape, None))
        for _ in range(p.init_passes):
            self._learn(m, self.box, first=True)
        if p.anchor > 0:
            self.anchor = copy.deepcopy(self.co)
        m = self._maps(frame, m["region"])
        c0 = float(self._contrast(m, np.array([self.box]))[0])
        self.accepted: deque[float] = deque([max(c0, 0.05)], maxlen=10)
        self.struct = None
        if p.scale_search == "ncc":
            self.struct = StructureCue(template_pixels=256, anchor=True)
            self.struct.init(frame, box_to_ellipse(self.box))
        self.particles = np.column_stack([np.full(p.n_particles, self.mu[0]), np.full(p.n_particles, self.mu[1]),
                                          np.ones(p.n_particles)])
        self.last_maps = m
        return TrackState(box=self.box, score=1.0, lost=False, particles=self.particles.copy(),
                          weights=np.full(p.n_particles, 1.0 / p.n_particles), state_names=self.state_names,
                          info={"contrast": c0})

    def _predict(self, frame_shape) -> np.ndarray:
        p = self.params
        n = len(self.particles)
        sig = p.position_noise * 0.5 * (self.box[2] + self.box[3]) * (p.lost_spread if self.lost else 1.0)
        z = self.rng.standard_normal((n, 3))
        X = self.particles.copy()
        X[:, :2] += sig * z[:, :2]
        X[:, 2] *= np.exp(p.scale_noise * z[:, 2])
        fh, fw = frame_shape[:2]
        X[:, 0] = np.clip(X[:, 0], 0, fw - 1)
        X[:, 1] = np.clip(X[:, 1], 0, fh - 1)
        X[:, 2] = np.clip(X[:, 2], 0.2, 5.0)
        self._sig = sig
        return X

    def _search_frame(self, frame: np.ndarray) -> None:
        """The whole-frame search while lost (``lost_search``, :mod:`pftrack.trackers.frame_search`): the ellipse of
        the box's size on a grid over the frame whose colour coefficient is best moves the particles, the gate's
        centre and the box there, when it passes the gates for ``lost_search_frames`` frames in one place."""
        p = self.params
        fh, fw = frame.shape[:2]
        w, h = self.box[2], self.box[3]
        step = p.lost_search_step * 0.5 * (w + h)
        centres, residents = exit_scan(frame, (w, h), step, self.box, p.lost_search_exit,
                                       self._residents if p.lost_search_resident else None, self.frame_index)
        if not len(centres):
            self._persist.offer(None)
            return
        feats = self.ccue.prepare(frame, (0, 0, fw, fh), self.ccue.step_for(np.array([[0.0, 0.0, w / 2, h / 2]])))

        def distance(c: np.ndarray) -> np.ndarray:
            e = np.column_stack([c, np.full(len(c), w / 2), np.full(len(c), h / 2)])
            return 1.0 - self.ccue.rho(feats, e, self._sqrt_q, reuse=False)[0]

        d_here = float(distance(self.mu[None])[0])
        best = frame_candidate(self._residents.passing_over(distance, w, h), centres, (w, h), step)
        gated = None
        if best is not None and best.taken(p.lost_search_distance, d_here, p.lost_search_ratio):
            gated = best.centre
        if not self._persist.offer(gated):
            return
        box = (float(gated[0] - w / 2), float(gated[1] - h / 2), float(w), float(h))
        if residents is not None and residents.resident(box):
            return  # another object, in view all the while the target was out
        self.mu = gated.copy()
        self.particles[:, :2] = gated
        self.box = box

    def _search_size(self, frame: np.ndarray, m: dict, est: np.ndarray, info: dict) -> float | None:
        """``scale_search='ncc'``: move the estimate's and the particles' scale (in place) to the size the NCC
        search chooses within the sizes the map's contrast allows.  Returns the contrast at the kept size when
        the check computed it (else None)."""
        p = self.params
        self.struct.new_frame()
        r, _, _ = search_scale(self.struct, frame, box_to_ellipse(self._boxes(est[None]))[0], step=p.scale_step,
                               margin=p.scale_margin, interpolate=p.scale_interpolate)
        c = None
        if r != 1.0 and p.scale_contrast_tol >= 0:
            c1, cr = self._contrast(m, self._boxes(np.array([est, [est[0], est[1], est[2] * r]])))
            r, c = (1.0, c1) if cr < c1 - p.scale_contrast_tol else (r, cr)
        if r != 1.0:
            est[2] *= r
            self.particles[:, 2] *= r
        info["scale_ratio"] = r
        return None if c is None else float(c)

    def _update(self, frame: np.ndarray) -> TrackState:
        p = self.params
        self._colour_frame(frame)
        if p.lost_search == "frame" and self.lost and self.ccue is not None:
            self._search_frame(frame)
        X = self._predict(frame.shape)
        m = self._maps(frame, self._region(frame.shape, self._boxes(X)))
        ll = self._log_lik(m, X)
        info: dict = {}
        if p.resampler == "seir":
            lam = np.array([p.mutation * self._sig, p.mutation * self._sig, p.mutation * p.scale_noise])
            X, ll, si = seir(X, ll, lambda s: self._log_lik(m, s), self.rng,
                             n_target=p.seir_target * len(X), max_loops=p.seir_max_loops, mutation_std=lam)
            info["ess"], info["loops"] = si.ess, si.loops
        w = weights_from_log(ll)
        if p.resampler != "seir":
            info["ess"], info["loops"] = [effective_sample_size(w)], 0
        est = w @ X
        idx = systematic(w, self.rng) if p.resampler != "multinomial" else multinomial(w, self.rng)
        self.particles = X[idx]
        c = None
        if self.struct is not None and not self.lost:
            c = self._search_size(frame, m, est, info)
        bw, bh = est[2] * self.size0[0], est[2] * self.size0[1]
        est_box = (float(est[0] - bw / 2), float(est[1] - bh / 2), float(bw), float(bh))
        if c is None:
            c = float(self._contrast(m, np.array([est_box]))[0])
        ref = max(float(np.median(self.accepted)), 0.05)
        good = c >= p.update_gate * ref
        self.miss = 0 if c >= p.lost_gate * ref else self.miss + 1
        if self.lost:
            self.lost = not good
        else:
            self.lost = self.miss >= p.lost_frames
        self.mu = est[:2].copy()
        if not self.lost:
            self._persist.reset()
            self._residents.reset()
            self.box = est_box
            if good:
                self.accepted.append(c)
                self._learn(m, est_box)
                if self.ccue is not None and p.colour_rate > 0:
                    self._colour_update(est_box)
                if self.struct is not None:
                    self.struct.update(frame, box_to_ellipse(est_box), p.scale_rate)
        self.last_maps = m
        info.update(contrast=c, reference=ref, region=m["region"])
        return TrackState(box=self.box, score=float(np.clip(c / ref, 0.0, 1.0)), lost=self.lost,
                          particles=X, weights=w, state_names=self.state_names, info=info)
