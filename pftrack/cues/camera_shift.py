"""The camera's translation between two frames from integral projections (a global-motion estimate).

A hand-held camera, or a frame rate too low for the motion, moves everything in view between two frames; a particle
filter whose samples spread a few pixels around the last estimate then loses the target. The classic cheap answer
of video stabilisation is integral projections: the mean intensity of every row and of every column of a frame are
two 1-D signals, and a translation of the view shifts them. Matching the derivatives of the two frames' signals
(so that a smooth change of light, which moves no edge, counts little) over a range of shifts gives the translation
along each axis at the cost of one pass over a lattice of the frame.

>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> y, x = np.mgrid[0:300, 0:400]
>>> scene = np.full((300, 400), 128.0)
>>> for cx, cy, r, v in zip(rng.uniform(0, 400, 40), rng.uniform(0, 300, 40), rng.uniform(5, 30, 40),
...                         rng.uniform(-80, 80, 40)):
...     scene += v * ((x - cx) ** 2 + (y - cy) ** 2 < r * r)     # discs of other shades: a scene with structure
>>> scene = np.clip(scene, 0, 255).astype(np.uint8)
>>> a, b = scene[50:250, 50:350], scene[57:257, 45:345]      # the view moved 5 px left and 7 px down
>>> dx, dy = camera_shift(frame_profiles(a), frame_profiles(b), max_shift=20)
>>> round(dx), round(dy)
(5, -7)

The returned shift is that of the image content: a point at ``x`` in the first frame is near ``x + dx`` in the
second. Pure functions, arrays in and arrays out; the trackers keep the previous frame's profiles.
"""

from __future__ import annotations

import numpy as np

from .._numba import njit, numba_enabled

__all__ = ["camera_shift", "frame_profiles", "lattice_step", "profile_shift"]


def frame_profiles(frame: np.ndarray, step: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Integral projections of ``frame`` (grey ``(H, W)`` or colour ``(H, W, C)``, any dtype) on a lattice of every
    ``step``-th row and column: ``(rows, cols)``, the mean intensity (summed over channels) of each kept row
    ``(ceil(H / step),)`` and of each kept column ``(ceil(W / step),)``."""
    f = np.asarray(frame)
    if f.ndim == 2:
        f = f[:, :, None]
    if numba_enabled() and f.dtype == np.uint8:
        return _profiles_numba(f, int(step))
    sub = f[::step, ::step].astype(np.float64).sum(axis=2)
    return sub.mean(axis=1), sub.mean(axis=0)


@njit(cache=True)
def _profiles_numba(f, step):  # pragma: no cover - compiled
    """The sums are integers, kept in integer accumulators (exact, as the float sums were: the same means to the
    bit) and divided once at the end."""
    h, w, c = f.shape
    nh = (h + step - 1) // step
    nw = (w + step - 1) // step
    rows = np.empty(nh)
    icols = np.zeros(nw, np.int64)
    for i in range(nh):
        y = i * step
        acc = 0
        if c == 3:
            for j in range(nw):
                x = j * step
                v = np.int64(f[y, x, 0]) + np.int64(f[y, x, 1]) + np.int64(f[y, x, 2])
                acc += v
                icols[j] += v
        else:
            for j in range(nw):
                x = j * step
                v = np.int64(0)
                for k in range(c):
                    v += np.int64(f[y, x, k])
                acc += v
                icols[j] += v
        rows[i] = acc / nw
    cols = np.empty(nw)
    for j in range(nw):
        cols[j] = icols[j] / nh
    return rows, cols


def _normalised_derivative(p: np.ndarray) -> np.ndarray:
    d = np.diff(np.asarray(p, dtype=np.float64))
    s = d.std()
    return d / s if s > 1e-9 else np.zeros_like(d)


def profile_shift(a: np.ndarray, b: np.ndarray, max_shift: int, *, min_gain: float = 0.8) -> float:
    """The shift ``s`` (sub-pixel, in profile samples) that best carries profile ``a`` onto profile ``b``
    (``b[i + s] ~ a[i]``), within ``±max_shift``; 0 when no shift matches clearly better than none.

    The two profiles' derivatives, each scaled to unit spread, are compared by their mean absolute difference over
    their overlap (at least half of them). The best integer shift is refined by a parabola through its neighbours'
    costs. It is taken only when its cost is below ``min_gain`` times the cost of no shift, and below ``min_gain``
    times the median cost of all the shifts tried (profiles of noise alone, on a featureless view, give one of
    some seventy costs that dips below no shift's by chance, but hardly below their median): a flat or changing
    scene (light, a large moving object) gives no clear minimum, and the samples are then left where they are.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if numba_enabled():
        return float(_profile_shift_numba(a, b, int(max_shift), float(min_gain)))
    da, db = _normalised_derivative(a), _normalised_derivative(b)
    n = min(da.size, db.size)
    m = int(min(max_shift, n // 2))
    if m < 1 or not np.any(da) or not np.any(db):
        return 0.0
    return _refine(_shift_costs_numpy(da[:n], db[:n], m), m, min_gain)


@njit(cache=True)
def _refine(costs: np.ndarray, m: int, min_gain: float) -> float:
    """The sub-pixel shift at the least of ``costs`` (shifts ``-m .. m``), or 0 when it is not below ``min_gain``
    times the cost of no shift."""
    best = int(np.argmin(costs))
    if not costs[best] < min_gain * costs[m]:
        return 0.0
    if not costs[best] < min_gain * np.median(costs):  # a dip among noisy costs, not a match: no shift
        return 0.0
    shift = float(best - m)
    if 0 < best < 2 * m:
        c0, c1, c2 = costs[best - 1], costs[best], costs[best + 1]
        den = c0 - 2.0 * c1 + c2
        if den > 1e-12:
            shift += 0.5 * (c0 - c2) / den
    return shift


@njit(cache=True)
def _unit_derivative(p):  # pragma: no cover - compiled; :func:`_normalised_derivative` is the reference
    n = p.size - 1
    d = np.empty(max(n, 0))
    if n <= 0:
        return d
    mean = 0.0
    for i in range(n):
        d[i] = p[i + 1] - p[i]
        mean += d[i]
    mean /= n
    var = 0.0
    for i in range(n):
        var += (d[i] - mean) ** 2
    sd = np.sqrt(var / n)
    if sd > 1e-9:
        for i in range(n):
            d[i] /= sd
    else:
        d[:] = 0.0
    return d


@njit(cache=True)
def _profile_shift_numba(a, b, max_shift, min_gain):  # pragma: no cover - compiled
    da = _unit_derivative(a)
    db = _unit_derivative(b)
    n = min(da.size, db.size)
    m = min(max_shift, n // 2)
    if m < 1 or not np.any(da != 0.0) or not np.any(db != 0.0):
        return 0.0
    return _refine(_shift_costs(da[:n], db[:n], m), m, min_gain)


def _shift_costs_numpy(da: np.ndarray, db: np.ndarray, m: int) -> np.ndarray:
    """Mean absolute difference of ``da[i]`` and ``db[i + s]`` over their overlap, for ``s = -m .. m``."""
    n = da.size
    costs = np.empty(2 * m + 1)
    for k, s in enumerate(range(-m, m + 1)):
        if s >= 0:
            costs[k] = np.abs(da[: n - s] - db[s:n]).mean()
        else:
            costs[k] = np.abs(da[-s:n] - db[: n + s]).mean()
    return costs


@njit(cache=True)
def _abs_sum(da, db, s, lo, hi, acc):  # pragma: no cover - compiled
    """``acc`` plus ``|da[i] - db[i + s]|`` for ``i`` from ``lo`` to ``hi`` (exclusive), in order."""
    for i in range(lo, hi):
        acc += abs(da[i] - db[i + s])
    return acc


@njit(cache=True)
def _shift_costs(da, db, m):  # pragma: no cover - compiled; :func:`_shift_costs_numpy` is the reference
    """Each shift's sum runs over ``i`` in ascending order, as one loop per shift would (the same costs to the last
    bit); four shifts are summed side by side over their common range, so that four additions are in flight."""
    n = da.size
    nk = 2 * m + 1
    costs = np.empty(nk)
    k0 = 0
    while k0 + 4 <= nk:
        s0 = k0 - m
        lo0, lo1, lo2, lo3 = max(0, -s0), max(0, -s0 - 1), max(0, -s0 - 2), max(0, -s0 - 3)
        hi0, hi1, hi2, hi3 = min(n, n - s0), min(n, n - s0 - 1), min(n, n - s0 - 2), min(n, n - s0 - 3)
        lo = max(max(lo0, lo1), max(lo2, lo3))
        hi = min(min(hi0, hi1), min(hi2, hi3))
        # each shift's own head, the common range with the four side by side, each shift's own tail
        a0 = _abs_sum(da, db, s0, lo0, lo, 0.0)
        a1 = _abs_sum(da, db, s0 + 1, lo1, lo, 0.0)
        a2 = _abs_sum(da, db, s0 + 2, lo2, lo, 0.0)
        a3 = _abs_sum(da, db, s0 + 3, lo3, lo, 0.0)
        for i in range(lo, hi):
            x = da[i]
            a0 += abs(x - db[i + s0])
            a1 += abs(x - db[i + s0 + 1])
            a2 += abs(x - db[i + s0 + 2])
            a3 += abs(x - db[i + s0 + 3])
        costs[k0] = _abs_sum(da, db, s0, hi, hi0, a0) / (hi0 - lo0)
        costs[k0 + 1] = _abs_sum(da, db, s0 + 1, hi, hi1, a1) / (hi1 - lo1)
        costs[k0 + 2] = _abs_sum(da, db, s0 + 2, hi, hi2, a2) / (hi2 - lo2)
        costs[k0 + 3] = _abs_sum(da, db, s0 + 3, hi, hi3, a3) / (hi3 - lo3)
        k0 += 4
    for k in range(k0, nk):
        s = k - m
        lo, hi = max(0, -s), min(n, n - s)
        costs[k] = _abs_sum(da, db, s, lo, hi, 0.0) / (hi - lo)
    return costs


def camera_shift(prev: tuple[np.ndarray, np.ndarray], cur: tuple[np.ndarray, np.ndarray], *,
                 max_shift: float | tuple[float, float], step: int = 2, min_gain: float = 0.8) -> tuple[float, float]:
    """``(dx, dy)`` in pixels: the translation of the image content from the frame of the profiles ``prev`` to that
    of ``cur`` (both from :func:`frame_profiles` with the same ``step``), searched within ``±max_shift`` pixels
    along each axis (one number, or ``(along x, along y)``; :func:`profile_shift`)."""
    mx, my = (max_shift, max_shift) if np.isscalar(max_shift) else max_shift
    dy = profile_shift(prev[0], cur[0], max(int(np.ceil(my / step)), 1), min_gain=min_gain)
    dx = profile_shift(prev[1], cur[1], max(int(np.ceil(mx / step)), 1), min_gain=min_gain)
    return dx * step, dy * step


def lattice_step(height: int, width: int, samples: int = 256) -> int:
    """The lattice step that leaves at most ``samples`` samples along the frame's longer side."""
    return max(1, -(-max(int(height), int(width)) // int(samples)))
