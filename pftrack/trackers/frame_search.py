"""Whole-frame re-acquisition while a tracker is lost (pftrack's addition to ``flow-pf``, ``cotrain-pf`` and the loss
monitor's ``monitor_search``, :mod:`pftrack.trackers.monitor`).

Those filters look for the target only where their particles are: once the target has walked off or been hidden,
the particles wait about where it was lost, and a target that comes back elsewhere is found only if it passes near
them again.  While the tracker is lost, :func:`scan_centres` lays boxes of the target's size over the whole frame,
the tracker scores each by its own appearance distance (``flow-pf``: the particles' EMD to the nearest model of the
subspace, the frame read at every k-th pixel, :func:`sample_step`; ``cotrain-pf``: 1 - rho of its colour term), and
:func:`frame_candidate` takes the best one and the best at least one box away from it (the runner-up), each refined
on a finer grid about it so that neither gains from where the coarse grid happened to fall.  The tracker takes the
best when it is near enough its models and at most a fraction of the runner-up's distance (among several look-alikes
none is taken), and :class:`Persistence` asks it to stay in one place for a few frames.

After the target left the view, a look-alike that stayed in view all the while is unique in the frame as soon as the
target is gone.  :class:`Residents` (an option of ``cotrain-pf``'s search and of the monitor's) keeps the grey frames
of the search and refuses a candidate whose box, traced back through them, stays inside the view on every one (as
``fusion-pf``'s ``reenter_resident``, :mod:`pftrack.trackers.vetoes`): a target coming back entered through an edge
since it left.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Callable

import cv2
import numpy as np

from ..cues.template import patch_shift, trace_back
from ..geometry import in_frame_fraction
from .vetoes import RESIDENT_CORE, RESIDENT_IN_FRAME  # fusion-pf's reenter_resident's: the same trace

#: the whole-frame search reads every k-th pixel of every k-th row, k chosen so that the box's shorter side keeps
#: at least this many samples (the colours stay the frame's own: no interpolation mixes them)
SEARCH_SAMPLES = 12

#: ... and so that it reads at most about this many pixels of a large frame
SEARCH_PIXELS = 1_000_000


def sample_step(w: float, h: float, width: int = 0, height: int = 0) -> int:
    """The sampling step ``k`` of the whole-frame search for a ``w`` x ``h`` box in a ``width`` x ``height`` frame
    (1 for boxes under 24 px in frames of up to a million pixels)."""
    k = max(1, int(min(w, h) // SEARCH_SAMPLES))
    return max(k, math.ceil(math.sqrt(width * height / SEARCH_PIXELS)))


#: the most centres a whole-frame search scores: a small box in a large frame widens the grid's step instead (the
#: development and synthetic sequences ask at most about 4 800)
MAX_CENTRES = 20_000


def scan_centres(width: int, height: int, w: float, h: float, step: float,
                 max_centres: int = MAX_CENTRES) -> np.ndarray:
    """``(M, 2)`` centres of ``w`` x ``h`` boxes on a grid of ``step`` px over a ``width`` x ``height`` frame, row by
    row, every box inside the frame (one centre per axis, the frame's middle, when the box is wider than the frame);
    the step is widened so that there are at most about ``max_centres``."""
    free = max(width - w, 1.0) * max(height - h, 1.0)
    step = max(float(step), 1.0, math.sqrt(free / max(max_centres, 1)))

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


def exit_side(box, width: float, height: float, near: float = 0.5) -> int | None:
    """The edge (0 left, 1 right, 2 top, 3 bottom) the box ``(x, y, w, h)`` lies within ``near`` of its own size of
    (the nearest), or None when it lies further inside: the edge a target whose last sure box this was left by."""
    x, y, w, h = (float(v) for v in box)
    gaps = (x / max(w, 1.0), (width - x - w) / max(w, 1.0), y / max(h, 1.0), (height - y - h) / max(h, 1.0))
    k = int(np.argmin(gaps))
    return k if gaps[k] <= near else None


def exit_band(centres: np.ndarray, side: int, width: float, height: float, w: float, h: float,
              depth: float = 1.5) -> np.ndarray:
    """``(M,)`` bool: the centres within ``depth`` box sizes of edge ``side`` (:func:`exit_side`), where a target
    that left through it comes back."""
    if side == 0:
        return centres[:, 0] <= depth * w
    if side == 1:
        return centres[:, 0] >= width - depth * w
    if side == 2:
        return centres[:, 1] <= depth * h
    return centres[:, 1] >= height - depth * h


def exit_scan(frame: np.ndarray, size: tuple[float, float], step: float, last, band: bool,
              residents: "Residents | None", index: int) -> tuple[np.ndarray, "Residents | None"]:
    """The coarse centres of a whole-frame search for boxes of ``size`` = (w, h) on ``frame`` (:func:`scan_centres`),
    and the resident store that applies to this frame.  When the last sure box ``last`` lay at an edge
    (:func:`exit_side`), with ``band`` the centres keep to the band along it (:func:`exit_band`), and ``residents``
    keeps this frame (number ``index``) and is returned; otherwise the store returned is None."""
    fh, fw = frame.shape[:2]
    w, h = size
    centres = scan_centres(fw, fh, w, h, step)
    side = exit_side(last, fw, fh) if last is not None and (band or residents is not None) else None
    if side is None:
        return centres, None
    if residents is not None:
        residents.keep(index, frame)
    if band:  # the target left through that edge: the band along it
        centres = centres[exit_band(centres, side, fw, fh, w, h)]
    return centres, residents


def local_grid(centre: np.ndarray, step: float, n: int = 2) -> np.ndarray:
    """``((2n + 1)^2, 2)`` centres spaced ``step / (2n)`` about ``centre``, out to half a coarse ``step`` each way:
    the finer grid that refines a coarse grid's cell."""
    off = np.linspace(-0.5 * step, 0.5 * step, 2 * n + 1)
    out = np.empty((off.size * off.size, 2))
    out[:, 0] = centre[0] + np.tile(off, off.size)
    out[:, 1] = centre[1] + np.repeat(off, off.size)
    return out


def best_candidate(centres: np.ndarray, distance: np.ndarray,
                   size: tuple[float, float]) -> tuple[np.ndarray, float, np.ndarray | None, float] | None:
    """The centre of the smallest finite distance and that distance, and the centre and distance of the best of the
    centres at least one box ``size = (w, h)`` away from it along x or y (None and inf when there is none): the
    runner-up elsewhere in the frame, for a uniqueness test. None when no distance is finite."""
    d = np.where(np.isfinite(distance), distance, np.inf)
    if not d.size or not np.isfinite(d.min()):
        return None
    k = int(np.argmin(d))
    c = centres[k]
    away = np.flatnonzero((np.abs(centres[:, 0] - c[0]) >= size[0]) | (np.abs(centres[:, 1] - c[1]) >= size[1]))
    if not away.size or not np.isfinite(d[away].min()):
        return c.copy(), float(d[k]), None, float("inf")
    j = int(away[np.argmin(d[away])])
    return c.copy(), float(d[k]), centres[j].copy(), float(d[j])


@dataclass(frozen=True)
class Candidate:
    """A whole-frame search's best place (``centre``, ``distance``) and the runner-up's distance (inf: none)."""

    centre: np.ndarray
    distance: float
    runner_up: float

    def unique(self, ratio: float, gap: float = 0.0) -> bool:
        """The uniqueness test: the best distance at most ``ratio`` times the runner-up's and ``gap`` below it."""
        return self.distance <= ratio * self.runner_up and self.runner_up - self.distance >= gap

    def taken(self, max_distance: float, here: float, ratio: float) -> bool:
        """The gates of a tracker's own search: within ``max_distance`` of the model, nearer it than the estimate
        (``here``), and :meth:`unique` with ``ratio``."""
        return self.distance <= max_distance and self.distance < here and self.unique(ratio)


def frame_candidate(score: Callable[[np.ndarray], np.ndarray], centres: np.ndarray, size: tuple[float, float],
                    step: float) -> Candidate | None:
    """Score the coarse grid ``centres`` (``score``: ``(M, 2)`` centres -> ``(M,)`` distances, inf where a box
    cannot be scored), take the best and the runner-up at least one box away (:func:`best_candidate`), and refine
    each on :func:`local_grid` about it; None when nothing could be scored."""
    coarse = best_candidate(centres, score(centres), size)
    if coarse is None:
        return None
    c, d, c2, d2 = coarse
    fine = local_grid(c, step)
    df = score(fine)
    k = int(np.argmin(np.where(np.isfinite(df), df, np.inf)))
    if np.isfinite(df[k]) and df[k] < d:
        c, d = fine[k].copy(), float(df[k])
    if c2 is not None:
        d2 = min(d2, float(np.min(np.where(np.isfinite(f := score(local_grid(c2, step))), f, np.inf))))
    return Candidate(c, d, d2)


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


def resident_radius(w: float, h: float) -> int:
    """The trace's search radius for a ``w`` x ``h`` box, in px a frame: half its shorter side, at least 8."""
    return max(8, int(math.ceil(0.5 * min(w, h))))


class Residents:
    """The resident veto of a whole-frame search after an exit: the grey frames of the last ``frames`` consecutive
    search frames; :meth:`resident`, which traces a candidate's box back through them; and the boxes of the refused
    residents, followed from frame to frame (:meth:`keep`), which the search passes over (:meth:`near`), so that the
    target coming back is unique in the frame again."""

    def __init__(self, frames: int):
        self.frames = int(frames)
        self._grays: deque[tuple[int, np.ndarray]] = deque(maxlen=max(1, self.frames))
        self.vetoed: list[np.ndarray] = []

    def reset(self) -> None:
        self._grays.clear()
        self.vetoed = []

    def __len__(self) -> int:
        return len(self._grays)

    def keep(self, index: int, frame: np.ndarray) -> np.ndarray:
        """Keep frame number ``index``'s grey image (the kept ones and the refused residents are forgotten unless it
        follows the last kept) and follow each refused resident's box to it (dropped when its trace is lost or it
        reaches an edge); returns the grey image."""
        gray = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        if self._grays and self._grays[-1][0] != index - 1:
            self.reset()
        if self._grays and self.vetoed:
            prev = self._grays[-1][1]
            fh, fw = gray.shape[:2]
            kept = []
            for b in self.vetoed:
                d = patch_shift(gray, prev, _core(b), resident_radius(b[2], b[3]))
                if d is not None:  # the box on the previous frame, moved by what its core did since
                    b = b.copy()
                    b[:2] -= d
                    if in_frame_fraction(tuple(b), fw, fh) >= RESIDENT_IN_FRAME:
                        kept.append(b)
            self.vetoed = kept
        self._grays.append((int(index), gray))
        return gray

    def resident(self, box) -> bool:
        """Was the candidate ``box`` (x, y, w, h on the newest kept frame) inside the view all along?  Its central
        part (:data:`RESIDENT_CORE`) is followed back frame by frame by normalised correlation
        (:func:`pftrack.cues.template.trace_back`, within :func:`resident_radius`); True when its box stays at least
        :data:`RESIDENT_IN_FRAME` inside the view on the newest frame and on every earlier kept one.  A trace that
        is lost (a flat patch, no match) or reaches an edge refuses nothing, nor does a store of one frame.  A
        resident is remembered (:attr:`vetoed`)."""
        if len(self._grays) < 2:
            return False
        gray = self._grays[-1][1]
        fh, fw = gray.shape[:2]
        b0 = np.array([float(v) for v in box])
        if in_frame_fraction(tuple(b0), fw, fh) < RESIDENT_IN_FRAME:
            return False
        earlier = (g for _, g in list(self._grays)[-2::-1])
        for b in trace_back(earlier, gray, b0, _core(b0), resident_radius(b0[2], b0[3])):
            if b is None or in_frame_fraction(tuple(b), fw, fh) < RESIDENT_IN_FRAME:
                return False
        self.vetoed.append(b0)
        return True

    def passing_over(self, score: Callable[[np.ndarray], np.ndarray], w: float,
                     h: float) -> Callable[[np.ndarray], np.ndarray]:
        """``score`` (centres -> distances) with the centres :meth:`near` a refused resident at inf."""
        def wrapped(centres: np.ndarray) -> np.ndarray:
            d = score(centres)
            return np.where(self.near(centres, w, h), np.inf, d) if self.vetoed else d
        return wrapped

    def near(self, centres: np.ndarray, w: float, h: float) -> np.ndarray:
        """``(M,)`` bool: the centres of ``w`` x ``h`` boxes less than a box from a refused resident's centre along
        both x and y (the search passes over them)."""
        out = np.zeros(len(centres), dtype=bool)
        for b in self.vetoed:
            cx, cy = b[0] + b[2] / 2.0, b[1] + b[3] / 2.0
            out |= (np.abs(centres[:, 0] - cx) < w) & (np.abs(centres[:, 1] - cy) < h)
        return out


def _core(box: np.ndarray) -> np.ndarray:
    """The central part of ``box`` (x, y, w, h): :data:`RESIDENT_CORE` of its sides."""
    x, y, w, h = (float(v) for v in box)
    cw, ch = RESIDENT_CORE * w, RESIDENT_CORE * h
    return np.array([x + 0.5 * (w - cw), y + 0.5 * (h - ch), cw, ch])
