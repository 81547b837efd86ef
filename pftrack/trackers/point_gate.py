"""Points tracked by Lucas–Kanade through occlusions: the RLS gate and the fuzzy gain (book ch. 7).

For each point and frame N (Sect. 2.3, L6826–6846):

1. ``v^of_N``: the LK velocity (:func:`pftrack.cues.lk.lk_flow`);
2. ``v^af_N``: the one-step RLS AR(p) prediction of each velocity component
   (:class:`pftrack.filtering.rls.RLSAR`, from the previous step's coefficients);
3. if ``ε_N = |v^of_N − v^af_N| < tol_N = k·|v_{N−1}|`` (Eq. 20) the flow is used,
   otherwise the prediction; the chosen ``v_N`` updates the filter and moves the point.

``k`` is fixed (0.75, L6896) or set every frame by the fuzzy controller of Sect. 3
(:class:`pftrack.filtering.fuzzy.FuzzyGain`) from ``Δε_N = ε_N − ε_{N−1}`` and the
previous frame's source ``qV``.  Proposed where the text is silent (ch07.md §1.3):
an LK failure counts as ``ε = +∞`` and as no measurement for ``Δε``; ``|v_{N−1}|`` is
floored at ``v_floor``; the gate uses the Euclidean norm of the 2-D velocity
(``per_component`` gates each component as Fig. 2 does).  A point carried by prediction
for more than ``max_predict`` frames, or leaving the image, is lost and stops.

The book's gate as printed recovers 12 % of the points on our synthetic occluder scenes
(sensor noise, illumination drift, grey frames; docs/points.md).  Five additions, each a
parameter that can be switched off, bring that to about 90 %:

* ``ridge``/``prior`` — the initial fit is pulled towards "the mean of the last p
  velocities", so a noisy near-constant velocity cannot fit an oscillating AR model;
* ``stable`` — predictions use AR roots pulled into the unit circle (a hidden point is
  extrapolated from its own predictions, which must not explode);
* ``learn_gate`` — accepted flow far from the prediction (a half-covered window at the
  obstacle's edge) moves the point but is not learnt;
* ``verify`` — rejected flow whose patch still matches the point's last clean
  appearance is used after all (a sudden turn is not an occlusion);
* ``reanchor`` — after the occlusion the point is moved to where its pre-occlusion
  patch is (NCC), undoing the prediction's drift.

:class:`PointTracker` runs any number of points at once (the gate is vectorised over
points); the methods are ``lk`` (plain LK: a failed point is lost), ``rls`` (fixed k)
and ``fuzzy``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..cues.lk import LKConfig, gray_of, lk_flow, ncc, patches_at, reanchor
from ..errors import FrameError
from ..filtering.fuzzy import FuzzyGain
from ..filtering.rls import RLSAR
from ..params import Params, param

__all__ = ["FLOW", "LOST", "PREDICTION", "SOURCES", "Anchor", "Decision", "PointParams", "PointStep", "PointTracker",
           "decide", "gate"]

FLOW, PREDICTION, LOST = 0, 1, 2
SOURCES = ("flow", "prediction", "lost")


@dataclass(frozen=True, kw_only=True)
class PointParams(Params):
    """LK point tracking with the RLS gate (ch07.md §2)."""

    method: Literal["lk", "rls", "fuzzy"] = param(
        "fuzzy", doc="lk: plain Lucas-Kanade; rls: the gate of Eq. 20 with fixed k; fuzzy: k from the controller "
                     "of Sect. 3")
    k: float = param(0.75, gt=0, doc="gate gain k of Eq. 20 for method=rls (0.75, L6896)")
    win: int = param(7, ge=3, doc="LK window side in pixels (7x7 in every experiment, L6855)")
    pyramid: int = param(2, ge=0, le=6, doc="LK pyramid levels; 0 is the book's plain LK (fails above ~3 px/frame)")
    min_eig: float = param(1e-4, gt=0, doc="LK eigenvalue gate lambda_eig (OpenCV minEigThreshold, per window area)")
    fb_check: bool = param(False, doc="forward-backward check: reject flow that does not return within fb_threshold")
    fb_threshold: float = param(1.0, gt=0, doc="forward-backward tolerance in pixels")
    order: int = param(2, ge=1, le=6, doc="AR order p of Eq. 11 (2)")
    n_init: int = param(7, ge=3, doc="frames N_in used to initialise the RLS (7, L6901)")
    forgetting: float = param(0.99, gt=0, le=1, doc="RLS forgetting factor lambda of Eq. 13 (0.99)")
    ridge: float = param(10.0, ge=0, doc="ridge delta of the initial fit, times max(1, trace/p) (ch07.md P4): 1e-6 is "
                                        "the book's plain fit; the default 10 makes the prior a strong starting "
                                        "point that the data must outweigh (a noisy velocity otherwise fits an "
                                        "oscillating or trending AR model)")
    window: int | None = param(None, doc="refit on the last `window` samples instead of recursing (ch07.md P6)")
    prior: Literal["zero", "hold", "mean"] = param(
        "mean", doc="coefficients the initial ridge pulls towards (zero is Haykin's start; mean predicts the mean "
                    "of the last p velocities, so noise in a near-constant velocity cannot make the AR fit wild)")
    learn_gate: float = param(0.15, gt=0, doc="flow accepted with eps >= learn_gate * max(|v_{N-1}|, v_floor) moves "
                                             "the point but the RLS learns the prediction instead (a half-covered "
                                             "window at the obstacle's edge must not teach the filter a wrong "
                                             "velocity); a huge value (1e9) learns every accepted flow, as the "
                                             "book does")
    learn_after: int = param(3, ge=1, doc="flow accepted but kept from learning this many frames in a row is learnt "
                                          "from then on: an edge biases one or two frames, a real change of "
                                          "velocity persists and the filter must follow it")
    verify: bool = param(True, doc="proposed: flow the gate rejects is still used (and learnt) when the patch it "
                                   "lands on matches the point's last clean appearance (NCC >= verify_score): a "
                                   "sudden turn is then not mistaken for an occlusion, which the book's gate cannot "
                                   "tell apart")
    verify_score: float = param(0.85, ge=-1, le=1, doc="NCC of the 9x9 patches that verifies a rejected flow")
    reanchor: bool = param(True, doc="after an occlusion, once flow is back for reanchor_after frames, move the "
                                     "point to where its pre-occlusion patch is (LK from that patch, proposed: the "
                                     "prediction's drift and the edge frames' biased flow are undone)")
    reanchor_after: int = param(3, ge=1, doc="consecutive flow frames after a prediction run before re-anchoring")
    reanchor_max: float = param(12.0, gt=0, doc="largest correction in pixels")
    stable: bool = param(True, doc="predict with the AR roots pulled into the unit circle (proposed: a hidden "
                                   "point is extrapolated from its own predictions, which must not explode)")
    v_floor: float = param(0.5, ge=0, doc="floor of |v_{N-1}| in px/frame, so tol never reaches 0")
    per_component: bool = param(False, doc="gate vx and vy separately (Fig. 2) instead of the 2-D norm")
    max_predict: int = param(30, ge=1, doc="frames a point may be carried by prediction before it is lost")
    defuzz: Literal["cos", "coa", "mom", "ca"] = param("cos", doc="defuzzification (centre of sums, L7070)")
    ei_units: Literal["relative", "px"] = param(
        "relative", doc="error increment normalised by the speed (relative) or in px/frame (ch07.md §1.4)")
    breakpoints: tuple[float, ...] = param((0.2, 0.6), doc="NB/M/PB crossovers of the error increment")

    def __post_init__(self):
        super().__post_init__()
        if self.win % 2 == 0:
            from ..errors import ParameterError

            raise ParameterError("parameter 'win' must be odd")
        if len(self.breakpoints) != 2 or not 0 <= self.breakpoints[0] < self.breakpoints[1]:
            from ..errors import ParameterError

            raise ParameterError("parameter 'breakpoints' must be two numbers 0 <= a < b")

    def lk_config(self) -> LKConfig:
        return LKConfig(self.win, self.pyramid, self.min_eig, fb_check=self.fb_check,
                        fb_threshold=self.fb_threshold)

    def fuzzy(self) -> FuzzyGain:
        return FuzzyGain(breakpoints=tuple(self.breakpoints), defuzz=self.defuzz, v_floor=self.v_floor,
                         units=self.ei_units)


def gate(v_of: np.ndarray, v_af: np.ndarray, v_prev: np.ndarray, k, *, v_floor: float,
         per_component: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 20 for ``n`` points: ``(use_flow (n,), eps (n,))``.

    ``v_of`` holds NaN where LK failed (``ε = +∞``, so the prediction is used).  The
    inequality is strict (ch07.md P9).
    """
    k = np.broadcast_to(np.asarray(k, dtype=np.float64), (len(v_of),))
    with np.errstate(invalid="ignore"):
        diff = np.abs(v_of - v_af)
    diff = np.where(np.isfinite(diff), diff, np.inf)
    if per_component:
        tol = k[:, None] * np.maximum(np.abs(v_prev), v_floor)
        return np.all(diff < tol, axis=1), np.hypot(diff[:, 0], diff[:, 1])
    eps = np.hypot(diff[:, 0], diff[:, 1])
    return eps < k * np.maximum(np.hypot(v_prev[:, 0], v_prev[:, 1]), v_floor), eps


@dataclass
class PointStep:
    """One frame of the point tracker, everything per point (the diagnostics of ch07.md §4)."""

    pos: np.ndarray      # (n, 2) positions after the step
    source: np.ndarray   # (n,) FLOW / PREDICTION / LOST
    v_of: np.ndarray     # (n, 2) LK velocity (NaN on failure)
    v_af: np.ndarray     # (n, 2) RLS prediction
    eps: np.ndarray      # (n,) |v_of - v_af| (inf on failure, NaN before the filter is ready)
    delta_eps: np.ndarray
    e: np.ndarray        # normalised increment fed to the fuzzy controller
    qv: np.ndarray       # (n,) previous frame's source was flow (1) or prediction (0)
    k: np.ndarray        # (n,) gain used this frame

    def source_names(self) -> list[str]:
        return [SOURCES[int(s)] for s in self.source]


@dataclass
class Decision:
    """The gate's verdict for ``n`` points at one frame."""

    use_flow: np.ndarray  # (n,) the flow velocity is used
    learn: np.ndarray     # (n,) the flow velocity is also what the RLS learns
    eps: np.ndarray       # (n,) |v_of - v_af| (inf on LK failure)
    delta: np.ndarray     # (n,) eps increment (0 on failure; NaN unless fuzzy)
    e: np.ndarray         # (n,) normalised increment
    k: np.ndarray         # (n,) gain used


def decide(v_of: np.ndarray, ok: np.ndarray, v_af: np.ndarray, v_prev: np.ndarray, eps_prev: np.ndarray,
           qv: np.ndarray, params: PointParams, fuzzy: FuzzyGain | None, trusted: np.ndarray | None = None
           ) -> Decision:
    """Steps 2–3 of Sect. 2.3 for ``n`` points once the filter is ready: ``k`` (fixed or fuzzy, Sect. 3),
    Eq. 20, and whether the accepted flow is clean enough to learn (``learn_gate``, or
    ``trusted``: the points whose accepted flow was kept from learning ``learn_after``
    frames in a row, i.e. a persistent change rather than an edge).

    ``v_of`` / ``v_af`` / ``v_prev`` are ``(n, d)`` velocities (d = 2 for an image point).
    An LK failure (``ok`` False) is no measurement: its ε is +∞, its increment 0, and the
    next increment is taken against the last measured ε (else failure-then-zero-flow would
    read as an obstacle exit).
    """
    n = len(v_of)
    vnorm = np.maximum(np.sqrt((v_prev ** 2).sum(1)), params.v_floor)
    with np.errstate(invalid="ignore"):
        raw = np.sqrt(((v_of - v_af) ** 2).sum(1))
    eps = np.where(ok & np.isfinite(raw), raw, np.inf)
    delta, e = np.full(n, np.nan), np.full(n, np.nan)
    if fuzzy is not None:
        prev = np.where(np.isfinite(eps_prev), eps_prev, eps)
        with np.errstate(invalid="ignore"):
            delta = np.where(np.isfinite(eps), eps - prev, 0.0)
        e = fuzzy.normalise(delta, vnorm)
        k = fuzzy.from_normalised(e, qv)
    else:
        k = np.full(n, params.k)
    if params.per_component and v_of.shape[1] == 2:
        use_flow, _ = gate(np.where(ok[:, None], v_of, np.nan), v_af, v_prev, k, v_floor=params.v_floor,
                           per_component=True)
    else:
        use_flow = eps < k * vnorm
    use_flow &= ok
    clean = eps < params.learn_gate * vnorm
    if trusted is not None:
        clean |= trusted
    return Decision(use_flow, use_flow & clean, eps, delta, e, k)


class Anchor:
    """Re-anchoring of hidden points (proposed; ``PointParams.reanchor``).

    Keeps the last three frames with the point positions on them.  When a point's
    prediction run starts, the frame from two steps before becomes its reference; when
    flow has been used ``reanchor_after`` frames in a row after the run, the point is
    moved to where its reference patch is found again (:func:`pftrack.cues.lk.reanchor`).
    """

    def __init__(self, gray: np.ndarray, pos: np.ndarray, params: PointParams):
        n = len(pos)
        self.params = params
        self.flow_run = np.zeros(n, dtype=int)
        self.hidden = np.zeros(n, dtype=bool)
        self.ring: list[tuple[np.ndarray, np.ndarray]] = [(gray, pos.copy())]
        self.ref_frame: list[np.ndarray | None] = [None] * n
        self.ref_pos = np.full((n, 2), np.nan)

    def update(self, gray: np.ndarray, pos: np.ndarray, use_flow: np.ndarray, run: np.ndarray,
               active: np.ndarray) -> np.ndarray:
        """Positions after re-anchoring the points that are due (``pos`` is not modified)."""
        p = self.params
        pos = pos.copy()
        starting = ~use_flow & (run == 1) & active & ~self.hidden
        for i in np.flatnonzero(starting):
            self.ref_frame[i], self.ref_pos[i] = self.ring[0][0], self.ring[0][1][i]
        self.hidden |= starting
        self.flow_run = np.where(use_flow, self.flow_run + 1, 0)
        due = self.hidden & use_flow & (self.flow_run == p.reanchor_after) & active
        rows_due = np.flatnonzero(due)
        for ref in {id(self.ref_frame[i]): self.ref_frame[i] for i in rows_due}.values():
            rows = np.array([i for i in rows_due if self.ref_frame[i] is ref])
            pos[rows], _ = reanchor(ref, gray, self.ref_pos[rows], pos[rows], half=p.win // 2 + 1,
                                    max_shift=p.reanchor_max)
        self.hidden &= ~due
        for i in rows_due:
            self.ref_frame[i] = None
        self.ring.append((gray, pos.copy()))
        if len(self.ring) > 3:
            self.ring.pop(0)
        return pos

    def forget(self, rows) -> None:
        self.flow_run[rows], self.hidden[rows] = 0, False
        for i in np.atleast_1d(rows):
            self.ref_frame[int(i)] = None


class PointTracker:
    """Track ``n`` points through a sequence of frames with LK and the RLS / fuzzy gate."""

    def __init__(self, params: PointParams | None = None):
        self.params = params or PointParams()
        self._lk = self.params.lk_config()
        self._fuzzy = self.params.fuzzy() if self.params.method == "fuzzy" else None

    def init(self, frame: np.ndarray, points) -> PointStep:
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        p = self.params
        n = len(pts)
        self.pos = pts.copy()
        self.prev = gray_of(frame)
        self.rls = RLSAR(2 * n, order=p.order, forgetting=p.forgetting, n_init=p.n_init, ridge=p.ridge,
                         window=p.window, stable=p.stable, prior=p.prior)
        self.v_prev = np.zeros((n, 2))
        self.eps_prev = np.full(n, np.nan)
        self.qv = np.ones(n, dtype=bool)
        self.run = np.zeros(n, dtype=int)       # consecutive frames carried by prediction
        self.unlearnt = np.zeros(n, dtype=int)  # consecutive frames of flow used but not learnt
        self.lost = np.zeros(n, dtype=bool)
        self.anchor = Anchor(self.prev, self.pos, p) if p.reanchor and p.method != "lk" else None
        self._half = p.win // 2 + 1
        self.ref_patch = patches_at(self.prev, self.pos, self._half) if p.verify and p.method != "lk" else None
        self.frames = 0
        nan2, nan = np.full((n, 2), np.nan), np.full(n, np.nan)
        k0 = np.full(n, p.k if p.method == "rls" else np.nan)
        return PointStep(self.pos.copy(), np.full(n, FLOW), nan2, nan2.copy(), nan, nan.copy(), nan.copy(),
                         self.qv.astype(int), k0)

    @property
    def n(self) -> int:
        return len(self.pos)

    def step(self, frame: np.ndarray) -> PointStep:
        p = self.params
        gray = gray_of(frame)
        if gray.shape != self.prev.shape:
            raise FrameError(f"frame size {gray.shape[1]}x{gray.shape[0]} differs from the first frame's "
                             f"{self.prev.shape[1]}x{self.prev.shape[0]}")
        h, w = gray.shape
        n = self.n
        active = ~self.lost
        new, ok = lk_flow(self.prev, gray, np.where(active[:, None], self.pos, np.nan), self._lk)
        v_of = new - self.pos
        v_af = self.rls.predict().reshape(-1, 2)
        qv_used = self.qv.astype(int)
        if p.method == "lk" or not self.rls.ready:
            # plain LK, or the first N_in frames: LK only while the filter learns (L6828)
            nan = np.full(n, np.nan)
            d = Decision(ok, ok, nan, nan.copy(), nan.copy(), np.full(n, p.k if p.method == "rls" else np.nan))
            v = np.where(ok[:, None], v_of, 0.0 if p.method == "lk" else v_af)
            learn = v
            if p.method == "lk":
                self.lost |= active & ~ok
        else:
            d = decide(v_of, ok, v_af, self.v_prev, self.eps_prev, self.qv, p, self._fuzzy,
                       trusted=self.unlearnt >= p.learn_after)
            if self.ref_patch is not None:
                cand = np.flatnonzero(ok & ~d.use_flow & active)
                if len(cand):
                    good = ncc(patches_at(gray, new[cand], self._half), self.ref_patch[cand]) >= p.verify_score
                    d.use_flow[cand[good]] = True
                    d.learn[cand[good]] = True
            v = np.where(d.use_flow[:, None], v_of, v_af)
            learn = np.where(d.learn[:, None], v_of, v_af)
        v = np.where(active[:, None], v, 0.0)
        if p.method != "lk":
            self.rls.push(np.where(active[:, None], learn, 0.0).reshape(-1))
        self.pos = self.pos + v
        outside = (self.pos[:, 0] < 0) | (self.pos[:, 0] > w - 1) | (self.pos[:, 1] < 0) | (self.pos[:, 1] > h - 1)
        self.run = np.where(d.use_flow, 0, self.run + 1)
        self.unlearnt = np.where(d.use_flow & ~d.learn, self.unlearnt + 1, 0)
        self.lost |= active & (outside | (self.run > p.max_predict))
        self.pos = np.where(self.lost[:, None] & outside[:, None], np.clip(self.pos, 0, [w - 1, h - 1]), self.pos)
        if self.anchor is not None:
            self.pos = self.anchor.update(gray, self.pos, d.use_flow, self.run, active)
        if self.ref_patch is not None:
            clean = np.flatnonzero(d.learn & d.use_flow & active)
            if len(clean):
                self.ref_patch[clean] = patches_at(gray, self.pos[clean], self._half)
        source = np.where(self.lost, LOST, np.where(d.use_flow, FLOW, PREDICTION))
        self.v_prev = np.where(active[:, None], v, self.v_prev)
        self.eps_prev = np.where(np.isfinite(d.eps), d.eps, self.eps_prev)
        self.qv = d.use_flow.copy()
        self.prev = gray
        self.frames += 1
        return PointStep(self.pos.copy(), source, v_of, v_af, d.eps, d.delta, d.e, qv_used, d.k)

    def reseed(self, rows: np.ndarray, points: np.ndarray, history: np.ndarray | None) -> None:
        """Replace the points ``rows`` by ``points``; their filters start from ``history`` (``(T, 2)``
        velocities, T ≥ n_init, e.g. the object's) when the filter is already running."""
        rows = np.asarray(rows)
        self.pos[rows] = points
        self.lost[rows], self.run[rows], self.qv[rows] = False, 0, True
        self.unlearnt[rows] = 0
        self.eps_prev[rows] = np.nan
        if self.ref_patch is not None:
            self.ref_patch[rows] = patches_at(self.prev, self.pos[rows], self._half)
        if self.anchor is not None:
            self.anchor.forget(rows)
        if history is not None and self.rls.ready and len(history) >= self.params.n_init:
            hist = np.asarray(history, dtype=np.float64)
            idx = np.stack([2 * rows, 2 * rows + 1], axis=1).reshape(-1)
            self.rls.prime(idx, np.tile(hist.T, (len(rows), 1)))
            self.v_prev[rows] = hist[-1]
