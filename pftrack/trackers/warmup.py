"""Compile (or load from Numba's on-disk cache) every kernel a tracker uses, before anything is timed.

Numba compiles a kernel on its first call and caches the machine code on disk,
so the first run on a fresh install pays the compilation and later runs pay a
cache load.  Neither belongs in a reported speed: :func:`warm_up` runs the
tracker, with the same parameters, on a few small synthetic frames (colour and
grey, so both feature paths are exercised) and returns the seconds it took.
"""

from __future__ import annotations

import time
from typing import Any, Mapping

import numpy as np

from ..cues import histogram_cue, intensity, reduced_region
from .registry import create_tracker, get_spec

_WARMED: set[tuple[str, tuple]] = set()


def _frames(n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(0)
    out = []
    for t in range(n):
        img = rng.integers(60, 140, (96, 128, 3), dtype=np.uint8)
        x, y = 40 + 2 * t, 30 + t
        img[y:y + 30, x:x + 20] = (40, 60, 200)
        img[y + 15:y + 30, x:x + 20] = (200, 120, 40)
        out.append(img)
    return out


def warm_up(name: str, params: Mapping[str, Any] | None = None, *, frames: int = 6, force: bool = False) -> float:
    """Run tracker ``name`` on small synthetic clips once per process; returns the seconds spent (0 if done).

    Only pftrack's own trackers are warmed (OpenCV's need no compilation).
    """
    key = (name, tuple(sorted((k, repr(v)) for k, v in (params or {}).items())))
    if (key in _WARMED and not force) or get_spec(name).family == "opencv":
        return 0.0
    t0 = time.perf_counter()
    reduced_region.warmup()
    intensity.warmup()
    histogram_cue.warmup()
    clip = _frames(frames)
    for gray in (False, True):
        tracker = create_tracker(name, seed=0, params=dict(params or {}))
        seq = [np.repeat(f.mean(axis=2, keepdims=True).astype(np.uint8), 3, axis=2) if gray else f for f in clip]
        tracker.init(seq[0], (40.0, 30.0, 20.0, 30.0))
        for f in seq[1:]:
            tracker.update(f)
        # the search path too: the target vanishes
        blank = np.full_like(seq[0], 100)
        for _ in range(4):
            tracker.update(blank)
    _WARMED.add(key)
    return time.perf_counter() - t0
