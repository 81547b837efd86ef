"""Book ch. 12 experiments (docs/calibration.md): calibrating LRFs and cameras by tracking a robot.

    python scripts/ch12_experiments.py [--seeds 100-109] [--json reports/ch12.json]

Tuning used the chapter's room (`default_scene`, noise seeds 0-9).  The figures reported come from
random rooms and configurations drawn from seeds 100+ (`random_scene(seed)`), which no default was
chosen on, each with 3 LRFs and 4 ceiling cameras:

* Table 1 / C1: the largest LRF pose error (LMedS refined; LMedS as printed; plain least squares),
  clean and with 10 % mis-associated pairs;
* Table 2 / C2-C3: the mean and max ground error at the nine image points, automated vs a simulated
  "manual" calibration (25 surveyed 3-D points with 5 mm survey error);
* C4: the path covering the central half of the room vs the whole room.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from pftrack.calibration import sim
from pftrack.calibration.camcal import calibrate, image_to_ground, nine_points
from pftrack.calibration.pipeline import (
    EstimateParams,
    estimate,
    score,
    simulate,
    summary,
)
from pftrack.calibration.scene import random_scene
from pftrack.cli.common import parse_seeds


def manual_cameras(scene, rng) -> list[dict]:
    """A calibration object at 25 surveyed points (heights 0-1 m) per camera, survey error 5 mm."""
    out = []
    for cam in scene.cameras:
        pts = []
        while len(pts) < 25:
            W, H = scene.room
            X = np.r_[rng.uniform(-W / 2, W / 2), rng.uniform(-H / 2, H / 2), rng.choice([0.0, 0.5, 1.0])]
            uv, ok = sim.project(cam, X[None])
            if ok[0]:
                pts.append((X, uv[0]))
        X = np.array([p[0] for p in pts]) + rng.normal(0, 0.005, (25, 3))
        uv = np.array([p[1] for p in pts]) + rng.normal(0, scene.noise.pixel, (25, 2))
        e = calibrate(X, uv, (cam.width, cam.height))
        px = nine_points((cam.width, cam.height))
        err = np.linalg.norm(image_to_ground(px, cam.K(), cam.dist(), cam.rvec, cam.tvec)
                             - image_to_ground(px, e.K, e.dist, e.rvec, e.tvec), axis=1) * 1000
        out.append({"mean_mm": float(err.mean()), "max_mm": float(err.max())})
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="100-109")
    ap.add_argument("--json")
    a = ap.parse_args()
    rows = []
    for seed in parse_seeds(a.seeds):
        scene = random_scene(seed)
        m = simulate(scene, seed)
        row = {"seed": seed}
        for name, p in [("lmeds_refined", EstimateParams()), ("lmeds_printed", EstimateParams(refine=False)),
                        ("least_squares", EstimateParams(use_lmeds=False)),
                        ("lmeds_refined_10pc_mismatch", EstimateParams(mismatch=0.10)),
                        ("lmeds_printed_10pc_mismatch", EstimateParams(refine=False, mismatch=0.10)),
                        ("least_squares_10pc_mismatch", EstimateParams(use_lmeds=False, mismatch=0.10))]:
            sc = score(scene, m, estimate(scene, m, p, seed))
            row[name] = summary(sc)
            if name == "lmeds_refined":
                row["cameras"] = sc["cameras"]
                row["ekf"] = sc["ekf"]
        row["manual_cameras"] = manual_cameras(scene, np.random.default_rng(seed + 1000))
        half = sim.coverage_waypoints(scene.room) * np.sqrt(0.5)
        mh = simulate(scene, seed, waypoints=half)
        row["half_room"] = summary(score(scene, mh, estimate(scene, mh, EstimateParams(), seed)))
        rows.append(row)
        s = row["lmeds_refined"]
        print(f"seed {seed}: LRF max {s['lrf_max_translation_m'] * 1000:.1f} mm {s['lrf_max_rotation_rad']:.4f} rad | "
              f"LS+10% {row['least_squares_10pc_mismatch']['lrf_max_translation_m'] * 1000:.0f} mm | "
              f"cam mean {s['camera_mean_mm']:.1f} max {s['camera_max_mm']:.1f} mm | "
              f"manual {np.mean([c['mean_mm'] for c in row['manual_cameras']]):.1f} / "
              f"{np.mean([c['max_mm'] for c in row['manual_cameras']]):.1f} | half room "
              f"{row['half_room']['camera_mean_mm']:.1f} / {row['half_room']['camera_max_mm']:.1f}", flush=True)

    def agg(key, field, fn=np.max):
        v = [r[key][field] for r in rows if np.isfinite(r[key][field])]
        return float(fn(v)) if v else float("nan")

    print("\nover", len(rows), "unseen rooms (worst LRF / mean over rooms for cameras):")
    for key in ["lmeds_refined", "lmeds_printed", "least_squares", "lmeds_refined_10pc_mismatch",
                "lmeds_printed_10pc_mismatch", "least_squares_10pc_mismatch", "half_room"]:
        print(f"  {key:30s} LRF worst {agg(key, 'lrf_max_translation_m') * 1000:7.1f} mm "
              f"{agg(key, 'lrf_max_rotation_rad'):.4f} rad | "
              f"cameras mean {agg(key, 'camera_mean_mm', np.mean):6.1f} mm "
              f"max {agg(key, 'camera_max_mm', np.mean):6.1f} mm | failed cams "
              f"{sum(r[key]['cameras_failed'] for r in rows)}")
    man_mean = np.mean([np.mean([c["mean_mm"] for c in r["manual_cameras"]]) for r in rows])
    man_max = np.mean([np.mean([c["max_mm"] for c in r["manual_cameras"]]) for r in rows])
    print(f"  {'manual (25 surveyed points)':30s} cameras mean {man_mean:6.1f} mm max {man_max:6.1f} mm")
    per_cam = [(c["mean_mm"], m["mean_mm"]) for r in rows for c, m in zip(r["cameras"], r["manual_cameras"])
               if c["mean_mm"] is not None]
    print(f"  manual better than automated on {sum(mm < cm for cm, mm in per_cam)} of {len(per_cam)} cameras")
    print(f"  EKF position RMSE mean {np.mean([r['ekf']['position_rmse_m'] for r in rows]) * 1000:.1f} mm")
    if a.json:
        Path(a.json).parent.mkdir(parents=True, exist_ok=True)
        Path(a.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
