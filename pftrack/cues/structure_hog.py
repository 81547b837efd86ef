"""The structural cue on gradient orientations: the zero-mean NCC of histograms of oriented gradients.

:class:`~pftrack.cues.structure.StructureCue` correlates grey patches, which is blind to a gain and an
offset over the patch but not to light that varies across it: a lamp or a shadow edge on one side of a face
changes the layout of the grey levels, and the NCC falls.  Dalal & Triggs' histograms of oriented gradients
(CVPR 2005; the features of OpenCV's CSRT and of most correlation-filter trackers) keep the layout of the
*edges* instead, each cell normalised by its own contrast, so a light that changes the contrast of one part of
the target more than another leaves the descriptor nearly unchanged.

A box ``(cx, cy, hx, hy)`` is described by a grid of ``nx x ny`` cells (the box's aspect, about ``cells`` in
all) and, in each cell, the gradient magnitude in ``bins`` unsigned orientations (0 to pi, each pixel's
magnitude split linearly between its two nearest bin centres):

    h_c(b) = sum_{pixels in c} |g| w_b(theta) / area_c,     v_c = h_c / sqrt(|h_c|^2 + (eps mean_c' |h_c'|)^2)

(the cell normalisation: ``eps`` times the box's mean cell norm keeps flat cells from amplifying noise).  Two
boxes compare by the zero-mean NCC of their descriptors ``v`` (length ``nx ny bins``), in [-1, 1] like the grey
NCC, so the caller's likelihood ``exp(gain r)`` and the loss test's score ``(r + 1) / 2`` stay as they are.

Speed: the region the boxes cover is block-averaged once per frame to about ``cell_px`` pixels a cell
(:func:`~pftrack.cues.reduced_region.reduce_region`, as the grey NCC does), the ``bins`` orientation channels of
its gradients are summed into integral images, and a cell costs four reads per bin whatever its size (cell edges
on the reduced pixel grid, rounded to the nearest).  :class:`HogStructure` has the interface of
:class:`~pftrack.cues.structure.StructureCue` (an anchor and a gated running mean, the better correlation of
the two), so ``fusion-pf`` takes either (``structure_features``); :class:`BestStructure` scores a box by the
better of several such cues.
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import njit, numba_enabled
from ..geometry import inside_cells
from .reduced_region import Reduced, reduced_for
from .structure import ratio_pairs

__all__ = ["BestStructure", "HogStructure", "cell_grid", "hog_descriptors", "hog_ncc", "orientation_integrals",
           "standardize_descriptors"]


def cell_grid(w: float, h: float, cells: int) -> tuple[int, int]:
    """``(nx, ny)``: about ``cells`` cells in the aspect of a ``w x h`` box, at least 2 along each side."""
    a = max(float(w), 1e-6) / max(float(h), 1e-6)
    nx = max(2, round(math.sqrt(cells * a)))
    ny = max(2, round(cells / nx))
    return nx, ny


# ---------------------------------------------------------------------------------------------- orientations
def _orientation_channels_numpy(gray: np.ndarray, bins: int) -> np.ndarray:
    g = gray.astype(np.float64)
    gx = np.zeros_like(g)
    gy = np.zeros_like(g)
    gx[:, 1:-1] = g[:, 2:] - g[:, :-2]  # [-1, 0, 1]; zero on the region's border
    gy[1:-1, :] = g[2:, :] - g[:-2, :]
    mag = np.sqrt(gx * gx + gy * gy)
    theta = _atan2_numpy(gy, gx)
    t = theta * (bins / math.pi) - 0.5
    b0 = np.floor(t)
    f = t - b0
    i0 = b0.astype(np.int64) % bins
    i1 = (i0 + 1) % bins
    ch = np.zeros(g.shape + (bins,))
    rows, cols = np.indices(g.shape)
    np.add.at(ch, (rows, cols, i0), mag * (1.0 - f))
    np.add.at(ch, (rows, cols, i1), mag * f)
    return ch


def _atan2_numpy(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """:func:`_unsigned_angle` elementwise."""
    ax, ay = np.abs(x), np.abs(y)
    big = np.maximum(ax, ay)
    a = np.divide(np.minimum(ax, ay), big, out=np.zeros_like(big), where=big > 0)
    s = a * a
    r = ((-0.0464964749 * s + 0.15931422) * s - 0.327622764) * s * a + a
    r = np.where(ay > ax, 0.5 * math.pi - r, r)
    return np.where(x * y < 0.0, math.pi - r, r)


@njit(cache=True, inline="always")
def _unsigned_angle(y, x):
    """The gradient's orientation modulo pi, in [0, pi]: a polynomial arctangent on the octant (error < 3e-4 rad,
    far below a bin's 20 degrees; the library's atan2 costs most of the kernel)."""
    ax = abs(x)
    ay = abs(y)
    big = max(ax, ay)
    if big == 0.0:
        return 0.0
    a = min(ax, ay) / big
    s = a * a
    r = ((-0.0464964749 * s + 0.15931422) * s - 0.327622764) * s * a + a
    if ay > ax:
        r = 0.5 * math.pi - r
    if x * y < 0.0:
        r = math.pi - r
    return r


@njit(cache=True)
def _orientation_integrals_numba(gray, bins, out):
    """The integrals of :func:`orientation_integrals`, row by row: each row's running sums per bin, added to the
    integral of the row above.  A row takes two passes: the magnitudes and orientations of all its pixels first
    (no dependence from one pixel to the next, so the compiler can vectorise it), then the running sums.  A pixel
    without gradient (flat, or on the region's border) adds nothing; it is skipped, which leaves every sum as it
    was bit for bit, since its two shares are exact zeros added to sums that are never negative zero."""
    h, w = gray.shape
    out[0, :, :] = 0.0
    row = np.zeros(bins)
    mag = np.empty(w)
    pos = np.empty(w)
    scale = bins / math.pi
    for j in range(h):
        out[j + 1, 0, :] = 0.0
        row[:] = 0.0
        above = out[j]
        here = out[j + 1]
        inner_row = 0 < j < h - 1
        for i in range(w):
            gx = float(gray[j, i + 1]) - float(gray[j, i - 1]) if 0 < i < w - 1 else 0.0
            gy = float(gray[j + 1, i]) - float(gray[j - 1, i]) if inner_row else 0.0
            mag[i] = math.sqrt(gx * gx + gy * gy)
            pos[i] = _unsigned_angle(gy, gx) * scale - 0.5
        for i in range(w):
            m = mag[i]
            if m != 0.0:
                t = pos[i]
                b0 = math.floor(t)
                f = t - b0
                i0 = int(b0)  # -1 .. bins - 1 (t in [-0.5, bins - 0.5]): the bins wrap without an integer division
                if i0 < 0:
                    i0 += bins
                i1 = i0 + 1 if i0 + 1 < bins else 0
                row[i0] += m * (1.0 - f)
                row[i1] += m * f
            a = above[i + 1]
            c = here[i + 1]
            for b in range(bins):
                c[b] = row[b] + a[b]
    return out


def orientation_integrals(gray: np.ndarray, bins: int = 9, *, backend: str | None = None) -> np.ndarray:
    """``(h + 1, w + 1, bins)`` integral images of the gradient magnitude of ``gray`` ``(h, w)`` in each unsigned
    orientation bin (central differences, zero on the region's border; linear split between the two nearest bin
    centres ``(b + 0.5) pi / bins``): the sum over rows ``y0:y1`` and columns ``x0:x1`` of channel ``b`` is
    ``I[y1, x1, b] - I[y0, x1, b] - I[y1, x0, b] + I[y0, x0, b]``."""
    g = np.ascontiguousarray(gray)
    if g.ndim != 2:
        raise ValueError(f"gray must be 2-D, got shape {g.shape}")
    use_numba = numba_enabled() if backend is None else backend == "numba"
    if use_numba:
        return _orientation_integrals_numba(g, int(bins), np.empty((g.shape[0] + 1, g.shape[1] + 1, int(bins))))
    ch = _orientation_channels_numpy(g, int(bins))
    out = np.zeros((g.shape[0] + 1, g.shape[1] + 1, int(bins)))
    np.cumsum(np.cumsum(ch, axis=0), axis=1, out=out[1:, 1:])
    return out


# ---------------------------------------------------------------------------------------------- descriptors
def _edges(lo: np.ndarray, hi: np.ndarray, n: int, limit: int) -> np.ndarray:
    """``(N, n + 1)`` integer cell edges from ``lo`` to ``hi`` (rounded to the nearest, clipped to [0, limit])."""
    t = np.arange(n + 1) / n
    e = lo[:, None] + (hi - lo)[:, None] * t[None, :]
    return np.clip(np.floor(e + 0.5), 0, limit).astype(np.int64)


def _descriptors_numpy(ii: np.ndarray, boxes: np.ndarray, nx: int, ny: int, eps: float) -> np.ndarray:
    h1, w1, _ = ii.shape
    xe = _edges(boxes[:, 0], boxes[:, 2], nx, w1 - 1)  # (N, nx + 1)
    ye = _edges(boxes[:, 1], boxes[:, 3], ny, h1 - 1)
    corner = ii[ye[:, :, None], xe[:, None, :]]  # (N, ny + 1, nx + 1, bins)
    cell = corner[:, 1:, 1:] - corner[:, :-1, 1:] - corner[:, 1:, :-1] + corner[:, :-1, :-1]
    area = (np.diff(ye, axis=1)[:, :, None] * np.diff(xe, axis=1)[:, None, :]).astype(np.float64)  # (N, ny, nx)
    cell = cell / np.maximum(area, 1.0)[..., None]  # (N, ny, nx, bins)
    norm = np.sqrt((cell * cell).sum(axis=3))  # (N, ny, nx)
    floor = eps * norm.reshape(len(boxes), -1).mean(axis=1)
    scale = 1.0 / np.sqrt(norm * norm + (floor * floor)[:, None, None] + 1e-12)
    return (cell * scale[..., None]).reshape(len(boxes), -1)


@njit(cache=True)
def _descriptor_one(ii, bx0, by0, bx1, by1, nx, ny, eps, xe, ye, out):
    h1, w1, bins = ii.shape
    for c in range(nx + 1):
        e = math.floor(bx0 + (bx1 - bx0) * (c / nx) + 0.5)
        xe[c] = min(max(int(e), 0), w1 - 1)
    for r in range(ny + 1):
        e = math.floor(by0 + (by1 - by0) * (r / ny) + 0.5)
        ye[r] = min(max(int(e), 0), h1 - 1)
    total = 0.0
    k = 0
    for r in range(ny):
        ya, yb = ye[r], ye[r + 1]
        for c in range(nx):
            xa, xb = xe[c], xe[c + 1]
            area = max(float((yb - ya) * (xb - xa)), 1.0)
            s2 = 0.0
            for b in range(bins):
                v = (ii[yb, xb, b] - ii[ya, xb, b] - ii[yb, xa, b] + ii[ya, xa, b]) / area
                out[k + b] = v
                s2 += v * v
            total += math.sqrt(s2)
            k += bins
    floor = eps * total / (nx * ny)
    k = 0
    for r in range(ny):
        for c in range(nx):
            s2 = 0.0
            for b in range(bins):
                s2 += out[k + b] * out[k + b]
            scale = 1.0 / math.sqrt(s2 + floor * floor + 1e-12)
            for b in range(bins):
                out[k + b] *= scale
            k += bins


@njit(cache=True)
def _hog_ncc_numba(ii, boxes, nx, ny, eps, refs, out, per_ref, descs):
    """Best zero-mean NCC of every box's descriptor with the standardised ``refs`` ``(R, D)``; ``per_ref`` ``(N, R)``
    receives each correlation, and ``descs`` ``(N, D)`` each descriptor when it has rows (``(0, D)``: not kept)."""
    bins = ii.shape[2]
    d = nx * ny * bins
    work = np.empty(d)
    keep = descs.shape[0] > 0
    xe = np.empty(nx + 1, np.int64)
    ye = np.empty(ny + 1, np.int64)
    for n in range(boxes.shape[0]):
        desc = descs[n] if keep else work
        _descriptor_one(ii, boxes[n, 0], boxes[n, 1], boxes[n, 2], boxes[n, 3], nx, ny, eps, xe, ye, desc)
        m = 0.0
        for t in range(d):
            m += desc[t]
        m /= d
        ss = 0.0
        for t in range(d):
            ss += (desc[t] - m) * (desc[t] - m)
        best = -1.0
        for q in range(refs.shape[0]):
            dot = 0.0
            for t in range(d):
                dot += (desc[t] - m) * refs[q, t]
            r = dot / math.sqrt(ss) if ss > 0.0 else 0.0
            per_ref[n, q] = r
            best = max(best, r)
        out[n] = best
    return out


@njit(cache=True)
def _descriptors_numba(ii, boxes, nx, ny, eps, out):
    xe = np.empty(nx + 1, np.int64)
    ye = np.empty(ny + 1, np.int64)
    for n in range(boxes.shape[0]):
        _descriptor_one(ii, boxes[n, 0], boxes[n, 1], boxes[n, 2], boxes[n, 3], nx, ny, eps, xe, ye, out[n])
    return out


def hog_descriptors(ii: np.ndarray, boxes: np.ndarray, nx: int, ny: int, eps: float = 0.2, *,
                    backend: str | None = None) -> np.ndarray:
    """Cell-normalised descriptors ``(N, nx ny bins)`` of ``boxes`` ``(N, 4)`` ``(x0, y0, x1, y1)`` in the pixel
    coordinates of the region whose :func:`orientation_integrals` are ``ii`` (cells in row-major order, each
    cell's bins together; cells outside the region are empty)."""
    b = np.ascontiguousarray(boxes, dtype=np.float64).reshape(-1, 4)
    use_numba = numba_enabled() if backend is None else backend == "numba"
    if use_numba:
        out = np.empty((len(b), int(nx) * int(ny) * ii.shape[2]))
        return _descriptors_numba(ii, b, int(nx), int(ny), float(eps), out)
    return _descriptors_numpy(ii, b, int(nx), int(ny), float(eps))


def standardize_descriptors(d: np.ndarray) -> np.ndarray:
    """Zero-mean, unit-norm rows (a constant row stays zero)."""
    d = np.atleast_2d(np.asarray(d, dtype=np.float64))
    z = d - d.mean(axis=1, keepdims=True)
    n = np.sqrt((z * z).sum(axis=1, keepdims=True))
    return np.divide(z, n, out=np.zeros_like(z), where=n > 0)


def hog_ncc(ii: np.ndarray, boxes: np.ndarray, nx: int, ny: int, refs: np.ndarray, eps: float = 0.2, *,
            backend: str | None = None, keep: bool = False):
    """``(best, per_ref)``: the zero-mean NCC of each box's descriptor with each standardised reference ``refs``
    ``(R, D)`` (``per_ref``, ``(N, R)``) and the best of them (``(N,)``); with ``keep``, also the descriptors
    (:func:`hog_descriptors`' numbers) as a third item."""
    b = np.ascontiguousarray(boxes, dtype=np.float64).reshape(-1, 4)
    r = np.ascontiguousarray(refs, dtype=np.float64)
    use_numba = numba_enabled() if backend is None else backend == "numba"
    if use_numba:
        out = np.empty(len(b))
        per = np.empty((len(b), r.shape[0]))
        descs = np.empty((len(b) if keep else 0, int(nx) * int(ny) * ii.shape[2]))
        _hog_ncc_numba(ii, b, int(nx), int(ny), float(eps), r, out, per, descs)
        return (out, per, descs) if keep else (out, per)
    d = _descriptors_numpy(ii, b, int(nx), int(ny), float(eps))
    per = standardize_descriptors(d) @ r.T
    return (per.max(axis=1), per, d) if keep else (per.max(axis=1), per)


# ---------------------------------------------------------------------------------------------- the cue
class HogStructure:
    """References (the first frame's descriptor as an anchor, and a gated running mean) and batched NCC scores of
    particle boxes on histograms of oriented gradients; the interface of
    :class:`~pftrack.cues.structure.StructureCue`.

    ``cells``: about this many cells a box (its aspect); ``bins``: unsigned orientations; ``cell_px``: a cell
    spans at least this many reduced pixels along each side (the region's block size follows the boxes' mean
    size); ``eps``: the cell normalisation's floor, a fraction of the box's mean cell norm."""

    def __init__(self, cells: int = 16, bins: int = 9, cell_px: int = 8, eps: float = 0.2):
        self.cells, self.bins, self.cell_px, self.eps = int(cells), int(bins), int(cell_px), float(eps)
        self.grid = (2, 2)
        self._first: np.ndarray | None = None
        self._run: np.ndarray | None = None
        self._refs: np.ndarray | None = None
        self._red: Reduced | None = None
        self._ii: np.ndarray | None = None

    @property
    def ready(self) -> bool:
        return self._refs is not None

    @property
    def shape(self) -> tuple[int, int]:
        """``(ph, pw)``: the reduced pixels a box spans (its cells times ``cell_px``)."""
        nx, ny = self.grid
        return ny * self.cell_px, nx * self.cell_px

    def new_frame(self) -> None:
        self._red = None
        self._ii = None

    def _region(self, frame: np.ndarray, roi, ell: np.ndarray) -> tuple[Reduced, np.ndarray]:
        red = self._red
        if red is None or not red.covers(ell):
            red = self._red = reduced_for(frame, roi, ell, self.shape, pad_blocks=2)
            self._ii = orientation_integrals(red.gray, self.bins)
        return red, self._ii

    @staticmethod
    def _boxes(red: Reduced, ell: np.ndarray) -> np.ndarray:
        k = float(red.k)
        b = np.empty((len(ell), 4))
        b[:, 0] = (ell[:, 0] - ell[:, 2] - red.x0) / k
        b[:, 1] = (ell[:, 1] - ell[:, 3] - red.y0) / k
        b[:, 2] = (ell[:, 0] + ell[:, 2] - red.x0) / k
        b[:, 3] = (ell[:, 1] + ell[:, 3] - red.y0) / k
        return b

    def _describe(self, frame: np.ndarray, ellipse) -> np.ndarray:
        e = np.asarray(ellipse, dtype=np.float64).reshape(1, 4)
        red, ii = self._region(frame, None, e)
        return hog_descriptors(ii, self._boxes(red, e), *self.grid, eps=self.eps)[0]

    def init(self, frame: np.ndarray, ellipse) -> None:
        e = np.asarray(ellipse, dtype=np.float64).reshape(4)
        self.new_frame()
        self.grid = cell_grid(2 * e[2], 2 * e[3], self.cells)
        self._first = self._describe(frame, e)
        self._run = self._first.copy()
        self._refresh()
        self.new_frame()  # the next frame is block-averaged anew

    def _refresh(self) -> None:
        self._refs = standardize_descriptors(np.stack([self._run, self._first]))

    def _correlate(self, frame: np.ndarray, roi, ellipses, keep: bool = False):
        """:func:`hog_ncc` of the ellipses' boxes with the references (``keep``: with their descriptors)."""
        ell = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
        if ell.shape[0] == 0:
            empty = (np.empty(0), np.empty((0, 2)))
            return (*empty, np.empty((0, self._refs.shape[1]))) if keep else empty
        red, ii = self._region(frame, roi, ell)
        return hog_ncc(ii, self._boxes(red, ell), *self.grid, self._refs, self.eps, keep=keep)

    def scores(self, frame: np.ndarray, roi, ellipses: np.ndarray) -> np.ndarray:
        """NCC in [-1, 1] of every ellipse's box descriptor with the references (the better of the two)."""
        return self._correlate(frame, roi, ellipses)[0]

    def visible_score(self, frame: np.ndarray, ellipse) -> float | None:
        """NCC of the descriptor's cells inside the frame with the same cells of the references (the better of the
        two), or None when every cell is inside or fewer than two are: cells outside the frame are empty, which the
        references' are not."""
        cx, cy, hx, hy = (float(x) for x in np.asarray(ellipse, dtype=np.float64).reshape(4))
        fh, fw = frame.shape[:2]
        nx, ny = self.grid
        cols, rows = inside_cells(cx - hx, cx + hx, nx, fw), inside_cells(cy - hy, cy + hy, ny, fh)
        if (cols.all() and rows.all()) or cols.sum() * rows.sum() < 2:
            return None
        cells = np.ix_(rows, cols)
        descs = np.stack([self._run, self._first, self._describe(frame, (cx, cy, hx, hy))])
        z = standardize_descriptors(descs.reshape(3, ny, nx, -1)[:, cells[0], cells[1]].reshape(3, -1))
        return float(np.max(z[:2] @ z[2]))

    def size_scores(self, frame: np.ndarray, ellipse, ratios, *, anchor_only: bool = False) -> list[float]:
        """:meth:`scores` of the box at each half-axis ratio (a number, or a pair ``(rx, ry)``), same centre
        (``anchor_only``: the NCC with the first frame's descriptor alone)."""
        cx, cy, hx, hy = (float(x) for x in np.asarray(ellipse, dtype=np.float64).reshape(4))
        pairs = ratio_pairs(ratios)
        e = np.array([[cx, cy, hx * rx, hy * ry] for rx, ry in pairs])
        if anchor_only:
            return self._correlate(frame, None, e)[1][:, 1].tolist()
        return self.scores(frame, None, e).tolist()

    def update(self, frame: np.ndarray, ellipse, rate: float, anchor_gate: float = -1.0) -> bool:
        """Blend the estimate's descriptor into the running reference (``(1 - rate) t + rate d``), unless its NCC
        with the anchor is below ``anchor_gate``; returns whether the reference changed."""
        if rate <= 0 or self._run is None:
            return False
        e = np.asarray(ellipse, dtype=np.float64).reshape(1, 4)
        if anchor_gate > -1.0:  # the estimate's descriptor comes with its correlations: computed once
            _, per, desc = self._correlate(frame, None, e, keep=True)
            if per[0, 1] < anchor_gate:
                return False
            desc = desc[0]
        else:
            desc = self._describe(frame, e)
        self._run = (1.0 - rate) * self._run + rate * desc
        self._refresh()
        return True

    def proposals(self, frame: np.ndarray, half_axes, k: int) -> tuple[np.ndarray, np.ndarray]:
        """No whole-frame proposals from this cue (``search_proposals`` uses the grey NCC's)."""
        return np.empty((0, 2)), np.empty(0)


class BestStructure:
    """Several structural cues with one interface: a box scores the best of their correlations; each cue keeps and
    updates its own references.  Proposals are the first cue's."""

    def __init__(self, *cues):
        if not cues:
            raise ValueError("BestStructure needs at least one cue")
        self.cues = list(cues)

    @property
    def primary(self):
        return self.cues[0]

    @property
    def ready(self) -> bool:
        return all(c.ready for c in self.cues)

    @property
    def shape(self) -> tuple[int, int]:
        return self.cues[0].shape

    def new_frame(self) -> None:
        for c in self.cues:
            c.new_frame()

    def init(self, frame: np.ndarray, ellipse) -> None:
        for c in self.cues:
            c.init(frame, ellipse)

    def scores(self, frame: np.ndarray, roi, ellipses: np.ndarray) -> np.ndarray:
        s = self.cues[0].scores(frame, roi, ellipses)
        for c in self.cues[1:]:
            s = np.maximum(s, c.scores(frame, roi, ellipses))
        return s

    def size_scores(self, frame: np.ndarray, ellipse, ratios, *, anchor_only: bool = False) -> list[float]:
        s = self.cues[0].size_scores(frame, ellipse, ratios, anchor_only=anchor_only)
        for c in self.cues[1:]:
            s = [max(a, b) for a, b in zip(s, c.size_scores(frame, ellipse, ratios, anchor_only=anchor_only))]
        return s

    def update(self, frame: np.ndarray, ellipse, rate: float, anchor_gate: float = -1.0) -> bool:
        changed = False
        for c in self.cues:
            changed = c.update(frame, ellipse, rate, anchor_gate) or changed
        return changed

    def proposals(self, frame: np.ndarray, half_axes, k: int) -> tuple[np.ndarray, np.ndarray]:
        return self.cues[0].proposals(frame, half_axes, k)

    def visible_score(self, frame: np.ndarray, ellipse) -> float | None:
        """The best of the cues' :meth:`visible_score` (None when none of them gives one)."""
        found = [c.visible_score(frame, ellipse) for c in self.cues if hasattr(c, "visible_score")]
        found = [v for v in found if v is not None]
        return max(found) if found else None
