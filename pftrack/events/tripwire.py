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
from typing import Literal

import cv2
import numpy as np

from ..cues.foreground import GREY_SHADOW_THRESHOLD, Foreground
from ..params import Params, param
from .blobs import FootCrossings, estimate_radius
from .geometry import PatchLayout, build_patches
from .scoring import bhattacharyya_distance, colour_bins, patch_similarity, ssd_motion
from .timing import CrossingTimer

__all__ = ["CrossingEvent", "TrackerlessTripwire", "TripwireParams", "estimate_radius"]


@dataclass(frozen=True, kw_only=True)
class TripwireParams(Params):
    """Options of the trackerless tripwire (ch10.md §2; the text gives no values for any of them)."""

    radius: float = param(12.0, gt=0, doc="patch radius r = envelope half-width in pixels (Eq. 1)")
    spacing: float | None = param(None, doc="arc-length spacing of the patches (default r: 50 % overlap)")
    direction: Literal["positive", "negative", "both"] = param("both", doc="crossings to detect")
    bgs: Literal["mog2", "diff"] = param("mog2", doc="foreground: MOG2 (shadows as background) or 3-frame difference")
    bgs_history: int = param(500, ge=2, doc="MOG2 history in frames")
    bgs_threshold: float = param(16.0, gt=0, doc="MOG2 varThreshold")
    bgs_grey_shadow_threshold: float = param(GREY_SHADOW_THRESHOLD, ge=0, le=1, doc=(
        "MOG2's shadow threshold on grey frames, where its shadow test cannot tell a shadow from an object up to "
        "twice as dark as the ground: a darker pixel is a shadow only above this fraction of the background's "
        "brightness (1: none; 0.5: OpenCV's, as on colour frames; 0.85 chosen on the grey tune data, "
        "docs/tripwire.md; pftrack.cues.foreground)"))
    bgs_bootstrap: float = param(0.0, ge=0, doc=(
        "seconds of processed frames (at least 3) held at the start; MOG2 learns them with their moving pixels "
        "replaced by the per-pixel median (pftrack.cues.foreground.still_frames), then they are processed (0: off; "
        "MOG2 alone takes the first frames' objects for background). An option: 4 s found 80 of the PETS tune "
        "frames' 96 crossings at strides 1-3 against 74, at mean F1 0.825 against 0.817, short of its rule"))
    diff_threshold: int = param(25, ge=1, le=255, doc="grey-level threshold of the frame difference")
    fg_ratio: float = param(0.3, gt=0, le=1, doc="foreground fraction of a disc that makes the patch foreground")
    contact: Literal["any", "bottom"] = param("any", doc=(
        "any: the text's reading, a patch is foreground when enough of its disc is; bottom: only where an "
        "object's lower edge is (the disc moved down by 1.5 r is mostly background), so that an upright object "
        "crosses when its foot point does (a walker's head crosses the image of a horizontal wire long before "
        "the walker does); on the PETS tune frames it traded recall for precision"))
    bits: int = param(2, ge=1, le=8, doc=(
        "bits per RGB channel of the patch histograms (2: 4x4x4 = 64 bins; the text gives no bin count, L9196). A "
        "disc of r = 10 px holds a few hundred foreground pixels, too few to fill 512 bins: the same walker's "
        "colours seen on the two sides scored S_c 0.6-0.74. 2 chosen with threshold 0.8 and t_max 4 on the tune "
        "data (PETS frames 1-200 at strides 1-3: 57 of 96 crossings found against 50 with 3 bits, 0.75 and 3 s; "
        "docs/tripwire.md)"))
    hist_pixels: Literal["fg", "all"] = param("fg", doc="histogram of the disc's foreground pixels, or of all of them")
    novelty: float = param(0.3, gt=0, le=1, doc="D_B to the last entry above which a new entry is appended")
    alpha_c: float = param(0.7, ge=0, doc="weight of the colour similarity (alpha_c > alpha_m, L9309)")
    alpha_m: float = param(0.3, ge=0, doc="weight of the motion consistency")
    threshold: float = param(0.8, doc="theta_S: a crossing when max S exceeds it (Eq. 7); 0.8 with 2 bits (0.75 "
                                      "was chosen with 3 bits)")
    t_th: float = param(0.1, ge=0, doc="T_th in seconds: an inner appearance must be at least this old")
    t_max: float = param(4.0, gt=0, doc="T_max in seconds: history entries last seen longer ago are ignored (4 "
                                       "chosen with bits; 3 before)")
    max_entries: int = param(32, ge=1, doc="history entries kept per patch")
    v_max: float = param(600.0, gt=0, doc="largest speed in px/s, for the SSD search range")
    motion_prior: float = param(1.0, ge=0, doc=(
        "lambda of the SSD block matching's prior for small motions: a displacement of d px per frame of the "
        "source costs lambda |d|^2 more per matched pixel (grey levels^2 per px^2; with --stride K, the K-frame "
        "displacement D costs lambda |D / K|^2; pftrack's addition, 0 = the text's plain SSD). A patch of a "
        "uniformly dark coat otherwise finds its best match on another dark patch 40-85 px away, and C_d rejects "
        "the crossing. 1 chosen on the PETS tune frames at strides 1-3, the synthetic walkers and the top-down "
        "traffic at strides 1-5 (tune seeds; docs/tripwire.md)"))
    colour: Literal["db", "bc"] = param("db", doc="S_c = 1 - D_B (restored) or the coefficient itself (ch10.md P1)")
    away_angle: float = param(60.0, gt=0, le=90, doc="C_d (Eq. 4) made strict: the motion must point within this "
                                                     "angle of straight away from the wire (90 is the text's "
                                                     "v.w < 0); walkers moving along the wire do not cross it")
    min_motion: float = param(0.5, ge=0, doc="C_d also needs at least this motion in px per processed frame (the "
                                             "direction of a smaller SSD motion is noise)")
    max_lateral: float = param(3.0, gt=0, doc="compare only patches of the other side within this many r of arc "
                                              "length (ch10.md P9; an object crosses, it does not jump along the "
                                              "wire)")
    fresh_time: float = param(1.0, ge=0, doc="a crossing brings an appearance new to its side: if a patch of the "
                                             "same side within max_lateral r saw a matching appearance (S above "
                                             "the threshold) in the last fresh_time seconds, the object was "
                                             "already there (walking along the wire, or counted); 0 turns it off")
    faithful: bool = param(False, doc="the text as written: no t_max, no consumption, no refractory, no grouping, "
                                      "timing 'match'")
    group: bool = param(True, doc="merge events of one object: an event where an emitted one of the same direction "
                                  "would be by now (its position moved by its motion, within 2r) in the last "
                                  "group_time seconds")
    group_time: float = param(2.0, gt=0, doc="how long an emitted event can absorb later ones, in seconds")
    group_blob: float = param(0.3, ge=0, doc=(
        "merge events of one object by its pixels: an event of the same direction emitted in the last group_blob "
        "seconds whose position (moved by its motion) lies in the same 8-connected foreground blob of the current "
        "frame as the new one; an upright walker's head and legs fire apart on a vertical wire (0: off). 0.3 s "
        "chosen on the PETS tune frames (precision 0.55 -> 0.60 at the same accuracy) and synthetic traffic seeds "
        "0-2 (unchanged but for one dense-traffic crossing of 300)"))
    timing: Literal["match", "foot", "centre"] = param("foot", doc=(
        "when a crossing happens (pftrack.events.timing; pftrack's addition): 'match' the text's, the frame where "
        "the appearance is matched on the far side (objects seen from above, the chapter's vehicles); 'foot' / "
        "'centre' the frame where that point of the object's box (its foreground blob, followed by overlap) "
        "passes the wire, as the tracker-based tripwire counts. A walker's head reaches the far side of a "
        "horizontal ground line long before its feet do. 'foot' (default) chosen on the PETS tune frames with "
        "`confirm`: accuracy 0.63 and precision 0.83 against 0.56 and 0.60 with 'match' (before motion_prior; "
        "0.66 / 0.84 against 0.59 / 0.63 with it); on top-down synthetic "
        "traffic (tune seeds 0-2) 'match' is better, because queued vehicles merge into one blob"))
    hold_time: float = param(6.0, gt=0, doc=(
        "with timing foot/centre: seconds an event may wait for its point to cross (a walker 100 px tall at 3 px "
        "per frame needs about 5 s at 7 fps); then, or when its blob is lost, it keeps its matching frame (or is "
        "dropped with confirm). 6 chosen on the PETS tune frames (2 and 4 lost one horizontal crossing)"))
    blob_close: float = param(1.0, ge=0, doc="with timing foot/centre: the foreground is closed with a square of "
                                             "this many r before its blobs are labelled (head, torso and legs of "
                                             "a walker in one blob)")
    confirm: bool = param(True, doc=(
        "with timing foot/centre: drop an event unless its point is seen to cross (on the origin side within the "
        "last `lookback` seconds or while held, then on the far side)"))
    crowd_width: float = param(0.0, ge=0, doc=(
        "with timing foot/centre: a blob wider than this many 2r (r is about half an object's width with --radius "
        "auto) is taken for several objects side by side, whose box point is nobody's: its events keep their "
        "matching frame, unconfirmed (0: off, the default). 2 helps in crowds (synthetic walkers, tune seeds: "
        "accuracy / precision 0.48 / 0.77 -> 0.64 / 0.70) but not on the PETS tune half (unchanged at stride 1, "
        "0.50 / 0.89 against 0.53 / 0.94 at stride 2, 0.22 / 0.41 against 0.28 / 1.00 at stride 3); the same "
        "trade with motion_prior (docs/tripwire.md)"))
    feet: bool = param(True, doc=(
        "with timing foot/centre: the blobs of the closed foreground near the wire are followed by overlap while "
        "they are seen, and a blob whose point crosses the wire (hysteresis foot_hysteresis px) is a crossing, "
        "unless a patch event already counted it (pftrack.events.blobs; pftrack's addition): a walker who "
        "reaches a ground line along it covers both sides before its feet cross, and the patches see nothing "
        "new arrive. Their events have to_patch = from_patch = -1 and no scores. On the PETS tune frames at "
        "strides 1-3: 74 of 96 crossings found at precision 0.82 / 0.96 / 0.91, against 57 at 0.88 / 1.00 / 0.94 "
        "without (docs/tripwire.md)"))
    foot_hysteresis: float = param(5.0, ge=0, doc="with feet: px the point must pass each side of the wire")
    foot_min_area: float = param(3.0, ge=0, doc="with feet: blobs of fewer than this many r^2 pixels are not "
                                                "followed (3 chosen on the tune data among 1, 2, 3, 4, 8)")
    foot_hold: int = param(0, ge=0, doc="with feet: processed frames a crossing waits before it is counted; it "
                                        "is dropped if the point goes back across the wire meanwhile (a blob's "
                                        "bottom jumps when MOG2 loses and finds the feet)")
    foot_inherit: Literal["wire", "always", "never"] = param("wire", doc=(
        "with feet: a blob that splits off a followed one (two walkers who overlapped part) starts on its "
        "parent's side when its point is on the wire, within the hysteresis ('wire'), whatever its point ('always'), "
        "or without a side ('never'). A walker who crossed while merged with another is then counted; but the "
        "side of a merged blob is that of its lowest foot, maybe another walker's. 'wire' chosen on the PETS tune "
        "frames (strides 1-3: 74 of 96 crossings at precision 0.82 / 0.96 / 0.91; 'always' 78 at 0.76 / 0.93 / "
        "0.82; 'never' 72 at 0.84 / 0.96 / 0.90) and the walkers of tune seeds 0-9 (38 of 69 at 0.78; 46 at 0.64; "
        "36 at 0.75)"))
    foot_window: float = param(6.0, gt=0, doc="with feet: seconds within which one blob's events of one direction "
                                              "are one event (6 chosen on the tune data among 1.5, 3, 6, 10)")
    merge_blob: bool = param(True, doc="with timing foot/centre: events of one direction on one blob are one event")
    lookback: float = param(2.5, ge=0, doc=(
        "with confirm: seconds the blob is followed backwards from the frame an event fires (the event is then "
        "dated by the frame its point reached the far side); MOG2 misses feet, which touch their shadows, so a "
        "walker's event often fires after its foot point has crossed. 2.5 s chosen on the PETS tune frames at "
        "strides 1-3 (stride 1, accuracy / precision: 0.53 / 0.89, 0.59 / 0.90, 0.59 / 0.86, 0.63 / 0.83 with "
        "0.7, 1.7, 2 and 2.5 s)"))


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
        below = np.clip(c[:, 1:2] + dy[None] + int(round(1.5 * r)), 0, rh - 1)
        self._below = below * rw + xs                  # the same discs 1.5 r lower
        self.half = half
        # the prior is on the object's speed: a displacement over K frames is K times one frame's
        self._prior = 0.0 if p.faithful else p.motion_prior / self.stride ** 2
        self.patches = [_Patch() for _ in range(len(self.layout.centres))]
        if p.bgs == "mog2":
            self._bgs = Foreground(p.bgs_history, p.bgs_threshold, grey_shadow_threshold=p.bgs_grey_shadow_threshold)
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

    # -- per frame ------------------------------------------------------------------------------
    def foreground(self, roi: np.ndarray, gray: np.ndarray) -> np.ndarray:
        p = self.params
        if p.bgs == "mog2":
            fg = self._bgs.apply(roi)
        else:
            if self._prev_gray is None or self._prev2_gray is None:
                fg = np.zeros(gray.shape, np.uint8)
            else:
                a = cv2.absdiff(gray, self._prev_gray) > p.diff_threshold
                b = cv2.absdiff(self._prev_gray, self._prev2_gray) > p.diff_threshold
                fg = (a | b).astype(np.uint8)
        return cv2.morphologyEx(fg, cv2.MORPH_OPEN, self._kernel)

    def process(self, frame: np.ndarray, number: int) -> list[CrossingEvent]:
        roi = frame[self.y0:self.y1, self.x0:self.x1]
        if roi.ndim == 2:
            roi = cv2.cvtColor(roi, cv2.COLOR_GRAY2BGR)
        if self._held is None:
            return self._process(roi, number)
        self._held.append((roi.copy(), number))
        return self._release_held() if len(self._held) >= self._boot_n else []

    def _release_held(self) -> list[CrossingEvent]:
        """``bgs_bootstrap``: start the background from the held frames, then process them."""
        held, self._held = self._held or [], None
        if held:
            self._bgs.prime([r for r, _ in held])
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
            bins = colour_bins(roi, p.bits).ravel()
            nb = 1 << (3 * p.bits)
            pix = self._disc[rows]                                    # (k, D)
            wts = fg[pix].astype(np.float64) if p.hist_pixels == "fg" else np.ones(pix.shape)
            ids = (np.arange(len(rows))[:, None] * nb + bins[pix]).ravel()
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
