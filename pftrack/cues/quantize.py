"""Colour quantisation: a pixel's bin from per-channel lookup tables (Nummiaro et al. §3: RGB 8x8x8, HSV
8x8x4), for the kernel histograms of :mod:`pftrack.cues.color`.  The region the particles can reach is
quantised once per frame; with power-of-two RGB bins (the default) by shifts on the frame's contiguous rows,
which the compiler vectorises, with the same bins as the table."""

from __future__ import annotations

import numpy as np

from .._numba import njit, numba_enabled


def make_lut(color_space: str, bins: tuple[int, int, int]) -> np.ndarray:
    """Per-channel lookup tables ``(3, 256)``: bin index = ``lut[0][c0] + lut[1][c1] + lut[2][c2]``.

    For RGB the channels arrive in OpenCV's BGR order and the bin index is
    ``r_idx * (nG * nB) + g_idx * nB + b_idx``.  For HSV (OpenCV's ``H`` in
    ``[0, 180)``) it is ``h_idx * (nS * nV) + s_idx * nV + v_idx``.
    """
    n0, n1, n2 = (int(b) for b in bins)
    v = np.arange(256, dtype=np.int64)
    if n0 * n1 * n2 > 65536:
        raise ValueError(f"at most 65536 colour bins, got {n0 * n1 * n2}")
    lut = np.zeros((3, 256), dtype=np.uint16)
    if color_space == "rgb":
        nr, ng, nb = n0, n1, n2
        lut[0] = (v * nb) >> 8  # B
        lut[1] = ((v * ng) >> 8) * nb  # G
        lut[2] = ((v * nr) >> 8) * (ng * nb)  # R
    elif color_space == "hsv":
        nh, ns, nv = n0, n1, n2
        lut[0] = (np.minimum(v, 179) * nh // 180) * (ns * nv)
        lut[1] = ((v * ns) >> 8) * nv
        lut[2] = (v * nv) >> 8
    else:
        raise ValueError(f"unknown colour space {color_space!r}")
    return lut


@njit
def _quantize_numba(img, lut, out):
    h, w = img.shape[0], img.shape[1]
    for j in range(h):
        for i in range(w):
            out[j, i] = lut[0, img[j, i, 0]] + lut[1, img[j, i, 1]] + lut[2, img[j, i, 2]]
    return out


@njit
def _quantize_cells_numba(img, pitch, cells, lut, out):
    """:func:`quantize_cells`, compiled: the lattice pixels of each block, looked up in the three tables."""
    for k in range(cells.shape[0]):
        for j in range(cells[k, 0], cells[k, 1]):
            row = img[j * pitch]
            o = out[j]
            for i in range(cells[k, 2], cells[k, 3]):
                x = i * pitch
                o[i] = lut[0, row[x, 0]] + lut[1, row[x, 1]] + lut[2, row[x, 2]]
    return out


def quantize_cells(img: np.ndarray, pitch: int, cells: np.ndarray, lut: np.ndarray, out: np.ndarray) -> np.ndarray:
    """:func:`quantize` of the lattice ``img[::pitch, ::pitch]`` in the blocks ``cells`` only (rows ``(r0, r1, c0,
    c1)`` of lattice indices): ``out[r0:r1, c0:c1]`` gets the bins of those lattice pixels, the rest of ``out`` is
    left as it is. The same bins as :func:`quantize` of the whole lattice, where they are written."""
    cells = np.ascontiguousarray(cells, dtype=np.int64).reshape(-1, 4)
    if numba_enabled():
        return _quantize_cells_numba(img, int(pitch), cells, lut, out)
    for r0, r1, c0, c1 in cells.tolist():
        if r1 > r0 and c1 > c0:
            q = quantize(img[r0 * pitch:r1 * pitch:pitch, c0 * pitch:c1 * pitch:pitch], lut)
            out[r0:r1, c0:c1] = q
    return out


def quantize(img: np.ndarray, lut: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Map an ``(h, w, 3)`` uint8 image to ``(h, w)`` uint16 bin indices."""
    if out is None:
        out = np.empty(img.shape[:2], dtype=np.uint16)
    if numba_enabled():
        return _quantize_numba(img, lut, out)
    np.add(lut[0][img[..., 0]], lut[1][img[..., 1]], out=out)
    out += lut[2][img[..., 2]]
    return out


def shift_form(lut: np.ndarray) -> tuple[int, int, int, int, int, int] | None:
    """``(s0, s1, s2, t0, t1, t2)`` when every channel's table is ``lut[c][v] == (v >> s_c) << t_c`` (RGB with
    power-of-two bins, as :func:`make_lut` builds it), else None."""
    v = np.arange(256, dtype=np.int64)
    out = []
    for c in range(3):
        row = np.asarray(lut[c], dtype=np.int64)
        for sh in range(9):
            base = v >> sh
            t = int(row[255]).bit_length() - int(base[255]).bit_length() if base[255] > 0 else 0
            if t >= 0 and np.array_equal(row, base << t):
                out.append((sh, t))
                break
        else:
            return None
    return out[0][0], out[1][0], out[2][0], out[0][1], out[1][1], out[2][1]


@njit
def _quantize_shift(rows, x0, y0, h, w, s0, s1, s2, t0, t1, t2, out):
    """:func:`quantize` of the ``h x w`` region at ``(x0, y0)`` of a BGR uint8 frame given as its ``(H, W*3)``
    rows, for a table of shift form (:func:`shift_form`): shifts on contiguous rows, which the compiler
    vectorises (twice as fast as the three table lookups per pixel)."""
    for j in range(h):
        seg = rows[y0 + j, 3 * x0:3 * (x0 + w)]
        o = out[j]
        for i in range(w):
            o[i] = np.uint16(((seg[3 * i] >> s0) << t0) + ((seg[3 * i + 1] >> s1) << t1)
                             + ((seg[3 * i + 2] >> s2) << t2))
    return out


@njit
def _quantize_rows(rows, x0, y0, h, w, l0, l1, l2, out):
    """:func:`quantize` of the ``h x w`` region at ``(x0, y0)`` of a BGR uint8 frame given as its ``(H, W*3)``
    rows, by the three channels' tables ``l0, l1, l2`` (contiguous): a third faster than indexing the 3-D
    region, for tables that have no shift form (a stretched or relit table)."""
    for j in range(h):
        seg = rows[y0 + j, 3 * x0:3 * (x0 + w)]
        o = out[j]
        for i in range(w):
            o[i] = l0[seg[3 * i]] + l1[seg[3 * i + 1]] + l2[seg[3 * i + 2]]
    return out


def quantize_region(frame: np.ndarray, x0: int, y0: int, x1: int, y1: int, lut: np.ndarray, out: np.ndarray,
                    shifts: tuple[int, int, int, int, int, int] | None = None) -> np.ndarray:
    """:func:`quantize` of ``frame[y0:y1, x0:x1]`` into ``out`` (its shape); with a contiguous uint8 BGR frame
    the same numbers on its rows: by shifts with ``shifts`` (the table's :func:`shift_form`), else by the table."""
    if (numba_enabled() and x0 >= 0 and y0 >= 0 and frame.ndim == 3 and frame.shape[2] == 3
            and frame.dtype == np.uint8 and frame.flags.c_contiguous):
        h, w = out.shape
        rows = frame.reshape(frame.shape[0], -1)
        if shifts is not None:
            return _quantize_shift(rows, int(x0), int(y0), h, w, *shifts, out)
        if lut.dtype == np.uint16 and lut.flags.c_contiguous:
            return _quantize_rows(rows, int(x0), int(y0), h, w, lut[0], lut[1], lut[2], out)
    return quantize(frame[y0:y1, x0:x1], lut, out)


def level_gain(frame: np.ndarray, *, percentile: float = 99.5, max_gain: float = 8.0, stride: int = 4) -> float:
    """The gain that brings a frame's bright end (its ``percentile`` over every channel of a ``stride`` lattice) to
    level 255, at most ``max_gain`` and at least 1: how much of the 0-255 range a dark camera leaves unused."""
    sample = np.asarray(frame)[::stride, ::stride]
    if sample.size == 0:
        return 1.0
    top = float(np.percentile(sample, percentile))
    return float(min(max_gain, max(1.0, 255.0 / max(top, 1.0))))


def level_range(frame: np.ndarray, *, percentile: float = 99.5, max_gain: float = 8.0,
                stride: int = 4) -> tuple[float, float]:
    """``(gain, offset)`` that bring a frame's dark end (its ``100 - percentile`` percentile over every channel of a
    ``stride`` lattice) to level 0 and its bright end (its ``percentile``) to 255: ``v -> gain * (v - offset)``, the
    gain at least 1 and at most ``max_gain``. How much of the 0-255 range a hazy camera leaves unused."""
    sample = np.asarray(frame)[::stride, ::stride]
    if sample.size == 0:
        return 1.0, 0.0
    lo, hi = (float(v) for v in np.percentile(sample, [100.0 - percentile, percentile]))
    return float(min(max_gain, max(1.0, 255.0 / max(hi - lo, 1.0)))), lo


def stretched_lut(lut: np.ndarray, gain: float, offset: float = 0.0) -> np.ndarray:
    """The table ``lut`` (``(3, 256)``) applied to levels minus ``offset`` times ``gain`` (rounded, within 0-255): the
    same bins spread over the levels a dark or hazy frame uses,
    ``stretched[c][v] = lut[c][clip(round(gain * (v - offset)), 0, 255)]``."""
    v = np.clip(np.rint((np.arange(256) - float(offset)) * float(gain)), 0, 255).astype(np.intp)
    return np.ascontiguousarray(np.asarray(lut)[:, v])
