"""The extent of a target that enters the view through a frame's edge, measured on a foreground-probability map.

A first box that touches the frame's edge may hold only the part of the target already in view: a sliver, when the
target is coming in.  A colour model cannot correct that box by itself: every part of a uniform target matches the
sliver's histogram as well as the whole does, so the box keeps its first width.  While such a target enters, its
extent across the edge is measured on each frame instead:

- at the first frame, each colour bin ``u`` gets ``P(u) = H_O(u) / (H_O(u) + H_S(u))`` from the pixel counts inside
  the box (``H_O``) and in a surround of :data:`SURROUND` times the box's larger side around it (``H_S``;
  :data:`SURROUND_GREY` on grey features), as the object-vs-surround models of :mod:`pftrack.cues.contrast` do
  (:func:`object_surround_lut`);
- on a later frame, the band of rows (for a left or right edge; columns for the top or bottom) the tracked box spans
  is read across the frame: the share ``f(c)`` of each line ``c`` of the band whose pixels are object-like
  (``P > 1/2``), smoothed over three lines (:func:`band_profile`);
- from the line of the tracked box where ``f`` peaks, the run of lines with ``f >= share * f_peak`` is the target's
  extent (:func:`grow_run`); the box spans it and the tracked box's own span (:func:`extent_box`): a box given
  covers at least the visible target, and a run may be only the part of it whose colours stand out most.

While the run still reaches the edge the target is still coming in; once it has left the edge the target is in view
and the tracker may start again from that box.

On grey input the target's levels are often the ground's, so no bin is more frequent inside the first box than around
it.  There the object-like pixels of a band are instead those more than :data:`CHANGE_LEVELS` levels from the first
frame's at the same place (:func:`change_mask`): what the target covers now and did not then.  Light that changes or
a camera that moves changes most of the band, and nothing is measured then.  Pure functions: arrays in, arrays out.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .contrast import foreground_lut

__all__ = ["CHANGE_LEVELS", "GLOBAL_CHANGE", "SURROUND", "SURROUND_GREY", "band_profile", "change_mask", "edge_sides",
           "extent_box", "grow_run", "object_surround_lut", "surround_roi"]

#: the first frame's surround reaches this many times the box's larger side beyond the box on each side: at an edge
#: one side of it is missing, and with 0.5 the ground a walker hid on the first frame read as object-like when he
#: walked away from a window's edge (0.75 chosen on colour input under docs/rules/enter_extent_surround_rule.txt)
SURROUND = 0.75
#: ... on grey features (levels x orientations), where that rule was not run: as before (0.75 there cost the grey
#: copies of the tune entering scenes and windows, docs/robustness-exits.md)
SURROUND_GREY = 0.5
#: on grey input a pixel is the target's where it differs from the first frame's by more than this many levels
CHANGE_LEVELS = 12
#: ... unless more than this share of the band changed (light or camera motion: nothing is measured then)
GLOBAL_CHANGE = 0.5


def edge_sides(box, width: int, height: int, tol: float = 1.0) -> str:
    """The frame's edges a box ``(x, y, w, h)`` touches (within ``tol`` pixels), as letters of ``"LTRB"``."""
    x, y, w, h = (float(v) for v in box)
    touch = (x <= tol, y <= tol, x + w >= width - tol, y + h >= height - tol)
    return "".join(s for s, t in zip("LTRB", touch) if t)


def surround_roi(box, width: int, height: int, margin: float = SURROUND) -> tuple[int, int, int, int]:
    """The region ``(x0, y0, x1, y1)`` of the box grown by ``margin`` times its larger side on each side, cut to the
    frame."""
    x, y, w, h = (float(v) for v in box)
    m = margin * max(w, h)
    return (max(int(math.floor(x - m)), 0), max(int(math.floor(y - m)), 0),
            min(int(math.ceil(x + w + m)), width), min(int(math.ceil(y + h + m)), height))


def object_surround_lut(bins: np.ndarray, x0: int, y0: int, box, n_bins: int) -> np.ndarray:
    """``P(u)`` per bin (float32) from the pixels of ``box`` against the rest of the quantised region ``bins``
    (whose top-left pixel is ``(x0, y0)``, every pixel quantised); 1/2 for a bin seen in neither."""
    x, y, w, h = (float(v) for v in box)
    rh, rw = bins.shape
    ix0, ix1 = max(int(math.floor(x)) - x0, 0), min(int(math.ceil(x + w)) - x0, rw)
    iy0, iy1 = max(int(math.floor(y)) - y0, 0), min(int(math.ceil(y + h)) - y0, rh)
    inside = np.bincount(bins[iy0:iy1, ix0:ix1].ravel(), minlength=n_bins).astype(np.float64)
    every = np.bincount(bins.ravel(), minlength=n_bins).astype(np.float64)
    return foreground_lut(inside, every - inside)


def band_profile(bins: np.ndarray, lut: np.ndarray, axis: int) -> np.ndarray:
    """The share of object-like pixels (``lut[bin] > 1/2``) of each line of a band of bins, smoothed over three
    lines: along ``axis = 1`` the band's columns (a band of rows), along ``axis = 0`` its rows."""
    like = (lut > 0.5)[bins]
    share = like.mean(axis=1 - axis) if like.size else np.zeros(bins.shape[axis])
    if share.size >= 3:
        padded = np.concatenate(([share[0]], share, [share[-1]]))
        share = (padded[:-2] + padded[1:-1] + padded[2:]) / 3.0
    return share


def grow_run(profile: np.ndarray, lo: int, hi: int, *, share: float = 0.2, min_peak: float = 0.25
             ) -> tuple[int, int] | None:
    """The run of lines around the profile's peak within ``[lo, hi)`` whose value is at least ``share`` times the
    peak's, as ``(first, last + 1)``; None when that peak is below ``min_peak`` (nothing object-like there)."""
    n = profile.size
    lo, hi = max(int(lo), 0), min(int(hi), n)
    if hi <= lo:
        return None
    seed = lo + int(np.argmax(profile[lo:hi]))
    peak = float(profile[seed])
    if peak < min_peak:
        return None
    below = np.flatnonzero(profile < share * peak)
    left = below[below < seed]
    right = below[below > seed]
    return (int(left[-1]) + 1 if left.size else 0), (int(right[0]) if right.size else n)


def extent_box(box, run: tuple[int, int], offset: int, axis: int, max_extent: float, *, keep: bool = False
               ) -> tuple[float, ...]:
    """``box`` with its extent along ``axis`` (1: x, 0: y) set to the run of lines ``[first, last)`` of a band that
    starts at pixel ``offset`` (with ``keep``, to the union of the run and the box's own span); of an extent longer
    than ``max_extent``, the part of that length nearest to being centred on the box."""
    x, y, w, h = (float(v) for v in box)
    a0, a1 = float(run[0] + offset), float(run[1] + offset)
    if keep:
        b0, b1 = (x, x + w) if axis == 1 else (y, y + h)
        a0, a1 = min(a0, b0), max(a1, b1)
    if a1 - a0 > max_extent:  # the window of that length within the run nearest to being centred on the box
        c = x + 0.5 * w if axis == 1 else y + 0.5 * h
        a0 = min(max(c - 0.5 * max_extent, a0), a1 - max_extent)
        a1 = a0 + max_extent
    return (a0, y, a1 - a0, h) if axis == 1 else (x, a0, w, a1 - a0)


def change_mask(band: np.ndarray, first: np.ndarray, levels: float = CHANGE_LEVELS,
                global_share: float = GLOBAL_CHANGE) -> np.ndarray | None:
    """``uint8`` 0/1: the pixels of a grey ``band`` more than ``levels`` from the first frame's ``first`` (same
    shape); None when more than ``global_share`` of them changed (the light or the view, not a target)."""
    diff = cv2.absdiff(band, first)
    mask = (diff > levels).view(np.uint8)
    if mask.size == 0 or np.count_nonzero(mask) > global_share * mask.size:
        return None
    return mask
