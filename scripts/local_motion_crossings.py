"""Local motion on same-colour crossings: failures and time of local-motion-pf against its colour-only variant.

    python scripts/local_motion_crossings.py [KEY=VALUE ...]     # extra local-motion-pf parameters

48 freshly seeded crossing scenes (``crossing_scene``, seeds 100-147: speeds, heights and slopes from the seed;
the distractor has the target's colours and passes in front). A failure is a mean IoU below 0.3 over the last
10 frames. Kernels are warmed up before timing. Results: docs/robustness.md.
"""

import sys
import time

import numpy as np

import pftrack
from pftrack.geometry import iou
from pftrack.synth import Scene, crossing_scene
from pftrack.trackers.warmup import warm_up

cfgs = {"color": ("local-motion-pf", {"motion": False}), "motion": ("local-motion-pf", {}), "color-pf": ("color-pf", {})}
extra = dict(a.split("=") for a in sys.argv[1:])
extra = {k: (int(v) if v.isdigit() else float(v) if v.replace('.','',1).isdigit() else v) for k,v in extra.items()}
cfgs["motion"] = ("local-motion-pf", extra)
for n,(t,p) in cfgs.items(): warm_up(t, p)
res = {k: [0, 0.0, 0] for k in cfgs}
for seed in range(100, 148):
    spec = crossing_scene(seed); sc = Scene(spec); frames = sc.frames(); gt = sc.groundtruth(0)
    for k,(t,p) in cfgs.items():
        tr = pftrack.create_tracker(t, seed=0, **p); tr.init(frames[0], tuple(gt[0]))
        boxes=[gt[0]]; t0=time.perf_counter()
        for f in frames[1:]: boxes.append(tr.update(f).box)
        res[k][1] += time.perf_counter()-t0; res[k][2] += len(frames)-1
        ious = iou(np.array(boxes[-10:]), gt[-10:])
        res[k][0] += int(ious.mean() < 0.3)   # failure: off the target at the end
for k,(f,t,n) in res.items(): print(f"{k:8s} failures {f:2d}/48  ms/frame {1000*t/n:.2f}")
