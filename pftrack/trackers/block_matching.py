"""``pisc``: block matching on peripheral increment sign codes, insensitive to illumination (book ch. 1).

Book *Object Tracking*, ch. 1 §3 (``shared/book/ch01.md`` §1.4): the interest object's region of
the previous frame is tiled into 9x9 blocks; each block's PISC code (Eqs. 7-8) searches the
current frame (Eq. 9); a block *matches* when its correlation reaches ``match_fraction`` of its 81
bits.  The box moves by the displacement with the largest summed correlation of its blocks, refined
to sub-pixel precision (a detector-free form of ch01.md's "dense" mode; the chapter's own mode
votes among the frame-differencing detector's blobs, which :mod:`pftrack.multi` provides).  As an
extension (``anchor_radius``), the first frame's blocks are then matched near the new position and,
when enough match, correct the drift that frame-to-frame matching accumulates.  When fewer than
``min_matched`` of the blocks match, "the matching process is repeated by enlarging the tracking
area" (L489-490): the search radius is doubled; if it still fails the frame is unreliable, and
``lost_frames`` unreliable frames raise ``lost``.

Because a code depends only on the order of grey levels, a monotonic change of brightness
(gain, offset, gamma) changes nothing; the tracker works on grey and colour input alike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from ..cues import pisc as P
from ..cues.ssim import to_gray
from ..geometry import Box
from ..params import Params, param
from .base import Tracker, TrackState


@dataclass(frozen=True, kw_only=True)
class PISCParams(Params):
    """Parameters of ``pisc`` (ch. 1 §3; thresholds the text leaves open are ch01.md §2's proposals)."""

    block: int = param(9, ge=3, le=15, doc="Block side (odd; the chapter's experiments use 9x9, 81 bits).")
    radius: int = param(8, ge=1, le=64, doc=(
        "Search radius (px) of each block in the current frame; doubled once when too few blocks match."))
    match_fraction: float = param(0.8, gt=0, le=1, doc=(
        "tau_c: a block matches when its correlation (Eq. 9) reaches this fraction of its bits."))
    min_matched: float = param(0.3, gt=0, le=1, doc=(
        "tau_v: the fraction of blocks that must match for the frame to count as tracked."))
    median_smooth: int = param(3, ge=1, le=9, doc=(
        "Median filter (odd px) on the grey frame before coding (ch. 1's 3x3): fewer flipped bits from noise."))
    lost_frames: int = param(3, ge=1, le=1000, doc="Consecutive unreliable frames before the target is declared lost.")
    anchor_radius: int = param(3, ge=0, le=32, doc=(
        "After the frame-to-frame step, the first frame's blocks are matched within this radius around the new "
        "position; when enough of them match, their displacement corrects the drift that frame-to-frame "
        "matching accumulates (an extension; 0 is the chapter's frame-to-frame matching only)."))


class PISCTracker(Tracker):
    """PISC block-matching tracker (deterministic: ``particles`` is None)."""

    name = "pisc"
    Params = PISCParams
    stochastic = False

    def _prepare(self, frame: np.ndarray) -> np.ndarray:
        g = to_gray(frame)
        k = self.params.median_smooth
        if k > 1:
            g = cv2.medianBlur(np.clip(g, 0, 255).astype(np.uint8), k).astype(np.float32)
        return g

    def _block_centres(self, box) -> np.ndarray:
        """Centres ``(x, y)`` of the non-overlapping blocks tiling the box (at least one)."""
        b = self.params.block
        x, y, w, h = box
        nx, ny = max(1, int(w // b)), max(1, int(h // b))
        ox, oy = x + (w - nx * b) / 2.0, y + (h - ny * b) / 2.0
        cx = ox + b * (np.arange(nx) + 0.5)
        cy = oy + b * (np.arange(ny) + 0.5)
        gx, gy = np.meshgrid(cx, cy)
        return np.column_stack([gx.ravel(), gy.ravel()])

    def _codes_at(self, gray: np.ndarray, centres: np.ndarray) -> np.ndarray:
        """Codes of the blocks centred at the nearest pixels to ``centres`` ``(x, y)``."""
        b = self.params.block
        r = b // 2
        h, w = gray.shape
        cols = np.clip(np.floor(centres[:, 0]).astype(int), 0, w - 1)
        rows = np.clip(np.floor(centres[:, 1]).astype(int), 0, h - 1)
        x0, y0 = max(cols.min() - r, 0), max(rows.min() - r, 0)
        x1, y1 = min(cols.max() + r + 1, w), min(rows.max() + r + 1, h)
        region = P.dense_codes(gray[y0:y1, x0:x1], block=b)
        return region[rows - y0, cols - x0]

    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        self.box = np.array(box, dtype=np.float64)
        self.prev = self._prepare(frame)
        centres = self._block_centres(self.box)
        fh, fw = self._shape
        ok = (centres[:, 0] >= 0) & (centres[:, 0] < fw) & (centres[:, 1] >= 0) & (centres[:, 1] < fh)
        self.ref_offsets = centres[ok] - self.box[:2]  # block centres relative to the box corner
        self.ref_codes = self._codes_at(self.prev, centres[ok])
        # the codes describe the integer pixel below each centre: remember the fractional part
        self.ref_frac = (centres[ok] - np.floor(centres[ok])).mean(axis=0) if ok.any() else np.zeros(2)
        self.miss = 0
        self.lost = False
        return TrackState(box=tuple(float(v) for v in box), score=1.0, lost=False, info={})

    def _search(self, gray: np.ndarray, centres: np.ndarray, prev_codes: np.ndarray, radius: int):
        b = self.params.block
        r = b // 2
        h, w = gray.shape
        m = radius + r + 1
        x0 = max(int(math.floor(centres[:, 0].min())) - m, 0)
        y0 = max(int(math.floor(centres[:, 1].min())) - m, 0)
        x1 = min(int(math.ceil(centres[:, 0].max())) + m + 1, w)
        y1 = min(int(math.ceil(centres[:, 1].max())) + m + 1, h)
        codes = P.dense_codes(gray[y0:y1, x0:x1], block=b)
        rc = np.column_stack([np.floor(centres[:, 1]).astype(int) - y0, np.floor(centres[:, 0]).astype(int) - x0])
        return P.region_offset(prev_codes, codes, rc, radius, block=b)

    def _update(self, frame: np.ndarray) -> TrackState:
        p = self.params
        gray = self._prepare(frame)
        fh, fw = self._shape
        centres = self._block_centres(self.box)
        inside = (centres[:, 0] >= 0) & (centres[:, 0] < fw) & (centres[:, 1] >= 0) & (centres[:, 1] < fh)
        centres = centres[inside] if inside.any() else np.clip(centres, 0, [fw - 1, fh - 1])
        prev_codes = self._codes_at(self.prev, centres)
        need = p.match_fraction * p.block * p.block
        d, corr = self._search(gray, centres, prev_codes, p.radius)
        matched = corr >= need
        if matched.mean() < p.min_matched:
            d, corr = self._search(gray, centres, prev_codes, 2 * p.radius)
            matched = corr >= need
        ok = matched.mean() >= p.min_matched
        if ok:  # d = (drow, dcol), the common displacement of the blocks
            self.box[0] = float(np.clip(self.box[0] + d[1], -self.box[2] + 1, fw - 1))
            self.box[1] = float(np.clip(self.box[1] + d[0], -self.box[3] + 1, fh - 1))
            if p.anchor_radius > 0 and len(self.ref_codes):
                anchors = self.box[:2] + self.ref_offsets
                keep = (anchors[:, 0] >= 0) & (anchors[:, 0] < fw) & (anchors[:, 1] >= 0) & (anchors[:, 1] < fh)
                if keep.mean() >= 0.5:
                    da, ca = self._search(gray, anchors[keep], self.ref_codes[keep], p.anchor_radius)
                    if (ca >= need).mean() >= p.min_matched:
                        # codes live on integer pixels: the correction is the blocks' displacement minus the
                        # fractional parts of the current and the first centres
                        frac = (anchors[keep] - np.floor(anchors[keep])).mean(axis=0)
                        self.box[0] += float(da[1] - frac[0] + self.ref_frac[0])
                        self.box[1] += float(da[0] - frac[1] + self.ref_frac[1])
            self.miss = 0
            self.lost = False
        else:
            self.miss += 1
            if self.miss >= p.lost_frames:
                self.lost = True
        self.prev = gray
        score = float(matched.mean())
        return TrackState(box=tuple(float(v) for v in self.box), score=score, lost=self.lost,
                          info={"matched": int(matched.sum()), "blocks": int(len(matched)),
                                "mean_corr": float(corr.mean())})
