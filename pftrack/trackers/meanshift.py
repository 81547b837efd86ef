"""Mean-shift baselines of Nummiaro et al. §7: ``meanshift`` and ``kalman-meanshift``.

``meanshift`` is the tracker of Comaniciu, Ramesh & Meer (CVPR 2000 / PAMI 2003):
starting from the previous location ``y0`` it moves the ellipse to the weighted
centroid of its pixels,

    y1 = sum_i x_i w_i / sum_i w_i,    w_i = sqrt(q_u / p_u(y0)) for u = h(x_i),

which climbs the Bhattacharyya coefficient ``rho[p(y), q]`` (with the kernel
profile k(r) = 1 - r^2 the derivative is constant, so the centroid is unweighted
by distance).  When ``rho(y1) < rho(y0)`` the step is halved (Comaniciu's
safeguard).  It stops when the shift is below ``epsilon`` pixels.  Scale: the
iteration runs at the current size and at ±5 %, and the size with the highest
rho is chosen (004 §7) and blended with the previous size,
``h = gamma h_opt + (1 - gamma) h_prev`` with Comaniciu et al.'s gamma = 0.1
(``scale_smoothing``; 1 keeps 004's plain choice).  It uses the same colour cue as ``color-pf``.

``kalman-meanshift`` (Comaniciu & Ramesh 2000) starts each mean-shift search from
the position predicted by a constant-velocity Kalman filter, which is then
corrected with the mean-shift result.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..cues.color import warmup
from ..cues.histogram_cue import ColorCue
from ..cues.meanshift_step import shift_sums
from ..filtering.kalman import KalmanFilter
from ..geometry import Box, box_to_ellipse, ellipse_to_box
from ..params import Params, param
from .base import Tracker, TrackState


@dataclass(frozen=True, kw_only=True)
class MeanShiftParams(Params):
    color_space: Literal["rgb", "hsv", "auto"] = param("auto", doc=(
        "Colour space, as color-pf (004 §3); 'auto': RGB on colour input, and on grey input (the first frame's "
        "channels equal) equalised intensity x gradient orientation, as color-pf (pftrack.cues.histogram_cue)."))
    bins: tuple[int, ...] = param((), ge=1, le=256, doc="Bins per channel; empty for the colour space default.")
    kernel: Literal["nummiaro", "epanechnikov"] = param("nummiaro", doc="Kernel, as color-pf (Eq. 2).")
    max_iterations: int = param(20, ge=1, le=1000, doc="Mean-shift iterations per scale.")
    epsilon: float = param(0.5, gt=0, doc="Stop when the shift is below this many pixels.")
    scale_step: float = param(0.05, ge=0, lt=1, doc="Relative size change tried on each side (004 §7: 5 %).")
    scale_smoothing: float = param(0.1, ge=0, le=1, doc=(
        "gamma in h = gamma h_opt + (1 - gamma) h_prev, the published setting of Comaniciu, Ramesh & Meer "
        "(PAMI 2003). 1 is the plain best-rho choice described in 004 §7 (the size then drifts quickly)."))


@dataclass(frozen=True, kw_only=True)
class KalmanMeanShiftParams(MeanShiftParams):
    process_noise: float = param(1.0, gt=0, doc="Std (px/frame^2) of the Kalman filter's white acceleration.")
    measurement_noise: float = param(2.0, gt=0, doc="Std (px) of the mean-shift position as a measurement.")


class MeanShift(Tracker):
    """Comaniciu mean shift maximising the Bhattacharyya coefficient."""

    name = "meanshift"
    Params = MeanShiftParams
    stochastic = False

    def __init__(self, params=None, *, rng=None, seed=None):
        super().__init__(params, rng=rng, seed=seed)
        p = self.params
        self.cue = ColorCue(p.color_space, tuple(p.bins) or None, p.kernel)
        warmup()

    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        self.ell = box_to_ellipse(box)
        self.cue.adapt_to(frame)
        self.cue.new_frame(frame)
        self.q = self.cue.histogram(frame, self.ell)
        self._sqrt_q = np.sqrt(self.q)
        self.rho = 1.0
        return TrackState(box=tuple(float(v) for v in box), score=1.0, lost=False)

    def _rho(self, feats, ell) -> tuple[float, np.ndarray]:
        hist, tot = self.cue.histograms(feats, np.asarray(ell).reshape(1, 4), reuse=False)
        if tot[0] <= 0:
            return 0.0, hist[0]
        return float(np.sum(np.sqrt(hist[0]) * self._sqrt_q)), hist[0]

    def _shift(self, feats, ell: np.ndarray) -> tuple[np.ndarray, float]:
        """Mean-shift iterations from ``ell`` at fixed size; returns the final ellipse and its rho."""
        p = self.params
        ell = ell.copy()
        rho0, p0 = self._rho(feats, ell)
        for _ in range(p.max_iterations):
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = np.where(p0 > 0, np.sqrt(self.q / np.where(p0 > 0, p0, 1.0)), 0.0)
            n, sw, sx, sy = shift_sums(feats.bins, feats.x0, feats.y0, ell, ratio)
            if n == 0 or sw <= 0:
                break
            new = ell.copy()
            new[0] = sx / sw
            new[1] = sy / sw
            rho1, p1 = self._rho(feats, new)
            halvings = 0
            while rho1 < rho0 and halvings < 5 and np.hypot(*(new[:2] - ell[:2])) > p.epsilon:
                new[:2] = 0.5 * (new[:2] + ell[:2])
                rho1, p1 = self._rho(feats, new)
                halvings += 1
            moved = float(np.hypot(*(new[:2] - ell[:2])))
            ell, rho0, p0 = new, rho1, p1
            if moved < p.epsilon:
                break
        return ell, rho0

    def _search(self, frame: np.ndarray, start: np.ndarray) -> tuple[np.ndarray, float]:
        p = self.params
        self.cue.new_frame(frame)  # the grey features' equalisation (nothing for RGB)
        feats = self.cue.prepare_frame(frame)
        best, best_rho = None, -1.0
        for f in (1.0, 1.0 - p.scale_step, 1.0 + p.scale_step) if p.scale_step > 0 else (1.0,):
            e = start.copy()
            e[2:] *= f
            e, rho = self._shift(feats, e)
            if rho > best_rho + 1e-12:
                best, best_rho = e, rho
        g = p.scale_smoothing
        best[2:] = g * best[2:] + (1.0 - g) * self.ell[2:]
        best[2:] = np.maximum(best[2:], 1.0)
        return best, best_rho

    def _update(self, frame: np.ndarray) -> TrackState:
        self.ell, self.rho = self._search(frame, self.ell)
        return TrackState(box=tuple(float(v) for v in ellipse_to_box(self.ell)), score=max(self.rho, 0.0),
                          lost=False)


class KalmanMeanShift(MeanShift):
    """Mean shift started from a constant-velocity Kalman prediction."""

    name = "kalman-meanshift"
    Params = KalmanMeanShiftParams

    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        st = super()._init(frame, box)
        p = self.params
        self.kf = KalmanFilter.constant_velocity_2d(self.ell[:2], process_std=p.process_noise,
                                                    measurement_std=p.measurement_noise)
        return st

    def _update(self, frame: np.ndarray) -> TrackState:
        pred = self.kf.predict()
        start = self.ell.copy()
        h, w = frame.shape[:2]
        start[0] = float(np.clip(pred[0], 0, w))
        start[1] = float(np.clip(pred[1], 0, h))
        self.ell, self.rho = self._search(frame, start)
        self.kf.update(self.ell[:2])
        return TrackState(box=tuple(float(v) for v in ellipse_to_box(self.ell)), score=max(self.rho, 0.0),
                          lost=False)
