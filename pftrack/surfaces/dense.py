"""The dense (per-pixel) deformation model of book ch. 13 (Eq. 7, ch13.md §1.2), solved by algebraic multigrid.

Every pixel of the model region carries its own displacement ``D(x)`` and, with the photometric warp, its own shading
ratio ``rho(x)``: ``N = 3p`` unknowns instead of the mesh's ``3K``.  The data term has no coupling between pixels
(ch13.md §1.7), so the data part of the normal equations is block diagonal with one 3 x 3 block per pixel; only the
smoothness couples them.  The per-pixel model is rank-deficient on its own (the aperture problem, L11143-11146), so
the directional-Laplacian smoothness (L11459-11478) is what makes the system solvable.

The same formulation as the mesh (:mod:`.solver`, ch13.md §1.8): the field is attached to the model image ``I_0``,
the residual of model pixel ``x_i`` is ``r_i = rho_i I_0(x_i) - I_n(x_i + D_i)``, Huber IRLS weights (Eqs. 29-30)
on the data and L2 smoothness ``Gamma = blockdiag(L, L, lambda_p L)`` (Eq. 38), with the normal equations

    (J^T W J / N + lam^2 G^T G / n_G) dtheta = -(J^T W r / N + lam^2 G^T G theta / n_G).

Unknowns are interleaved per pixel (``dx, dy, rho``), so the matrix is block-sparse with 3 x 3 blocks: smoothed
aggregation (PyAMG) with symmetric Gauss-Seidel smoothing, the chapter's multigrid V-cycles (L11733-11739), solves
it as a preconditioner of conjugate gradients.  Without PyAMG a sparse direct factorisation gives the same step.

Coarse to fine: at pyramid level ``l`` the unknowns are that level's pixels, a regular :class:`~.mesh.Grid` of
spacing ``2^l`` in full-resolution coordinates, and the field is carried between levels by bilinear interpolation
(only the level's increment is interpolated, so the finer field keeps its detail).  Displacements are in
full-resolution pixels at every level, as in the mesh solver.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import ParameterError
from .mesh import Grid, directional_laplacian, displacement_at, fold_safe_step, keeps_orientation, signed_areas
from .solver import _sample, gradients, huber_rho, huber_scale, pyramid, robust_terms


_CONTROLLER = None


def one_blas_thread():
    """A context in which BLAS runs on one thread.  The conjugate gradients' vector products are too small to gain
    from threads, and with another busy process on the machine OpenBLAS's waiting threads made them 3-4x slower."""
    global _CONTROLLER
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError:                                  # pragma: no cover - threadpoolctl is a dependency
        return contextlib.nullcontext()
    if _CONTROLLER is None:
        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER.limit(limits=1, user_api="blas")


def amg_available() -> bool:
    try:
        import pyamg  # noqa: F401
    except ImportError:
        return False
    return True


@dataclass(frozen=True)
class DenseSettings:
    lam: float = 3.0                 # the dense_lam default of deformable-mesh, chosen on tune seeds
    lam_p: float = 10.0
    levels: int = 4
    max_iter: int = 10
    tol: float = 0.01
    coarse_tol: float = 0.05
    huber_k: float = 1.345
    photometric: bool = True
    rho_min: float = 0.2
    rho_max: float = 5.0
    solver: str = "auto"          # "amg", "lu" (preconditioned CG), "direct" (sparse LU), "auto": see choose_method
    rtol: float = 1e-3            # relative residual of each Gauss-Newton step's solve (an inexact Newton step)
    direct_below: int = 3000      # systems with fewer unknowns are solved by sparse LU


def level_grid(box, level: int, shape: tuple[int, int]) -> Grid:
    """The pixels of pyramid level ``level`` inside ``box`` (full-resolution x, y, w, h) as a grid in full-resolution
    coordinates: level pixel ``i`` sits at full-resolution ``2^level i`` (the ``pyrDown`` convention)."""
    s = 2.0 ** level
    x, y, w, h = map(float, box)
    c0, c1 = max(int(np.ceil(x / s)), 0), min(int(np.floor((x + w) / s)), shape[1] - 1)
    r0, r1 = max(int(np.ceil(y / s)), 0), min(int(np.floor((y + h) / s)), shape[0] - 1)
    if c1 - c0 < 2 or r1 - r0 < 2:
        raise ValueError(f"box {box} has fewer than 3 x 3 pixels at pyramid level {level}")
    return Grid(c0 * s, r0 * s, s, s, r1 - r0 + 1, c1 - c0 + 1)


def smoothness_matrix(grid: Grid, lam: float, lam_p: float, photometric: bool):
    """``(lam^2/n_G) G^T G`` in interleaved order, ``L^T L`` of the grid's directional Laplacian and the number of
    rows ``n_G`` of ``Gamma = blockdiag(L, L[, lam_p L])`` (Eqs. 37-38)."""
    L = directional_laplacian(grid.rows, grid.cols)
    LtL = (L.T @ L).tocsr()
    c = [1.0, 1.0] + ([lam_p ** 2] if photometric else [])
    n_gamma = L.shape[0] * len(c)
    return (lam ** 2 / max(n_gamma, 1)) * sp.kron(LtL, sp.diags(c), format="csr"), LtL, n_gamma


def data_blocks(Gx: np.ndarray, Gy: np.ndarray, I0: np.ndarray, r: np.ndarray, w: np.ndarray, N: int,
                photometric: bool) -> tuple[sp.bsr_matrix, np.ndarray]:
    """``J^T W J / N`` (block diagonal, one ``m x m`` block per pixel) and ``J^T W r / N`` (interleaved) from the
    per-pixel Jacobian rows ``(G_x, G_y[, I_0])`` of Eq. (36)."""
    J = np.stack([Gx, Gy, I0] if photometric else [Gx, Gy], 1)          # (p, m)
    p, m = J.shape
    wJ = (w / N)[:, None] * J
    blocks = wJ[:, :, None] * J[:, None, :]                             # (p, m, m)
    A = sp.bsr_matrix((blocks, np.arange(p), np.arange(p + 1)), shape=(p * m, p * m))
    return A, (wJ * r[:, None]).ravel()


#: Up to this many pixels on a level, ``"auto"`` preconditions with sparse LU factors: measured 2.2x faster than the
#: multigrid V-cycle at 48 000, 109 000 and 221 000 pixels (docs/surfaces.md), but their memory grows faster than the
#: region (about 1.7 GB more at 221 000 pixels), so larger regions use multigrid.
LU_PIXELS = 250_000


def choose_method(setting: str, pixels: int) -> str:
    """The preconditioner of a level: ``setting`` unless it is ``"auto"``, then LU factors up to
    :data:`LU_PIXELS` pixels and multigrid above (LU when PyAMG is not installed)."""
    if setting != "auto":
        return setting
    return "amg" if pixels > LU_PIXELS and amg_available() else "lu"


class ChannelPreconditioner:
    """An approximate inverse of the normal matrix, one scalar solver per kind of unknown (``dx``, ``dy``, ``rho``).

    Each kind's own block is its smoothness operator plus the diagonal of its data term; the data's coupling between
    the kinds of one pixel is left to the conjugate gradients.  ``"amg"``: smoothed aggregation (PyAMG) with the
    constant and the two linear fields as near-null-space candidates (the directional Laplacian is blind to all
    three), symmetric Gauss-Seidel smoothing, one V-cycle per application.  ``"lu"``: a sparse LU of each block."""

    def __init__(self, A: sp.spmatrix, m: int, V: np.ndarray, method: str):
        A = A.tocsr()
        p = A.shape[0] // m
        self.m, self.p = m, p
        self._apply = []
        x, y = V[:, 0] - V[:, 0].mean(), V[:, 1] - V[:, 1].mean()
        scale = max(float(np.abs(x).max()), float(np.abs(y).max()), 1.0)
        B = np.stack([np.ones(p), x / scale, y / scale], 1)
        for a in range(m):
            Aa = A[a::m, a::m].tocsr()
            if method == "amg":
                import pyamg

                ml = pyamg.smoothed_aggregation_solver(Aa, B=B, symmetry="symmetric", max_coarse=300,
                                                       smooth=("energy", {"krylov": "cg", "maxiter": 2}))
                self._apply.append(ml.aspreconditioner(cycle="V").matvec)
            else:
                self._apply.append(spla.splu(Aa.tocsc(), permc_spec="MMD_AT_PLUS_A").solve)

    def __call__(self, v: np.ndarray) -> np.ndarray:
        v = v.reshape(self.p, self.m)
        out = np.empty_like(v)
        for a, f in enumerate(self._apply):
            out[:, a] = f(np.ascontiguousarray(v[:, a]))
        return out.ravel()

    def operator(self) -> spla.LinearOperator:
        n = self.p * self.m
        return spla.LinearOperator((n, n), matvec=self, dtype=np.float64)


def solve_spd(A: sp.spmatrix, b: np.ndarray, M: spla.LinearOperator | None, rtol: float, x0=None,
              maxiter: int = 80) -> tuple[np.ndarray, bool]:
    """``A x = b`` for the symmetric positive definite normal matrix: conjugate gradients preconditioned by ``M``, or
    a sparse LU when ``M`` is None.  Returns ``(x, converged)``; a truncated conjugate-gradient iterate is still a
    descent direction, so the caller may use it."""
    if M is None:
        return spla.spsolve(A.tocsc(), b), True
    x, info = spla.cg(A, b, x0=x0, rtol=rtol, maxiter=maxiter, M=M)
    return x, info == 0


class DenseLevel:
    """One pyramid level: its pixel grid, the model intensities there and the constant smoothness matrix."""

    def __init__(self, I0_level: np.ndarray, box, level: int, s: DenseSettings):
        self.level, self.f = level, 0.5 ** level
        self.grid = level_grid(box, level, I0_level.shape)
        self.V = self.grid.vertices()                   # full-resolution positions of the level's pixels
        self.pts = self.V * self.f                      # their level coordinates (integers)
        ij = np.rint(self.pts).astype(np.int64)
        self.I0 = I0_level[ij[:, 1], ij[:, 0]].astype(np.float64)
        self.S, self.LtL, self.n_gamma = smoothness_matrix(self.grid, s.lam, s.lam_p, s.photometric)
        self.tris = self.grid.triangles()
        self.area0 = signed_areas(self.V, self.tris)
        self.M = None                                   # the preconditioner, built on the first step, then kept


class DenseSolver:
    """Everything that stays constant for a model image and region; :meth:`solve` registers one frame."""

    def __init__(self, I0: np.ndarray, box, settings: DenseSettings = DenseSettings()):
        if settings.solver not in ("auto", "amg", "lu", "direct"):
            raise ParameterError(f"unknown solver {settings.solver!r} (auto, amg, lu or direct)")
        if settings.solver == "amg" and not amg_available():
            raise ParameterError("the dense model's multigrid solver needs PyAMG: pip install 'pftrack[dense]' "
                                 "(or dense_solver=lu)")
        self.s = settings
        self.method = settings.solver
        self.box = tuple(map(float, box))
        pyr = pyramid(I0, settings.levels)
        self.levels = [DenseLevel(p, box, lvl, settings) for lvl, p in enumerate(pyr)]
        self.grid = self.levels[0].grid                  # the field's pixels at full resolution
        self.m = 3 if settings.photometric else 2

    def rebase(self, I0: np.ndarray) -> None:
        """A new model image over the same region (frame-to-frame chaining); the preconditioners are kept."""
        for lv, img in zip(self.levels, pyramid(I0, self.s.levels)):
            ij = np.rint(lv.pts).astype(np.int64)
            lv.I0 = img[ij[:, 1], ij[:, 0]].astype(np.float64)

    @property
    def K(self) -> int:
        return self.grid.K

    def residual(self, lv: DenseLevel, img: np.ndarray, D: np.ndarray, rho: np.ndarray):
        warped = lv.pts + D * lv.f
        In = _sample(img, warped)
        psi = rho if self.s.photometric else 1.0
        return psi * lv.I0 - In, warped

    def normal_equations(self, lv: DenseLevel, img, gx, gy, D, rho, vH=None):
        """``(A, b, r, ok, vH)`` of one IRLS step at a level (``A`` sparse, unknowns interleaved per pixel)."""
        r, warped = self.residual(lv, img, D, rho)
        r, ok, w, Gx, Gy, N, vH = robust_terms(r, warped, gx, gy, lv.f, self.s.huber_k, vH)
        A, b = data_blocks(Gx, Gy, lv.I0, r, w, N, self.s.photometric)
        theta = np.c_[D, rho] if self.s.photometric else D
        A = (A + lv.S).tocsr()
        b = b + lv.S @ theta.ravel()
        return A, b, r, ok, vH

    def energies(self, D, rho, img: np.ndarray, level: int = 0) -> tuple[float, float]:
        """``(E_D, E_S)`` as normalised in ch13.md §2 (``img`` is the frame at pyramid ``level``)."""
        lv = self.levels[level]
        r, _ = self.residual(lv, img, D, rho)
        ok = np.isfinite(r)
        r = np.where(ok, r, 0.0)
        e_d = float(np.sum(huber_rho(r, huber_scale(r[ok], self.s.huber_k)) * ok) / max(ok.sum(), 1))
        e_s = float(D[:, 0] @ lv.LtL @ D[:, 0] + D[:, 1] @ lv.LtL @ D[:, 1])
        if self.s.photometric:
            e_s += float(self.s.lam_p ** 2 * rho @ lv.LtL @ rho)
        return e_d, e_s / max(lv.n_gamma, 1)

    def _at_level(self, lv: DenseLevel, D: np.ndarray, rho: np.ndarray, grid: Grid):
        """A field given on ``grid`` (displacements and shading), sampled at the level's pixels (bilinear)."""
        Dl = displacement_at(grid, lv.V, D, "bilinear")
        rl = displacement_at(grid, lv.V, np.c_[rho, rho], "bilinear")[:, 0]
        return Dl, rl

    def _step(self, lv: DenseLevel, A: sp.csr_matrix, b: np.ndarray) -> np.ndarray | None:
        """The Gauss-Newton step ``-A^-1 b``.  The level's preconditioner is built from the first system it meets and
        kept across iterations and frames (the smoothness, which dominates it, never changes).  When the conjugate
        gradients do not converge with it, it is rebuilt from the current system, at most once per level and frame,
        and the (possibly truncated) iterate is the step."""
        method = choose_method(self.method, len(lv.V))
        if method == "direct" or A.shape[0] < self.s.direct_below:
            delta, ok = solve_spd(A, -b, None, self.s.rtol)
        else:
            if lv.M is None:
                lv.M = ChannelPreconditioner(A, self.m, lv.V, method).operator()
            delta, ok = solve_spd(A, -b, lv.M, self.s.rtol)
            if not ok and lv.level not in self._rebuilt:
                self._rebuilt.add(lv.level)
                lv.M = ChannelPreconditioner(A, self.m, lv.V, method).operator()
                delta, ok = solve_spd(A, -b, lv.M, self.s.rtol, x0=delta)
        return delta if np.all(np.isfinite(delta)) else None

    def solve(self, frame_gray: np.ndarray, D0: np.ndarray, rho0: np.ndarray):
        """Coarse-to-fine IRLS from the full-resolution field ``(D0 (K, 2), rho0 (K,))``; returns ``D, rho, info``."""
        with one_blas_thread():
            return self._solve(frame_gray, D0, rho0)

    def _solve(self, frame_gray: np.ndarray, D0: np.ndarray, rho0: np.ndarray):
        pyr = pyramid(frame_gray, self.s.levels)
        D0 = np.asarray(D0, np.float64)
        rho0 = np.asarray(rho0, np.float64)
        folds = iters = 0
        self._rebuilt: set[int] = set()
        inc_D = inc_r = None
        prev = None
        for lvl in range(self.s.levels - 1, -1, -1):
            lv = self.levels[lvl]
            D, rho = (D0.copy(), rho0.copy()) if lvl == 0 else self._at_level(lv, D0, rho0, self.grid)
            start_D, start_r = D.copy(), rho.copy()
            if inc_D is not None:                       # the coarser level's increment, interpolated
                dD, dr = self._at_level(lv, inc_D, inc_r, prev.grid)
                D, rho = D + dD, np.clip(rho + dr, self.s.rho_min, self.s.rho_max)
            img = pyr[lvl]
            gx, gy = gradients(img)
            for _ in range(self.s.max_iter):
                A, b, r, ok, _ = self.normal_equations(lv, img, gx, gy, D, rho)
                if ok.sum() < 8:
                    break
                A = A + 1e-10 * sp.identity(A.shape[0], format="csr")
                delta = self._step(lv, A, b)
                if delta is None:
                    break
                delta = delta.reshape(-1, self.m)
                dd, dr = delta[:, :2], (delta[:, 2] if self.s.photometric else 0.0)
                step, halvings = fold_safe_step(lv.V + D, dd, lv.tris, lv.area0)    # every pixel triangle
                folds += halvings
                D = D + step * dd
                if self.s.photometric:
                    rho = np.clip(rho + step * dr, self.s.rho_min, self.s.rho_max)
                iters += 1
                move = float(np.sqrt(np.mean(np.sum((step * dd) ** 2, 1)))) * lv.f      # RMS over the pixels
                if move < (self.s.tol if lvl == 0 else max(self.s.tol, self.s.coarse_tol)):
                    break
            inc_D, inc_r, prev = D - start_D, rho - start_r, lv
        r, _ = self.residual(self.levels[0], pyr[0], D, rho)
        ok = np.isfinite(r)
        rms = float(np.sqrt(np.mean(r[ok] ** 2))) if ok.any() else float("inf")
        lv0 = self.levels[0]
        folded = not keeps_orientation(lv0.V + D, lv0.tris, lv0.area0)
        return D, rho, {"rms": rms, "iterations": iters, "fold_halvings": folds, "folded": folded,
                        "valid_fraction": float(ok.mean()),
                        "solver": choose_method(self.method, self.K)}


def dense_jacobian(solver: DenseSolver, level: int, img, gx, gy, D) -> np.ndarray:
    """The explicit ``p x 3p`` (interleaved) Jacobian of Eq. (36) for the dense model (tests, small problems)."""
    lv = solver.levels[level]
    warped = lv.pts + D * lv.f
    Gx = np.nan_to_num(_sample(gx, warped)) * (-lv.f)
    Gy = np.nan_to_num(_sample(gy, warped)) * (-lv.f)
    rows = [Gx, Gy] + ([lv.I0] if solver.s.photometric else [])
    p, m = len(Gx), len(rows)
    J = np.zeros((p, p * m))
    for a, v in enumerate(rows):
        J[np.arange(p), np.arange(p) * m + a] = v
    return J
