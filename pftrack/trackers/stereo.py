"""Stereo point tracking through occlusions (book ch. 7, Sect. 4).

A rectified pair (parallel axes, the right camera shifted by ``B`` along x, focal ``f``
pixels, principal point ``(cx, cy)``).  Eqs. 23–26, with image coordinates measured from
the principal point and the disparity ``d = x₁ − x₂ > 0``::

    X = x₁ B / d,   Y = y₁ B / d,   Z = f B / d

Per frame (Sect. 4.2, L7435–7465): LK moves the point in the left image; the right point
is found by a 7×7 correlation search along the same row (:func:`disparity_search`), so
``v^of_R = x₂,N − x₂,N−1``.  The x-velocities of both views are predicted by one joint
RLS AR(p) (Eqs. 27–29, :class:`pftrack.filtering.rls.JointRLSAR`), vy by a scalar one.
Each view has its own gate (Eq. 31) and fuzzy gain.  Proposed where the text is silent
(ch07.md P11): vy follows the left view's decision; the right view can only use its
measurement when the left view uses flow (the right point is found from the left one);
a disparity search whose best normalised correlation is below ``min_score`` is a failure.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ..cues.lk import gray_of, lk_flow
from ..errors import FrameError
from ..filtering.rls import RLSAR, JointRLSAR, stabilise
from ..geometry import parabola_peak
from ..params import param
from .point_gate import FLOW, LOST, PREDICTION, Anchor, PointParams, decide

__all__ = ["StereoParams", "StereoStep", "StereoTracker", "disparity_search", "triangulate"]


def triangulate(x1, y1, d, *, f: float, B: float, cx: float, cy: float):
    """Eqs. 24–26: ``(X, Y, Z)`` in metres from left-image pixels and disparity (NaN where d ≤ 0)."""
    x1, y1, d = (np.asarray(v, dtype=np.float64) for v in (x1, y1, d))
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(d > 0, B / d, np.nan)
    return (x1 - cx) * s, (y1 - cy) * s, f * s


def disparity_search(left: np.ndarray, right: np.ndarray, pts: np.ndarray, d_lo, d_hi, *, win: int = 7,
                     subpixel: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Disparity of each left point by correlation along its row of the right image (L7177–7183).

    The ``win × win`` window around the (sub-pixel) left point is slid over the right
    image's row for every integer disparity in ``[d_lo, d_hi]`` (``TM_CCOEFF_NORMED``),
    and the peak is refined by a parabola.  Returns ``(d, score)`` per point; NaN where
    the range is empty or the point is out of the image.
    """
    pts = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
    n = len(pts)
    lo = np.broadcast_to(np.asarray(d_lo, dtype=np.float64), (n,))
    hi = np.broadcast_to(np.asarray(d_hi, dtype=np.float64), (n,))
    lf, rf = left.astype(np.float32), right.astype(np.float32)
    h, w = left.shape[:2]
    d_out, s_out = np.full(n, np.nan), np.full(n, np.nan)
    for i, (x, y) in enumerate(pts):
        if not (np.isfinite(x) and np.isfinite(y)) or not (0 <= x <= w - 1 and 0 <= y <= h - 1):
            continue
        a, b = int(np.floor(lo[i])), int(np.ceil(hi[i]))
        a = max(a, int(np.ceil(x - (w - 1))))  # the right point must stay in the image
        b = min(b, int(np.floor(x)))
        if b < a:
            continue
        tmpl = cv2.getRectSubPix(lf, (win, win), (float(x), float(y)))
        if tmpl.std() < 1e-3:
            continue
        span = b - a
        # strip columns: right x from x - b - r to x - a + r; result index j <-> d = b - j
        centre = x - (a + b) / 2.0
        strip = cv2.getRectSubPix(rf, (span + win, win), (float(centre), float(y)))
        score = cv2.matchTemplate(strip, tmpl, cv2.TM_CCOEFF_NORMED)[0]
        j = int(np.argmax(score))
        dj = parabola_peak(score[j - 1], score[j], score[j + 1]) if subpixel and 0 < j < len(score) - 1 else 0.0
        d_out[i], s_out[i] = b - (j + dj), float(score[j])
    return d_out, s_out


@dataclass(frozen=True, kw_only=True)
class StereoParams(PointParams):
    """Stereo point tracking: the point tracker's options plus the disparity search (ch07.md §2)."""

    d_min: float = param(0.0, ge=0, doc="smallest disparity in pixels")
    d_max: float = param(64.0, gt=0, doc="largest disparity in pixels")
    d_radius: float = param(6.0, gt=0, doc="after frame 1, search the predicted disparity +- d_radius pixels")
    min_score: float = param(0.6, ge=-1, le=1, doc="a disparity whose correlation peak is lower is a failure")
    reacquire_score: float = param(0.8, ge=-1, le=1, doc="proposed: a right point carried by prediction is put back "
                                                         "at the measured disparity once the search peaks this high "
                                                         "on two frames in a row (its prediction may have drifted "
                                                         "too far for the velocity gate to accept it again)")


@dataclass
class StereoStep:
    """One frame: left point, right x, depth and the two views' sources and gains."""

    xl: np.ndarray       # (n, 2)
    xr: np.ndarray       # (n,)
    Z: np.ndarray        # (n,) metres
    X: np.ndarray
    Y: np.ndarray
    src_l: np.ndarray    # FLOW / PREDICTION / LOST
    src_r: np.ndarray
    k_l: np.ndarray
    k_r: np.ndarray


class StereoTracker:
    """Points of the left image tracked in both views, with depth (Sect. 4)."""

    def __init__(self, calib: dict, params: StereoParams | None = None):
        self.params = params or StereoParams()
        try:
            self.f, self.B = float(calib["f"]), float(calib["B"])
            self.cx, self.cy = float(calib["cx"]), float(calib["cy"])
        except (KeyError, TypeError, ValueError):
            raise ValueError("calibration needs numbers f, B, cx and cy") from None
        if self.f <= 0 or self.B <= 0:
            raise ValueError("calibration f and B must be positive")
        self._lk = self.params.lk_config()
        self._fuzzy = self.params.fuzzy() if self.params.method == "fuzzy" else None

    def _depth(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return triangulate(self.xl[:, 0], self.xl[:, 1], self.xl[:, 0] - self.xr, f=self.f, B=self.B, cx=self.cx,
                           cy=self.cy)

    def init(self, left: np.ndarray, right: np.ndarray, points) -> StereoStep:
        p = self.params
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        n = len(pts)
        self.prev_l, self.prev_r = gray_of(left), gray_of(right)
        d, score = disparity_search(self.prev_l, self.prev_r, pts, p.d_min, p.d_max, win=p.win)
        bad = ~np.isfinite(d) | (score < p.min_score) | (d <= 0)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ValueError(f"point {i} ({pts[i, 0]:g},{pts[i, 1]:g}): no match in the right image "
                             f"for disparities {p.d_min:g}..{p.d_max:g}")
        self.xl, self.xr = pts.copy(), pts[:, 0] - d
        kw = {"order": p.order, "forgetting": p.forgetting, "n_init": p.n_init, "ridge": p.ridge}
        self.joint = [JointRLSAR(2, prior=p.prior, **kw) for _ in range(n)]
        self.rls_y = RLSAR(n, window=p.window, stable=p.stable, prior=p.prior, **kw)
        self.v_prev = np.zeros((n, 3))  # vLx, vRx, vy
        self.eps_prev = np.full((2, n), np.nan)
        self.qv = np.ones((2, n), dtype=bool)
        self.run = np.zeros((2, n), dtype=int)  # consecutive predicted frames per view
        self.unlearnt = np.zeros((2, n), dtype=int)  # consecutive frames of flow used but not learnt, per view
        self.good_r = np.zeros(n, dtype=int)    # consecutive confident disparities while the right view predicts
        self.lost = np.zeros(n, dtype=bool)
        self.anchor = Anchor(self.prev_l, self.xl, p) if p.reanchor and p.method != "lk" else None
        X, Y, Z = self._depth()
        src = np.full(n, FLOW)
        k0 = np.full(n, p.k if p.method == "rls" else np.nan)
        return StereoStep(self.xl.copy(), self.xr.copy(), Z, X, Y, src, src.copy(), k0, k0.copy())

    def _predict(self) -> np.ndarray:
        """``(n, 3)`` predicted ``(vLx, vRx, vy)``; the joint model is only used once initialised."""
        p = self.params
        out = np.zeros((len(self.xl), 3))
        for i, j in enumerate(self.joint):
            if j.ready and p.stable:
                c = j._regressor()
                out[i, :2] = c @ np.stack([_stable_joint(j.coef[:, m], p.order) for m in range(2)], axis=1)
            else:
                out[i, :2] = j.predict()
        out[:, 2] = self.rls_y.predict()
        return out

    def step(self, left: np.ndarray, right: np.ndarray) -> StereoStep:
        p = self.params
        gl, gr = gray_of(left), gray_of(right)
        if gl.shape != self.prev_l.shape or gr.shape != self.prev_l.shape:
            raise FrameError(f"stereo frames must keep the first frame's size {self.prev_l.shape[1]}x"
                             f"{self.prev_l.shape[0]}")
        h, w = gl.shape
        n = len(self.xl)
        active = ~self.lost
        new_l, ok_l = lk_flow(self.prev_l, gl, np.where(active[:, None], self.xl, np.nan), self._lk)
        v_af = self._predict()
        d_pred = (self.xl[:, 0] + v_af[:, 0]) - (self.xr + v_af[:, 1])
        d, score = disparity_search(gl, gr, np.where(ok_l[:, None], new_l, np.nan),
                                    np.maximum(d_pred - p.d_radius, p.d_min), np.minimum(d_pred + p.d_radius, p.d_max),
                                    win=p.win)
        ok_r = ok_l & np.isfinite(d) & (score >= p.min_score) & (d > 0)
        v_of = np.stack([new_l[:, 0] - self.xl[:, 0], (new_l[:, 0] - d) - self.xr, new_l[:, 1] - self.xl[:, 1]], 1)
        ready = self.joint[0].ready if n else False
        if p.method == "lk" or not ready:
            use_l, use_r = ok_l, ok_r
            learn_l, learn_r = use_l, use_r
            k_l = k_r = np.full(n, p.k if p.method == "rls" else np.nan)
            if p.method == "lk":
                self.lost |= active & ~ok_r
        else:
            trusted = self.unlearnt >= p.learn_after
            dl = decide(v_of[:, [0, 2]], ok_l, v_af[:, [0, 2]], self.v_prev[:, [0, 2]], self.eps_prev[0],
                        self.qv[0], p, self._fuzzy, trusted=trusted[0])
            dr = decide(v_of[:, [1, 2]], ok_r, v_af[:, [1, 2]], self.v_prev[:, [1, 2]], self.eps_prev[1],
                        self.qv[1], p, self._fuzzy, trusted=trusted[1])
            use_l, use_r = dl.use_flow, dr.use_flow & dl.use_flow
            learn_l, learn_r = dl.learn, dr.learn & use_r
            k_l, k_r = dl.k, dr.k
            self.eps_prev[0] = np.where(np.isfinite(dl.eps), dl.eps, self.eps_prev[0])
            self.eps_prev[1] = np.where(np.isfinite(dr.eps), dr.eps, self.eps_prev[1])
        fallback = 0.0 if p.method == "lk" else v_af
        v = np.where(np.stack([use_l, use_r, use_l], 1), v_of, fallback)
        learn = np.where(np.stack([learn_l, learn_r, learn_l], 1), v_of, fallback if ready else v)
        v = np.where(active[:, None], v, 0.0)
        if p.method != "lk":
            for i, j in enumerate(self.joint):
                j.push(learn[i, :2] if active[i] else np.zeros(2))
            self.rls_y.push(np.where(active, learn[:, 2], 0.0))
        self.xl = self.xl + v[:, [0, 2]]
        self.xr = self.xr + v[:, 1]
        if p.method != "lk":
            confident = use_l & ~use_r & (self.run[1] >= 1) & np.isfinite(d) & (score >= p.reacquire_score)
            self.good_r = np.where(confident, self.good_r + 1, 0)
            back = confident & (self.good_r >= 2) & active
            self.xr = np.where(back, self.xl[:, 0] - np.nan_to_num(d), self.xr)
            use_r = use_r | back
        self.run = np.where(np.stack([use_l, use_r]), 0, self.run + 1)
        self.unlearnt = np.where(np.stack([use_l & ~learn_l, use_r & ~learn_r]), self.unlearnt + 1, 0)
        outside = (self.xl[:, 0] < 0) | (self.xl[:, 0] > w - 1) | (self.xl[:, 1] < 0) | (self.xl[:, 1] > h - 1)
        self.lost |= active & (outside | (self.run.max(0) > p.max_predict))
        if self.anchor is not None:
            moved = self.anchor.update(gl, self.xl, use_l, self.run[0], active)
            fixed = np.any(moved != self.xl, axis=1)
            if fixed.any():  # re-measure the right point at the corrected left one
                dd, sc = disparity_search(gl, gr, moved[fixed], np.maximum(self.xl[fixed, 0] - self.xr[fixed]
                                          - p.d_radius, p.d_min), self.xl[fixed, 0] - self.xr[fixed] + p.d_radius,
                                          win=p.win)
                good = np.isfinite(dd) & (sc >= p.min_score) & (dd > 0)
                rows = np.flatnonzero(fixed)
                self.xr[rows[good]] = moved[rows[good], 0] - dd[good]
                self.xr[rows[~good]] += moved[rows[~good], 0] - self.xl[rows[~good], 0]
            self.xl = moved
        self.v_prev = np.where(active[:, None], v, self.v_prev)
        self.qv = np.stack([use_l, use_r])
        self.prev_l, self.prev_r = gl, gr
        X, Y, Z = self._depth()
        src_l = np.where(self.lost, LOST, np.where(use_l, FLOW, PREDICTION))
        src_r = np.where(self.lost, LOST, np.where(use_r, FLOW, PREDICTION))
        return StereoStep(self.xl.copy(), self.xr.copy(), Z, X, Y, src_l, src_r, k_l, k_r)


def _stable_joint(col: np.ndarray, order: int) -> np.ndarray:
    """A joint-model column used for prediction, with each channel's own-lag AR part kept stable.

    The interleaved column ``[a₁ᴸ, a₁ᴿ, a₂ᴸ, a₂ᴿ, …]`` mixes both channels' lags; the
    sum over channels at each lag is the effective AR(p) of a common velocity
    (xL ≈ xR), which :func:`~pftrack.filtering.rls.stabilise` projects; the projection's
    ratio is applied to both channels' terms of that lag.
    """
    c = col.reshape(order, 2)
    eff = c.sum(1)
    st = stabilise(eff[None])[0]
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(np.abs(eff) > 1e-12, st / eff, 1.0)
    return (c * ratio[:, None]).reshape(-1)
