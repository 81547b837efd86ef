"""Crossings of the foreground blobs' foot points near the wire (pftrack's addition to ch. 10).

The patches of the trackerless tripwire see a crossing when an appearance new to one side of the wire
matches one seen earlier on the other side, moving away from the wire. A walker who reaches a
horizontal ground line obliquely, along it, has covered the patches of both sides with their body
before their feet cross: nothing new arrives on the far side when the crossing happens, and their
motion is along the wire, so the crossing test never fires (docs/tripwire.md).

:class:`FootCrossings` gives such crossings a second way in. Every blob of the closed foreground
near the wire (the blobs the foot timing already labels, :mod:`.timing`) is followed from frame to
frame by overlap, for as long as it is seen, and its box's foot point goes through the same
hysteresis state machine as the tracker-based tripwire (:func:`.geometry.crossings_of_track`). Nothing
is tracked through occlusions or across gaps: a blob that is not seen on a frame is forgotten, and a
blob that appears starts without a side. A blob that splits off a followed one starts on its parent's
side if its point is on the wire (``inherit="wire"``: a walker who crossed while merged with another),
and on its own otherwise. A blob that already produced an event of the same direction from the
patches (or from its foot point) within ``window`` frames is not counted again, and a patch event on a
blob counted by its foot point is dropped.

:func:`estimate_radius` reads the patch radius from the foreground blobs near the wire (``--radius
auto``), :func:`estimate_speed` the block matching's speed limit from their motion (``--v-max auto``), and
:func:`label_stats` the blobs' boxes from a label image.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from ..cues.foreground import GREY_SHADOW_THRESHOLD, Foreground, apply_levels
from .geometry import _segments, polyline_project

__all__ = ["FootCrossings", "FootEvent", "estimate_radius", "estimate_speed", "label_stats"]


@dataclass(frozen=True)
class FootEvent:
    """A blob's foot point crossing the wire: the interpolated frame and time, direction, point."""

    frame: int
    time_s: float
    direction: int
    x: float
    y: float
    area: int


@dataclass
class _Blob:
    state: int = 0                       # -1 / +1: the side its point was last seen clearly on; 0: none yet
    tail: list = field(default_factory=list)   # (number, t, signed, x, y) since the last clear point
    counted: dict = field(default_factory=dict)  # (source, direction) -> frame number of its last event
    pending: FootEvent | None = None     # a crossing held for ``hold`` frames
    age: int = 0                         # frames the pending crossing has been held


class FootCrossings:
    """Blobs followed by overlap and their foot (or centre) points' crossings of the wire.

    ``origin`` is the ROI's top-left pixel and ``width`` its width (the labels are ROI images).
    ``hysteresis`` px each side of the wire, ``min_area`` px of a blob to be followed, ``window`` frames
    within which one blob's events of one direction are one event, ``hold`` processed frames a crossing
    waits before it is counted, dropped if the point goes back across the wire meanwhile (a blob whose
    bottom jumps when MOG2 loses and finds the feet crosses and crosses back); a crossing of a blob that
    is no longer seen is counted at once.
    """

    def __init__(self, polyline: np.ndarray, origin: tuple[int, int], width: int, *, point: str = "foot",
                 hysteresis: float = 5.0, min_area: int = 60, window: float = 20.0, hold: int = 0,
                 inherit: str = "wire"):
        self.polyline = np.asarray(polyline, dtype=np.float64)
        self.x0, self.y0 = origin
        self.width = int(width)
        self.point = point
        self.hysteresis = float(hysteresis)
        self.min_area = int(min_area)
        self.window = float(window)
        self.hold = max(0, int(hold))
        if inherit not in ("wire", "always", "never"):
            raise ValueError(f"inherit must be wire, always or never, got {inherit!r}")
        self.inherit = inherit
        a, _b, u, _n, _l, _c = _segments(self.polyline)
        self._a0, self._u0, self._u1 = a[0], u[0], u[-1]
        self._nseg = len(a)
        self.blobs: dict[int, _Blob] = {}
        self._next = 0
        self._prev: np.ndarray | None = None   # the previous frame's labels (flat)
        self._bid_of: dict[int, int] = {}      # the previous frame's label -> blob id

    # -- geometry ------------------------------------------------------------------------------
    def _points(self, stats: np.ndarray) -> np.ndarray:
        """The foot (bottom centre) or centre of each labelled blob's box, in frame pixels."""
        x, y, w, h = (stats[:, k].astype(np.float64) for k in range(4))
        cx = x + 0.5 * (w - 1.0)
        cy = y + h - 0.5 if self.point == "foot" else y + 0.5 * (h - 1.0)
        return np.stack([cx + self.x0, cy + self.y0], axis=1)

    def _signed(self, pts: np.ndarray) -> np.ndarray:
        """Signed offsets from the wire, NaN where the projection falls beyond the wire's ends."""
        if len(pts) == 0:
            return np.zeros(0)
        _, _, seg, _, signed = polyline_project(pts, self.polyline)
        t0 = (pts - self._a0) @ self._u0
        t1 = (pts - self.polyline[-1]) @ self._u1
        off = ((seg == 0) & (t0 < 0)) | ((seg == self._nseg - 1) & (t1 > 0))
        return np.where(off, np.nan, signed)

    # -- per frame -----------------------------------------------------------------------------
    def _follow(self, flat: np.ndarray, areas: np.ndarray) -> tuple[dict[int, int], dict[int, int]]:
        """Each followed blob's label on this frame: the label covering most of its pixels of the previous
        frame (where two blobs take one label, the larger overlap keeps it, and the other is forgotten); and,
        for the other labels, the blob they overlap most (a blob that split in two: its parent)."""
        prev = self._prev
        if prev is None or not self.blobs:
            return {}, {}
        n = len(areas)
        idx = np.flatnonzero((prev > 0) & (flat > 0))  # a boolean mask: fast
        if idx.size == 0:
            return {}, {}
        cnt = np.bincount(prev[idx].astype(np.int64) * n + flat[idx], minlength=0)
        pairs = np.flatnonzero(cnt)
        best: dict[int, tuple[int, int]] = {}   # previous label -> (overlap, label)
        parent: dict[int, tuple[int, int]] = {}  # label -> (overlap, previous label)
        for k, lab, c in zip((pairs // n).tolist(), (pairs % n).tolist(), cnt[pairs].tolist()):
            if k not in self._bid_of:
                continue
            if k not in best or (c, lab) > best[k]:
                best[k] = (c, lab)
            if lab not in parent or (c, k) > parent[lab]:
                parent[lab] = (c, k)
        claims = sorted(((ov, self._bid_of[k], lab) for k, (ov, lab) in best.items() if areas[lab] >= self.min_area),
                        reverse=True)
        taken: dict[int, int] = {}
        for _, bid, lab in claims:
            if lab not in taken:
                taken[lab] = bid
        return taken, {lab: self._bid_of[k] for lab, (_, k) in parent.items() if lab not in taken}

    def step(self, labels: np.ndarray, stats: np.ndarray, number: int, t: float,
             patch_events: list) -> tuple[list, list[FootEvent]]:
        """Follow the blobs of this frame's ``labels`` (ROI, 0 = background; ``stats`` as OpenCV's
        ``connectedComponentsWithStats``: ``x, y, w, h, area`` per label).

        ``patch_events``: ``(event, label)`` of the patch events released on this frame (label 0: unknown).
        Returns the patch events that are not a blob already counted by its foot point, and the foot
        crossings of blobs not counted by a patch event.
        """
        flat = labels.ravel()
        areas = stats[:, cv2.CC_STAT_AREA]
        taken, parents = self._follow(flat, areas)
        big = np.flatnonzero(areas >= self.min_area)
        big = big[big > 0]
        blobs: dict[int, _Blob] = {}
        by_label: dict[int, int] = {}
        heirs: dict[int, int] = {}   # a blob split off a followed one -> that blob's id
        for lab in big.tolist():
            bid = taken.get(lab)
            if bid is None:
                bid = self._next
                self._next += 1
                blobs[bid] = _Blob()
                p = parents.get(lab)
                if self.inherit != "never" and p is not None:  # split off a followed blob
                    heirs[bid] = p
            else:
                blobs[bid] = self.blobs[bid]
            by_label[lab] = bid
        parent_of = {bid: self.blobs[p] for bid, p in heirs.items()}
        gone = [b for bid, b in self.blobs.items() if bid not in blobs and b.pending is not None]
        self.blobs = blobs
        self._bid_of = by_label
        self._prev = flat  # a fresh label image every frame: kept, not copied
        kept = []
        for ev, lab in patch_events:
            bid = by_label.get(lab)
            if bid is not None and not self._count(blobs[bid], "patch", ev.direction, ev.frame, ("foot",)):
                continue
            kept.append(ev)
        # a held crossing of a blob no longer seen (merged, gone) is counted
        found = [ev for ev in map(self._release, gone) if ev is not None]
        if not by_label:
            return kept, found
        labs = np.fromiter(by_label, np.int64, len(by_label))
        pts = self._points(stats[labs])
        signed = self._signed(pts)
        for k, lab in enumerate(labs.tolist()):
            bid = by_label[lab]
            b = blobs[bid]
            if bid in parent_of and (self.inherit == "always" or abs(signed[k]) < self.hysteresis):
                # split off a followed blob on the wire: it was on its parent's side (a child clear of the wire
                # takes its own, with "wire": the parent's side may have been another object's, merged with it)
                b.state, b.tail = parent_of[bid].state, list(parent_of[bid].tail)
            ev = self._advance(b, number, t, float(signed[k]), pts[k], int(areas[lab]))
            if ev is not None and self._count(b, "foot", ev.direction, ev.frame, ("patch", "foot")):
                found.append(ev)
        return kept, found

    def _count(self, b: _Blob, source: str, direction: int, frame: int, against: tuple[str, ...]) -> bool:
        """Count an event of ``b`` from ``source`` in ``direction`` at ``frame``, unless an event from one of
        the ``against`` sources was counted within ``window`` (two patch events on one blob may be two
        objects walking side by side; the patches' own rules merge them)."""
        for src in against:
            last = b.counted.get((src, direction))
            if last is not None and abs(frame - last) <= self.window:
                return False
        b.counted[(source, direction)] = frame
        return True

    def _advance(self, b: _Blob, number: int, t: float, v: float, xy: np.ndarray, area: int) -> FootEvent | None:
        """The hysteresis state machine of :func:`.geometry.crossings_of_track`, one point at a time; a
        crossing is released after ``hold`` more frames unless the point has gone back meanwhile."""
        if b.pending is not None:
            b.age += 1
        if np.isfinite(v):
            b.tail.append((number, t, v, float(xy[0]), float(xy[1])))
            h = self.hysteresis
            new = -1 if v <= -h else (1 if v >= h else 0)
            if new != 0:
                if b.pending is not None and new != b.pending.direction:
                    b.pending = None  # back on the old side: it did not cross
                elif b.pending is None and b.state != 0 and new != b.state:
                    j = len(b.tail) - 1
                    while j > 1 and np.sign(b.tail[j - 1][2]) == np.sign(v):
                        j -= 1
                    (n0, t0, s0, x0, y0), (n1, t1, s1, x1, y1) = b.tail[j - 1], b.tail[j]
                    frac = 0.0 if s1 == s0 else float(np.clip(-s0 / (s1 - s0), 0.0, 1.0))
                    b.pending = FootEvent(int(round(n0 + frac * (n1 - n0))), t0 + frac * (t1 - t0), new,
                                          x0 + frac * (x1 - x0), y0 + frac * (y1 - y0), area)
                    b.age = 0
                elif b.pending is None:
                    b.state = new
                b.tail = [b.tail[-1]]
        if b.pending is not None and b.age >= self.hold:
            ev, b.pending = b.pending, None
            b.state = ev.direction
            return ev
        return None

    def _release(self, b: _Blob) -> FootEvent | None:
        """A blob's held crossing, now, unless an event already counted the blob."""
        ev, b.pending = b.pending, None
        return ev if ev is not None and self._count(b, "foot", ev.direction, ev.frame, ("patch", "foot")) else None

    def finish(self) -> list[FootEvent]:
        """At the end of the stream: the crossings still held."""
        return [ev for ev in map(self._release, self.blobs.values()) if ev is not None]


def label_stats(labels: np.ndarray) -> np.ndarray:
    """``(n_labels, 5)``: each label's box and area, ``x, y, w, h, area`` as OpenCV's
    ``connectedComponentsWithStats`` gives them (row 0, the background, left at zero), from the labelled
    pixels only (OpenCV's statistics cost ten times the labelling)."""
    flat = labels.ravel()
    idx = np.flatnonzero(flat > 0)   # on a boolean mask: several times faster than on the labels
    n = int(flat[idx].max()) + 1 if idx.size else 1
    out = np.zeros((n, 5), np.int64)
    if idx.size == 0:
        return out
    lab = flat[idx]
    # a stable sort of 16-bit keys is a radix sort
    order = np.argsort(lab.astype(np.uint16) if n <= 65536 else lab, kind="stable")
    lab, idx = lab[order], idx[order]
    ys, xs = np.divmod(idx, labels.shape[1])
    starts = np.flatnonzero(np.r_[True, lab[1:] != lab[:-1]])
    ids = lab[starts]
    x_lo, x_hi = np.minimum.reduceat(xs, starts), np.maximum.reduceat(xs, starts)
    out[ids, 0] = x_lo
    out[ids, 1] = ys[starts]                       # the pixels are in raster order within a label
    out[ids, 2] = x_hi - x_lo + 1
    out[ids, 3] = np.maximum.reduceat(ys, starts) - ys[starts] + 1
    out[ids, 4] = np.diff(np.r_[starts, lab.size])
    return out


def _near_blobs(frames, pts: np.ndarray, near: float, min_area: int, grey_shadow_threshold: float, gain: float,
                smooth: bool):
    """Per frame, the tripwire's foreground blobs (MOG2, ``grey_shadow_threshold``; the frames smoothed and multiplied
    by ``gain`` as ``dark_denoise`` and ``dark_stretch`` decide, :func:`~pftrack.events.tripwire.dark_levels`; a 3 x 3
    opening): ``(labels, stats, centroids, idx)``, ``idx`` the labels of the blobs of at least ``min_area`` pixels
    whose centroids lie within ``near`` px of the wire ``pts``."""
    bgs = Foreground(500, 16.0, grey_shadow_threshold=grey_shadow_threshold)
    kernel = np.ones((3, 3), np.uint8)
    for frame in frames:
        fg = cv2.morphologyEx(bgs.apply(apply_levels(frame, gain, smooth)), cv2.MORPH_OPEN, kernel)
        _, labels, stats, cent = cv2.connectedComponentsWithStats(fg)
        idx = np.flatnonzero(stats[1:, cv2.CC_STAT_AREA] >= min_area) + 1
        if len(idx):
            idx = idx[polyline_project(cent[idx], pts)[0] <= near]
        yield labels, stats, cent, idx


def estimate_radius(frames, polyline: np.ndarray, *, near: float = 50.0, min_area: int = 60,
                    default: float = 12.0, grey_shadow_threshold: float = GREY_SHADOW_THRESHOLD,
                    gain: float = 1.0, smooth: bool = False) -> float:
    """``--radius auto`` (ch10.md §1.2, proposed): half the median short side of the foreground blobs whose
    centroids lie within ``near`` px of the wire, over the given frames (e.g. the first 10 s); the foreground is
    the tripwire's (:func:`_near_blobs`)."""
    sides = []
    for _, stats, _, idx in _near_blobs(frames, np.asarray(polyline, dtype=np.float64), near, min_area,
                                        grey_shadow_threshold, gain, smooth):
        st = stats[idx]
        sides += np.minimum(st[:, cv2.CC_STAT_WIDTH], st[:, cv2.CC_STAT_HEIGHT]).tolist()
    return float(0.5 * np.median(sides)) if len(sides) >= 5 else float(default)


def estimate_speed(frames, polyline: np.ndarray, fps: float, *, near: float = 150.0, min_area: int = 60,
                   quantile: float = 0.95, factor: float = 2.0, min_samples: int = 10, default: float = 600.0,
                   grey_shadow_threshold: float = GREY_SHADOW_THRESHOLD, gain: float = 1.0,
                   smooth: bool = False) -> float:
    """``--v-max auto``: the block matching's speed limit ``v_max`` (px/s) read from the given frames (e.g. the
    first 10 s, ``fps`` frames a second as given): ``factor`` times the ``quantile`` of the speeds of the foreground
    blobs whose centroids lie within ``near`` px of the wire. A blob's speed is its centroid's displacement from the
    blob of the frame before that it overlaps most, when their areas are within a factor 1.5 of each other (merges
    and splits are left out). ``default`` when fewer than ``min_samples`` speeds were read. The foreground is the
    tripwire's (:func:`_near_blobs`)."""
    speeds: list[float] = []
    prev = None  # (labels, areas, centroids) of the frame before
    for labels, stats, cent, idx in _near_blobs(frames, np.asarray(polyline, dtype=np.float64), near, min_area,
                                                grey_shadow_threshold, gain, smooth):
        areas = stats[:, cv2.CC_STAT_AREA]
        if prev is not None:
            p_labels, p_areas, p_cent = prev
            for i in idx:
                x, y, bw, bh = stats[i, :4]
                box = (slice(y, y + bh), slice(x, x + bw))  # the blob's box: its pixels and what lay under them
                under = np.bincount(p_labels[box][labels[box] == i], minlength=len(p_areas))
                under[0] = 0
                j = int(np.argmax(under))
                if under[j] == 0 or not 1 / 1.5 <= areas[i] / p_areas[j] <= 1.5:
                    continue
                speeds.append(float(np.hypot(*(cent[i] - p_cent[j]))) * fps)
        prev = (labels, areas, cent)
    if len(speeds) < min_samples:
        return float(default)
    return float(factor * np.quantile(speeds, quantile))
