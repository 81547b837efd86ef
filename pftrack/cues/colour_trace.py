"""An object followed back through earlier frames by its colour histogram (pftrack's addition; the colour trackers'
``resident_trace = "colour"``, :mod:`pftrack.trackers.vetoes`).

The normalised correlation of an object's central part (:func:`pftrack.cues.template.trace_back`) follows rigid
texture well, but a walker's arms and legs change between two frames at a low frame rate: at 7 fps a PETS walker's
central part correlates with itself one frame earlier at 0.38-0.45. Its colours change little. Here a box is followed
back frame by frame to the place, within ``radius`` px, whose colour histogram (8 x 8 x 8 bins of B, G, R over the
box's central part) is most like its own on the frame after, by Bhattacharyya coefficient; the trace is lost where
the best coefficient is below ``min_rho``.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator

import cv2
import numpy as np

BINS = 8


def core_hist(frame: np.ndarray, box, core: float = 0.5) -> np.ndarray | None:
    """The normalised ``BINS``^3 B, G, R histogram of the central ``core`` of ``box`` (x, y, w, h) on ``frame``
    (the part inside the frame), or None when that part is smaller than 2 x 2 px."""
    h, w = frame.shape[:2]
    x, y, bw, bh = (float(v) for v in box)
    cx, cy = x + 0.5 * bw, y + 0.5 * bh
    x0, y0 = max(int(round(cx - 0.5 * core * bw)), 0), max(int(round(cy - 0.5 * core * bh)), 0)
    x1, y1 = min(int(round(cx + 0.5 * core * bw)), w), min(int(round(cy + 0.5 * core * bh)), h)
    if x1 - x0 < 2 or y1 - y0 < 2:
        return None
    patch = np.ascontiguousarray(frame[y0:y1, x0:x1])
    if patch.ndim == 2:
        patch = cv2.cvtColor(patch, cv2.COLOR_GRAY2BGR)
    hist = cv2.calcHist([patch], [0, 1, 2], None, [BINS] * 3, [0, 256] * 3).ravel()
    return hist / max(float(hist.sum()), 1.0)


def best_shift(frame: np.ndarray, box, ref: np.ndarray, radius: int) -> tuple[np.ndarray, float]:
    """The shift ``(dx, dy)`` within ``radius`` px of ``box`` on ``frame`` whose central histogram is most like
    ``ref`` (Bhattacharyya coefficient), on a grid of about a quarter radius, then refined about the best at a
    quarter of that step; and its coefficient."""
    sq = np.sqrt(ref)

    def rho_at(dx: float, dy: float) -> float:
        hb = core_hist(frame, (box[0] + dx, box[1] + dy, box[2], box[3]))
        return -1.0 if hb is None else float(np.sqrt(hb) @ sq)

    step = max(1, int(round(radius / 4)))
    best, best_d = -1.0, (0.0, 0.0)
    for dy in range(-radius, radius + 1, step):
        for dx in range(-radius, radius + 1, step):
            r = rho_at(dx, dy)
            if r > best:
                best, best_d = r, (float(dx), float(dy))
    fine = max(1, step // 4)
    cx, cy = best_d
    for dy in range(-step + fine, step, fine):
        for dx in range(-step + fine, step, fine):
            r = rho_at(cx + dx, cy + dy)
            if r > best:
                best, best_d = r, (cx + dx, cy + dy)
    return np.array(best_d), best


def trace_back_colour(earlier: Iterable[np.ndarray], frame: np.ndarray, box, radius: int, *,
                      min_rho: float = 0.8) -> Iterator[np.ndarray | None]:
    """``box`` (x, y, w, h on ``frame``) followed back through the ``earlier`` frames (newest first) by its central
    histogram (:func:`best_shift`, the reference taken afresh on each frame so that a slow change is followed).
    Yields the box on each earlier frame in turn, or ``None`` once the trace is lost, and then stops; lazily."""
    box = np.array(box, dtype=np.float64)
    ref = core_hist(frame, box)
    for prev in earlier:
        if ref is None:
            yield None
            return
        d, rho = best_shift(prev, box, ref, radius)
        if rho < min_rho:
            yield None
            return
        box[:2] += d
        ref = core_hist(prev, box)
        yield box.copy()
