"""Plot of a simulated calibration (book ch. 12): room, true and estimated sensors, true and EKF paths."""

from __future__ import annotations

import numpy as np


def _camera_centre(rvec, tvec):
    import cv2

    R, _ = cv2.Rodrigues(np.asarray(rvec, float))
    return -R.T @ np.asarray(tvec, float).ravel(), R[2]


def plot_calibration(scene, m, est, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    W, H = scene.room
    fig, ax = plt.subplots(figsize=(7, 6.5))
    ax.add_patch(plt.Rectangle((-W / 2, -H / 2), W, H, fill=False, lw=2, color="k"))
    ax.plot(*m.traj.pose[:, :2].T, color="0.6", lw=1, label="true path")
    ax.plot(*est["ekf_path"][:, :2].T, color="tab:green", lw=0.8, ls="--", label="EKF path")
    for i, (t, e) in enumerate(zip(scene.lrfs, est["lrfs"])):
        ax.plot(t.x, t.y, "ks", ms=8, label="LRF (true)" if i == 0 else None)
        ax.arrow(t.x, t.y, 0.4 * np.cos(t.theta), 0.4 * np.sin(t.theta), color="k", width=0.02)
        if e.get("x") is not None:
            ax.plot(e["x"], e["y"], "r+", ms=14, mew=2, label="LRF (estimated)" if i == 0 else None)
            ax.arrow(e["x"], e["y"], 0.4 * np.cos(e["theta"]), 0.4 * np.sin(e["theta"]), color="r", width=0.01)
        ax.annotate(f"L{i + 1}", (t.x, t.y), textcoords="offset points", xytext=(6, 6))
    for i, (c, e) in enumerate(zip(scene.cameras, est["cameras"])):
        C, z = _camera_centre(c.rvec, c.tvec)
        ax.plot(C[0], C[1], "bo", ms=7, label="camera (true)" if i == 0 else None)
        ax.arrow(C[0], C[1], 0.5 * z[0], 0.5 * z[1], color="b", width=0.015)
        if not isinstance(e, dict):
            Ce, _ = _camera_centre(e.rvec, e.tvec)
            ax.plot(Ce[0], Ce[1], "mx", ms=10, mew=2, label="camera (estimated)" if i == 0 else None)
        ax.annotate(f"C{i + 1}", (C[0], C[1]), textcoords="offset points", xytext=(6, -12))
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("Calibration by robot tracking (book ch. 12)")
    ax.legend(loc="upper left", fontsize=8, framealpha=0.8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
