"""Whole-frame re-acquisition for ``flow-pf`` while it is lost (pftrack's addition; the paper does not search).

Tung & Matsuyama's filter looks for the target only where its particles are: once the target has walked off or
been hidden, the particles wait where it was lost, and a target that comes back elsewhere is found only if it passes
near them again.  While the tracker is lost, :func:`scan_centres` lays boxes of the target's size over the whole
frame, each is scored by the same colour distance as the particles (the nearest model of the subspace; the frame
read at every k-th pixel, :func:`sample_step`, so that a search costs about what a tracked frame does), and
:class:`Persistence` asks the best of them to stay in one place for a few frames before the particles are moved
there: a look-alike that crosses the view once is not taken.
"""

from __future__ import annotations

import math

import numpy as np


def scan_centres(width: int, height: int, w: float, h: float, step: float) -> np.ndarray:
    """``(M, 2)`` centres of ``w`` x ``h`` boxes on a grid of ``step`` px over a ``width`` x ``height`` frame, row by
    row, every box inside the frame (one centre per axis, the frame's middle, when the box is wider than the frame)."""
    step = max(float(step), 1.0)

    def axis(extent: float, size: float) -> np.ndarray:
        lo, hi = size / 2.0, extent - size / 2.0
        if hi <= lo:
            return np.array([extent / 2.0])
        n = int(math.floor((hi - lo) / step)) + 1
        off = (hi - lo - (n - 1) * step) / 2.0  # the grid centred in the free range
        return lo + off + step * np.arange(n)

    xs, ys = axis(width, w), axis(height, h)
    out = np.empty((len(xs) * len(ys), 2))
    out[:, 0] = np.tile(xs, len(ys))
    out[:, 1] = np.repeat(ys, len(xs))
    return out


#: the whole-frame search reads every k-th pixel of every k-th row, k chosen so that the box's shorter side keeps
#: at least this many samples (the colours stay the frame's own: no interpolation mixes them)
SEARCH_SAMPLES = 12


def sample_step(w: float, h: float) -> int:
    """The sampling step ``k`` of the whole-frame search for a ``w`` x ``h`` box (1 for boxes under 24 px)."""
    return max(1, int(min(w, h) // SEARCH_SAMPLES))


def best_candidate(centres: np.ndarray, distance: np.ndarray,
                   size: tuple[float, float]) -> tuple[np.ndarray, float, float] | None:
    """The centre of the smallest finite distance, that distance, and the smallest distance of the centres at least
    one box ``size = (w, h)`` away from it along x or y (inf when there is none): the runner-up elsewhere in the
    frame, for a uniqueness test. None when no distance is finite."""
    d = np.where(np.isfinite(distance), distance, np.inf)
    if not d.size or not np.isfinite(d.min()):
        return None
    k = int(np.argmin(d))
    c = centres[k]
    away = (np.abs(centres[:, 0] - c[0]) >= size[0]) | (np.abs(centres[:, 1] - c[1]) >= size[1])
    second = float(d[away].min()) if away.any() else float("inf")
    return c.copy(), float(d[k]), second


class Persistence:
    """A candidate is taken after ``frames`` consecutive frames whose best candidate passed the gate, each within
    ``radius`` px of the one before."""

    def __init__(self, frames: int, radius: float):
        self.frames = int(frames)
        self.radius = float(radius)
        self.reset()

    def reset(self) -> None:
        self.streak = 0
        self.last: np.ndarray | None = None

    def offer(self, centre: np.ndarray | None) -> bool:
        """Feed this frame's gated candidate (None: nothing passed); True when it is to be taken."""
        if centre is None:
            self.reset()
            return False
        near = self.last is not None and float(np.hypot(*(centre - self.last))) <= self.radius
        self.streak = self.streak + 1 if near else 1
        self.last = np.asarray(centre, dtype=np.float64).copy()
        if self.streak >= self.frames:
            self.reset()
            return True
        return False
