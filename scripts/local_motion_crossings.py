"""Local motion on same-colour crossings: failures and time of local-motion-pf against its colour-only variant.

    python scripts/local_motion_crossings.py [--scene crossing|waving] [--seeds 100-147] [--texture T] [KEY=VALUE ...]

Freshly seeded scenes where a distractor with the target's colours passes in front of it:

* ``crossing``: one crossing (speeds, heights and slopes from the seed);
* ``waving``: two "hands" swinging past each other six times (Kristan et al.'s hands experiment).

A failure is a mean IoU below 0.3 over the last 10 frames. The same seeds for every tracker; kernels are
warmed up before timing; extra ``KEY=VALUE`` arguments go to local-motion-pf. Results: docs/robustness.md.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np

import pftrack
from pftrack.geometry import iou
from pftrack.synth import Scene, crossing_scene, waving_scene
from pftrack.trackers.warmup import warm_up


def _value(text: str):
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    return text


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", choices=["crossing", "waving"], default="crossing")
    ap.add_argument("--seeds", default="100-147")
    ap.add_argument("--texture", type=float, default=None, help=(
        "speckle amplitude of both objects (grey levels; default: the scene's own, 12); 0 gives objects of two "
        "flat colours"))
    ap.add_argument("params", nargs="*", help="local-motion-pf parameters KEY=VALUE")
    args = ap.parse_args()
    a, b = (int(v) for v in args.seeds.split("-"))
    extra = {k: _value(v) for k, v in (p.split("=", 1) for p in args.params)}
    make = {"crossing": crossing_scene, "waving": waving_scene}[args.scene]
    cfgs = {"local-motion-pf": ("local-motion-pf", extra),
            "local-motion-pf motion=false": ("local-motion-pf", {**extra, "motion": False}),
            "color-pf": ("color-pf", {})}
    for name, p in cfgs.values():
        warm_up(name, p)
    res = {k: [0, 0.0, 0] for k in cfgs}
    for seed in range(a, b + 1):
        spec = make(seed)
        if args.texture is not None:
            spec = replace(spec, targets=tuple(replace(t, texture=args.texture) for t in spec.targets))
        scene = Scene(spec)
        frames, gt = scene.frames(), scene.groundtruth(0)
        for label, (name, p) in cfgs.items():
            tr = pftrack.create_tracker(name, seed=0, **p)
            tr.init(frames[0], tuple(gt[0]))
            boxes = [gt[0]]
            t0 = time.perf_counter()
            for f in frames[1:]:
                boxes.append(tr.update(f).box)
            res[label][1] += time.perf_counter() - t0
            res[label][2] += len(frames) - 1
            res[label][0] += int(iou(np.array(boxes[-10:]), gt[-10:]).mean() < 0.3)
    n = b - a + 1
    what = args.scene if args.texture is None else f"{args.scene}, texture {args.texture:g}"
    print(f"| tracker ({what}, seeds {args.seeds}) | failures | ms per frame |")
    print("|---|---|---|")
    for label, (fails, sec, frames) in res.items():
        print(f"| {label} | {fails} / {n} | {1e3 * sec / frames:.2f} |")


if __name__ == "__main__":
    main()
