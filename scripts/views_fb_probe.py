"""Would a forward-backward check at the object level tell a switch to another walker on the PETS views?

    python scripts/views_fb_probe.py reports/split/tune_views --pets ../shared/data/pets09_s2l1_dev --lag 5

For each view (``scripts/make_pets_views.py``), ``fusion-pf`` (seed 0) is run, and on every frame t where neither t
nor t - lag is lost, the estimate's grey patch at t is matched (normalised cross-correlation) back into frame
t - lag, within 1.5 box widths and 0.75 box heights of the estimate there. The error is the distance from the best
match to the estimate of t - lag, in box widths: the forward-backward error of Kalal et al. (2010), taken on the
whole object. Frames are classed as ``on`` (IoU >= 0.5 with the person), ``switch`` (IoU < 0.1 or the person
absent, and the estimate on another annotated walker, IoU >= 0.3 clipped to the window) or ``other``, and the
error's quantiles are printed per class, with its share above 0.5 and 0.7 widths in the first 10 frames after the
first switch of each view. Diagnosis only: it chooses nothing.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

from pftrack.geometry import iou
from pftrack.io.datasets import read_sequence
from pftrack.trackers import create_tracker

sys.path.insert(0, str(Path(__file__).parent))
from views_flag_trace import view_walkers, walker_on  # noqa: E402


def fb_error(g_now: np.ndarray, g_then: np.ndarray, b_now, b_then, reach: float = 1.5) -> float:
    """The distance, in box widths, from ``b_then`` to where ``b_now``'s patch of ``g_now`` matches best in
    ``g_then`` (searched within ``reach`` widths and half as many heights); NaN when a patch is cut by the frame."""
    x, y, w, h = (int(round(v)) for v in b_now)
    fh, fw = g_now.shape
    if x < 0 or y < 0 or x + w > fw or y + h > fh or w < 6 or h < 6:
        return float("nan")
    xt, yt = b_then[0], b_then[1]
    rx, ry = int(reach * w), int(reach * h / 2)
    x0, y0 = max(int(xt) - rx, 0), max(int(yt) - ry, 0)
    x1, y1 = min(int(xt) + w + rx, fw), min(int(yt) + h + ry, fh)
    if x1 - x0 < w + 1 or y1 - y0 < h + 1:
        return float("nan")
    r = cv2.matchTemplate(g_then[y0:y1, x0:x1], g_now[y:y + h, x:x + w], cv2.TM_CCOEFF_NORMED)
    loc = cv2.minMaxLoc(r)[3]
    return float(np.hypot(x0 + loc[0] - xt, y0 + loc[1] - yt) / w)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("views", type=Path, help="a folder of views (scripts/make_pets_views.py)")
    ap.add_argument("--pets", type=Path, default=Path("../shared/data/pets09_s2l1_dev"))
    ap.add_argument("--lag", type=int, default=5)
    args = ap.parse_args()
    pets = read_sequence(args.pets)
    gt = pets.mot_gt
    height, width = cv2.imread(str(pets.frames[0])).shape[:2]
    k = args.lag
    rows = []  # (class, error, within 10 frames of the view's first switch)
    for folder in sorted(p for p in args.views.iterdir() if (p / "groundtruth_rect.txt").exists()):
        seq = read_sequence(folder)
        _, window, others = view_walkers(folder, seq, gt, width, height)
        frames = [cv2.imread(str(p)) for p in seq.frames]
        grays = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in frames]
        truth = np.asarray(seq.groundtruth, float)
        tr = create_tracker("fusion-pf", seed=0)
        tr.init(frames[0], seq.init_box)
        est, lost = [seq.init_box], [False]
        for f in frames[1:]:
            st = tr.update(f)
            est.append(st.info.get("box_full", st.box))
            lost.append(bool(st.lost))
        first = None
        for t in range(k, len(frames)):
            if lost[t] or lost[t - k]:
                continue
            g = truth[t]
            seen = bool(np.all(np.isfinite(g)))
            overlap = iou(est[t], tuple(g)) if seen else 0.0
            off = overlap < 0.1 and walker_on(est[t], others.get(t, ()), window) is not None
            if off and first is None:
                first = t
            cls = "on" if overlap >= 0.5 else "switch" if off else "other"
            rows.append((cls, fb_error(grays[t], grays[t - k], est[t], est[t - k]),
                         off and first is not None and t - first < 10))
    for cls in ("on", "switch", "other"):
        e = np.array([r[1] for r in rows if r[0] == cls and np.isfinite(r[1])])
        if len(e):
            q = " / ".join(f"{np.quantile(e, v):.2f}" for v in (0.5, 0.9, 0.95, 0.99))
            print(f"{cls:7s} frames {len(e):5d}  error quantiles 50/90/95/99 %: {q}  above 0.5: {np.mean(e > 0.5):.3f}"
                  f"  above 0.7: {np.mean(e > 0.7):.3f}")
    e = np.array([r[1] for r in rows if r[2] and np.isfinite(r[1])])
    if len(e):
        print(f"first 10 frames after a view's first switch: {len(e)} frames, above 0.5: {np.mean(e > 0.5):.3f}, "
              f"above 0.7: {np.mean(e > 0.7):.3f}")


if __name__ == "__main__":
    main()
