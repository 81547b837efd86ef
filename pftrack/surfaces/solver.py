"""Robust Gauss-Newton registration of a deformable mesh with a photometric warp (book ch. 13 §5,
ch13.md §1.4-1.8).

The warp runs from the model image ``I_0`` (mesh attached to it, vertices ``v_k``) to frame ``I_n``:
vertices move to ``v_k + d_k`` and the shading ratio at a model pixel is ``psi_p = sum_k beta_k rho_k``
(Eqs. 2-5, 8-11).  Per model pixel ``x_i`` the residual is (§1.8, the roles of Eq. 35's images swapped)

    r_i = psi_p(x_i) I_0(x_i) - I_n(x_i + D(x_i)),

with Jacobian row ``[-g_x B, -g_y B, I_0 B_p]`` (Eq. 36).  Huber weights (Eqs. 29-30, MAD scale) on the
data, L2 Tikhonov smoothness ``Gamma = blockdiag(L, L, lambda_p L_p)`` (Eqs. 37-38) with the directional
Laplacian, and the normal equations of Eq. (32) with the ``lambda`` fixed on the smoothness residual:

    (J^T W J / N + lam^2 G^T G / n_G) dtheta = -(J^T W r / N + lam^2 G^T G theta / n_G)

solved coarse to fine on an image pyramid.  Displacements are kept in full-resolution pixels at every
level, which scales the data term by ``2^-l`` and is the ``lambda_l = lambda 2^l`` rule of ch13.md §2.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy.linalg import cho_factor, cho_solve

from .._numba import njit, numba_enabled
from .mesh import (
    Grid,
    directional_laplacian,
    fold_safe_step,
    interp_weights,
    keeps_orientation,
    signed_areas,
    weights_matrix,
)


@njit(cache=True)
def _assemble_kernel(ig, wg, ip, wp, Gx, Gy, I0, r, w, Kg, photometric, A, b):  # pragma: no cover - compiled
    """``A += J^T W J`` and ``b += J^T W r`` one pixel at a time (upper triangle, then mirrored)."""
    p, m = ig.shape
    mp = ip.shape[1]
    nn = 2 * m + (mp if photometric else 0)
    idx = np.empty(nn, np.int64)
    val = np.empty(nn)
    for i in range(p):
        wi = w[i]
        if wi == 0.0:
            continue
        for a in range(m):
            idx[a] = ig[i, a]
            val[a] = Gx[i] * wg[i, a]
            idx[m + a] = Kg + ig[i, a]
            val[m + a] = Gy[i] * wg[i, a]
        if photometric:
            for a in range(mp):
                idx[2 * m + a] = 2 * Kg + ip[i, a]
                val[2 * m + a] = I0[i] * wp[i, a]
        ri = r[i]
        for a in range(nn):
            va = wi * val[a]
            ia = idx[a]
            b[ia] += va * ri
            for c in range(nn):
                ic = idx[c]
                if ic >= ia:
                    A[ia, ic] += va * val[c]
    n = A.shape[0]
    for i in range(n):
        for j in range(i + 1, n):
            A[j, i] = A[i, j]


def huber_weights(r: np.ndarray, k: float) -> np.ndarray:
    """Eq. (30): ``1`` where ``|r| <= k``, else ``k/|r|``."""
    a = np.abs(r)
    return np.where(a <= k, 1.0, k / np.maximum(a, 1e-300))


def huber_rho(r: np.ndarray, k: float) -> np.ndarray:
    """Eq. (29) with the square restored: ``r^2/2`` inside, ``k|r| - k^2/2`` outside."""
    a = np.abs(r)
    return np.where(a <= k, 0.5 * r * r, k * a - 0.5 * k * k)


def huber_scale(r: np.ndarray, k: float = 1.345, floor: float = 1 / 255) -> float:
    """``k * 1.4826 * MAD(r)``, at least ``floor``."""
    if r.size == 0:
        return floor
    if r.size > 20000:          # the MAD of a regular subsample is as good and 4x cheaper
        r = r[::4]
    return max(k * 1.4826 * float(np.median(np.abs(r - np.median(r)))), floor)


def robust_terms(r: np.ndarray, warped: np.ndarray, gx: np.ndarray, gy: np.ndarray, f: float, huber_k: float,
                 vH: float | None = None):
    """The robust data terms of one IRLS step, shared by the mesh and the dense model: residuals with the pixels that
    fell outside ``I_n`` zeroed (pitfall 9), Huber weights (Eqs. 29-30, MAD scale unless ``vH`` is given), the frame
    gradients at the warped points times ``-f`` (Eq. 36 with displacements in full-resolution pixels), and the count
    of valid pixels.  Returns ``(r, ok, w, Gx, Gy, N, vH)``."""
    ok = np.isfinite(r)
    r = np.where(ok, r, 0.0)
    if vH is None:
        vH = huber_scale(r[ok], huber_k)
    w = huber_weights(r, vH) * ok
    Gx = np.nan_to_num(_sample(gx, warped)) * (-f)
    Gy = np.nan_to_num(_sample(gy, warped)) * (-f)
    return r, ok, w, Gx, Gy, max(int(ok.sum()), 1), vH


@dataclass(frozen=True)
class SolverSettings:
    lam: float = 0.5
    lam_p: float = 10.0
    levels: int = 4
    max_iter: int = 10
    tol: float = 0.01
    coarse_tol: float = 0.05      # coarser levels only need to land in the next level's capture range
    huber_k: float = 1.345
    photometric: bool = True
    model: str = "affine"
    rho_min: float = 0.2
    rho_max: float = 5.0
    max_pixels: int = 0           # per level; 0 = every pixel


class _Pairs:
    """Index pairs for assembling ``B_a^T diag(c) B_b`` with one ``bincount``."""

    def __init__(self, ia, wa, Ka, ib, wb, Kb):
        self.flat = (ia[:, :, None] * Kb + ib[:, None, :]).reshape(len(ia), -1)
        self.prod = (wa[:, :, None] * wb[:, None, :]).reshape(len(ia), -1)
        self.shape = (Ka, Kb)
        self._flat_r = self.flat.ravel()

    def block(self, c: np.ndarray) -> np.ndarray:
        w = (c[:, None] * self.prod).ravel()
        return np.bincount(self._flat_r, w, self.shape[0] * self.shape[1]).reshape(self.shape)


class LevelModel:
    """The model pixels of one pyramid level with their constant interpolation weights."""

    def __init__(self, I0: np.ndarray, grid_g: Grid, grid_p: Grid, level: int, model: str, max_pixels: int = 0):
        f = 0.5 ** level
        self.level, self.f = level, f
        gg = grid_g.scaled(f)
        x1, y1 = gg.x0 + gg.sx * (gg.cols - 1), gg.y0 + gg.sy * (gg.rows - 1)
        xs = np.arange(max(int(np.ceil(gg.x0)), 0), min(int(np.floor(x1)), I0.shape[1] - 1) + 1)
        ys = np.arange(max(int(np.ceil(gg.y0)), 0), min(int(np.floor(y1)), I0.shape[0] - 1) + 1)
        if max_pixels and len(xs) * len(ys) > max_pixels:   # speed bound: a regular subset of the region's pixels
            step = int(np.ceil(np.sqrt(len(xs) * len(ys) / max_pixels)))
            xs, ys = xs[step // 2::step], ys[step // 2::step]
        X, Y = np.meshgrid(xs, ys)
        self.pts = np.stack([X.ravel(), Y.ravel()], 1).astype(np.float64)
        self.shape = X.shape
        self.I0 = I0[Y.ravel(), X.ravel()].astype(np.float64)
        self.ig, self.wg = interp_weights(gg, self.pts, model)
        self.ip, self.wp = interp_weights(grid_p.scaled(f), self.pts, model)
        Kg, Kp = grid_g.K, grid_p.K
        self.Kg, self.Kp = Kg, Kp
        self.Bg = weights_matrix(self.ig, self.wg, Kg)
        self.Bp = weights_matrix(self.ip, self.wp, Kp)
        self._pairs = None          # bincount tables of the NumPy path, built on first use

    def pairs(self) -> tuple[_Pairs, _Pairs, _Pairs]:
        """``(gg, gp, pp)`` index tables for ``B_a^T diag(c) B_b`` (only the NumPy reference path needs them)."""
        if self._pairs is None:
            self._pairs = (_Pairs(self.ig, self.wg, self.Kg, self.ig, self.wg, self.Kg),
                           _Pairs(self.ig, self.wg, self.Kg, self.ip, self.wp, self.Kp),
                           _Pairs(self.ip, self.wp, self.Kp, self.ip, self.wp, self.Kp))
        return self._pairs

    def displacement(self, d: np.ndarray) -> np.ndarray:
        """Per-pixel displacement (full-resolution px) from vertex displacements ``d`` (K, 2)."""
        return self.Bg @ d

    def shading(self, rho: np.ndarray) -> np.ndarray:
        return self.Bp @ rho

    def tvec(self, idx, w, c, K) -> np.ndarray:
        return np.bincount(idx.ravel(), (c[:, None] * w).ravel(), K)


@njit(cache=True)
def _bilinear_kernel(img, x, y, out):  # pragma: no cover - compiled
    h, w = img.shape
    for i in range(x.shape[0]):
        xi, yi = x[i], y[i]
        if not (xi >= 0.0 and yi >= 0.0 and xi <= w - 1 and yi <= h - 1):
            out[i] = np.nan
            continue
        x0 = min(int(xi), w - 2) if w > 1 else 0
        y0 = min(int(yi), h - 2) if h > 1 else 0
        tx, ty = xi - x0, yi - y0
        out[i] = ((1 - ty) * ((1 - tx) * img[y0, x0] + tx * img[y0, x0 + 1])
                  + ty * ((1 - tx) * img[y0 + 1, x0] + tx * img[y0 + 1, x0 + 1]))


def _bilinear_numpy(img, x, y):
    h, w = img.shape
    ok = (x >= 0) & (y >= 0) & (x <= w - 1) & (y <= h - 1)
    x0 = np.clip(np.floor(x).astype(np.int64), 0, w - 2)
    y0 = np.clip(np.floor(y).astype(np.int64), 0, h - 2)
    tx, ty = x - x0, y - y0
    v = ((1 - ty) * ((1 - tx) * img[y0, x0] + tx * img[y0, x0 + 1])
         + ty * ((1 - tx) * img[y0 + 1, x0] + tx * img[y0 + 1, x0 + 1]))
    return np.where(ok, v, np.nan)


def _sample(img: np.ndarray, pts: np.ndarray, shape=None) -> np.ndarray:
    """Exact bilinear samples at ``pts`` (NaN outside the image).  ``cv2.remap`` quantises coordinates to
    1/32 pixel, which would floor the registration's accuracy and break its derivatives."""
    x = np.ascontiguousarray(pts[:, 0], dtype=np.float64)
    y = np.ascontiguousarray(pts[:, 1], dtype=np.float64)
    if numba_enabled():
        out = np.empty(len(x))
        _bilinear_kernel(img, x, y, out)
        return out
    return _bilinear_numpy(img, x, y)


def gradients(img: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Central-difference gradients (Scharr, normalised to unit gain) of a float32 image."""
    gx = cv2.Scharr(img, cv2.CV_32F, 1, 0) / 32.0
    gy = cv2.Scharr(img, cv2.CV_32F, 0, 1) / 32.0
    return gx, gy


def pyramid(img: np.ndarray, levels: int) -> list[np.ndarray]:
    out = [img.astype(np.float32)]
    for _ in range(levels - 1):
        out.append(cv2.pyrDown(out[-1]))
    return out


class MeshSolver:
    """Everything that stays constant for a model image and mesh: pyramid, weights, smoothness."""

    def __init__(self, I0: np.ndarray, grid_g: Grid, grid_p: Grid, settings: SolverSettings = SolverSettings()):
        self.s = settings
        self.grid_g, self.grid_p = grid_g, grid_p
        self.V0 = grid_g.vertices()
        self.tris = grid_g.triangles()
        self.area0 = signed_areas(self.V0, self.tris)
        pyr = pyramid(I0, settings.levels)
        self.levels = [LevelModel(p, grid_g, grid_p, lvl, settings.model, settings.max_pixels)
                       for lvl, p in enumerate(pyr)]
        Lg = directional_laplacian(grid_g.rows, grid_g.cols)
        Lp = directional_laplacian(grid_p.rows, grid_p.cols)
        self.LtL_g = (Lg.T @ Lg).toarray()
        self.LtL_p = (Lp.T @ Lp).toarray()
        self.n_gamma = 2 * Lg.shape[0] + (Lp.shape[0] if settings.photometric else 0)
        self.Kg, self.Kp = grid_g.K, grid_p.K

    # ---- one IRLS step (Eqs. 27-32) ------------------------------------------------------
    def residual(self, lv: LevelModel, img, d, rho):
        warped = lv.pts + lv.displacement(d) * lv.f
        In = _sample(img, warped, lv.shape)
        psi = lv.shading(rho) if self.s.photometric else 1.0
        return psi * lv.I0 - In, warped

    def normal_equations(self, lv: LevelModel, img, gx, gy, d, rho, vH=None):
        r, warped = self.residual(lv, img, d, rho)
        r, ok, w, Gx, Gy, N, vH = robust_terms(r, warped, gx, gy, lv.f, self.s.huber_k, vH)
        Kg, Kp = self.Kg, self.Kp
        n = 2 * Kg + (Kp if self.s.photometric else 0)
        A = np.zeros((n, n))
        b = np.zeros(n)
        if numba_enabled():
            _assemble_kernel(lv.ig, lv.wg, lv.ip, lv.wp, Gx, Gy, lv.I0, r, w, Kg, self.s.photometric, A, b)
        else:
            self._assemble_numpy(lv, Gx, Gy, r, w, A, b)
        A /= N
        b /= N
        lam2 = self.s.lam ** 2 / max(self.n_gamma, 1)
        A[:Kg, :Kg] += lam2 * self.LtL_g
        A[Kg:2 * Kg, Kg:2 * Kg] += lam2 * self.LtL_g
        b[:Kg] += lam2 * self.LtL_g @ d[:, 0]
        b[Kg:2 * Kg] += lam2 * self.LtL_g @ d[:, 1]
        if self.s.photometric:
            A[2 * Kg:, 2 * Kg:] += lam2 * self.s.lam_p ** 2 * self.LtL_p
            b[2 * Kg:] += lam2 * self.s.lam_p ** 2 * self.LtL_p @ rho
        return A, b, r, ok, vH

    def _assemble_numpy(self, lv: LevelModel, Gx, Gy, r, w, A, b) -> None:
        """The NumPy reference of the compiled assembly: ``B_a^T diag(c) B_b`` blocks by ``bincount``."""
        Kg, Kp = self.Kg, self.Kp
        gg, gp, pp = lv.pairs()
        A[:Kg, :Kg] = gg.block(w * Gx * Gx)
        A[:Kg, Kg:2 * Kg] = gg.block(w * Gx * Gy)
        A[Kg:2 * Kg, Kg:2 * Kg] = gg.block(w * Gy * Gy)
        A[Kg:2 * Kg, :Kg] = A[:Kg, Kg:2 * Kg].T
        b[:Kg] = lv.tvec(lv.ig, lv.wg, w * Gx * r, Kg)
        b[Kg:2 * Kg] = lv.tvec(lv.ig, lv.wg, w * Gy * r, Kg)
        if self.s.photometric:
            A[:Kg, 2 * Kg:] = gp.block(w * Gx * lv.I0)
            A[Kg:2 * Kg, 2 * Kg:] = gp.block(w * Gy * lv.I0)
            A[2 * Kg:, :2 * Kg] = A[:2 * Kg, 2 * Kg:].T
            A[2 * Kg:, 2 * Kg:] = pp.block(w * lv.I0 * lv.I0)
            b[2 * Kg:] = lv.tvec(lv.ip, lv.wp, w * lv.I0 * r, Kp)

    def energies(self, d, rho, img: np.ndarray, level: int = 0) -> tuple[float, float]:
        """``(E_D, E_S)`` as normalised in ch13.md §2, on ``img`` (the frame at pyramid ``level``)."""
        r, _ = self.residual(self.levels[level], img, d, rho)
        ok = np.isfinite(r)
        r = np.where(ok, r, 0.0)
        vH = huber_scale(r[ok], self.s.huber_k)
        e_d = float(np.sum(huber_rho(r, vH) * ok) / max(ok.sum(), 1))
        e_s = float(d[:, 0] @ self.LtL_g @ d[:, 0] + d[:, 1] @ self.LtL_g @ d[:, 1])
        if self.s.photometric:
            e_s += float(self.s.lam_p ** 2 * rho @ self.LtL_p @ rho)
        return e_d, e_s / max(self.n_gamma, 1)

    def solve(self, frame_gray: np.ndarray, d0: np.ndarray, rho0: np.ndarray):
        """Coarse-to-fine IRLS from ``(d0, rho0)``; returns ``d, rho, info``."""
        d, rho = d0.astype(np.float64).copy(), rho0.astype(np.float64).copy()
        pyr = pyramid(frame_gray, self.s.levels)
        folds, iters = 0, 0
        Kg = self.Kg
        for lvl in range(self.s.levels - 1, -1, -1):
            lv = self.levels[lvl]
            img = pyr[lvl]
            gx, gy = gradients(img)
            for _ in range(self.s.max_iter):
                A, b, r, ok, _ = self.normal_equations(lv, img, gx, gy, d, rho)
                if ok.sum() < 8:
                    break
                A[np.diag_indices_from(A)] += 1e-10
                try:                                             # A is symmetric positive definite
                    delta = -cho_solve(cho_factor(A, check_finite=False), b, check_finite=False)
                except np.linalg.LinAlgError:
                    try:
                        delta = -np.linalg.solve(A, b)
                    except np.linalg.LinAlgError:
                        break
                dd = np.stack([delta[:Kg], delta[Kg:2 * Kg]], 1)
                dr = delta[2 * Kg:] if self.s.photometric else 0.0
                step, halvings = fold_safe_step(self.V0 + d, dd, self.tris, self.area0)
                folds += halvings
                d = d + step * dd
                if self.s.photometric:
                    rho = np.clip(rho + step * dr, self.s.rho_min, self.s.rho_max)
                iters += 1
                if np.max(np.abs(step * dd)) * lv.f < (self.s.tol if lvl == 0 else max(self.s.tol, self.s.coarse_tol)):
                    break
        r, _ = self.residual(self.levels[0], pyr[0], d, rho)
        ok = np.isfinite(r)
        rms = float(np.sqrt(np.mean(r[ok] ** 2))) if ok.any() else float("inf")
        folded = not keeps_orientation(self.V0 + d, self.tris, self.area0)
        return d, rho, {"rms": rms, "iterations": iters, "fold_halvings": folds, "folded": folded,
                        "valid_fraction": float(ok.mean())}


def dense_jacobian(solver: MeshSolver, level: int, img, gx, gy, d) -> np.ndarray:
    """The explicit ``p x N`` Jacobian of Eq. (36) in the §1.8 form (for tests and small problems)."""
    lv = solver.levels[level]
    warped = lv.pts + lv.displacement(d) * lv.f
    Gx = np.nan_to_num(_sample(gx, warped, lv.shape)) * (-lv.f)
    Gy = np.nan_to_num(_sample(gy, warped, lv.shape)) * (-lv.f)
    cols = [lv.Bg.multiply(Gx[:, None]).toarray(), lv.Bg.multiply(Gy[:, None]).toarray()]
    if solver.s.photometric:
        cols.append(lv.Bp.multiply(lv.I0[:, None]).toarray())
    return np.hstack(cols)
