"""When did a detected crossing happen? The point of the object that crosses (pftrack's addition to ch. 10).

The trackerless tripwire fires when an appearance that was on one side of the wire arrives on the
other. For an object seen from above (the chapter's vehicles) that is the crossing. For an upright
object seen obliquely (a walker) it is not: a walker's head reaches the far side of a horizontal
ground line long before the walker does, which is when the foot point crosses. The tracker-based
tripwire and its ground truth take the box's foot point (bottom centre) or centre.

:class:`CrossingTimer` holds an event until the chosen point of its object has passed the wire. The
object is the 8-connected blob of the (closed) foreground that covers the event's patch; from frame
to frame the blob is followed by overlap (the blob of the new frame that covers most of the old
blob's pixels). An event whose point is still on the origin side when it fires is released on the
first frame its point is on the far side. One whose point is already on the far side is released
at once; with ``confirm`` only if, followed backwards over the last frames, the point was on the
origin side, and it is then dated by the first frame on the far side. An event whose blob is lost,
or whose point has not crossed within ``hold_time``, keeps its matching frame, or is dropped with
``confirm``.

Two held events of one direction whose blobs become one are one object: the later is dropped (a
walker's head and then its torso are matched across the wire a few frames apart).

Pure helpers (:func:`blob_labels`, :func:`follow`, :func:`blob_point`) work on arrays; the class
keeps the held events.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, replace

import cv2
import numpy as np

from .blobs import FootCrossings, FootEvent, label_stats
from .geometry import polyline_project

__all__ = ["CrossingTimer", "blob_labels", "blob_point", "follow"]


def blob_labels(fg: np.ndarray, close: int, *, stats: bool = False):
    """8-connected labels of the foreground after a closing with a ``close`` × ``close`` square (0: none),
    so that an upright object's head, torso and legs form one blob; with ``stats``, also each label's box
    and area (OpenCV's ``x, y, w, h, area``)."""
    m = fg.astype(np.uint8)
    if close > 1:
        m = cv2.morphologyEx(m, cv2.MORPH_CLOSE, np.ones((close, close), np.uint8))
    labels = cv2.connectedComponents(m, connectivity=8)[1]
    return (labels, label_stats(labels)) if stats else labels


def follow(labels: np.ndarray, pixels: np.ndarray) -> tuple[int, np.ndarray | None]:
    """The label and pixels (flat indices) of the blob of ``labels`` that covers most of ``pixels``;
    (0, None) if none does."""
    flat = labels.ravel()
    hit = flat[pixels]
    hit = hit[hit > 0]
    if hit.size == 0:
        return 0, None
    lab = int(np.bincount(hit).argmax())
    return lab, np.flatnonzero(flat == lab)


def blob_point(pixels: np.ndarray, width: int, point: str) -> tuple[float, float]:
    """The blob's box point in ROI pixels: ``foot`` the bottom centre, ``centre`` the centre."""
    ys, xs = np.divmod(pixels, width)
    x = 0.5 * (xs.min() + xs.max())
    y = float(ys.max()) + 0.5 if point == "foot" else 0.5 * (ys.min() + ys.max())
    return float(x), float(y)


@dataclass
class _Held:
    event: object
    pixels: np.ndarray
    until: float


class CrossingTimer:
    """Holds events until their object's ``point`` (``foot`` or ``centre``) has passed the wire.

    With ``confirm``, an event is released only when the point is seen to cross: on the origin side in
    one of the last ``lookback`` processed frames (the blob followed backwards; the event is then dated
    by the first frame on the far side) or while held, then on the far side. Events whose point is
    never seen to cross are dropped; without ``confirm`` they keep their matching frame."""

    def __init__(self, polyline: np.ndarray, origin: tuple[int, int], width: int, *, point: str, hold_time: float,
                 close: int, confirm: bool = False, lookback: int = 0, merge: bool = True,
                 max_width: float = 0.0, feet: FootCrossings | None = None):
        self.polyline = np.asarray(polyline, dtype=np.float64)
        self.x0, self.y0 = origin
        self.width = int(width)
        self.point, self.hold_time, self.close = point, float(hold_time), int(close)
        self.confirm, self.lookback = bool(confirm), int(lookback)
        self.merge = bool(merge)
        self.max_width = float(max_width)
        self.feet = feet
        self.held: list[_Held] = []
        self.past: deque[tuple[int, float, np.ndarray]] = deque(maxlen=max(1, self.lookback))

    def _side(self, pixels: np.ndarray) -> tuple[float, float, float]:
        x, y = blob_point(pixels, self.width, self.point)
        p = np.array([[x + self.x0, y + self.y0]])
        return float(polyline_project(p, self.polyline)[4][0]), p[0, 0], p[0, 1]

    def _crossed_at(self, pix: np.ndarray, direction: int, number: int, t: float) -> tuple[int, float] | None:
        """Following the blob back through the stored frames: the first frame (number, time) on the far side
        after a frame on the origin side, or None if it was on the far side throughout."""
        first = (number, t)
        for n, tt, labels in reversed(self.past):
            _, pix = follow(labels, pix)
            if pix is None:
                return None
            if self._side(pix)[0] * direction <= 0:
                return first
            first = (n, tt)
        return None

    def _crowd(self, pixels: np.ndarray) -> bool:
        """Is the blob wider than one object (``max_width`` px; 0: never)? Its box point is then nobody's."""
        if self.max_width <= 0:
            return False
        xs = pixels % self.width
        return bool(xs.max() - xs.min() + 1 > self.max_width)

    def _unconfirmed(self, ev, out: list) -> None:
        """An event whose point was not seen to cross: kept at its matching frame (blob unknown), or dropped
        with ``confirm``."""
        if not self.confirm:
            out.append((ev, 0))

    def finish(self) -> list:
        """The held events at the end of the stream: released at their matching frame, or none with confirm."""
        out: list = []
        for h in self.held:
            self._unconfirmed(h.event, out)
        self.held = []
        return [ev for ev, _ in out]

    def step(self, fg: np.ndarray, fired: list, number: int, t: float, disc_of) -> tuple[list, list[FootEvent]]:
        """Release the events due on this frame. ``fired``: the events that fired on it; ``disc_of(i)``:
        the flat ROI pixels of patch ``i``'s disc (where a fired event's blob is looked up). Returns the
        released events and, with ``feet``, the foot crossings of blobs that no released event counts."""
        if not fired and not self.held and not (self.confirm and self.lookback) and self.feet is None:
            return [], []
        if self.feet is not None:
            labels, stats = blob_labels(fg, self.close, stats=True)
        else:
            labels, stats = blob_labels(fg, self.close), None
        out: list = []
        keep: list[_Held] = []
        taken: set[tuple[int, int]] = set()   # (label, direction) of the objects already held or released
        for h in self.held:
            lab, pix = follow(labels, h.pixels)
            if pix is not None and self._crowd(pix):
                out.append((h.event, lab))  # merged with others: the matching frame
                continue
            if pix is None or t > h.until:
                self._unconfirmed(h.event, out)
                continue
            if self.merge and (lab, h.event.direction) in taken:
                continue
            taken.add((lab, h.event.direction))
            s, x, y = self._side(pix)
            if s * h.event.direction > 0:
                out.append((replace(h.event, frame=number, time_s=t, x=x, y=y), lab))
            else:
                keep.append(_Held(h.event, pix, h.until))
        for ev in fired:
            lab, pix = follow(labels, disc_of(ev.to_patch))
            if pix is not None and self._crowd(pix):
                out.append((ev, lab))  # merged with others: the matching frame
                continue
            if pix is None:
                self._unconfirmed(ev, out)
                continue
            if self.merge and (lab, ev.direction) in taken:
                continue
            taken.add((lab, ev.direction))
            s, x, y = self._side(pix)
            if s * ev.direction <= 0:
                keep.append(_Held(ev, pix, t + self.hold_time))
            elif not self.confirm:
                out.append((replace(ev, x=x, y=y), lab))
            else:
                when = self._crossed_at(pix, ev.direction, number, t)
                if when is not None:
                    out.append((replace(ev, frame=when[0], time_s=when[1], x=x, y=y), lab))
        self.held = keep
        if self.lookback:
            # the look-back keeps a few seconds of label images: 2 bytes a pixel where that suffices
            self.past.append((number, t, labels.astype(np.uint16) if labels.max() < 65535 else labels))
        if self.feet is None:
            return [ev for ev, _ in out], []
        return self.feet.step(labels, stats, number, t, out)
