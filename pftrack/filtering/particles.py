"""Weighted particle sets kept in the log domain.

A particle set approximates a posterior by ``N`` states ``s^(n)`` (rows of an
``(N, D)`` float array) with weights ``pi^(n)`` (Nummiaro et al., §2).  The
weights are stored as log-weights so that likelihoods far in the tail never
underflow to zero and never produce NaN: normalisation uses log-sum-exp.
"""

from __future__ import annotations

import numpy as np

from .kernels import log_normalize, normalize_and_estimate

__all__ = ["ParticleSet", "effective_sample_size", "log_normalize", "weights_from_log"]


def weights_from_log(log_w: np.ndarray) -> np.ndarray:
    """Normalised linear weights from (unnormalised) log-weights."""
    lw, _ = log_normalize(log_w)
    w = np.exp(lw)
    w /= w.sum()
    return w


def effective_sample_size(weights: np.ndarray) -> float:
    """``N_eff = 1 / sum(w^2)`` for normalised weights."""
    w = np.asarray(weights, dtype=np.float64)
    s = float(np.dot(w, w))
    return 1.0 / s if s > 0 else 0.0


#: ``-log(N)`` (NumPy's) by particle count: the uniform log-weight after resampling
_NEG_LOG_N: dict[int, np.floating] = {}


class ParticleSet:
    """``N`` states of dimension ``D`` with log-weights.

    Attributes
    ----------
    states : (N, D) float64
    log_weights : (N,) float64, normalised (log-sum-exp = 0)
    w : (N,) float64, the normalised linear weights (kept in step with ``log_weights``)
    """

    __slots__ = ("states", "log_weights", "w", "_scratch", "_mean", "_ess")

    def __init__(self, states: np.ndarray, log_weights: np.ndarray | None = None):
        states = np.array(states, dtype=np.float64, copy=True)
        if states.ndim != 2 or states.shape[0] == 0:
            raise ValueError(f"states must be a non-empty (N, D) array, got shape {states.shape}")
        self.states = states
        n = states.shape[0]
        self._scratch = np.empty_like(self.states)
        self._mean = np.empty(states.shape[1])
        self.log_weights = np.empty(n)
        self.w = np.empty(n)
        self.set_log_likelihood(np.zeros(n) if log_weights is None else np.asarray(log_weights, dtype=np.float64))

    def __len__(self) -> int:
        return self.states.shape[0]

    @property
    def n(self) -> int:
        return self.states.shape[0]

    @property
    def dim(self) -> int:
        return self.states.shape[1]

    @property
    def weights(self) -> np.ndarray:
        """Normalised linear weights (a copy)."""
        return self.w.copy()

    def set_log_likelihood(self, log_lik: np.ndarray, *, accumulate: bool = False) -> bool:
        """Set (or multiply in, with ``accumulate``) likelihoods and normalise.

        Also computes the weighted mean and the effective sample size.  Returns
        False when every likelihood was zero; the weights are then uniform.
        """
        ll = np.asarray(log_lik, dtype=np.float64)
        if accumulate:
            ll = ll + self.log_weights
        ok, self._ess = normalize_and_estimate(ll, self.states, self.log_weights, self.w, self._mean)
        return ok

    def mean(self) -> np.ndarray:
        """Weighted mean state ``E[S] = sum_n pi^(n) s^(n)`` (Nummiaro Eq. 1)."""
        return (self.w[:, None] * self.states).sum(axis=0)

    def covariance(self) -> np.ndarray:
        w = self.w
        d = self.states - w @ self.states
        return (d * w[:, None]).T @ d

    def ess(self) -> float:
        """Effective sample size ``1 / sum(w^2)``."""
        return effective_sample_size(self.w)

    def scale_columns(self, start: int, stop: int, factor: float) -> None:
        """Multiply the state columns ``start:stop`` of every particle, and of the weighted mean, by ``factor`` (a
        size correction found after the estimate; the weights are unchanged)."""
        self.states[:, start:stop] *= factor
        self._mean[start:stop] *= factor

    def resample(self, indices: np.ndarray) -> None:
        """Replace the set by the selected particles with uniform weights (in place)."""
        np.take(self.states, indices, axis=0, out=self._scratch, mode="clip")  # valid indices; "raise" buffers out
        self.states, self._scratch = self._scratch, self.states
        n = self.n
        neg_log = _NEG_LOG_N.get(n)
        if neg_log is None:
            neg_log = _NEG_LOG_N[n] = -np.log(n)
        self.log_weights.fill(neg_log)
        self.w.fill(1.0 / n)

    def copy(self) -> "ParticleSet":
        return ParticleSet(self.states, self.log_weights)
