"""Optional Numba support.

pftrack imports and works without Numba: every compiled kernel has a pure NumPy
reference implementation with the same signature and the same results (tests
check this).  When Numba is installed the compiled kernels are used unless the
environment variable ``PFTRACK_NO_NUMBA`` is set to a non-empty value other than
``0``.
"""

from __future__ import annotations

import os

import numpy as np

try:  # pragma: no cover - exercised implicitly by whichever branch is installed
    import numba as _numba

    NUMBA_INSTALLED = True
except Exception:  # ImportError, or a broken llvmlite
    _numba = None
    NUMBA_INSTALLED = False


_ENABLED = NUMBA_INSTALLED and os.environ.get("PFTRACK_NO_NUMBA", "") in ("", "0")


def numba_enabled() -> bool:
    """True when compiled kernels should be used (read once; see :func:`set_numba_enabled`)."""
    return _ENABLED


def set_numba_enabled(flag: bool) -> bool:
    """Switch between compiled kernels and the NumPy reference path; returns the previous setting."""
    global _ENABLED
    previous = _ENABLED
    _ENABLED = bool(flag) and NUMBA_INSTALLED
    return previous


#: ``numba.prange`` (parallel loops in kernels compiled with ``parallel=True``), or ``range`` without Numba.
prange = range if _numba is None else _numba.prange


def njit(*args, **kwargs):
    """``numba.njit`` with caching when available, otherwise a no-op decorator."""
    kwargs.setdefault("cache", True)
    kwargs.setdefault("nogil", True)
    if _numba is None:
        if args and callable(args[0]):
            return args[0]
        return lambda f: f
    return _numba.njit(*args, **kwargs)


@njit
def _block_sum(a, lo, n):
    """NumPy's pairwise summation of ``n <= 128`` elements: eight interleaved partial sums, then the rest."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[lo + i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    m = n - n % 8
    while i < m:
        r0 += a[lo + i]
        r1 += a[lo + i + 1]
        r2 += a[lo + i + 2]
        r3 += a[lo + i + 3]
        r4 += a[lo + i + 4]
        r5 += a[lo + i + 5]
        r6 += a[lo + i + 6]
        r7 += a[lo + i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@njit
def np_sum(a):
    """``a.sum()`` of a 1-D float64 array as NumPy computes it (pairwise: blocks of at most 128 summed by
    :func:`_block_sum`, longer runs split in halves rounded to multiples of 8 and the halves added), so that
    compiled code gives the number NumPy code did, to the last bit (checked against NumPy in the tests).
    Iterative: Numba cannot cache a recursive function."""
    n = a.shape[0]
    if n <= 128:
        return _block_sum(a, 0, n)
    # post-order walk of the halving tree with explicit stacks (depth < 64 for any array)
    los = np.empty(128, np.int64)
    ns = np.empty(128, np.int64)
    done = np.zeros(128, np.bool_)
    vals = np.empty(128)
    top = 0
    nv = 0
    los[0] = 0
    ns[0] = n
    while top >= 0:
        lo = los[top]
        m = ns[top]
        if m <= 128:
            vals[nv] = _block_sum(a, lo, m)
            nv += 1
            top -= 1
        elif done[top]:
            vals[nv - 2] = vals[nv - 2] + vals[nv - 1]
            nv -= 1
            done[top] = False
            top -= 1
        else:
            done[top] = True
            m2 = m // 2
            m2 -= m2 % 8
            los[top + 1] = lo + m2  # the right half, evaluated second
            ns[top + 1] = m - m2
            los[top + 2] = lo  # the left half, evaluated first
            ns[top + 2] = m2
            top += 2
    return vals[0]
