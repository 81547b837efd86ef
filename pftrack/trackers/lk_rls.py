"""``lk-rls`` / ``lk-rls-fuzzy``: a box carried by LK points with the RLS gate of book ch. 7.

The chapter tracks single points (:class:`~pftrack.trackers.point_gate.PointTracker`).
As a box tracker of the registry (ch07.md §4): up to ``n_points`` corners inside the box
(``goodFeaturesToTrack``, 7×7 blocks; a grid where the box is flat) are tracked with the
RLS gate; the box moves by the median displacement of the live points and scales by the
median ratio of their pairwise distances (only pairs both on flow, as MedianFlow does).

Points that are lost, or that leave the box by more than a quarter of its size, are
replaced by fresh corners of the current box, with filters primed from the box's own
velocity history, so a long sequence does not run out of points.  ``lost`` is raised when
most points have been carried by prediction for more than ``lost_after`` frames in a row
(the target is behind something); ``score`` is the fraction of points on flow.

A box that has left the view is a lost target too: ``lost`` is raised while less than ``exit_share`` (0.05) of
the box's area lies inside the frame, and fresh corners are drawn from the box's part inside the frame only.  With
``exit_share=0`` (the former default) fresh corners of a box that reaches past the edge are clipped onto the
frame's border, where they follow the still background, and the box is reported found after its target has left
(docs/points.md, "Targets that leave the view").
"""

from __future__ import annotations

import dataclasses
from collections import deque
from dataclasses import dataclass

import cv2
import numpy as np

from ..cues.lk import gray_of, ncc
from ..geometry import Box, in_frame_fraction
from ..params import param
from .base import Tracker, TrackState
from .point_gate import FLOW, LOST, PointParams, PointTracker

__all__ = ["LKRLS", "LKRLSFuzzy", "LKRLSParams", "box_ncc", "box_patch", "box_points"]


@dataclass(frozen=True, kw_only=True)
class LKRLSParams(PointParams):
    """The point tracker's options (ch07.md §2) plus the box policy."""

    method: str = param("rls", choices=("lk", "rls", "fuzzy"), doc="lk, rls (fixed k) or fuzzy gain")
    n_points: int = param(25, ge=1, le=400, doc="points tracked inside the box")
    min_fraction: float = param(0.5, gt=0, le=1, doc="'most points': the fraction on prediction that counts")
    lost_after: int = param(3, ge=1, doc="frames in a row with most points on prediction before lost is raised")
    reseed: bool = param(True, doc="replace lost points and points that left the box with fresh corners")
    max_scale_step: float = param(0.1, ge=0, le=1, doc="largest relative scale change per frame")
    exit_share: float = param(0.05, ge=0, lt=1, doc=(
        "lost while less than this share of the box's area is inside the frame (the target left the view), and "
        "fresh corners only from the box's part inside the frame; 0: off, the former default (corners of a box past "
        "the edge are clipped onto the border). 0.05 chosen on the tune side under docs/rules/lkrls_exit_rule2.txt "
        "(0.1 failed lkrls_exit_rule.txt)"))
    reseed_lost: float = param(0.0, ge=0, le=1, doc=(
        "while lost (but in view), when the box's grey patch matches the last patch seen while tracking (NCC of "
        "16 x 16 samples at least this), replace the points that are lost -- carried by prediction beyond "
        "max_predict frames, or failed -- with fresh corners of the box; the points still on prediction are kept. "
        "0: off, nothing is replaced while lost, so a box whose points fell to prediction stays lost even on its "
        "target"))


def box_points(gray: np.ndarray, box, n: int, *, block: int = 7, in_view: bool = False) -> np.ndarray:
    """Up to ``n`` corners inside ``box`` (inner 90 %), padded with a regular grid when too few.  The grid's points
    outside the frame are clipped onto its border, or with ``in_view`` left out (then a box wholly outside the
    frame gives none)."""
    x, y, w, h = (float(v) for v in box)
    H, W = gray.shape[:2]
    mx, my = 0.05 * w, 0.05 * h
    x0, y0 = int(max(0, np.floor(x + mx))), int(max(0, np.floor(y + my)))
    x1, y1 = int(min(W, np.ceil(x + w - mx))), int(min(H, np.ceil(y + h - my)))
    pts = np.zeros((0, 2))
    if x1 - x0 >= block and y1 - y0 >= block:
        min_d = max(2.0, 0.5 * np.sqrt((x1 - x0) * (y1 - y0) / max(n, 1)))
        c = cv2.goodFeaturesToTrack(gray[y0:y1, x0:x1], maxCorners=n, qualityLevel=0.01, minDistance=min_d,
                                    blockSize=block)
        if c is not None:
            pts = c.reshape(-1, 2).astype(np.float64) + (x0, y0)
    if len(pts) < max(1, n // 2):
        k = int(np.ceil(np.sqrt(n)))
        gx, gy = np.meshgrid(np.linspace(x + 0.2 * w, x + 0.8 * w, k), np.linspace(y + 0.2 * h, y + 0.8 * h, k))
        grid = np.stack([gx.ravel(), gy.ravel()], 1)
        if in_view:
            grid = grid[(grid[:, 0] >= 0) & (grid[:, 0] <= W - 1) & (grid[:, 1] >= 0) & (grid[:, 1] <= H - 1)]
        pts = np.vstack([pts, grid])[:n]
    return np.clip(pts, 0, [W - 1, H - 1])


#: Side of the grey patch that :func:`box_patch` samples from a box.
PATCH = 16


def box_patch(gray: np.ndarray, box) -> np.ndarray:
    """``box``'s grey content sampled on a ``PATCH`` x ``PATCH`` grid (bilinear; beyond the frame, the border)."""
    x, y, w, h = (float(v) for v in box)
    t = (np.arange(PATCH) + 0.5) / PATCH
    mx = (x + w * t).astype(np.float32)[None, :].repeat(PATCH, 0)
    my = (y + h * t).astype(np.float32)[:, None].repeat(PATCH, 1)
    return cv2.remap(gray, mx - 0.5, my - 0.5, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).astype(np.float64)


def box_ncc(gray: np.ndarray, box, template: np.ndarray) -> float:
    """Normalised cross-correlation of ``box``'s patch (:func:`box_patch`) with ``template`` (0 when either is
    flat)."""
    return float(ncc(box_patch(gray, box)[None], np.asarray(template)[None])[0])


class LKRLS(Tracker):
    """LK points with the RLS gate carrying a box (ch. 7)."""

    name = "lk-rls"
    Params = LKRLSParams
    stochastic = False

    def _point_params(self) -> PointParams:
        fields = {f.name for f in dataclasses.fields(PointParams)}
        return PointParams(**{k: v for k, v in dataclasses.asdict(self.params).items() if k in fields})

    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        p = self.params
        gray = gray_of(frame)
        self.box = np.asarray(box, dtype=np.float64)
        pts = box_points(gray, self.box, p.n_points, in_view=p.exit_share > 0)
        self.points = PointTracker(self._point_params())
        self.points.init(gray, pts)
        self.history: deque[np.ndarray] = deque(maxlen=max(p.n_init, 8))
        self.bad_run = 0
        self.template = box_patch(gray, self.box) if p.reseed_lost > 0 else None
        self.last_ncc = float("nan")
        return self._state(np.full(len(pts), FLOW), lost=False)

    def _centre(self) -> np.ndarray:
        return self.box[:2] + self.box[2:] / 2.0

    def _update(self, frame: np.ndarray) -> TrackState:
        p = self.params
        gray = gray_of(frame)
        prev = self.points.pos.copy()
        step = self.points.step(gray)
        live = step.source != LOST
        flow = step.source == FLOW
        centre = self._centre()
        if live.any():
            # the points on flow move the box when there are enough of them; else every live point
            # (then mostly predictions: the box coasts through the occlusion)
            use = flow if flow.sum() >= max(3, 0.3 * len(flow)) else live
            disp = np.median(step.pos[use] - prev[use], axis=0)
            scale = self._scale(prev[flow], step.pos[flow])
            new_wh = self.box[2:] * scale
            centre = centre + disp
            self.box = np.concatenate([centre - new_wh / 2.0, new_wh])
            self.history.append(disp)
        frac_pred = 1.0 - flow.mean() if len(flow) else 1.0
        self.bad_run = self.bad_run + 1 if frac_pred > p.min_fraction else 0
        lost = self.bad_run > p.lost_after or not live.any()
        out_of_view = p.exit_share > 0 and in_frame_fraction(self.box, gray.shape[1], gray.shape[0]) < p.exit_share
        lost = lost or out_of_view    # the target left the view
        if p.reseed and not lost:
            self._reseed(gray)
        elif p.reseed and p.reseed_lost > 0 and not out_of_view:
            self.last_ncc = box_ncc(gray, self.box, self.template)
            if self.last_ncc >= p.reseed_lost:
                self._reseed(gray, only_lost=True)
        if p.reseed_lost > 0 and not lost:
            self.template = box_patch(gray, self.box)
        return self._state(step.source, lost=lost)

    def _scale(self, a: np.ndarray, b: np.ndarray) -> float:
        if len(a) < 3:
            return 1.0
        i, j = np.triu_indices(len(a), 1)
        da = np.hypot(*(a[i] - a[j]).T)
        db = np.hypot(*(b[i] - b[j]).T)
        good = da > 2.0
        if good.sum() < 3:
            return 1.0
        s = float(np.median(db[good] / da[good]))
        m = self.params.max_scale_step
        return float(np.clip(s, 1.0 - m, 1.0 + m))

    def _reseed(self, gray: np.ndarray, only_lost: bool = False) -> None:
        pos = self.points.pos
        x, y, w, h = self.box
        out = (pos[:, 0] < x - 0.25 * w) | (pos[:, 0] > x + 1.25 * w) | (pos[:, 1] < y - 0.25 * h) | \
              (pos[:, 1] > y + 1.25 * h)
        rows = np.flatnonzero(self.points.lost if only_lost else self.points.lost | out)
        if len(rows) == 0:
            return
        fresh = box_points(gray, self.box, self.params.n_points, in_view=self.params.exit_share > 0)
        if len(fresh) == 0:
            return
        # prefer corners far from the points that are kept
        keep = np.delete(pos, rows, axis=0)
        if len(keep):
            dmin = np.min(np.hypot(*(fresh[:, None, :] - keep[None, :, :]).transpose(2, 0, 1)), axis=1)
            fresh = fresh[np.argsort(-dmin)]
        fresh = fresh[:len(rows)]
        rows = rows[:len(fresh)]
        hist = np.array(self.history) if len(self.history) >= self.params.n_init else None
        self.points.reseed(rows, fresh, hist)

    def _state(self, source: np.ndarray, *, lost: bool) -> TrackState:
        pts = self.points.pos
        n = len(pts)
        flow = float(np.mean(source == FLOW)) if n else 0.0
        return TrackState(box=tuple(float(v) for v in self.box), score=flow, lost=bool(lost), particles=pts.copy(),
                          weights=np.full(n, 1.0 / max(n, 1)), state_names=("x", "y"),
                          info={"flow_points": int(np.sum(source == FLOW)), "points": n})


@dataclass(frozen=True, kw_only=True)
class LKRLSFuzzyParams(LKRLSParams):
    method: str = param("fuzzy", choices=("lk", "rls", "fuzzy"), doc="lk, rls (fixed k) or fuzzy gain")


class LKRLSFuzzy(LKRLS):
    """``lk-rls`` with the fuzzy-tuned gate gain of Sect. 3."""

    name = "lk-rls-fuzzy"
    Params = LKRLSFuzzyParams
