"""Robot localisation with an extended Kalman filter (book ch. 12 §5, Eqs. 7-13 restored in
ch12.md §1.7 after Welch & Bishop's notation A, W, H, V).

State ``(x, y, theta)``; inputs ``(v, omega)`` from the wheel encoders, whose white noise ``Q`` acts
through ``W`` (Eq. 11); measurements: the ultrasound tag at ``(L, 0)`` in the robot frame (Eq. 9).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .sim import wrap


@dataclass(frozen=True)
class EkfParams:
    """``Q = diag(sigma_v^2, sigma_w^2)`` (encoder noise), ``R = diag(sigma_z^2, sigma_z^2)`` (tag), ``L`` the
    tag offset (Eq. 9).  The chapter says only "constant diagonal, tuned experimentally" (L10755)."""

    sigma_v: float = 0.02
    sigma_w: float = 0.05
    sigma_z: float = 0.05
    tag_offset: float = 0.15


def f(x, u, dt):
    """Eq. (8)."""
    return np.array([x[0] + u[0] * dt * np.cos(x[2]), x[1] + u[0] * dt * np.sin(x[2]), wrap(x[2] + u[1] * dt)])


def A_jac(x, u, dt):
    """Eq. (10)."""
    return np.array([[1, 0, -u[0] * dt * np.sin(x[2])], [0, 1, u[0] * dt * np.cos(x[2])], [0, 0, 1.0]])


def W_jac(x, dt):
    """Eq. (11)."""
    return np.array([[dt * np.cos(x[2]), 0], [dt * np.sin(x[2]), 0], [0, dt]])


def h(x, L):
    """Eq. (9) without noise."""
    return np.array([x[0] + L * np.cos(x[2]), x[1] + L * np.sin(x[2])])


def H_jac(x, L):
    """Eq. (12); ``V = I`` (Eq. 13)."""
    return np.array([[1, 0, -L * np.sin(x[2])], [0, 1, L * np.cos(x[2])]])


class TagUnicycleEKF:
    def __init__(self, x0, P0=None, params: EkfParams = EkfParams()):
        self.x = np.asarray(x0, np.float64).copy()
        self.P = np.diag([1e-4, 1e-4, 1e-4]) if P0 is None else np.asarray(P0, np.float64).copy()
        self.p = params
        self.Q = np.diag([params.sigma_v ** 2, params.sigma_w ** 2])
        self.R = np.eye(2) * params.sigma_z ** 2

    def predict(self, u, dt) -> None:
        A, W = A_jac(self.x, u, dt), W_jac(self.x, dt)
        self.x = f(self.x, u, dt)
        self.P = A @ self.P @ A.T + W @ self.Q @ W.T

    def update(self, z) -> None:
        H = H_jac(self.x, self.p.tag_offset)
        S = H @ self.P @ H.T + self.R
        K = np.linalg.solve(S, H @ self.P).T
        self.x = self.x + K @ (np.asarray(z, float) - h(self.x, self.p.tag_offset))
        self.x[2] = wrap(self.x[2])
        I_KH = np.eye(3) - K @ H
        self.P = I_KH @ self.P @ I_KH.T + K @ self.R @ K.T


def run_ekf(t, odo, z_idx, z, x0, params: EkfParams = EkfParams()):
    """Filter a whole run: ``odo[k]`` is applied from ``t[k]`` to ``t[k+1]``; tag fixes at steps ``z_idx``.
    Returns the posterior states (T, 3) and covariances (T, 3, 3)."""
    ekf = TagUnicycleEKF(x0, params=params)
    fix = dict(zip(np.asarray(z_idx).tolist(), np.asarray(z)))
    X, P = np.empty((len(t), 3)), np.empty((len(t), 3, 3))
    for k in range(len(t)):
        if k > 0:
            ekf.predict(odo[k - 1], t[k] - t[k - 1])
        if k in fix:
            ekf.update(fix[k])
        X[k], P[k] = ekf.x, ekf.P
    return X, P
