"""Every registered tracker honours the protocol on colour, three-channel grey and one-channel grey frames.

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


def _check(state) -> None:
    x, y, w, h = state.box
    assert np.all(np.isfinite(state.box)) and w >= 1 and h >= 1
    assert -1e-6 <= x and -1e-6 <= y and x + w <= W + 1e-6 and y + h <= H + 1e-6
    assert 0.0 <= state.score <= 1.0
    assert isinstance(state.lost, (bool, np.bool_))
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
