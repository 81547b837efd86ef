"""MPEG-7 motion activity from compressed-domain motion vectors (book ch. 8, Section 2.2): the intensity level of
Table 1 from the spread of the motion vectors' magnitudes (Eqs. 18-19), each partition weighted by its size and
shape as ch08.md §1.10 restores Eq. 15.  Used by ``pftrack compressed`` and ``pftrack mot --detector mv``'s
activity log."""

from __future__ import annotations

import numpy as np

__all__ = ["THRESHOLDS", "intensity_level", "motion_sigma", "partition_weights"]

THRESHOLDS = (3.9, 10.7, 17.1, 32.0)


def intensity_level(sigma) -> np.ndarray:
    """Table 1: level 1-5 from the standard deviation of motion-vector magnitudes."""
    return 1 + np.digitize(np.asarray(sigma, float), THRESHOLDS)


def partition_weights(w: np.ndarray, h: np.ndarray, order: np.ndarray, n_mb: int, kappa: float = 4.0,
                      penalty: bool = True) -> np.ndarray:
    """Eq. (15) as ch08.md §1.10 restores it: ``w_i = M_i exp(-kappa r_i PB_n(i) / N_MB)``,
    ``M = (256/(m n))^s`` (s = 1 square, 1/2 otherwise), ``r = max/min``, ``PB_n(i)`` the number of partitions
    of i's class met so far in raster order ``order``."""
    w = np.asarray(w, float)
    h = np.asarray(h, float)
    s = np.where(w == h, 1.0, 0.5)
    M = (256.0 / (w * h)) ** s
    if not penalty:
        return M
    r = np.maximum(w, h) / np.minimum(w, h)
    cls = (w * 100 + h).astype(np.int64)
    pb = np.empty(len(w))
    counts: dict[int, int] = {}
    for i in order:
        counts[cls[i]] = counts.get(cls[i], 0) + 1
        pb[i] = counts[cls[i]]
    return M * np.exp(-kappa * r * pb / max(n_mb, 1))


def motion_sigma(mvs, frame_width: int, frame_height: int, *, weighted: bool = False, penalty: bool = True,
                 kappa: float = 4.0, mv_scale: float | None = None) -> float:
    """Eqs. (18)-(19): the population standard deviation of ``x_i = w_i |mv_i|`` over the frame's partitions,
    magnitudes in pixels scaled by ``352/W`` (the SIF reference width) unless ``mv_scale`` is given."""
    if mvs is None or len(mvs) == 0:
        return 0.0
    m = mvs[mvs["source"] < 0] if "source" in mvs.dtype.names else mvs
    if len(m) == 0:
        return 0.0
    scale = (352.0 / frame_width) if mv_scale is None else mv_scale
    mag = np.hypot(m["motion_x"], m["motion_y"]).astype(float) / np.maximum(m["motion_scale"], 1) * scale
    if weighted:
        order = np.lexsort((m["dst_x"], m["dst_y"]))
        n_mb = ((frame_width + 15) // 16) * ((frame_height + 15) // 16)
        mag = mag * partition_weights(m["w"], m["h"], order, n_mb, kappa, penalty)
    return float(np.std(mag))
