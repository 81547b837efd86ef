"""Appearance of a person patch for matching across cameras (book ch. 11, Sect. 4 and 6).

Four extractions (ch11.md §1.5), each a set of disjoint regions of the box whose RGB
histograms (256 bins per channel) are concatenated:

* ``whole`` — the whole box;
* ``ellipse1`` — one ellipse cutting off head and feet (centre (0.5w, 0.55h), semi-axes
  (0.45w, 0.38h); proposed, the text gives no numbers);
* ``ellipse2`` — torso (0.5w, 0.37h; 0.42w, 0.19h) and legs (0.5w, 0.74h; 0.35w, 0.18h);
* ``positional`` — circular sectors about the box centre (Eq. 19): ``n_rings`` rings of
  width D/(2 n_rings) (D the box diagonal) × ``n_sectors`` sectors, half-open bins so every
  pixel of the box belongs to exactly one region (Eqs. 14–15).

Only foreground pixels count when a mask is given.  The concatenated histogram is
normalised per channel; similarity is ``1 − D_B`` per channel (Eqs. 23–24), averaged over
the three channels (L10204–10206).
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["FEATURES", "box_regions", "region_histograms", "region_labels", "rgb_patch", "similarity",
           "similarity_matrix"]

FEATURES = ("whole", "ellipse1", "ellipse2", "positional")


def region_labels(h: int, w: int, feature: str, *, n_rings: int = 2, n_sectors: int = 4,
                  theta0: float = 0.0) -> tuple[np.ndarray, int]:
    """``(h, w)`` integer map of region indices (−1 outside every region) and the number of regions."""
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    xx, yy = xx + 0.5, yy + 0.5
    lab = np.full((h, w), -1, dtype=np.int32)
    if feature == "whole":
        lab[:] = 0
        return lab, 1

    def ellipse(cx, cy, ax, ay):
        return ((xx - cx * w) / (ax * w)) ** 2 + ((yy - cy * h) / (ay * h)) ** 2 <= 1.0

    if feature == "ellipse1":
        lab[ellipse(0.5, 0.55, 0.45, 0.38)] = 0
        return lab, 1
    if feature == "ellipse2":
        lab[ellipse(0.5, 0.74, 0.35, 0.18)] = 1
        lab[ellipse(0.5, 0.37, 0.42, 0.19)] = 0
        return lab, 2
    if feature == "positional":
        dx, dy = xx - w / 2.0, yy - h / 2.0
        r = np.hypot(dx, dy)
        half_diag = np.hypot(w, h) / 2.0
        ring = np.minimum((r / half_diag * n_rings).astype(np.int32), n_rings - 1)
        ang = (np.arctan2(dy, dx) - theta0) % (2 * np.pi)
        sector = np.minimum((ang / (2 * np.pi) * n_sectors).astype(np.int32), n_sectors - 1)
        return ring * n_sectors + sector, n_rings * n_sectors
    raise ValueError(f"feature must be one of {', '.join(FEATURES)}")


def box_regions(frame: np.ndarray, box, feature: str, *, fg: np.ndarray | None = None,
                **kw) -> tuple[np.ndarray, np.ndarray, int]:
    """``(patch, labels, regions)``: the box's pixels (cut to the frame), their region map (:func:`region_labels`;
    −1 outside every region, and for background pixels when ``fg`` is given) and the number of regions."""
    H, W = frame.shape[:2]
    x, y, w, h = (float(v) for v in box)
    x0, y0 = max(0, int(round(x))), max(0, int(round(y)))
    x1, y1 = min(W, int(round(x + w))), min(H, int(round(y + h)))
    patch = frame[y0:y1, x0:x1]
    lab, n = region_labels(patch.shape[0], patch.shape[1], feature, **kw)
    if fg is not None:
        lab = np.where(fg[y0:y1, x0:x1] > 0, lab, -1)
    return patch, lab, n


def rgb_patch(patch: np.ndarray) -> np.ndarray:
    """A BGR patch's pixels in RGB order (the histograms' channels); an empty patch (a box beyond the frame) stays
    empty."""
    return cv2.cvtColor(patch, cv2.COLOR_BGR2RGB) if patch.size else patch[..., ::-1]


def region_histograms(frame: np.ndarray, box, feature: str, *, fg: np.ndarray | None = None, raw: bool = False,
                      parts: tuple[np.ndarray, np.ndarray, int] | None = None, rgb: np.ndarray | None = None,
                      **kw) -> np.ndarray:
    """``(regions, 3, 256)`` RGB histograms of the box's regions (foreground pixels only when ``fg``
    is given); normalised per channel over all regions unless ``raw`` (pixel counts, for CBTF). ``parts``: the
    box's :func:`box_regions` of these arguments, when already computed; ``rgb``: its patch in RGB (:func:`rgb_patch`),
    when already converted."""
    patch, lab, n = parts if parts is not None else box_regions(frame, box, feature, fg=fg, **kw)
    ok = lab >= 0
    out = np.zeros((n, 3, 256))
    if ok.any():
        rgb = (rgb_patch(patch) if rgb is None else rgb)[ok].astype(np.int64)
        reg = lab[ok].astype(np.int64)
        for c in range(3):
            out[:, c, :] = np.bincount(reg * 256 + rgb[:, c], minlength=n * 256).reshape(n, 256)
    if raw:
        return out
    tot = out.sum(axis=(0, 2), keepdims=True)
    return out / np.maximum(tot, 1e-12)


def similarity(a: np.ndarray, b: np.ndarray) -> float:
    """Eqs. 23–24: mean over channels of ``1 − √(1 − Σ √(a·b))`` of two ``(regions, 3, 256)`` histograms."""
    return float(similarity_matrix(a[None], b[None])[0, 0])


def similarity_matrix(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``(len(A), len(B))`` similarities of two stacks of ``(regions, 3, 256)`` histograms."""
    sa = np.sqrt(np.asarray(A, dtype=np.float64)).transpose(2, 0, 1, 3).reshape(3, len(A), -1)
    sb = np.sqrt(np.asarray(B, dtype=np.float64)).transpose(2, 0, 1, 3).reshape(3, len(B), -1)
    bc = np.einsum("cik,cjk->cij", sa, sb)
    return np.mean(1.0 - np.sqrt(np.clip(1.0 - bc, 0.0, 1.0)), axis=0)
