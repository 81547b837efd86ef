"""Measures for point tracking through occlusions (book ch. 7 experiments).

* :func:`recovery` — per point, is it within ``tol`` pixels of the truth ``after`` frames
  after its window has left the obstacle (the issue's "recovery after occlusion").
* :func:`run_points` / :func:`run_stereo` — run a point or stereo tracker over a
  synthetic scene and return positions, sources and gains per frame.
* :func:`box_passes` — the frames where MOT ground-truth boxes of one identity overlap
  a fixed vertical occluder (a lamp post), for the through-occlusion test on real video.
"""

from __future__ import annotations

import numpy as np

__all__ = ["box_passes", "recovery", "run_points", "run_stereo"]


def recovery(pos: np.ndarray, truth: np.ndarray, exits: np.ndarray, *, after: int = 5, tol: float = 3.0
             ) -> np.ndarray:
    """``(P,)`` booleans for the points that are occluded at some time (``exits >= 0``) and whose
    position ``after`` frames after the exit is within ``tol`` px (points whose check frame
    is beyond the sequence are left out)."""
    out = []
    for j, e in enumerate(np.asarray(exits)):
        t = int(e) + after
        if e < 0 or t >= len(pos):
            continue
        out.append(bool(np.hypot(*(pos[t, j] - truth[t, j])) <= tol))
    return np.asarray(out, dtype=bool)


def run_points(frames, points0: np.ndarray, params) -> dict[str, np.ndarray]:
    """Positions ``(T, P, 2)``, sources, ``k`` and ``eps`` ``(T, P)`` of a :class:`PointTracker` run."""
    from ..trackers.point_gate import PointTracker

    tr = PointTracker(params)
    steps = [tr.init(frames[0], points0)] + [tr.step(f) for f in frames[1:]]
    return {"pos": np.array([s.pos for s in steps]), "source": np.array([s.source for s in steps]),
            "k": np.array([s.k for s in steps]), "eps": np.array([s.eps for s in steps])}


def run_stereo(scene, params) -> dict[str, np.ndarray]:
    """``xl (T, P, 2)``, ``xr``, ``Z``, sources of a :class:`StereoTracker` run on a :class:`StereoScene`."""
    from ..trackers.stereo import StereoTracker

    tr = StereoTracker(scene.calib, params)
    steps = [tr.init(scene.left[0], scene.right[0], scene.xl[0])]
    steps += [tr.step(a, b) for a, b in zip(scene.left[1:], scene.right[1:])]
    return {"xl": np.array([s.xl for s in steps]), "xr": np.array([s.xr for s in steps]),
            "Z": np.array([s.Z for s in steps]), "src_l": np.array([s.src_l for s in steps]),
            "src_r": np.array([s.src_r for s in steps])}


def box_passes(mot_gt: np.ndarray, x_range: tuple[float, float], *, y_range: tuple[float, float] | None = None,
               lead: int = 5, tail: int = 10) -> list[dict]:
    """Identities whose box overlaps the column ``x_range`` (and ``y_range``) for a contiguous run.

    Returns one record per pass: ``id``, ``start`` (first frame of the overlap), ``exit``
    (first frame after it), ``init`` (``start - lead``), with the identity present on every
    frame from ``init`` to ``exit + tail`` (frames numbered from 1, as in the file).
    """
    gt = np.asarray(mot_gt, dtype=np.float64)
    out = []
    for tid in np.unique(gt[:, 1]).astype(int):
        rows = gt[gt[:, 1] == tid]
        rows = rows[np.argsort(rows[:, 0])]
        frames = rows[:, 0].astype(int)
        x, y, w, h = rows[:, 2], rows[:, 3], rows[:, 4], rows[:, 5]
        over = (x < x_range[1]) & (x + w > x_range[0])
        if y_range is not None:
            over &= (y < y_range[1]) & (y + h > y_range[0])
        idx = np.flatnonzero(over)
        if len(idx) == 0:
            continue
        runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1)
        for run in runs:
            start, exit_ = frames[run[0]], frames[run[-1]] + 1
            need = set(range(start - lead, exit_ + tail + 1))
            if need <= set(frames.tolist()):
                out.append({"id": int(tid), "start": int(start), "exit": int(exit_), "init": int(start - lead)})
    return out
