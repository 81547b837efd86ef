"""The trackerless tripwire ("NTT") of book ch. 10: crossings counted without tracking anything.

Ground patches of radius ``r`` lie on both sides of a polyline (:func:`~.geometry.build_patches`).
Per frame (ch10.md §1.3–1.4):

1. a background subtractor (MOG2 with shadows as background on colour frames, 3×3 opening; or three-frame
   differencing) runs on the wire's neighbourhood only;
2. a patch whose disc is at least ``fg_ratio`` foreground takes a colour histogram of its
   foreground pixels; it is appended to the patch's history when it differs from the last
   entry (``D_B > novelty``) or the patch was background since that entry, and the patch's
   motion is then measured by SSD block matching;
3. a new appearance on an outer patch whose motion leaves the wire (Eq. 4) is compared with
   every inner history entry old enough (``t_th``) and, unless ``faithful``, fresh enough
   (``t_max``): ``S = α_c S_c + α_m S_m`` (Eqs. 5–7); ``max S > threshold`` is a positive
   crossing.  Negative crossings swap the sides.

Proposed additions, each off with ``faithful=True`` (ch10.md §1.4, P9, P13): entries keep a
first-seen and a last-seen time (T_th on the first, T_max on the last); a matched entry is
consumed; an outer patch fires once until it is background again; an event where a
recent one's motion has taken its object, or that lies in one foreground blob with a very
recent one (``group_blob``), is merged into it (``group``); only patches of
the other side within ``max_lateral``·r of arc are compared; C_d asks for a motion of at
least ``min_motion`` pointing within ``away_angle`` of straight away from the wire; an event is
dated, and confirmed, by the frame where its object's foot point passes the wire (``timing``,
``confirm``; :mod:`.timing`); the blobs near the wire are followed while they are seen, and a blob
whose foot point crosses the wire is a crossing unless a patch event counted it (``feet``;
:mod:`.blobs`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from ..cues import foreground as _fg
from ..cues.foreground import PACK_ROWS, Foreground, apply_levels
from ..cues.still_gain import frame_undo
from .blobs import FootCrossings, estimate_radius
from .geometry import PatchLayout, band_rects, blocks_outside, build_patches
from .scoring import bhattacharyya_distance, colour_bins, patch_similarity, ssd_motion
from .timing import CrossingTimer
from .tripwire_params import TripwireParams

__all__ = ["CrossingEvent", "TrackerlessTripwire", "TripwireParams", "dark_levels", "estimate_radius"]


@dataclass
class CrossingEvent:
    """One detected crossing."""

    frame: int
    time_s: float
    direction: int          # +1 positive (inner -> outer), -1 negative
    to_patch: int           # the patch where the object arrived (-1: a blob's foot crossing, ``feet``)
    from_patch: int         # the patch of the matched earlier appearance (-1: a blob's foot crossing)
    tau_frame: int          # frame of that appearance (first seen)
    score: float
    s_color: float
    s_motion: float
    x: float
    y: float
    vx: float
    vy: float


def _foot_event(f) -> CrossingEvent:
    """A blob's foot crossing (:class:`.blobs.FootEvent`) as a row of the output: no patches, no scores."""
    nan = float("nan")
    return CrossingEvent(f.frame, f.time_s, f.direction, -1, -1, f.frame, nan, nan, nan, f.x, f.y, 0.0, 0.0)


@dataclass
class _Entry:
    hist: np.ndarray
    v: np.ndarray
    first: float
    last: float
    frame: int
    used: bool = False


@dataclass
class _Patch:
    entries: list[_Entry] = field(default_factory=list)
    fg: bool = False
    gap: bool = True        # background since the last append
    armed: bool = True      # may fire (refractory)


def dark_levels(frame: np.ndarray, p: TripwireParams) -> tuple[float, bool]:
    """``(gain, smooth)`` of ``dark_stretch`` and ``dark_denoise`` on a first frame
    (:func:`pftrack.cues.foreground.dark_levels`); ``(1, False)`` when ``faithful``."""
    return (1.0, False) if p.faithful else _fg.dark_levels(frame, p.dark_stretch, p.dark_denoise)


class TrackerlessTripwire:
    """``process(frame, frame_number)`` → the crossings found on that frame.

    ``fps`` converts frame numbers to seconds (T_th, T_max, the SSD range); with a frame
    stride the caller passes the original frame numbers and ``fps``.
    """

    def __init__(self, polyline: np.ndarray, shape: tuple[int, int], fps: float, params: TripwireParams | None = None,
                 stride: int = 1):
        self.params = p = params or TripwireParams()
        self.polyline = np.asarray(polyline, dtype=np.float64)
        self.fps, self.stride = float(fps), int(stride)
        self.layout: PatchLayout = build_patches(self.polyline, r=p.radius, spacing=p.spacing)
        h, w = shape
        r = p.radius
        self.search = int(max(np.ceil(r), np.ceil(p.v_max * stride / self.fps)))
        half = int(np.ceil(r))
        pad = half + self.search + int(np.ceil(1.5 * r)) + 2
        lo = np.floor(self.layout.centres.min(0) - pad).astype(int)
        hi = np.ceil(self.layout.centres.max(0) + pad).astype(int)
        self.x0, self.y0 = max(0, lo[0]), max(0, lo[1])
        self.x1, self.y1 = min(w, hi[0]), min(h, hi[1])
        rw, rh = self.x1 - self.x0, self.y1 - self.y0
        if rw <= 0 or rh <= 0:
            raise ValueError("the tripwire lies outside the frame")
        dy, dx = np.mgrid[-half:half + 1, -half:half + 1]
        disc = (dx ** 2 + dy ** 2) <= r * r
        dx, dy = dx[disc], dy[disc]
        c = np.round(self.layout.centres).astype(int) - [self.x0, self.y0]
        xs = np.clip(c[:, 0:1] + dx[None], 0, rw - 1)
        ys = np.clip(c[:, 1:2] + dy[None], 0, rh - 1)
        self._disc = ys * rw + xs                      # (m, D) flat ROI indices of each disc
        self._disc_yx = (ys, xs)                       # the same as rows and columns
        below = np.clip(c[:, 1:2] + dy[None] + int(round(1.5 * r)), 0, rh - 1)
        self._below = below * rw + xs                  # the same discs 1.5 r lower
        self.half = half
        # the prior is on the object's speed: a displacement over K frames is K times one frame's
        self._prior = 0.0 if p.faithful else p.motion_prior / self.stride ** 2
        self.patches = [_Patch() for _ in range(len(self.layout.centres))]
        self._bgs: Foreground | None = None  # the background model (None: 3-frame difference)
        self._bgs_near: Foreground | None = None  # bgs_outer_scale: the full-size model of the pixels near the wire
        if p.bgs in ("mog2", "mog"):
            k = p.bgs_scale
            reach = min(pad + r, p.bgs_reach * r) if p.bgs_reach > 0 else pad + r
            rects = band_rects(self.polyline / k, (self.x0 / k, self.y0 / k), (max(rh // k, 1), max(rw // k, 1)),
                               reach / k + (k > 1)) if p.bgs_band else None
            rects = rects or None  # no pixel within reach (a wire outside the view): the whole box
            kw = dict(grey_shadow_threshold=p.bgs_grey_shadow_threshold, rate_k=p.bgs_rate_k, model=p.bgs,
                      mog_ratio=p.bgs_mog_ratio)
            split = (rects is not None and p.bgs_outer_scale > 1 and k == 1 and p.bgs_near * r < reach
                     and not p.faithful)
            models = self._split_models(p, kw, rh, rw, p.bgs_near * r, reach) if split else None
            if models is None:
                self._bgs = Foreground(p.bgs_history, p.bgs_threshold, rects=rects, scale=k, **kw)
            else:
                self._bgs, self._bgs_near = models
        self._gain: float | None = None  # dark_stretch's gain and dark_denoise's decision, on the first frame
        self._cast = None if p.faithful else frame_undo(p)
        self._denoise = False
        self._prev_gray: np.ndarray | None = None
        self._prev2_gray: np.ndarray | None = None
        self._kernel = np.ones((3, 3), np.uint8)
        self._recent: list[CrossingEvent] = []
        self._timer = None if p.timing == "match" or p.faithful else CrossingTimer(
            self.polyline, (self.x0, self.y0), rw, point=p.timing, hold_time=p.hold_time,
            close=int(round(p.blob_close * r)), confirm=p.confirm,
            lookback=int(np.ceil(p.lookback * self.fps / self.stride)), merge=p.merge_blob,
            max_width=p.crowd_width * 2.0 * r,
            feet=FootCrossings(self.polyline, (self.x0, self.y0), rw, point=p.timing, hysteresis=p.foot_hysteresis,
                               min_area=int(round(p.foot_min_area * r * r)),
                               window=p.foot_window * self.fps, hold=p.foot_hold,
                               inherit=p.foot_inherit) if p.feet else None)
        self.frames = 0
        # bgs_bootstrap: the first frames' regions, held until the background is started from them
        self._boot_n = (max(3, int(round(p.bgs_bootstrap * self.fps / self.stride)))
                        if p.bgs_bootstrap > 0 and p.bgs == "mog2" and not p.faithful else 0)
        self._held: list[tuple[np.ndarray, int]] | None = [] if self._boot_n else None

    def _split_models(self, p: TripwireParams, kw: dict, rh: int, rw: int, near: float, reach: float):
        """``bgs_outer_scale``: the model of the band at that reduction, without the blocks that lie wholly among
        the pixels within ``near`` of the wire, and the full-size model of those pixels; None when either region
        holds no pixel of the view."""
        k = p.bgs_outer_scale
        outer = band_rects(self.polyline / k, (self.x0 / k, self.y0 / k), (max(rh // k, 1), max(rw // k, 1)),
                           reach / k + 1)
        rects = band_rects(self.polyline, (self.x0, self.y0), (rh, rw), near)
        if not outer or not rects:
            return None
        inside = np.zeros((rh, rw), bool)
        for y0, y1, x0, x1 in rects:
            inside[y0:y1, x0:x1] = True
        outer = blocks_outside(outer, inside, k, PACK_ROWS)  # the full-size model's blocks need no reduced label
        return (Foreground(p.bgs_history, p.bgs_threshold, rects=outer, scale=k, **kw),
                Foreground(p.bgs_history, p.bgs_threshold, rects=rects, **kw))

    # -- per frame ------------------------------------------------------------------------------
    def _apply_bgs(self, roi: np.ndarray) -> np.ndarray:
        fg = self._bgs.apply(roi)
        if self._bgs_near is not None:  # its rectangles' labels written over the reduced model's
            self._bgs_near.apply(roi, out=fg)
        return fg

    def foreground(self, roi: np.ndarray, gray: np.ndarray) -> np.ndarray:
        p = self.params
        if self._bgs is not None:
            fg = self._apply_bgs(roi)
        else:
            if self._prev_gray is None or self._prev2_gray is None:
                fg = np.zeros(gray.shape, np.uint8)
            else:
                a = cv2.absdiff(gray, self._prev_gray) > p.diff_threshold
                b = cv2.absdiff(self._prev_gray, self._prev2_gray) > p.diff_threshold
                fg = (a | b).astype(np.uint8)
        return cv2.morphologyEx(fg, cv2.MORPH_OPEN, self._kernel)

    def process(self, frame: np.ndarray, number: int) -> list[CrossingEvent]:
        if self._gain is None:  # the first frame decides (dark_stretch, dark_denoise)
            self._gain, self._denoise = dark_levels(frame, self.params)
        roi = frame[self.y0:self.y1, self.x0:self.x1]
        if self._cast is not None and frame.ndim == 3:  # cast_jump: read on the whole frame, undone on the wire's part
            self._cast.read(frame)
            roi = self._cast.undo(roi)
        if roi.ndim == 2:
            roi = cv2.cvtColor(roi, cv2.COLOR_GRAY2BGR)
        roi = apply_levels(roi, self._gain, self._denoise)
        if self._held is None:
            return self._process(roi, number)
        self._held.append((roi.copy(), number))
        return self._release_held() if len(self._held) >= self._boot_n else []

    def _release_held(self) -> list[CrossingEvent]:
        """``bgs_bootstrap``: start the background from the held frames, then process them."""
        held, self._held = self._held or [], None
        if held:
            for model in [self._bgs] + ([self._bgs_near] if self._bgs_near is not None else []):
                model.prime([r for r, _ in held])
        return [ev for roi, n in held for ev in self._process(roi, n)]

    def _process(self, roi: np.ndarray, number: int) -> list[CrossingEvent]:
        p = self.params
        gray = cv2.cvtColor(roi, cv2.COLOR_BGR2GRAY)
        fg2d = self.foreground(roi, gray)
        self._fg = fg2d
        self._labels = None
        fg = fg2d.ravel()
        t = number / self.fps
        frac = fg[self._disc].mean(1)
        is_fg = frac >= p.fg_ratio
        if p.contact == "bottom":
            is_fg &= fg[self._below].mean(1) < p.fg_ratio
        events: list[CrossingEvent] = []
        new_app = np.zeros(len(self.patches), dtype=bool)
        rows = np.flatnonzero(is_fg)
        if len(rows) and self._prev_gray is not None:
            nb = 1 << (3 * p.bits)
            pix = self._disc[rows]                                    # (k, D)
            bins = colour_bins(roi[self._disc_yx[0][rows], self._disc_yx[1][rows]], p.bits)  # the discs' pixels
            wts = fg[pix].astype(np.float64) if p.hist_pixels == "fg" else np.ones(pix.shape)
            ids = (np.arange(len(rows))[:, None] * nb + bins).ravel()
            hists = np.bincount(ids, weights=wts.ravel(), minlength=len(rows) * nb).reshape(len(rows), nb)
            hists /= np.maximum(hists.sum(1, keepdims=True), 1e-12)
            for k, i in enumerate(rows):
                if self._update_history(i, hists[k], t, number, gray):
                    new_app[i] = True
        for i, patch in enumerate(self.patches):
            if not is_fg[i]:
                patch.gap = True
                patch.armed = True
            patch.fg = bool(is_fg[i])
        for i in np.flatnonzero(new_app):
            ev = self._test(i, t, number)
            if ev is not None:
                events.append(ev)
        if self._timer is not None:
            events, feet = self._timer.step(fg2d, events, number, t, lambda i: self._disc[i])
            events += [_foot_event(f) for f in feet]
        self._prev2_gray, self._prev_gray = self._prev_gray, gray
        self.frames += 1
        return events

    def finish(self) -> list[CrossingEvent]:
        """At the end of the stream: the events still waiting for their point to cross (none with confirm), after
        the frames still held for ``bgs_bootstrap``."""
        held = self._release_held() if self._held is not None else []
        if self._timer is None:
            return held
        feet = self._timer.feet.finish() if self._timer.feet is not None else []
        return held + self._timer.finish() + [_foot_event(f) for f in feet]

    def _update_history(self, i: int, hist: np.ndarray, t: float, number: int, gray: np.ndarray) -> bool:
        p = self.params
        patch = self.patches[i]
        last = patch.entries[-1] if patch.entries else None
        if last is not None and not patch.gap and float(bhattacharyya_distance(hist, last.hist[None])[0]) <= p.novelty:
            last.last = t  # the same object is still there (P13)
            return False
        c = self.layout.centres[i] - [self.x0, self.y0]
        v, _ = ssd_motion(self._prev_gray, gray, c, self.half, self.search, mask=self._fg,
                          penalty=self._prior)
        patch.entries.append(_Entry(hist, v, t, t, number))
        if len(patch.entries) > p.max_entries:
            patch.entries.pop(0)
        patch.gap = False
        return True

    def _test(self, i: int, t: float, number: int) -> CrossingEvent | None:
        """Eqs. 4–7 for the new appearance on patch ``i`` against the other side's histories."""
        p = self.params
        side = int(self.layout.side[i])
        direction = 1 if side == 1 else -1
        if p.direction == "positive" and direction < 0 or p.direction == "negative" and direction > 0:
            return None
        patch = self.patches[i]
        if not p.faithful and not patch.armed:
            return None
        new = patch.entries[-1]
        speed = float(np.hypot(*new.v))
        if float(new.v @ self.layout.w[i]) >= 0:  # C_d: must move away from the wire (Eq. 4)
            return None
        if not p.faithful and (speed < p.min_motion or
                               -float(new.v @ self.layout.w[i]) < np.cos(np.radians(p.away_angle)) * speed):
            return None
        arc = self.layout.arc
        if not p.faithful and p.fresh_time > 0 and self._seen_on_side(i, new, t):
            return None
        cand = []
        for j in self.layout.of_side(-side):
            if not p.faithful and abs(arc[j] - arc[i]) > p.max_lateral * p.radius:
                continue
            for e in self.patches[j].entries:
                if e.first > t - p.t_th or e.used and not p.faithful:
                    continue
                if not p.faithful and e.last < t - p.t_max:
                    continue
                cand.append((j, e))
        if not cand:
            return None
        H = np.stack([e.hist for _, e in cand])
        V = np.stack([e.v for _, e in cand])
        S, s_c, s_m = patch_similarity(new.hist, new.v, H, V, alpha_c=p.alpha_c, alpha_m=p.alpha_m, colour=p.colour)
        k = int(np.argmax(S))
        if S[k] <= p.threshold:
            return None
        j, entry = cand[k]
        c = self.layout.centres[i]
        ev = CrossingEvent(number, t, direction, int(i), int(j), int(entry.frame), float(S[k]), float(s_c[k]),
                           float(s_m[k]), float(c[0]), float(c[1]), float(new.v[0]), float(new.v[1]))
        if not p.faithful:
            entry.used = True
            for q in self._run_of(i):  # one object, one event: its whole foreground run waits for background
                self.patches[q].armed = False
            if p.group and self._duplicate(ev):
                return None
            self._recent = [e for e in self._recent if t - e.time_s <= p.group_time] + [ev]
        return ev

    def _seen_on_side(self, i: int, new: _Entry, t: float) -> bool:
        """Did a nearby patch of ``i``'s own side see this appearance in the last ``fresh_time`` seconds?"""
        p = self.params
        arc = self.layout.arc
        H, V = [], []
        for j in self.layout.of_side(int(self.layout.side[i])):
            if abs(arc[j] - arc[i]) > p.max_lateral * p.radius:
                continue
            for e in self.patches[j].entries:
                if e is new or e.first >= t or e.last < t - p.fresh_time:
                    continue
                H.append(e.hist)
                V.append(e.v)
        if not H:
            return False
        S, _, _ = patch_similarity(new.hist, new.v, np.stack(H), np.stack(V), alpha_c=p.alpha_c, alpha_m=p.alpha_m,
                                   colour=p.colour)
        return bool(S.max() > p.threshold)

    def _run_of(self, i: int) -> list[int]:
        """The contiguous run of foreground patches on ``i``'s side that contains ``i`` (by arc length)."""
        same = self.layout.of_side(int(self.layout.side[i]))
        same = same[np.argsort(self.layout.arc[same])]
        pos = int(np.flatnonzero(same == i)[0])
        gap = 1.5 * (self.params.spacing or self.params.radius)
        run = [i]
        for step in (-1, 1):
            k = pos
            while 0 <= k + step < len(same):
                nxt = same[k + step]
                if not self.patches[nxt].fg or abs(self.layout.arc[nxt] - self.layout.arc[same[k]]) > gap:
                    break
                run.append(int(nxt))
                k += step
        return run

    def _duplicate(self, ev: CrossingEvent) -> bool:
        """Is ``ev`` the object of a recent event, seen again where that event's motion has taken it?"""
        r = self.params.radius
        for e in self._recent:
            if e.direction != ev.direction or ev.time_s - e.time_s > self.params.group_time:
                continue
            steps = (ev.frame - e.frame) / self.stride
            guess = np.array([e.x + e.vx * steps, e.y + e.vy * steps])
            slack = 2.0 * r + 0.5 * np.hypot(e.vx, e.vy) * steps
            if np.hypot(*(guess - [ev.x, ev.y])) <= slack:
                return True
            if self.params.group_blob > 0 and ev.time_s - e.time_s <= self.params.group_blob and \
                    self._same_blob(guess, (ev.x, ev.y)):
                return True
        return False

    def _same_blob(self, a, b) -> bool:
        """Do frame points ``a`` and ``b`` lie in one 8-connected blob of this frame's foreground (each looked up
        in the square of half-side r around it: an event's point is a patch centre, and its patch is only
        partly foreground)?"""
        if self._labels is None:
            self._labels = cv2.connectedComponents(self._fg, connectivity=8)[1]
        lab = self._labels
        h, w = lab.shape
        k = int(np.ceil(self.params.radius))

        def blobs(pt):
            x, y = int(round(pt[0])) - self.x0, int(round(pt[1])) - self.y0
            win = lab[max(0, y - k):min(h, y + k + 1), max(0, x - k):min(w, x + k + 1)]
            return set(np.unique(win[win > 0]).tolist())

        return bool(blobs(a) & blobs(b))
