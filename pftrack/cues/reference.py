"""Online learning of a reference histogram from the best stable frame of each interval
(book ch. 5 §5.2, Eqs. 17-19; ``shared/book/ch05.md`` §1.5).

Frames are grouped in intervals of ``S`` frames.  Within an interval every frame's final
region is scored against the reference in force, ``rho_t = sum sqrt(q p_t)``, together with its
corner displacement ``dist_t``.  A frame is *eligible* when ``dist_t < T1`` and ``rho_t > T2``
(Eq. 17).  At the interval's end the reference becomes ``q <- kappa p_t* + (1 - kappa) q``
(Eq. 18) with ``t*`` the eligible frame of highest ``rho`` (Eq. 19); without an eligible frame
it is unchanged.  Only the best eligible histogram is kept (O(1) memory).
"""

from __future__ import annotations

import math

import numpy as np


class ReferenceLearner:
    """Eqs. 17-19 as a small state machine: :meth:`observe` once per frame returns the reference."""

    def __init__(self, q: np.ndarray, *, interval: int = 25, kappa: float = 0.1, t1_dist: float = 30.0,
                 t2_rho: float = 0.95):
        self.q = np.asarray(q, dtype=np.float64).copy()
        self.interval, self.kappa = int(interval), float(kappa)
        self.t1_dist, self.t2_rho = float(t1_dist), float(t2_rho)
        self.count = 0
        self.best_rho = -math.inf
        self.best_p: np.ndarray | None = None
        self.updates = 0

    def eligible(self, rho: float, dist: float) -> bool:
        """Eq. 17."""
        return dist < self.t1_dist and rho > self.t2_rho

    def observe(self, rho: float, dist: float, p: np.ndarray) -> np.ndarray:
        """Record one frame (its ``rho`` against the current reference, ``dist`` and histogram ``p``);
        at an interval's end apply Eq. 18.  Returns the reference in force for the next frame."""
        self.count += 1
        if self.eligible(rho, dist) and rho > self.best_rho:
            self.best_rho = float(rho)
            self.best_p = np.asarray(p, dtype=np.float64).copy()
        if self.count % self.interval == 0:
            if self.best_p is not None:
                self.q = self.kappa * self.best_p + (1.0 - self.kappa) * self.q
                self.updates += 1
            self.best_rho, self.best_p = -math.inf, None
        return self.q
