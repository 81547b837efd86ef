"""Joint colour histograms of person patches, carried through a per-channel BTF (pftrack's extension of ch. 11).

The chapter compares the three channels' histograms one by one (Eqs. 23–24): a red shirt over blue jeans and a blue
shirt over red jeans have the same marginals in a region that holds both. A joint histogram counts colours, not
levels: each region's pixels fall into ``levels³`` cells of (R, G, B).

A BTF maps each channel on its own (Eq. 12), so it carries a joint histogram cell by cell. The histograms are kept
at ``JOINT_LEVELS`` levels a channel (bins of 8 grey levels) and compared at ``COMPARE_LEVELS`` (bins of 32). A cell
spreads over the cells that the BTF maps its levels to, in the share of its levels that go to each (assumed evenly
used within the cell). For a BTF constant on each bin of 8 levels this equals histogramming the mapped pixels
(tested).

Histograms are sparse ``(cells, masses)``: flat cell indices ``region * levels³ + (r * levels + g) * levels + b``
and their masses, summing to 1 over the box.
"""

from __future__ import annotations

import numpy as np

from .appearance import box_regions, rgb_patch

__all__ = ["COMPARE_LEVELS", "JOINT_LEVELS", "joint_histogram", "joint_similarity_matrix", "mean_sparse",
           "push_joint", "transfer_matrices"]

JOINT_LEVELS = 32    # levels a channel as kept (bins of 8 grey levels)
COMPARE_LEVELS = 8   # levels a channel as compared (bins of 32 grey levels)


def joint_histogram(frame: np.ndarray, box, feature: str, *, fg: np.ndarray | None = None,
                    levels: int = JOINT_LEVELS, parts: tuple[np.ndarray, np.ndarray, int] | None = None,
                    rgb: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, int]:
    """``(cells, masses, regions)``: the sparse joint RGB histogram of the box's regions (:func:`box_regions`;
    ``parts``: that of these arguments, when already computed; ``rgb``: its patch in RGB, when already converted),
    foreground pixels only when ``fg`` is given; the masses sum to 1 (none when no pixel counts)."""
    if 256 % levels:
        raise ValueError("levels must divide 256")
    patch, lab, n = parts if parts is not None else box_regions(frame, box, feature, fg=fg)
    ok = lab >= 0
    if not ok.any():
        return np.zeros(0, np.int64), np.zeros(0), n
    rgb = (rgb_patch(patch) if rgb is None else rgb)[ok].astype(np.int64) // (256 // levels)
    flat = lab[ok].astype(np.int64) * levels ** 3 + (rgb[:, 0] * levels + rgb[:, 1]) * levels + rgb[:, 2]
    cells, counts = np.unique(flat, return_counts=True)
    return cells, counts / counts.sum(), n


def mean_sparse(hists: list[tuple[np.ndarray, np.ndarray]], count: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The mean of sparse histograms (each ``(cells, masses)``), sparse, over ``count`` of them (default: as many
    as given; more when empty histograms, of frames without a foreground pixel in the box, count too, as in the
    mean of the channels' histograms of :func:`pftrack.multicam.handover.describe_tracks`)."""
    n = len(hists) if count is None else max(int(count), len(hists))
    if not hists:
        return np.zeros(0, np.int64), np.zeros(0)
    cells = np.concatenate([c for c, _ in hists])
    masses = np.concatenate([m for _, m in hists])
    uniq, inv = np.unique(cells, return_inverse=True)
    return uniq, np.bincount(inv, weights=masses, minlength=len(uniq)) / n


def transfer_matrices(lut: np.ndarray, levels_in: int = JOINT_LEVELS,
                      levels_out: int = COMPARE_LEVELS) -> np.ndarray:
    """``(3, levels_in, levels_out)``: for each channel, the share of the grey levels of each input bin that the
    table ``lut`` ``(3, 256)`` maps (rounded, clipped) into each output bin."""
    idx = np.clip(np.round(np.asarray(lut, dtype=np.float64)), 0, 255).astype(np.int64)
    win, wout = 256 // levels_in, 256 // levels_out
    T = np.zeros((3, levels_in, levels_out))
    src = np.arange(256) // win
    for c in range(3):
        np.add.at(T[c], (src, idx[c] // wout), 1.0 / win)
    return T


def push_joint(cells: np.ndarray, masses: np.ndarray, regions: int, lut: np.ndarray, *,
               levels_in: int = JOINT_LEVELS, levels_out: int = COMPARE_LEVELS,
               transfer: np.ndarray | None = None) -> np.ndarray:
    """The dense ``(regions * levels_out³,)`` histogram of a sparse joint histogram carried through ``lut``
    (:func:`transfer_matrices`, or ``transfer`` when given: those of ``lut``, computed once for many histograms);
    its mass is the input's."""
    T = transfer_matrices(lut, levels_in, levels_out) if transfer is None else transfer
    dense = np.zeros(regions * levels_in ** 3)
    np.add.at(dense, np.asarray(cells, dtype=np.int64), np.asarray(masses, dtype=np.float64))
    d = dense.reshape(regions, levels_in, levels_in, levels_in)  # region, r, g, b
    d = np.tensordot(d, T[2], axes=([3], [0]))                   # region, r, g, b'
    d = np.tensordot(d, T[1], axes=([2], [0]))                   # region, r, b', g'
    d = np.tensordot(d, T[0], axes=([1], [0]))                   # region, b', g', r'
    return d.transpose(0, 3, 2, 1).reshape(-1)


def joint_similarity_matrix(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``(len(A), len(B))`` similarities ``1 − D_B`` (Eq. 24 on one joint histogram) of two stacks of dense
    histograms (each the mean over a track's sampled frames, so below unit mass where some had no foreground)."""
    bc = np.sqrt(np.asarray(A, dtype=np.float64)) @ np.sqrt(np.asarray(B, dtype=np.float64)).T
    return 1.0 - np.sqrt(np.clip(1.0 - bc, 0.0, 1.0))
