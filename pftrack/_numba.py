"""Optional Numba support.

pftrack imports and works without Numba: every compiled kernel has a pure NumPy
reference implementation with the same signature and the same results (tests
check this).  When Numba is installed the compiled kernels are used unless the
environment variable ``PFTRACK_NO_NUMBA`` is set to a non-empty value other than
``0``.
"""

from __future__ import annotations

import os

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
