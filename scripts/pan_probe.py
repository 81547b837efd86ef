"""A camera that pans to keep the target in view: mean OTB AUC of trackers on seeded synthetic scenes
(docs/robustness-cameras.md).

    python scripts/pan_probe.py [--trackers fusion-pf,fusion-pf[camera_motion=false]] [--speeds 5,12] \
        [--seeds 0-7]

Each scene (100 frames of 320 x 240) is ``simple_scene``'s target and textured background, seen by a camera that
pans along a smooth random path at a constant speed in pixels a frame, while the target wanders a few pixels
about the view's centre: the background moves and the target hardly does, the reverse of a hand-held camera
watching a still target. Seeds 0-7 are tune data (docs/rules/camera_share_rule.txt); other seeds are of neither
split.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from pftrack.cli.common import parse_seeds
from pftrack.eval.metrics import ope_scores
from pftrack.eval.runner import parse_tracker_list
from pftrack.synth import Scene
from pftrack.synth.scenes import SceneSpec, simple_scene
from pftrack.trackers.registry import create_tracker

N_FRAMES = 100


def pan_scene(seed: int, speed: float, n: int = N_FRAMES) -> SceneSpec:
    """``simple_scene(seed)`` seen by a camera panning at ``speed`` px a frame along a smooth random path, the
    target a few pixels about the view's centre (its path and the camera's as key frames every 5 frames)."""
    rng = np.random.default_rng(seed)
    angle = rng.uniform(0, 2 * np.pi)
    turn = rng.normal(0, 0.03, n).cumsum()
    v = speed * np.column_stack([np.cos(angle + turn), np.sin(angle + turn)])
    cam = np.vstack([[0.0, 0.0], np.cumsum(v, axis=0)[:-1]])
    wobble = rng.normal(0, 1.0, (n, 2)).cumsum(axis=0) * 0.5
    cx, cy = 160 + wobble[:, 0], 120 + wobble[:, 1]
    path = tuple((t, float(cx[t]), float(cy[t])) for t in range(0, n, 5))
    camera = tuple((t, float(cam[t, 0]), float(cam[t, 1])) for t in range(0, n, 5))
    base = simple_scene(seed, n_frames=n)
    target = dataclasses.replace(base.targets[0], path=path)
    return dataclasses.replace(base, targets=(target,), camera_path=camera)


def auc_of(spec: str, name: str, params: dict, seed: int, speed: float) -> float:
    """One tracker's OTB AUC on one scene (run seed 0)."""
    scene = Scene(pan_scene(seed, speed))
    frames, gt = scene.frames(), scene.groundtruth(0)
    tracker = create_tracker(name, seed=0, params=params)
    boxes = [tracker.init(frames[0], tuple(gt[0])).box] + [tracker.update(f).box for f in frames[1:]]
    return ope_scores(np.array(boxes), gt).auc


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trackers", default="fusion-pf,fusion-pf[camera_motion=false]")
    ap.add_argument("--speeds", default="5,12")
    ap.add_argument("--seeds", default="0-7")
    args = ap.parse_args(argv)
    configs = parse_tracker_list(args.trackers)
    speeds = [float(s) for s in args.speeds.split(",")]
    seeds = parse_seeds(args.seeds)
    print("tracker | " + " | ".join(f"{s:g} px a frame" for s in speeds))
    for cfg in configs:
        means = [np.mean([auc_of(cfg.label, cfg.name, cfg.param_dict, seed, s) for seed in seeds]) for s in speeds]
        print(f"{cfg.label} | " + " | ".join(f"{m:.3f}" for m in means), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
