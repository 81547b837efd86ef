"""A first box at the frame's edge: the extent of a target still entering the view (``enter_extent``).

When the first box touches an edge of the frame, the target may be coming in and the box hold only its visible part.
For at most ``enter_extent`` frames the colour particle filters then measure the target's extent across that edge on
each tracked frame (:mod:`pftrack.cues.extent`: the band the tracked box spans, read on the first frame's
object-vs-surround colour table), never narrower than the tracked box, and report the box spanning it: the far side
where the target reaches, the near side at the edge.  The particle filter meanwhile follows the part it was given.
Once the measured extent has left the edge (the target is in view) or the frames are spent, the tracker starts again
from the measured box on that frame, keeping its velocity, if that box is at least :data:`GROWN` times the tracked
one across the edge; otherwise (the first box held the target already) the phase ends with nothing changed.  A
declared loss ends it too.  Armed only at a box given (the first frame's, or a detector's), never at the tracker's
own restarts.

With ``enter_grey`` (an option, off), on grey input the extent is read instead on what changed against the first
frame (:func:`~pftrack.cues.extent.change_mask`), and the filter restarts as soon as the measured box is
:data:`GROWN` times the followed one, the phase going on: a grey sliver holds too little for the filter to follow.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..cues.extent import (SURROUND, SURROUND_GREY, band_profile, change_mask, edge_sides, extent_box, grow_run,
                           object_surround_lut, surround_roi)
from ..filtering.dynamics import VX, VY
from ..geometry import visible_box
from .base import TrackState

__all__ = ["EnteringMixin", "GROWN", "MAX_EXTENT_RATIO"]

#: the measured extent is at most this many times the box's other side
MAX_EXTENT_RATIO = 3.0
#: the tracker restarts from the measured box only when it spans at least this many times the tracked box
GROWN = 1.25
#: a change mask's values as "object-like" through band_profile's table
_MASK_LUT = np.array([0.0, 1.0], dtype=np.float32)


class EnteringMixin:
    """``enter_extent`` for :class:`~pftrack.trackers.color_pf.ColorParticleFilter` (see the module docstring)."""

    _entering: dict | None = None

    def _entering_start(self, frame: np.ndarray, box) -> None:
        """At a first box (None at the tracker's own restarts): arm the phase when the box touches an edge."""
        self._entering = None
        if self.params.enter_extent <= 0 or box is None:
            return
        fh, fw = self._shape
        sides = edge_sides(box, fw, fh)
        # the side across which the box is thinnest for its other side; a box that spans the frame has no such side
        w, h = max(float(box[2]), 1e-9), max(float(box[3]), 1e-9)
        options = []
        for pair, axis, ratio in (("LR", 1, w / h), ("TB", 0, h / w)):
            touched = [s for s in sides if s in pair]
            if len(touched) == 1:
                options.append((ratio, touched[0], axis))
        if not options:
            return
        _, side, axis = min(options)
        ent = {"side": side, "axis": axis, "until": self.frame_index + self.params.enter_extent}
        grey = self.cue.color_space == "gray"
        if grey and self.params.enter_grey:  # what changes against this frame
            ent["first"] = self._frame_gray(frame).copy()  # the tracker's one grey image of the frame
            ent["lut"] = _MASK_LUT
        else:  # the wider surround was chosen on colour input; grey features keep the former one
            feats = self.cue.prepare(frame, surround_roi(box, fw, fh, SURROUND_GREY if grey else SURROUND), 1)
            ent["lut"] = object_surround_lut(feats.bins, feats.x0, feats.y0, box, self.cue.feature_bins)
        self._entering = ent

    def _entering_step(self, frame: np.ndarray, state: TrackState) -> TrackState:
        """After a tracked frame of the phase: the measured box, or a restart from it (see the module docstring)."""
        ent = self._entering
        if state.lost or self.mode != "tracking":
            self._entering = None
            return state
        fh, fw = self._shape
        box = visible_box(state.box, fw, fh) or tuple(state.box)
        measured = self._measure_extent(frame, box, ent)
        if measured is None:
            return state
        new_box, at_edge, grown = measured
        ends = not at_edge or self.frame_index >= ent["until"]
        early = "first" in ent and grown and not ends  # grey: a sliver holds too little to follow; restart now
        if not ends and not early:
            return replace(state, box=new_box, info={**state.info, "entering": True, "box_tracked": state.box})
        self._entering = None
        if not grown:  # the tracked box held the target already
            return state
        velocity = self.estimate[[VX, VY]].copy()
        restarted = self._init(frame, new_box)  # not a first box: the phase is not armed again ...
        if early:
            self._entering = ent  # ... but for a grey restart while the target still comes in
        self.ps.states[:, VX] = velocity[0]
        self.ps.states[:, VY] = velocity[1]
        self.estimate[[VX, VY]] = velocity
        return self._state(box=restarted.box, score=state.score, lost=False,
                           info={**state.info, "entered": True, "entering": early, "box_tracked": state.box})

    def _measure_extent(self, frame: np.ndarray, box, ent: dict):
        """``(box, at_edge, grown)``: the tracked ``box`` with its extent across the phase's edge measured on
        ``frame`` (never narrower than the box), whether it reaches the edge, and whether it is at least
        :data:`GROWN` times the box's span; None when nothing object-like lies on the tracked box's lines."""
        fh, fw = self._shape
        x, y, w, h = box
        axis = ent["axis"]
        if axis == 1:  # a band of the box's rows across the frame
            roi = (0, max(int(np.floor(y)), 0), fw, min(int(np.ceil(y + h)), fh))
            lo, hi, size, other = int(np.floor(x)), int(np.ceil(x + w)), fw, h
        else:
            roi = (max(int(np.floor(x)), 0), 0, min(int(np.ceil(x + w)), fw), fh)
            lo, hi, size, other = int(np.floor(y)), int(np.ceil(y + h)), fh, w
        if roi[2] <= roi[0] or roi[3] <= roi[1]:
            return None
        if "first" in ent:
            x0, y0, x1, y1 = roi
            band = change_mask(self._frame_gray(frame)[y0:y1, x0:x1], ent["first"][y0:y1, x0:x1])
            if band is None:
                return None
        else:
            band = self.cue.prepare(frame, roi, 1).bins
        run = grow_run(band_profile(band, ent["lut"], axis), lo, hi)
        if run is None:
            return None
        new_box = extent_box(box, run, 0, axis, MAX_EXTENT_RATIO * other, keep=True)
        side = ent["side"]
        first, last = (new_box[0], new_box[0] + new_box[2]) if axis == 1 else (new_box[1], new_box[1] + new_box[3])
        at_edge = first <= 0.5 if side in "LT" else last >= size - 0.5
        return new_box, at_edge, last - first >= GROWN * (w if axis == 1 else h)
