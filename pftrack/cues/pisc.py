"""Peripheral increment sign correlation (PISC) of image blocks (book ch. 1, Eqs. 7-9).

Book *Object Tracking*, ch. 1 (``shared/seeds/002_*`` lines 401-493; ``shared/book/ch01.md`` §1.4):
the code of a block centred at pixel ``(i, j)`` has one bit per pixel ``p`` of the block,
``b_p = 1 if f_p >= f(i, j)`` (Eqs. 7-8); two codes are compared by the number of agreeing bits
(Eq. 9), ``corr = N - popcount(b XOR b')``.  The code depends only on the order of the grey levels,
so any strictly increasing change of brightness (gain, offset, gamma) leaves it unchanged.

:func:`dense_codes` computes the code of the ``block x block`` neighbourhood of every pixel of a
region at once (one shifted comparison per neighbour, packed into 64-bit words);
:func:`block_correlation` compares many code pairs at once with ``numpy.bitwise_count``.
"""

from __future__ import annotations

import numpy as np

from ..geometry import parabola_peak

BLOCK = 9


def _n_words(block: int) -> int:
    return (block * block + 63) // 64


def dense_codes(gray: np.ndarray, *, block: int = BLOCK) -> np.ndarray:
    """PISC code of the ``block x block`` neighbourhood centred at every pixel: ``(H, W, words)`` uint64.

    Pixels whose neighbourhood leaves the image compare against the replicated border.
    """
    if block % 2 != 1 or block < 3:
        raise ValueError(f"block must be odd and >= 3, got {block}")
    g = np.asarray(gray, dtype=np.float32)
    r = block // 2
    pad = np.pad(g, r, mode="edge")
    h, w = g.shape
    words = _n_words(block)
    out = np.zeros((h, w, words), dtype=np.uint64)
    bit = 0
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            ge = pad[r + dy:r + dy + h, r + dx:r + dx + w] >= g  # Eq. 7: neighbour >= centre
            out[..., bit // 64] |= ge.astype(np.uint64) << np.uint64(bit % 64)
            bit += 1
    return out


def block_correlation(a: np.ndarray, b: np.ndarray, *, block: int = BLOCK) -> np.ndarray:
    """Eq. 9, the number of agreeing bits ``N - popcount(a XOR b)``, over the last axis (the words)."""
    n = block * block
    x = np.bitwise_xor(np.asarray(a, dtype=np.uint64), np.asarray(b, dtype=np.uint64))
    return n - np.bitwise_count(x).sum(axis=-1).astype(np.int64)


def block_correlation_reference(fa: np.ndarray, fb: np.ndarray) -> int:
    """Eq. 9 written literally for two ``block x block`` grey blocks (the tests' oracle)."""
    fa = np.asarray(fa, dtype=np.float64)
    fb = np.asarray(fb, dtype=np.float64)
    c = fa.shape[0] // 2
    ba = fa >= fa[c, c]
    bb = fb >= fb[c, c]
    return int(np.sum(ba & bb) + np.sum(~ba & ~bb))


def match_blocks(prev_codes: np.ndarray, codes: np.ndarray, centres: np.ndarray, radius: int, *,
                 block: int = BLOCK) -> tuple[np.ndarray, np.ndarray]:
    """Best offset of each block within ``[-radius, radius]^2`` and its correlation.

    ``prev_codes`` are the blocks' codes ``(B, words)``; ``codes`` the dense codes of the current
    region; ``centres`` the blocks' centres ``(B, 2)`` as ``(row, col)`` in that region (offsets that
    leave the region are not tried).  Returns ``(offsets (B, 2) as (drow, dcol), corr (B,))``; the
    offsets are refined to sub-pixel precision by a parabola through the neighbouring correlations,
    so frame-to-frame matching does not accumulate the rounding of integer offsets.
    """
    h, w = codes.shape[:2]
    d = np.arange(-radius, radius + 1)
    dr, dc = np.meshgrid(d, d, indexing="ij")
    dr, dc = dr.ravel(), dc.ravel()
    rows = centres[:, 0:1] + dr[None, :]
    cols = centres[:, 1:2] + dc[None, :]
    inside = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
    cand = codes[np.clip(rows, 0, h - 1), np.clip(cols, 0, w - 1)]  # (B, O, words)
    corr = block_correlation(cand, prev_codes[:, None, :], block=block)
    corr = np.where(inside, corr, -1)
    # the smallest displacement among equal correlations (stable against flat blocks)
    order = np.argsort(dr * dr + dc * dc, kind="stable")
    best = order[np.argmax(corr[:, order], axis=1)]
    idx = np.arange(len(centres))
    # sub-pixel: a parabola through the best correlation and its neighbours along each axis
    side = 2 * radius + 1
    grid = corr.reshape(len(centres), side, side).astype(np.float64)
    bi, bj = best // side, best % side
    off = np.column_stack([dr[best], dc[best]]).astype(np.float64)
    for axis, (ii, jj) in enumerate(((bi, bj), (bi, bj))):
        lo_i, hi_i = (ii - 1, ii + 1) if axis == 0 else (ii, ii)
        lo_j, hi_j = (jj, jj) if axis == 0 else (jj - 1, jj + 1)
        ok = (lo_i >= 0) & (hi_i < side) & (lo_j >= 0) & (hi_j < side)
        a = np.where(ok, grid[idx, np.clip(lo_i, 0, side - 1), np.clip(lo_j, 0, side - 1)], 0.0)
        c = np.where(ok, grid[idx, np.clip(hi_i, 0, side - 1), np.clip(hi_j, 0, side - 1)], 0.0)
        b0 = grid[idx, ii, jj]
        den = a - 2.0 * b0 + c
        valid = ok & (den < 0) & (a >= 0) & (c >= 0)
        off[:, axis] += np.where(valid, np.clip(0.5 * (a - c) / np.where(valid, den, -1.0), -0.5, 0.5), 0.0)
    return off, corr[idx, best]


def region_offset(prev_codes: np.ndarray, codes: np.ndarray, centres: np.ndarray, radius: int, *,
                  block: int = BLOCK) -> tuple[np.ndarray, np.ndarray]:
    """The common displacement of all blocks: the offset with the largest summed correlation.

    The region whose blocks agree most (ch. 1: "the object has maximum number of matching blocks")
    moving rigidly; the summed correlation is smooth enough for a sub-pixel parabola.  Returns
    ``(offset (drow, dcol), corr of every block at the integer best offset)``.
    """
    h, w = codes.shape[:2]
    d = np.arange(-radius, radius + 1)
    dr, dc = np.meshgrid(d, d, indexing="ij")
    rows = centres[:, 0:1] + dr.ravel()[None, :]
    cols = centres[:, 1:2] + dc.ravel()[None, :]
    inside = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
    cand = codes[np.clip(rows, 0, h - 1), np.clip(cols, 0, w - 1)]
    corr = np.where(inside, block_correlation(cand, prev_codes[:, None, :], block=block), 0)
    side = 2 * radius + 1
    total = corr.sum(axis=0).reshape(side, side).astype(np.float64)
    i, j = np.unravel_index(int(np.argmax(total)), total.shape)

    di = parabola_peak(total[i - 1, j], total[i, j], total[i + 1, j]) if 0 < i < side - 1 else 0.0
    dj = parabola_peak(total[i, j - 1], total[i, j], total[i, j + 1]) if 0 < j < side - 1 else 0.0
    return np.array([i - radius + di, j - radius + dj]), corr[:, i * side + j]
