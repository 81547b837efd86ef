"""``sift-ransac``: spatiotemporal SIFT point sets with a RANSAC similarity (book ch. 5, Tracker A).

Book *Object Tracking*, ch. 5 §4.1 and §5.1 (``shared/book/ch05.md`` §1.2).  Per frame:

1. SIFT in the search area (the last region's hull widened by ``k_x w`` and ``k_y h``);
2. ratio-test matches against the stored foreground (PF) and background (PB) points;
3. a RANSAC similarity (Eq. 2) from the matched PF points moves the last region;
4. the candidate set (Eq. 15): inliers PF_a, matched outliers PF_b, and new keypoints inside the
   moved region that match no background point PF_c;
5. the region: the moved box (``box_mode="transform"``) or the tight rectangle around PF_a
   (``"tight"``, the literal reading, which shrinks; ch05.md P6), and its colour similarity
   ``rho`` (Bhattacharyya, 32^3 RGB bins, or the grey features on grey input);
6. unless frozen (``rho <= T_F``): foreground weights (Eq. 16, top ``L_F`` kept) and background
   maintenance (``L_B`` newest kept; foreground points that land in the background move to PB);
7. re-initialisation (Eqs. 3-4) when the corners jump by more than ``T1`` or ``rho < T2``.

:class:`SiftRansacCore` is the engine (shared with ``keypoint-ams``); :class:`SiftRansac` is
the stand-alone tracker (the chapter's "Tracker-2"): a failed fit keeps its last region; a region
failing the colour or jump test is followed but flagged, with the point sets frozen (``lost``
after ``lost_frames`` such frames), since alone it has no better estimate.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Literal

import cv2
import numpy as np

from ..cues import anisotropic as an
from ..cues import keypoints as kp
from ..cues.histogram_cue import ColorCue, check_gray_bins
from ..filtering.loss import LossDetector
from ..filtering.running_threshold import RunningThreshold
from ..geometry import Box
from ..params import Params, param
from .base import Tracker, TrackState
from .working_resolution import WORKING_RESOLUTION_DOC, ReducedFrames

#: A rotated box: centre x, centre y, long side h, short side w, angle of the long side.
RBox = tuple[float, float, float, float, float]


@dataclass(frozen=True, kw_only=True)
class SiftRansacParams(Params):
    k_x: float = param(0.5, ge=0, le=3, doc="Search area: widened by k_x w left and right (L4603).")
    k_y: float = param(0.3, ge=0, le=3, doc="... and by k_y h up and down (L4609: 0.1-0.5).")
    ratio: float = param(0.8, gt=0, le=1, doc="Lowe's ratio test (the chapter's value is 'empirical', L3994).")
    ransac_threshold: float = param(3.0, gt=0, doc="T_e, RANSAC reprojection error in px (OpenCV's default).")
    ransac_iters: int = param(2000, ge=10, le=100000, doc="T_iter, RANSAC iterations (OpenCV's default).")
    min_side: float = param(40.0, ge=0, le=1024, doc=(
        "SIFT runs on the search area enlarged (up to 4x, fixed at the first frame) so the target's shorter side "
        "spans at least this many pixels: small targets otherwise yield too few keypoints (design; 0 disables). "
        "Chosen on the tune split (55 sequences; SIFT doubles the image itself for its first octave): 40 against "
        "64 costs keypoint-ams 0.009 mean AUC (0.347 vs 0.355) and makes it 1.5x faster; sift-ransac gains "
        "(0.322 vs 0.317) and runs 3x faster; 32 loses more (0.338, 0.282)."))
    sift_budget: float = param(4.0, ge=1, le=10000, doc=(
        "The image SIFT runs on has at most this many times the first frame's pixels: a region that grew far "
        "(a failing track) is searched at a lower enlargement instead of at ever higher cost (design)."))
    min_matches: int = param(3, ge=2, le=100, doc="Matched foreground points below which A fails (L4439).")
    max_fg: int = param(1000, ge=10, le=100000, doc="L_F, foreground set size (L4540).")
    max_bg: int = param(1500, ge=0, le=100000, doc="L_B, background set size (L4619).")
    box_mode: Literal["transform", "tight"] = param("transform", doc=(
        "'transform': the last region moved by the similarity; 'tight': the rectangle around the RANSAC "
        "inliers (L4013-4014, the literal reading; boxes shrink, ch05.md P6)."))
    fg_ellipse: bool = param(False, doc="Foreground points only inside the box's inscribed ellipse (L4051, humans).")
    freeze: bool = param(True, doc="Skip point-set maintenance when rho <= T_F (L4582-4586).")
    thresholds: Literal["auto", "paper"] = param("auto", doc=(
        "'auto': re-init when rho fails the two-class loss test (target history vs background windows) or the "
        "corners jump beyond mu + 3 sigma of accepted jumps (see ReinitGate; no per-video tuning, ch05.md P4); "
        "'paper': the fixed t1_dist and t2_rho below (Table 2 medians)."))
    t1_dist: float = param(100.0, gt=0, doc="T(1)_1: re-init when the 4 corners move by more than this (sum, px).")
    t2_rho: float = param(0.87, ge=0, le=1, doc="T(1)_2: re-init when rho falls below this.")
    auto_frames: int = param(10, ge=3, le=100, doc="'auto': frames whose rho and dist set the thresholds.")
    color_space: Literal["auto", "rgb", "gray"] = param("auto", doc=(
        "Histogram features for rho: 32^3 RGB (L4992), or intensity x orientation on grey input ('auto')."))
    gray_bins: tuple[int, ...] = param((64, 1), ge=1, le=256, doc=(
        "Grey features (equalised intensity bins, gradient-orientation bins) on grey input; colour input keeps "
        "32^3 RGB. The chapter has colour only. (64, 1), intensity alone, chosen on the tune split's 64 grey "
        "sequences (docs/keypoints.md): mean AUC of anisotropic-meanshift / keypoint-ams / sift-ransac 0.346 / "
        "0.435 / 0.412 against 0.275 / 0.387 / 0.415 with color-pf's (16, 8)."))
    lost_frames: int = param(3, ge=1, le=1000, doc="Consecutive failed frames before lost is raised.")
    max_pixels: int = param(2000, ge=0, le=10_000_000, doc=WORKING_RESOLUTION_DOC + (
        " The pixel thresholds of thresholds='paper' are divided by k. Chosen on the tune split (docs/keypoints.md)."))

    def validate(self) -> None:
        check_gray_bins(self.gray_bins)


class ReinitGate:
    """The re-initialisation test of Eqs. 3-4 / 13-14: is a tracker's new region acceptable?

    ``mode="paper"``: ``rho >= t_rho`` and ``dist <= t_dist`` with fixed values (the chapter's
    per-video Table 2).  ``mode="auto"`` (default, no per-video tuning, ch05.md P4): the
    similarity passes pftrack's two-class loss test (:class:`~pftrack.filtering.loss.LossDetector`:
    the target's rho history against the rho of background windows around the region) and the
    corner jump stays within ``mu + 3 sigma`` of the accepted frames' jumps (spread floored at a
    quarter of the box's mean side).  A fixed ``mu - 3 sigma`` of the first frames (the spec's
    proposal) re-initialises for good under a slow lighting change; the history follows it.
    """

    def __init__(self, mode: str, *, t_rho: float, t_dist: float, size: float, n_seed: int = 10):
        self.mode, self.t_rho, self.t_dist = mode, t_rho, t_dist
        self.loss = LossDetector(lost_frames=1, reacquire_margin=0.0)
        self.jumps = RunningThreshold(window=30, seed=n_seed, k=3.0, sd_floor=0.25 * size)

    def check(self, rho: float, dist: float, background: np.ndarray) -> tuple[bool, bool]:
        """``(rho passes, jump passes)``; the statistics learn only from frames that pass both."""
        if not (math.isfinite(rho) and math.isfinite(dist)):
            return False, False
        if self.mode == "paper":
            return rho >= self.t_rho, dist <= self.t_dist
        if background.size:
            self.loss.set_background(background)
        ok_rho = self.loss.evaluate(rho) >= 0.0
        ok_jump = not self.jumps.exceeds(dist)
        if ok_rho and ok_jump:
            self.loss.step(rho)
            self.jumps.push(dist)
        return ok_rho, ok_jump

    def test(self, rho: float, dist: float, background: np.ndarray) -> bool:
        """Eqs. 3-4 / 13-14: the region is kept (no re-initialisation)."""
        a, b = self.check(rho, dist, background)
        return a and b


def corner_distance(a: RBox, b: RBox) -> float:
    """Eqs. 3-4 / 17: the sum of the 4 corner displacements (px, 2-norms; ch05.md P3)."""
    ca = an.rotated_corners(a[0], a[1], a[2], a[3], a[4])
    cb = an.rotated_corners(b[0], b[1], b[2], b[3], b[4])
    # corners are matched in order; the angle is taken modulo pi so a flipped box is not a jump
    d1 = float(np.sum(np.hypot(*(ca - cb).T)))
    d2 = float(np.sum(np.hypot(*(ca - cb[[2, 3, 0, 1]]).T)))
    return min(d1, d2)


def hull(v: RBox) -> tuple[float, float, float, float]:
    return an.rotated_to_axis_box(*v)


def colour_roi(v: RBox) -> tuple[int, int, int, int]:
    """The region quantised for the colour histograms: the region's hull widened by 0.75 of its
    longer side (covers the search area, a mean-shift move and the background windows)."""
    x, y, w, h = hull(v)
    m = 0.75 * max(w, h)
    return int(x - m), int(y - m), int(x + w + m), int(y + h + m)


class ColorModel:
    """rho of rotated boxes against a reference histogram over one prepared region per frame (Eq. 6)."""

    def __init__(self, color_space: str, gray_bins: tuple[int, int] = (64, 1)):
        self.cue = ColorCue(color_space, bins=(32, 32, 32), fallback="rgb", gray_bins=gray_bins)

    def adapt(self, frame: np.ndarray) -> None:
        self.cue.adapt_to(frame)

    def prepare(self, frame: np.ndarray, roi: tuple[int, int, int, int]) -> None:
        self.cue.new_frame(frame)
        fh, fw = frame.shape[:2]
        x0, y0, x1, y1 = roi
        roi = (max(int(x0), 0), max(int(y0), 0), min(int(math.ceil(x1)), fw), min(int(math.ceil(y1)), fh))
        self.feats = self.cue.prepare(frame, roi)

    @property
    def n_bins(self) -> int:
        return self.cue.n_bins

    def hist(self, v: RBox) -> np.ndarray:
        """Histogram of the box's inscribed ellipse (the K-scaled kernel ellipse, §1.0)."""
        sig = an.sigma_from_box(v[2], v[3], v[4], 1.0)
        f = self.feats
        return an.ellipse_histogram(f.bins, (f.x0, f.y0), (v[0], v[1]), sig, self.n_bins)

    def background(self, v: RBox, q: np.ndarray, offset: float = 1.0) -> np.ndarray:
        """rho of ``q`` at the 8 regions ``offset`` box sizes around ``v`` (inside the prepared region)."""
        u = np.array([math.cos(v[4]), math.sin(v[4])]) * v[2] * offset
        n = np.array([-math.sin(v[4]), math.cos(v[4])]) * v[3] * offset
        out = []
        for a in (-1, 0, 1):
            for b in (-1, 0, 1):
                if a or b:
                    c = np.array([v[0], v[1]]) + a * u + b * n
                    h = self.hist((float(c[0]), float(c[1]), v[2], v[3], v[4]))
                    if h.sum() > 0:
                        out.append(float(np.sum(np.sqrt(h * q))))
        return np.array(out)


class SiftRansacCore:
    """Tracker A's state and step (the point sets, the last region, the thresholds)."""

    def __init__(self, p: SiftRansacParams):
        self.p = p
        self.first_rho: list[float] = []  # rho of the first successful steps (keypoint-ams' guidance level)

    def observe(self, rho: float) -> None:
        if len(self.first_rho) < self.p.auto_frames and math.isfinite(rho):
            self.first_rho.append(float(rho))

    def freeze_level(self) -> float:
        """T_F = (1 + T2)/2 (ch05.md §2): with 'auto', T2 is the loss test's rho at LLR = 0."""
        t2 = self.p.t2_rho if self.p.thresholds == "paper" else self.gate.loss.threshold()
        return 0.5 * (1.0 + t2)

    def upsample(self, area: tuple[int, int, int, int]) -> float:
        """The enlargement of the search area for SIFT: the first region's, so that the scale space stays the
        one the stored descriptors came from, unless the enlarged area would exceed ``sift_budget`` times the
        first one's pixels (a region that has grown far: the factor then keeps the area at the budget)."""
        px = max((area[2] - area[0]) * (area[3] - area[1]), 1)
        if self._sift_px is None:
            self._sift_px = px * self.up0 ** 2
        cap = math.sqrt(self.p.sift_budget * self._sift_px / px)
        return min(self.up0, cap)

    def search_area(self, v: RBox, shape) -> tuple[int, int, int, int]:
        x, y, w, h = hull(v)
        fh, fw = shape
        x0 = int(math.floor(x - self.p.k_x * w))
        x1 = int(math.ceil(x + w + self.p.k_x * w))
        y0 = int(math.floor(y - self.p.k_y * h))
        y1 = int(math.ceil(y + h + self.p.k_y * h))
        return max(x0, 0), max(y0, 0), min(max(x1, 1), fw), min(max(y1, 1), fh)

    # -- initialisation ---------------------------------------------------------------
    def init(self, gray: np.ndarray, v: RBox) -> None:
        self.v = v
        self.gate = ReinitGate(self.p.thresholds, t_rho=self.p.t2_rho, t_dist=self.p.t1_dist,
                               size=0.5 * (v[2] + v[3]), n_seed=self.p.auto_frames)
        self.up0 = 1.0 if self.p.min_side <= 0 else float(np.clip(self.p.min_side / max(min(v[2], v[3]), 1.0),
                                                                   1.0, 4.0))
        self._sift_px = None
        area = self.search_area(v, gray.shape)
        xy, desc = kp.detect(gray, area, upsample=self.upsample(area))
        inside = (kp.points_in_ellipse(xy, *v) if self.p.fg_ellipse else kp.points_in_rotated_box(xy, *v))
        in_box = kp.points_in_rotated_box(xy, *v)
        n_in = int(inside.sum())
        self.PF = kp.PointSet(xy[inside], desc[inside], np.zeros(n_in), np.zeros(n_in, np.int64))
        ring = ~in_box
        self.PB = kp.PointSet(xy[ring], desc[ring], np.zeros(int(ring.sum())), np.zeros(int(ring.sum()), np.int64))

    # -- one step ---------------------------------------------------------------------
    def step(self, gray: np.ndarray, rho_of) -> dict:
        """Steps 1-5: the candidate region ``v`` and ``rho``; the maintenance waits for :meth:`maintain`."""
        p = self.p
        area = self.search_area(self.v, gray.shape)
        xy, desc = kp.detect(gray, area, upsample=self.upsample(area))
        stored = kp.PointSet.concat(self.PF, self.PB)
        nf = len(self.PF)
        qi, ti = kp.match(desc, stored.desc, ratio=p.ratio)
        fg = ti < nf
        q_fg, t_fg = qi[fg], ti[fg]
        q_bg, t_bg = qi[~fg], ti[~fg] - nf
        out = {"failed": True, "v": self.v, "rho": 0.0, "n_inliers": 0, "n_matches": int(fg.sum()),
               "area": area, "xy": xy, "desc": desc}
        self._pending = out
        if len(q_fg) < p.min_matches:
            return out
        M, inl = kp.ransac_similarity(self.PF.xy[t_fg], xy[q_fg], threshold=p.ransac_threshold,
                                      max_iters=p.ransac_iters)
        if M is None or inl.sum() < min(p.min_matches, 3):
            return out
        beta, dtheta, _, _ = kp.similarity_params(M)
        if not (np.all(np.isfinite(M)) and 0.5 <= beta <= 2.0):
            return out  # a degenerate fit (collinear or coincident points): A fails this frame
        cx, cy = kp.transform_points(M, np.array([[self.v[0], self.v[1]]]))[0]
        vt: RBox = (float(cx), float(cy), self.v[2] * beta, self.v[3] * beta, self.v[4] + dtheta)
        inside = kp.points_in_rotated_box(xy[q_fg], *vt)
        a_mask, b_mask = inl & inside, ~inl & inside
        matched = np.zeros(len(xy), bool)
        matched[qi] = True
        c_mask = ~matched & kp.points_in_rotated_box(xy, *vt)
        v1 = vt
        if p.box_mode == "tight" and a_mask.sum() >= 2:
            pts = xy[q_fg[a_mask]].astype(np.float64) - np.array([cx, cy])
            th = vt[4]
            u = pts @ np.array([math.cos(th), math.sin(th)])
            w_ = pts @ np.array([-math.sin(th), math.cos(th)])
            uc, wc = 0.5 * (u.min() + u.max()), 0.5 * (w_.min() + w_.max())
            centre = np.array([cx, cy]) + uc * np.array([math.cos(th), math.sin(th)]) + wc * np.array(
                [-math.sin(th), math.cos(th)])
            v1 = (float(centre[0]), float(centre[1]), max(float(u.max() - u.min()), 2.0),
                  max(float(w_.max() - w_.min()), 2.0), th)
        out.update(failed=False, v=v1, vt=vt, M=M, rho=float(rho_of(v1)), n_inliers=int(a_mask.sum()),
                   q_fg=q_fg, t_fg=t_fg, q_bg=q_bg, t_bg=t_bg, a=a_mask, b=b_mask, c=c_mask, inside=inside)
        return out

    def maintain(self, res: dict, *, frozen: bool) -> None:
        """Steps 7-9 after a successful step: accept ``res['v']`` and update the point sets."""
        p = self.p
        self.v = res["v"]
        M = res["M"]
        if frozen:
            self.PF.xy = kp.transform_points(M, self.PF.xy) if len(self.PF) else self.PF.xy
            return
        xy, desc = res["xy"], res["desc"]
        q_fg, t_fg, a, b, c = res["q_fg"], res["t_fg"], res["a"], res["b"], res["c"]
        wa, wb, wc = kp.update_foreground_weights(self.PF.weight[t_fg[a]], self.PF.weight[t_fg[b]], int(c.sum()))
        PF = self.PF
        pf_new = PF.weight.copy()
        pf_xy = kp.transform_points(M, PF.xy) if len(PF) else PF.xy.copy()
        pf_xy[t_fg[a]] = xy[q_fg[a]]
        pf_xy[t_fg[b]] = xy[q_fg[b]]
        pf_new[t_fg[a]] = wa
        pf_new[t_fg[b]] = wb
        # matched foreground points that landed outside the moved region go to the background (L4615-4616)
        out_fg = t_fg[~res["inside"]]
        keep = np.ones(len(PF), bool)
        keep[out_fg] = False
        moved = kp.PointSet(xy[q_fg[~res["inside"]]], PF.desc[out_fg], np.zeros(len(out_fg)),
                            np.zeros(len(out_fg), np.int64))
        ages = PF.age + 1
        PF2 = kp.PointSet(pf_xy[keep], PF.desc[keep], pf_new[keep], ages[keep])
        new = kp.PointSet(xy[c], desc[c], wc, np.zeros(int(c.sum()), np.int64))
        self.PF = kp.keep_heaviest(kp.PointSet.concat(PF2, new), p.max_fg)
        # background: matched points follow their match, all age; new ring keypoints join with age 0
        PB = self.PB
        pb_xy = PB.xy.copy()
        pb_xy[res["t_bg"]] = xy[res["q_bg"]]
        matched = np.zeros(len(xy), bool)
        matched[res["q_fg"]] = True
        matched[res["q_bg"]] = True
        ring = ~matched & ~kp.points_in_rotated_box(xy, *self.v)
        PB2 = kp.PointSet(pb_xy, PB.desc, PB.weight, PB.age + 1)
        self.PB = kp.keep_newest(kp.PointSet.concat(PB2, moved, kp.PointSet(
            xy[ring], desc[ring], np.zeros(int(ring.sum())), np.zeros(int(ring.sum()), np.int64))), p.max_bg)

    def reinit(self, v_obj: RBox) -> None:
        """Eqs. 3-4: ``R(1) <- R(obj)``; the point sets are carried by the similarity between the rejected
        region and ``R(obj)`` (design: descriptors and weights are kept)."""
        T = kp.similarity_between((self.v[0], self.v[1]), self.v[2], self.v[4], (v_obj[0], v_obj[1]), v_obj[2],
                                  v_obj[4])
        if len(self.PF):
            self.PF.xy = kp.transform_points(T, self.PF.xy)
        self.v = v_obj


class SiftRansac(ReducedFrames, Tracker):
    """Tracker A alone (the chapter's Tracker-2); deterministic."""

    name = "sift-ransac"
    Params = SiftRansacParams
    stochastic = False

    def _init_at(self, frame: np.ndarray, box: Box) -> None:
        p = self.params
        # the pixel thresholds in working pixels
        self.wp = dataclasses.replace(p, t1_dist=p.t1_dist / self._k)
        self.core = SiftRansacCore(self.wp)
        self.color = ColorModel(p.color_space, p.gray_bins)
        self.color.adapt(frame)
        v = an.axis_box_to_rotated(box)
        self.color.prepare(frame, colour_roi(v))
        self.q = self.color.hist(v)
        self.core.init(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY), v)
        self.v = v
        self.fail = 0

    def _update_at(self, frame: np.ndarray) -> TrackState:
        p = self.wp
        self.color.prepare(frame, colour_roi(self.v))
        gray = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        res = self.core.step(gray, lambda v: an.bhattacharyya(self.color.hist(v), self.q))
        ok_rho = ok_jump = not res["failed"]
        if not res["failed"]:
            dist = corner_distance(res["v"], self.v)
            self.core.observe(res["rho"])
            ok_rho, ok_jump = self.core.gate.check(res["rho"], dist, self.color.background(res["v"], self.q))
        if not res["failed"]:
            # alone, a region failing the test is still the best estimate: it is followed and flagged (with
            # the point sets frozen); only a failed fit keeps the previous region
            frozen = not (ok_rho and ok_jump) or (p.freeze and res["rho"] <= self.core.freeze_level())
            self.core.maintain(res, frozen=frozen)
            self.v = self.core.v
        else:
            self.core.reinit(self.v)
        ok = ok_rho and ok_jump
        self.fail = 0 if ok else self.fail + 1
        lost = self.fail >= p.lost_frames
        return TrackState(box=hull(self.v), score=float(res["rho"]) if ok else min(float(res["rho"]), 0.5), lost=lost,
                          info={"inliers": res["n_inliers"], "matches": res["n_matches"], "rho": res["rho"],
                                "fg": len(self.core.PF), "bg": len(self.core.PB), "reinit": not ok})
