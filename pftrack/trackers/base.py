"""The single-target tracker protocol shared by every pftrack and OpenCV tracker.

>>> tracker = pftrack.create_tracker("color-pf", seed=0)      # doctest: +SKIP
>>> state = tracker.init(frame, (x, y, w, h))                 # doctest: +SKIP
>>> state = tracker.update(next_frame)                        # doctest: +SKIP
>>> state.box, state.score, state.lost, state.particles       # doctest: +SKIP

``init`` may be called again on the same instance to re-initialise.  Frames are
BGR ``uint8`` arrays (grayscale, BGRA and 16-bit frames are converted); boxes
are ``(x, y, w, h)`` floats with a top-left origin.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np

from ..errors import FrameError
from ..frames import as_bgr_uint8
from ..geometry import Box, validate_box, visible_box
from ..params import Params


@dataclass(frozen=True)
class TrackState:
    """What a tracker reports for one frame.

    Attributes
    ----------
    box : ``(x, y, w, h)``; while ``lost`` it is the last confident box for the particle
        filters (or the best candidate before the first acquisition), and the current local
        estimate for the deterministic mean-shift and keypoint trackers, which keep following
        their mode.  Always finite.  It is the part of the estimate inside the frame (at least
        one pixel wide and high), as single-object benchmarks annotate a target at the image's
        edge: where the estimate reaches beyond the frame, ``info["box_full"]`` holds all of it
        (the particles keep the full state).
    score : confidence in ``[0, 1]``. For the colour particle filters it is the loss
        test's posterior P(target | rho) (:mod:`pftrack.filtering.loss`): ``lost`` is raised
        when it stays below 0.5 for ``lost_frames`` frames; the Bhattacharyya coefficient of
        the estimate is ``info["rho"]`` (with ``loss_test="appearance"`` the score is rho).  While
        ``lost`` the score is at most 0.5 for every tracker (a tracker's own higher figure is kept in
        ``info["score_raw"]``).
    lost : True while the target is judged absent or occluded.
    particles : ``(N, D)`` particle states (None for trackers without particles);
        ``state_names`` labels the columns.
    weights : ``(N,)`` normalised particle weights.
    info : small per-frame extras (mode, number of samples passing the
        appearance condition, ...; while a colour PF searches, ``vetoes`` names why each candidate its loss
        test would have taken was refused, :class:`~pftrack.trackers.vetoes.Acquisition`).
    """

    box: Box
    score: float
    lost: bool
    particles: np.ndarray | None = None
    weights: np.ndarray | None = None
    state_names: tuple[str, ...] = ()
    info: dict[str, Any] = field(default_factory=dict)


class Tracker(abc.ABC):
    """Base class: validates frames and boxes at the boundary, then delegates."""

    name: ClassVar[str] = "tracker"
    Params: ClassVar[type[Params]] = Params
    stochastic: ClassVar[bool] = True
    #: the default of the ``grey_restart`` option every tracker takes (pftrack.trackers.input_switch.GreyRestarted)
    grey_restart: ClassVar[int] = 0

    def __init__(self, params: Params | None = None, *, rng: np.random.Generator | None = None,
                 seed: int | None = None):
        self.params = params if params is not None else self.Params()
        if rng is not None and seed is not None:
            raise ValueError("give either rng or seed, not both")
        self.rng = rng if rng is not None else np.random.default_rng(seed)
        self._shape: tuple[int, int] | None = None
        self.frame_index = -1

    # -- protocol -----------------------------------------------------------------
    def init(self, frame: np.ndarray, box) -> TrackState:
        """Start (or restart) tracking the object inside ``box`` on ``frame``."""
        frame = as_bgr_uint8(frame, where="init frame")
        h, w = frame.shape[:2]
        box = validate_box(box, w, h)
        self._shape = (h, w)
        self.frame_index = 0
        return self._visible(self._init(self._transform_input(frame, first=True), box))

    def update(self, frame: np.ndarray) -> TrackState:
        """Track into the next frame."""
        if self._shape is None:
            raise RuntimeError(f"{self.name}: call init(frame, box) before update(frame)")
        frame = self._check_frame(frame)
        self.frame_index += 1
        return self._visible(self._update(self._transform_input(frame, first=False)))

    # -- helpers ------------------------------------------------------------------
    def _check_frame(self, frame: np.ndarray) -> np.ndarray:
        frame = as_bgr_uint8(frame, where=f"frame {self.frame_index + 2}")
        if frame.shape[:2] != self._shape:
            raise FrameError(
                f"frame {self.frame_index + 2}: size {frame.shape[1]}x{frame.shape[0]} differs from the "
                f"first frame's {self._shape[1]}x{self._shape[0]}", index=self.frame_index + 1)
        return frame

    def _visible(self, state: TrackState) -> TrackState:
        """``state`` with its box cut to the frame (:func:`visible_box`), the whole box in ``info["box_full"]``, and a
        lost state's score at most 0.5 (a tracker's own higher figure in ``info["score_raw"]``): ``lost`` and a
        confident score never come together."""
        if state.lost and state.score > 0.5:
            state = replace(state, score=0.5, info={**state.info, "score_raw": float(state.score)})
        h, w = self._shape
        box = state.box
        cut = visible_box(box, w, h)
        if cut is None:
            return state
        return replace(state, box=cut, info={**state.info, "box_full": tuple(float(v) for v in box)})

    def _transform_input(self, frame: np.ndarray, *, first: bool) -> np.ndarray:
        """Per-frame input transform applied before ``_init`` (``first``) and ``_update`` (default: none)."""
        return frame

    @property
    def frame_size(self) -> tuple[int, int] | None:
        """``(width, height)`` of the frames being tracked."""
        return None if self._shape is None else (self._shape[1], self._shape[0])

    @abc.abstractmethod
    def _init(self, frame: np.ndarray, box: Box) -> TrackState: ...

    @abc.abstractmethod
    def _update(self, frame: np.ndarray) -> TrackState: ...
