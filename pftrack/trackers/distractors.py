"""Look-alikes seen while the target cannot be there: a distractor memory for the colour trackers' search.

Right after a gradual loss the target is close to where it was last seen: a target moving a few pixels a
frame that was being covered by an occluder cannot be 150 px away two frames later.  A candidate of the
search that passes the acquisition test out there is therefore another object of the target's appearance (in
grey video, or among distractors of similar hue, it can score as high as the target itself).

:class:`DistractorMemory` records such candidates during the first ``record_frames`` frames of the search and
follows them while the search goes on: a candidate near a remembered one, within the distance it can have
moved since, is that object again, and the search chooses its candidate among the other samples.  The target
coming out from behind its occluder, away from them, is acquired as before.  Nothing is recorded after an
abrupt loss (:func:`gradual`): a target whose score falls from confident to absent within a frame has jumped,
or the camera cut away, and it may be anywhere.  The memory is forgotten ``LIFE`` times ``record_frames``
frames after the search began, because the estimate the reach is measured from may itself have been on the
wrong object.

The geometry is pure functions (:func:`beyond_reach`, :func:`follow_radius`,
:func:`peak_speed`, :func:`gradual`); the class holds the positions.
"""

from __future__ import annotations

import math

import numpy as np

from ..filtering.dynamics import lost_prediction

#: The memory is forgotten this many times ``record_frames`` after the search began: the estimate the reach is
#: measured from may itself have been on a look-alike, and the object then refused is the target.
LIFE = 6

#: A candidate farther than this many spreads of the search's position prior from the predicted position is
#: out of the target's reach.
REACH_SIGMAS = 4.0


def peak_speed(track) -> float:
    """The largest displacement per frame between consecutive points of a short track of ``(frame index, x,
    y)`` points (how fast the target has been seen to move; 0 with fewer than two points)."""
    best = 0.0
    pts = list(track)
    for (f0, x0, y0), (f1, x1, y1) in zip(pts, pts[1:]):
        best = max(best, math.hypot(float(x1) - float(x0), float(y1) - float(y0)) / max(float(f1 - f0), 1.0))
    return best


def beyond_reach(xy, lost_at, frame_index: int, size: tuple[float, float], speed: float = 0.0, *,
                 sigmas: float = REACH_SIGMAS) -> bool:
    """Could the target not be at ``xy`` now?  True when ``xy`` is farther than ``sigmas`` spreads of
    :func:`~pftrack.filtering.dynamics.lost_prediction`, plus the distance the target covers in the frames
    since at ``speed`` (its fastest seen; at least its velocity's and 1 px a frame), from both the predicted
    position and the last confident one (a target may stop or turn back, and a filter's velocity lags a
    turn)."""
    centre, sd = lost_prediction(lost_at, frame_index, size)
    k = frame_index - lost_at[0]
    speed = max(speed, math.hypot(*(float(v) for v in lost_at[2])), 1.0)
    reach = sigmas * sd + speed * k
    x, y = float(xy[0]), float(xy[1])
    last = lost_at[1]
    return min(math.hypot(x - float(centre[0]), y - float(centre[1])),
               math.hypot(x - float(last[0]), y - float(last[1]))) > reach


def follow_radius(size: tuple[float, float], speed: float, frames: int, base: float = 1.0) -> float:
    """How far a look-alike last seen ``frames`` frames ago can be now: ``base`` target sizes, plus twice the
    target's own speed (at least 1 px a frame) for every frame since, at most four target sizes."""
    reach = 2.0 * max(speed, 1.0) * max(frames, 0)
    return min(base * float(size[0] + size[1]) + reach, 4.0 * float(size[0] + size[1]))


def gradual(last_confident: int, declared: int, lost_frames: int) -> bool:
    """Was the target lost gradually?  A loss is declared after ``lost_frames`` frames of absence evidence; when
    they follow the last confident frame at once, the score fell from confident to absent within a frame (a
    jump, a cut, dropped frames: the target may now be anywhere).  Frames of doubt between the two mean the
    target was being covered, or was leaving, where it was."""
    return declared - last_confident > lost_frames


#: ``distractor_gradual="scores"``: a loss is abrupt only when the score fell from at least ``SURE`` on the last
#: confident frame to at most ``1 - SURE`` on the next one.
SURE = 0.95


def score_gradual(scores, last_confident: int) -> bool:
    """Was the score already falling when the target was lost?  ``scores``: ``(frame index, score)`` of the recent
    tracked frames; ``last_confident``: the frame index of the last confident estimate.  False (abrupt) only when
    the score was at least :data:`SURE` there and at most ``1 - SURE`` on the next frame: a target covered or
    leaving where it was loses its score over frames, one that jumped or was cut away within one (a missing
    frame counts as neither: False)."""
    by_frame = {int(f): float(v) for f, v in scores}
    before, after = by_frame.get(int(last_confident)), by_frame.get(int(last_confident) + 1)
    if before is None or after is None or not (math.isfinite(before) and math.isfinite(after)):
        return False
    return before < SURE or after > 1.0 - SURE


class DistractorMemory:
    """Positions of the look-alikes met during a loss (see the module docstring)."""

    def __init__(self, record_frames: int, lost_frames: int, follow: float = 1.0):
        self.record_frames = int(record_frames)
        self.lost_frames = int(lost_frames)
        self.follow_base = float(follow)  # follow_radius's base, in target sizes
        self.items: list[list[float]] = []  # [x, y, frame index last seen]

    def clear(self) -> None:
        self.items = []

    def _expired(self, frame_index: int, since: int) -> bool:
        """Forget the memory ``LIFE`` times ``record_frames`` after the search began (the last confident estimate
        may have been on the wrong object); True when it is forgotten."""
        if frame_index - since >= LIFE * self.record_frames:
            self.items = []
            return True
        return False

    def follow(self, xy: np.ndarray, rank: np.ndarray, frame_index: int, lost_at, size: tuple[float, float],
               since: int) -> np.ndarray:
        """Follow the remembered look-alikes through this frame's search samples and mask them out.

        ``xy``: ``(M, 2)`` sample positions; ``rank``: their scores (higher is better, ``-inf`` unusable).
        Each remembered look-alike moves to the best sample within the distance it can have moved since it
        was last seen, if there is one.  Returns the ``(M,)`` mask of the samples within that distance of a
        look-alike: the search chooses its candidate among the others.  ``since``: the frame index at which
        the search began."""
        mask = np.zeros(len(xy), dtype=bool)
        if not self.items or lost_at is None or self._expired(frame_index, since):
            return mask
        speed = math.hypot(*(float(v) for v in lost_at[2]))
        for item in self.items:
            near = np.hypot(xy[:, 0] - item[0], xy[:, 1] - item[1]) <= follow_radius(
                size, speed, frame_index - int(item[2]), self.follow_base)
            usable = near & np.isfinite(rank)
            if usable.any():
                j = int(np.flatnonzero(usable)[np.argmax(rank[usable])])
                item[0], item[1], item[2] = float(xy[j, 0]), float(xy[j, 1]), float(frame_index)
            mask |= near
        return mask

    def vetoes(self, xy, frame_index: int, lost_at, size: tuple[float, float], since: int, track=(), *,
               falling: bool = False) -> bool:
        """Is the acquisition candidate at ``xy`` a look-alike rather than the target?  Records or follows it
        when it is.  ``lost_at``: ``(frame index, position, velocity)`` of the last confident estimate;
        ``size``: the searched half-axes; ``since``: the frame index at which the search began; ``track``: the
        last confident ``(frame index, x, y)`` estimates before the loss (their :func:`peak_speed`);
        ``falling``: the score was already falling at the loss (:func:`score_gradual`), which makes the loss
        gradual too."""
        if self.record_frames <= 0 or lost_at is None or self._expired(frame_index, since):
            return False
        x, y = float(xy[0]), float(xy[1])
        speed = math.hypot(*(float(v) for v in lost_at[2]))
        best, best_d = None, math.inf
        for item in self.items:
            d = math.hypot(x - item[0], y - item[1])
            if d <= follow_radius(size, speed, frame_index - int(item[2]), self.follow_base) and d < best_d:
                best, best_d = item, d
        if best is not None:
            best[0], best[1], best[2] = x, y, frame_index  # the same look-alike, followed
            return True
        if frame_index - since < self.record_frames and (falling or gradual(lost_at[0], since, self.lost_frames)):
            if beyond_reach((x, y), lost_at, frame_index, size, peak_speed(track)):
                self.items.append([x, y, float(frame_index)])
                return True
        return False
