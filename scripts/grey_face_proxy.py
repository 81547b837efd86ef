"""A grey face under strong illumination change: a proxy built from a real portrait (docs/robustness.md).

    python scripts/grey_face_proxy.py [--seeds 0-7] [--trackers fusion-pf,color-pf,opencv-csrt] [--frames 150]
                                      [--dark GAIN --noise SD] [--turn DEGREES] [--live]

(scikit-image, from the `dev` extra, provides the portrait.)

No grey face sequence is among the development data, and issue #14 asks for such sequences. This script
runs trackers on :func:`pftrack.synth.face.face_scene` (also ``pftrack synth face``), a stand-in made from
scikit-image's ``astronaut`` portrait (NASA, public domain): the grey image is viewed
through a camera that pans and zooms along a seeded smooth path (320 x 240 frames), so the face moves and
changes size in the frame, and the frames are lit by

* a global gain that falls from 1 to 0.35 and back (seeded phase),
* a lamp, a bright spot drifting across the frame (as ``scripts/make_variants.py``), and
* a soft shadow edge that sweeps across the view at a seeded angle, darkening one side to 40 %.

The ground truth is the face box carried through the camera's motion, exact in every frame. It is a proxy
for a real grey face sequence: the face does not turn or change expression, so it measures the trackers'
tolerance of the light, not of pose. ``--dark 0.25 --noise 2`` darkens every frame by that gain and adds
Gaussian sensor noise of that spread (grey levels, seeded per scene): a dim, noisy indoor camera. Prints the
mean OTB AUC, the fraction of frames with ``lost`` raised (the face is visible in every frame, so every raised
flag is a false alarm) and the update rate. ``--live`` runs :func:`pftrack.synth.face_live.live_face_scene` instead
(``pftrack synth face --live``): the head moves in front of a still room, and the camera's automatic gain amplifies
the noise of the dark frames.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import pftrack
from pftrack.eval.metrics import frame_ious, ope_scores
from pftrack.eval.runner import _split_top, parse_tracker_list
from pftrack.synth.face import export_face, face_scene, portrait
from pftrack.synth.face_live import live_face_scene


def run(spec: str, frames, gt, seed: int) -> dict:
    cfg = parse_tracker_list(spec)[0]
    t = pftrack.create_tracker(cfg.name, seed=seed, params=cfg.param_dict)
    t.init(frames[0], tuple(gt[0]))
    boxes, lost = [], []
    t0 = time.perf_counter()
    for f in frames[1:]:
        st = t.update(f)
        boxes.append(st.box)
        lost.append(bool(st.lost))
    fps = (len(frames) - 1) / (time.perf_counter() - t0)
    b = np.array(boxes)
    iou = frame_ious(b, gt[1:])
    return {"auc": ope_scores(b, gt[1:]).auc, "lost": float(np.mean(lost)),
            "false_lost": float(np.mean(np.array(lost)[iou >= 0.5])) if np.any(iou >= 0.5) else float("nan"),
            "fps": fps}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0-7")
    ap.add_argument("--trackers", default="fusion-pf,color-pf,cotrain-pf,opencv-csrt",
                    help="tracker specs, as pftrack eval's (e.g. fusion-pf[illumination=quotient])")
    ap.add_argument("--frames", type=int, default=150)
    ap.add_argument("--save", help="write the first seed's frames as an OTB folder here")
    ap.add_argument("--dark", type=float, default=1.0, help="a further gain on every frame (a dim camera)")
    ap.add_argument("--noise", type=float, default=0.0, help="std of added Gaussian noise, grey levels")
    ap.add_argument("--portrait", choices=["astronaut", "camera"], default="astronaut",
                    help="the portrait (pftrack.synth.face.portrait): astronaut, the one the defaults were checked "
                         "on, or camera, a second face")
    ap.add_argument("--turn", type=float, default=0.0,
                    help="the face turns back and forth up to this angle, degrees (face_scene's turn; 0: it does not)")
    ap.add_argument("--live", action="store_true",
                    help="the head moves in front of a room, seen with automatic gain (pftrack.synth.face_live)")
    a = ap.parse_args()
    lo, _, hi = a.seeds.partition("-")
    seeds = list(range(int(lo), int(hi or lo) + 1))
    names = _split_top(a.trackers)
    res = {n: [] for n in names}
    image, face = portrait(a.portrait)
    for sd in seeds:
        frames, gt = (live_face_scene if a.live else face_scene)(sd, a.frames, image=image, face=face, turn=a.turn)
        if a.dark != 1.0 or a.noise > 0:
            rng = np.random.default_rng(sd)
            frames = [np.clip(f.astype(np.float32) * a.dark + rng.normal(0.0, a.noise, f.shape), 0, 255)
                      .astype(np.uint8) for f in frames]
        if a.save and sd == seeds[0]:
            export_face(frames, gt, a.save)
        for n in names:
            r = run(n, frames, gt, sd)
            res[n].append(r)
            print(f"seed {sd} {n}: AUC {r['auc']:.3f} lost {r['lost']:.2f} false-lost {r['false_lost']:.2f} "
                  f"{r['fps']:.0f} fps", flush=True)
    print("\n| tracker | mean AUC | min AUC | runs below 0.5 | frames with lost raised | false-lost (IoU >= 0.5) "
          "| median fps |")
    print("|---|---|---|---|---|---|---|")
    for n in names:
        r = res[n]
        print(f"| `{n}` | {np.mean([x['auc'] for x in r]):.3f} | {np.min([x['auc'] for x in r]):.3f} | "
              f"{sum(x['auc'] < 0.5 for x in r)} of {len(r)} | "
              f"{np.mean([x['lost'] for x in r]):.3f} | {np.nanmean([x['false_lost'] for x in r]):.3f} | "
              f"{np.median([x['fps'] for x in r]):.0f} |")


if __name__ == "__main__":
    main()
