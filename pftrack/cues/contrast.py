"""Background-aware colour cue: object/surround contrast on a foreground-probability map.

The colour histogram of the target says what the target looks like; it does not
say which of its colours are *also* common around it.  Following the
object-vs-surround colour models of discriminative colour trackers (Collins et al.
2005; Possegger et al., "In defense of color-based model-free tracking", CVPR 2015),
each colour bin ``u`` gets the probability that a pixel of that colour belongs to
the object,

    P(u) = H_O(u) / (H_O(u) + H_S(u))          (0.5 for colours seen in neither)

from pixel counts ``H_O`` inside the target box and ``H_S`` in a ring around it.
Mapping the quantised region through ``P`` gives a foreground-probability map;
with its integral image the mean probability of any box costs four lookups.

A candidate box ``B`` scores the **contrast** between the mean probability inside
it and in the ring ``R(B)`` that surrounds it (``B`` grown by ``ring`` times its
size on each side, minus ``B``):

    c(B) = mean_{x in B} P - mean_{x in R(B)} P  in [-1, 1].

``c`` is high only when ``B`` covers object-like colours *and* its surround does
not: a box too large takes in surround colours, a box too small leaves object
colours in its ring.  Unlike the Bhattacharyya coefficient, it therefore observes
the target's extent, which is what keeps a colour tracker's scale from drifting.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .._numba import njit, np_sum, numba_enabled


def box_counts(bins: np.ndarray, x0: int, y0: int, box, n_bins: int, *, ring: float = 0.0, pitch: int = 1
               ) -> tuple[np.ndarray, np.ndarray]:
    """Bin counts inside ``box`` and in the ring around it (``ring`` x size on each side).

    ``bins`` is a quantised region whose top-left pixel is ``(x0, y0)`` (a lattice of
    ``pitch``, see :class:`~pftrack.cues.color.ColorFeatures`); pixels outside it are
    ignored.  Returns ``(inside, ring_counts)`` as float64 arrays.
    """
    h, w = bins.shape
    bx, by, bw, bh = box.tolist() if isinstance(box, np.ndarray) and box.shape == (4,) else (float(v) for v in box)
    bx, by, bw, bh = (bx - x0) / pitch, (by - y0) / pitch, bw / pitch, bh / pitch
    ix0, ix1 = _span(bx, bx + bw, w)
    iy0, iy1 = _span(by, by + bh, h)
    if ring <= 0:
        return _counts(bins, ix0, iy0, ix1, iy1, n_bins), np.zeros(n_bins)
    ox0, ox1 = _span(bx - ring * bw, bx + bw + ring * bw, w)
    oy0, oy1 = _span(by - ring * bh, by + bh + ring * bh, h)
    if numba_enabled():
        inside, outer = np.zeros(n_bins), np.zeros(n_bins)
        _ring_counts_numba(bins, ix0, iy0, ix1, iy1, ox0, oy0, ox1, oy1, inside, outer)
        return inside, outer
    inside = _counts(bins, ix0, iy0, ix1, iy1, n_bins)
    outer = _counts(bins, ox0, oy0, ox1, oy1, n_bins)
    return inside, np.maximum(outer - inside, 0.0)


def _span(a0: float, a1: float, lim: int) -> tuple[int, int]:
    """The pixel columns (rows) ``[a0, a1)`` covers, within ``[0, lim)``."""
    return max(int(math.floor(a0)), 0), min(int(math.ceil(a1)), lim)


def _counts(bins: np.ndarray, x0: int, y0: int, x1: int, y1: int, n_bins: int) -> np.ndarray:
    return np.bincount(bins[y0:y1, x0:x1].ravel(), minlength=n_bins).astype(np.float64)


@njit(cache=True)
def _ring_counts_numba(bins, ix0, iy0, ix1, iy1, ox0, oy0, ox1, oy1, inside, ring):
    """Bin counts of the box ``[ix0, ix1) x [iy0, iy1)`` and of the rest of ``[ox0, ox1) x [oy0, oy1)`` (one pass)."""
    for j in range(oy0, oy1):
        row = bins[j]
        in_row = iy0 <= j < iy1
        for i in range(ox0, ox1):
            if in_row and ix0 <= i < ix1:
                inside[row[i]] += 1.0
            else:
                ring[row[i]] += 1.0


def foreground_lut(obj_counts: np.ndarray, surround_counts: np.ndarray, *, prior: float = 0.5) -> np.ndarray:
    """``P(u) = H_O(u) / (H_O(u) + H_S(u))`` per bin, ``prior`` where both are empty (float32)."""
    o = np.asarray(obj_counts, dtype=np.float64)
    s = np.asarray(surround_counts, dtype=np.float64)
    tot = o + s
    return np.where(tot > 0, o / np.where(tot > 0, tot, 1.0), prior).astype(np.float32)


@njit
def _blend_counts_numba(obj_ref, obj, sur_ref, sur, a, prior, lut):
    """:func:`blend_counts` compiled: the same operations in the same order, element by element."""
    s_new = np_sum(obj)
    if s_new <= 0:
        return False
    ratio = np_sum(obj_ref) / s_new
    for u in range(obj.shape[0]):
        obj_ref[u] = (1 - a) * obj_ref[u] + a * obj[u] * ratio
    s_new = np_sum(sur)
    s_ref = np_sum(sur_ref)
    if s_new > 0 and s_ref > 0:
        ratio = s_ref / s_new
        for u in range(sur.shape[0]):
            sur_ref[u] = (1 - a) * sur_ref[u] + a * sur[u] * ratio
    for u in range(obj.shape[0]):
        tot = obj_ref[u] + sur_ref[u]
        lut[u] = np.float64(np.float32(obj_ref[u] / tot if tot > 0 else prior))
    return True


def blend_counts(obj_ref: np.ndarray, obj: np.ndarray, sur_ref: np.ndarray, sur: np.ndarray, a: float,
                 *, prior: float = 0.5) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Blend a frame's object and surround counts into the reference counts at rate ``a``, each scaled to the
    reference's total (``ref <- (1 - a) ref + a new sum(ref) / sum(new)``; the surround only when both are
    non-empty), and the new :func:`foreground_lut` as float64.  None (nothing changed) when the object counts
    are empty.  Returns new arrays; the compiled path gives the NumPy path's numbers to the last bit."""
    if numba_enabled():
        o, s, lut = obj_ref.astype(np.float64), sur_ref.astype(np.float64), np.empty(obj_ref.shape[0])
        ok = _blend_counts_numba(o, np.asarray(obj, np.float64), s, np.asarray(sur, np.float64), float(a),
                                 float(prior), lut)
        return (o, s, lut) if ok else None
    if obj.sum() <= 0:
        return None
    o = (1 - a) * obj_ref + a * obj * (obj_ref.sum() / obj.sum())
    s = sur_ref
    if sur.sum() > 0 and sur_ref.sum() > 0:
        s = (1 - a) * sur_ref + a * sur * (sur_ref.sum() / sur.sum())
    return o, s, foreground_lut(o, s, prior=prior).astype(np.float64)


@njit
def _integral_numba(bins, lut, out):
    h, w = bins.shape
    for i in range(w + 1):
        out[0, i] = 0.0
    for j in range(h):
        out[j + 1, 0] = 0.0
        row = 0.0
        for i in range(w):
            row += lut[bins[j, i]]
            out[j + 1, i + 1] = out[j, i + 1] + row
    return out


def probability_integral(bins: np.ndarray, lut: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Integral image (``(h + 1, w + 1)`` float64) of the foreground-probability map ``lut[bins]``."""
    h, w = bins.shape
    if out is None or out.shape != (h + 1, w + 1):
        out = np.empty((h + 1, w + 1))
    if bins.size == 0:
        out[:] = 0.0
        return out
    if numba_enabled():
        return _integral_numba(bins, np.asarray(lut, dtype=np.float64), out)
    out[:] = cv2.integral(lut[bins].astype(np.float64))
    return out


def _box_mean(ii: np.ndarray, x0: np.ndarray, y0: np.ndarray, x1: np.ndarray, y1: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    s = ii[y1, x1] - ii[y0, x1] - ii[y1, x0] + ii[y0, x0]
    area = (x1 - x0) * (y1 - y0)
    return s, area


@njit
def _clipped_sum(ii, x0, y0, x1, y1, outside):
    h = ii.shape[0] - 1
    w = ii.shape[1] - 1
    cx0 = min(max(x0, 0), w)
    cx1 = min(max(x1, 0), w)
    cy0 = min(max(y0, 0), h)
    cy1 = min(max(y1, 0), h)
    if cx1 < cx0:
        cx1 = cx0
    if cy1 < cy0:
        cy1 = cy0
    s = ii[cy1, cx1] - ii[cy0, cx1] - ii[cy1, cx0] + ii[cy0, cx0]
    inside = (cx1 - cx0) * (cy1 - cy0)
    full = (x1 - x0) * (y1 - y0)
    return s + outside * (full - inside), full


@njit
def _contrast_numba(ii, x0, y0, boxes, ring, outside, out):
    for k in range(boxes.shape[0]):
        out[k] = _contrast_one(ii, x0, y0, boxes[k, 0], boxes[k, 1], boxes[k, 2], boxes[k, 3], ring, outside)
    return out


@njit
def _contrast_ellipses_numba(ii, ox, oy, pitch, ell, ring, outside, out):
    """:func:`_contrast_numba` of the ellipses' bounding boxes ``(cx - hx, cy - hy, 2 hx, 2 hy)``, moved to the
    lattice of origin ``(ox, oy)`` and ``pitch`` (the same arithmetic as :func:`contrast_scores`)."""
    for k in range(ell.shape[0]):
        cx, cy, hx, hy = ell[k, 0], ell[k, 1], ell[k, 2], ell[k, 3]
        out[k] = _contrast_one(ii, 0, 0, (cx - hx - ox) / pitch, (cy - hy - oy) / pitch, 2.0 * hx / pitch,
                               2.0 * hy / pitch, ring, outside)
    return out


@njit
def _contrast_one(ii, x0, y0, bx, by, bw, bh, ring, outside):
    ax0 = int(np.rint(bx - x0))
    ax1 = max(int(np.rint(bx + bw - x0)), ax0 + 1)
    ay0 = int(np.rint(by - y0))
    ay1 = max(int(np.rint(by + bh - y0)), ay0 + 1)
    rx = max(int(np.rint(ring * bw)), 1)
    ry = max(int(np.rint(ring * bh)), 1)
    s_in, a_in = _clipped_sum(ii, ax0, ay0, ax1, ay1, outside)
    s_out, a_out = _clipped_sum(ii, ax0 - rx, ay0 - ry, ax1 + rx, ay1 + ry, outside)
    ring_area = max(a_out - a_in, 1)
    return s_in / a_in - (s_out - s_in) / ring_area


#: horizontal strips that approximate an ellipse in :func:`contrast_scores_ellipses` with ``shape="ellipse"``
ELLIPSE_STRIPS = 8
#: Strips of the ellipse against its box's ring (``shape="ellipse-box"``): with 8, a strip's ends past the ellipse
#: pull its peak to 0.94-0.96 of an ideal ellipse's size, with 16 to 0.96-0.97.
ELLIPSE_BOX_STRIPS = 16


@njit
def _strips_sum(ii, cx, cy, hx, hy, k, outside):
    """Sum of the map and area over the ellipse ``(cx, cy, hx, hy)`` (integral-image coordinates) taken as ``k``
    horizontal strips of equal height, each as wide as the ellipse at its middle row (parts outside the map count
    ``outside`` per pixel, as :func:`_clipped_sum`)."""
    s = 0.0
    a = 0.0
    top = cy - hy
    for j in range(k):
        ya = int(np.rint(top + 2.0 * hy * j / k))
        yb = int(np.rint(top + 2.0 * hy * (j + 1) / k))
        if yb <= ya:
            continue
        t = ((ya + yb) * 0.5 - cy) / hy
        half = hx * math.sqrt(max(1.0 - t * t, 0.0))
        xa = int(np.rint(cx - half))
        xb = max(int(np.rint(cx + half)), xa + 1)
        ss, aa = _clipped_sum(ii, xa, ya, xb, yb, outside)
        s += ss
        a += aa
    return s, a


@njit
def _contrast_ellipses_strips(ii, ox, oy, pitch, ell, ring, outside, k, out):
    """The contrast of each ellipse against the elliptic annulus around it (half-axes ``1 + 2 ring`` times its own,
    the box version's ring in each direction), both as strips (:func:`_strips_sum`)."""
    for n in range(ell.shape[0]):
        cx, cy = (ell[n, 0] - ox) / pitch, (ell[n, 1] - oy) / pitch
        hx, hy = max(ell[n, 2] / pitch, 0.5), max(ell[n, 3] / pitch, 0.5)
        s_in, a_in = _strips_sum(ii, cx, cy, hx, hy, k, outside)
        g = 1.0 + 2.0 * ring
        s_out, a_out = _strips_sum(ii, cx, cy, g * hx, g * hy, k, outside)
        a_in = max(a_in, 1.0)
        out[n] = s_in / a_in - (s_out - s_in) / max(a_out - a_in, 1.0)
    return out


@njit
def _contrast_ellipses_in_boxes(ii, ox, oy, pitch, ell, ring, outside, k, out):
    """The mean over each ellipse (as strips, :func:`_strips_sum`) against the rectangular ring around its bounding
    box (the box grown by ``ring`` times its size on each side, minus the box): the corners between the ellipse and
    its box count in neither mean."""
    for n in range(ell.shape[0]):
        cx, cy = (ell[n, 0] - ox) / pitch, (ell[n, 1] - oy) / pitch
        hx, hy = max(ell[n, 2] / pitch, 0.5), max(ell[n, 3] / pitch, 0.5)
        s_in, a_in = _strips_sum(ii, cx, cy, hx, hy, k, outside)
        xa, xb = int(np.rint(cx - hx)), int(np.rint(cx + hx))
        ya, yb = int(np.rint(cy - hy)), int(np.rint(cy + hy))
        xb, yb = max(xb, xa + 1), max(yb, ya + 1)
        rx, ry = max(int(np.rint(2.0 * ring * hx)), 1), max(int(np.rint(2.0 * ring * hy)), 1)
        s_box, a_box = _clipped_sum(ii, xa, ya, xb, yb, outside)
        s_out, a_out = _clipped_sum(ii, xa - rx, ya - ry, xb + rx, yb + ry, outside)
        out[n] = s_in / max(a_in, 1.0) - (s_out - s_box) / max(a_out - a_box, 1.0)
    return out


def contrast_scores_ellipses(integral: np.ndarray, x0: int, y0: int, ellipses: np.ndarray, *, ring: float = 0.5,
                             outside: float = 0.5, pitch: int = 1, shape: str = "box") -> np.ndarray:
    """:func:`contrast_scores` of the bounding boxes of ellipses ``(N, 4)`` ``(cx, cy, hx, hy)`` (the same numbers,
    compiled in one pass when Numba is enabled); with ``shape="ellipse"`` the mean over each ellipse against the
    elliptic annulus around it, each taken as :data:`ELLIPSE_STRIPS` strips of the integral image (a box's
    corners are background around an elliptic target, which pulls the box contrast toward smaller boxes); with
    ``shape="ellipse-box"`` the mean over the ellipse against the box's rectangular ring (the corners in neither)."""
    ell = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
    if shape == "ellipse":
        return _contrast_ellipses_strips(integral, float(x0), float(y0), float(pitch), ell, float(ring),
                                         float(outside), ELLIPSE_STRIPS, np.empty(ell.shape[0]))
    if shape == "ellipse-box":
        return _contrast_ellipses_in_boxes(integral, float(x0), float(y0), float(pitch), ell, float(ring),
                                           float(outside), ELLIPSE_BOX_STRIPS, np.empty(ell.shape[0]))
    if shape != "box":
        raise ValueError(f"shape must be 'box', 'ellipse' or 'ellipse-box', got {shape!r}")
    if not numba_enabled():
        from ..geometry import ellipse_to_box

        return contrast_scores(integral, x0, y0, ellipse_to_box(ell), ring=ring, outside=outside, pitch=pitch)
    return _contrast_ellipses_numba(integral, float(x0), float(y0), float(pitch), ell, float(ring), float(outside),
                                    np.empty(ell.shape[0]))


def contrast_scores(integral: np.ndarray, x0: int, y0: int, boxes: np.ndarray, *, ring: float = 0.5,
                    outside: float = 0.5, pitch: int = 1, backend: str | None = None) -> np.ndarray:
    """``c(B) = mean_B P - mean_R(B) P`` for every box ``(x, y, w, h)`` (image coordinates).

    Box edges are rounded to the pixel grid (to the lattice when ``pitch > 1``).
    Parts of a box or ring outside the quantised region count with probability
    ``outside`` (unknown), so leaving the image is neither rewarded nor punished.
    """
    b = np.ascontiguousarray(boxes, dtype=np.float64).reshape(-1, 4)
    if pitch != 1 or x0 or y0:
        b = (b - np.array([x0, y0, 0.0, 0.0])) / float(pitch)
        x0 = y0 = 0
    use_numba = numba_enabled() if backend is None else backend == "numba"
    if use_numba:
        return _contrast_numba(integral, int(x0), int(y0), b, float(ring), float(outside), np.empty(b.shape[0]))
    h = integral.shape[0] - 1
    w = integral.shape[1] - 1

    def edges(lo, hi, off, lim):
        a = np.rint(lo - off).astype(np.int64)
        c = np.rint(hi - off).astype(np.int64)
        c = np.maximum(c, a + 1)
        return a, c

    ax0, ax1 = edges(b[:, 0], b[:, 0] + b[:, 2], x0, w)
    ay0, ay1 = edges(b[:, 1], b[:, 1] + b[:, 3], y0, h)
    rx = np.maximum(np.rint(ring * b[:, 2]).astype(np.int64), 1)
    ry = np.maximum(np.rint(ring * b[:, 3]).astype(np.int64), 1)
    bx0, bx1, by0, by1 = ax0 - rx, ax1 + rx, ay0 - ry, ay1 + ry

    def clipped_sum(x_0, y_0, x_1, y_1):
        cx0, cx1 = np.clip(x_0, 0, w), np.clip(x_1, 0, w)
        cy0, cy1 = np.clip(y_0, 0, h), np.clip(y_1, 0, h)
        cx1 = np.maximum(cx1, cx0)
        cy1 = np.maximum(cy1, cy0)
        s, inside_area = _box_mean(integral, cx0, cy0, cx1, cy1)
        full = (x_1 - x_0) * (y_1 - y_0)
        return s + outside * (full - inside_area), full

    s_in, a_in = clipped_sum(ax0, ay0, ax1, ay1)
    s_out, a_out = clipped_sum(bx0, by0, bx1, by1)
    ring_area = np.maximum(a_out - a_in, 1)
    return s_in / a_in - (s_out - s_in) / ring_area
