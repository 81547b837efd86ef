"""``pftrack calibrate-sim``: calibrate simulated LRFs and cameras by tracking a robot (book ch. 12)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from .common import seed_value


def add_calibrate_sim(sub) -> None:
    p = sub.add_parser("calibrate-sim", help="calibrate simulated laser scanners and cameras by tracking a robot "
                                             "(book ch. 12)",
                       description="Simulates the measurements of a scene (odometry, ultrasound tag, LRF scans, "
                                   "camera pixels of the robot's markers) and estimates every sensor from them "
                                   "alone: EKF robot path, Kalman-tracked LRF clusters registered by LMedS, DLT + "
                                   "OpenCV camera calibration. Prints the errors against the scene's truth.")
    p.add_argument("--scene", help="scene JSON (room, lrfs, cameras, robot, noise); default: the chapter's room")
    p.add_argument("--random-scene", type=seed_value, metavar="S",
                   help="instead of --scene: a random room drawn from seed S")
    p.add_argument("--seed", type=seed_value, default=0, help="noise seed (default 0)")
    p.add_argument("--no-refine", action="store_true", help="keep LMedS's best 2-point sample (faithful to the text)")
    p.add_argument("--least-squares", action="store_true", help="plain least squares instead of LMedS (ablation)")
    p.add_argument("--out", help="result JSON (estimated sensors in the scene schema, residuals, errors)")
    p.add_argument("--plot", help="PNG: room, true and estimated sensors, true and EKF paths")
    p.add_argument("--write-scene", help="write the scene used (JSON) and exit")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_calibrate_sim)


def cmd_calibrate_sim(args) -> int:
    from ..calibration import EstimateParams, default_scene, load_scene, random_scene
    from ..calibration.pipeline import estimate, result_json, score, simulate, summary
    from ..errors import InputError

    if args.scene and args.random_scene is not None:
        raise InputError("give --scene or --random-scene, not both")
    scene = (load_scene(args.scene) if args.scene else
             random_scene(args.random_scene) if args.random_scene is not None else default_scene())
    if args.write_scene:
        Path(args.write_scene).write_text(json.dumps(scene.to_dict(), indent=2) + "\n", encoding="utf-8")
        return 0
    if not scene.lrfs and not scene.cameras:
        raise InputError("the scene has neither lrfs nor cameras: nothing to calibrate")
    params = EstimateParams(refine=not args.no_refine, use_lmeds=not args.least_squares)
    m = simulate(scene, args.seed)
    est = estimate(scene, m, params, args.seed)
    sc = score(scene, m, est)
    res = result_json(est, sc)
    if args.out:
        Path(args.out).write_text(json.dumps(res, indent=2) + "\n", encoding="utf-8")
    if args.plot:
        from ..viz.calibration import plot_calibration

        plot_calibration(scene, m, est, args.plot)
    if not args.quiet:
        for i, e in enumerate(sc["lrfs"]):
            if e["translation_m"] is None:
                print(f"lrf {i}: not calibrated ({res['lrfs'][i].get('error')})")
            else:
                print(f"lrf {i}: error {e['translation_m'] * 1000:.1f} mm, {e['rotation_rad']:.4f} rad "
                      f"({res['lrfs'][i]['pairs']} pairs)")
        for i, e in enumerate(sc["cameras"]):
            if e["mean_mm"] is None:
                print(f"camera {i}: not calibrated ({res['cameras'][i].get('error')})")
            else:
                print(f"camera {i}: ground error at 9 points mean {e['mean_mm']:.1f} mm, max {e['max_mm']:.1f} mm, "
                      f"reprojection {res['cameras'][i]['reprojection_rms_px']:.2f} px")
        s = summary(sc)
        print(f"summary: LRF max {s['lrf_max_translation_m'] * 1000:.1f} mm / {s['lrf_max_rotation_rad']:.4f} rad; "
              f"cameras mean {s['camera_mean_mm']:.1f} mm, max {s['camera_max_mm']:.1f} mm; "
              f"EKF position RMSE {sc['ekf']['position_rmse_m'] * 1000:.1f} mm", file=sys.stdout)
    return 0
