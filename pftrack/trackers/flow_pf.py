"""``flow-pf``: colour particle filter driven by optical flow, with EMD and a template subspace.

T. Tung, T. Matsuyama, "Human motion tracking using a color-based particle filter
driven by optical flow" — ``shared/seeds/003_*.txt``.

* **Colour model** (§4.2): separate H, S and V histograms of 10 bins each over the
  region (a window of the initial box size) — by default the mean over 2 nested boxes, a
  stepped kernel density estimate (``kernel_levels``); the model is their average in the
  sense that the distance between two models is the mean of the three per-channel distances.
* **Earth Mover's Distance** (§4.3) with the L1 ground distance between bins, in closed
  form (:mod:`pftrack.cues.emd`): circular for hue, linear for saturation and value, in
  units of bins (so ``E_s = D^2`` over ``sigma^2 = 0.1`` discriminates shifts of a
  fraction of a bin).
* **Template subspace** ``S_t`` of ``k = 5`` colour models;
  ``E_s = min_{h in S_t} D^2[h, q(x)]`` (Eq. 6).  ``S_t`` is updated with the model of the
  response ``z_t``: the detection when there is one, else the estimate (§3.2).  By default
  (measured better, ``docs/flow-pf.md``) the initial model stays in ``S_t`` beside the last
  four responses (``anchor``), and an estimate's model joins only when it lies within
  ``update_distance`` of the subspace (``update_distance`` large and ``anchor=False`` give the
  paper's subspace of the last ``k`` responses, updated every frame).
* **Motion energies** (§4.4, Eqs. 10–11) from KLT: Shi-Tomasi features are detected in
  the search region of this frame and tracked back to the previous one; those whose match
  lies in the previous window give the target's displacement (their median), and
  ``E_m = alpha ||x_i - y~||`` with ``y~ = x_{t-1} + median displacement`` (the printed
  formula subtracts the other way round, which would move the window against the
  motion; we use the displacement from ``t-1`` to ``t``).
  ``E_d = beta (1 - |Y~_i ∩ Y_t| / |Y~_i|)`` is the share of the features inside particle
  ``i``'s window that are not tracked ones, ``Y_t`` being the features that move with the
  target (its displacement within ``flow_tolerance``).  Counting instead every feature
  that comes from the previous window also counts the background the target uncovers, and
  holds the window behind a moving target (measured: a steady lag on ``otb_couple``).
  ``alpha`` is relative to the window size: a displacement of one window costs
  ``motion_weight``.
* **Likelihood** ``exp(-E / sigma^2)``, ``E = E_s + E_m + E_d``, ``sigma^2 = 0.1`` (Eq. 4),
  ``P = 200`` particles, bootstrap filter with constant-velocity dynamics.
* **Detection / tracking switching** (§3.2): with a detector (any callable, or the Haar
  frontal-face cascade shipped with OpenCV via ``detector="haar-face"``) a positive
  detection near the target replaces the response (``z_t = y_t``), re-centres the
  particles and feeds the subspace; without one the tracker runs in tracking mode alone.

* **While lost** (``lost_search="frame"``, an option; not in the paper): the whole frame is searched with the same
  colour distance (:mod:`pftrack.trackers.frame_search`), and a unique, steady best place re-centres the particles.

:class:`FlowPFGroup` tracks several objects at once (M objects with their own
subspaces, §3.2) and returns the per-object states.
"""

from __future__ import annotations

import math
from collections import deque
from typing import Callable, Sequence

import cv2
import numpy as np

from ..cues.emd import emd_hsv, min_emd_hsv
from ..cues.hsv import HSVHistogramCue
from ..cues.intensity import is_gray
from ..cues.motion import to_gray
from ..errors import ParameterError
from ..filtering.loss import LossDetector, confidence
from ..filtering.particles import ParticleSet
from ..filtering.resampling import get_resampler
from ..frames import as_bgr_uint8
from ..geometry import Box, background_grid, iou, validate_box
from .base import Tracker, TrackState
from .flow_params import FlowPFParams
from .frame_search import Persistence, frame_candidate, sample_step, scan_centres

__all__ = ["FlowPF", "FlowPFGroup", "FlowPFParams", "haar_face_detector"]


def haar_face_detector(min_size: int = 24) -> Callable[[np.ndarray], np.ndarray]:
    """The frontal-face Haar cascade shipped with opencv-contrib (Viola & Jones), as a detector callable."""
    path = cv2.data.haarcascades + "haarcascade_frontalface_default.xml"
    cascade = cv2.CascadeClassifier(path)
    if cascade.empty():
        raise ParameterError(f"cannot load the Haar cascade {path}")

    def detect(frame: np.ndarray) -> np.ndarray:
        gray = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        found = cascade.detectMultiScale(gray, scaleFactor=1.1, minNeighbors=4, minSize=(min_size, min_size))
        if len(found) == 0:
            return np.zeros((0, 5))
        return np.column_stack([np.asarray(found, dtype=np.float64), np.ones(len(found))])

    return detect


class FlowPF(Tracker):
    """Tung & Matsuyama's colour particle filter driven by optical flow (single object)."""

    name = "flow-pf"
    Params = FlowPFParams
    state_names = ("x", "y", "vx", "vy")

    def __init__(self, params: FlowPFParams | None = None, *, rng=None, seed=None,
                 detector: Callable | str | None = None):
        super().__init__(params, rng=rng, seed=seed)
        p = self.params
        self.cue = HSVHistogramCue(p.bins)
        self._grey = False  # set from the first frame
        self.resampler = get_resampler("systematic")
        if isinstance(detector, str):
            if detector != "haar-face":
                raise ParameterError(f"unknown detector {detector!r} (built-in: 'haar-face')")
            detector = haar_face_detector()
        if detector is not None and not callable(detector):
            raise ParameterError("detector must be a callable frame -> boxes or 'haar-face'")
        self.detector = detector

    # ------------------------------------------------------------------ colour distances
    def _distance(self, hist: np.ndarray, template: np.ndarray) -> np.ndarray:
        """Mean over H, S, V of the per-channel distance (hist: (N, 3, n), template: (3, n)); on grey input
        (``grey_value_only``) the distance of V alone, since hue and saturation are 0 in every box there and
        their zero distances would only flatten the likelihood threefold.

        EMD is in units of bins (the L1 ground distance between bin indices, Eq. 9);
        the Bhattacharyya distance lies in [0, 1]."""
        v_only = self._grey and self.params.grey_value_only
        if self.params.distance == "emd":
            return emd_hsv(hist, template, value_only=v_only)
        rho = np.sqrt(np.clip(hist, 0, None) * np.clip(template, 0, None)[None]).sum(axis=-1)
        d = np.sqrt(np.clip(1.0 - rho, 0.0, 1.0))
        return d[:, 2] if v_only else d.mean(axis=-1)

    def _histograms(self, feats, boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Colour models of boxes: with ``kernel_levels`` L > 1, the mean of the normalised histograms of L
        nested boxes scaled by 1, (L-1)/L, ..., 1/L about the centre — a stepped kernel density estimate
        whose weight falls linearly from the centre to the border, like the kernel of Nummiaro et al."""
        hist, npx = self.cue.box_histograms(feats, boxes)
        levels = self.params.kernel_levels
        if levels > 1:
            c = boxes[:, 0:2] + boxes[:, 2:4] / 2
            for k in range(1, levels):
                f = (levels - k) / levels
                wh = boxes[:, 2:4] * f
                hk, _ = self.cue.box_histograms(feats, np.column_stack([c - wh / 2, wh]))
                hist = hist + hk
            hist = hist / levels
        return hist, npx

    def _model(self, frame: np.ndarray, box, feats=None) -> np.ndarray:
        """Colour model of one box; ``feats`` (this frame's prepared region) is reused when it holds the box."""
        fh, fw = frame.shape[:2]
        x, y, bw, bh = (float(v) for v in box)
        if feats is not None:
            rh, rw = feats.integral.shape[2] - 1, feats.integral.shape[3] - 1
            if (feats.x0 <= max(np.floor(x), 0) and feats.y0 <= max(np.floor(y), 0)
                    and min(np.ceil(x + bw), fw) <= feats.x0 + rw and min(np.ceil(y + bh), fh) <= feats.y0 + rh):
                return self._histograms(feats, np.array([[x, y, bw, bh]]))[0][0]
        roi = (max(int(np.floor(x)), 0), max(int(np.floor(y)), 0), min(int(np.ceil(x + bw)), fw),
               min(int(np.ceil(y + bh)), fh))
        roi = (roi[0], roi[1], max(roi[2], roi[0]), max(roi[3], roi[1]))
        return self._histograms(self.cue.prepare(frame, roi), np.array([[x, y, bw, bh]]))[0][0]

    def _templates(self) -> list[np.ndarray]:
        return ([self.first] if self.params.anchor else []) + list(self.subspace)

    def _colour_energy(self, hist: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        d = np.stack([self._distance(hist, t) for t in self._templates()])  # (k, N)
        dmin = d.min(axis=0)
        return dmin * dmin, dmin

    # ------------------------------------------------------------------ protocol
    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        p = self.params
        x, y, w, h = box
        self.size = (w, h)
        self.window = 0.5 * (w + h)
        st = np.array([x + w / 2, y + h / 2, 0.0, 0.0])
        self.ps = ParticleSet(np.tile(st, (p.n_particles, 1)))
        self.estimate = st.copy()
        self._grey = is_gray(frame)
        n_bins = p.grey_bins if self._grey and p.grey_value_only and p.grey_bins else p.bins
        if n_bins != self.cue.n_bins:
            self.cue = HSVHistogramCue(n_bins)
        self.first = self._model(frame, box)
        self.subspace: deque = deque(maxlen=max(p.templates - (1 if p.anchor else 0), 1))
        self.subspace.append(self.first)
        self._prev_gray = to_gray(frame)
        self._lost, self._d_est = False, 0.0
        self._persist = Persistence(p.lost_search_frames, 0.5 * self.window)
        self.loss: LossDetector | None = None
        if p.loss_test == "likelihood":
            self.loss = LossDetector()
            self.loss.reset(1.0)
            self._background(frame)
        return self._state(box, 1.0, False)

    # ------------------------------------------------------------------ loss test ("likelihood")
    def _background(self, frame: np.ndarray) -> None:
        """Scores ``1 / (1 + d)`` of boxes of the target's size on a fixed grid over the frame, away from the
        estimate (Nummiaro et al.'s Eqs. 13-14 samples, as the colour PFs take them), into the loss test."""
        fh, fw = frame.shape[:2]
        w, h = self.size
        ell = background_grid(fw, fh, w / 2, h / 2, 100, np.array([self.estimate[0], self.estimate[1], w / 2, h / 2]))
        if ell.shape[0] < 2:
            return  # nothing left that is background: keep the previous statistics
        hist, npx = self._histograms(self.cue.prepare(frame, (0, 0, fw, fh)), self._boxes(ell))
        d = self._colour_energy(hist)[1][npx > 0]
        if d.size >= 2:
            self.loss.set_background(1.0 / (1.0 + d))

    def _loss_step(self, frame: np.ndarray, d_est: float, ok: bool) -> tuple[bool, float]:
        """``(lost, score)`` of this frame from the two-class test, with hysteresis."""
        if self.frame_index % self.params.background_every == 0:
            self._background(frame)
        s = 1.0 / (1.0 + d_est) if ok else 0.0
        if not self.loss.lost:
            return self.loss.step(s)
        return not self.loss.acquire(s), confidence(self.loss.llr)

    def _boxes(self, states: np.ndarray) -> np.ndarray:
        w, h = self.size
        return np.column_stack([states[:, 0] - w / 2, states[:, 1] - h / 2, np.full(len(states), w),
                                np.full(len(states), h)])

    def _flow(self, gray: np.ndarray) -> tuple[np.ndarray | None, np.ndarray, np.ndarray]:
        """KLT motion features (§4.4) around the previous estimate.

        Shi-Tomasi features are detected once in this frame over the search region (the
        previous window widened by ``search`` windows) and tracked back to the previous
        frame (pyramidal LK).  The median displacement of the features whose match lies
        inside the previous window ``x_{t-1}`` is the target's motion; the tracked set
        ``Y_t`` is the features that move that way (``flow_tolerance``); the others belong
        to whatever else is in the region.  Returns ``(median displacement or None, the
        features (M, 2), mask of the tracked ones)``.
        """
        p = self.params
        fh, fw = gray.shape[:2]
        w, h = self.size
        ex, ey = self.estimate[0], self.estimate[1]
        mx = w / 2 + p.search * self.window + abs(self.estimate[2])
        my = h / 2 + p.search * self.window + abs(self.estimate[3])
        region = (int(max(ex - mx, 0)), int(max(ey - my, 0)), int(min(ex + mx, fw)), int(min(ey + my, fh)))
        pts = _features(gray, region, p.max_features)  # float32 pixel indices, as LK takes them
        if not len(pts):
            return None, np.empty((0, 2)), np.zeros(0, bool)
        crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 20, 0.03)
        back, st, _ = cv2.calcOpticalFlowPyrLK(gray, self._prev_gray, pts.reshape(-1, 1, 2), None,
                                               winSize=(p.klt_window, p.klt_window), maxLevel=p.klt_levels - 1,
                                               criteria=crit)
        # pixel indices -> continuous coordinates
        back = back.reshape(-1, 2).astype(np.float64) + 0.5
        feats = pts.astype(np.float64) + 0.5
        ok = (st.ravel() == 1) & np.all(np.isfinite(back), axis=1)
        in_prev = ok & (np.abs(back[:, 0] - ex) < w / 2) & (np.abs(back[:, 1] - ey) < h / 2)
        if in_prev.sum() < p.min_tracked:
            return None, feats, in_prev
        d = feats - back
        disp = np.median(d[in_prev], axis=0)
        # Y_t: the features that move with the target (Y_{t-1}'s displacement, within tolerance) — not merely
        # those that come from the previous window, which would count the background the target uncovers and
        # make E_d hold the window behind a moving target
        tol = p.flow_tolerance + 0.2 * float(np.hypot(*disp))
        tracked = ok & (np.hypot(d[:, 0] - disp[0], d[:, 1] - disp[1]) <= tol)
        return disp, feats, tracked

    def _update(self, frame: np.ndarray) -> TrackState:
        p = self.params
        ps = self.ps
        fh, fw = self._shape
        w, h = self.size
        win = self.window
        if p.lost_search == "frame" and self._lost:
            self._search_frame(frame)
        prev_est = self.estimate.copy()
        gray = to_gray(frame)
        disp = tracked = None
        if p.motion:
            disp, feats_m, tracked = self._flow(gray)
        # propagate: driven by the optical flow when it is available (the median KLT displacement moves every
        # sample, as the flow-predicted position y~ does), else constant velocity; plus Gaussian noise
        s = ps.states
        if disp is not None:
            s[:, 0:2] += disp
            s[:, 2:4] = disp
        else:
            s[:, 0:2] += s[:, 2:4]
        noise = self.rng.standard_normal(s.shape) * np.array([p.position_noise * win, p.position_noise * win,
                                                              p.velocity_noise * win, p.velocity_noise * win])
        s += noise
        np.clip(s[:, 0], -w / 2, fw + w / 2, out=s[:, 0])
        np.clip(s[:, 1], -h / 2, fh + h / 2, out=s[:, 1])
        boxes = self._boxes(s)
        roi = (int(max(np.floor(boxes[:, 0].min()) - 1, 0)), int(max(np.floor(boxes[:, 1].min()) - 1, 0)),
               int(min(np.ceil((boxes[:, 0] + boxes[:, 2]).max()) + 1, fw)),
               int(min(np.ceil((boxes[:, 1] + boxes[:, 3]).max()) + 1, fh)))
        roi = (roi[0], roi[1], max(roi[2], roi[0]), max(roi[3], roi[1]))
        feats = self.cue.prepare(frame, roi)
        hist, npx = self._histograms(feats, boxes)
        e_s, _ = self._colour_energy(hist)
        energy = e_s
        if p.motion:
            if disp is not None:
                y_pred = prev_est[0:2] + disp
                energy = energy + p.motion_weight * np.hypot(s[:, 0] - y_pred[0], s[:, 1] - y_pred[1]) / win
            if p.drift_weight > 0:
                energy = energy + p.drift_weight * _untracked_share(feats_m, tracked, boxes)
        log_lik = -energy / p.sigma2
        log_lik[npx <= 0] = -np.inf
        ok = ps.set_log_likelihood(log_lik)
        est = ps._mean.copy()
        # detection / tracking switching (§3.2): a positive detection replaces the response
        det_box = self._detection(frame, est) if self.detector is not None else None
        if det_box is not None:
            dx, dy, dw, dh = det_box
            c = np.array([dx + dw / 2, dy + dh / 2])
            ps.states[:, 0:2] += c - est[0:2]
            est[0:2] = c
        est[2:4] = est[0:2] - prev_est[0:2]
        self.estimate = est
        box = tuple(float(v) for v in self._boxes(est[None, :])[0])
        # subspace update with the response's colour model
        model = self._model(frame, det_box if det_box is not None else box, feats)
        d_est = float(self._colour_energy(model[None])[1][0])
        if det_box is not None or d_est <= p.update_distance:
            self.subspace.append(model)
        # resample for the next frame
        ps.resample(self.resampler(ps.w, self.rng))
        self._prev_gray = gray
        if self.loss is not None:
            lost, score = self._loss_step(frame, d_est, ok)
        else:
            lost, score = (not ok) or d_est > p.lost_distance, 1.0 / (1.0 + d_est)
        self._lost, self._d_est = bool(lost), d_est
        if not lost:
            self._persist.reset()
        return self._state(box, score, lost, det=det_box is not None)

    def _search_frame(self, frame: np.ndarray) -> None:
        """The whole-frame search while lost (``lost_search``, :mod:`pftrack.trackers.frame_search`): the best box of
        the target's size on a grid over the frame, when within ``lost_search_distance`` of the models and nearer
        them than the last estimate for ``lost_search_frames`` frames in one place, re-centres the particles."""
        p = self.params
        fh, fw = self._shape
        w, h = self.size
        step = p.lost_search_step * self.window
        k = sample_step(w, h, fw, fh)  # every k-th pixel of every k-th row: the histograms' cost falls k^2 times
        small = frame[::k, ::k]
        feats = self.cue.prepare(small, (0, 0, small.shape[1], small.shape[0]))
        value_only = self._grey and p.grey_value_only
        templates = np.stack(self._templates())

        def score(centres: np.ndarray) -> np.ndarray:
            hist, npx = self._histograms(feats, self._boxes(centres) / k)
            if p.distance == "emd":  # the particles' distance, compiled for the many boxes
                d = min_emd_hsv(hist, templates, value_only=value_only)
            else:
                d = self._colour_energy(hist)[1]
            d[npx <= 0] = np.inf
            return d

        best = frame_candidate(score, scan_centres(fw, fh, w, h, step), (w, h), step)
        gated = None
        if best is not None and best.taken(p.lost_search_distance, self._d_est, p.lost_search_ratio):
            gated = best.centre
        if not self._persist.offer(gated):
            return
        s = self.ps.states
        s[:, 0:2] = gated
        s[:, 2:4] = 0.0
        self.estimate = np.array([gated[0], gated[1], 0.0, 0.0])

    def _detection(self, frame: np.ndarray, est: np.ndarray) -> Box | None:
        fh, fw = frame.shape[:2]
        out = self.detector(frame)
        rows = []
        for d in out if out is not None else []:
            d = [float(v) for v in d]
            if len(d) >= 4 and d[2] > 0 and d[3] > 0 and all(math.isfinite(v) for v in d[:4]):
                rows.append(d[:4])
        if not rows:
            return None
        cand = np.array(rows)
        ov = iou(cand, self._boxes(est[None, :])[0])
        k = int(np.argmax(ov))
        if ov[k] <= self.params.detector_min_iou:
            return None
        try:
            return validate_box(cand[k], fw, fh)
        except ValueError:
            return None

    def _state(self, box, score, lost, det: bool = False) -> TrackState:
        return TrackState(box=tuple(float(v) for v in box), score=float(score), lost=bool(lost),
                          particles=self.ps.states.copy(), weights=self.ps.w.copy(), state_names=self.state_names,
                          info={"detection": det, "templates": len(self.subspace)})


def _features(gray: np.ndarray, roi, max_features: int) -> np.ndarray:
    """Shi-Tomasi features (lambda_min > 1e-3) on a lattice over ``roi`` (the #4 feature detector)."""
    from ..cues.motion import shi_tomasi_features

    x0, y0, x1, y1 = roi
    if x1 - x0 < 5 or y1 - y0 < 5:
        return np.empty((0, 2), np.float32)
    return shi_tomasi_features(gray, roi, max_features=max_features)


def _untracked_share(features: np.ndarray, tracked: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """C(Y~_i, Y_t) = 1 - |Y~_i ∩ Y_t| / |Y~_i| for every box (Eq. 11); 1 for a box without features.

    ``features`` (M, 2) are this frame's features, ``tracked`` (M,) marks those in ``Y_t``
    (matched to features of the previous window); ``Y~_i`` are the features inside box i.
    """
    n = len(boxes)
    if len(features) == 0:
        return np.ones(n)
    inside = ((features[None, :, 0] >= boxes[:, 0:1]) & (features[None, :, 0] < boxes[:, 0:1] + boxes[:, 2:3])
              & (features[None, :, 1] >= boxes[:, 1:2]) & (features[None, :, 1] < boxes[:, 1:2] + boxes[:, 3:4]))
    n_in = inside.sum(axis=1)
    n_tr = (inside & tracked[None, :]).sum(axis=1)
    return np.where(n_in > 0, 1.0 - n_tr / np.maximum(n_in, 1), 1.0)


class FlowPFGroup:
    """Several objects (e.g. body parts) tracked at once, each with its own subspace (§3.2).

    >>> group = FlowPFGroup(seed=0)                       # doctest: +SKIP
    >>> states = group.init(frame, [head_box, hand_box])  # doctest: +SKIP
    >>> states = group.update(next_frame)                 # list of TrackState, one per object
    """

    def __init__(self, params: FlowPFParams | None = None, *, seed: int | None = None,
                 detectors: Sequence[Callable | None] | None = None):
        self.params = params or FlowPFParams()
        self.seed = seed
        self.detectors = detectors
        self.trackers: list[FlowPF] = []

    def init(self, frame: np.ndarray, boxes: Sequence) -> list[TrackState]:
        frame = as_bgr_uint8(frame, where="init frame")
        ss = np.random.SeedSequence(self.seed)
        rngs = [np.random.default_rng(s) for s in ss.spawn(len(boxes))]
        dets = list(self.detectors) if self.detectors is not None else [None] * len(boxes)
        if len(dets) != len(boxes):
            raise ParameterError("give one detector (or None) per object")
        self.trackers = [FlowPF(self.params, rng=r, detector=d) for r, d in zip(rngs, dets)]
        return [t.init(frame, b) for t, b in zip(self.trackers, boxes)]

    def update(self, frame: np.ndarray) -> list[TrackState]:
        return [t.update(frame) for t in self.trackers]
