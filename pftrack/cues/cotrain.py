"""Co-trained confidence maps (book ch. 3, §3.2–3.3, Algorithm 2).

Two online real-AdaBoost classifiers (:class:`~.boosting.OnlineRealBoost`), one on the colour
group and one on the texture group of :func:`~.boosting.pixel_features`, score every pixel of
the candidate region.  Each map is opened (grey-level opening), and the two are fused by
vote (restored with ``|·|``, ch03.md §1.3): ``h = sign(min(conf_c, conf_t))`` and
``conf = max(|conf_c|, |conf_t|)·h`` — a pixel is object only if both agree.  The most
confident blob of the fused map locates the object; its best pixels and the region's border
pixels retrain both classifiers.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .boosting import OnlineRealBoost, pixel_features

__all__ = ["Blob", "CoTrainer", "best_blob", "fuse"]


def fuse(conf_c: np.ndarray, conf_t: np.ndarray) -> np.ndarray:
    """The vote of ch03.md §1.3: positive only where both maps are positive."""
    h = np.sign(np.minimum(conf_c, conf_t))
    return np.maximum(np.abs(conf_c), np.abs(conf_t)) * h


@dataclass
class Blob:
    mask: np.ndarray      # (H, W) bool
    mass: float           # A(B) = sum of the fused confidence in the blob
    centre: np.ndarray    # (x, y)
    size: np.ndarray      # (w, h): sqrt(12)·sigma, the side of a uniform box with that spread


def best_blob(fused: np.ndarray) -> Blob | None:
    """The 8-connected positive blob with the largest accumulated confidence (§3.3), with its moments."""
    pos = (fused > 0).astype(np.uint8)
    n, lab = cv2.connectedComponents(pos, connectivity=8)
    if n <= 1:
        return None
    mass = np.bincount(lab.ravel(), weights=np.maximum(fused, 0).ravel(), minlength=n)
    mass[0] = -1.0
    k = int(np.argmax(mass))
    mask = lab == k
    ys, xs = np.nonzero(mask)
    wts = fused[mask]
    cx, cy = np.average(xs, weights=wts), np.average(ys, weights=wts)
    sx = np.sqrt(max(np.average((xs - cx) ** 2, weights=wts), 0.25))
    sy = np.sqrt(max(np.average((ys - cy) ** 2, weights=wts), 0.25))
    return Blob(mask, float(mass[k]), np.array([cx, cy]), np.sqrt(12.0) * np.array([sx, sy]))


class CoTrainer:
    """The two classifiers and their training from labelled pixels of a region."""

    def __init__(self, *, n_selectors: int = 30, colour_blocks: int = 32, ltp_t: float = 5.0,
                 error_weighting: str = "confidence", rng: np.random.Generator | None = None):
        self.colour = OnlineRealBoost(4, colour_blocks, n_selectors=n_selectors, error_weighting=error_weighting)
        self.texture = OnlineRealBoost(9, 100, n_selectors=n_selectors, error_weighting=error_weighting)
        self.blocks, self.t = colour_blocks, ltp_t
        self.rng = rng or np.random.default_rng(0)

    def features(self, bgr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return pixel_features(bgr, t=self.t, colour_blocks=self.blocks)

    def maps(self, feats, *, opening: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Opened colour and texture confidence maps and their fusion."""
        col, tex = feats
        k = np.ones((opening, opening), np.uint8)
        conf_c = cv2.morphologyEx(self.colour.confidence(col).astype(np.float32), cv2.MORPH_OPEN, k)
        conf_t = cv2.morphologyEx(self.texture.confidence(tex).astype(np.float32), cv2.MORPH_OPEN, k)
        return conf_c, conf_t, fuse(conf_c, conf_t)

    def learn(self, feats, pos: np.ndarray, neg: np.ndarray, *, max_each: int = 200,
              pos_texture: np.ndarray | None = None) -> int:
        """Train both classifiers on positive and negative pixel masks (each in a random interleaved order).

        ``pos_texture`` gives the texture classifier its own positives (co-training across views, where
        each classifier is taught by the other's most confident pixels); by default both get ``pos``."""
        n = self._learn_one(self.colour, feats[0], pos, neg, max_each)
        return n + self._learn_one(self.texture, feats[1], pos if pos_texture is None else pos_texture, neg,
                                   max_each)

    def _learn_one(self, clf: OnlineRealBoost, feat: np.ndarray, pos: np.ndarray, neg: np.ndarray,
                   max_each: int) -> int:
        py, px = np.nonzero(pos)
        ny, nx = np.nonzero(neg)
        if len(py) > max_each:
            k = self.rng.choice(len(py), max_each, replace=False)
            py, px = py[k], px[k]
        if len(ny) > max_each:
            k = self.rng.choice(len(ny), max_each, replace=False)
            ny, nx = ny[k], nx[k]
        ys, xs = np.concatenate([py, ny]), np.concatenate([px, nx])
        lab = np.concatenate([np.ones(len(py)), -np.ones(len(ny))])
        order = self.rng.permutation(len(lab))
        clf.update(feat[ys[order], xs[order]], lab[order])
        return len(lab)
