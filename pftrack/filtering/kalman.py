"""A linear Kalman filter (used to predict the mean-shift start point, Comaniciu et al. 2003)."""

from __future__ import annotations

import numpy as np


class KalmanFilter:
    """Linear-Gaussian filter ``x_t = F x_{t-1} + w``, ``z_t = H x_t + v``.

    ``w ~ N(0, Q)``, ``v ~ N(0, R)``.  :meth:`predict` and :meth:`update` follow
    the textbook equations; the Joseph form keeps the covariance symmetric and
    positive semi-definite.
    """

    def __init__(self, F: np.ndarray, H: np.ndarray, Q: np.ndarray, R: np.ndarray,
                 x0: np.ndarray, P0: np.ndarray):
        self.F = np.asarray(F, dtype=np.float64)
        self.H = np.asarray(H, dtype=np.float64)
        self.Q = np.asarray(Q, dtype=np.float64)
        self.R = np.asarray(R, dtype=np.float64)
        self.x = np.asarray(x0, dtype=np.float64).copy()
        self.P = np.asarray(P0, dtype=np.float64).copy()

    @classmethod
    def constant_velocity_2d(cls, position, *, process_std: float = 1.0, measurement_std: float = 2.0,
                             initial_velocity_std: float = 10.0) -> "KalmanFilter":
        """State ``(x, y, vx, vy)`` with white-acceleration noise; measures ``(x, y)``."""
        F = np.eye(4)
        F[0, 2] = F[1, 3] = 1.0
        H = np.zeros((2, 4))
        H[0, 0] = H[1, 1] = 1.0
        G = np.array([[0.5, 0], [0, 0.5], [1, 0], [0, 1]])
        Q = G @ G.T * process_std ** 2
        R = np.eye(2) * measurement_std ** 2
        x0 = np.array([position[0], position[1], 0.0, 0.0])
        P0 = np.diag([measurement_std ** 2, measurement_std ** 2, initial_velocity_std ** 2, initial_velocity_std ** 2])
        return cls(F, H, Q, R, x0, P0)

    def predict(self) -> np.ndarray:
        self.x = self.F @ self.x
        self.P = self.F @ self.P @ self.F.T + self.Q
        return self.x

    def update(self, z) -> np.ndarray:
        z = np.asarray(z, dtype=np.float64)
        y = z - self.H @ self.x
        S = self.H @ self.P @ self.H.T + self.R
        K = np.linalg.solve(S.T, (self.P @ self.H.T).T).T
        self.x = self.x + K @ y
        I_KH = np.eye(self.P.shape[0]) - K @ self.H
        self.P = I_KH @ self.P @ I_KH.T + K @ self.R @ K.T
        return self.x
