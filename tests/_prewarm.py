"""Compile the kernels of a share of pftrack's trackers into Numba's on-disk cache (run by ``conftest.py`` before
the test workers start on a checkout that has none): ``python tests/_prewarm.py K N`` warms share K of N."""

from __future__ import annotations

import sys

import numpy as np

#: The colour trackers share most kernels and take most of the compilation (about 17 s of 30 cold): one share.
COLOUR = ("color-pf", "fusion-pf", "local-motion-pf")


def shares(n: int) -> list[list[str]]:
    """The registry's own trackers in ``n`` shares: the colour trackers in the first, the rest dealt to the others
    (to all ``n`` when ``n`` is 1)."""
    from pftrack.trackers.registry import list_trackers

    rest = [s.name for s in list_trackers() if s.name not in COLOUR and s.family in ("pftrack", "baseline")
            and s.available()]
    if n <= 1:
        return [list(COLOUR) + rest]
    return [list(COLOUR)] + [rest[k::n - 1] for k in range(n - 1)]


def _multi() -> None:
    """``pftrack mot``'s tracker on a few frames of two coloured movers (its own kernels)."""
    from pftrack.multi import create_multi_tracker

    rng = np.random.default_rng(0)
    tracker = create_multi_tracker(seed=0)
    for t in range(12):
        frame = rng.integers(90, 110, (120, 160, 3), dtype=np.uint8)
        frame[20:60, 10 + 4 * t:30 + 4 * t] = (40, 60, 200)
        frame[60:100, 120 - 4 * t:140 - 4 * t] = (200, 120, 40)
        tracker.update(frame)


def main(k: int, n: int) -> None:
    from pftrack.trackers.warmup import warm_up

    for name in shares(n)[k]:
        warm_up(name)
    if k == n - 1:
        _multi()


if __name__ == "__main__":
    main(int(sys.argv[1]), int(sys.argv[2]))
