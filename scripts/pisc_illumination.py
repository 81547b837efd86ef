"""pisc against colour and template trackers on scenes whose light changes (book ch. 1 experiment).

    python scripts/pisc_illumination.py [--seeds 100-111] [--trackers pisc,color-pf,template,fusion-pf]

Fresh seeds of two synthetic scene kinds, the same seeds for every tracker (each tracker's seed is the scene's);
mean OTB AUC. Results: docs/pisc.md.
"""

from __future__ import annotations

import argparse

import numpy as np

from pftrack import create_tracker
from pftrack.cli.common import parse_seeds
from pftrack.eval.metrics import ope_scores
from pftrack.synth import Scene, illumination_scene, varied_scene
from pftrack.trackers.warmup import warm_up

KINDS = (
    ("varied, light drift always", lambda s: varied_scene(s, illumination=1.0)),
    ("illumination_scene", illumination_scene),
)


def auc_of(name: str, frames, gt: np.ndarray, seed: int) -> float:
    """One tracker's OTB AUC on a scene's ``frames``, started from the first frame's true box."""
    tracker = create_tracker(name, seed=seed)
    tracker.init(frames[0], tuple(gt[0]))
    boxes = [gt[0]] + [tracker.update(f).box for f in frames[1:]]
    return ope_scores(np.array(boxes), gt).auc


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="100-111", help="scene seeds, e.g. 100-111 or 100,105")
    ap.add_argument("--trackers", default="pisc,color-pf,template,fusion-pf")
    args = ap.parse_args(argv)
    names = args.trackers.split(",")
    for n in names:
        warm_up(n)
    try:
        seeds = parse_seeds(args.seeds)
    except ValueError as exc:
        ap.error(str(exc))
    for label, make in KINDS:
        res: dict[str, list[float]] = {n: [] for n in names}
        for seed in seeds:
            scene = Scene(make(seed))
            frames, gt = scene.frames(), scene.groundtruth(0)
            for n in names:
                res[n].append(auc_of(n, frames, gt, seed))
        print(f"{label} (seeds {args.seeds})", " ".join(f"{n} {np.mean(v):.3f}" for n, v in res.items()))


if __name__ == "__main__":
    main()
