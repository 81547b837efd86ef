"""Where a tracked frame's time goes: compiled kernels and OpenCV calls against the Python around them.

    python scripts/frame_split.py reports/split/report_real --trackers fusion-pf,color-pf --seeds 0,1,2

Each sequence's frames are decoded first (decode excluded, as `pftrack eval` times updates). Each tracker runs the
sequence once per seed to compile and warm its caches, then again with the same seed (the same path through the
code, so nothing compiles while timed) with every compiled kernel of the package (each Numba dispatcher a module
of ``pftrack`` holds) and every OpenCV function wrapped in a timer. A kernel that calls another counts once, in the
outer call. Printed per sequence and tracker: update microseconds a frame, the part spent inside the wrapped calls,
the rest (the interpreter and NumPy's small-array calls between them), the number of wrapped calls a frame and the
largest kernels. The timers cost about half a microsecond a call, which falls into the wrapped part.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import time
from collections import Counter, defaultdict
from contextlib import contextmanager

import cv2

import pftrack
from pftrack.cli.common import parse_seeds
from pftrack.frames import as_bgr_uint8
from pftrack.io import discover_sequences
from pftrack.io.sources import read_image
from pftrack.trackers.registry import create_tracker


class Split:
    """One run's split: seconds in all updates, in the wrapped calls, per wrapped name; calls per name; frames."""

    def __init__(self, frames: int = 0):
        self.total = 0.0
        self.wrapped = 0.0
        self.per_name: dict[str, float] = defaultdict(float)
        self.calls: Counter = Counter()
        self.frames = frames


def _package_modules() -> list:
    """Every importable module of ``pftrack`` but the command line's (imported as the trackers use them)."""
    mods = []
    for info in pkgutil.walk_packages(pftrack.__path__, "pftrack."):
        if info.name.startswith("pftrack.cli") or info.name.endswith("__main__"):
            continue
        try:
            mods.append(importlib.import_module(info.name))
        except ImportError:  # an optional extra (PyAV) missing: its module cannot hold a kernel a tracker calls
            continue
    return mods


def _is_kernel(obj) -> bool:
    try:
        from numba.core.registry import CPUDispatcher
    except ImportError:  # no Numba: the NumPy paths run, nothing is compiled
        return False
    return isinstance(obj, CPUDispatcher)


@contextmanager
def timed_calls(split: Split):
    """Wrap the package's kernels and OpenCV's functions in timers adding to ``split`` while inside; restore them on
    exit. The innermost wrapped call is not counted apart: a wrapped call made from within another is not timed."""
    depth = [0]

    def wrap(name, fn):
        def timed(*args, **kwargs):
            if depth[0]:
                return fn(*args, **kwargs)
            depth[0] += 1
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                dt = time.perf_counter() - t0
                depth[0] -= 1
                split.wrapped += dt
                split.per_name[name] += dt
                split.calls[name] += 1
        return timed

    saved = []
    wrappers = {}
    for mod in _package_modules():
        for key, obj in list(vars(mod).items()):
            if _is_kernel(obj):
                if id(obj) not in wrappers:
                    wrappers[id(obj)] = wrap(key, obj)
                saved.append((mod, key, obj))
                setattr(mod, key, wrappers[id(obj)])
    for key, obj in list(vars(cv2).items()):
        if type(obj).__name__ == "builtin_function_or_method" and not key.startswith("_"):
            saved.append((cv2, key, obj))
            setattr(cv2, key, wrap("cv2." + key, obj))
    try:
        yield split
    finally:
        for mod, key, obj in saved:
            setattr(mod, key, obj)


def _run(name: str, frames: list, start: int, box, seed: int) -> float:
    tracker = create_tracker(name, seed=seed)
    tracker.init(frames[start], box)
    t0 = time.perf_counter()
    for frame in frames[start + 1:]:
        tracker.update(frame)
    return time.perf_counter() - t0


def frame_split(frames: list, start: int, box, name: str, seed: int) -> Split:
    """The split of one run of tracker ``name`` over preloaded ``frames`` from ``start`` (first box ``box``), after
    a warm run with the same seed."""
    _run(name, frames, start, box, seed)
    split = Split(frames=len(frames) - start - 1)
    with timed_calls(split):
        split.total = _run(name, frames, start, box, seed)
    return split


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data", nargs="+", help="sequence folders, or dataset folders of them")
    ap.add_argument("--trackers", default="fusion-pf,color-pf")
    ap.add_argument("--seeds", default="0", help="e.g. 0,1,2 or 0-2")
    ap.add_argument("--top", type=int, default=4, help="largest wrapped calls listed per run")
    args = ap.parse_args(argv)
    seeds = parse_seeds(args.seeds)
    print("sequence | tracker | us a frame | in kernels and OpenCV | the rest | wrapped calls a frame | largest")
    for path in args.data:
        for seq in discover_sequences(path):
            # decoded and converted as `pftrack eval` does, outside the timed updates (a grey file is one channel)
            frames = [as_bgr_uint8(read_image(f)) for f in seq.frames]
            start, box = seq.init_index, seq.init_box
            for name in args.trackers.split(","):
                runs = [frame_split(frames, start, box, name, s) for s in seeds]
                n = sum(r.frames for r in runs)
                total = sum(r.total for r in runs) / n * 1e6
                inside = sum(r.wrapped for r in runs) / n * 1e6
                per = defaultdict(float)
                for r in runs:
                    for k, v in r.per_name.items():
                        per[k] += v
                calls = sum(sum(r.calls.values()) for r in runs) / n
                top = ", ".join(f"{k} {v / n * 1e6:.0f}" for k, v in sorted(per.items(), key=lambda kv: -kv[1])
                                [:args.top])
                print(f"{seq.name} | {name} | {total:.0f} | {inside:.0f} ({inside / total:.0%}) | "
                      f"{total - inside:.0f} ({1 - inside / total:.0%}) | {calls:.1f} | {top}")


if __name__ == "__main__":
    main()
