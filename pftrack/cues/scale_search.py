"""The target's scale from a grey reference patch: NCC over a few scales around an estimate (DSST-style).

A tracker whose likelihood cannot tell sizes apart still needs the box's size. Danelljan et
al.'s DSST ("Accurate scale estimation for robust visual tracking", BMVC 2014) estimates the
position first and then compares the target's appearance at a handful of scales around it.
Here the appearance is the zero-mean NCC of grey patches (:class:`~pftrack.cues.structure.StructureCue`:
a running reference and the first frame's, gain- and offset-invariant), so the estimate holds on
grey video and under a change of light. Each scale's score is the best over a few small shifts
of the centre, so that a position error of a pixel or two does not decide the scale.
"""

from __future__ import annotations

import math

import numpy as np

from .structure import StructureCue


def scale_candidates(ellipse, ratios: np.ndarray, shifts: np.ndarray) -> np.ndarray:
    """``(R*S, 4)`` ellipses ``(cx, cy, hx, hy)``: each ratio of the half-axes at each shift of the centre.

    ``shifts`` is ``(S, 2)`` in units of the scaled half-axes (row ``r * S + s`` is ratio ``r``, shift ``s``)."""
    cx, cy, hx, hy = (float(v) for v in ellipse)
    r = np.asarray(ratios, dtype=np.float64)[:, None]
    d = np.asarray(shifts, dtype=np.float64).reshape(-1, 2)[None, :, :]
    ex = (cx + d[..., 0] * r * hx).ravel()
    ey = (cy + d[..., 1] * r * hy).ravel()
    ax = np.broadcast_to(r * hx, (r.shape[0], d.shape[1])).ravel()
    ay = np.broadcast_to(r * hy, (r.shape[0], d.shape[1])).ravel()
    return np.column_stack([ex, ey, ax, ay])


def best_ratio(scores: np.ndarray, ratios: np.ndarray, n_shifts: int,
               margin: float = 0.0) -> tuple[float, float, float]:
    """From the ``(R*S,)`` NCC of :func:`scale_candidates`: ``(ratio, its score, the score at ratio 1)``.

    Each ratio scores the best of its shifts. A ratio other than 1 is taken only when it beats ratio 1
    by more than ``margin`` (no change on a flat response)."""
    per = np.asarray(scores, dtype=np.float64).reshape(len(ratios), n_shifts).max(axis=1)
    ratios = np.asarray(ratios, dtype=np.float64)
    i1 = int(np.argmin(np.abs(ratios - 1.0)))
    k = int(np.argmax(per))
    if per[k] <= per[i1] + margin:
        k = i1
    return float(ratios[k]), float(per[k]), float(per[i1])


def vertex_ratio(scores: np.ndarray, step: float, n_shifts: int, margin: float = 0.0) -> tuple[float, float, float]:
    """Like :func:`best_ratio` for the three ratios ``1/(1+step), 1, 1+step``, with the optimum between them:
    the vertex of the parabola through the three scores in log-scale (clipped to the outer ratios).

    Noise in the scores then moves the size by a fraction of a step, around zero, instead of a whole step.
    A response that is not concave (no maximum between the outer ratios) takes the better outer ratio
    when it beats ratio 1 by more than ``margin``, else keeps the size. Returns
    ``(ratio, best score, score at ratio 1)``."""
    lo, mid, hi = (float(v) for v in np.asarray(scores, dtype=np.float64).reshape(3, n_shifts).max(axis=1))
    x = vertex_offset(lo, mid, hi, margin)
    return float(np.exp(x * np.log1p(step))), max(lo, mid, hi), mid


def vertex_offset(lo: float, mid: float, hi: float, margin: float = 0.0) -> float:
    """Where the best of three equally spaced scores lies, in steps from the middle one, in ``[-1, 1]``: the vertex
    of the parabola through them when it is a maximum; otherwise the better outer point when it beats the middle
    by more than ``margin``, else 0."""
    curv = lo - 2.0 * mid + hi
    if curv < 0.0:  # concave: the vertex
        return min(max(0.5 * (lo - hi) / curv, -1.0), 1.0)
    if max(lo, hi) - mid > margin:
        return -1.0 if lo > hi else 1.0
    return 0.0


def search_scale(cue: StructureCue, frame: np.ndarray, ellipse, *, step: float = 0.05, shift: float = 0.1,
                 margin: float = 0.0, interpolate: bool = False) -> tuple[float, float, float]:
    """The ratio in ``{1/(1+step), 1, 1+step}`` whose box around ``ellipse`` best matches the cue's reference
    (:func:`best_ratio`), or with ``interpolate`` the parabola's vertex between them (:func:`vertex_ratio`).

    The centre is also tried at ``shift`` of the half-axes to each side (9 positions). Returns
    ``(ratio, best NCC, NCC at ratio 1)``."""
    ratios = np.array([1.0 / (1.0 + step), 1.0, 1.0 + step])
    g = np.array([-shift, 0.0, shift])
    shifts = np.array([(a, b) for b in g for a in g])
    ell = scale_candidates(ellipse, ratios, shifts)
    scores = cue.scores(frame, None, ell)
    if interpolate:
        return vertex_ratio(scores, step, len(shifts), margin)
    return best_ratio(scores, ratios, len(shifts), margin)


def _fits(frame: np.ndarray, cx: float, cy: float, ax: float, ay: float) -> bool:
    """Is the box of half-axes ``(ax, ay)`` around ``(cx, cy)`` inside the frame?"""
    fh, fw = frame.shape[:2]
    return cx - ax >= 0 and cy - ay >= 0 and cx + ax <= fw and cy + ay <= fh


def best_shape_score(cue, frame: np.ndarray, ellipse, step: float) -> float:
    """The best of ``cue``'s scores (``size_scores``) of the 3 x 3 shapes around ``ellipse`` ``(cx, cy, hx, hy)``:
    each half-axis times 1/(1+step), 1 or 1+step, on its own; -inf when the largest box is not inside the frame (its
    part beyond the border has no pixels to correlate)."""
    cx, cy, hx, hy = (float(v) for v in ellipse)
    k = 1.0 + step
    if not _fits(frame, cx, cy, k * hx, k * hy):
        return -math.inf
    f = (1.0 / k, 1.0, k)
    return max(cue.size_scores(frame, (cx, cy, hx, hy), [(a, b) for a in f for b in f]))


def _vertex_factor(cue, frame: np.ndarray, ellipse, ratios, step: float, rate: float, *,
                   anchor_only: bool = False) -> float:
    """``exp(rate log(1+step) v)``, ``v`` the vertex (:func:`vertex_offset`) of the NCC of the boxes of ``ellipse`` at
    the three half-axis ``ratios`` (scalars, or ``(rx, ry)`` pairs); 1 when a box ``1+step`` times as large on both
    axes is not inside the frame (the part of a box beyond the border has no pixels to correlate, and comparing
    boxes there favours the one that fits, docs/robustness.md), or a score is not finite."""
    cx, cy, hx, hy = np.asarray(ellipse, dtype=np.float64).ravel()[:4].tolist()
    if not _fits(frame, cx, cy, (1.0 + step) * hx, (1.0 + step) * hy):
        return 1.0
    lo, mid, hi = cue.size_scores(frame, (cx, cy, hx, hy), ratios, anchor_only=anchor_only)
    if not (math.isfinite(lo) and math.isfinite(mid) and math.isfinite(hi)):
        return 1.0
    return math.exp(vertex_offset(lo, mid, hi) * math.log1p(step) * rate)


def size_factor(cue, frame: np.ndarray, ellipse, step: float, rate: float, *, anchor_only: bool = False) -> float:
    """The factor by which the half-axes of ``ellipse`` ``(cx, cy, hx, hy)`` move toward the size whose patch best
    matches ``cue``'s references (anything with ``size_scores(frame, ellipse, ratios)``, as
    :class:`~pftrack.cues.structure.StructureCue`): the NCC at the sizes 1/(1+step), 1 and 1+step, the vertex of
    the parabola through them (:func:`vertex_offset`), ``rate`` of the way.

    1 when the largest of the three boxes is not inside the frame: the part of a box beyond the border has no
    pixels to correlate, and comparing sizes there favours the box that fits (docs/robustness.md).  ``anchor_only``:
    the cue's first-frame reference alone (:meth:`~pftrack.cues.structure.StructureCue.size_scores`)."""
    return _vertex_factor(cue, frame, ellipse, (1.0 / (1.0 + step), 1.0, 1.0 + step), step, rate,
                          anchor_only=anchor_only)


def aspect_factor(cue, frame: np.ndarray, ellipse, step: float, rate: float) -> float:
    """Like :func:`size_factor` for the box's shape at a constant area: the NCC of the boxes whose half-axes are
    ``(hx / (1+step), hy (1+step))``, ``(hx, hy)`` and ``(hx (1+step), hy / (1+step))``, the vertex of the parabola
    through them, ``rate`` of the way.  Returns ``f``: the width's factor (the height's is ``1 / f``).

    A target that turns, bends or is seen from another side changes its width and height apart, and a size search
    at a fixed aspect cannot follow it.  1 when the widest or the tallest box is not inside the frame."""
    k = 1.0 + step
    return _vertex_factor(cue, frame, ellipse, ((1.0 / k, k), (1.0, 1.0), (k, 1.0 / k)), step, rate)
