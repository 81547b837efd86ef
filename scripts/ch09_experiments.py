"""Book ch. 9 experiments (docs/graphcut.md): graph-cut tracking with masks on the DAVIS dev sequences.

    python scripts/ch09_experiments.py [--data ../shared/data] [--part j,speed] [--json reports/ch09.json]

* j: mean J (mask IoU) per sequence, initialised from the first ground-truth mask, for `graphcut`
  (defaults chosen on the tune sequence davis16_dog) and its ablations (full resolution, the chapter's
  Eq. 8 boundary, model update, hard temporal seeds), against OpenCV grabCut run on every frame from the
  previous frame's box (+10 %, 3 iterations);
* speed: graph building and cut in ms, full frame against the focused ROI (Table 4 analogue), and the whole
  update per frame at 320x240, 854x480 (native), 1280x720 and 1920x1080 (frames and masks resized).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import cv2
import numpy as np

from pftrack.segmentation import graphcut as G
from pftrack.segmentation.tracker import (
    GraphCutParams,
    GraphCutTracker,
    largest_component,
)

TUNE = ["davis16_dog"]
REPORT = ["davis16_blackswan", "davis16_car-shadow"]


def load(data: Path, seq: str, size=None):
    d = data / seq
    imgs = sorted((d / "img").glob("*.jpg"))
    masks = sorted((d / "masks").glob("*.png"))
    fr = [cv2.imread(str(p)) for p in imgs]
    gt = [cv2.imread(str(p), cv2.IMREAD_GRAYSCALE) > 0 for p in masks]
    if size is not None:
        fr = [cv2.resize(f, size, interpolation=cv2.INTER_AREA) for f in fr]
        gt = [cv2.resize(g.astype(np.uint8), size, interpolation=cv2.INTER_NEAREST) > 0 for g in gt]
    return fr, gt


def iou(a, b) -> float:
    u = np.count_nonzero(a | b)
    return float(np.count_nonzero(a & b) / u) if u else 1.0


def run_graphcut(frames, gts, **kw):
    tr = GraphCutTracker(GraphCutParams(**kw))
    tr.init_mask(frames[0], gts[0])
    J, t, lost = [], 0.0, 0
    for f, g in zip(frames[1:], gts[1:]):
        t0 = time.perf_counter()
        st = tr.update(f)
        t += time.perf_counter() - t0
        J.append(iou(st.info["mask"], g))
        lost += st.lost
    return {"J": float(np.mean(J)), "J_recall": float(np.mean(np.array(J) > 0.5)), "fps": len(J) / t, "lost": lost,
            "per_frame": J}


def run_grabcut(frames, gts, iters: int = 3):
    """OpenCV grabCut on every frame, initialised with the previous result's box enlarged by 10 %."""
    h, w = frames[0].shape[:2]
    prev = gts[0]
    J, t = [], 0.0
    for f, g in zip(frames[1:], gts[1:]):
        ys, xs = np.nonzero(prev)
        t0 = time.perf_counter()
        if len(xs):
            x0, x1, y0, y1 = xs.min(), xs.max(), ys.min(), ys.max()
            mx, my = 0.05 * (x1 - x0 + 1) + 2, 0.05 * (y1 - y0 + 1) + 2
            x0, y0 = int(max(x0 - mx, 0)), int(max(y0 - my, 0))
            x1, y1 = int(min(x1 + mx, w - 1)), int(min(y1 + my, h - 1))
            mask = np.zeros((h, w), np.uint8)
            bgd, fgd = np.zeros((1, 65)), np.zeros((1, 65))
            cv2.grabCut(f, mask, (x0, y0, max(x1 - x0, 2), max(y1 - y0, 2)), bgd, fgd, iters, cv2.GC_INIT_WITH_RECT)
            m = largest_component((mask == cv2.GC_FGD) | (mask == cv2.GC_PR_FGD))
        else:
            m = prev
        t += time.perf_counter() - t0
        J.append(iou(m, g))
        prev = m if m.any() else prev
    return {"J": float(np.mean(J)), "J_recall": float(np.mean(np.array(J) > 0.5)), "fps": len(J) / t}


VARIANTS = {
    "graphcut (default)": {},
    "full resolution (max_pixels=0)": {"max_pixels": 0},
    "boundary bj (Boykov-Jolly)": {"boundary": "bj"},
    "model update alpha=0.05": {"alpha": 0.05},
    "one-sided seeding (bkg_distance=False)": {"bkg_distance": False},
    "hard temporal seeds": {"soft_seeds": False},
}


def part_j(data: Path, out: dict):
    rows = []
    for split, seqs in (("tune", TUNE), ("report", REPORT)):
        for seq in seqs:
            frames, gts = load(data, seq)
            row = {"sequence": seq, "split": split}
            for name, kw in VARIANTS.items():
                r = run_graphcut(frames, gts, **kw)
                row[name] = {k: v for k, v in r.items() if k != "per_frame"}
                print(f"{split} {seq:20s} {name:40s} J {r['J']:.3f} recall {r['J_recall']:.2f} fps {r['fps']:.1f} "
                      f"lost {r['lost']}", flush=True)
            g = run_grabcut(frames, gts)
            row["grabCut per frame"] = g
            print(f"{split} {seq:20s} {'grabCut per frame (prev. box)':40s} J {g['J']:.3f} recall {g['J_recall']:.2f} "
                  f"fps {g['fps']:.1f}", flush=True)
            rows.append(row)
    rep = [r for r in rows if r["split"] == "report"]
    for name in list(VARIANTS) + ["grabCut per frame"]:
        print(f"report mean J {name:40s} {np.mean([r[name]['J'] for r in rep]):.3f}  "
              f"fps median {np.median([r[name]['fps'] for r in rep]):.1f}", flush=True)
    out["j"] = rows


def part_speed(data: Path, out: dict):
    rows = []
    for size in ((320, 240), (854, 480), (1280, 720), (1920, 1080)):
        frames, gts = load(data, "davis16_blackswan", size)
        full_build, roi_build, full_cut, roi_cut = [], [], [], []
        for f, g in zip(frames[1:6], gts[:5]):
            for sub, (bl, cl) in (("full", (full_build, full_cut)), ("roi", (roi_build, roi_cut))):
                if sub == "full":
                    img, prev = f, g
                else:
                    d = cv2.distanceTransform((~g).astype(np.uint8), cv2.DIST_L2, 5) <= 20 * size[0] / 640
                    ys, xs = np.nonzero(d)
                    sl = (slice(ys.min(), ys.max() + 1), slice(xs.min(), xs.max() + 1))
                    img, prev = f[sl], g[sl]
                t0 = time.perf_counter()
                bins = G.color_bins(img)
                H = G.color_hist(bins, prev)
                Hb = G.color_hist(bins, ~prev)
                Ro, Rb = G.regional(bins, H, Hb)
                nl = G.nlink_weights(img, "exp")
                Do, Db = G.seed_maps(prev)
                cs, ct = G.tlink_caps(Ro, Rb, 2.0, Do, Db)
                t1 = time.perf_counter()
                G.min_cut(cs, ct, nl)
                t2 = time.perf_counter()
                bl.append(1000 * (t1 - t0))
                cl.append(1000 * (t2 - t1))
        r = run_graphcut(frames[:16], gts[:16])
        r_full = run_graphcut(frames[:16], gts[:16], max_pixels=0)
        row = {"size": size, "build_full_ms": float(np.median(full_build)), "build_roi_ms": float(np.median(roi_build)),
               "cut_full_ms": float(np.median(full_cut)), "cut_roi_ms": float(np.median(roi_cut)),
               "update_ms": 1000 / r["fps"], "update_ms_full_resolution": 1000 / r_full["fps"]}
        rows.append(row)
        print(f"{size[0]}x{size[1]}: terms full {row['build_full_ms']:.1f} ms vs ROI {row['build_roi_ms']:.1f} ms "
              f"({row['build_full_ms'] / row['build_roi_ms']:.1f}x); max-flow (graph + cut) full "
              f"{row['cut_full_ms']:.0f} ms vs ROI {row['cut_roi_ms']:.0f} ms; whole update {row['update_ms']:.0f} ms "
              f"({1000 / row['update_ms']:.1f} fps), full-resolution ROI {row['update_ms_full_resolution']:.0f} ms",
              flush=True)
    out["speed"] = rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(Path(__file__).resolve().parents[1].parent / "shared" / "data"))
    ap.add_argument("--part", default="j,speed")
    ap.add_argument("--json")
    a = ap.parse_args()
    data = Path(a.data)
    if not (data / "davis16_dog").is_dir():
        raise SystemExit(f"{data}: DAVIS dev sequences not found")
    out: dict = {}
    for p in a.part.split(","):
        {"j": part_j, "speed": part_speed}[p](data, out)
    if a.json:
        Path(a.json).parent.mkdir(parents=True, exist_ok=True)
        Path(a.json).write_text(json.dumps(out, indent=1, default=float))


if __name__ == "__main__":
    main()
