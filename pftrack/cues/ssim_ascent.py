"""Global SSIM of one region, its analytic gradient and the DSSIM ascent (book ch. 2, Table 3).

* **(18)-(20)** global statistics over the L pixels of a region (``L - 1`` denominators) —
  :func:`ssim_global`; **(31)-(39)** the analytic gradient of ``rho = sign(S) log|S|`` with
  respect to the region's position, with the corrected ``A3 = 2/(2 sigma_IJ + C2)`` (the book
  prints ``1/(...)``; ch02.md P5) — :func:`grad_rho`;
* the DSSIM ascent of Table 3 (one-pixel steps to the 8-neighbour along the gradient while
  S does not decrease), compiled — :func:`dssim_ascent`, :func:`dssim_ascent_batch`.  The
  region is sampled bilinearly on the reference patch's grid, scaled; the taps are computed
  once per row and per column (:func:`_axis_taps`).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .._numba import njit
from .ssim import C1, C2

# ------------------------------------------------------------------------------ global SSIM and its gradient

def _global_stats(i: np.ndarray, j: np.ndarray, c1: float, c2: float):
    """``(i, j, mi, mj, vi, vj, cij, S)``: the flattened regions, statistics (18)-(20) and Eq. (21)."""
    i = np.asarray(i, dtype=np.float64).ravel()
    j = np.asarray(j, dtype=np.float64).ravel()
    n = i.size
    mi, mj = i.mean(), j.mean()
    vi = ((i - mi) ** 2).sum() / (n - 1)
    vj = ((j - mj) ** 2).sum() / (n - 1)
    cij = ((i - mi) * (j - mj)).sum() / (n - 1)
    s = (2 * mi * mj + c1) * (2 * cij + c2) / ((mi * mi + mj * mj + c1) * (vi + vj + c2))
    return i, j, mi, mj, vi, vj, cij, s


def ssim_global(i: np.ndarray, j: np.ndarray, *, c1: float = C1, c2: float = C2) -> float:
    """Eq. (21) with the global statistics (18)-(20) over all L pixels (``L - 1`` denominators)."""
    return float(_global_stats(i, j, c1, c2)[-1])


def grad_rho(i: np.ndarray, j: np.ndarray, gix: np.ndarray, giy: np.ndarray, *, c1: float = C1, c2: float = C2,
             a3_paper: bool = False) -> np.ndarray:
    """Eq. (39): gradient of ``rho = sign(S) log|S|`` w.r.t. the region's position.

    ``i`` is the frame region, ``j`` the template, ``gix, giy`` the frame's intensity
    gradient at the region's pixels.  ``a3_paper`` uses the printed ``A3 = 1/(2 sigma_IJ + C2)``
    instead of the analytic ``2/(2 sigma_IJ + C2)``.
    """
    i, j, mi, mj, vi, vj, cij, s = _global_stats(i, j, c1, c2)
    gx = np.asarray(gix, dtype=np.float64).ravel()
    gy = np.asarray(giy, dtype=np.float64).ravel()
    n = i.size
    sign = 1.0 if s >= 0 else -1.0
    a1 = 2 * mj / (2 * mi * mj + c1) - 2 * mi / (mi * mi + mj * mj + c1)
    a2 = -1.0 / (vi + vj + c2)
    a3 = (1.0 if a3_paper else 2.0) / (2 * cij + c2)
    coef = a1 / n + (2 * a2 * (i - mi) + a3 * (j - mj)) / (n - 1)
    return sign * np.array([np.sum(coef * gx), np.sum(coef * gy)])


@njit
def _axis_taps(n, centre, s, size, off, idx, frac):
    """Bilinear taps along one axis of a regular sample grid: for sample ``k`` at
    ``centre + s * (k - (n - 1) / 2) + off``, the two pixel indices ``idx[0, k], idx[1, k]`` and the weight
    ``frac[k]`` of the second.  Coordinates are pixel-centre based (pixel ``i`` has its centre at ``i + 0.5``)
    and clamped to the image, so samples beyond the border repeat the edge pixels."""
    half = (n - 1) / 2.0
    for k in range(n):
        p = (centre + s * (k - half)) + off
        f = min(max(p - 0.5, 0.0), size - 1.0)
        i0 = min(int(f), size - 2) if size > 1 else 0
        frac[k] = f - i0
        idx[0, k] = i0
        idx[1, k] = min(i0 + 1, size - 1)


@njit
def _grid_value(img, xi, xa, yi, ya, r, c):
    """Bilinear value at grid sample ``(r, c)`` from the x and y taps of :func:`_axis_taps`."""
    ax = xa[c]
    ay = ya[r]
    x0 = xi[0, c]
    x1 = xi[1, c]
    y0 = yi[0, r]
    y1 = yi[1, r]
    return ((1 - ay) * ((1 - ax) * img[y0, x0] + ax * img[y0, x1])
            + ay * ((1 - ax) * img[y1, x0] + ax * img[y1, x1]))


@njit
def _region_value(gray, tmpl, cx, cy, s, c1, c2, vals, ti, ta):
    """Global SSIM (21) of the region at ``(cx, cy)``, scale ``s``; the samples are left in ``vals``.

    ``ti, ta``: tap workspaces ``(2, 2, max(h, w))`` int64 and ``(2, max(h, w))``, for x and y.
    Returns ``(S, mi, mj, vi, vj, cij)``, the statistics (18)-(20) the gradient needs."""
    h, w = tmpl.shape
    n = h * w
    _axis_taps(w, cx, s, gray.shape[1], 0.0, ti[0], ta[0])
    _axis_taps(h, cy, s, gray.shape[0], 0.0, ti[1], ta[1])
    k = 0
    for r in range(h):
        for c in range(w):
            vals[k] = _grid_value(gray, ti[0], ta[0], ti[1], ta[1], r, c)
            k += 1
    mi = 0.0
    mj = 0.0
    for k in range(n):
        mi += vals[k]
        mj += tmpl.flat[k]
    mi /= n
    mj /= n
    vi = 0.0
    vj = 0.0
    cij = 0.0
    for k in range(n):
        di = vals[k] - mi
        dj = tmpl.flat[k] - mj
        vi += di * di
        vj += dj * dj
        cij += di * dj
    vi /= n - 1
    vj /= n - 1
    cij /= n - 1
    sv = (2 * mi * mj + c1) * (2 * cij + c2) / ((mi * mi + mj * mj + c1) * (vi + vj + c2))
    return sv, mi, mj, vi, vj, cij


@njit
def _region_gradient(gray, gx, gy, tmpl, cx, cy, s, c1, c2, vals, sv, mi, mj, vi, vj, cij, gi, ga):
    """grad rho (39) at the region of :func:`_region_value` (its samples ``vals`` and statistics).

    The image derivative at each sample is read from ``gx, gy``, or, when they are empty, is the central
    difference of the bilinear image there.  ``gi, ga``: tap workspaces ``(3, 2, 2, m)`` and ``(3, 2, m)``
    for the offsets -1, 0, +1 along x (``[., 0]``) and y (``[., 1]``)."""
    h, w = tmpl.shape
    n = h * w
    sign = 1.0 if sv >= 0 else -1.0
    a1 = 2 * mj / (2 * mi * mj + c1) - 2 * mi / (mi * mi + mj * mj + c1)
    a2 = -1.0 / (vi + vj + c2)
    a3 = 2.0 / (2 * cij + c2)
    dense = gx.shape[0] != 0
    for o in range(3):
        if dense and o != 1:
            continue
        _axis_taps(w, cx, s, gray.shape[1], o - 1.0, gi[o, 0], ga[o, 0])
        _axis_taps(h, cy, s, gray.shape[0], o - 1.0, gi[o, 1], ga[o, 1])
    gxo = 0.0
    gyo = 0.0
    k = 0
    for r in range(h):
        for c in range(w):
            if dense:
                dx = _grid_value(gx, gi[1, 0], ga[1, 0], gi[1, 1], ga[1, 1], r, c)
                dy = _grid_value(gy, gi[1, 0], ga[1, 0], gi[1, 1], ga[1, 1], r, c)
            else:
                dx = 0.5 * (_grid_value(gray, gi[2, 0], ga[2, 0], gi[1, 1], ga[1, 1], r, c)
                            - _grid_value(gray, gi[0, 0], ga[0, 0], gi[1, 1], ga[1, 1], r, c))
                dy = 0.5 * (_grid_value(gray, gi[1, 0], ga[1, 0], gi[2, 1], ga[2, 1], r, c)
                            - _grid_value(gray, gi[1, 0], ga[1, 0], gi[0, 1], ga[0, 1], r, c))
            coef = a1 / n + (2 * a2 * (vals[k] - mi) + a3 * (tmpl.flat[k] - mj)) / (n - 1)
            gxo += coef * dx
            gyo += coef * dy
            k += 1
    return sign * gxo, sign * gyo


@njit
def _region_ssim_grad(gray, gx, gy, tmpl, cx, cy, s, c1, c2, want_grad):
    """Global SSIM (21) of the region at ``(cx, cy)``, scale ``s``, and (optionally) grad rho (39)."""
    vals = np.empty(tmpl.shape[0] * tmpl.shape[1])
    m = max(tmpl.shape[0], tmpl.shape[1])
    ti, ta = np.empty((2, 2, m), np.int64), np.empty((2, m))
    sv, mi, mj, vi, vj, cij = _region_value(gray, tmpl, cx, cy, s, c1, c2, vals, ti, ta)
    if not want_grad:
        return sv, 0.0, 0.0
    gi, ga = np.empty((3, 2, 2, m), np.int64), np.empty((3, 2, m))
    gxo, gyo = _region_gradient(gray, gx, gy, tmpl, cx, cy, s, c1, c2, vals, sv, mi, mj, vi, vj, cij, gi, ga)
    return sv, gxo, gyo


@njit
def _ascent(gray, gx, gy, tmpl, cx, cy, s, max_iter, c1, c2):
    """Table 3: one-pixel steps to the 8-neighbour nearest the gradient direction while S does not drop.

    The gradient is computed only at the points the ascent moves to (a rejected step needs only S)."""
    vals = np.empty(tmpl.shape[0] * tmpl.shape[1])
    m = max(tmpl.shape[0], tmpl.shape[1])
    ti, ta = np.empty((2, 2, m), np.int64), np.empty((2, m))
    gi, ga = np.empty((3, 2, 2, m), np.int64), np.empty((3, 2, m))
    s0, mi, mj, vi, vj, cij = _region_value(gray, tmpl, cx, cy, s, c1, c2, vals, ti, ta)
    g_x, g_y = _region_gradient(gray, gx, gy, tmpl, cx, cy, s, c1, c2, vals, s0, mi, mj, vi, vj, cij, gi, ga)
    it = 0
    while it < max_iter:
        if abs(s0) < 1e-6 or (g_x == 0.0 and g_y == 0.0):
            break
        ang = math.atan2(g_y, g_x)
        sector = int(math.floor(ang / (math.pi / 4.0) + 0.5))
        dx = round(math.cos(sector * math.pi / 4.0))
        dy = round(math.sin(sector * math.pi / 4.0))
        nx = cx + dx
        ny = cy + dy
        s1, mi, mj, vi, vj, cij = _region_value(gray, tmpl, nx, ny, s, c1, c2, vals, ti, ta)
        it += 1
        if s1 < s0:
            break
        if s1 == s0 and it > 1:  # a plateau: stop rather than wander
            cx, cy = nx, ny
            break
        g_x, g_y = _region_gradient(gray, gx, gy, tmpl, nx, ny, s, c1, c2, vals, s1, mi, mj, vi, vj, cij, gi, ga)
        cx, cy, s0 = nx, ny, s1
    return cx, cy, s0, it


def dssim_ascent(gray: np.ndarray, gx: np.ndarray | None, gy: np.ndarray | None, template: np.ndarray, center, *,
                 scale: float = 1.0, max_iter: int = 20, c1: float = C1,
                 c2: float = C2) -> tuple[float, float, float, int]:
    """DSSIM (Table 3) from ``center``: returns ``(cx, cy, S, iterations)`` (global SSIM, eq. 21).

    ``gx, gy`` are the image's gradient images; with ``None`` the gradient at each sampled point is the
    central difference of the bilinear image there, which avoids computing gradient images when the
    region is sampled sparsely (a large target compared at reduced resolution)."""
    if gx is None or gy is None:
        gx = gy = np.empty((0, 0), np.float32)
    cx, cy, s, it = _ascent(np.ascontiguousarray(gray, np.float32), np.ascontiguousarray(gx, np.float32),
                            np.ascontiguousarray(gy, np.float32), np.ascontiguousarray(template, np.float64),
                            float(center[0]), float(center[1]), float(scale), int(max_iter), float(c1), float(c2))
    return float(cx), float(cy), float(s), int(it)


def region_ssim(gray: np.ndarray, template: np.ndarray, center, *, scale: float = 1.0, c1: float = C1,
                c2: float = C2) -> float:
    """Global SSIM (21) of the region at ``center`` and ``scale`` with the template (bilinear samples)."""
    e = np.empty((0, 0), np.float32)
    s, _, _ = _region_ssim_grad(np.ascontiguousarray(gray, np.float32), e, e,
                                np.ascontiguousarray(template, np.float64), float(center[0]), float(center[1]),
                                float(scale), float(c1), float(c2), False)
    return float(s)


@njit
def _ascent_batch(gray, gx, gy, tmpl, states, max_iter, c1, c2, out):
    for k in range(states.shape[0]):
        cx, cy, s, it = _ascent(gray, gx, gy, tmpl, states[k, 0], states[k, 1], states[k, 2], max_iter, c1, c2)
        out[k, 0] = cx
        out[k, 1] = cy
        out[k, 2] = s
        out[k, 3] = it


def dssim_ascent_batch(gray: np.ndarray, gx: np.ndarray, gy: np.ndarray, template: np.ndarray, states: np.ndarray, *,
                       max_iter: int = 10, c1: float = C1, c2: float = C2) -> np.ndarray:
    """DSSIM from every state ``(cx, cy, s, ...)`` (position only): ``(N, 4)`` rows ``cx, cy, S, iterations``."""
    st = np.ascontiguousarray(np.asarray(states, dtype=np.float64)[:, :3])
    out = np.empty((st.shape[0], 4))
    _ascent_batch(np.ascontiguousarray(gray, np.float32), np.ascontiguousarray(gx, np.float32),
                  np.ascontiguousarray(gy, np.float32), np.ascontiguousarray(template, np.float64), st, int(max_iter),
                  float(c1), float(c2), out)
    return out


def image_gradients(gray: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Central-difference intensity gradients ``(dI/dx, dI/dy)`` of a grey float image (ch02.md §2)."""
    gx = cv2.Sobel(gray, cv2.CV_32F, 1, 0, ksize=1, scale=0.5, borderType=cv2.BORDER_REPLICATE)
    gy = cv2.Sobel(gray, cv2.CV_32F, 0, 1, ksize=1, scale=0.5, borderType=cv2.BORDER_REPLICATE)
    return gx, gy
