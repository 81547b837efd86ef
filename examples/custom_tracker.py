"""Write your own tracker, register it, and compare it with pftrack's on seeded synthetic scenes.

    python examples/custom_tracker.py [--seeds 0-4]

The tracker below is a plain normalised-cross-correlation template matcher searching a window around its last
box, with a lost flag when the best correlation is low.  Declaring its parameters as a ``Params`` dataclass gives
it validation and ``--param``-style settings; registering it makes ``create_tracker("ncc-template")`` work.  To
reach the command line (``pftrack track --tracker ...``), install it as a plugin (README, "Your own tracker").
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass

import cv2
import numpy as np

import pftrack
from pftrack.eval.metrics import lost_detection, ope_scores
from pftrack.params import Params, param
from pftrack.synth import Scene, hidden_frames, vanish_scene
from pftrack.trackers.base import Tracker, TrackState
from pftrack.trackers.registry import register, tracker_names


@dataclass(frozen=True)
class NCCParams(Params):
    search: float = param(1.0, ge=0.1, le=5.0, doc="search margin around the last box, in box sizes")
    lost_below: float = param(0.5, ge=-1.0, le=1.0, doc="best NCC under which the target is reported lost")


class NCCTemplate(Tracker):
    name = "ncc-template"
    Params = NCCParams
    stochastic = False

    def _init(self, frame, box) -> TrackState:
        x, y, w, h = (int(round(v)) for v in box)
        self.template = cv2.cvtColor(frame[y:y + h, x:x + w], cv2.COLOR_BGR2GRAY)
        self.box = (float(x), float(y), float(w), float(h))
        return TrackState(box=self.box, score=1.0, lost=False)

    def _update(self, frame) -> TrackState:
        gray = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        x, y, w, h = self.box
        m = self.params.search
        x0, y0 = max(0, int(x - m * w)), max(0, int(y - m * h))
        x1, y1 = min(gray.shape[1], int(x + w + m * w)), min(gray.shape[0], int(y + h + m * h))
        window = gray[y0:y1, x0:x1]
        th, tw = self.template.shape
        if window.shape[0] < th or window.shape[1] < tw:
            return TrackState(box=self.box, score=0.0, lost=True)
        ncc = cv2.matchTemplate(window, self.template, cv2.TM_CCOEFF_NORMED)
        _, best, _, (bx, by) = cv2.minMaxLoc(ncc)
        lost = best < self.params.lost_below
        if not lost:  # stay on the last box while lost
            self.box = (float(x0 + bx), float(y0 + by), float(tw), float(th))
        return TrackState(box=self.box, score=float(max(best, 0.0)), lost=bool(lost))


if "ncc-template" not in tracker_names():
    register("ncc-template", NCCTemplate, "NCC template matching in a window around the last box (example)")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0-4", help="scene seeds, e.g. 0-4")
    args = ap.parse_args(argv)
    a, _, b = args.seeds.partition("-")
    seeds = range(int(a), int(b or a) + 1)

    print("tracker         mean AUC  lost recall  false-lost")
    for name in ("ncc-template", "color-pf", "fusion-pf"):
        aucs, recalls, false = [], [], []
        for seed in seeds:
            spec = vanish_scene(seed)
            scene = Scene(spec)
            gt = scene.groundtruth(0)
            tracker = pftrack.create_tracker(name, seed=0)
            states = [tracker.init(f, tuple(gt[0])) if t == 0 else tracker.update(f)
                      for t, f in enumerate(scene.frames())]
            boxes = np.array([s.box for s in states])
            aucs.append(ope_scores(boxes, gt).auc)
            r = lost_detection(np.array([s.lost for s in states[1:]]), boxes[1:], gt[1:], hidden_frames(spec)[1:])
            recalls.append(r.recall)
            false.append(r.false_rate)
        print(f"{name:14s}  {np.mean(aucs):8.3f}  {np.nanmean(recalls):11.2f}  {np.nanmean(false):10.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
