"""The densitometric measurement of book ch. 14 along a line: pure functions (``shared/book/ch14.md`` §1.1, §2).

* The line is translated with the tracked segment, its slope kept (``line_n = line_nr + (k[n], l[n])``,
  L12240): :func:`translate_line`.
* The brightness profile ``Da(x)`` along it, averaged over ``width`` parallel lines:
  :func:`profile_along` (bilinear sampling, one sample per pixel of length).
* The background ``Db(x)``, a straight line through two interpolation nodes (Fig. 3a):
  :func:`background_line`, methods I (the end pixels), II (the means of the 3 outermost pixels at
  each end) and III (least squares through the pixels outside the vessel) — ch14.md §2 proposes them.
* The vessel's inner edges ``d1, d2`` at half the maximum of ``-ln(Da/Db)`` around its peak:
  :func:`vessel_edges`.
* Eq. (1), restored from the chapter's Appendix A: ``A(t) = -sum_{x=d1}^{d2} ln(Da(x,t) / Db(x,t))``,
  proportional to the amount of contrast under the line: :func:`densitometric_area`.  Vessels filled
  with contrast are darker than the background on positive images, so ``A > 0``.
"""

from __future__ import annotations

import math

import cv2
import numpy as np


def line_points(p1, p2) -> np.ndarray:
    """Sample points along the segment, one per pixel of length (inclusive ends): ``(L, 2)`` as ``x, y``."""
    p1, p2 = np.asarray(p1, dtype=np.float64), np.asarray(p2, dtype=np.float64)
    n = max(2, int(math.ceil(float(np.hypot(*(p2 - p1))))) + 1)
    t = np.linspace(0.0, 1.0, n)[:, None]
    return p1[None] + t * (p2 - p1)[None]


def translate_line(line, offset) -> np.ndarray:
    """The line ``(x1, y1, x2, y2)`` moved by ``offset = (dx, dy)``; the slope is kept (L12240)."""
    x1, y1, x2, y2 = (float(v) for v in line)
    dx, dy = (float(v) for v in offset)
    return np.array([x1 + dx, y1 + dy, x2 + dx, y2 + dy])


def profile_along(gray: np.ndarray, line, *, width: int = 1) -> np.ndarray:
    """Grey levels ``Da(x)`` along ``line`` (pixel-index coordinates), averaged over ``width`` parallel lines."""
    x1, y1, x2, y2 = (float(v) for v in line)
    pts = line_points((x1, y1), (x2, y2))
    d = np.array([x2 - x1, y2 - y1])
    nrm = np.array([-d[1], d[0]]) / max(float(np.hypot(*d)), 1e-9)
    offs = np.arange(width, dtype=np.float64) - (width - 1) / 2.0
    xs = (pts[None, :, 0] + offs[:, None] * nrm[0]).astype(np.float32)
    ys = (pts[None, :, 1] + offs[:, None] * nrm[1]).astype(np.float32)
    src = np.asarray(gray, dtype=np.float32)
    vals = cv2.remap(src, xs, ys, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return vals.mean(axis=0).astype(np.float64)


def background_line(profile: np.ndarray, *, method: str = "II", edges: tuple[int, int] | None = None) -> np.ndarray:
    """The background ``Db(x)``: a straight line under the vessel (ch14.md §2 methods I, II, III).

    III needs the vessel's ``edges`` (from a first pass with II); it fits the pixels outside them.
    """
    p = np.asarray(profile, dtype=np.float64)
    n = p.size
    x = np.arange(n, dtype=np.float64)
    if method == "I":
        a, b = p[0], p[-1]
        return a + (b - a) * x / max(n - 1, 1)
    if method == "II":
        k = min(3, max(1, n // 4))
        xa, xb = (k - 1) / 2.0, n - 1 - (k - 1) / 2.0
        a, b = p[:k].mean(), p[-k:].mean()
        return a + (b - a) * (x - xa) / max(xb - xa, 1e-9)
    if method == "III":
        if edges is None:
            edges = vessel_edges(p, background_line(p, method="II"))
        d1, d2 = edges
        out = np.ones(n, dtype=bool)
        out[d1:d2 + 1] = False
        if out.sum() < 2:
            return background_line(p, method="II")
        slope, icpt = np.polyfit(x[out], p[out], 1)
        return icpt + slope * x
    raise ValueError(f"unknown background method {method!r}; choose I, II or III")


def _attenuation(profile, background) -> np.ndarray:
    da = np.clip(np.asarray(profile, dtype=np.float64), 1.0, None)
    db = np.clip(np.asarray(background, dtype=np.float64), 1.0, None)
    return -np.log(da / db)


def vessel_edges(profile: np.ndarray, background: np.ndarray) -> tuple[int, int]:
    """Inner edges ``d1 <= d2``: where ``-ln(Da/Db)`` falls below half its maximum on each side of the peak."""
    a = _attenuation(profile, background)
    k = int(np.argmax(a))
    half = 0.5 * a[k]
    if half <= 0:
        return k, k
    d1 = k
    while d1 > 0 and a[d1 - 1] >= half:
        d1 -= 1
    d2 = k
    while d2 < a.size - 1 and a[d2 + 1] >= half:
        d2 += 1
    return d1, d2


def densitometric_area(profile: np.ndarray, background: np.ndarray, d1: int, d2: int) -> float:
    """Eq. (1): ``A = -sum_{x=d1}^{d2} ln(Da(x) / Db(x))`` (levels clipped at 1 so the log is finite)."""
    return float(_attenuation(profile, background)[d1:d2 + 1].sum())
