"""Anisotropic mean shift with a full bandwidth matrix (book ch. 5, §4.2; Tracker B of the hybrid).

Book *Object Tracking*, ch. 5 (``shared/seeds/002_*`` lines 3595-5369; specification
``shared/book/ch05.md`` §1.0, §1.3), after Sumin & Xianwu (2008) and Comaniciu et al. (2003):

* **(9)** ``Sigma = R(theta)^T diag((h/2)^2, (w/2)^2) R(theta)`` with ``R = [[cos, sin], [-sin, cos]]``:
  ``h``, ``w`` are the full long and short axes, ``theta`` the long axis' angle to the image
  x-axis; **(10)-(11)** back by the eigen-decomposition.  The reported box is the kernel ellipse
  scaled by ``K = 0.9`` (L4325-4329; ch05.md §1.0 ``k_mode="box"``) —
  :func:`sigma_from_box`, :func:`box_from_sigma`;
* **(5)** the kernel histogram ``p_u(y, Sigma) = c |Sigma|^-1/2 sum_j k(y~_j^T Sigma^-1 y~_j) delta[b(y_j) - u]``
  with the Epanechnikov profile ``k(d) = 1 - d`` (not given; ch05.md P2) — :func:`ellipse_histogram`;
* **(6)-(7)** weights ``omega_j = sqrt(q_u / p_u(y0))`` and the location step
  ``y = sum omega_j y_j / sum omega_j`` (``g`` constant; the book prints ``x_j``, ch05.md P1);
* **(8)** the bandwidth step maximising ``|Sigma|^(gamma/2) rho``:
  ``Sigma = 2/(1 - gamma) sum omega_j y~_j y~_j^T / sum omega_j k(d_j)`` — the outer product,
  restored (the book prints the scalar ``y~^T y~``; ch05.md P1) — :func:`aniso_mean_shift`.

For a uniform object ellipse ``A`` the iteration's fixed point is ``Sigma = c* A`` with
``c* = (2 - gamma) / (2 (1 - gamma))`` (ch05.md §5.1-2): with ``gamma = 0.33`` the kernel's
semi-axes are 1.116 times the object's and ``K = 0.9`` makes the reported box fit it.
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import njit, np_sum, numba_enabled


def rotation(theta: float) -> np.ndarray:
    """``R(theta) = [[cos, sin], [-sin, cos]]`` (Eq. 9)."""
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, s], [-s, c]])


def sigma_from_box(h: float, w: float, theta: float, K: float = 1.0) -> np.ndarray:
    """Eq. 9 with the K-scaling: the kernel whose ``K``-scaled ellipse has axes ``h`` (along ``theta``) and ``w``."""
    R = rotation(theta)
    return R.T @ np.diag([(h / (2.0 * K)) ** 2, (w / (2.0 * K)) ** 2]) @ R


def box_from_sigma(sigma: np.ndarray, K: float = 1.0) -> tuple[float, float, float]:
    """Eqs. 10-11: ``(h, w, theta)`` of the ``K``-scaled ellipse, ``h >= w``, ``theta`` in ``(-pi/2, pi/2]``."""
    lam, V = np.linalg.eigh(np.asarray(sigma, dtype=np.float64))
    l1, l2 = max(lam[1], 0.0), max(lam[0], 0.0)
    v = V[:, 1]
    theta = math.atan2(v[1], v[0])
    if theta <= -math.pi / 2:
        theta += math.pi
    elif theta > math.pi / 2:
        theta -= math.pi
    return 2.0 * K * math.sqrt(l1), 2.0 * K * math.sqrt(l2), theta


def axis_box_to_rotated(box) -> tuple[float, float, float, float, float]:
    """An axis-aligned ``(x, y, w, h)`` as ``(cx, cy, h_long, w_short, theta)`` (ch05.md §1.0)."""
    x, y, bw, bh = (float(v) for v in box)
    if bh >= bw:
        return x + bw / 2, y + bh / 2, bh, bw, math.pi / 2
    return x + bw / 2, y + bh / 2, bw, bh, 0.0


def rotated_corners(cx: float, cy: float, h: float, w: float, theta: float) -> np.ndarray:
    """``(4, 2)`` corners of the rotated rectangle (long side ``h`` along ``theta``)."""
    u = np.array([math.cos(theta), math.sin(theta)]) * h / 2
    v = np.array([-math.sin(theta), math.cos(theta)]) * w / 2
    c = np.array([cx, cy])
    return np.array([c - u - v, c + u - v, c + u + v, c - u + v])


def rotated_to_axis_box(cx: float, cy: float, h: float, w: float, theta: float) -> tuple[float, float, float, float]:
    """The axis-aligned hull ``(x, y, w, h)`` of a rotated rectangle (the OTB output)."""
    pts = rotated_corners(cx, cy, h, w, theta)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    return float(lo[0]), float(lo[1]), float(hi[0] - lo[0]), float(hi[1] - lo[1])


def _support(bins, origin, y, sigma):
    """The pixels of ``bins`` (pixel ``(0, 0)`` at ``origin``) under the ellipse ``d <= 1`` of ``sigma`` at ``y``,
    in row order: ``(offsets x, offsets y, d, their bins)``; None for a degenerate or empty kernel."""
    hgt, wid = bins.shape
    if not (np.all(np.isfinite(sigma)) and np.linalg.det(sigma) > 1e-9):
        return None  # a degenerate kernel covers no pixel
    ex = math.sqrt(max(sigma[0, 0], 1e-12))
    ey = math.sqrt(max(sigma[1, 1], 1e-12))
    lx, ly = y[0] - origin[0], y[1] - origin[1]
    i0, i1 = max(int(math.floor(lx - ex)), 0), min(int(math.ceil(lx + ex)) + 1, wid)
    j0, j1 = max(int(math.floor(ly - ey)), 0), min(int(math.ceil(ly + ey)) + 1, hgt)
    if i1 <= i0 or j1 <= j0:
        return None
    inv = np.linalg.inv(sigma)
    if numba_enabled():
        n = (j1 - j0) * (i1 - i0)
        X, Y, d, B = np.empty(n), np.empty(n), np.empty(n), np.empty(n, dtype=bins.dtype)
        k = _gather_ellipse(bins, i0, i1, j0, j1, float(lx), float(ly), inv[0, 0], inv[0, 1], inv[1, 1], X, Y, d, B)
        return X[:k], Y[:k], d[:k], B[:k]
    xs = np.arange(i0, i1) + 0.5 - lx
    ys = np.arange(j0, j1) + 0.5 - ly
    X, Y = np.meshgrid(xs, ys)
    d = inv[0, 0] * X * X + 2 * inv[0, 1] * X * Y + inv[1, 1] * Y * Y
    inside = d <= 1.0
    return X[inside], Y[inside], d[inside], bins[j0:j1, i0:i1][inside]


@njit
def _gather_ellipse(bins, i0, i1, j0, j1, lx, ly, a, b, c, X, Y, d, B):
    """:func:`_support`'s pixels, compiled: the NumPy path's arithmetic and its boolean-mask (row) order, so the
    offsets, ``d`` and bins are the same to the last bit; returns their count."""
    k = 0
    b2 = 2 * b
    for j in range(j0, j1):
        yv = j + 0.5 - ly
        for i in range(i0, i1):
            xv = i + 0.5 - lx
            dv = a * xv * xv + b2 * xv * yv + c * yv * yv
            if dv <= 1.0:
                X[k] = xv
                Y[k] = yv
                d[k] = dv
                B[k] = bins[j, i]
                k += 1
    return k


def ellipse_histogram(bins: np.ndarray, origin: tuple[int, int], y, sigma: np.ndarray, n_bins: int
                      ) -> np.ndarray:
    """Eq. 5: the Epanechnikov-weighted histogram of the ellipse ``d(y_j) <= 1`` (normalised to sum 1;
    zeros when the ellipse covers no pixel of ``bins``, whose pixel ``(0, 0)`` is at ``origin``)."""
    sup = _support(bins, origin, y, np.asarray(sigma, dtype=np.float64))
    if sup is None:
        return np.zeros(n_bins)
    _, _, d, b = sup
    h = np.bincount(b, weights=1.0 - d, minlength=n_bins).astype(np.float64)
    s = h.sum()
    return h / s if s > 0 else h


def ring_histogram(bins: np.ndarray, origin: tuple[int, int], y, sigma: np.ndarray, n_bins: int,
                   scale: float = math.sqrt(3.0)) -> np.ndarray:
    """Counts of the pixels between the ellipse ``d <= 1`` of ``sigma`` and the same ellipse scaled by ``scale``
    (unnormalised; the background region of Ning et al.'s corrected background-weighted histogram, 3x the
    target's area by default)."""
    sup = _support(bins, origin, y, np.asarray(sigma, dtype=np.float64) * scale * scale)
    if sup is None:
        return np.zeros(n_bins)
    _, _, d, b = sup
    ring = d * scale * scale > 1.0
    return np.bincount(b[ring], minlength=n_bins).astype(np.float64)


def _pool_factors(bins, s: int) -> tuple[tuple[int, ...], list[int]]:
    """The histogram shape and, per axis, how many of its bins pool into one (1: the axis is kept)."""
    bins = tuple(int(b) for b in bins)
    return bins, [b // s if (b > s and b % s == 0) else 1 for b in bins]


def pool_histogram(h: np.ndarray, bins, s: int) -> np.ndarray:
    """A flattened histogram of shape ``bins`` with each axis of more than ``s`` bins pooled to ``s`` bins (when
    ``s`` divides it; other axes are kept): 32^3 RGB to s^3, or the intensity axis of a grey histogram."""
    bins, f = _pool_factors(bins, s)
    if max(f) == 1 or h.size != int(np.prod(bins)):
        return h
    shape = [d for b, k in zip(bins, f) for d in (b // k, k)]
    return h.reshape(shape).sum(axis=tuple(range(1, 2 * len(bins), 2))).ravel()


def pool_index(bins, s: int) -> np.ndarray:
    """For each bin of a flattened histogram of shape ``bins``, its bin after :func:`pool_histogram`."""
    bins, f = _pool_factors(bins, s)
    if max(f) == 1:
        return np.arange(int(np.prod(bins)))
    idx = np.indices(bins).reshape(len(bins), -1)
    return np.ravel_multi_index(tuple(i // k for i, k in zip(idx, f)), tuple(b // k for b, k in zip(bins, f)))


def background_weights(ring: np.ndarray) -> np.ndarray:
    """CBWH's ``v_u = min(o* / o_u, 1)`` with ``o*`` the smallest non-zero count of the background histogram
    ``ring`` (bins absent from the background keep weight 1); Ning, Zhang, Zhang & Wu 2012, Eq. 13."""
    occ = ring > 0
    if not occ.any():
        return np.ones_like(ring)
    o_star = ring[occ].min()
    v = np.ones_like(ring)
    v[occ] = np.minimum(o_star / ring[occ], 1.0)
    return v


def background_weighted(q: np.ndarray, ring: np.ndarray, index: np.ndarray | None = None) -> np.ndarray:
    """CBWH's target model ``q'_u = C v_u q_u`` (Ning et al. 2012, Eqs. 13-14): the reference with the bins
    of the background ``ring`` down-weighted.  ``index`` maps each bin to a coarser one (:func:`pool_index`):
    the weights are then taken on the pooled background, which a few hundred pixels fill densely enough to
    rank.  Returns ``q`` itself when nothing is left."""
    if index is None:
        w = background_weights(ring)
    else:
        # the last fine bin falls in the last pooled bin (row-major pooling)
        w = background_weights(np.bincount(index, weights=ring, minlength=int(index[-1]) + 1))[index]
    qb = q * w
    s = qb.sum()
    return qb / s if s > 0 else q


def bhattacharyya(p: np.ndarray, q: np.ndarray) -> float:
    """``rho = sum sqrt(p q)`` (Eq. 6)."""
    return float(np.sum(np.sqrt(p * q)))


def objective(bins: np.ndarray, origin, q: np.ndarray, y, sigma: np.ndarray, gamma: float) -> float:
    """The quantity Eq. 8 climbs, ``|Sigma|^(gamma/2) rho(p(y, Sigma), q)``."""
    p = ellipse_histogram(bins, origin, y, sigma, q.shape[0])
    return float(np.linalg.det(sigma)) ** (gamma / 2.0) * bhattacharyya(p, q)


@njit
def _aniso_sums(X, Y, d, B, q, p, a, b, c, adapt):
    """One iteration's sums over the support, compiled: ``(s, sw, shift x, shift y, den, Mxx, Mxy, Myy)`` with
    ``s`` the histogram's mass (Eq. 5), ``sw`` the weights' sum (Eq. 6), the Eq. 7 shift and Eq. 8's
    denominator and second moments about the shifted centre.  The NumPy path's numbers up to the order of
    the sums (sequential here)."""
    p[:] = 0.0
    for k in range(B.shape[0]):
        p[B[k]] += 1.0 - d[k]
    s = np_sum(p)
    out = np.zeros(8)
    out[0] = s
    if s <= 0:
        return out
    sw = 0.0
    sx = 0.0
    sy = 0.0
    for k in range(B.shape[0]):
        pb = p[B[k]] / s
        w = math.sqrt(q[B[k]] / pb) if pb > 0 else 0.0
        sw += w
        sx += w * X[k]
        sy += w * Y[k]
    out[1] = sw
    if sw <= 0:
        return out
    shx = sx / sw
    shy = sy / sw
    out[2] = shx
    out[3] = shy
    if adapt:
        b2 = 2 * b
        den = 0.0
        mxx = 0.0
        mxy = 0.0
        myy = 0.0
        for k in range(B.shape[0]):
            xn = X[k] - shx
            yn = Y[k] - shy
            dn = a * xn * xn + b2 * xn * yn + c * yn * yn
            if dn <= 1.0:
                pb = p[B[k]] / s
                w = math.sqrt(q[B[k]] / pb) if pb > 0 else 0.0
                den += w * (1.0 - dn)
                mxx += w * (xn * xn)
                mxy += w * (xn * yn)
                myy += w * (yn * yn)
        out[4] = den
        out[5] = mxx
        out[6] = mxy
        out[7] = myy
    return out


def clamp_scale(sigma: np.ndarray, det0: float, step: float) -> np.ndarray:
    """``sigma`` scaled uniformly so its linear size ``|sigma|^(1/4)`` is within a factor ``1 + step``
    of the size of a kernel whose determinant is ``det0``."""
    f = (max(float(np.linalg.det(sigma)), 1e-300) / det0) ** 0.25
    fc = min(max(f, 1.0 / (1.0 + step)), 1.0 + step)
    return sigma if fc == f else sigma * (fc / f) ** 2


def aniso_mean_shift(bins: np.ndarray, origin: tuple[int, int], q: np.ndarray, y0, sigma0: np.ndarray, *,
                     gamma: float = 0.33, max_iter: int = 10, shift_tol: float = 0.5, sigma_tol: float = 1e-3,
                     min_axis: float = 2.0, adapt_sigma: bool = True, safeguard: bool = False,
                     max_scale_step: float = 0.0) -> tuple[np.ndarray, np.ndarray, int]:
    """Eqs. 7-8 alternated (recomputing ``p`` and ``omega`` each iteration), at most ``max_iter`` times.

    Stops when the shift is below ``shift_tol`` px and ``||dSigma||_F / ||Sigma||_F < sigma_tol``.
    Returns ``(y, Sigma, iterations)``.  ``min_axis`` (px) floors the kernel's semi-axes.

    ``safeguard`` (design, not in the chapter): Eq. 8 maximises a linearisation, and on real
    backgrounds that share the target's colours its step can inflate the kernel while the true
    objective ``|Sigma|^(gamma/2) rho`` falls; the step is then halved (up to 3 times, as
    Comaniciu's location safeguard) or refused.

    ``max_scale_step > 0`` (design, not in the chapter): the kernel's linear size
    ``|Sigma|^(1/4)`` stays within a factor ``1 + max_scale_step`` of ``sigma0``'s (Sigma is scaled
    uniformly back inside; its shape and angle are free): the size of a video object changes
    little from one frame to the next, and this bounds Eq. 8's inflation on backgrounds that
    share the target's colours.
    """
    n_bins = q.shape[0]
    y = np.asarray(y0, dtype=np.float64).copy()
    sigma = np.asarray(sigma0, dtype=np.float64).copy()
    det0 = float(np.linalg.det(sigma)) if max_scale_step > 0 else 0.0
    hist = None
    it = 0
    for it in range(1, max_iter + 1):
        sup = _support(bins, origin, y, sigma)
        if sup is None:
            break
        X, Y, d, b = sup
        inv = np.linalg.inv(sigma)
        if numba_enabled():
            if hist is None:
                hist = np.empty(n_bins)
            r = _aniso_sums(X, Y, d, b, q, hist, inv[0, 0], inv[0, 1], inv[1, 1], adapt_sigma)
            if r[0] <= 0 or r[1] <= 0:
                break
            shift = np.array([r[2], r[3]])
            den, M = r[4], np.array([[r[5], r[6]], [r[6], r[7]]])
        else:
            p = np.bincount(b, weights=1.0 - d, minlength=n_bins)
            s = p.sum()
            if s <= 0:
                break
            p /= s
            ratio = np.zeros(n_bins)
            nz = p > 0
            ratio[nz] = np.sqrt(q[nz] / p[nz])
            w = ratio[b]
            sw = w.sum()
            if sw <= 0:
                break
            # Eq. 7: location (g constant on the support)
            shift = np.array([np.dot(w, X), np.dot(w, Y)]) / sw
            den, M = 0.0, None
            if adapt_sigma:
                # Eq. 8's sums about the new location, with the current kernel's support and weights
                Xn, Yn = X - shift[0], Y - shift[1]
                dn = inv[0, 0] * Xn * Xn + 2 * inv[0, 1] * Xn * Yn + inv[1, 1] * Yn * Yn
                keep = dn <= 1.0
                wk = w[keep]
                den = float(np.dot(wk, 1.0 - dn[keep]))
                xk, yk = Xn[keep], Yn[keep]
                M = np.array([[np.dot(wk, xk * xk), np.dot(wk, xk * yk)],
                              [np.dot(wk, xk * yk), np.dot(wk, yk * yk)]])
        y_new = y + shift
        sigma_new = sigma
        if adapt_sigma:
            # Eq. 8
            if den > 0:
                sigma_new = (2.0 / (1.0 - gamma)) * M / den
                lam, V = np.linalg.eigh(sigma_new)
                lam = np.maximum(lam, min_axis ** 2)
                sigma_new = (V * lam) @ V.T
                if safeguard:
                    j0 = objective(bins, origin, q, y_new, sigma, gamma)
                    for _ in range(4):
                        if objective(bins, origin, q, y_new, sigma_new, gamma) >= j0:
                            break
                        sigma_new = 0.5 * (sigma + sigma_new)
                    else:
                        sigma_new = sigma
                if max_scale_step > 0 and det0 > 0:
                    sigma_new = clamp_scale(sigma_new, det0, max_scale_step)
        moved = float(np.hypot(*shift))
        dsig = float(np.linalg.norm(sigma_new - sigma) / max(np.linalg.norm(sigma), 1e-12))
        y, sigma = y_new, sigma_new
        if moved < shift_tol and dsig < sigma_tol:
            break
    return y, sigma, it
