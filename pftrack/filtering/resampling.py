"""Resampling schemes.

Every resampler maps normalised weights ``w`` (length ``N``) to ``N`` indices of
the particles to keep, using only the injected :class:`numpy.random.Generator`.
All four are unbiased: the expected number of copies of particle ``n`` is
``N * w[n]``.  They differ in variance (multinomial > residual > stratified >=
systematic) and in cost.

* :func:`multinomial` — Nummiaro et al., Fig. 2, step 1: normalised cumulative
  sums and, for each of ``N`` uniform numbers ``r``, a binary search for the
  smallest ``j`` with ``c'(j) >= r``.
* :func:`stratified` — one uniform number in each of ``N`` equal strata.
* :func:`systematic` — one uniform offset shared by all strata.
* :func:`residual` — ``floor(N w)`` deterministic copies, the rest multinomial.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from .._numba import njit, numba_enabled

Resampler = Callable[[np.ndarray, np.random.Generator], np.ndarray]


def _cumulative(weights: np.ndarray) -> np.ndarray:
    w = np.asarray(weights, dtype=np.float64)
    if w.ndim != 1 or w.size == 0:
        raise ValueError("weights must be a non-empty 1-D array")
    c = np.cumsum(w)
    total = c[-1]
    if not math.isfinite(total) or total <= 0:
        raise ValueError("weights must be finite with a positive sum")
    c /= total  # c'(n) = c(n) / c(N)
    c[-1] = 1.0  # guard against round-off so every r in [0, 1) finds an index
    return c


def _search(c: np.ndarray, r: np.ndarray) -> np.ndarray:
    # smallest j with c'(j) >= r  (binary search, Fig. 2 step 1c)
    idx = np.searchsorted(c, r, side="left")
    np.minimum(idx, c.size - 1, out=idx)
    return idx


def weighted_choice(p: np.ndarray, m: int, rng: np.random.Generator) -> np.ndarray:
    """``m`` indices drawn with replacement with probabilities ``p`` (normalised): the indices, random numbers and
    generator state of ``rng.choice(len(p), size=m, p=p)`` (NumPy's ``Generator``: normalised cumulative sums and a
    search on the right of ``m`` uniform numbers), without its checks of ``p``, which cost more than the draw on
    a few hundred samples."""
    cdf = p.cumsum()
    cdf /= cdf[-1]
    return cdf.searchsorted(rng.random(m), side="right")


@njit(cache=True)
def _multinomial_numba(w, r, out):  # pragma: no cover - compiled
    """:func:`_cumulative` and :func:`_search` in one call, the same numbers (the sums in order, each divided by the
    total, the last set to 1, the smallest ``j`` with ``c[j] >= r`` by bisection); False when the total is not a
    finite positive number."""
    n = w.shape[0]
    c = np.empty(n)
    s = 0.0
    for i in range(n):
        s += w[i]
        c[i] = s
    total = c[n - 1]
    if not (math.isfinite(total) and total > 0):
        return False
    for i in range(n):
        c[i] /= total
    c[n - 1] = 1.0
    for k in range(r.shape[0]):
        x = r[k]
        lo, hi = 0, n
        while lo < hi:
            mid = (lo + hi) >> 1
            if c[mid] < x:
                lo = mid + 1
            else:
                hi = mid
        out[k] = min(lo, n - 1)
    return True


def multinomial(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    if (numba_enabled() and isinstance(weights, np.ndarray) and weights.dtype == np.float64 and weights.ndim == 1
            and weights.size):
        out = np.empty(weights.size, np.intp)
        if _multinomial_numba(weights, rng.random(weights.size), out):
            return out
        _cumulative(weights)  # raises: the total is not a finite positive number
    c = _cumulative(weights)
    return _search(c, rng.random(c.size))


def stratified(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    c = _cumulative(weights)
    n = c.size
    r = (np.arange(n) + rng.random(n)) / n
    return _search(c, r)


def systematic(weights: np.ndarray, rng: np.random.Generator, n: int | None = None) -> np.ndarray:
    """``n`` indices (default: as many as weights) with one uniform offset shared by all strata."""
    c = _cumulative(weights)
    n = c.size if n is None else int(n)
    r = (np.arange(n) + rng.random()) / n
    return _search(c, r)


def residual(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    w = np.asarray(weights, dtype=np.float64)
    w = w / w.sum()
    n = w.size
    scaled = n * w
    copies = np.floor(scaled).astype(np.int64)
    det = np.repeat(np.arange(n), copies)
    rest = n - det.size
    if rest == 0:
        return det
    res = scaled - copies
    c = _cumulative(res)
    extra = _search(c, rng.random(rest))
    out = np.concatenate([det, extra])
    return out


RESAMPLERS: dict[str, Resampler] = {
    "multinomial": multinomial,
    "systematic": systematic,
    "stratified": stratified,
    "residual": residual,
}


def get_resampler(name_or_fn: str | Resampler) -> Resampler:
    """A resampler by registry name, or a callable passed through."""
    if callable(name_or_fn):
        return name_or_fn
    try:
        return RESAMPLERS[name_or_fn]
    except KeyError:
        raise ValueError(f"unknown resampler {name_or_fn!r}; choose from {', '.join(RESAMPLERS)}") from None
