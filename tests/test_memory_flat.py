"""Memory stays flat over long streams (GUIDE §7): after a first cycle of tracking, losing, searching and
re-acquiring, more cycles of the same allocate nothing that stays.

A per-frame list that grew without bound (a history kept "for later", a cache keyed by frame) would cost an
hours-long camera stream its memory. The scene repeats a cycle: the target circles for 300 frames, then is
hidden for 100, so each cycle exercises the tracked frames, the loss test, the search and the re-acquisition.
The Python heap (``tracemalloc``) is read after the first cycle and after two more; OpenCV's and Numba's own
buffers are not traced, and their sizes follow the frame's, not the stream's length.
"""

from __future__ import annotations

import gc
import tracemalloc

import numpy as np
import pytest

from pftrack.trackers.registry import create_tracker

from .conftest import HIDDEN_BOX_START, HIDDEN_FRAMES, HIDDEN_PERIOD, hidden_box_frame

H, W = 120, 160
PERIOD, HIDDEN = HIDDEN_PERIOD, HIDDEN_FRAMES
#: allowed growth of the traced heap over two cycles (800 frames): a list growing by one small tuple a frame
#: (~100 bytes) would exceed it
GROWTH_BYTES = 48 * 1024


def _background() -> np.ndarray:
    rng = np.random.default_rng(0)
    return rng.integers(0, 255, (H, W, 3), dtype=np.uint8)


def _traced_after(tracker, bg: np.ndarray, start: int, stop: int) -> int:
    for t in range(start, stop):
        tracker.update(hidden_box_frame(bg, t))
    gc.collect()
    return tracemalloc.get_traced_memory()[0]


@pytest.mark.parametrize("name", ["fusion-pf", "color-pf", "local-motion-pf"])
def test_memory_is_flat_over_repeated_loss_cycles(name):
    bg = _background()
    tracker = create_tracker(name, seed=0)
    tracker.init(hidden_box_frame(bg, 0), HIDDEN_BOX_START)
    tracemalloc.start()
    try:
        first = _traced_after(tracker, bg, 1, PERIOD + 50)  # one cycle: lost, searched and re-acquired once
        later = _traced_after(tracker, bg, PERIOD + 50, 3 * PERIOD + 50)
    finally:
        tracemalloc.stop()
    assert later - first < GROWTH_BYTES, f"{name}: the heap grew by {(later - first) / 1024:.0f} KB over 800 frames"


@pytest.mark.parametrize("name", ["fusion-pf", "color-pf", "local-motion-pf"])
def test_the_scene_makes_each_tracker_lose_and_find_the_target(name):
    """The cycles above mean something only if the trackers do lose the target and find it again."""
    bg = _background()
    tracker = create_tracker(name, seed=0)
    tracker.init(hidden_box_frame(bg, 0), HIDDEN_BOX_START)
    lost = [tracker.update(hidden_box_frame(bg, t)).lost for t in range(1, 2 * PERIOD)]
    hidden = [t % PERIOD >= PERIOD - HIDDEN for t in range(1, 2 * PERIOD)]
    assert np.mean([flag for flag, h in zip(lost, hidden) if h]) > 0.8
    assert np.mean([flag for flag, h in zip(lost, hidden) if not h]) < 0.1


class _Leaky:
    """A tracker that keeps one small tuple per frame: what the check above must catch."""

    def __init__(self, inner):
        self.inner, self.kept = inner, []

    def update(self, frame):
        state = self.inner.update(frame)
        self.kept.append((len(self.kept), float(state.box[0]), float(state.box[1])))
        return state


def test_the_check_catches_a_per_frame_leak():
    bg = _background()
    inner = create_tracker("color-pf", seed=0)
    inner.init(hidden_box_frame(bg, 0), HIDDEN_BOX_START)
    tracker = _Leaky(inner)
    tracemalloc.start()
    try:
        first = _traced_after(tracker, bg, 1, PERIOD + 50)
        later = _traced_after(tracker, bg, PERIOD + 50, 3 * PERIOD + 50)
    finally:
        tracemalloc.stop()
    assert later - first > GROWTH_BYTES
