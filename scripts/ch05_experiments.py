"""Book ch. 5, Tables 4-6 analogues (docs/keypoints.md): the hybrid against its parts.

For each sequence and tracker (keypoint-ams, anisotropic-meanshift = Tracker-1, sift-ransac =
Tracker-2, and ablations of the hybrid), one pass with:

* d1 (Eq. 25, mean corner distance, px) and the per-parameter MAE of Eq. 26 (x, y, w, h);
* d2 (Eq. 27): the Bhattacharyya distance of the output box's 32^3 RGB histogram to the
  *initial* reference q0 (the honest version; the chapter's is against the tracker's own,
  learned reference, which grades the hybrid by its own selection criterion, ch05.md P9) and,
  for keypoint-ams, against its learned reference q_t;
* OTB AUC and the update time per frame (the ratios of Table 6).

    python scripts/ch05_experiments.py SEQ_DIR... [--trackers keypoint-ams,...] [--out results.csv]
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

import cv2
import numpy as np

import pftrack
from pftrack.cues import anisotropic as an
from pftrack.eval.metrics import corner_distance, ope_scores, param_mae
from pftrack.io.datasets import discover_sequences
from pftrack.trackers.sift_ransac import ColorModel

DEFAULT = ("keypoint-ams,anisotropic-meanshift,sift-ransac,keypoint-ams[learn=false],"
           "keypoint-ams[box_mode=tight],keypoint-ams[thresholds=paper]")


def _spec(item: str) -> tuple[str, dict]:
    if "[" not in item:
        return item, {}
    name, rest = item.split("[", 1)
    return name, dict(kv.split("=", 1) for kv in rest.rstrip("]").split(";") if kv)


def _split(text: str) -> list[str]:
    out, depth, cur = [], 0, ""
    for ch in text:
        depth += ch == "["
        depth -= ch == "]"
        if ch == "," and depth == 0:
            out.append(cur)
            cur = ""
        else:
            cur += ch
    return out + [cur] if cur else out


def run(seq, item: str) -> dict:
    name, params = _spec(item)
    frames = [cv2.imread(str(f)) for f in seq.frames]
    tracker = pftrack.create_tracker(name, **params)
    box0 = seq.init_box
    tracker.init(frames[0], box0)
    color = ColorModel("auto")
    color.adapt(frames[0])
    own = ColorModel("auto")
    own.adapt(frames[0])
    boxes, d2_q0, d2_qt, times = [box0], [], [], []
    v0 = an.axis_box_to_rotated(box0)
    color.prepare(frames[0], (0, 0, frames[0].shape[1], frames[0].shape[0]))
    q0 = color.hist(v0)
    for f in frames[1:]:
        t = time.perf_counter()
        st = tracker.update(f)
        times.append(time.perf_counter() - t)
        boxes.append(st.box)
        v = an.axis_box_to_rotated(st.box)
        color.prepare(f, (0, 0, f.shape[1], f.shape[0]))
        p = color.hist(v)
        d2_q0.append(np.sqrt(max(1 - an.bhattacharyya(p, q0), 0.0)))
        if hasattr(tracker, "learner"):
            # the learned reference lives at the tracker's working resolution: compare like with like
            zf = tracker._zoomed(f)
            own.prepare(zf, (0, 0, zf.shape[1], zf.shape[0]))
            d2_qt.append(np.sqrt(max(1 - an.bhattacharyya(own.hist(tracker.v_obj), tracker.q), 0.0)))
    pred, gt = np.array(boxes), seq.groundtruth
    mae = param_mae(pred, gt)
    return {"sequence": seq.name, "tracker": item, "auc": ope_scores(pred, gt).auc,
            "d1": float(np.nanmean(corner_distance(pred, gt))), "mae_x": mae[0], "mae_y": mae[1], "mae_w": mae[2],
            "mae_h": mae[3], "d2_q0": float(np.mean(d2_q0)), "d2_qt": float(np.mean(d2_qt)) if d2_qt else np.nan,
            "ms_per_frame": 1e3 * float(np.median(times))}


def _mean_defined(values) -> float:
    """The mean of the values that are not NaN; NaN when none is."""
    v = np.asarray(values, dtype=np.float64)
    v = v[~np.isnan(v)]
    return float(v.mean()) if v.size else float("nan")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("sequences", nargs="+")
    ap.add_argument("--trackers", default=DEFAULT)
    ap.add_argument("--out", default="reports/ch05_experiments.csv")
    args = ap.parse_args()
    seqs = [s for p in args.sequences for s in discover_sequences(p)]
    rows = []
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("w", newline="") as fh:
        w = None
        for seq in seqs:
            for item in _split(args.trackers):
                r = run(seq, item)
                rows.append(r)
                if w is None:
                    w = csv.DictWriter(fh, fieldnames=list(r))
                    w.writeheader()
                w.writerow(r)
                fh.flush()
                print(f"{seq.name:28s} {item:34s} AUC {r['auc']:.3f} d1 {r['d1']:7.1f} d2(q0) {r['d2_q0']:.3f} "
                      f"d2(qt) {r['d2_qt']:.3f} {r['ms_per_frame']:.1f} ms", flush=True)
    print("\nmean over sequences:")
    for item in _split(args.trackers):
        rs = [r for r in rows if r["tracker"] == item]
        m = {k: _mean_defined([r[k] for r in rs]) for k in ("auc", "d1", "mae_x", "mae_y", "mae_w", "mae_h", "d2_q0",
                                                              "d2_qt", "ms_per_frame")}
        qt = "–" if np.isnan(m["d2_qt"]) else f"{m['d2_qt']:.3f}"  # only the hybrid learns a reference
        print(f"| `{item}` | {m['auc']:.3f} | {m['d1']:.1f} | {m['mae_x']:.1f} / {m['mae_y']:.1f} / {m['mae_w']:.1f} / "
              f"{m['mae_h']:.1f} | {m['d2_q0']:.3f} | {qt} | {m['ms_per_frame']:.1f} |")


if __name__ == "__main__":
    main()
