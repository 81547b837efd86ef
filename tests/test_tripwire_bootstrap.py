"""The background started from the first seconds (`bgs_bootstrap`, pftrack.cues.foreground.still_frames)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from pftrack.cues.foreground import Foreground, still_frames
from pftrack.events.tripwire import TrackerlessTripwire, TripwireParams

H, W = 120, 160
LINE = np.array([[20.0, 60.0], [140.0, 60.0]])


def _mover(n: int = 40, start: int = 30, speed: int = 3, seed: int = 0) -> list[np.ndarray]:
    """A two-coloured square in view from the first frame, moving down across the line y = 60 (its bottom edge
    crosses at frame 5-6), over a blurred random background with pixel noise."""
    rng = np.random.default_rng(seed)
    bg = cv2.GaussianBlur(rng.integers(60, 120, (H, W, 3)).astype(np.uint8), (5, 5), 0)
    out = []
    for t in range(n):
        f = bg.copy()
        y = start + speed * t
        f[y:y + 16, 70:86] = (40, 40, 220)
        f[y + 4:y + 12, 74:82] = (220, 220, 40)
        out.append((f.astype(np.int16) + rng.integers(-2, 3, f.shape)).clip(0, 255).astype(np.uint8))
    return out


def _events(frames, **kw):
    tw = TrackerlessTripwire(LINE, (H, W), 10.0, TripwireParams(radius=6, **kw))
    per_call = [tw.process(f, n) for n, f in enumerate(frames, 1)]
    return per_call, tw.finish()


def test_still_frames_takes_out_what_moves_and_keeps_the_rest():
    rng = np.random.default_rng(1)
    base = rng.integers(50, 200, (8, 10, 3)).astype(np.uint8)
    frames = np.stack([base] * 7)
    frames[2, 3, 4] = (255, 0, 0)          # something passes over one pixel on one frame
    frames[:, 0, 0] = [[10, 10, 10], [11, 11, 11], [12, 12, 12], [10, 10, 10], [11, 11, 11], [12, 12, 12],
                       [10, 10, 10]]       # a still pixel with noise
    out = still_frames(frames, diff=25)
    assert out.shape == frames.shape and out.dtype == np.uint8
    assert np.array_equal(out[2, 3, 4], base[3, 4])
    assert np.array_equal(out[:, 0, 0], frames[:, 0, 0])   # the noise of a still pixel is kept
    assert np.array_equal(np.delete(out, 2, axis=0), np.delete(frames, 2, axis=0))
    grey = still_frames(frames[..., 0], diff=25)            # grey frames too
    assert grey[2, 3, 4] == base[3, 4, 0]


def test_prime_makes_an_object_of_the_first_frames_foreground():
    frames = _mover()
    plain, primed = Foreground(), Foreground()
    primed.prime(frames[:10])
    box = (slice(30, 46), slice(70, 86))   # the square on the first frame
    assert plain.apply(frames[0])[box].mean() < 0.1   # MOG2 takes its first frame for the background
    assert primed.apply(frames[0])[box].mean() > 0.5


def test_off_by_default_and_events_as_found():
    frames = _mover()
    per_call, rest = _events(frames, timing="match")
    assert TripwireParams().bgs_bootstrap == 0
    assert [(e.frame, e.direction) for c in per_call for e in c] + [(e.frame, e.direction) for e in rest] == [(8, 1)]
    assert per_call[7] and per_call[7][0].frame == 8   # reported on the frame it is found


@pytest.mark.parametrize("seconds", [1.0, 2.0])
def test_a_crossing_by_an_object_in_view_from_the_first_frame(seconds):
    frames = _mover()
    per_call, rest = _events(frames)                       # foot timing, confirmed: MOG2 absorbed the square
    assert not any(per_call) and not rest
    per_call, rest = _events(frames, bgs_bootstrap=seconds)
    held = int(round(seconds * 10))
    assert not any(per_call[:held - 1])                    # the first frames are held ...
    found = [(e.frame, e.direction) for c in per_call for e in c] + [(e.frame, e.direction) for e in rest]
    assert found == [(6, 1)]                               # ... and processed once the background is started
    assert any(e.frame == 6 for e in per_call[held - 1])


def test_a_stream_shorter_than_the_bootstrap_is_processed_at_the_end():
    frames = _mover(n=12)
    per_call, rest = _events(frames, bgs_bootstrap=3.0)    # 30 frames would be held; the stream has 12
    assert not any(per_call)
    assert [(e.frame, e.direction) for e in rest] == [(6, 1)]
