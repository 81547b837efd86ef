"""2-D rigid registration of an LRF's track to the world path (book ch. 12, Eqs. 2-6) and its LMedS
wrapper (L10604-10621).

``fit_rigid_2d`` is the closed-form least-squares solution of Eq. (2) (restored Eqs. 3-5: Procrustes
without scale, Lu & Milios 1997 / Umeyama 1991), vectorised over any number of hypotheses.
``lmeds_rigid_2d`` draws 2-point samples, fits each with Eqs. (3)-(5) and keeps the hypothesis with the
least median of squared residuals (50 % breakdown).
"""

from __future__ import annotations

import numpy as np


def fit_rigid_2d(p_local, p_world, weights=None) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. (3)-(6): ``theta`` and ``T`` minimising ``sum |p_world - R(theta) p_local - T|^2``.

    ``p_local``/``p_world`` have shape ``(..., n, 2)``; the result has shapes ``(...)`` and ``(..., 2)``.
    """
    a = np.asarray(p_local, np.float64)
    b = np.asarray(p_world, np.float64)
    if weights is None:
        ma, mb = a.mean(-2), b.mean(-2)
        wt = 1.0
    else:
        wt = np.asarray(weights, np.float64)[..., None]
        s = wt.sum(-2)
        ma, mb = (wt * a).sum(-2) / s, (wt * b).sum(-2) / s
    ac, bc = a - ma[..., None, :], b - mb[..., None, :]
    sin = np.sum(wt * (ac[..., 0] * bc[..., 1] - ac[..., 1] * bc[..., 0])[..., None], axis=(-2, -1))
    cos = np.sum(wt * (ac[..., 0] * bc[..., 0] + ac[..., 1] * bc[..., 1])[..., None], axis=(-2, -1))
    theta = np.arctan2(sin, cos)                                                        # Eq. (3)
    c, s_ = np.cos(theta), np.sin(theta)
    T = np.stack([mb[..., 0] - (ma[..., 0] * c - ma[..., 1] * s_),                         # Eq. (4)
                  mb[..., 1] - (ma[..., 0] * s_ + ma[..., 1] * c)], -1)                    # Eq. (5)
    return theta, T


def apply_rigid_2d(theta, T, p) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    p = np.asarray(p, np.float64)
    return np.stack([c * p[..., 0] - s * p[..., 1], s * p[..., 0] + c * p[..., 1]], -1) + T


def residuals(theta, T, p_local, p_world) -> np.ndarray:
    return np.linalg.norm(np.asarray(p_world) - apply_rigid_2d(theta, T, p_local), axis=-1)


def lmeds_rigid_2d(p_local, p_world, *, rng=None, max_trials: int = 500, min_separation: float = 0.3,
                   refine: bool = False):
    """Least median of squares (L10604-10621).

    All 2-point samples are used when there are at most 5000 of them, else ``max_trials`` random ones;
    samples whose local points are closer than ``min_separation`` are rejected (pitfall 4).  With
    ``refine`` the inliers ``r <= 2.5 sigma`` (``sigma = 1.4826 (1 + 5/(n-3)) sqrt(med r^2)``,
    Rousseeuw & Leroy 1987) are refitted with Eqs. (3)-(5); the faithful default keeps the best sample.

    Returns ``theta, T, inlier_mask, median_sq``.
    """
    a = np.asarray(p_local, np.float64)
    b = np.asarray(p_world, np.float64)
    n = len(a)
    if n < 2:
        raise ValueError("LMedS needs at least 2 correspondences")
    rng = np.random.default_rng(0) if rng is None else rng
    if n * (n - 1) // 2 <= 5000:
        i, j = np.triu_indices(n, 1)
    else:
        i = rng.integers(0, n, 4 * max_trials)
        j = rng.integers(0, n, 4 * max_trials)
    ok = (i != j) & (np.linalg.norm(a[i] - a[j], axis=1) >= min_separation)
    i, j = i[ok], j[ok]
    if n * (n - 1) // 2 > 5000:
        i, j = i[:max_trials], j[:max_trials]
    if len(i) == 0:
        raise ValueError("LMedS: every sample is degenerate (local points closer than min_separation)")
    theta, T = fit_rigid_2d(np.stack([a[i], a[j]], 1), np.stack([b[i], b[j]], 1))
    med = np.empty(len(i))
    for s in range(0, len(i), 256):       # (hypotheses x points) residuals in chunks
        r2 = np.sum((b[None] - apply_rigid_2d(theta[s:s + 256, None], T[s:s + 256, None], a[None])) ** 2, -1)
        med[s:s + 256] = np.median(r2, axis=1)
    k = int(np.argmin(med))
    th, t = float(theta[k]), T[k]
    sigma = 1.4826 * (1 + 5 / max(n - 3, 1)) * np.sqrt(med[k])
    inl = residuals(th, t, a, b) <= max(2.5 * sigma, 1e-12)
    if refine and inl.sum() >= 2:
        th, t = fit_rigid_2d(a[inl], b[inl])
        th = float(th)
        inl = residuals(th, t, a, b) <= max(2.5 * sigma, 1e-12)
    return th, np.asarray(t), inl, float(med[k])
