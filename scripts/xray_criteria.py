"""Book ch. 14's comparison of the six matching criteria on angiography frames warped by a known motion.

    python scripts/xray_criteria.py [--data ../shared/data/xray_angio] [--frames 15-37] [--seeds 10]

Each sequence warps one real frame of the cine (a frame where the contrast has filled the arteries)
with a smooth "heart" motion of up to 20 px, a contrast drift and noise
(:func:`pftrack.synth.xray.warped_sequence`); the template is the most structured 32x32 region.  The
``template`` tracker runs with each criterion; a failure is a frame with centre error > 10 px.
Results: docs/template.md.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import cv2
import numpy as np

import pftrack
from pftrack.synth.xray import structured_box, warped_sequence
from pftrack.trackers.warmup import warm_up

METRICS = ["ssd", "ccorr", "ncc", "sad", "morph", "morph_normed", "mi"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default="../shared/data/xray_angio")
    ap.add_argument("--frames", default="15-37")
    ap.add_argument("--seeds", type=int, default=10, help="how many sequences")
    ap.add_argument("--first", type=int, default=0, help="the first sequence's seed (300: a fresh draw, 10 seeds)")
    args = ap.parse_args()
    a, b = (int(v) for v in args.frames.split("-"))
    files = sorted((Path(args.data) / "img").glob("*.jpg"))[a - 1:b]
    for m in METRICS:
        warm_up("template", {"metric": m, "search_margin": 1.0})
    res = {m: {"err": [], "fail": 0, "frames": 0, "psr": [], "sec": 0.0} for m in METRICS}
    for seed in range(args.first, args.first + args.seeds):
        src = cv2.imread(str(files[seed % len(files)]), cv2.IMREAD_GRAYSCALE)
        frames, shifts = warped_sequence(src, seed, n_frames=40)
        box0 = structured_box(src)
        gt_c = np.array([box0[0] + 16, box0[1] + 16]) + shifts
        for m in METRICS:
            t = pftrack.create_tracker("template", metric=m, search_margin=1.0)
            t.init(frames[0], box0)
            t0 = time.perf_counter()
            for k, f in enumerate(frames[1:], 1):
                st = t.update(f)
                c = np.array([st.box[0] + st.box[2] / 2, st.box[1] + st.box[3] / 2])
                e = float(np.hypot(*(c - gt_c[k])))
                res[m]["err"].append(e)
                res[m]["fail"] += int(e > 10)
                res[m]["frames"] += 1
                if np.isfinite(st.info["psr"]):
                    res[m]["psr"].append(st.info["psr"])
            res[m]["sec"] += time.perf_counter() - t0
    print(f"| criterion ({args.seeds} sequences x 39 frames) | mean centre error (px) | failures (> 10 px) | "
          "median PSR | fps |")
    print("|---|---|---|---|---|")
    for m, r in res.items():
        print(f"| `{m}` | {np.mean(r['err']):.2f} | {r['fail']} / {r['frames']} | {np.median(r['psr']):.1f} | "
              f"{r['frames'] / r['sec']:.0f} |")


if __name__ == "__main__":
    main()
