"""The lost flag as a detector, on seeded synthetic scenes where the target walks behind an occluder.

    python examples/lost_flag.py [--tracker NAME] [--seeds 0-4] [--monitor]

Each scene is drawn from its seed (occluder texture, look-alike distractors, light, size and speed) and knows
the frames where its target is hidden.  For every seed the flag's recall on those frames, its false-alarm rate
on the frames where the estimate covers the target, and the reappearances re-acquired are printed.  With
``--monitor`` the tracker's boxes are judged by the colour PFs' loss test (``monitor=true``), which gives a tracker
without a test of its own (``--tracker opencv-medianflow``, ``meanshift``) a calibrated flag.
"""

from __future__ import annotations

import argparse

import numpy as np

import pftrack
from pftrack.eval.metrics import lost_detection
from pftrack.synth import Scene, hidden_frames, vanish_scene


def seed_range(text: str) -> list[int]:
    a, _, b = text.partition("-")
    return list(range(int(a), int(b or a) + 1))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tracker", default="fusion-pf")
    ap.add_argument("--seeds", default="0-4", help="scene seeds, e.g. 0-4")
    ap.add_argument("--monitor", action="store_true", help="judge the boxes with the colour PFs' loss test")
    args = ap.parse_args(argv)

    print("seed  hidden  lost recall  false-lost  re-acquired")
    for seed in seed_range(args.seeds):
        spec = vanish_scene(seed)
        scene = Scene(spec)
        frames = list(scene.frames())
        gt = scene.groundtruth(0)
        hidden = hidden_frames(spec)
        tracker = pftrack.create_tracker(args.tracker, seed=0, monitor=args.monitor)
        boxes, lost = [], []
        for t, frame in enumerate(frames):
            state = tracker.init(frame, tuple(gt[0])) if t == 0 else tracker.update(frame)
            boxes.append(state.box)
            lost.append(state.lost)
        # scored from the first update on: the first frame's box is given
        r = lost_detection(np.array(lost[1:]), np.array(boxes[1:]), gt[1:], hidden[1:])
        print(f"{seed:4d}  {int(hidden.sum()):6d}  {r.recall:11.2f}  {r.false_rate:10.3f}  "
              f"{r.reacquired} of {r.reappearances}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
