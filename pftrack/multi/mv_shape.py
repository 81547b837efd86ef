"""Object shapes for motion-vector groups from a pixel-domain background (our addition to book ch. 8).

The motion-vector groups of :mod:`pftrack.multi.compressed` say *where* something moves, but their
boxes are poor shapes (docs/compressed.md): FFmpeg exports 8x8 and 16x16 partitions, so a 30-px walker
spans two or three macroblocks and the box is about 1.3x too wide; legs carry no consistent vector at
low frame rates, so the box is too short; a frame difference marks the object twice.

``shape="background"`` keeps the groups as the motion-vector stage finds them and only redraws each
group's box from the pixels: a running-average background of the decoded luma at a reduced scale
(each pixel's first updates averaged, then a running average), updated selectively (not near moving
blocks), and the foreground pixels ``|Y - B| > tau`` near moving blocks, inside the group's widened
box, in components that touch the group's own blocks; one box per such silhouette, wide ones split
side by side.
This is the pixel-domain work of a background subtractor confined to the few regions where the stream
says something moves; it decodes nothing extra, since the luma is decoded anyway for the
pseudo-residual.

Pure functions (arrays in, arrays out) and one small stateful class, :class:`SilhouetteShaper`.
"""

from __future__ import annotations

import cv2
import numpy as np

from .._numba import njit, numba_enabled
from .detectors import split_wide

BLOCK = 4


def reduce_luma(y: np.ndarray, scale: int) -> np.ndarray:
    """The luma at 1/``scale`` resolution: the float32 means of its ``scale x scale`` blocks (a partial block
    at the right or bottom edge is dropped).  Compiled for uint8 input, OpenCV's area resize of the float
    image otherwise (the same means; exact for power-of-two scales)."""
    if scale == 1:
        return y.astype(np.float32)
    h, w = y.shape[:2]
    if numba_enabled() and y.dtype == np.uint8 and y.ndim == 2:
        return _grey_block_means(np.ascontiguousarray(y), int(scale), np.empty((h // scale, w // scale), np.float32))
    return cv2.resize(y[:h // scale * scale, :w // scale * scale].astype(np.float32), (w // scale, h // scale),
                      interpolation=cv2.INTER_AREA)


@njit(cache=True)
def _grey_block_means(y, k, out):
    oh, ow = out.shape
    acc = np.empty(ow * k, np.int32)
    inv = np.float32(1.0) / np.float32(k * k)
    for j in range(oh):
        r0 = j * k
        for t in range(ow * k):
            acc[t] = y[r0, t]
        for r in range(1, k):
            for t in range(ow * k):
                acc[t] += y[r0 + r, t]
        for i in range(ow):
            s = 0
            for q in range(k):
                s += acc[i * k + q]
            out[j, i] = np.float32(s) * inv
    return out


def foreground_pixels(y: np.ndarray, background: np.ndarray, tau: float) -> np.ndarray:
    """``|y - background| > tau`` as a uint8 0/1 mask (both at the same reduced scale)."""
    return (cv2.absdiff(y, background) > tau).astype(np.uint8)


def update_background(background: np.ndarray, count: np.ndarray, y: np.ndarray, keep: np.ndarray,
                      alpha: float) -> None:
    """In place, where ``keep`` is 0 (selective update: pixels of moving objects keep their background):
    ``B <- B + r (y - B)`` with ``r = max(alpha, 1 / n)`` and ``n`` the pixel's number of updates so far
    (``count``, incremented here).  Each pixel's background is the plain mean of its first 1/alpha
    updates, then a running average, as MOG2's history; a pixel covered by an object in the first frames
    forgets it after a few updates instead of 1/alpha frames."""
    upd = keep == 0
    count += upd
    rate = np.maximum(np.float32(alpha), 1.0 / np.maximum(count, 1.0)).astype(np.float32)
    background += (rate * upd) * (y - background)


def roi_of(box, margin: float, shape: tuple[int, int], scale: int) -> tuple[int, int, int, int]:
    """A box ``(x, y, w, h)`` in frame pixels, widened by ``margin`` times its larger side on every
    side, as integer bounds ``(x0, y0, x1, y1)`` at the reduced scale, clipped to ``shape``."""
    x, y, w, h = box
    m = margin * max(w, h)
    H, W = shape
    x0, y0 = max(0, int((x - m) // scale)), max(0, int((y - m) // scale))
    x1, y1 = min(W, int(np.ceil((x + w + m) / scale))), min(H, int(np.ceil((y + h + m) / scale)))
    return x0, y0, x1, y1


def silhouette_boxes(labels: np.ndarray, stats: np.ndarray, core: np.ndarray, scale: int, min_pixels: int = 4,
                     min_share: float = 0.3) -> list[tuple[float, float, float, float]]:
    """The frame-pixel boxes ``(x, y, w, h)`` of the foreground components that touch ``core`` (a group's
    own blocks at the reduced scale), largest first; empty when none touches it.

    ``labels`` and ``stats`` are OpenCV's connected components of the foreground inside the regions of
    interest (labelled once for all groups, so a silhouette touching two groups gives the same box to
    both).  A component counts when it has at least ``min_pixels`` pixels and ``min_share`` of the
    largest touching one's: two people walking side by side form one motion-vector group but, with a
    gap between them, two silhouettes."""
    touching = np.unique(labels[(core != 0) & (labels > 0)])
    if touching.size == 0:
        return []
    areas = stats[touching, cv2.CC_STAT_AREA]
    keep = touching[(areas >= min_pixels) & (areas >= min_share * areas.max())]
    keep = keep[np.argsort(-stats[keep, cv2.CC_STAT_AREA], kind="stable")]
    return [(float(stats[k, 0] * scale), float(stats[k, 1] * scale),
             float(stats[k, 2] * scale), float(stats[k, 3] * scale)) for k in keep]


def union_box(boxes) -> tuple[float, float, float, float]:
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    x0, y0 = b[:, 0].min(), b[:, 1].min()
    return (float(x0), float(y0), float((b[:, 0] + b[:, 2]).max() - x0), float((b[:, 1] + b[:, 3]).max() - y0))


def block_mask_at(mask: np.ndarray, scale: int, shape: tuple[int, int]) -> np.ndarray:
    """A 4x4-block mask ``(I, J)`` drawn at 1/``scale`` resolution, cut or zero-padded to ``shape``."""
    k = BLOCK // scale if BLOCK % scale == 0 else 0
    if k == 1 and mask.shape == tuple(shape):
        return mask.view(np.uint8) if mask.dtype == np.bool_ else mask.astype(np.uint8)
    if k >= 1:
        up = np.repeat(np.repeat(mask.astype(np.uint8), k, axis=0), k, axis=1)
    else:
        up = cv2.resize(mask.astype(np.uint8), (mask.shape[1] * BLOCK // scale, mask.shape[0] * BLOCK // scale),
                        interpolation=cv2.INTER_NEAREST)
    out = np.zeros(shape, np.uint8)
    h, w = min(shape[0], up.shape[0]), min(shape[1], up.shape[1])
    out[:h, :w] = up[:h, :w]
    return out


class SilhouetteShaper:
    """Redraws motion-vector group boxes from a selectively updated background (see the module doc).

    ``mask`` holds, after each call, the foreground pixels inside the regions of interest at
    1/``scale`` resolution (the particle filters' foreground cue).  The defaults are
    :class:`~pftrack.multi.compressed.CDParams`' ``bg_*`` values."""

    def __init__(self, scale: int = 4, alpha: float = 0.01, tau: float = 35.0, margin: float = 0.5,
                 close: int = 3, reach: int = 2, min_share: float = 0.3, split_aspect: float = 0.0):
        self.scale, self.alpha, self.tau, self.margin, self.close = int(scale), float(alpha), float(tau), \
            float(margin), int(close)
        self.reach, self.min_share, self.split_aspect = int(reach), float(min_share), float(split_aspect)
        self.background: np.ndarray | None = None
        self.mask: np.ndarray | None = None
        self.count: np.ndarray | None = None

    def __call__(self, y: np.ndarray, groups: list, moving: np.ndarray | None = None) -> list:
        self.foreground(y, moving)
        return self.shape(groups)

    def foreground(self, y: np.ndarray, moving: np.ndarray | None = None) -> np.ndarray | None:
        """This frame's foreground pixels at the reduced scale (uint8 0/1; near moving blocks when ``reach``),
        or None on the first frame, which only starts the background."""
        small = reduce_luma(y, self.scale)
        self._small = small
        if self.background is None:
            self.background = small.copy()
            self.count = np.ones(small.shape, np.float32)
            self.mask = np.zeros(small.shape, np.uint8)
            self._fg = None
            return None
        fg = foreground_pixels(small, self.background, self.tau)
        if self.close:
            fg = cv2.morphologyEx(fg, cv2.MORPH_CLOSE, np.ones((self.close, self.close), np.uint8))
        near = block_mask_at(moving, self.scale, small.shape) if moving is not None else None
        if self.reach and near is not None:
            k = 2 * self.reach * BLOCK // self.scale + 1
            near = cv2.dilate(near, np.ones((k, k), np.uint8))
            fg = fg & near
        self._near, self._fg = near, fg
        return fg

    def shape(self, groups: list) -> list:
        """Redraw the groups' boxes from the foreground of :meth:`foreground`, then learn the background."""
        if self._fg is None:
            return groups
        small, fg, near = self._small, self._fg, self._near
        rois = np.zeros(small.shape, np.uint8)
        for g in groups:
            x0, y0, x1, y1 = roi_of(g.box, self.margin, small.shape, self.scale)
            rois[y0:y1, x0:x1] = 1
        fg = fg * rois
        _, labels, stats, _ = cv2.connectedComponentsWithStats(fg, connectivity=8)
        for g in groups:
            parts = silhouette_boxes(labels, stats, block_mask_at(g.mask, self.scale, small.shape), self.scale,
                                     min_share=self.min_share)
            if parts:
                g.box = union_box(parts)
                g.parts = [b for part in parts for b in split_wide(part, self.split_aspect)]
        # pixels near moving blocks keep their background: an object's parts without vectors (legs) are not
        # learnt into it; a ghost is learnt away once its object has moved on
        update_background(self.background, self.count, small, near if near is not None else rois, self.alpha)
        self.mask = fg
        return groups
