"""A grey face under strong illumination change: a proxy built from a real portrait (docs/robustness.md).

    python scripts/grey_face_proxy.py [--seeds 0-7] [--trackers fusion-pf,color-pf,opencv-csrt] [--frames 150]

(scikit-image, from the `dev` extra, provides the portrait.)

No grey face sequence is among the development data, and issue #14 asks for such sequences. This script
makes a stand-in from scikit-image's ``astronaut`` portrait (NASA, public domain): the grey image is viewed
through a camera that pans and zooms along a seeded smooth path (320 x 240 frames), so the face moves and
changes size in the frame, and the frames are lit by

* a global gain that falls from 1 to 0.35 and back (seeded phase),
* a lamp, a bright spot drifting across the frame (as ``scripts/make_variants.py``), and
* a soft shadow edge that sweeps across the view at a seeded angle, darkening one side to 40 %.

The ground truth is the face box carried through the camera's motion, exact in every frame. It is a proxy
for a real grey face sequence: the face does not turn or change expression, so it measures the trackers'
tolerance of the light, not of pose. Prints the mean OTB AUC, the fraction of frames with ``lost`` raised
(the face is visible in every frame, so every raised flag is a false alarm) and the update rate.
"""

from __future__ import annotations

import argparse
import time

import cv2
import numpy as np

import pftrack
from pftrack.eval.metrics import frame_ious, ope_scores
from pftrack.eval.runner import _split_top, parse_tracker_list

FACE = (170.0, 40.0, 112.0, 140.0)  # x, y, w, h of the face and hair in the 512 x 512 portrait
OUT_W, OUT_H = 320, 240


def portrait() -> np.ndarray:
    from skimage import data

    return cv2.cvtColor(data.astronaut()[:, :, ::-1].copy(), cv2.COLOR_BGR2GRAY)


def scene(seed: int, n: int = 150) -> tuple[list[np.ndarray], np.ndarray]:
    """Frames (grey uint8) and exact face boxes of one seeded proxy sequence."""
    rng = np.random.default_rng(seed)
    base = portrait().astype(np.float32)
    fx, fy, fw, fh = FACE
    f1, f2, f3 = rng.uniform(0.5, 1.5, 3)
    p1, p2, p3, p4 = rng.uniform(0, 2 * np.pi, 4)
    lamp0, lamp1 = rng.uniform((0, 0), (OUT_W, OUT_H)), rng.uniform((0, 0), (OUT_W, OUT_H))
    theta = rng.uniform(0, 2 * np.pi)
    dark_at = rng.uniform(0.3, 0.7)
    yy, xx = np.mgrid[0:OUT_H, 0:OUT_W].astype(np.float32)
    along = xx * np.cos(theta) + yy * np.sin(theta)
    lo, hi = float(along.min()), float(along.max())
    frames, boxes = [], []
    for k in range(n):
        t = k / max(n - 1, 1)
        zoom = 1.0 + 0.2 * np.sin(2 * np.pi * f3 * t + p3)          # 0.8-1.2
        s = zoom * 0.9                                              # source pixels -> frame pixels
        cx = fx + fw / 2 + 40 * np.sin(2 * np.pi * f1 * t + p1)     # the view's centre in the portrait
        cy = fy + fh / 2 + 20 * np.sin(2 * np.pi * f2 * t + p2) + 15
        m = np.array([[s, 0, OUT_W / 2 - s * cx], [0, s, OUT_H / 2 - s * cy]], dtype=np.float64)
        img = cv2.warpAffine(base, m, (OUT_W, OUT_H), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        gain = 1.0 - 0.65 * np.exp(-((t - dark_at) / 0.2) ** 2)   # 1 -> 0.35 -> 1
        lc = lamp0 + (lamp1 - lamp0) * t
        lamp = 0.55 + 0.9 * np.exp(-((xx - lc[0]) ** 2 + (yy - lc[1]) ** 2) / (0.35 * OUT_W) ** 2)
        edge = lo + (hi - lo) * (0.5 + 0.5 * np.sin(2 * np.pi * t + p4))
        shadow = 1.0 - 0.6 / (1.0 + np.exp(-(along - edge) / 10.0))
        img = img * gain * lamp * shadow + rng.normal(0, 2.0, img.shape)
        frames.append(np.clip(img, 0, 255).astype(np.uint8))
        boxes.append((s * fx + m[0, 2], s * fy + m[1, 2], s * fw, s * fh))
    return frames, np.array(boxes)


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
    a = ap.parse_args()
    lo, _, hi = a.seeds.partition("-")
    seeds = list(range(int(lo), int(hi or lo) + 1))
    names = _split_top(a.trackers)
    res = {n: [] for n in names}
    for sd in seeds:
        frames, gt = scene(sd, a.frames)
        if a.save and sd == seeds[0]:
            from pathlib import Path

            out = Path(a.save)
            (out / "img").mkdir(parents=True, exist_ok=True)
            for i, f in enumerate(frames):
                cv2.imwrite(str(out / "img" / f"{i + 1:04d}.png"), f)
            np.savetxt(out / "groundtruth_rect.txt", gt, fmt="%.2f", delimiter=",")
        for n in names:
            r = run(n, frames, gt, sd)
            res[n].append(r)
            print(f"seed {sd} {n}: AUC {r['auc']:.3f} lost {r['lost']:.2f} false-lost {r['false_lost']:.2f} "
                  f"{r['fps']:.0f} fps", flush=True)
    print("\n| tracker | mean AUC | min AUC | frames with lost raised | false-lost (IoU >= 0.5) | median fps |")
    print("|---|---|---|---|---|---|")
    for n in names:
        r = res[n]
        print(f"| `{n}` | {np.mean([x['auc'] for x in r]):.3f} | {np.min([x['auc'] for x in r]):.3f} | "
              f"{np.mean([x['lost'] for x in r]):.3f} | {np.nanmean([x['false_lost'] for x in r]):.3f} | "
              f"{np.median([x['fps'] for x in r]):.0f} |")


if __name__ == "__main__":
    main()
