"""Separate hue, saturation and value histograms of boxes, by integral histograms (Tung & Matsuyama §4.2).

The colour model of a region is three histograms of ``N_h = N_s = N_v = 10`` bins
(Eq. 5: plain counts inside the region, normalised).  To score every particle's
box each frame, the region the particles can reach is converted to HSV and its
bin maps turned into one integral image per (channel, bin) once per frame; the
histograms of any box then cost ``4 x 30`` lookups.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .._numba import njit, numba_enabled
from ..frames import bgr_view


@njit
def _integral_counts_numba(maps, n_bins, out):
    # maps: (3, h, w) uint8 bin indices; out: (3, n_bins, h + 1, w + 1) int32
    c_n, h, w = maps.shape
    for c in range(c_n):
        for b in range(n_bins):
            for i in range(w + 1):
                out[c, b, 0, i] = 0
        for j in range(h):
            for b in range(n_bins):
                out[c, b, j + 1, 0] = 0
            for b in range(n_bins):
                row = 0
                for i in range(w):
                    if maps[c, j, i] == b:
                        row += 1
                    out[c, b, j + 1, i + 1] = out[c, b, j, i + 1] + row
    return out


def integral_counts(maps: np.ndarray, n_bins: int) -> np.ndarray:
    """``(3, n_bins, h + 1, w + 1)`` integral images of the one-hot bin maps."""
    c, h, w = maps.shape
    if numba_enabled():
        return _integral_counts_numba(maps, n_bins, np.empty((c, n_bins, h + 1, w + 1), np.int32))
    onehot = (maps[:, None, :, :] == np.arange(n_bins, dtype=maps.dtype)[None, :, None, None]).astype(np.int32)
    out = np.zeros((c, n_bins, h + 1, w + 1), np.int32)
    out[:, :, 1:, 1:] = onehot.cumsum(axis=2).cumsum(axis=3)
    return out


@dataclass
class HSVFeatures:
    integral: np.ndarray  # (3, n_bins, h + 1, w + 1)
    x0: int
    y0: int


class HSVHistogramCue:
    """Three ``n_bins``-bin histograms (H, S, V) of axis-aligned boxes."""

    def __init__(self, n_bins: int = 10):
        self.n_bins = int(n_bins)
        v = np.arange(256)
        self._lut_h = np.minimum(v * self.n_bins // 180, self.n_bins - 1).astype(np.uint8)
        self._lut_sv = (v * self.n_bins // 256).astype(np.uint8)

    def bin_maps(self, region: np.ndarray) -> np.ndarray:
        hsv = cv2.cvtColor(bgr_view(region), cv2.COLOR_BGR2HSV)
        return np.stack([self._lut_h[hsv[..., 0]], self._lut_sv[hsv[..., 1]], self._lut_sv[hsv[..., 2]]])

    def prepare(self, frame: np.ndarray, roi: tuple[int, int, int, int]) -> HSVFeatures:
        x0, y0, x1, y1 = roi
        region = frame[y0:y1, x0:x1]
        if region.size == 0:
            return HSVFeatures(np.zeros((3, self.n_bins, 1, 1), np.int32), x0, y0)
        return HSVFeatures(integral_counts(self.bin_maps(region), self.n_bins), x0, y0)

    def box_histograms(self, feats: HSVFeatures, boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Normalised ``(N, 3, n_bins)`` histograms of boxes ``(x, y, w, h)`` and their pixel counts."""
        b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
        ii = feats.integral
        h, w = ii.shape[2] - 1, ii.shape[3] - 1
        x0 = np.clip(np.rint(b[:, 0] - feats.x0).astype(np.int64), 0, w)
        y0 = np.clip(np.rint(b[:, 1] - feats.y0).astype(np.int64), 0, h)
        x1 = np.clip(np.rint(b[:, 0] + b[:, 2] - feats.x0).astype(np.int64), 0, w)
        y1 = np.clip(np.rint(b[:, 1] + b[:, 3] - feats.y0).astype(np.int64), 0, h)
        x1 = np.maximum(x1, x0)
        y1 = np.maximum(y1, y0)
        counts = (ii[:, :, y1, x1] - ii[:, :, y0, x1] - ii[:, :, y1, x0] + ii[:, :, y0, x0]).astype(np.float64)
        counts = np.moveaxis(counts, 2, 0)  # (N, 3, n_bins)
        n = (x1 - x0) * (y1 - y0)
        hist = counts / np.where(n > 0, n, 1)[:, None, None]
        return hist, n

    def histogram(self, frame: np.ndarray, box) -> np.ndarray:
        """``(3, n_bins)`` histogram of one box."""
        h, w = frame.shape[:2]
        x, y, bw, bh = (float(v) for v in box)
        roi = (max(int(np.floor(x)), 0), max(int(np.floor(y)), 0), min(int(np.ceil(x + bw)), w),
               min(int(np.ceil(y + bh)), h))
        feats = self.prepare(frame, roi)
        hist, _ = self.box_histograms(feats, np.array([[x, y, bw, bh]]))
        return hist[0]
