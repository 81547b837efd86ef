"""The input switching between colour and grey mid-sequence: the colour trackers choose their features again.

The colour trackers choose their features from the first frame (:meth:`pftrack.cues.histogram_cue.ColorCue
.adapt_to`): an RGB histogram on colour input, grey features on grey input (every channel equal). A camera that
turns to monochrome mid-sequence (a day/night camera at dusk, an infrared mode, a black-and-white stretch) would
otherwise hand a colour model grey frames, whose histograms fall on the grey diagonal: the loss test then calls a
target in plain view lost. With ``input_switch = N`` (docs/rules/input_switch_rule.txt), once N frames in a row are
grey the tracker starts again with grey features. It starts them on the grey copy of the frame before the switch,
at that frame's box (the grey copy holds the same target at the same place), then tracks the new frame; if the
target was lost there, on the grey copy of the last frame where it was not, and it goes on searching.

Grey features stay when colour comes back: they read the grey levels of any frame, and starting colour features
again mid-track cost more than it gained (docs/rules/input_switch_rule.txt). One case is set apart
(``input_switch_return``, docs/rules/input_switch_return_rule.txt): a switch made while the target is lost. A grey
search among look-alikes may never find the target again, or take a look-alike, where a colour search would find it
once colour returns. So a copy of the tracker as it was, on colour features, goes on beside it with every frame
(:class:`ColourReturn`), exactly as without the switch; once ``input_switch`` colour frames in a row have come, the
tracker goes on as that copy.

Grey frames before the switch (``input_switch`` > 1) are tracked with the colour features. A blank frame (a cut
to black, a flash: its grey levels span fewer than :data:`BLANK_SPAN`) is no evidence either way.

:func:`frame_is_grey` is :func:`pftrack.cues.intensity.is_gray` (99 % of a lattice's pixels with every channel
within ``tolerance`` of the others, compiled with an early exit) on a lattice of about 4096 pixels: a colour frame is
told after its first few coloured samples, so the check costs a few microseconds a frame.
"""

from __future__ import annotations

import copy
import math
from dataclasses import replace

import cv2
import numpy as np

from .._numba import njit, numba_enabled
from ..cues.intensity import is_gray
from ..frames import as_bgr_uint8
from .base import Tracker

#: pixels of the lattice :func:`frame_is_grey` samples (about)
CHECK_SAMPLES = 4096
#: channel difference within which a pixel counts as grey (JPEG leaves a level or two on a grey source)
GREY_TOLERANCE = 2


def _lattice_stride(h: int, w: int, samples: int = CHECK_SAMPLES) -> int:
    return max(1, int(math.sqrt(h * w / float(samples))))


def frame_is_grey(frame: np.ndarray, *, tolerance: int = GREY_TOLERANCE, samples: int = CHECK_SAMPLES) -> bool:
    """:func:`pftrack.cues.intensity.is_gray` on a lattice of about ``samples`` pixels."""
    return is_gray(frame, tolerance=tolerance, stride=_lattice_stride(frame.shape[0], frame.shape[1], samples))


#: a frame whose lattice spans fewer grey levels than this is blank (a cut to black, a flash): no evidence of a switch
BLANK_SPAN = 16


@njit(cache=True)
def _span_numba(frame, stride, limit):  # pragma: no cover - compiled
    h, w = frame.shape[0], frame.shape[1]
    lo, hi = 255, 0
    for y in range(0, h, stride):
        for x in range(0, w, stride):
            v = np.int32(frame[y, x, 1])
            lo = min(lo, v)
            hi = max(hi, v)
            if hi - lo >= limit:
                return hi - lo
    return hi - lo


def frame_is_blank(frame: np.ndarray, *, span: int = BLANK_SPAN, samples: int = CHECK_SAMPLES) -> bool:
    """True when the green channel (the grey level of a grey frame) of a lattice of about ``samples`` pixels spans
    fewer than ``span`` levels: a black or white frame, which says nothing of the camera's kind."""
    g = frame if frame.ndim == 2 else frame[..., min(1, frame.shape[2] - 1)]
    h, w = g.shape[:2]
    stride = _lattice_stride(h, w, samples)
    if numba_enabled() and frame.ndim == 3:
        return _span_numba(frame, stride, span) < span
    lattice = g[::stride, ::stride]
    return int(lattice.max()) - int(lattice.min()) < span


def grey_copy(frame: np.ndarray) -> np.ndarray:
    """The BGR grey copy of ``frame`` (three equal channels), remembering its grey image
    (:func:`pftrack.frames.grey_origin`)."""
    if frame_is_grey(frame, samples=1 << 30):
        return frame
    return as_bgr_uint8(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY))


class FrameRow:
    """A count of frames of one kind in a row (``grey`` or colour): a frame of that kind counts, a frame of the other
    kind breaks the row, and a blank grey frame (a cut to black, a flash) does neither."""

    def __init__(self, after: int, grey: bool):
        if after < 1:
            raise ValueError(f"after must be at least 1, got {after!r}")
        self.after, self.grey = int(after), bool(grey)
        self.pending = 0

    def observe(self, frame: np.ndarray) -> bool:
        """True when ``frame`` completes ``after`` frames of the kind in a row."""
        grey = frame_is_grey(frame)
        if not (grey and frame_is_blank(frame)):
            self.pending = self.pending + 1 if grey == self.grey else 0
        return self.pending >= self.after


class InputSwitch(FrameRow):
    """When colour features should give way to grey ones, and where to start them (the module's bookkeeping).

    ``after``: grey frames in a row before the switch. :meth:`observe` counts them; :meth:`record` keeps the frame
    before the next one and the last frame where the target was not lost, with their boxes.
    """

    def __init__(self, after: int):
        super().__init__(after, grey=True)
        self.prev: np.ndarray | None = None
        self.prev_box: tuple | None = None
        self.prev_lost = False
        self.anchor: tuple[np.ndarray, tuple] | None = None

    def record(self, frame: np.ndarray, box, lost: bool) -> None:
        self.prev, self.prev_box, self.prev_lost = frame, tuple(float(v) for v in box), bool(lost)
        if not lost:
            self.anchor = (frame, self.prev_box)

    def grey_start(self) -> tuple[np.ndarray, tuple, bool]:
        """``(frame, box, lost)`` to start the grey features from: the grey copy of the frame before, with its box,
        or, when the target was lost there, of the last frame where it was not (the first frame at the latest)."""
        if not self.prev_lost:
            return grey_copy(self.prev), self.prev_box, False
        frame, box = self.anchor
        return grey_copy(frame), box, True


class ColourReturn(FrameRow):
    """After a switch to grey features made while the target was lost (``input_switch_return``): the tracker on
    colour features as it was at the switch (``twin``, fed every frame since, as without the switch), and the count
    of colour frames in a row since."""

    def __init__(self, twin: Tracker, after: int):
        super().__init__(after, grey=False)
        self.twin = twin


class InputSwitchMixin:
    """``input_switch`` for a colour tracker: grey features once the input has turned grey (see the module
    docstring). The tracker provides ``params.input_switch``, ``cue.color_space`` and ``_resume_search()``."""

    _input: InputSwitch | None = None
    _return: ColourReturn | None = None

    def init(self, frame, box):
        self._input = self._return = None
        state = super().init(frame, box)
        n = int(getattr(self.params, "input_switch", 0) or 0)
        if n > 0 and self.cue.color_space != "gray":  # grey features read any frame's grey levels: they stay
            self._input = InputSwitch(n)
            self._input.record(as_bgr_uint8(frame, where="init frame"), state.box, False)
        return state

    def init_auto(self, *args, **kwargs):
        self._input = self._return = None  # a given histogram is of one kind of input: its features stay
        return super().init_auto(*args, **kwargs)

    def init_detect(self, *args, **kwargs):
        self._input = self._return = None
        return super().init_detect(*args, **kwargs)

    def update(self, frame):
        guard = self._input
        if (guard is None and self._return is None) or self._shape is None:
            return super().update(frame)
        frame = self._check_frame(frame)  # once more in Tracker.update: no copy of a BGR uint8 frame
        if guard is None:  # after a switch during a search (input_switch_return)
            back = self._return
            twin_state = back.twin.update(frame)
            if not back.observe(frame):
                return super().update(frame)
            # colour is back: go on as the colour-featured tracker, which has searched on since the switch
            self.__dict__.update(back.twin.__dict__)
            return replace(twin_state, info={**twin_state.info, "input_switch": "colour"})
        if guard.observe(frame):  # colour to grey: start again on a grey copy, then track this frame
            base, box, lost = guard.grey_start()
            self._input = None
            if lost and int(getattr(self.params, "input_switch_return", 0) or 0):
                self._return = self._colour_twin(frame, guard.after)
            self._restart(base, box, lost)
            state = super().update(frame)
            return replace(state, info={**state.info, "input_switch": "grey"})
        state = super().update(frame)
        guard.record(frame, state.box, state.lost)
        return state

    def _colour_twin(self, frame, after: int) -> ColourReturn | None:
        """The copy of this tracker that searches on by colour (``input_switch_return``), fed ``frame``; None when
        the tracker holds an object that cannot be copied (a library's native state): it then keeps grey features,
        as with ``input_switch_return = 0``."""
        try:
            twin = copy.deepcopy(self)
        except (TypeError, copy.Error, NotImplementedError):
            return None
        twin.update(frame)
        return ColourReturn(twin, after)

    def _restart(self, frame, box, lost: bool) -> None:
        """Start again on ``frame`` at ``box`` (features for its kind), keeping the frame count."""
        index = self.frame_index
        super().init(frame, box)
        self.frame_index = index
        if lost:
            self._resume_search()


class GreyRestarted(Tracker):
    """Any tracker started again on grey features once the input turns grey (the option ``grey_restart`` that every
    tracker takes, :func:`pftrack.trackers.registry.create_tracker`).

    Most trackers choose their features on the first frame, from a colour histogram or colour names to grey levels.
    After ``after`` grey frames in a row this wrapper calls the tracker's ``init`` on the grey copy of the frame
    before, at that frame's box, or, if the target was lost there, of the last frame where it was not; then it tracks
    the new frame. Unlike the colour particle filters' own ``input_switch`` it cannot put a tracker back into its
    search: a tracker started at a stale box follows what is there until its own loss test, if any, objects.
    """

    def __init__(self, inner: Tracker, after: int):
        super().__init__(inner.params)
        self.inner = inner
        self.after = int(after)
        self.name = inner.name  # transparent: the same tracker, its features chosen again
        self.stochastic = inner.stochastic
        self.state_names = getattr(inner, "state_names", ())
        self._switch: InputSwitch | None = None

    def __getattr__(self, name: str):
        """What the wrapper does not hold is the tracker's (its confidence map, its models)."""
        inner = self.__dict__.get("inner")
        if inner is None:
            raise AttributeError(name)
        return getattr(inner, name)

    def _init(self, frame: np.ndarray, box) -> object:
        state = self.inner.init(frame, box)
        self._switch = None if frame_is_grey(frame) else InputSwitch(self.after)
        if self._switch is not None:
            self._switch.record(frame, state.box, False)
        return state

    def _update(self, frame: np.ndarray) -> object:
        switch = self._switch
        if switch is None:
            return self.inner.update(frame)
        if switch.observe(frame):
            base, box, _ = switch.grey_start()
            self.inner.init(base, box)
            self._switch = None
            state = self.inner.update(frame)
            return replace(state, info={**state.info, "input_switch": "grey"})
        state = self.inner.update(frame)
        switch.record(frame, state.box, state.lost)
        return state
