"""A camera that drops out, fades or freezes: how the trackers come through it (docs/robustness-cameras.md).

    python scripts/dropout_probe.py [--kinds none,black,white,fade,frozen] \
        [--trackers fusion-pf,color-pf,local-motion-pf,opencv-csrt] [--seeds 0-4]

Each scene (seeded, 300 frames of 160 x 120) is a two-colour box of 16 x 24 pixels circling over a background of
random 8 x 8 blocks. Frames 100-109 are then all black (``black``) or all white (``white``), repeat frame 99
(``frozen``, a stalled decoder), or the whole frame fades to black and back over frames 100-139 (``fade``; the box
counts as absent while the light is under 15 %). Printed per kind and tracker, means over the seeds: the share of
frames 51-99 with IoU >= 0.5 (before anything happens), the box's median width after frame 150 (the truth's is 16),
the share of frames after 150 with IoU >= 0.5, and the lost flag on the visible and on the blank frames.
Neither split: nothing is chosen on these scenes.
"""

from __future__ import annotations

import argparse

import numpy as np

from pftrack.cli.common import parse_seeds
from pftrack.eval.runner import parse_tracker_list
from pftrack.geometry import iou
from pftrack.trackers.registry import create_tracker

H, W = 120, 160
N_FRAMES = 300
KINDS = ("none", "black", "white", "fade", "frozen")


def scene(seed: int, kind: str) -> tuple[list[np.ndarray], list[tuple[int, int, int, int]], np.ndarray]:
    """Frames, true boxes and the blank frames (where the box cannot be seen) of one scene."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    rng = np.random.default_rng(seed)
    bg = rng.integers(0, 255, (H // 8, W // 8, 3), dtype=np.uint8).repeat(8, 0).repeat(8, 1)
    frames, boxes, blank = [], [], []
    for t in range(N_FRAMES):
        f = bg.copy()
        x, y = int(70 + 40 * np.sin(t / 30.0)), int(50 + 20 * np.cos(t / 45.0))
        f[y:y + 24, x:x + 16] = (30, 40, 220)
        f[y + 12:y + 24, x:x + 16] = (200, 160, 40)
        out = False
        if 100 <= t < 110 and kind in ("black", "white"):
            f[:] = 0 if kind == "black" else 255
            out = True
        elif 100 <= t < 110 and kind == "frozen":
            f = frames[-1].copy()
            x, y = boxes[-1][:2]
        elif 100 <= t < 140 and kind == "fade":
            gain = abs(t - 120) / 20.0
            f = (f * gain).astype(np.uint8)
            out = gain < 0.15
        frames.append(f)
        boxes.append((x, y, 16, 24))
        blank.append(out)
    return frames, boxes, np.array(blank)


def run(spec: str, kind: str, seed: int) -> np.ndarray:
    """``[before, width after, after, lost on visible, lost on blank]`` of one tracker on one scene."""
    frames, boxes, blank = scene(seed, kind)
    cfg = parse_tracker_list(spec)[0]
    tracker = create_tracker(cfg.name, seed=seed, params=cfg.param_dict)
    tracker.init(frames[0], boxes[0])
    states = [tracker.update(f) for f in frames[1:]]
    ious = np.array([iou(s.box, b) for s, b in zip(states, boxes[1:])])
    lost = np.array([s.lost for s in states])
    visible = ~blank[1:]
    return np.array([np.mean(ious[50:99] >= 0.5), np.median([s.box[2] for s in states[150:]]),
                     np.mean(ious[150:] >= 0.5), lost[visible].mean(),
                     lost[~visible].mean() if (~visible).any() else np.nan])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kinds", default=",".join(KINDS))
    ap.add_argument("--trackers", default="fusion-pf,color-pf,local-motion-pf,opencv-csrt")
    ap.add_argument("--seeds", default="0-4", help="e.g. 0-9 or 1,4,7 (default 0-4)")
    args = ap.parse_args(argv)
    seeds = parse_seeds(args.seeds)
    print("kind | tracker | IoU >= 0.5, frames 51-99 | width after 150 | IoU >= 0.5 after 150 | lost: visible, blank")
    for kind in args.kinds.split(","):
        for spec in parse_tracker_list(args.trackers):
            rows = np.array([run(spec.label, kind, s) for s in seeds])
            m = [float(np.mean(rows[:, i])) if np.isfinite(rows[:, i]).any() else float("nan") for i in range(5)]
            blank = "-" if np.isnan(m[4]) else f"{m[4]:.2f}"
            print(f"{kind} | {spec.label} | {m[0]:.2f} | {m[1]:.1f} | {m[2]:.2f} | {m[3]:.3f}, {blank}")


if __name__ == "__main__":
    main()
