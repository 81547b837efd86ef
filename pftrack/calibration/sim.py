"""Simulated measurements of the intelligent space (book ch. 12, ch12.md §4 ``sim.py``).

Exact truth, seeded noise: a unicycle robot (Eq. 7) steered along a path that covers the room,
wheel-encoder odometry, an ultrasound tag at ``(L, 0)`` on the robot (Eq. 9), horizontal laser
range finders that see the robot's outline and the legs of walking people, and ceiling cameras
that see the robot's marker(s).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .scene import CameraSpec, LrfPose, Scene

LRF_FOV = np.pi
LRF_STEP = np.radians(0.5)
LRF_MAX_RANGE = 8.0
LEG_RADIUS = 0.076       # d = 0.06 m of Eq. (1) implies rho ~ 0.076 m (ch12.md §1.3)
LEG_SPREAD = 0.12        # half the distance between the legs
ULTRASOUND_HZ = 5.0


def wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def unicycle_step(state: np.ndarray, v: float, w: float, dt: float) -> np.ndarray:
    """Eq. (8): one Euler step of ``x' = v cos th, y' = v sin th, th' = w``."""
    x, y, th = state
    return np.array([x + v * dt * np.cos(th), y + v * dt * np.sin(th), wrap(th + w * dt)])


def coverage_waypoints(room, margin: float = 0.6, n: int = 120) -> np.ndarray:
    """A 3:2 Lissajous figure inside the room: it crosses every part of the floor (ch12.md pitfall 10)."""
    W, H = room
    margin = min(margin, 0.25 * min(W, H))
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.stack([(W / 2 - margin) * np.sin(3 * t + np.pi / 4), (H / 2 - margin) * np.sin(2 * t)], 1)


def figure_eight(t, ax: float = 1.6, ay: float = 0.9, beta: float = 2 * np.pi / 600, center=(0.0, 0.0)):
    """The restored Eq. (14): ``x = ax sin(beta t)``, ``y = ay sin(2 beta t)`` around ``center``."""
    t = np.asarray(t, float)
    return np.stack([center[0] + ax * np.sin(beta * t), center[1] + ay * np.sin(2 * beta * t)], -1)


@dataclass
class Trajectory:
    t: np.ndarray            # (T,)
    pose: np.ndarray         # (T, 3) true x, y, theta
    cmd: np.ndarray          # (T, 2) true v, omega applied from t[k] to t[k+1]


def drive(scene: Scene, waypoints: np.ndarray | None = None) -> Trajectory:
    """Steer the robot from its start pose through the waypoints (cyclically) for ``duration_s``."""
    r = scene.robot
    dt = 1.0 / r.rate_hz
    n = round(r.duration_s * r.rate_hz) + 1
    wp = coverage_waypoints(scene.room) if waypoints is None else np.asarray(waypoints, float)
    # start at the waypoint nearest to the start position
    k = int(np.argmin(np.linalg.norm(wp - np.asarray(r.start[:2]), axis=1)))
    pose = np.empty((n, 3))
    cmd = np.zeros((n, 2))
    pose[0] = r.start
    for i in range(n - 1):
        x, y, th = pose[i]
        for _ in range(len(wp)):                # next waypoint not yet reached (bounded: a tiny room has all close)
            if np.hypot(*(wp[k] - (x, y))) >= 0.25:
                break
            k = (k + 1) % len(wp)
        err = wrap(np.arctan2(wp[k, 1] - y, wp[k, 0] - x) - th)
        w = float(np.clip(1.5 * err, -1.0, 1.0))
        v = r.speed * max(np.cos(err), 0.0) ** 2
        cmd[i] = v, w
        pose[i + 1] = unicycle_step(pose[i], v, w, dt)
    cmd[-1] = cmd[-2]
    return Trajectory(np.arange(n) * dt, pose, cmd)


def odometry(traj: Trajectory, sigma_v: float, sigma_w: float, rng) -> np.ndarray:
    """Wheel-encoder readings: the applied ``(v, omega)`` with white Gaussian noise (L10746)."""
    return traj.cmd + rng.normal(0, 1, traj.cmd.shape) * (sigma_v, sigma_w)


def ultrasound(traj: Trajectory, tag_offset: float, sigma: float, rng, rate_hz: float = ULTRASOUND_HZ):
    """Eq. (9): tag positions ``(x + L cos th, y + L sin th) + noise`` at ``rate_hz``; returns (indices, z)."""
    step = max(1, round((1.0 / rate_hz) / (traj.t[1] - traj.t[0])))
    idx = np.arange(0, len(traj.t), step)
    p = traj.pose[idx]
    z = p[:, :2] + tag_offset * np.stack([np.cos(p[:, 2]), np.sin(p[:, 2])], 1)
    return idx, z + rng.normal(0, sigma, z.shape)


def human_positions(scene: Scene, t: np.ndarray) -> np.ndarray:
    """(T, n_humans, 3): each person walks start -> end -> start at constant speed; last column heading."""
    out = np.zeros((len(t), len(scene.humans), 3))
    for j, h in enumerate(scene.humans):
        a, b = np.asarray(h.start), np.asarray(h.end)
        L = max(np.linalg.norm(b - a), 1e-6)
        s = (h.speed * t) % (2 * L)
        fwd = s <= L
        frac = np.where(fwd, s, 2 * L - s) / L
        out[:, j, :2] = a + frac[:, None] * (b - a)
        head = np.arctan2(*(b - a)[::-1])
        out[:, j, 2] = np.where(fwd, head, wrap(head + np.pi))
    return out


def leg_circles(humans_t: np.ndarray, t: float) -> np.ndarray:
    """(2 n, 2) leg centres of the people at one instant (legs swing +-0.1 m along the heading)."""
    legs = []
    for x, y, h in humans_t:
        side = np.array([-np.sin(h), np.cos(h)]) * LEG_SPREAD
        fwd = np.array([np.cos(h), np.sin(h)]) * 0.1 * np.sin(2 * np.pi * 1.0 * t)
        legs += [np.array([x, y]) + side + fwd, np.array([x, y]) - side - fwd]
    return np.array(legs).reshape(-1, 2)


def beam_angles() -> np.ndarray:
    return np.arange(-LRF_FOV / 2, LRF_FOV / 2 + 1e-9, LRF_STEP)


def cast(origin, angles, room, circles: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Ranges of rays from ``origin`` (world angles) to the room's walls or the nearest circle."""
    u = np.stack([np.cos(angles), np.sin(angles)], 1)
    W, H = room
    lo, hi = np.array([-W / 2, -H / 2]), np.array([W / 2, H / 2])
    with np.errstate(divide="ignore", invalid="ignore"):
        tw = np.where(u > 0, (hi - origin) / u, np.where(u < 0, (lo - origin) / u, np.inf))
    r = np.min(tw, axis=1)
    if len(circles):
        oc = circles[None, :, :] - origin                      # (1, C, 2)
        b = np.einsum("bk,ck->bc", u, oc[0])                   # (B, C)
        cc = np.sum(oc[0] ** 2, 1) - radii ** 2                # (C,)
        disc = b ** 2 - cc
        tc = np.where(disc >= 0, b - np.sqrt(np.maximum(disc, 0)), np.inf)
        tc = np.where(tc > 0, tc, np.inf)
        r = np.minimum(r, tc.min(axis=1))
    return np.minimum(r, LRF_MAX_RANGE)


def scan(pose: LrfPose, room, circles, radii, sigma: float, rng) -> np.ndarray:
    """One scan in the LRF's own frame: ranges at :func:`beam_angles` (no return -> max range)."""
    a = beam_angles()
    r = cast(np.array([pose.x, pose.y]), a + pose.theta, room, np.asarray(circles, float).reshape(-1, 2),
             np.asarray(radii, float))
    hit = r < LRF_MAX_RANGE
    return np.where(hit, r + rng.normal(0, sigma, r.shape), LRF_MAX_RANGE)


def scan_points(ranges: np.ndarray) -> np.ndarray:
    a = beam_angles()
    return np.stack([ranges * np.cos(a), ranges * np.sin(a)], 1)


def lrf_scans(scene: Scene, traj: Trajectory, rng, *, empty: int = 50):
    """For every LRF: ``empty`` scans of the empty room, then one scan per trajectory step."""
    humans = human_positions(scene, traj.t)
    out = []
    for pose in scene.lrfs:
        bg = np.stack([scan(pose, scene.room, [], [], scene.noise.lrf_range, rng) for _ in range(empty)])
        scans = np.empty((len(traj.t), len(beam_angles())))
        for k, (x, y, _) in enumerate(traj.pose):
            legs = leg_circles(humans[k], traj.t[k])
            circles = np.vstack([[[x, y]], legs]) if len(legs) else np.array([[x, y]])
            radii = np.r_[scene.robot.radius, np.full(len(legs), LEG_RADIUS)]
            scans[k] = scan(pose, scene.room, circles, radii, scene.noise.lrf_range, rng)
        out.append((bg, scans))
    return out


def project(cam: CameraSpec, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixels of world points and whether each is in front of the camera and inside the image."""
    import cv2

    X = np.asarray(X, np.float64).reshape(-1, 3)
    R, _ = cv2.Rodrigues(np.asarray(cam.rvec, float))
    z = X @ R[2] + cam.tvec[2]
    uv, _ = cv2.projectPoints(X, np.asarray(cam.rvec, float), np.asarray(cam.tvec, float), cam.K(), cam.dist())
    uv = uv.reshape(-1, 2)
    ok = (z > 0.1) & (uv[:, 0] >= 0) & (uv[:, 0] <= cam.width - 1) & (uv[:, 1] >= 0) & (uv[:, 1] <= cam.height - 1)
    return uv, ok


def camera_observations(scene: Scene, traj: Trajectory, rng):
    """For every camera: a list of (step index, height, noisy pixel) of the visible markers."""
    out = []
    for cam in scene.cameras:
        rows = []
        for h in scene.robot.marker_height:
            X = np.c_[traj.pose[:, :2], np.full(len(traj.t), h)]
            uv, ok = project(cam, X)
            idx = np.flatnonzero(ok)
            noisy = uv[idx] + rng.normal(0, scene.noise.pixel, (len(idx), 2))
            rows += [(int(i), h, p) for i, p in zip(idx, noisy)]
        rows.sort(key=lambda r: (r[0], r[1]))
        out.append(rows)
    return out
