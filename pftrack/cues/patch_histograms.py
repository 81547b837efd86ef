"""Histogram cues on resampled patches, for comparing cues inside one particle filter (book ch. 2, Table 5).

The chapter runs colour (Nummiaro et al.), edge (Brasnett et al.) and colour & edge
cues "in the same PF framework with identical initialisation and common parameters"
as SSIM.  Here every cue reads the same ``(N, h, w)`` patches that SSIM reads
(:func:`pftrack.cues.ssim.sample_patches`), so only the cue differs:

* **colour**: kernel-weighted RGB 8x8x8 histogram over the patch (Nummiaro's
  ``k(r) = 1 - r^2`` on the inscribed ellipse);
* **edges**: a magnitude-weighted histogram of Sobel gradient orientations in
  ``[0, pi)`` (8 bins), ignoring pixels below 10 % of the patch's strongest gradient
  (ch02.md §2, proposed — the chapter does not specify Brasnett's cue);
* distance (30): ``D = sqrt(1 - sum_i sqrt(h_ref,i h_k,i))``, then likelihood (29).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .quantize import make_lut


def ellipse_kernel(shape: tuple[int, int]) -> np.ndarray:
    """``k(r) = 1 - r^2`` inside the ellipse inscribed in a ``(h, w)`` patch, 0 outside."""
    h, w = shape
    v = (np.arange(h) - (h - 1) / 2.0) / (h / 2.0)
    u = (np.arange(w) - (w - 1) / 2.0) / (w / 2.0)
    r2 = v[:, None] ** 2 + u[None, :] ** 2
    return np.clip(1.0 - r2, 0.0, None)


def color_histograms(patches: np.ndarray, *, bins: tuple[int, int, int] = (8, 8, 8)) -> np.ndarray:
    """Kernel-weighted RGB histograms of ``(N, h, w, 3)`` BGR patches: ``(N, prod(bins))``, rows sum to 1."""
    n, h, w = patches.shape[:3]
    lut = make_lut("rgb", bins).astype(np.int64)
    q = np.clip(np.rint(patches), 0, 255).astype(np.intp)
    idx = lut[0][q[..., 0]] + lut[1][q[..., 1]] + lut[2][q[..., 2]]  # (N, h, w)
    nb = int(np.prod(bins))
    k = np.broadcast_to(ellipse_kernel((h, w)), (n, h, w))
    flat = (idx + nb * np.arange(n)[:, None, None]).ravel()
    hist = np.bincount(flat, weights=k.ravel(), minlength=n * nb).reshape(n, nb)
    tot = hist.sum(axis=1, keepdims=True)
    return hist / np.where(tot > 0, tot, 1.0)


def edge_histograms(gray_patches: np.ndarray, *, n_bins: int = 8, min_fraction: float = 0.1) -> np.ndarray:
    """Magnitude-weighted gradient-orientation histograms of ``(N, h, w)`` grey patches: ``(N, n_bins)``."""
    p = np.asarray(gray_patches, dtype=np.float32)
    n, h, w = p.shape
    stack = np.ascontiguousarray(p.transpose(1, 2, 0))
    gx = np.empty_like(stack)
    gy = np.empty_like(stack)
    for a in range(0, n, 512):  # OpenCV filters up to 512 channels at once
        sl = np.ascontiguousarray(stack[..., a:a + 512])
        gx[..., a:a + 512] = cv2.Sobel(sl, cv2.CV_32F, 1, 0, ksize=3, borderType=cv2.BORDER_REPLICATE).reshape(
            sl.shape)
        gy[..., a:a + 512] = cv2.Sobel(sl, cv2.CV_32F, 0, 1, ksize=3, borderType=cv2.BORDER_REPLICATE).reshape(
            sl.shape)
    mag = np.sqrt(gx * gx + gy * gy).transpose(2, 0, 1)
    ang = np.arctan2(gy, gx).transpose(2, 0, 1) % math.pi
    b = np.minimum((ang * (n_bins / math.pi)).astype(np.intp), n_bins - 1)
    peak = mag.reshape(n, -1).max(axis=1)
    wgt = np.where(mag >= min_fraction * peak[:, None, None], mag, 0.0)
    flat = (b + n_bins * np.arange(n)[:, None, None]).ravel()
    hist = np.bincount(flat, weights=wgt.ravel(), minlength=n * n_bins).reshape(n, n_bins)
    tot = hist.sum(axis=1, keepdims=True)
    return hist / np.where(tot > 0, tot, 1.0)


def bhattacharyya_distance(hists: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Eq. (30): ``D = sqrt(1 - sum_i sqrt(h_ref,i h_k,i))`` for each row of ``hists``."""
    rho = np.sqrt(np.asarray(hists) * np.asarray(ref)[None, :]).sum(axis=1)
    return np.sqrt(np.clip(1.0 - rho, 0.0, None))
