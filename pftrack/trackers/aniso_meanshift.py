"""``anisotropic-meanshift``: mean shift with a full bandwidth matrix (book ch. 5, Tracker B).

Book *Object Tracking*, ch. 5 §4.2 (``shared/book/ch05.md`` §1.3): location (Eq. 7) and
bandwidth (Eq. 8) steps alternate for at most 10 iterations on a kernel-weighted 32^3 RGB
histogram (the grey features on grey input); the box (centre, long and short sides, angle) comes
from the eigen-decomposition of ``Sigma`` (Eqs. 10-11) scaled by ``K``.  By default (``background``)
the iterations climb the corrected background-weighted reference of Ning, Zhang, Zhang & Wu (2012),
which keeps Eq. 8 from inflating the kernel over surroundings of the target's colours.  Re-initialisation
(Eqs. 13-14) when the corners jump by more than ``T3`` or ``rho < T4``.  The stand-alone tracker
(the chapter's "Tracker-1") has no other region to fall back on: a region failing the test is
followed but flagged (``lost`` after ``lost_frames`` such frames).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..cues import anisotropic as an
from ..cues.histogram_cue import check_gray_bins
from ..geometry import Box
from ..params import Params, param
from .base import Tracker, TrackState
from .working_resolution import WORKING_RESOLUTION_DOC, ReducedFrames
from .sift_ransac import ColorModel, RBox, ReinitGate, colour_roi, corner_distance, hull


@dataclass(frozen=True, kw_only=True)
class AnisoMeanShiftParams(Params):
    gamma: float = param(0.33, ge=0, lt=1, doc=(
        "gamma of Eq. 8, the bandwidth normalisation |Sigma|^(gamma/2) rho (Table 2: 0.23-0.33). 0 leaves the "
        "size unobservable (every kernel inside a uniform object is a fixed point)."))
    K: float = param(0.9, gt=0, le=2, doc=(
        "The reported box is the kernel ellipse scaled by K (L4325-4329; with gamma 0.33 it fits the object)."))
    k_mode: Literal["box", "kernel"] = param("box", doc=(
        "'box': kernel = ellipse, box = K-scaled ellipse (ch05.md §1.0); 'kernel': kernel = K-scaled ellipse, box = "
        "ellipse / K (the alternative reading; boxes come out ~24 % larger)."))
    safeguard: bool = param(False, doc=(
        "Refuse or halve a bandwidth step (Eq. 8) that lowers the true objective |Sigma|^(gamma/2) rho (design: on "
        "backgrounds sharing the target's colours the linearised step inflates the kernel). False is the literal "
        "chapter."))
    max_scale_step: float = param(0.1, ge=0, le=10, doc=(
        "Bound on the kernel's size change in one frame: |Sigma|^(1/4) within a factor 1 + this of the frame's "
        "start (Sigma scaled uniformly; shape and angle free). Design, not in the chapter: Eq. 8 inflates the "
        "kernel on backgrounds sharing the target's colours, and every later step then sums over more pixels. "
        "0: unbounded (the chapter). 0.1 chosen on the tune split (55 sequences): mean AUC 0.295 against 0.286 "
        "unbounded (0.05: 0.283; 0.2: 0.285)."))
    background: Literal["none", "cbwh"] = param("cbwh", doc=(
        "'cbwh' (pftrack's default, not in the chapter): the iterations climb the corrected background-weighted "
        "model of Ning, Zhang, Zhang & Wu (2012): the reference's bins are scaled by min(o*/o_u, 1), o the "
        "histogram of the ring around the last region (out to background_scale times its axes), o* its smallest "
        "non-zero bin, so colours the target shares with its surroundings pull the kernel less. rho, the tests "
        "and the reference stay the chapter's. Against Eq. 8's inflation over backgrounds of the target's colours. "
        "'none': the chapter's model."))
    background_scale: float = param(math.sqrt(3.0), gt=1, le=4, doc=(
        "The background ring reaches this multiple of the region's axes (sqrt(3): three times its area, as Ning "
        "et al.)."))
    background_bins: int = param(8, ge=1, le=32, doc=(
        "The CBWH weights are taken on the background histogram pooled to this many bins per channel (8^3 for "
        "RGB): a ring of a few hundred pixels leaves most of the 32^3 bins empty."))
    max_iterations: int = param(10, ge=1, le=100, doc="Mean-shift iterations (L4993).")
    shift_tol: float = param(0.5, gt=0, doc="Stop when the shift is below this (px) ...")
    sigma_tol: float = param(1e-3, gt=0, doc="... and ||dSigma||/||Sigma|| below this (proposed).")
    thresholds: Literal["auto", "paper"] = param("auto", doc=(
        "'auto': the re-init test of sift-ransac's ReinitGate (loss test on rho, jump beyond mu + 3 sigma); "
        "'paper': the fixed t3_dist, t4_rho."))
    t3_dist: float = param(15.0, gt=0, doc="T(2)_3: re-init when the 4 corners move by more than this (sum, px).")
    t4_rho: float = param(0.975, ge=0, le=1, doc="T(2)_4: re-init when rho falls below this (Table 2 median).")
    auto_frames: int = param(10, ge=3, le=100, doc="'auto': frames whose rho and dist set the thresholds.")
    color_space: Literal["auto", "rgb", "gray"] = param("auto", doc="Histogram features, as sift-ransac.")
    gray_bins: tuple[int, ...] = param((64, 1), ge=1, le=256, doc="Grey features on grey input, as sift-ransac.")
    lost_frames: int = param(3, ge=1, le=1000, doc="Consecutive re-initialisations before lost is raised.")
    max_pixels: int = param(2000, ge=0, le=10_000_000, doc=WORKING_RESOLUTION_DOC + (
        " The pixel thresholds of thresholds='paper' are divided by k. Chosen on the tune split (docs/keypoints.md)."))

    def validate(self) -> None:
        check_gray_bins(self.gray_bins)


class AnisoCore:
    """Tracker B's step on a prepared :class:`ColorModel`."""

    def __init__(self, p: AnisoMeanShiftParams, v0: RBox):
        self.p = p
        self.gate = ReinitGate(p.thresholds, t_rho=p.t4_rho, t_dist=p.t3_dist, size=0.5 * (v0[2] + v0[3]),
                               n_seed=p.auto_frames)
        self._index = None  # fine bin -> pooled bin, for the CBWH weights

    def kernel_of(self, v: RBox) -> np.ndarray:
        K = self.p.K if self.p.k_mode == "box" else 1.0
        return an.sigma_from_box(v[2], v[3], v[4], K)

    def box_of(self, sigma: np.ndarray, y) -> RBox:
        K = self.p.K if self.p.k_mode == "box" else 1.0 / self.p.K
        h, w, th = an.box_from_sigma(sigma, K)
        return float(y[0]), float(y[1]), h, w, th

    def model(self, color: ColorModel, q: np.ndarray, around: RBox) -> np.ndarray:
        """The model the iterations climb: ``q``, or with ``background='cbwh'`` its background-weighted form
        for the ring around ``around`` on the prepared frame."""
        p = self.p
        if p.background == "none":
            return q
        if self._index is None:
            self._index = an.pool_index(color.cue.bins, p.background_bins)
        f = color.feats
        ring = an.ring_histogram(f.bins, (f.x0, f.y0), (around[0], around[1]),
                                 an.sigma_from_box(around[2], around[3], around[4], 1.0), color.n_bins,
                                 p.background_scale)
        return an.background_weighted(q, ring, self._index)

    def step(self, color: ColorModel, q: np.ndarray, start: RBox, around: RBox | None = None
             ) -> tuple[RBox, float, int]:
        """Eqs. 7-8 from ``start``: ``(region, rho, iterations)``.  ``rho`` is against ``q``; the iterations
        climb :meth:`model`, whose background ring lies around ``around`` (default: ``start``)."""
        p = self.p
        f = color.feats
        qm = self.model(color, q, start if around is None else around)
        y, S, it = an.aniso_mean_shift(f.bins, (f.x0, f.y0), qm, (start[0], start[1]), self.kernel_of(start),
                                       gamma=p.gamma, max_iter=p.max_iterations, shift_tol=p.shift_tol,
                                       sigma_tol=p.sigma_tol, safeguard=p.safeguard,
                                       max_scale_step=p.max_scale_step)
        v = self.box_of(S, y)
        return v, an.bhattacharyya(color.hist(v), q), it


class AnisoMeanShift(ReducedFrames, Tracker):
    """Tracker B alone (the chapter's Tracker-1); deterministic."""

    name = "anisotropic-meanshift"
    Params = AnisoMeanShiftParams
    stochastic = False

    def _init_at(self, frame: np.ndarray, box: Box) -> None:
        p = self.params
        self.v = an.axis_box_to_rotated(box)
        # the pixel thresholds in working pixels
        self.core = AnisoCore(dataclasses.replace(p, t3_dist=p.t3_dist / self._k), self.v)
        self.color = ColorModel(p.color_space, p.gray_bins)
        self.color.adapt(frame)
        self.color.prepare(frame, colour_roi(self.v))
        self.q = self.color.hist(self.v)
        self.fail = 0

    def _update_at(self, frame: np.ndarray) -> TrackState:
        p = self.params
        self.color.prepare(frame, colour_roi(self.v))
        v, rho, it = self.core.step(self.color, self.q, self.v)
        dist = corner_distance(v, self.v)
        ok_rho, ok_jump = self.core.gate.check(rho, dist, self.color.background(v, self.q))
        # alone, a region failing the test is still the best estimate: it is followed and flagged (going back
        # to the previous region, the "re-initialisation" of a tracker on its own output, only deadlocks)
        self.v = v
        ok = ok_rho and ok_jump
        self.fail = 0 if ok else self.fail + 1
        return TrackState(box=hull(self.v), score=float(rho) if ok else min(float(rho), 0.5),
                          lost=self.fail >= p.lost_frames,
                          info={"rho": rho, "iterations": it, "theta": self.v[4], "reinit": not ok})
