"""The VOT supervised (reset) protocol (GUIDE §4).

* The tracker is initialised on the first frame from the ground truth.
* A **failure** is a frame whose IoU with the ground truth is 0 (frames without
  ground truth cannot fail).
* After a failure at frame ``f`` the tracker is re-initialised from the ground
  truth at frame ``f + 5`` (the frames in between are not tracked).
* **Accuracy** is the mean IoU over the tracked frames, excluding the first
  ``burn_in = 10`` frames after each (re)initialisation (the initialisation frame
  included in those 10).
* **Robustness** is the number of failures.

Overlaps are computed within the frame (both boxes cut to the image), as the VOT toolkit does.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Iterable

import numpy as np

from ..geometry import iou
from .metrics import valid_gt, within_frame


@dataclass
class VOTResult:
    failures: int
    accuracy: float
    n_frames: int
    boxes: np.ndarray  # (n, 4) predictions, NaN where not tracked (between failure and re-init)
    ious: np.ndarray  # (n,) per-frame IoU, NaN where not tracked or no ground truth
    inits: list[int] = field(default_factory=list)  # frame indices of (re)initialisations
    failure_frames: list[int] = field(default_factory=list)
    update_seconds: float = 0.0
    updates: int = 0


def run_vot(tracker, frames: Iterable[np.ndarray], gt: np.ndarray, *, skip: int = 5, burn_in: int = 10,
            timer: Callable[[], float] | None = None) -> VOTResult:
    """Run the reset protocol.

    ``frames`` may be a list or any iterable (frames are consumed in order; the
    frames skipped after a failure are read and discarded).  ``tracker`` follows
    the pftrack protocol (``init`` may be called again to re-initialise).
    """
    import time

    timer = timer or time.perf_counter
    gt = np.asarray(gt, dtype=np.float64).reshape(-1, 4)
    ok_gt = valid_gt(gt)
    n = len(gt)
    boxes = np.full((n, 4), np.nan)
    ious = np.full(n, np.nan)
    inits: list[int] = []
    fails: list[int] = []
    counted = np.zeros(n, bool)
    reinit_at = 0
    since_init = 0
    tracking = False
    upd_s = 0.0
    upd_n = 0
    for t, frame in enumerate(frames):
        if t >= n:
            break
        if not tracking:
            if t < reinit_at or not ok_gt[t]:
                if t >= reinit_at:
                    reinit_at = t + 1  # wait for a frame with usable ground truth
                continue
            tracker.init(frame, tuple(gt[t]))
            boxes[t] = gt[t]
            ious[t] = 1.0
            inits.append(t)
            tracking = True
            since_init = 0
            continue
        t0 = timer()
        state = tracker.update(frame)
        upd_s += timer() - t0
        upd_n += 1
        since_init += 1
        boxes[t] = state.box
        if ok_gt[t]:
            shape = getattr(frame, "shape", None)
            size = (shape[1], shape[0]) if shape is not None else None
            g = within_frame(gt[t], size)
            if not valid_gt(g)[0]:  # the target wholly outside the frame: nothing to fail on
                continue
            ov = float(iou(within_frame(state.box, size), g)[0])
            ious[t] = ov
            if ov <= 0.0:
                fails.append(t)
                tracking = False
                reinit_at = t + skip
                continue
            if since_init >= burn_in:
                counted[t] = True
    acc_vals = ious[counted]
    return VOTResult(failures=len(fails), accuracy=float(acc_vals.mean()) if acc_vals.size else float("nan"),
                     n_frames=n, boxes=boxes, ious=ious, inits=inits, failure_frames=fails,
                     update_seconds=upd_s, updates=upd_n)
