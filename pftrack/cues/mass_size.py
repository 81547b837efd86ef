"""The target's size read from the mass of the foreground-probability map (``fusion-pf``'s ``mass_size``).

The colour histogram barely observes the size of a box that lies inside the target, and the box contrast and the
structural NCC of an elliptic target with little texture of its own prefer a box smaller than the target (the box's
corners are background that changes as the target moves; docs/robustness-cameras.md). Its box then shrinks. The
zeroth moment of a foreground-probability map measures the size instead, as CamShift reads it from a colour
back-projection (Bradski 1998): the object's pixels carry a high probability, the background's a low one.

With ``P`` the contrast cue's map (:mod:`pftrack.cues.contrast`) and ``B`` the estimate's box (half-axes
``hx, hy``), three centred windows are read from the map's integral image:

* the core, ``B`` shrunk to half its size: ``p_t``, the mean probability of the object's pixels;
* the window, ``B`` grown to ``inner`` times its size: the mass ``M`` and the number of pixels ``n``;
* the ring between the window and ``outer`` times the box: ``p_b``, the mean probability of the background.

The object's area is then ``A = (M - p_b n) / (p_t - p_b)``: the window's mass above the background's level,
counted in object pixels (so that a colour model that adapts, moving ``p_t``, does not move ``A``). Only a map that
separates the two, ``p_t - p_b >= gate``, is read. Against ``(A_0, s_0)``, the area and the size ``s = sqrt(hx hy)``
at the first reading, the size the area implies is ``s_0 sqrt(A / A_0)``; the estimate moves toward it by a share
``rate`` of the ratio in log scale, the ratio clipped to ``[0.8, 1.25]``.

Pure functions on the integral image: arrays in, numbers out.
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import njit, numba_enabled

__all__ = ["CORE", "INNER", "OUTER", "mass_factor", "object_area", "window_mass"]

#: the windows, as multiples of the estimate's box (centred on it): the core (the object's own pixels), the window
#: whose mass is read, and the outer edge of the background ring around it
CORE, INNER, OUTER = 0.5, 2.0, 2.6
#: the largest step of the size toward the area's in one frame, before ``rate`` (either way)
MAX_RATIO = 1.25


def window_mass(ii: np.ndarray, x0: float, y0: float, pitch: int, rect: tuple[float, float, float, float]
                ) -> tuple[float, int]:
    """The mass of the frame rectangle ``rect = (X0, Y0, X1, Y1)`` on the map whose integral image is ``ii``
    (``(h + 1, w + 1)``, of a lattice of ``pitch`` pixels whose first sample is the frame's pixel ``(x0, y0)``):
    ``(sum of P over the lattice samples inside, their number)``, the rectangle clipped to the lattice."""
    h, w = ii.shape[0] - 1, ii.shape[1] - 1
    a0 = min(max(int(math.floor((rect[0] - x0) / pitch)), 0), w)
    a1 = min(max(int(math.ceil((rect[2] - x0) / pitch)), 0), w)
    b0 = min(max(int(math.floor((rect[1] - y0) / pitch)), 0), h)
    b1 = min(max(int(math.ceil((rect[3] - y0) / pitch)), 0), h)
    if a1 <= a0 or b1 <= b0:
        return 0.0, 0
    m = float(ii[b1, a1]) - float(ii[b0, a1]) - float(ii[b1, a0]) + float(ii[b0, a0])
    return m, (a1 - a0) * (b1 - b0)


@njit(cache=True)
def _mass_numba(ii, x0, y0, pitch, X0, Y0, X1, Y1):  # pragma: no cover - compiled; window_mass is the reference
    h, w = ii.shape[0] - 1, ii.shape[1] - 1
    a0 = min(max(int(math.floor((X0 - x0) / pitch)), 0), w)
    a1 = min(max(int(math.ceil((X1 - x0) / pitch)), 0), w)
    b0 = min(max(int(math.floor((Y0 - y0) / pitch)), 0), h)
    b1 = min(max(int(math.ceil((Y1 - y0) / pitch)), 0), h)
    if a1 <= a0 or b1 <= b0:
        return 0.0, 0
    return ii[b1, a1] - ii[b0, a1] - ii[b1, a0] + ii[b0, a0], (a1 - a0) * (b1 - b0)


@njit(cache=True)
def _area_numba(ii, x0, y0, pitch, cx, cy, hx, hy, gate, core, inner, outer, fw, fh):  # pragma: no cover - compiled
    """:func:`object_area` in one call: ``(A, separation)``, or NaNs where it gives None (the same operations)."""
    nan = (math.nan, math.nan)
    if not (hx > 0 and hy > 0):
        return nan
    mc, nc = _mass_numba(ii, x0, y0, pitch, cx - core * hx, cy - core * hy, cx + core * hx, cy + core * hy)
    X0, Y0, X1, Y1 = cx - inner * hx, cy - inner * hy, cx + inner * hx, cy + inner * hy
    mass, n = _mass_numba(ii, x0, y0, pitch, X0, Y0, X1, Y1)
    if fw > 0:  # the window's part inside the frame is what must be covered
        X0, Y0, X1, Y1 = max(X0, 0.0), max(Y0, 0.0), min(X1, fw), min(Y1, fh)
        if X1 <= X0 or Y1 <= Y0:
            return nan
    mo, no = _mass_numba(ii, x0, y0, pitch, cx - outer * hx, cy - outer * hy, cx + outer * hx, cy + outer * hy)
    if nc == 0 or n < 0.95 * ((X1 - X0) * (Y1 - Y0) / (pitch * pitch)) or no - n < 4:
        return nan
    p_b = (mo - mass) / (no - n)
    sep = mc / nc - p_b
    if sep < gate:
        return nan
    area = (mass - p_b * n) / sep * pitch * pitch
    return (area, sep) if area > 0 else nan


def _rect(cx: float, cy: float, hx: float, hy: float, f: float) -> tuple[float, float, float, float]:
    return cx - f * hx, cy - f * hy, cx + f * hx, cy + f * hy


def _cells(pitch: int, rect: tuple[float, float, float, float]) -> float:
    """The lattice samples a rectangle would hold unclipped (about)."""
    return (rect[2] - rect[0]) * (rect[3] - rect[1]) / (pitch * pitch)


def object_area(ii: np.ndarray, x0: float, y0: float, pitch: int, ellipse, *, gate: float = 0.8,
                frame: tuple[int, int] | None = None) -> tuple[float, float] | None:
    """``(A, p_t - p_b)``: the object's area in pixels around the box of ``ellipse`` ``(cx, cy, hx, hy)`` and the
    map's separation (module docstring), or None when the map does not separate the object (below ``gate``), the
    window is cut by the lattice's edge (less than 95 % of it inside), the ring holds fewer than 4 samples, or the
    area is not positive. With ``frame = (width, height)`` only the window's part inside the frame must be covered:
    beyond the frame's edge there is nothing to count (the visible area is read, as single-object benchmarks box a
    target at the edge), so a target near the edge of a small frame is read too."""
    cx, cy, hx, hy = (float(v) for v in ellipse)
    fw, fh = (float(frame[0]), float(frame[1])) if frame is not None else (0.0, 0.0)
    if numba_enabled() and ii.dtype == np.float64 and ii.ndim == 2:
        area, sep = _area_numba(ii, float(x0), float(y0), int(pitch), cx, cy, hx, hy, float(gate), CORE, INNER,
                                OUTER, fw, fh)
        return None if area != area else (area, sep)
    if not (hx > 0 and hy > 0):
        return None
    core = window_mass(ii, x0, y0, pitch, _rect(cx, cy, hx, hy, CORE))
    inner_rect = _rect(cx, cy, hx, hy, INNER)
    mass, n = window_mass(ii, x0, y0, pitch, inner_rect)
    if fw > 0:
        inner_rect = (max(inner_rect[0], 0.0), max(inner_rect[1], 0.0), min(inner_rect[2], fw),
                      min(inner_rect[3], fh))
        if inner_rect[2] <= inner_rect[0] or inner_rect[3] <= inner_rect[1]:
            return None
    outer, n_outer = window_mass(ii, x0, y0, pitch, _rect(cx, cy, hx, hy, OUTER))
    if core[1] == 0 or n < 0.95 * _cells(pitch, inner_rect) or n_outer - n < 4:
        return None
    p_b = (outer - mass) / (n_outer - n)
    sep = core[0] / core[1] - p_b
    if sep < gate:
        return None
    area = (mass - p_b * n) / sep * pitch * pitch
    return (area, sep) if area > 0 else None


def mass_factor(reference: tuple[float, float], area: float, size: float, rate: float) -> float:
    """The factor ``k`` for the estimate's half-axes: ``(s_0 sqrt(A / A_0) / s) ** rate``, the ratio clipped to
    ``[1 / MAX_RATIO, MAX_RATIO]``; ``reference = (A_0, s_0)``, ``size = s = sqrt(hx hy)``."""
    a0, s0 = reference
    ratio = s0 * math.sqrt(area / a0) / size
    ratio = min(max(ratio, 1.0 / MAX_RATIO), MAX_RATIO)
    return ratio ** rate
