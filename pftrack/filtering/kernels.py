"""Compiled per-frame steps of the particle filter, each with a NumPy reference.

A frame of a particle filter is a dozen small array operations; at hundreds of
frames per second their Python overhead rivals the image work.  These kernels
fuse them:

* :func:`propagate_cv_scale` — the first-order model of Nummiaro et al. (Eq. 9)
  plus noise, bounds on the half-axes and the scale rate, and the frame limits;
  it also returns the region the particles can reach.
* :func:`normalize_and_estimate` — log-weights from log-likelihoods (log-sum-exp),
  linear weights, the weighted mean state (Eq. 1) and the effective sample size.

Both paths give the same numbers up to floating-point rounding (tested).
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import njit, numba_enabled


@njit
def _propagate_numba(states, noise, std, damping, min_h, max_h, max_rate, width, height):
    n = states.shape[0]
    x0 = 1e300
    y0 = 1e300
    x1 = -1e300
    y1 = -1e300
    for i in range(n):
        s = states[i]
        f = 1.0 + s[6]
        x = s[0] + s[2] + noise[i, 0] * std[0]
        y = s[1] + s[3] + noise[i, 1] * std[1]
        vx = s[2] + noise[i, 2] * std[2]
        vy = s[3] + noise[i, 3] * std[3]
        hx = s[4] * f + noise[i, 4] * std[4]
        hy = s[5] * f + noise[i, 5] * std[5]
        ad = s[6] * damping + noise[i, 6] * std[6]
        hx = min(max(hx, min_h), max_h)
        hy = min(max(hy, min_h), max_h)
        ad = min(max(ad, -max_rate), max_rate)
        if width > 0:
            x = min(max(x, -hx), width + hx)
            y = min(max(y, -hy), height + hy)
        s[0] = x
        s[1] = y
        s[2] = vx
        s[3] = vy
        s[4] = hx
        s[5] = hy
        s[6] = ad
        x0 = min(x0, x - hx)
        y0 = min(y0, y - hy)
        x1 = max(x1, x + hx)
        y1 = max(y1, y + hy)
    return x0, y0, x1, y1


def _propagate_numpy(states, noise, std, damping, min_h, max_h, max_rate, width, height):
    f = 1.0 + states[:, 6]
    out = np.empty_like(states)
    out[:, 0] = states[:, 0] + states[:, 2] + noise[:, 0] * std[0]
    out[:, 1] = states[:, 1] + states[:, 3] + noise[:, 1] * std[1]
    out[:, 2] = states[:, 2] + noise[:, 2] * std[2]
    out[:, 3] = states[:, 3] + noise[:, 3] * std[3]
    out[:, 4] = states[:, 4] * f + noise[:, 4] * std[4]
    out[:, 5] = states[:, 5] * f + noise[:, 5] * std[5]
    out[:, 6] = states[:, 6] * damping + noise[:, 6] * std[6]
    out[:, 4:6] = np.minimum(np.maximum(out[:, 4:6], min_h), max_h)
    out[:, 6] = np.minimum(np.maximum(out[:, 6], -max_rate), max_rate)
    if width > 0:
        out[:, 0] = np.minimum(np.maximum(out[:, 0], -out[:, 4]), width + out[:, 4])
        out[:, 1] = np.minimum(np.maximum(out[:, 1], -out[:, 5]), height + out[:, 5])
    states[:] = out
    return (float(np.min(out[:, 0] - out[:, 4])), float(np.min(out[:, 1] - out[:, 5])),
            float(np.max(out[:, 0] + out[:, 4])), float(np.max(out[:, 1] + out[:, 5])))


def propagate_cv_scale(states: np.ndarray, noise: np.ndarray, std: np.ndarray, *, damping: float = 1.0,
                       min_half_axis: float = 2.0, max_half_axis: float = 1e5, max_scale_rate: float = 0.1,
                       width: float = 0.0, height: float = 0.0) -> tuple[float, float, float, float]:
    """``s <- A s + std * noise`` in place for the state ``{x, y, vx, vy, Hx, Hy, adot}``.

    ``noise`` holds standard normal draws (the caller draws them from its
    injected generator).  Half-axes are clipped to ``[min_half_axis, max_half_axis]``,
    ``|adot|`` to ``max_scale_rate``; with ``width > 0`` centres are kept within one
    half-axis of the frame.  Returns the bounding region ``(x0, y0, x1, y1)`` of all
    particle ellipses.
    """
    args = (states, noise, np.asarray(std, dtype=np.float64), float(damping), float(min_half_axis),
            float(max_half_axis), float(max_scale_rate), float(width), float(height))
    if numba_enabled():
        return _propagate_numba(*args)
    return _propagate_numpy(*args)


@njit
def _propagate_ncv_numba(states, noise, sigma_xy, max_change, min_h, max_h, keep_aspect, width, height):
    n = states.shape[0]
    sd = max_change / 3.0
    x0 = 1e300
    y0 = 1e300
    x1 = -1e300
    y1 = -1e300
    for i in range(n):
        s = states[i]
        ax = noise[i, 0] * sigma_xy
        ay = noise[i, 1] * sigma_xy
        x = s[0] + s[2] + 0.5 * ax
        y = s[1] + s[3] + 0.5 * ay
        s[2] += ax
        s[3] += ay
        ex = min(max(noise[i, 2] * sd, -max_change), max_change)
        ey = ex if keep_aspect else min(max(noise[i, 3] * sd, -max_change), max_change)
        hx = min(max(s[4] * (1.0 + ex), min_h), max_h)
        hy = min(max(s[5] * (1.0 + ey), min_h), max_h)
        if width > 0:
            x = min(max(x, -hx), width + hx)
            y = min(max(y, -hy), height + hy)
        s[0] = x
        s[1] = y
        s[4] = hx
        s[5] = hy
        x0 = min(x0, x - hx)
        y0 = min(y0, y - hy)
        x1 = max(x1, x + hx)
        y1 = max(y1, y + hy)
    return x0, y0, x1, y1


def _propagate_ncv_numpy(states, noise, sigma_xy, max_change, min_h, max_h, keep_aspect, width, height):
    acc = noise[:, :2] * sigma_xy
    states[:, 0] += states[:, 2] + 0.5 * acc[:, 0]
    states[:, 1] += states[:, 3] + 0.5 * acc[:, 1]
    states[:, 2] += acc[:, 0]
    states[:, 3] += acc[:, 1]
    e = np.clip(noise[:, 2:4] * (max_change / 3.0), -max_change, max_change)
    if keep_aspect:
        e[:, 1] = e[:, 0]
    states[:, 4] = np.clip(states[:, 4] * (1.0 + e[:, 0]), min_h, max_h)
    states[:, 5] = np.clip(states[:, 5] * (1.0 + e[:, 1]), min_h, max_h)
    if width > 0:
        states[:, 0] = np.minimum(np.maximum(states[:, 0], -states[:, 4]), width + states[:, 4])
        states[:, 1] = np.minimum(np.maximum(states[:, 1], -states[:, 5]), height + states[:, 5])
    return (float(np.min(states[:, 0] - states[:, 4])), float(np.min(states[:, 1] - states[:, 5])),
            float(np.max(states[:, 0] + states[:, 4])), float(np.max(states[:, 1] + states[:, 5])))


def propagate_ncv_rw(states: np.ndarray, noise: np.ndarray, *, sigma_xy: float, max_size_change: float,
                     min_half_axis: float = 2.0, max_half_axis: float = 1e5, keep_aspect: bool = False,
                     width: float = 0.0, height: float = 0.0) -> tuple[float, float, float, float]:
    """Nearly-constant velocity + size random walk (Kristan et al., Eq. 10) in place on ``{x, y, vx, vy, Hx, Hy}``.

    ``noise`` is ``(N, 4)`` standard normal: two accelerations (scaled by
    ``sigma_xy``) and two relative size changes (std ``max_size_change / 3``, clipped
    to ``±max_size_change``).  Returns the region covered by the new ellipses.
    """
    args = (states, noise, float(sigma_xy), float(max_size_change), float(min_half_axis), float(max_half_axis),
            bool(keep_aspect), float(width), float(height))
    if numba_enabled():
        return _propagate_ncv_numba(*args)
    return _propagate_ncv_numpy(*args)


@njit
def _normalize_numba(log_lik, states, log_w, w, mean):
    n, d = states.shape
    m = -np.inf
    for i in range(n):
        v = log_lik[i]
        if v > m and v < np.inf:
            m = v
    ok = m > -np.inf
    if not ok:
        lw = -math.log(n)
        for i in range(n):
            log_w[i] = lw
            w[i] = 1.0 / n
    else:
        total = 0.0
        for i in range(n):
            v = log_lik[i]
            e = math.exp(v - m) if (v > -np.inf and v < np.inf) else 0.0
            w[i] = e
            total += e
        lt = math.log(total)
        for i in range(n):
            v = log_lik[i]
            log_w[i] = (v - m - lt) if (v > -np.inf and v < np.inf) else -np.inf
            w[i] /= total
    ss = 0.0
    for k in range(d):
        mean[k] = 0.0
    for i in range(n):
        wi = w[i]
        ss += wi * wi
        for k in range(d):
            mean[k] += wi * states[i, k]
    return ok, (1.0 / ss if ss > 0 else 0.0)


def log_normalize(log_w: np.ndarray, out: np.ndarray | None = None) -> tuple[np.ndarray, bool]:
    """Normalise log-weights so that ``sum(exp(out)) == 1``.

    Returns ``(out, ok)``.  ``ok`` is False when no weight is finite (every
    particle had zero likelihood); the weights are then reset to uniform, so the
    result is always finite and sums to one.
    """
    log_w = np.asarray(log_w, dtype=np.float64)
    if out is None:
        out = np.empty_like(log_w)
    finite = np.isfinite(log_w)
    if not finite.any():
        out.fill(-np.log(log_w.size) if log_w.size else 0.0)
        return out, False
    m = log_w[finite].max()
    # -inf stays -inf (weight 0); +inf/NaN are treated as invalid (weight 0).
    np.subtract(log_w, m, out=out)
    out[~finite] = -np.inf
    lse = np.log(np.exp(out).sum())
    out -= lse
    return out, True


def _normalize_numpy(log_lik, states, log_w, w, mean):
    _, ok = log_normalize(log_lik, out=log_w)
    np.exp(log_w, out=w)
    w /= w.sum()
    mean[:] = (w[:, None] * states).sum(axis=0)
    ss = float(np.sum(w * w))
    return ok, (1.0 / ss if ss > 0 else 0.0)


def normalize_and_estimate(log_lik: np.ndarray, states: np.ndarray, log_w: np.ndarray, w: np.ndarray,
                           mean: np.ndarray) -> tuple[bool, float]:
    """Normalise ``log_lik`` into ``log_w`` and ``w``; weighted mean state into ``mean``.

    Returns ``(ok, ess)``: ``ok`` is False when every likelihood was zero (the
    weights are then uniform), ``ess`` the effective sample size ``1 / sum w^2``.
    """
    if numba_enabled():
        return _normalize_numba(log_lik, states, log_w, w, mean)
    return _normalize_numpy(log_lik, states, log_w, w, mean)
