"""The chapter's whole calibration on simulated data (book ch. 12): simulate the measurements of a
scene, estimate every sensor from the measurements alone, and score the estimate against the truth.

Estimation sees only: the odometry, the ultrasound fixes, the LRF scans (with 50 scans of the empty
room), the marker pixels of each camera, the robot's known start pose, the marker heights and the
sensor noise levels (the EKF's Q and R are "tuned" to them, L10756).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import sim
from .camcal import calibrate, image_to_ground, nine_points
from .ekf import EkfParams, run_ekf
from .lrf import LrfParams, track_robot
from .rigid2d import fit_rigid_2d, lmeds_rigid_2d, residuals
from .scene import Scene


@dataclass
class Measurements:
    traj: sim.Trajectory          # truth (used only for scoring)
    odo: np.ndarray
    tag_idx: np.ndarray
    tag: np.ndarray
    lrf: list                     # per LRF: (empty-room scans, scans)
    cams: list                    # per camera: [(step, height, uv)]


def simulate(scene: Scene, seed: int = 0, waypoints=None) -> Measurements:
    rng = np.random.default_rng(seed)
    traj = sim.drive(scene, waypoints)
    odo = sim.odometry(traj, scene.noise.odometry, 2.5 * scene.noise.odometry, rng)
    idx, z = sim.ultrasound(traj, scene.robot.tag_offset, scene.noise.ultrasound, rng)
    return Measurements(traj, odo, idx, z, sim.lrf_scans(scene, traj, rng), sim.camera_observations(scene, traj, rng))


@dataclass(frozen=True)
class EstimateParams:
    settle_s: float = 5.0         # pairs start after this much motion (pitfall 6: theta unobservable at rest)
    refine: bool = True           # LMedS followed by a least-squares refit on its inliers
    use_lmeds: bool = True        # False: plain least squares (Eq. 2), for the ablation
    mismatch: float = 0.0         # fraction of LRF pairs deliberately mis-associated (robustness experiment)


def estimate(scene: Scene, m: Measurements, params: EstimateParams = EstimateParams(), seed: int = 0) -> dict:
    t = m.traj.t
    dt = float(t[1] - t[0])
    ekf_p = EkfParams(sigma_v=max(scene.noise.odometry, 1e-4), sigma_w=max(2.5 * scene.noise.odometry, 1e-4),
                      sigma_z=max(scene.noise.ultrasound, 1e-3), tag_offset=scene.robot.tag_offset)
    X, _ = run_ekf(t, m.odo, m.tag_idx, m.tag, scene.robot.start, ekf_p)
    ok_t = t >= params.settle_s
    rng = np.random.default_rng(seed + 7)
    out = {"lrfs": [], "cameras": [], "ekf_path": X}
    for bg, scans in m.lrf:
        steps, local, _ = track_robot(bg, scans, dt, LrfParams(sigma=max(scene.noise.lrf_range, 0.01) * 3))
        keep = ok_t[steps] if len(steps) else np.zeros(0, bool)
        steps, local = steps[keep], local[keep]
        world = X[steps, :2].copy()
        if params.mismatch > 0 and len(world):     # mis-associated pairs: world points anywhere in the room
            bad = rng.random(len(world)) < params.mismatch
            W, H = scene.room
            world[bad] = rng.uniform((-W / 2, -H / 2), (W / 2, H / 2), (int(bad.sum()), 2))
        entry = {"pairs": len(steps)}
        if len(steps) < 2:
            entry.update(x=None, y=None, theta=None, error="the robot was not tracked by this scanner")
        else:
            if params.use_lmeds:
                th, T, inl, med = lmeds_rigid_2d(local, world, rng=rng, refine=params.refine)
            else:
                th, T = fit_rigid_2d(local, world)
                th = float(th)
                inl = np.ones(len(local), bool)
                med = float(np.median(residuals(th, T, local, world) ** 2))
            r = residuals(th, T, local, world)
            entry.update(x=float(T[0]), y=float(T[1]), theta=float(th), inliers=int(inl.sum()),
                         residual_median_m=float(np.sqrt(med)), residual_rms_m=float(np.sqrt(np.mean(r[inl] ** 2))))
        out["lrfs"].append(entry)
    for cam, obs in zip(scene.cameras, m.cams):
        obs = [o for o in obs if ok_t[o[0]]]
        Xw = np.array([[X[k, 0], X[k, 1], hgt] for k, hgt, _ in obs]).reshape(-1, 3)
        uv = np.array([p for *_, p in obs]).reshape(-1, 2)
        try:
            est = calibrate(Xw, uv, (cam.width, cam.height))
            out["cameras"].append(est)
        except Exception as exc:  # noqa: BLE001 - DegenerateError, or cv2.error on hopeless input
            out["cameras"].append({"error": str(exc).splitlines()[0][:200], "points": len(Xw)})
    return out


def score(scene: Scene, m: Measurements, est: dict) -> dict:
    """Errors against the truth: LRF pose, camera ground-plane error at the nine points (mm), EKF RMSE."""
    lrf = []
    for truth, e in zip(scene.lrfs, est["lrfs"]):
        if e.get("x") is None:
            lrf.append({"translation_m": None, "rotation_rad": None})
            continue
        dth = float(np.abs(sim.wrap(e["theta"] - truth.theta)))
        lrf.append({"translation_m": float(np.hypot(e["x"] - truth.x, e["y"] - truth.y)), "rotation_rad": dth})
    cams = []
    for c, e in zip(scene.cameras, est["cameras"]):
        if isinstance(e, dict):
            cams.append({"mean_mm": None, "max_mm": None})
            continue
        px = nine_points((c.width, c.height))
        g_true = image_to_ground(px, c.K(), c.dist(), c.rvec, c.tvec)
        g_est = image_to_ground(px, e.K, e.dist, e.rvec, e.tvec)
        err = np.linalg.norm(g_true - g_est, axis=1) * 1000
        cams.append({"mean_mm": float(err.mean()), "max_mm": float(err.max()),
                     "f_rel_error": float(abs((e.K[0, 0] + e.K[1, 1]) / 2 - c.f) / c.f)})
    X = est["ekf_path"]
    dpos = np.linalg.norm(X[:, :2] - m.traj.pose[:, :2], axis=1)
    return {"lrfs": lrf, "cameras": cams,
            "ekf": {"position_rmse_m": float(np.sqrt(np.mean(dpos ** 2))),
                    "heading_rmse_rad": float(np.sqrt(np.mean(sim.wrap(X[:, 2] - m.traj.pose[:, 2]) ** 2)))}}


def summary(sc: dict) -> dict:
    tr = [e["translation_m"] for e in sc["lrfs"] if e["translation_m"] is not None]
    rot = [e["rotation_rad"] for e in sc["lrfs"] if e["rotation_rad"] is not None]
    mean = [e["mean_mm"] for e in sc["cameras"] if e["mean_mm"] is not None]
    mx = [e["max_mm"] for e in sc["cameras"] if e["max_mm"] is not None]
    nan = float("nan")
    return {"lrf_max_translation_m": max(tr) if tr else nan, "lrf_max_rotation_rad": max(rot) if rot else nan,
            "camera_mean_mm": float(np.mean(mean)) if mean else nan, "camera_max_mm": float(np.mean(mx)) if mx else nan,
            "lrfs_failed": len(sc["lrfs"]) - len(tr), "cameras_failed": len(sc["cameras"]) - len(mean)}


def result_json(est: dict, sc: dict | None = None) -> dict:
    """The estimate in the scene schema, plus residuals (and the errors against the truth when scored)."""
    cams = [e.to_dict() if not isinstance(e, dict) else e for e in est["cameras"]]
    out = {"lrfs": est["lrfs"], "cameras": cams}
    if sc is not None:
        out["errors_vs_truth"] = sc
        out["summary"] = summary(sc)
    return out


def run(scene: Scene, seed: int = 0, params: EstimateParams = EstimateParams(), waypoints=None):
    m = simulate(scene, seed, waypoints)
    est = estimate(scene, m, params, seed)
    sc = score(scene, m, est)
    return m, est, sc
