"""Targets of flat colour: every tracker on the same synthetic scenes with and without the target's texture
(docs/robustness-cameras.md).

    python scripts/texture_probe.py [--trackers all] [--kinds varied,vanish,leave,simple] [--seeds 7100-7102]

Each scene is drawn by the ``pftrack synth`` generator of its kind; its flat copy is the same scene with the
objects' speckle set to 0 (two flat colours, an ellipse in its box). Per tracker: the mean IoU over the frames where
the target is in view, textured and flat; the share of the flat copies' frames in view where the box is off the
target (IoU < 0.1) on which ``lost`` is raised, and of those on it (IoU >= 0.5). Neither split: nothing is chosen
on these scenes.
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from pftrack.cli.common import parse_seeds
from pftrack.eval.metrics import frame_ious
from pftrack.eval.runner import parse_tracker_list
from pftrack.synth import Scene, leave_scene, simple_scene, vanish_scene, varied_scene
from pftrack.trackers.registry import create_tracker, tracker_names

KINDS = {"varied": varied_scene, "vanish": vanish_scene, "leave": leave_scene, "simple": simple_scene}
#: left out of ``--trackers all``: too slow for a sweep (under 60 update fps), or unseeded OpenCV
SLOW = ("graphcut", "deformable-mesh", "covariance", "opencv-tld", "opencv-mil")


def scene(kind: str, seed: int, flat: bool) -> tuple[list[np.ndarray], np.ndarray]:
    """Frames and ground truth (NaN where the target is out of view) of one scene, or of its flat copy."""
    spec = KINDS[kind](seed)
    if flat:
        spec = replace(spec, targets=tuple(replace(t, texture=0.0) for t in spec.targets))
    sc = Scene(spec)
    return sc.frames(), sc.groundtruth(0)


def run(spec: str, frames: list[np.ndarray], gt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """IoU with the truth (NaN where it is out of view) and the lost flag on frames 1 .. n - 1."""
    cfg = parse_tracker_list(spec)[0]
    tracker = create_tracker(cfg.name, seed=0, params=cfg.param_dict)
    tracker.init(frames[0], tuple(gt[0]))
    states = [tracker.update(f) for f in frames[1:]]
    ious = frame_ious(np.array([s.box for s in states], dtype=np.float64), gt[1:])
    return np.where(np.isnan(gt[1:, 0]), np.nan, ious), np.array([s.lost for s in states])


def measure(spec: str, kinds, seeds) -> dict:
    """Mean IoU in view, textured and flat, and the flat copies' flag off and on the target."""
    iou = {False: [], True: []}
    off = on = off_lost = on_lost = 0
    for kind in kinds:
        for seed in seeds:
            for flat in (False, True):
                ious, lost = run(spec, *scene(kind, seed, flat))
                iou[flat].append(float(np.nanmean(ious)))
                if flat:
                    o, n = ious < 0.1, ious >= 0.5  # NaN (out of view) is neither
                    off, on = off + int(o.sum()), on + int(n.sum())
                    off_lost, on_lost = off_lost + int(lost[o].sum()), on_lost + int(lost[n].sum())
    return {"textured": float(np.mean(iou[False])), "flat": float(np.mean(iou[True])),
            "lost_off": off_lost / off if off else float("nan"), "lost_on": on_lost / on if on else float("nan")}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trackers", default="all", help="tracker specs, comma separated, or all (the registry)")
    ap.add_argument("--kinds", default=",".join(KINDS))
    ap.add_argument("--seeds", default="7100-7102", help="e.g. 7100-7102 or 1,4,7")
    args = ap.parse_args(argv)
    kinds = args.kinds.split(",")
    bad = [k for k in kinds if k not in KINDS]
    if bad:
        raise SystemExit(f"unknown kind {bad[0]!r}; choose from {', '.join(KINDS)}")
    specs = [n for n in tracker_names() if n not in SLOW] if args.trackers == "all" else args.trackers.split(",")
    seeds = parse_seeds(args.seeds)
    print("| tracker | mean IoU in view, textured | flat | flat: lost when off the target (IoU < 0.1) | on it |")
    print("|---|---|---|---|---|")
    for spec in specs:
        r = measure(spec, kinds, seeds)
        print(f"| `{spec}` | {r['textured']:.3f} | {r['flat']:.3f} | {r['lost_off']:.2f} | {r['lost_on']:.2f} |",
              flush=True)


if __name__ == "__main__":
    main()
