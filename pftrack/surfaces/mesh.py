"""Regular 2-D meshes for deformable-surface tracking (book ch. 13 §4.2-4.3, ch13.md §1.2-1.3).

A :class:`Grid` of ``rows x cols`` vertices spans a box uniformly (row-major, top row first).  Each
cell is split into two triangles along its main diagonal for the affine mesh (Eqs. 8-10), or used
whole for the bilinear mesh (Eq. 11).  Interpolation weights of any point are closed-form on the
regular grid: barycentric coordinates ``beta`` (3 non-zeros) or bilinear ``eta`` (4 non-zeros).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp


@dataclass(frozen=True)
class Grid:
    x0: float
    y0: float
    sx: float       # vertex spacing along x
    sy: float       # along y
    rows: int
    cols: int

    @classmethod
    def for_box(cls, box, rows: int, cols: int) -> Grid:
        x, y, w, h = map(float, box)
        if rows < 2 or cols < 2:
            raise ValueError("a mesh needs at least 2 x 2 vertices")
        return cls(x, y, w / (cols - 1), h / (rows - 1), int(rows), int(cols))

    @property
    def K(self) -> int:
        return self.rows * self.cols

    def scaled(self, f: float) -> Grid:
        return Grid(self.x0 * f, self.y0 * f, self.sx * f, self.sy * f, self.rows, self.cols)

    def vertices(self) -> np.ndarray:
        gx, gy = np.meshgrid(self.x0 + self.sx * np.arange(self.cols), self.y0 + self.sy * np.arange(self.rows))
        return np.stack([gx.ravel(), gy.ravel()], 1)

    def triangles(self) -> np.ndarray:
        """(2 (rows-1)(cols-1), 3): per cell ``(a, b, d)`` and ``(a, d, c)`` with a = top-left, b = top-right,
        c = bottom-left, d = bottom-right (counter-clockwise in image coordinates order)."""
        r, c = np.meshgrid(np.arange(self.rows - 1), np.arange(self.cols - 1), indexing="ij")
        a = (r * self.cols + c).ravel()
        b, cc, d = a + 1, a + self.cols, a + self.cols + 1
        return np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, cc], 1)])

    def quads(self) -> np.ndarray:
        r, c = np.meshgrid(np.arange(self.rows - 1), np.arange(self.cols - 1), indexing="ij")
        a = (r * self.cols + c).ravel()
        return np.stack([a, a + 1, a + self.cols, a + self.cols + 1], 1)

    def edges(self) -> np.ndarray:
        """Undirected edges of the triangulated grid (horizontal, vertical, diagonal)."""
        t = self.triangles()
        e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
        return np.unique(np.sort(e, axis=1), axis=0)


def interp_weights(grid: Grid, pts: np.ndarray, model: str = "affine") -> tuple[np.ndarray, np.ndarray]:
    """Vertex indices and weights ``(p, m)`` of points: ``m = 3`` barycentric (affine), ``4`` bilinear.

    Points outside the grid are clamped to the border cell (their weights extrapolate linearly)."""
    pts = np.asarray(pts, np.float64)
    u = (pts[:, 0] - grid.x0) / grid.sx
    v = (pts[:, 1] - grid.y0) / grid.sy
    c = np.clip(np.floor(u), 0, grid.cols - 2).astype(np.int64)
    r = np.clip(np.floor(v), 0, grid.rows - 2).astype(np.int64)
    s, t = u - c, v - r
    a = r * grid.cols + c
    b, cc, d = a + 1, a + grid.cols, a + grid.cols + 1
    if model == "bilinear":     # Eq. (11)
        idx = np.stack([a, b, cc, d], 1)
        w = np.stack([(1 - s) * (1 - t), s * (1 - t), t * (1 - s), s * t], 1)
        return idx, w
    if model != "affine":
        raise ValueError(f"unknown mesh model {model!r} (affine or bilinear)")
    lower = s >= t              # triangle (a, b, d), else (a, d, c)
    idx = np.where(lower[:, None], np.stack([a, b, d], 1), np.stack([a, d, cc], 1))
    w = np.where(lower[:, None], np.stack([1 - s, s - t, t], 1), np.stack([1 - t, s, t - s], 1))
    # (a, b, d): beta = (1 - s, s - t, t); (a, d, c): beta = (1 - t, s, t - s)
    return idx, w


def displacement_at(grid: Grid, pts: np.ndarray, d: np.ndarray, model: str = "affine") -> np.ndarray:
    """The mesh's displacement field ``D`` (Eq. 5) at points (P, 2), from vertex displacements ``d`` (K, 2). Points
    outside the mesh are clamped onto it first, so they take the border's displacement unchanged (no linear
    extrapolation)."""
    pts = np.asarray(pts, np.float64)
    x1, y1 = grid.x0 + grid.sx * (grid.cols - 1), grid.y0 + grid.sy * (grid.rows - 1)
    inner = np.c_[np.clip(pts[:, 0], grid.x0, x1), np.clip(pts[:, 1], grid.y0, y1)]
    idx, w = interp_weights(grid, inner, model)
    return np.einsum("pm,pmc->pc", w, np.asarray(d, np.float64)[idx])


def weights_matrix(idx: np.ndarray, w: np.ndarray, K: int) -> sp.csr_matrix:
    """The sparse ``p x K`` interpolation matrix B (Eq. 5's M rows)."""
    p, m = idx.shape
    return sp.csr_matrix((w.ravel(), idx.ravel(), np.arange(0, p * m + 1, m)), shape=(p, K))


def directional_laplacian(rows: int, cols: int, diagonal: bool = False) -> sp.csr_matrix:
    """Stacked directional Laplacians (L11459-11478): a row ``(-1, 2, -1)`` for every vertex that has
    both neighbours along a direction (horizontal, vertical, optionally the triangulation diagonal).
    Zero on any affine deformation of the grid, border included."""
    K = rows * cols
    ids = np.arange(K).reshape(rows, cols)
    blocks = [(ids[:, 1:-1], ids[:, :-2], ids[:, 2:]), (ids[1:-1, :], ids[:-2, :], ids[2:, :])]
    if diagonal:
        blocks.append((ids[1:-1, 1:-1], ids[:-2, :-2], ids[2:, 2:]))
    centre = np.concatenate([b[0].ravel() for b in blocks])
    lo = np.concatenate([b[1].ravel() for b in blocks])
    hi = np.concatenate([b[2].ravel() for b in blocks])
    n = len(centre)
    r = np.arange(n)
    return sp.csr_matrix((np.r_[np.full(n, 2.0), -np.ones(n), -np.ones(n)], (np.r_[r, r, r], np.r_[centre, lo, hi])),
                         shape=(n, K))


def umbrella_laplacian(grid: Grid, weights: str = "graph") -> sp.csr_matrix:
    """Eq. (22) ``L = V - A`` (``weights="graph"``), or the scaled forms with ``L_ii = -1`` and
    ``L_ij = 1/|N_i|`` (Eq. 23, ``"uniform"``) or inverse-distance weights (Eq. 24, ``"distance"``)."""
    K = grid.K
    e = grid.edges()
    i, j = np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]]
    A = sp.csr_matrix((np.ones(len(i)), (i, j)), shape=(K, K))
    deg = np.asarray(A.sum(1)).ravel()
    if weights == "graph":
        return (sp.diags(deg) - A).tocsr()
    if weights == "uniform":
        return (A.multiply(1.0 / deg[:, None]) - sp.eye(K)).tocsr()
    if weights == "distance":
        V = grid.vertices()
        inv = 1.0 / np.linalg.norm(V[i] - V[j], axis=1)
        Wd = sp.csr_matrix((inv, (i, j)), shape=(K, K))
        s = np.asarray(Wd.sum(1)).ravel()
        return (Wd.multiply(1.0 / s[:, None]) - sp.eye(K)).tocsr()
    raise ValueError(f"unknown weights {weights!r}")


def signed_areas(V: np.ndarray, tris: np.ndarray) -> np.ndarray:
    a, b, c = V[tris[:, 0]], V[tris[:, 1]], V[tris[:, 2]]
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


def keeps_orientation(V: np.ndarray, tris: np.ndarray, area0: np.ndarray) -> bool:
    """True when every triangle of the deformed mesh ``V`` has the sign of area it had (no fold)."""
    return bool(np.all(np.sign(signed_areas(V, tris)) == np.sign(area0)))


def fold_safe_step(V: np.ndarray, dd: np.ndarray, tris: np.ndarray, area0: np.ndarray, halvings: int = 4):
    """The fold check of ch13.md §4: the step along ``dd`` from vertex positions ``V``, halved until no triangle flips,
    at most ``halvings`` times (the last halving is not checked again).  Returns ``(step, halvings done)``."""
    step, done = 1.0, 0
    for _ in range(halvings):
        if keeps_orientation(V + step * dd, tris, area0):
            break
        step *= 0.5
        done += 1
    return step, done


def parse_mesh(text: str) -> tuple[int, int]:
    """``"7x7"`` -> (rows, cols) = (7, 7); ``"9x5"`` is 9 columns by 5 rows (width x height)."""
    try:
        c, r = (int(a) for a in str(text).lower().split("x"))
    except ValueError:
        raise ValueError(f"mesh {text!r}: expected COLSxROWS, e.g. 7x7") from None
    if c < 2 or r < 2:
        raise ValueError(f"mesh {text!r}: at least 2x2 vertices")
    return r, c
