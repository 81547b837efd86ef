"""Calibration of distributed sensors by tracking a robot (book ch. 12), simulation first.

- :mod:`.scene` — the scene file (room, LRF poses, cameras, robot, noise) and its defaults;
- :mod:`.sim` — exact-truth measurements: unicycle robot, odometry, ultrasound tag, LRF scans, camera pixels;
- :mod:`.lrf` — LRF background subtraction, clustering, Eq. (1) centres, Kalman tracks, human/robot vote;
- :mod:`.ekf` — the robot's EKF (Eqs. 7-13);
- :mod:`.rigid2d` — Eqs. (2)-(6) and LMedS;
- :mod:`.camcal` — DLT + OpenCV refinement standing in for Tsai; ground-plane back-projection;
- :mod:`.markers` — the robot's three colour markers: rendering, histograms, detection in the foreground;
- :mod:`.pipeline` — simulate, estimate, score.
"""

from .camcal import calibrate, dlt, image_to_ground
from .ekf import EkfParams, TagUnicycleEKF, run_ekf
from .lrf import LrfParams, LrfTracker, object_center
from .pipeline import (
           EstimateParams,
           estimate,
           result_json,
           run,
           score,
           simulate,
           summary,
)
from .rigid2d import fit_rigid_2d, lmeds_rigid_2d
from .scene import Scene, default_scene, load_scene, random_scene, scene_from_dict

__all__ = ["EkfParams", "EstimateParams", "LrfParams", "LrfTracker", "Scene", "TagUnicycleEKF", "calibrate",
           "default_scene", "dlt", "estimate", "fit_rigid_2d", "image_to_ground", "lmeds_rigid_2d", "load_scene",
           "object_center", "random_scene", "result_json", "run", "run_ekf", "scene_from_dict", "score",
           "simulate", "summary"]
