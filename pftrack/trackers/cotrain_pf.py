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
   the lost flag when it stays below ``lost_gate`` for ``lost_frames`` frames.

Every change from the chapter is measured on the tune split in docs/cotrain.md.
"""

from __future__ import annotations

import copy
from collections import deque
from dataclasses import dataclass
from typing import Literal

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
from ..params import Params, param
from .base import Tracker, TrackState
from .color_params import ColorModelParams

#: color-pf's colour-model defaults (colour space, grey bins, kernel, ...) for the colour term
_COLOUR_DEFAULTS = ColorModelParams()


@dataclass(frozen=True, kw_only=True)
class CoTrainPFParams(Params):
    """Parameters of ``cotrain-pf`` (ch03.md §2; values the text leaves open are proposed there or selected
    on the tune split, docs/cotrain.md)."""

    n_particles: int = param(300, ge=1, le=100_000, doc="N (ch. 3's experiments: 300, L2647).")
    resampler: Literal["seir", "systematic", "multinomial"] = param("seir", doc=(
        "'seir': sequential evolutionary importance resampling (Algorithm 3, Eqs. 8-10); 'systematic' or "
        "'multinomial': plain SIR resampling every frame (the chapter's comparison)."))
    seir_target: float = param(0.8, gt=0, le=1, doc="N_thr / N: SEIR loops while N_eff < N_thr (ch03.md §2).")
    seir_max_loops: int = param(10, ge=0, le=100, doc="T_max of Algorithm 3 (ch03.md §2).")
    mutation: float = param(0.5, ge=0, le=10, doc="lambda of Eq. 10, as a multiple of the random-walk std.")
    position_noise: float = param(0.15, gt=0, le=5, doc=(
        "sigma_rw of Eq. 4, as a fraction of the box's mean side (ch03.md §2: 0.15)."))
    scale_noise: float = param(0.005, ge=0, le=1, doc=(
        "Std of the log-scale random walk (the (x, y, s) extension, ch03.md P10). Small: the map is learned "
        "from the box, so a fast-moving size feeds back into what is learned (tune split, docs/cotrain.md)."))
    likelihood: Literal["contrast", "window"] = param("contrast", doc=(
        "'window': Eq. 13, the window sum of max(conf, 0) times the gate (the chapter's); 'contrast': the "
        "fraction of fused-positive pixels in the box minus that in the ring around it, as a log-likelihood "
        "scaled by contrast_gain, times the gate (peaked in position and size; docs/cotrain.md)."))
    fusion: Literal["vote", "sum"] = param("sum", doc=(
        "How the two opened maps are fused for the likelihood: 'vote' (Algorithm 2: object only where both "
        "classifiers agree, the contrast counts positive pixels) or 'sum' (the two views as independent "
        "evidence: log-odds conf_c + conf_t, the contrast averages the posterior sigmoid(conf_c + conf_t))."))
    forgetting: float = param(1.0, gt=0, le=1, doc=(
        "beta: the weak learners' block counts are multiplied by beta once per retraining (ch03.md P4: 1 in "
        "the text)."))
    contrast_gain: float = param(20.0, gt=0, le=1000, doc="Log-likelihood per unit of contrast ('contrast').")
    inner: float = param(0.6, gt=0, le=1, doc=(
        "The contrast's inside term is the map's mean over the box scaled by this factor (its centre): the "
        "positives are learned from the box's core, so the map covers less than the box, and a whole-box mean "
        "would pull the box's size down to the map's extent."))
    ring: float = param(0.25, gt=0, le=2, doc="Width of the contrast ring, as a fraction of the box per side.")
    gate_sigma: float = param(0.5, ge=0, le=20, doc=(
        "sigma_g of the Gaussian gate g(X; mu, sigma_g) of Eq. 13, as a multiple of the box's larger side "
        "(ch03.md §2: 0.5); mu is the previous estimate. 0 disables the gate."))
    anchor: float = param(0.5, ge=0, le=1, doc=(
        "Weight of a frozen copy of the first frame's classifiers in each view's confidence (0: the chapter's "
        "purely online maps). 0.5, selected on the tune split: 0.3-0.85 all gave 0.44-0.45 mean AUC over its 15 "
        "real and grey sequences, 0 and 1 gave 0.42 (docs/cotrain.md)."))
    margin: float = param(0.5, ge=0, le=5, doc="Candidate-region margin m on each side, in box sizes (ch03.md §2).")
    work_area: int = param(1600, ge=100, le=1_000_000, doc=(
        "The candidate region is resampled so that the target covers about this many pixels (never enlarged): "
        "the cost per frame does not grow with the target."))
    n_selectors: int = param(10, ge=1, le=200, doc="Selectors per classifier (Algorithm 1; ch03.md §2: 10).")
    colour_blocks: int = param(32, ge=2, le=256, doc="Blocks per colour feature (ch03.md §2: 32).")
    ltp_t: float = param(5.0, ge=0, le=255, doc="LTP threshold t of Eq. 2 (grey levels; ch03.md §2: 5).")
    texture: Literal["pairs", "radii"] = param("pairs", doc=(
        "The texture view on colour input: 'pairs', the chapter's nine cross-channel LTP_{8,1} codes; 'radii', "
        "LTP codes of the grey image at radii 1-3 and thresholds t/2, t, 2t (the grey-input set)."))
    grey_features: Literal["auto", "on", "off"] = param("auto", doc=(
        "On grey input the chapter's 13 features collapse (R = G = B = Y; the nine channel pairs give one LTP "
        "code). 'auto' switches to the grey set when the first frame has no colour: Y, two smoothed Y, the "
        "gradient magnitude, and LTP codes at radii 1-3 and thresholds t/2, t, 2t (cues.boosting.grey_features)."))
    eps: float = param(1.0, gt=0, le=100, doc="epsilon of the weak learners' log-odds (ch03.md §2: 1.0).")
    error_weighting: Literal["confidence", "count"] = param("confidence", doc=(
        "Error accumulators weighted by |h| (the text's reading) or counted (Grabner)."))
    replace: Literal["update", "sample"] = param("update", doc=(
        "Replace each selector's worst weak learner once per frame ('update', ch03.md P3) or after every "
        "sample (the text's literal rule)."))
    opening: int = param(3, ge=1, le=15, doc="Side of the grey-level opening of each map (ch03.md §2: 3).")
    label_mode: Literal["fused", "cross", "blob", "self"] = param("fused", doc=(
        "Positives of each retraining, inside the core of the estimated box: 'fused' (both classifiers learn "
        "the pixels the fused map calls object, Algorithm 2), 'cross' (Blum & Mitchell co-training: each "
        "learns the pixels the other one calls object; a blind view then starves the other), 'blob' (the "
        "most confident half of the fused map's best blob, the text's rule), 'self' (the whole core)."))
    label_confidence: float = param(0.5, ge=0, lt=1, doc=(
        "label_mode='fused': a core pixel is a positive when the object map exceeds this (0.5: the fused "
        "decision)."))
    core: float = param(0.6, gt=0, le=1, doc="Positives come from the ellipse of this fraction of the box.")
    max_samples: int = param(300, ge=10, le=100_000, doc="Positives and negatives per classifier per frame (cap).")
    min_negatives: int = param(30, ge=0, le=100_000, doc=(
        "Negatives per retraining: as many as the positives, at least this many (class balance)."))
    calibrate: bool = param(True, doc=(
        "Re-centre each classifier's decision at every retraining: the offset halfway between the median "
        "confidence of the positives and of the negatives just learned (not in the chapter, whose sign rule "
        "leaves most of a target negative after the first frame; docs/cotrain.md)."))
    init_passes: int = param(3, ge=1, le=20, doc="Training passes over the first frame (ch03.md §2: 3).")
    update_gate: float = param(0.25, ge=0, le=1, doc=(
        "Retrain only when the estimate's contrast is at least this fraction of the median of the last 10 "
        "accepted contrasts (ch03.md §2's acceptance rule on A(B*), on the contrast)."))
    lost_gate: float = param(0.15, ge=0, le=1, doc=(
        "A frame counts as a miss when the contrast is below this fraction of the running median."))
    lost_frames: int = param(3, ge=1, le=1000, doc="Consecutive misses before lost is raised.")
    lost_spread: float = param(2.0, ge=1, le=10, doc="Random-walk std multiplier while lost (re-acquisition).")
    scale_search: Literal["ncc", "none"] = param("none", doc=(
        "How the box's size follows the target. 'none': the particles' scale alone. 'ncc': after the filter's "
        "estimate, the sizes 1/(1+scale_step), 1 and 1+scale_step around it are compared with grey reference "
        "patches by zero-mean NCC (DSST-style, cues.scale_search), and the best moves the estimate and the "
        "particles. The contrast of the object map is flat over a range of sizes (the map covers the learned "
        "core), so on its own the size drifts. 'ncc' gained 0.014 mean AUC on the tune split and lost on the "
        "report split (docs/cotrain.md), so it is an option, not the default."))
    colour_weight: float = param(1.5, ge=0, le=100, doc=(
        "Weight of a kernel colour histogram term in each particle's log-likelihood: colour_weight * "
        "-(1 - rho) / (2 colour_sigma^2), rho the Bhattacharyya coefficient of the particle's ellipse with the "
        "model (color-pf's cue, Nummiaro et al. Eq. 10; intensity x orientation on grey input). Not in the "
        "chapter. 0: the object map alone. 1.5 selected on the tune split, 6 seeds: 1, 1.5 and 2 gave 0.559, "
        "0.571 and 0.569 mean AUC over its real, grey and synthetic sequences, 0 gave 0.516 (docs/cotrain.md)."))
    colour_sigma: float = param(0.1, gt=0, le=10, doc="sigma of the colour term (color-pf's default).")
    colour_pixels: int = param(400, ge=0, le=1_000_000, doc=(
        "The colour term samples each ellipse on a lattice of at most about this many pixels (0: every pixel; "
        "color-pf's max_pixels)."))
    colour_rate: float = param(0.05, ge=0, le=1, doc=(
        "The colour model is blended with the estimate's histogram at this rate on frames that pass update_gate."))
    scale_step: float = param(0.05, gt=0, le=0.5, doc="Relative size step of the NCC scale search per frame.")
    scale_margin: float = param(0.04, ge=0, le=1, doc=(
        "A size other than the current one is taken only when its NCC beats the current size's by more than this "
        "(tune split: 0.01, 0.02, 0.03 and 0.04 tried; docs/cotrain.md)."))
    scale_interpolate: bool = param(False, doc=(
        "The size between the three compared ones: the vertex of the parabola through their NCC in log-scale "
        "(cues.scale_search.vertex_ratio), so that noise moves the size by a fraction of a step. Tried on the tune "
        "split and not kept: the fractional steps drifted (docs/cotrain.md)."))
    scale_contrast_tol: float = param(0.02, ge=-1, le=2, doc=(
        "A new size is taken only when the object map's contrast at it is at least the current size's minus this "
        "(-1: not checked). The contrast is flat over the sizes that fit the map and falls for a box far too large "
        "or too small, so the NCC chooses within the sizes the map allows."))
    scale_rate: float = param(0.05, ge=0, le=1, doc=(
        "Blending rate of the scale search's running grey reference, on frames that pass update_gate (the first "
        "frame's patch is kept as a second reference)."))


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
