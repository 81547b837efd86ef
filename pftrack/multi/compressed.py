"""Objects from compressed-domain motion vectors (book ch. 8, ch08.md §1.3-1.9).

A 4x4 block is foreground when it carries a non-zero motion vector and a non-zero (pseudo-)residual.
Foreground blocks are closed, hole-filled and grouped by 8-connectivity into at most 10 groups, each with
its position (top-left), direction (Eq. 1 restored: the angle of the mean forward vector) and energy
(Eq. 2 restored: the sum of squared residuals).  Two consumers:

- :class:`MVDetector` — a causal detector for the per-target particle filters of ``pftrack mot``
  (``--detector mv``): the groups that also existed in one of the two previous frames;
- :class:`CDTracker` — the chapter's own labelling (``--tracker cd``): the 5-frame temporal refinement
  (Eqs. 3-4, 2 frames of delay), statuses (occlusion, out of frame, stop, into frame; Eq. 9 read as
  ch08.md §1.8) and labels kept through occlusions by direction and energy (Eqs. 10-14).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Literal

import cv2
import numpy as np
from scipy.optimize import linear_sum_assignment

from ..io.motion_vectors import BLOCK, block_energy_at, mv_field
from ..params import Params, param


@dataclass(frozen=True, kw_only=True)
class CDParams(Params):
    """Compressed-domain object parameters (ch08.md §2; ``proposed`` values where the text gives none)."""

    tau_r: float = param(1024.0, ge=0, doc=(
        "Pseudo-residual energy per 4x4 block above which it counts as non-zero (grey levels^2). ch08.md proposes 64, "
        "exact only on full-pel, non-deblocked encodes; 1024 was chosen on PETS frames 1-200 encoded at crf 23."))
    n_min: int = param(40, ge=1, le=1000, doc="Smallest group in blocks (40 chosen on PETS frames 1-200; ch08.md: 2).")
    max_groups: int = param(10, ge=1, le=100, doc="At most this many groups per frame (L7578).")
    closing: int = param(3, ge=0, le=31, doc=(
        "Close the block mask with a closing x closing block element and fill its holes before grouping (0: off; the "
        "residual AND-rule punches holes into rigid, well-predicted objects)."))
    border: float = param(8.0, ge=0, doc="Border margin in pixels for the into/out-of-frame statuses (L7721).")
    occ_margin: float = param(8.0, ge=0, doc="Box dilation in pixels for the occlusion test (delta_occ).")
    gate_px: float = param(48.0, gt=0, doc="Association gate in pixels at 384 px width (scaled with the width).")
    tau_new: float = param(0.5, ge=0, doc="Eq. (12) dissimilarity above which a reappearing group gets a new label.")
    similarity: Literal["default", "faithful"] = param("default", doc=(
        "'default' (1 + dtheta/180) |dlog10(1+e)| or 'faithful' |dlog10 D| |dlog10 e|."))
    refine: Literal["none", "difference"] = param("difference", doc=(
        "'none': the chapter's rule (a vector and a pseudo-residual above tau_r); 'difference' (our addition, the "
        "default: MOTA -0.26 -> 0.02 on PETS frames 1-200): around the moving blocks (2 blocks), keep the 4x4 blocks "
        "whose plain frame difference exceeds tau_d -- FFmpeg exports 8x8/16x16 partitions, which bleed onto the "
        "background, and the pseudo-residual of an ordinary encode is noisy."))
    tau_d: float = param(8192.0, ge=0, doc="Frame-difference energy per 4x4 block for refine='difference'.")
    trim: bool = param(True, doc=(
        "With refine='difference' and shape='blocks': a frame difference marks the object where it was and where "
        "it is, so each group's box is cut back on its trailing side by the object's displacement, the median vector "
        "of the group's moving blocks (PETS frames 1-200: MOTA 0.02 -> 0.10)."))
    min_speed: float = param(1.0, ge=0, doc=(
        "Blocks whose vector is shorter than this (pixels) count as zero motion: the encoder's sub-pixel vectors on "
        "static texture are noise (1.0 chosen on PETS frames 1-200)."))
    shape: Literal["blocks", "background"] = param("background", doc=(
        "How a group's box is drawn. 'blocks': the bounding box of its 4x4 blocks (the chapter). 'background' (our "
        "addition, the default; pftrack.multi.mv_shape): the foreground pixels of a selectively updated "
        "running-average background, inside the group's widened box and connected to its blocks, one box per "
        "silhouette (PETS frames 1-200, --detector mv: MOTA 0.10 -> 0.45-0.51 over seeds 0-3)."))
    bg_scale: int = param(4, ge=1, le=8, doc=(
        "shape='background': the background's resolution is 1/bg_scale (4: one pixel per 4x4 block; on PETS frames "
        "1-200 MOTA 0.45-0.51 over seeds 0-3, against 0.38-0.46 at 2 and 0.21 at 1, where pixel noise splits "
        "the silhouettes)."))
    bg_alpha: float = param(0.01, gt=0, le=1, doc=(
        "shape='background': running-average rate of the background away from moving blocks (each pixel's first "
        "1/alpha updates are averaged with rate 1/n; 0.01 chosen on PETS frames 1-200)."))
    bg_tau: float = param(35.0, ge=0, doc=(
        "shape='background': |Y - B| above this (grey levels, at 1/bg_scale resolution) is foreground (35 chosen on "
        "PETS frames 1-200 at bg_scale 2, where 30-45 gave MOTA within 0.02; at bg_scale 4, 45 was 0.02-0.08 lower "
        "over seeds 0-3)."))
    bg_margin: float = param(0.5, ge=0, le=3, doc=(
        "shape='background': the region of interest is the group's box widened by this times its larger side."))
    bg_reach: int = param(2, ge=0, le=16, doc=(
        "shape='background': foreground pixels count only within this many 4x4 blocks of a moving block, so that "
        "ghosts of objects that stood still and left stay out of the silhouettes (0: anywhere in the region)."))
    bg_share: float = param(0.3, ge=0, le=1, doc=(
        "shape='background': a silhouette of a group counts when it has at least this share of the group's "
        "largest one (smaller ones are fragments: a hand, a bag, a patch of noise)."))
    split_aspect: float = param(0.4, ge=0, le=10, doc=(
        "shape='background': expected width/height of one object (0.4: people, as multi-pf's object_aspect); "
        "wider silhouettes at least 32 px tall are split side by side, as the blob detectors do (0: never)."))


@dataclass
class Group:
    box: tuple[float, float, float, float]       # x, y, w, h in pixels
    mask: np.ndarray                              # (I, J) bool block mask
    direction: float                              # degrees in [0, 360), image axes (y down)
    energy: float
    velocity: tuple[float, float]
    blocks: int
    parts: list | None = None                     # shape='background': one box per silhouette in the group

    @property
    def pos(self) -> np.ndarray:
        return np.array(self.box[:2])


def foreground_blocks(fwd: np.ndarray, has: np.ndarray, E: np.ndarray, tau_r: float, min_speed: float = 0.25):
    """MV != 0 and residual energy > tau_r (L7563-7568)."""
    return has & (np.hypot(fwd[..., 0], fwd[..., 1]) >= min_speed) & (E > tau_r)


def fill_holes(mask: np.ndarray) -> np.ndarray:
    """``scipy.ndimage.binary_fill_holes`` (4-connected background) of a 0/1 mask, with one OpenCV flood fill:
    the background reachable from outside the padded mask is not a hole.  uint8 0/1."""
    m = np.zeros((mask.shape[0] + 2, mask.shape[1] + 2), np.uint8)
    m[1:-1, 1:-1] = mask != 0
    cv2.floodFill(m, None, (0, 0), 2, flags=4)
    return (m[1:-1, 1:-1] != 2).astype(np.uint8)


def group_blocks(fg: np.ndarray, fwd: np.ndarray, E: np.ndarray, p: CDParams = CDParams()) -> list[Group]:
    m = fg.astype(np.uint8)
    if p.closing:
        m = cv2.morphologyEx(m, cv2.MORPH_CLOSE, np.ones((p.closing, p.closing), np.uint8))
        m = fill_holes(m)
    n, lab, stats, _ = cv2.connectedComponentsWithStats(m, connectivity=8)
    comps = [k for k in range(1, n) if stats[k, cv2.CC_STAT_AREA] >= p.n_min]
    comps = sorted(comps, key=lambda k: -stats[k, cv2.CC_STAT_AREA])[:p.max_groups]
    out = []
    for k in comps:
        mk = lab == k
        x, y, w, h = stats[k, :4]
        win = (slice(y, y + h), slice(x, x + w))          # the component's bounding box: the same elements,
        mw = mk[win]                                      # in the same order, as the full-frame masks
        moving = mw & fg[win]
        sel = moving if moving.any() else mw
        v = fwd[win][sel].mean(axis=0)
        out.append(Group((float(x * BLOCK), float(y * BLOCK), float(w * BLOCK), float(h * BLOCK)), mk,
                         float(np.degrees(np.arctan2(v[1], v[0])) % 360.0), float(E[win][mw].sum()),
                         (float(v[0]), float(v[1])), int(mw.sum())))
    out.sort(key=lambda g: (g.box[1], g.box[0]))      # top-left first (L7604-7606)
    return out


class BlockAnalyser:
    """Per frame: the block motion field, the pseudo-residual's block energies and the groups."""

    def __init__(self, params: CDParams = CDParams()):
        self.p = params
        self.prev_y = None
        self.fg = None
        self.shaper = None
        if params.shape == "background":
            from .mv_shape import SilhouetteShaper

            self.shaper = SilhouetteShaper(params.bg_scale, params.bg_alpha, params.bg_tau, params.bg_margin,
                                           reach=params.bg_reach, min_share=params.bg_share,
                                           split_aspect=params.split_aspect)

    def __call__(self, mvf) -> list[Group]:
        y = mvf.y
        fwd, has = mv_field(mvf.mvs, y.shape)
        if self.prev_y is None or mvf.mvs is None:
            self.prev_y = y
            self.fg = np.zeros(has.shape, bool)
            if self.shaper is not None:
                self.shaper(y, [])
            return []
        moving = has & (np.hypot(fwd[..., 0], fwd[..., 1]) >= self.p.min_speed)
        if self.p.refine == "difference":
            cand = _dilate(moving, 2)
            E = block_energy_at(y, self.prev_y, np.zeros_like(fwd), cand)
            self.fg = cand & (E > self.p.tau_d)
        else:
            E = block_energy_at(y, self.prev_y, fwd, moving)   # only blocks with motion can be foreground
            self.fg = foreground_blocks(fwd, has, E, self.p.tau_r, self.p.min_speed)
        self.prev_y = y
        groups = group_blocks(self.fg, fwd, E, self.p)
        if self.p.refine == "difference" and self.p.trim and self.shaper is None:   # silhouettes replace the trim
            for g in groups:
                # the object's displacement: the median vector of its blocks that move (the difference mask
                # also holds blocks with no or a zero vector, which would shrink a mean)
                bx, by, bw, bh = (int(v) // BLOCK for v in g.box)
                win = (slice(by, by + bh), slice(bx, bx + bw))   # the group's blocks all lie in its box
                sel = g.mask[win] & moving[win]
                if sel.any():
                    g.box = trailing_trim(g.box, np.median(fwd[win][sel], axis=0))
        if self.shaper is not None:
            groups = self.shaper(y, groups, self.fg)
        return groups


def trailing_trim(box, velocity, min_size: float = BLOCK) -> tuple[float, float, float, float]:
    """The box of a frame-difference region ``(x, y, w, h)`` without its trailing part: the difference of two
    frames covers an object moving by ``velocity = (vx, vy)`` pixels at both positions, so the current one is
    the union cut back by ``|v|`` on the side it moved away from (not below ``min_size``)."""
    x, y, w, h = (float(v) for v in box)
    vx, vy = (float(v) for v in velocity)
    cx, cy = min(abs(vx), max(w - min_size, 0.0)), min(abs(vy), max(h - min_size, 0.0))
    return (x + (cx if vx > 0 else 0.0), y + (cy if vy > 0 else 0.0), w - cx, h - cy)


def _dilate(mask: np.ndarray, r: int) -> np.ndarray:
    return cv2.dilate(mask.astype(np.uint8), np.ones((2 * r + 1, 2 * r + 1), np.uint8)).astype(bool)


def _exists(g: Group, groups: list[Group], r: int) -> list[Group]:
    """The groups whose blocks touch ``g``'s blocks dilated by ``r`` blocks (worked on ``g``'s window only:
    the same answer as on the whole grid)."""
    I, J = g.mask.shape
    bx, by, bw, bh = _block_window(g.mask)
    y0, y1, x0, x1 = max(0, by - r), min(I, by + bh + r), max(0, bx - r), min(J, bx + bw + r)
    d = _dilate(g.mask[y0:y1, x0:x1], r)
    return [h for h in groups if np.any(d & h.mask[y0:y1, x0:x1])]


def _block_window(mask: np.ndarray) -> tuple[int, int, int, int]:
    """``(x, y, w, h)`` in blocks of the bounding box of a block mask."""
    x, y, w, h = cv2.boundingRect(mask.view(np.uint8) if mask.dtype == np.bool_ else mask.astype(np.uint8))
    return x, y, w, h


class MVDetector:
    """``--detector mv``: groups that overlap a group of one of the two previous frames (a causal version
    of the 5-frame filter), as boxes; ``foreground`` is the block mask for the particle filters' cue."""

    def __init__(self, source, params: CDParams = CDParams()):
        self.source = source
        self.analyser = BlockAnalyser(params)
        self.history: deque[list[Group]] = deque(maxlen=2)
        self.foreground = None
        if hasattr(source, "analyse"):
            source.analyse = self.detect      # the source runs it as it decodes, ahead of the tracker

    def detect(self, mvf) -> tuple[np.ndarray, tuple | None]:
        """One frame's detections and foreground ``(mask, scale)``, frames taken in order."""
        groups = self.analyser(mvf)
        keep = [g for g in groups if any(_exists(g, past, 1 + k) for k, past in enumerate(reversed(self.history)))]
        self.history.append(groups)
        fg, shaper = self.analyser.fg, self.analyser.shaper
        if shaper is not None and shaper.mask is not None:
            foreground = (shaper.mask * 255, float(shaper.scale))
        else:
            foreground = ((fg.astype(np.uint8) * 255), float(BLOCK)) if fg is not None else None
        boxes = dict.fromkeys(b for g in keep for b in (g.parts or [g.box]))   # a silhouette shared by two groups once
        return np.array(list(boxes), dtype=np.float64).reshape(-1, 4), foreground

    def __call__(self, frame: np.ndarray) -> np.ndarray:
        mvf = self.source.current
        res = mvf.analysis if getattr(mvf, "analysis", None) is not None else self.detect(mvf)
        boxes, self.foreground = res
        return boxes


class TemporalRefiner:
    """Eqs. (3)-(4) over the window f-2..f+2: drop a group seen in at most 2 of the 5 frames; insert a group
    missing at f but present before and after it (and in at least 3 of the other 4 frames, so that it passes
    Eq. 3 itself), with the mean box, direction and energy.  ``push`` takes frame f's groups and returns the
    frames that became final (f-2 once f is known; fewer frames at the start), ``flush`` the rest."""

    def __init__(self):
        self.buf: deque[tuple[int, list[Group]]] = deque()
        self._pos = 0                                   # index in buf of the next frame to emit

    def push(self, number: int, groups: list[Group]) -> list[tuple[int, list[Group]]]:
        self.buf.append((number, groups))
        out = []
        while self._pos + 2 < len(self.buf):
            out.append(self._refine(self._pos))
            self._pos += 1
            while self._pos > 2:
                self.buf.popleft()
                self._pos -= 1
        return out

    def flush(self) -> list[tuple[int, list[Group]]]:
        out = []
        while self._pos < len(self.buf):
            out.append(self._refine(self._pos))
            self._pos += 1
        return out

    def _refine(self, c: int) -> tuple[int, list[Group]]:
        frames = [g for _, g in self.buf]
        number, cur = self.buf[c]
        window = range(max(0, c - 2), min(len(frames), c + 3))
        # Eq. (3): h <= 2 of 5 frames is flicker (at the ends of the video the window is shorter)
        need = min(2, len(window) - 1)
        kept = [g for g in cur if sum(1 for k in window if k == c or _exists(g, frames[k], 1 + abs(k - c))) > need]
        before = [k for k in (c - 1, c - 2) if k >= 0]
        after = [k for k in (c + 1, c + 2) if k < len(frames)]
        for k0 in before:
            for g in frames[k0]:
                if _exists(g, cur, 1 + abs(k0 - c)) or any(_exists(g, [x], 2) for x in kept):
                    continue
                others = {k: _exists(g, frames[k], 1 + abs(k - k0)) for k in before + after if k != k0}
                if 1 + sum(1 for v in others.values() if v) < 3 or not any(others.get(k) for k in after):
                    continue
                members = [g] + [m for v in others.values() for m in v]
                box = tuple(float(np.mean([m.box[i] for m in members])) for i in range(4))
                ang = np.radians([m.direction for m in members])
                mask = np.zeros_like(g.mask)
                I, J = mask.shape
                x0, y0 = int(box[0] // BLOCK), int(box[1] // BLOCK)
                x1, y1 = x0 + max(round(box[2] / BLOCK), 1), y0 + max(round(box[3] / BLOCK), 1)
                mask[max(y0, 0):min(y1, I), max(x0, 0):min(x1, J)] = True
                heading = float(np.degrees(np.arctan2(np.sin(ang).mean(), np.cos(ang).mean())) % 360)
                kept.append(Group(box, mask, heading,
                                  float(np.mean([m.energy for m in members])),
                                  tuple(float(v) for v in np.mean([m.velocity for m in members], axis=0)),
                                  int(mask.sum())))
        return number, kept


@dataclass
class CDObject:
    label: int
    group: Group
    status: int = 0                 # 0 default, 1 occluded, 2 out of frame, 3 stopped, 4 into frame
    frozen: tuple[float, float] | None = None   # (direction, energy) before an occlusion
    hidden: int = 0
    partners: list = field(default_factory=list)    # labels hidden inside this object's merged group
    prev: Group | None = None


def similarity(d1: float, e1: float, d2: float, e2: float, mode: str = "default") -> float:
    """Eq. (12): dissimilarity of direction and energy on log scales."""
    if mode == "faithful":
        return (abs(np.log10(max(d1, 1.0)) - np.log10(max(d2, 1.0)))
                * abs(np.log10(max(e1, 1.0)) - np.log10(max(e2, 1.0))))
    dth = abs((d1 - d2 + 180.0) % 360.0 - 180.0)
    return (1.0 + dth / 180.0) * abs(np.log10(1.0 + e1) - np.log10(1.0 + e2))


class CDTracker:
    """The chapter's labelling of refined groups (Eqs. 5-14, as ch08.md §1.7-1.9 operationalises them).

    Groups are matched to the previous frame's objects by position (Eqs. 11, 14; Hungarian, gated).  An
    object that vanishes into a group that also continues another object is occluded (S1): both freeze their
    pre-occlusion direction and energy, and the continuing object records it as a partner.  When the merged
    group splits again, the pieces near it are assigned to the merged labels by Eq. (12) (Hungarian on the
    direction/energy dissimilarity).  Other vanished objects are out of frame (S2, near the border) or
    stopped (S3, kept); new groups reappearing away from the border are matched to stopped or occluded
    objects by Eq. (12), or get a new label (S4 at the border)."""

    def __init__(self, frame_size: tuple[int, int], params: CDParams = CDParams()):
        self.p = params
        self.W, self.H = frame_size
        self.gate = params.gate_px * self.W / 384.0
        self.active: dict[int, CDObject] = {}
        self.waiting: dict[int, CDObject] = {}       # occluded or stopped: may come back
        self.next_label = 1

    def _near_border(self, box) -> bool:
        x, y, w, h = box
        b = self.p.border
        return x <= b or y <= b or x + w >= self.W - b or y + h >= self.H - b

    @staticmethod
    def _overlap(a, b, m=0.0) -> bool:
        return (a[0] - m < b[0] + b[2] + m and b[0] - m < a[0] + a[2] + m and
                a[1] - m < b[1] + b[3] + m and b[1] - m < a[1] + a[3] + m)

    def _new(self, g: Group) -> CDObject:
        o = CDObject(self.next_label, g, status=4 if self._near_border(g.box) else 0)
        self.next_label += 1
        return o

    def _sim(self, o: CDObject, g: Group) -> float:
        d, e = o.frozen if o.frozen is not None else (o.group.direction, o.group.energy)
        return similarity(d, e, g.direction, g.energy, self.p.similarity)

    def step(self, groups: list[Group]) -> list[CDObject]:
        prev = list(self.active.values())
        assigned: dict[int, int] = {}
        if prev and groups:
            cost = np.array([[np.linalg.norm(o.group.pos - g.pos) for g in groups] for o in prev])
            r, c = linear_sum_assignment(cost)
            for i, j in zip(r, c):
                if cost[i, j] <= self.gate:
                    assigned[j] = i
        new_active: dict[int, CDObject] = {}
        for j, i in assigned.items():
            o = prev[i]
            o.prev, o.group, o.hidden = o.group, groups[j], 0
            o.status = 1 if o.partners else 0
            new_active[o.label] = o
        matched_prev = set(assigned.values())
        for i, o in enumerate(prev):                   # objects that vanished (gamma = 2)
            if i in matched_prev:
                continue
            host = [q for q in new_active.values() if any(
                self._overlap(g.box, o.group.box, self.p.occ_margin) for g in [q.group])]
            if host:                                   # S1: hidden in another object's (merged) group
                q = host[0]
                if not q.partners:
                    src = q.prev if q.prev is not None else q.group
                    q.frozen = (src.direction, src.energy)
                q.partners.append(o.label)
                q.partners.extend(o.partners)
                q.status = o.status = 1
                o.frozen = o.frozen if o.partners else (o.group.direction, o.group.energy)
                o.partners = []
                self.waiting[o.label] = o
            elif self._near_border(o.group.box):
                o.status = 2                           # S2: out of frame, forgotten
            else:
                o.status, o.frozen = 3, (o.group.direction, o.group.energy)   # S3: stopped, kept
                self.waiting[o.label] = o
        leftovers = [j for j in range(len(groups)) if j not in assigned]
        for q in list(new_active.values()):            # a merged group splits (gamma = 1)
            if not q.partners or not leftovers:
                continue
            last = q.prev.box if q.prev is not None else q.group.box
            near = [j for j in leftovers if self._overlap(groups[j].box, last, 2 * self.p.occ_margin + 8)]
            if not near:
                continue
            cands = [self.waiting[lab] for lab in q.partners if lab in self.waiting] + [q]
            gidx = [j for j, i in assigned.items() if prev[i] is q] + near
            cost = np.array([[self._sim(o, groups[j]) for j in gidx] for o in cands])
            r, c = linear_sum_assignment(cost)
            new_active.pop(q.label, None)
            for oi, gi in zip(r, c):
                o, j = cands[oi], gidx[gi]
                o.prev, o.group, o.status, o.hidden, o.partners, o.frozen = o.group, groups[j], 0, 0, [], None
                self.waiting.pop(o.label, None)
                new_active[o.label] = o
                if j in leftovers:
                    leftovers.remove(j)
            for oi in set(range(len(cands))) - set(r):  # still hidden
                o = cands[oi]
                if o is q:
                    self.waiting[o.label] = o
        for j in leftovers:                            # reappearance or entry
            g = groups[j]
            best, best_d = None, np.inf
            if not self._near_border(g.box):
                for lab, o in self.waiting.items():
                    if lab in new_active:
                        continue
                    d = self._sim(o, g)
                    if d < best_d:
                        best, best_d = lab, d
            if best is not None and best_d <= self.p.tau_new:
                o = self.waiting.pop(best)
                o.prev, o.group, o.status, o.hidden, o.frozen = o.group, g, 0, 0, None
                new_active[o.label] = o
            else:
                o = self._new(g)
                new_active[o.label] = o
        for lab in list(self.waiting):
            if lab in new_active:
                self.waiting.pop(lab)
            else:
                self.waiting[lab].hidden += 1
        self.active = new_active
        return list(new_active.values())
