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


def _normalize_numpy(log_lik, states, log_w, w, mean):
    from .particles import log_normalize

    _, ok = log_normalize(log_lik, out=log_w)
    np.exp(log_w, out=w)
    w /= w.sum()
    mean[:] = w @ states
    ss = float(w @ w)
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
