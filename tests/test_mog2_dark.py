"""The mog2 detector on a dark camera (``dark_stretch``): its frames are brought to the levels' full range before
MOG2, whose floor on each pixel's variance would hide a person's contrast in the dark."""

from __future__ import annotations

import numpy as np

from pftrack.multi.detectors import MOG2Detector, MOG2DetectorParams


def _frames(gain: float, n: int = 40, seed: int = 0):
    """A textured ground and a box walking across it, times ``gain``, with noise of 2 levels."""
    rng = np.random.default_rng(seed)
    ground = rng.integers(90, 150, (120, 160, 3)).astype(np.float32)
    out = []
    for t in range(n):
        f = ground.copy()
        x = 10 + 3 * t
        f[40:90, x:x + 24] += np.array([-45.0, -20.0, 10.0], np.float32)  # a person in other colours than the ground
        f = f * gain + rng.normal(0, 2, f.shape)
        out.append(np.clip(np.rint(f), 0, 255).astype(np.uint8))
    return out


def _found(frames, **params) -> tuple[int, float]:
    det = MOG2Detector(MOG2DetectorParams(downscale=1, min_area=200, **params))
    hits = sum(len(det(f)) > 0 for f in frames[10:])
    return hits, det.gain


def test_a_dark_camera_is_stretched_before_mog2_and_an_ordinary_one_is_not():
    dark = _frames(0.2)
    plain_hits, plain_gain = _found(dark, dark_stretch=0.0)
    stretch_hits, gain = _found(dark, dark_stretch=2.0)
    assert plain_gain == 1.0 and 4.0 < gain <= 8.0
    assert stretch_hits > plain_hits + 5, (plain_hits, stretch_hits)
    ordinary = _frames(1.0)
    hits, gain = _found(ordinary, dark_stretch=2.0)
    assert gain == 1.0 and hits == _found(ordinary, dark_stretch=0.0)[0] and hits >= 15
