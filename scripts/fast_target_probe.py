"""Fast targets: the share of frames tracked (IoU >= 0.5) as the target's speed grows (docs/robustness-cameras.md).

    python scripts/fast_target_probe.py [--trackers fusion-pf,color-pf,opencv-csrt] [--speeds 4,8,12,16] \
        [--seeds 0-3]

Each scene (seeded, 150 frames of 320 x 240) is a two-colour box of 20 x 30 pixels with a white stripe, moving at
a constant speed in pixels a frame over a background of random 8 x 8 blocks from the first frame on, bouncing off
the frame's edges (``bounce``) or also turning in a random direction on about one frame in ten (``turns``).
Neither split: nothing is chosen on these scenes.
"""

from __future__ import annotations

import argparse

import numpy as np

from pftrack.cli.common import parse_seeds
from pftrack.eval.runner import parse_tracker_list
from pftrack.geometry import iou
from pftrack.trackers.registry import create_tracker

H, W = 240, 320
TW, TH = 20, 30
N_FRAMES = 150
MODES = ("bounce", "turns")


def scene(seed: int, speed: float, mode: str) -> tuple[list[np.ndarray], list[tuple[int, int, int, int]]]:
    """Frames and true boxes of one scene."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
    rng = np.random.default_rng(seed)
    bg = rng.integers(0, 255, (H // 8, W // 8, 3), dtype=np.uint8).repeat(8, 0).repeat(8, 1)
    patch = np.empty((TH, TW, 3), np.uint8)
    patch[:] = (40, 60, 210)
    patch[15:] = (200, 180, 40)
    patch[5:10, 5:15] = (250, 250, 250)
    ang = rng.uniform(0, 2 * np.pi)
    v = speed * np.array([np.cos(ang), np.sin(ang)])
    p = np.array([W / 2, H / 2])
    frames, boxes = [], []
    for _ in range(N_FRAMES):
        if mode == "turns" and rng.random() < 0.1:
            ang = rng.uniform(0, 2 * np.pi)
            v = speed * np.array([np.cos(ang), np.sin(ang)])
        p = p + v
        for i, lim in ((0, W - TW), (1, H - TH)):
            if p[i] < 0 or p[i] > lim:
                v[i] = -v[i]
                p[i] = min(max(p[i], 0), lim)
        x, y = int(p[0]), int(p[1])
        f = bg.copy()
        f[y:y + TH, x:x + TW] = patch
        frames.append(f)
        boxes.append((x, y, TW, TH))
    return frames, boxes


def tracked_share(spec: str, speed: float, mode: str, seed: int) -> float:
    """The share of the updates whose box has IoU >= 0.5 with the truth."""
    frames, boxes = scene(seed, speed, mode)
    cfg = parse_tracker_list(spec)[0]
    tracker = create_tracker(cfg.name, seed=seed, params=cfg.param_dict)
    tracker.init(frames[0], boxes[0])
    return float(np.mean([iou(tracker.update(f).box, b) >= 0.5 for f, b in zip(frames[1:], boxes[1:])]))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trackers", default="fusion-pf,color-pf,opencv-csrt")
    ap.add_argument("--speeds", default="4,8,12,16")
    ap.add_argument("--modes", default=",".join(MODES))
    ap.add_argument("--seeds", default="0-3", help="e.g. 0-9 or 1,4,7 (default 0-3)")
    args = ap.parse_args(argv)
    seeds = parse_seeds(args.seeds)
    specs = [c.label for c in parse_tracker_list(args.trackers)]
    print("mode | px a frame | " + " | ".join(specs))
    for mode in args.modes.split(","):
        for speed in (float(s) for s in args.speeds.split(",")):
            shares = [np.mean([tracked_share(spec, speed, mode, s) for s in seeds]) for spec in specs]
            print(f"{mode} | {speed:g} | " + " | ".join(f"{v:.2f}" for v in shares), flush=True)


if __name__ == "__main__":
    main()
