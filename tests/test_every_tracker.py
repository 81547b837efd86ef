"""Every registered tracker honours the protocol on colour, three-channel grey and one-channel grey frames, and on
awkward starts and inputs (a one-pixel box, a box partly or wholly beyond the frame, BGRA and 16-bit frames, a tiny
frame).

``init(frame, box)`` and ``update(frame)`` return a state whose box is finite, at least a pixel wide and high and
inside the frame, whose score is in [0, 1] and whose ``lost`` is a bool; particles, when a tracker has them, are
finite with weights summing to one. Grey video is normal input (GUIDE; issue #14), so no tracker may fail on a
frame without colour, whether it comes as one channel or three equal ones.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pftrack
from pftrack.errors import InputError
from pftrack.trackers.registry import tracker_names

H, W = 120, 160
BOX = (50.0, 40.0, 24.0, 30.0)


def _frames(kind: str) -> list[np.ndarray]:
    rng = np.random.default_rng(3)
    bg = rng.integers(30, 110, (H, W, 3)).astype(np.uint8)
    bg[..., 1] = bg[..., 0] // 2 + 20
    out = []
    for n in range(8):
        f = bg.copy()
        x = 50 + 2 * n
        f[40:70, x:x + 24] = (40, 60, 210)
        f[48:56, x + 4:x + 20] = (200, 200, 40)
        if kind != "colour":
            f = f.mean(axis=2).astype(np.uint8)
            f = f if kind == "grey-1" else np.dstack([f] * 3)
        out.append(np.ascontiguousarray(f))
    return out


FRAMES = {kind: _frames(kind) for kind in ("colour", "grey-3", "grey-1")}


def _check(state, width: int = W, height: int = H) -> None:
    """The protocol on one state of a ``width x height`` frame."""
    x, y, w, h = state.box
    assert np.all(np.isfinite(state.box)) and w >= 1 and h >= 1
    assert -1e-6 <= x and -1e-6 <= y and x + w <= width + 1e-6 and y + h <= height + 1e-6
    assert 0.0 <= state.score <= 1.0
    assert isinstance(state.lost, (bool, np.bool_))
    assert not (state.lost and state.score > 0.5)  # lost and a confident score never come together
    if state.particles is not None:
        assert np.all(np.isfinite(state.particles))
        if state.weights is not None:
            assert abs(float(np.sum(state.weights)) - 1.0) < 1e-6


@pytest.mark.parametrize("kind", ["colour", "grey-3", "grey-1"])
@pytest.mark.parametrize("name", tracker_names())
def test_tracker_protocol_on_colour_and_grey_frames(name, kind):
    frames = FRAMES[kind]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tracker = pftrack.create_tracker(name, seed=0)
        _check(tracker.init(frames[0], BOX))
        for f in frames[1:]:
            _check(tracker.update(f))


@pytest.mark.parametrize("kind", ["colour", "grey-3", "grey-1"])
@pytest.mark.parametrize("cues", ["color", "fused"])
def test_the_loss_monitor_keeps_the_protocol(cues, kind):
    """The loss monitor's state (both its cues) on the same frames: the tracker's box, the test's score and flag."""
    frames = FRAMES[kind]
    tracker = pftrack.create_tracker("meanshift", monitor=True, monitor_cues=cues)
    _check(tracker.init(frames[0], BOX))
    states = [tracker.update(f) for f in frames[1:]]
    for s in states:
        _check(s)
    assert not any(s.lost for s in states)  # the box stays on the target


def _edge_frames(case: str) -> tuple[list[np.ndarray], tuple[float, float, float, float]]:
    """Five frames and a first box for one awkward start: a one-pixel box, a target leaving through a corner, a box
    larger than the frame, BGRA and 16-bit input, a 16 x 16 frame."""
    rng = np.random.default_rng(7)
    h, w, box, step = H, W, (40.0, 40.0, 20.0, 24.0), (2, 1)
    if case == "one-pixel":
        box = (40.0, 40.0, 1.0, 1.0)
    elif case == "corner":
        box, step = (145.0, 105.0, 20.0, 24.0), (3, 3)
    elif case == "larger-than-frame":
        h, w, box, step = 60, 80, (-10.0, -10.0, 100.0, 80.0), (0, 0)
    elif case == "small-frame":
        h, w, box, step = 16, 16, (4.0, 4.0, 6.0, 6.0), (0, 0)
    out = []
    for n in range(5):
        f = rng.integers(40, 200, (h, w, 3)).astype(np.uint8)
        x0, y0 = int(box[0]) + step[0] * n, int(box[1]) + step[1] * n
        f[max(y0, 0):max(y0 + int(box[3]), 0), max(x0, 0):max(x0 + int(box[2]), 0)] = (30, 60, 220)
        if case == "bgra":
            f = np.dstack([f, np.full((h, w), 255, np.uint8)])
        elif case == "uint16":
            f = f.astype(np.uint16) * 257
        out.append(f)
    return out, box


@pytest.mark.parametrize("case", ["one-pixel", "corner", "larger-than-frame", "bgra", "uint16", "small-frame"])
@pytest.mark.parametrize("name", tracker_names())
def test_tracker_protocol_on_awkward_starts_and_inputs(name, case):
    """Either a clean one-line input error at ``init`` (some of OpenCV's trackers refuse tiny boxes and frames) or
    states that honour the protocol on every frame, whatever the box and pixel type."""
    frames, box = _edge_frames(case)
    h, w = frames[0].shape[:2]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tracker = pftrack.create_tracker(name, seed=0)
        try:
            state = tracker.init(frames[0], box)
        except InputError as exc:
            assert case in ("one-pixel", "larger-than-frame", "small-frame") and "\n" not in str(exc)
            return
        _check(state, w, h)
        for f in frames[1:]:
            _check(tracker.update(f), w, h)


def test_a_lost_state_never_keeps_a_confident_score():
    """The protocol's boundary caps a lost state's score at 0.5, for any tracker (a plug-in's included), and keeps the
    tracker's own figure in ``info["score_raw"]``; a state that is not lost keeps its score."""
    from pftrack.trackers.base import Tracker, TrackState

    class Stubborn(Tracker):
        name = "stubborn"

        def _init(self, frame, box):
            return TrackState(box=tuple(box), score=1.0, lost=False)

        def _update(self, frame):
            return TrackState(box=(10.0, 10.0, 5.0, 5.0), score=0.9, lost=self.frame_index % 2 == 1)

    frames = FRAMES["colour"]
    t = Stubborn(seed=0)
    assert t.init(frames[0], BOX).score == 1.0
    lost, kept = t.update(frames[1]), t.update(frames[2])
    assert lost.lost and lost.score == 0.5 and lost.info["score_raw"] == 0.9
    assert not kept.lost and kept.score == 0.9 and "score_raw" not in kept.info
