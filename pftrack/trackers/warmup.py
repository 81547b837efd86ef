"""Compile (or load from Numba's on-disk cache) every kernel a tracker uses, before anything is timed.

Numba compiles a kernel on its first call and caches the machine code on disk,
so the first run on a fresh install pays the compilation and later runs pay a
cache load.  Neither belongs in a reported speed: :func:`warm_up` runs the
tracker, with the same parameters, on short synthetic clips of a small, a medium
and a large target, in colour and in grey, each ending with the target gone (so
the size-dependent paths, both feature paths and the search are exercised), and
returns the seconds it took.
"""

from __future__ import annotations

import time
from typing import Any, Mapping

import numpy as np

from .monitor import wrapper_options
from .registry import create_tracker, get_spec

_WARMED: set[tuple[str, tuple]] = set()


#: The warm-up clips: (frames, frame height and width, target width and height).  Kernels and their array layouts
#: depend on the target's size (lattice pitch, block size of the grey reduction, neighbourhood or whole-region
#: gradients), so a small, a medium and a large target are all tracked, and lost.
_CLIPS = ((6, (96, 128), (20, 30)), (3, (240, 320), (60, 80)), (3, (240, 320), (150, 190)))


def _frames(n: int, shape: tuple[int, int] = (96, 128), size: tuple[int, int] = (20, 30)) -> list[np.ndarray]:
    rng = np.random.default_rng(0)
    w, h = size
    out = []
    for t in range(n):
        img = rng.integers(60, 140, (*shape, 3), dtype=np.uint8)
        x, y = 40 + 2 * t, 30 + t
        img[y:y + h, x:x + w] = (40, 60, 200)
        img[y + h // 2:y + h, x:x + w] = (200, 120, 40)
        out.append(img)
    return out


def warm_up(name: str, params: Mapping[str, Any] | None = None, *, frames: int = 6, force: bool = False) -> float:
    """Run tracker ``name`` on small synthetic clips once per process; returns the seconds spent (0 if done).

    Only pftrack's own trackers are warmed (OpenCV's need no compilation, unless ``monitor=true`` wraps them).
    ``frames``: length of the first (small-target) clip.
    """
    key = (name, tuple(sorted((k, repr(v)) for k, v in (params or {}).items())))
    monitored = wrapper_options(params).monitor  # the loss monitor's kernels need warming too
    if (key in _WARMED and not force) or (get_spec(name).family == "opencv" and not monitored):
        return 0.0
    t0 = time.perf_counter()
    for i, (n, shape, size) in enumerate(_CLIPS):
        clip = _frames(frames if i == 0 else n, shape, size)
        for gray in (False, True):
            tracker = create_tracker(name, seed=0, params=dict(params or {}))
            seq = [np.repeat(f.mean(axis=2, keepdims=True).astype(np.uint8), 3, axis=2) if gray else f for f in clip]
            tracker.init(seq[0], (40.0, 30.0, float(size[0]), float(size[1])))
            for f in seq[1:]:
                tracker.update(f)
            # the search path too: the target vanishes
            blank = np.full_like(seq[0], 100)
            for _ in range(4):
                tracker.update(blank)
    _WARMED.add(key)
    return time.perf_counter() - t0
