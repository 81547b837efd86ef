"""Boxes, ellipses, overlap and conversions.

Conventions (used everywhere in pftrack):

* A **box** is ``(x, y, w, h)``: the top-left corner and the size, in pixels,
  as floats.  The pixel with integer index ``(i, j)`` covers ``[i, i+1) x [j, j+1)``,
  so its centre is at ``(i + 0.5, j + 0.5)`` and a box ``(0, 0, W, H)`` covers a whole
  ``W x H`` image.
* An **ellipse** is ``(cx, cy, hx, hy)``: the centre and the half-axes, upright
  (Nummiaro et al., §3).  The ellipse inscribed in a box has
  ``cx = x + w/2, cy = y + h/2, hx = w/2, hy = h/2``.

All functions accept a single box (shape ``(4,)``) or a batch (shape ``(N, 4)``)
and return arrays of matching shape.
"""

from __future__ import annotations

import math
from typing import Iterable, Sequence

import numpy as np

from ._numba import njit, numba_enabled
from .errors import BoxError

Box = tuple[float, float, float, float]


def as_boxes(boxes: Sequence[float] | np.ndarray) -> np.ndarray:
    """Return ``boxes`` as a float64 array of shape ``(..., 4)``."""
    arr = np.asarray(boxes, dtype=np.float64)
    if arr.shape[-1:] != (4,):
        raise BoxError(f"a box has 4 numbers (x, y, w, h), got shape {arr.shape}")
    return arr


def box_to_ellipse(boxes) -> np.ndarray:
    """``(x, y, w, h)`` → ``(cx, cy, hx, hy)`` of the inscribed upright ellipse."""
    b = as_boxes(boxes)
    out = np.empty_like(b)
    out[..., 2] = b[..., 2] * 0.5
    out[..., 3] = b[..., 3] * 0.5
    out[..., 0] = b[..., 0] + out[..., 2]
    out[..., 1] = b[..., 1] + out[..., 3]
    return out


def ellipse_box(cx: float, cy: float, hx: float, hy: float) -> Box:
    """One ellipse's bounding box ``(x, y, w, h)`` on Python floats (:func:`ellipse_to_box`'s numbers, for the
    once-a-frame estimate, where an array's overhead would dominate)."""
    return cx - hx, cy - hy, 2.0 * hx, 2.0 * hy


def ellipse_to_box(ellipses) -> np.ndarray:
    """``(cx, cy, hx, hy)`` → the bounding box ``(x, y, w, h)``."""
    e = as_boxes(ellipses)
    out = np.empty_like(e)
    out[..., 0] = e[..., 0] - e[..., 2]
    out[..., 1] = e[..., 1] - e[..., 3]
    out[..., 2] = 2.0 * e[..., 2]
    out[..., 3] = 2.0 * e[..., 3]
    return out


def box_center(boxes) -> np.ndarray:
    """Centres ``(cx, cy)`` of boxes."""
    b = as_boxes(boxes)
    return b[..., :2] + 0.5 * b[..., 2:]


def box_area(boxes) -> np.ndarray:
    b = as_boxes(boxes)
    return np.clip(b[..., 2], 0, None) * np.clip(b[..., 3], 0, None)


def intersection_area(a, b) -> np.ndarray:
    """Area of the intersection of boxes ``a`` and ``b`` (broadcast)."""
    a = as_boxes(a)
    b = as_boxes(b)
    iw = np.minimum(a[..., 0] + a[..., 2], b[..., 0] + b[..., 2]) - np.maximum(a[..., 0], b[..., 0])
    ih = np.minimum(a[..., 1] + a[..., 3], b[..., 1] + b[..., 3]) - np.maximum(a[..., 1], b[..., 1])
    return np.clip(iw, 0, None) * np.clip(ih, 0, None)


def iou(a, b) -> np.ndarray:
    """Intersection over union of boxes ``a`` and ``b`` (broadcast).

    Boxes with non-positive area or non-finite values give IoU 0 (never NaN).
    """
    a = as_boxes(a)
    b = as_boxes(b)
    inter = intersection_area(a, b)
    union = box_area(a) + box_area(b) - inter
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(union > 0, inter / np.where(union > 0, union, 1.0), 0.0)
    out = np.where(np.isfinite(out), out, 0.0)
    return np.clip(out, 0.0, 1.0)  # rounding can exceed 1 by an ulp for identical boxes


def iou_matrix(a, b) -> np.ndarray:
    """Pairwise IoU between ``(N, 4)`` and ``(M, 4)`` boxes → ``(N, M)``."""
    a = as_boxes(a).reshape(-1, 4)
    b = as_boxes(b).reshape(-1, 4)
    return iou(a[:, None, :], b[None, :, :])


def center_error(a, b) -> np.ndarray:
    """Euclidean distance between box centres."""
    d = box_center(a) - box_center(b)
    return np.hypot(d[..., 0], d[..., 1])


def in_frame_fraction(box, width: float, height: float) -> float:
    """Fraction of one box's area inside the image ``(0, 0, width, height)``, on Python floats (per-frame
    tests of one estimate, where NumPy's per-call overhead would dominate); 0 for an empty box."""
    x, y, bw, bh = (float(v) for v in box)
    iw = max(min(x + bw, 0.0 + width) - max(x, 0.0), 0.0)
    ih = max(min(y + bh, 0.0 + height) - max(y, 0.0), 0.0)
    return iw * ih / max(bw * bh, 1e-9)


def exit_edge(cx: float, cy: float, hx: float, hy: float, width: float, height: float) -> int:
    """The edge of the ``width x height`` frame (0 left, 1 right, 2 top, 3 bottom) that a centre ``(cx, cy)`` lies
    furthest beyond, or least inside, in half-axes ``(hx, hy)``: ``np.argmin`` of the four distances (the first
    smallest, or the first NaN), on Python floats (it runs several times a search frame)."""
    d = (cx / hx, (width - cx) / hx, cy / hy, (height - cy) / hy)
    best = 0
    for i, v in enumerate(d):
        if v != v:
            return i
        if v < d[best]:
            best = i
    return best


def visible_box(box, width: int, height: int) -> tuple[float, float, float, float] | None:
    """The part of ``box`` inside the ``width x height`` frame, at least one pixel wide and high (a box wholly
    outside becomes a one-pixel box at the nearest edge, and a box under a pixel grows to one from its top-left
    corner); None when the box lies inside already and is at least a pixel wide and high (on Python floats: it runs
    on every tracked frame)."""
    x, y, bw, bh = box
    x1, y1 = x + bw, y + bh
    if x >= 0.0 and y >= 0.0 and x1 <= width and y1 <= height and bw >= 1.0 and bh >= 1.0:
        return None
    x0 = min(max(float(x), 0.0), width - 1.0)
    y0 = min(max(float(y), 0.0), height - 1.0)
    x1 = min(max(float(x1), x0 + 1.0), float(width))
    y1 = min(max(float(y1), y0 + 1.0), float(height))
    return x0, y0, x1 - x0, y1 - y0


def displacement_rate(track) -> tuple[float, float]:
    """Mean displacement per frame of a short track of ``(frame index, x, y)`` points, from its first point to its
    last (a target's observed velocity; a filter's velocity state lags behind it); ``(0, 0)`` with fewer than two
    points."""
    if len(track) < 2:
        return 0.0, 0.0
    f0, x0, y0 = track[0]
    f1, x1, y1 = track[-1]
    dt = max(float(f1 - f0), 1.0)
    return (float(x1) - float(x0)) / dt, (float(y1) - float(y0)) / dt


def clip_box(boxes, width: float, height: float) -> np.ndarray:
    """Clip boxes to the image ``[0, width) x [0, height)``; empty results get zero size."""
    b = as_boxes(boxes)
    x1 = np.clip(b[..., 0], 0, width)
    y1 = np.clip(b[..., 1], 0, height)
    x2 = np.clip(b[..., 0] + b[..., 2], 0, width)
    y2 = np.clip(b[..., 1] + b[..., 3], 0, height)
    return np.stack([x1, y1, np.maximum(x2 - x1, 0), np.maximum(y2 - y1, 0)], axis=-1)


def polygon_to_box(polygons) -> np.ndarray:
    """VOT polygon ``(x1, y1, ..., xk, yk)`` → its axis-aligned bounding box.

    A 4-number row is already a box and is returned unchanged, so a VOT ground
    truth file with either form can be converted row by row.
    """
    p = np.asarray(polygons, dtype=np.float64)
    if p.shape[-1] == 4:
        return p.copy()
    if p.shape[-1] < 6 or p.shape[-1] % 2:
        raise BoxError(f"a polygon has an even number (>= 6) of coordinates, got {p.shape[-1]}")
    xs = p[..., 0::2]
    ys = p[..., 1::2]
    x1, x2 = xs.min(axis=-1), xs.max(axis=-1)
    y1, y2 = ys.min(axis=-1), ys.max(axis=-1)
    return np.stack([x1, y1, x2 - x1, y2 - y1], axis=-1)


def parse_box(text: str) -> Box:
    """Parse ``"x,y,w,h"`` (commas, spaces or tabs) into a box; raise :class:`BoxError`."""
    parts = [p for p in text.replace("\t", ",").replace(" ", ",").split(",") if p]
    if len(parts) != 4:
        raise BoxError(f"box must be X,Y,W,H (4 numbers), got {text!r}")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        raise BoxError(f"box must be X,Y,W,H (4 numbers), got {text!r}") from None
    return values  # type: ignore[return-value]


def validate_box(box: Iterable[float], width: int, height: int, *, min_size: float = 1.0) -> Box:
    """Check that ``box`` is finite, of positive size and overlaps the image.

    Returns the box as a tuple of floats.  Raises :class:`BoxError` with a one-line
    message otherwise.
    """
    try:
        values = tuple(float(v) for v in box)
    except (TypeError, ValueError):
        raise BoxError(f"box must be 4 numbers (x, y, w, h), got {box!r}") from None
    if len(values) != 4:
        raise BoxError(f"box must be 4 numbers (x, y, w, h), got {len(values)}")
    if not all(math.isfinite(v) for v in values):
        raise BoxError(f"box {values} has non-finite values")
    x, y, w, h = values
    if w <= 0 or h <= 0:
        raise BoxError(f"box {values} has zero or negative size")
    if w < min_size or h < min_size:
        raise BoxError(f"box {values} is smaller than {min_size} pixel(s)")
    if x >= width or y >= height or x + w <= 0 or y + h <= 0:
        raise BoxError(f"box {values} lies outside the {width}x{height} image")
    return values  # type: ignore[return-value]


def ellipse_mask(shape: tuple[int, int], ellipse) -> np.ndarray:
    """Boolean mask of the pixels whose centres lie inside an ellipse (closed)."""
    cx, cy, hx, hy = (float(v) for v in ellipse)
    h, w = shape
    ys = np.arange(h) + 0.5 - cy
    xs = np.arange(w) + 0.5 - cx
    return (xs[None, :] ** 2) / (hx * hx) + (ys[:, None] ** 2) / (hy * hy) <= 1.0


def parabola_peak(a: float, b: float, c: float) -> float:
    """Sub-pixel offset of a maximum at ``b`` from three equally spaced samples ``a, b, c`` (the vertex of
    the parabola through them), clamped to ±0.5; 0 when the samples do not curve downwards.  For a
    minimum, pass the negated samples."""
    den = a - 2.0 * b + c
    return 0.0 if den >= 0 else float(np.clip(0.5 * (a - c) / den, -0.5, 0.5))


@njit
def _grid(step_x, step_y, nx, ny, hx, hy, ex, exclude):
    """:func:`background_grid`'s ellipses: cell centres ``(i + 0.5) step_x``, ``(j + 0.5) step_y`` row by row,
    without those whose box overlaps ``ex``'s when ``exclude``."""
    out = np.empty((nx * ny, 4))
    m = 0
    for j in range(ny):
        y = (j + 0.5) * step_y
        for i in range(nx):
            x = (i + 0.5) * step_x
            if exclude and not (abs(x - ex[0]) >= hx + ex[2] or abs(y - ex[1]) >= hy + ex[3]):
                continue
            out[m, 0] = x
            out[m, 1] = y
            out[m, 2] = hx
            out[m, 3] = hy
            m += 1
    return out[:m]


def background_grid(width: float, height: float, hx: float, hy: float, cap: int, exclude=None) -> np.ndarray:
    """Ellipses ``(cx, cy, hx, hy)`` of one size on a regular grid over a ``width`` x ``height`` frame, row by row
    (at most about ``cap``, and no denser than one half-axis per cell), without those that overlap the ellipse
    ``exclude``'s bounding box: the background samples of the colour trackers' statistics (Nummiaro Eqs. 13-14)."""
    nx = max(1, min(int(width / max(hx, 1.0)), int(math.ceil(math.sqrt(cap * width / max(height, 1))))))
    ny = max(1, min(int(height / max(hy, 1.0)), int(math.ceil(cap / nx))))
    if numba_enabled():  # the same numbers in one compiled pass (the statistics are refreshed every few frames)
        ex = np.zeros(4) if exclude is None else np.asarray(exclude, dtype=np.float64)
        return _grid(float(width / nx), float(height / ny), nx, ny, float(hx), float(hy), ex, exclude is not None)
    xs = (np.arange(nx) + 0.5) * (width / nx)
    ys = (np.arange(ny) + 0.5) * (height / ny)
    ell = np.empty((nx * ny, 4))  # the grid row by row (np.meshgrid's order)
    ell[:, 0] = np.tile(xs, ny)
    ell[:, 1] = np.repeat(ys, nx)
    ell[:, 2] = hx
    ell[:, 3] = hy
    if exclude is not None:
        ex = exclude
        far = (np.abs(ell[:, 0] - ex[0]) >= hx + ex[2]) | (np.abs(ell[:, 1] - ex[1]) >= hy + ex[3])
        ell = ell[far]
    return ell


def inside_cells(lo: float, hi: float, n: int, limit: float) -> np.ndarray:
    """``(n,)`` bool: which of the ``n`` equal cells of the interval ``[lo, hi]`` lie within ``[0, limit]`` (the
    columns or rows of a box's patch that are inside the frame)."""
    e = lo + (hi - lo) * np.arange(n + 1) / n
    return (e[:-1] >= 0.0) & (e[1:] <= limit)
