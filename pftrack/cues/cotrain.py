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

__all__ = ["Blob", "CoTrainer", "best_blob", "box_sums", "contrast_scores", "fuse", "integral",
           "train_pixels"]


def fuse(conf_c: np.ndarray, conf_t: np.ndarray) -> np.ndarray:
    """The vote of ch03.md §1.3: positive only where both maps are positive."""
    h = np.sign(np.minimum(conf_c, conf_t))
    return np.maximum(np.abs(conf_c), np.abs(conf_t)) * h


def integral(values: np.ndarray) -> np.ndarray:
    """``(H + 1, W + 1)`` float64 integral image of a map (for O(1) box sums)."""
    return cv2.integral(np.ascontiguousarray(values, dtype=np.float64))


def box_sums(ii: np.ndarray, boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sums and areas of the map over ``(P, 4)`` boxes ``(x, y, w, h)`` in map pixels.

    Box edges are rounded to the pixel grid and clipped to the map; a box outside the map has
    sum 0 and area 0."""
    hh, ww = ii.shape[0] - 1, ii.shape[1] - 1
    b = np.asarray(boxes, dtype=np.float64)
    x0 = np.clip(np.rint(b[:, 0]), 0, ww).astype(np.int64)
    y0 = np.clip(np.rint(b[:, 1]), 0, hh).astype(np.int64)
    x1 = np.clip(np.rint(b[:, 0] + b[:, 2]), 0, ww).astype(np.int64)
    y1 = np.clip(np.rint(b[:, 1] + b[:, 3]), 0, hh).astype(np.int64)
    x1, y1 = np.maximum(x1, x0), np.maximum(y1, y0)
    s = ii[y1, x1] - ii[y0, x1] - ii[y1, x0] + ii[y0, x0]
    return s, ((x1 - x0) * (y1 - y0)).astype(np.float64)


def _scaled_boxes(b: np.ndarray, k: float) -> np.ndarray:
    """The boxes scaled by ``k`` about their centres."""
    return np.column_stack([b[:, 0] + 0.5 * (1 - k) * b[:, 2], b[:, 1] + 0.5 * (1 - k) * b[:, 3],
                            k * b[:, 2], k * b[:, 3]])


def contrast_scores(ii: np.ndarray, boxes: np.ndarray, *, ring: float = 0.25,
                    inner: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Object contrast of each box on an object map in [0, 1] (its integral ``ii``).

    Returns ``(f_in − f_ring, f_in)``: the mean of the map over the box's centre (the box scaled
    by ``inner``) minus its mean over the ring around the box (the box enlarged by ``ring`` of
    its size on each side, minus the box).  The contrast is highest for a box whose centre is
    covered by object pixels and whose surroundings are free of them: it falls when the box
    slides off the object, when it is too large (background in its centre) and when it is too
    small (object pixels in the ring).  ``inner`` < 1 matches a map that, like one trained on
    the box's core, covers less than the whole box.  A ring clipped away by the map's border
    counts as empty."""
    b = np.asarray(boxes, dtype=np.float64)
    s_box, a_box = box_sums(ii, b)
    if inner == 1.0:
        s_in, a_in = s_box, a_box
    else:
        s_in, a_in = box_sums(ii, _scaled_boxes(b, inner))
    s_out, a_out = box_sums(ii, _scaled_boxes(b, 1.0 + 2.0 * ring))
    f_in = s_in / np.maximum(a_in, 1.0)
    f_ring = (s_out - s_box) / np.maximum(a_out - a_box, 1.0)
    return f_in - f_ring, f_in


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
                 error_weighting: str = "confidence", eps: float = 0.01, replace: str = "update",
                 forgetting: float = 1.0, rng: np.random.Generator | None = None):
        kw = {"n_selectors": n_selectors, "error_weighting": error_weighting, "eps": eps, "replace": replace,
              "forgetting": forgetting}
        self.colour = OnlineRealBoost(4, colour_blocks, **kw)
        self.texture = OnlineRealBoost(9, 100, **kw)
        self.blocks, self.t = colour_blocks, ltp_t
        #: per-view decision offsets (0 = the classifiers' own sign); see ``learn_view(calibrate=True)``
        self.bias = {"colour": 0.0, "texture": 0.0}
        self.rng = rng or np.random.default_rng(0)

    def features(self, bgr: np.ndarray, *, gray: bool = False, texture: str = "pairs") -> tuple[np.ndarray, np.ndarray]:
        return pixel_features(bgr, t=self.t, colour_blocks=self.blocks, gray=gray, texture=texture)

    def raw_maps(self, feats) -> tuple[np.ndarray, np.ndarray]:
        """Both views' confidences, re-centred by their offsets, before opening."""
        return (self.colour.confidence(feats[0]) - self.bias["colour"],
                self.texture.confidence(feats[1]) - self.bias["texture"])

    def maps(self, feats, *, opening: int = 3, anchor: CoTrainer | None = None,
             anchor_weight: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Opened colour and texture confidence maps and their fusion.

        With ``anchor`` (a frozen copy of the first frame's pair), each view's confidence is
        ``(1 − anchor_weight)·online + anchor_weight·anchor``: what was learned from the given box
        cannot drift away."""
        k = np.ones((opening, opening), np.uint8)
        conf_c, conf_t = self.raw_maps(feats)
        if anchor is not None and anchor_weight > 0:
            a_c, a_t = anchor.raw_maps(feats)
            conf_c = (1 - anchor_weight) * conf_c + anchor_weight * a_c
            conf_t = (1 - anchor_weight) * conf_t + anchor_weight * a_t
        conf_c = cv2.morphologyEx(conf_c.astype(np.float32), cv2.MORPH_OPEN, k)
        conf_t = cv2.morphologyEx(conf_t.astype(np.float32), cv2.MORPH_OPEN, k)
        return conf_c, conf_t, fuse(conf_c, conf_t)

    def learn(self, feats, pos: np.ndarray, neg: np.ndarray, *, max_each: int = 200,
              pos_texture: np.ndarray | None = None) -> int:
        """Train both classifiers on positive and negative pixel masks (each in a random interleaved order).

        ``pos_texture`` gives the texture classifier its own positives (co-training across views, where
        each classifier is taught by the other's most confident pixels); by default both get ``pos``."""
        n = self.learn_view("colour", feats, pos, neg, max_each=max_each)
        return n + self.learn_view("texture", feats, pos if pos_texture is None else pos_texture, neg,
                                   max_each=max_each)

    def learn_view(self, view: str, feats, pos: np.ndarray, neg: np.ndarray, *, max_each: int = 200,
                   balance: int | None = None, calibrate: bool = False) -> int:
        """Train one classifier (``"colour"`` or ``"texture"``) on at most ``max_each`` pixels of each mask.

        With ``balance``, at most ``max(number of positives, balance)`` negatives are drawn, so that a
        frame with few positives does not teach the classifier that everything is background."""
        clf, feat = (self.colour, feats[0]) if view == "colour" else (self.texture, feats[1])
        offset, n = train_pixels(clf, feat, pos, neg, self.rng, max_each=max_each, balance=balance)
        if calibrate and offset is not None:
            self.bias[view] = offset
        return n


def train_pixels(clf: OnlineRealBoost, feat: np.ndarray, pos: np.ndarray, neg: np.ndarray,
                 rng: np.random.Generator, *, max_each: int = 200,
                 balance: int | None = None) -> tuple[float | None, int]:
    """Teach ``clf`` at most ``max_each`` pixels of each mask (``feat`` is ``(H, W, M)`` block indices), in a
    random interleaved order; with ``balance``, at most ``max(number of positives, balance)`` negatives.

    Returns the calibrated decision offset — halfway between the median confidence of the positives and
    that of the negatives just learned (None when a class is empty) — and the number of samples."""
    py, px = np.nonzero(pos)
    ny, nx = np.nonzero(neg)
    if len(py) > max_each:
        k = rng.choice(len(py), max_each, replace=False)
        py, px = py[k], px[k]
    n_neg = max_each if balance is None else min(max_each, max(len(py), balance))
    if len(ny) > n_neg:
        k = rng.choice(len(ny), n_neg, replace=False)
        ny, nx = ny[k], nx[k]
    ys, xs = np.concatenate([py, ny]), np.concatenate([px, nx])
    lab = np.concatenate([np.ones(len(py)), -np.ones(len(ny))])
    order = rng.permutation(len(lab))
    x = feat[ys[order], xs[order]]
    clf.update(x, lab[order])
    if not (len(py) and len(ny)):
        return None, len(lab)
    conf = clf.confidence(x)
    is_pos = lab[order] > 0
    return 0.5 * (float(np.median(conf[is_pos])) + float(np.median(conf[~is_pos]))), len(lab)
