"""The pure maths of the trackerless tripwire (book ch. 10, Eqs. 4–7), arrays in, arrays out."""

from __future__ import annotations

import math
from functools import lru_cache

import cv2
import numpy as np

from ..geometry import parabola_peak

__all__ = ["bhattacharyya_distance", "colour_bins", "patch_similarity", "ssd_motion"]


def colour_bins(bgr: np.ndarray, bits: int = 3) -> np.ndarray:
    """Bin index of every pixel in an RGB histogram with ``2**bits`` levels per channel (512 for 3 bits)."""
    shift = 8 - bits
    q = (bgr >> shift).astype(np.int32)
    return (q[..., 2] << (2 * bits)) | (q[..., 1] << bits) | q[..., 0]


def bhattacharyya_distance(h: np.ndarray, H: np.ndarray) -> np.ndarray:
    """``D_B = √(1 − Σ√(h·H))`` of one normalised histogram ``h`` against each row of ``H``.

    The text writes D as the Bhattacharyya *coefficient* (L9219–9225); as a distance it must
    be ``√(1 − BC)`` (Comaniciu et al. 2003; ch10.md P1).
    """
    bc = np.sqrt(np.asarray(H, dtype=np.float64)) @ np.sqrt(np.asarray(h, dtype=np.float64))
    return np.sqrt(np.clip(1.0 - bc, 0.0, 1.0))


def patch_similarity(h_o: np.ndarray, v_o: np.ndarray, H: np.ndarray, V: np.ndarray, *, alpha_c: float,
                     alpha_m: float, colour: str = "db") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eqs. 5–7 for one new appearance ``(h_o, v_o)`` against history entries ``(H, V)``.

    ``S_m`` is the cosine of the two motion vectors (Eq. 5; 0 when either is zero), ``S_c`` is
    ``1 − D_B`` where ``S_m > 0`` and 0 elsewhere (Eq. 6; ``colour="bc"`` uses the coefficient
    itself, the other reading of P1), and ``S = α_c S_c + α_m S_m`` (the argument of the max of
    Eq. 7).  Returns ``(S, S_c, S_m)`` per entry.
    """
    V = np.asarray(V, dtype=np.float64).reshape(-1, 2)
    v_o = np.asarray(v_o, dtype=np.float64)
    nv = np.hypot(V[:, 0], V[:, 1]) * np.hypot(*v_o)
    with np.errstate(invalid="ignore", divide="ignore"):
        s_m = np.where(nv > 1e-12, (V @ v_o) / nv, 0.0)
    if colour == "bc":
        sim = np.sqrt(np.asarray(H, dtype=np.float64)) @ np.sqrt(np.asarray(h_o, dtype=np.float64))
    else:
        sim = 1.0 - bhattacharyya_distance(h_o, H)
    s_c = np.where(s_m > 0, sim, 0.0)
    return alpha_c * s_c + alpha_m * s_m, s_c, s_m


@lru_cache(maxsize=8)
def _squared_offsets(search: int) -> np.ndarray:
    """``dx² + dy²`` over ``[-search, search]²`` (float32), centre at ``[search, search]``."""
    d = np.arange(-search, search + 1, dtype=np.float32) ** 2
    out = d[:, None] + d[None, :]
    out.flags.writeable = False
    return out


#: the block matching first searches this far (px); farther displacements are searched only when the prior allows a
#: better match there (see :func:`ssd_motion`)
NEAR_SEARCH = 16


def ssd_motion(prev: np.ndarray, cur: np.ndarray, centre, half: int, search: int,
               mask: np.ndarray | None = None, penalty: float = 0.0) -> tuple[np.ndarray, float]:
    """Motion of the ``(2·half+1)²`` square around ``centre`` from ``prev`` to ``cur`` by SSD block
    matching over ±``search`` px (``TM_SQDIFF``, parabolic sub-pixel refinement; ch10.md §1.3).

    ``penalty`` λ adds ``λ |d|²`` per matched pixel to the cost of a displacement ``d`` (grey levels²
    per px²): a prior for small motions, as video coders bias their block search towards the zero
    vector. A larger displacement then wins only where it matches clearly better; a patch of a
    uniformly dark coat otherwise finds its best match on some other dark patch far away.

    With ``mask`` (the foreground of ``cur``, full image size) the square of ``cur`` is matched
    back into ``prev`` on its foreground pixels only: an object that has just entered a patch
    is mostly background there, and unmasked SSD would report the background's zero motion.
    Returns ``(v, ssd_per_pixel)`` (the SSD without the prior); ``v`` is ``(0, 0)`` with infinite cost when
    the square does not fit.

    With the prior, the search runs first over ±``NEAR_SEARCH`` px. A displacement ``d`` costs at least
    ``λ n |d|²`` (``n`` matched pixels), so none beyond ``√(C / (λ n))`` can beat the best cost ``C`` found there; the
    search is widened to that radius (at most ``search``) only when it reaches past the first window's inner edge.
    The best displacement and its neighbours (for the sub-pixel step) are those of the whole window; OpenCV's
    correlation rounds differently over the smaller window, which moves the sub-pixel step by up to about 0.002 px.
    """
    full = search  # the prior's table is the full range's, sliced for any window (one cached table per range)
    if penalty > 0 and search > NEAR_SEARCH:
        v, ssd, cost, n_pix = _ssd_search(prev, cur, centre, half, NEAR_SEARCH, mask, penalty, full)
        reach = math.sqrt(cost / (penalty * n_pix)) if math.isfinite(cost) else math.inf
        if reach < NEAR_SEARCH - 1 or not math.isfinite(ssd):
            return v, ssd
        search = min(search, int(math.ceil(reach)) + 2)
    v, ssd, _, _ = _ssd_search(prev, cur, centre, half, search, mask, penalty, full)
    return v, ssd


def _ssd_search(prev, cur, centre, half, search, mask, penalty, table):
    """:func:`ssd_motion` over ±``search`` px (``table`` >= ``search``: the range of the prior's offsets table):
    ``(v, ssd per pixel, best cost with the prior, matched pixels)``."""
    h, w = prev.shape[:2]
    cx, cy = (int(round(float(c))) for c in centre)
    x0, y0, x1, y1 = cx - half, cy - half, cx + half + 1, cy + half + 1
    sx0, sy0 = max(0, x0 - search), max(0, y0 - search)
    sx1, sy1 = min(w, x1 + search), min(h, y1 + search)
    if x0 < 0 or y0 < 0 or x1 > w or y1 > h or sx1 - sx0 < x1 - x0 or sy1 - sy0 < y1 - y0:
        return np.zeros(2), float("inf"), float("inf"), 1.0
    m = None
    if mask is not None:
        m = mask[y0:y1, x0:x1].astype(np.float32)
        if m.sum() < 0.2 * m.size:
            m = None
    if m is None:
        tmpl, area, sign = prev[y0:y1, x0:x1].astype(np.float32), cur[sy0:sy1, sx0:sx1].astype(np.float32), 1.0
        cost = cv2.matchTemplate(area, tmpl, cv2.TM_SQDIFF)
        n_pix = tmpl.size
    else:  # match the current foreground back into the previous frame
        tmpl, area, sign = cur[y0:y1, x0:x1].astype(np.float32), prev[sy0:sy1, sx0:sx1].astype(np.float32), -1.0
        cost = cv2.matchTemplate(area, tmpl, cv2.TM_SQDIFF, mask=m)
        n_pix = float(m.sum())
    ssd = cost
    if penalty > 0:  # the prior for small motions: lambda |d|^2 per matched pixel
        oy, ox = y0 - sy0, x0 - sx0  # where the zero motion lies in the cost map
        sq = _squared_offsets(table)[table - oy:table - oy + cost.shape[0], table - ox:table - ox + cost.shape[1]]
        cost = cost + np.float32(penalty * n_pix) * sq
    _, _, (bx, by), _ = cv2.minMaxLoc(cost)
    exact = ssd[by, bx] <= 1e-6 * n_pix
    dx = (parabola_peak(-cost[by, bx - 1], -cost[by, bx], -cost[by, bx + 1])
          if 0 < bx < cost.shape[1] - 1 and not exact else 0.0)
    dy = (parabola_peak(-cost[by - 1, bx], -cost[by, bx], -cost[by + 1, bx])
          if 0 < by < cost.shape[0] - 1 and not exact else 0.0)
    v = sign * np.array([sx0 + bx + dx - x0, sy0 + by + dy - y0])
    return v, float(ssd[by, bx]) / n_pix, float(cost[by, bx]), float(n_pix)
