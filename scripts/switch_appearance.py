"""Does the tracked box's appearance break when the tracker switches between look-alikes? (a diagnosis)

    python scripts/switch_appearance.py VIEWS --tracker fusion-pf --seeds 0,1 --out trace.npz
    python scripts/switch_appearance.py VIEWS SEQS ... --load trace.npz   # these folders' tables again, no tracking

Each sequence is tracked once per seed. On every frame the box's appearance is book ch. 11's two-ellipse layout
(torso and legs) as the hand-over's joint colour histogram (:mod:`pftrack.multicam.joint`, 8 levels a channel).
Its *lag similarity* is ``1 - D_B`` against the mean of the box's histograms ``LAG_FAR`` to ``LAG_NEAR + 1`` frames
before, and its *break* the lag's z-score against the lags of up to ``BASE`` frames before (skipping the last
``LAG_NEAR``; at least ``MIN_BASE`` of them, the spread at least ``MIN_SD``). On the PETS views
(``scripts/make_pets_views.py``) a *switch* is the first frame on another annotated walker (``views_flag_trace``'s
``walker_on``) while the overlap with the person is under 0.3, within 10 frames of an overlap of 0.5 or more.

Printed per folder given: the breaks that the lowest break within ``[-8, +5]`` frames of a quarter and of half of
the switches reach, with the share of the frames on the target (IoU >= 0.5) below each; and a *doubt flag* simulated
on the recorded tracks (the tracker's path unchanged): a break below ``z`` raises the flag for at most ``T`` frames,
and it falls again as soon as the box's histogram is back within ``c`` spreads of the lag's mean against the mean
histogram before the break. Diagnosis only: it chooses nothing.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from views_flag_trace import view_walkers, walker_on  # noqa: E402

from pftrack.cli.common import parse_seeds  # noqa: E402
from pftrack.frames import as_bgr_uint8  # noqa: E402
from pftrack.geometry import iou  # noqa: E402
from pftrack.io.datasets import read_sequence  # noqa: E402
from pftrack.io.sources import read_image  # noqa: E402
from pftrack.multicam.btf import identity_btf  # noqa: E402
from pftrack.multicam.joint import joint_histogram, joint_similarity_matrix, push_joint  # noqa: E402
from pftrack.trackers import create_tracker  # noqa: E402

LAG_NEAR, LAG_FAR = 5, 15   # the lag's reference: the box's histograms 15 to 6 frames before
BASE, MIN_BASE, MIN_SD = 50, 10, 0.03
SWITCH_WINDOW = (8, 5)      # frames before and after a switch searched for its lowest break
GRID = [(z, t, c) for z in (-8.0, -7.0, -6.0) for t in (30, 50) for c in (3.0, 4.0)]


def descriptor(frame: np.ndarray, box) -> np.ndarray:
    """The two-ellipse joint colour histogram of ``box`` (``(2 * 512,)``, mass 1; all zeros for an empty box)."""
    cells, masses, n = joint_histogram(frame, box, "ellipse2")
    return push_joint(cells, masses, n, identity_btf())


def similarity(h: np.ndarray, ref: np.ndarray) -> float:
    """``1 - D_B`` of two histograms (Eq. 24 on one joint histogram)."""
    return float(joint_similarity_matrix(np.asarray(h)[None], np.asarray(ref)[None])[0, 0])


def lag_similarities(desc: np.ndarray, first: np.ndarray) -> np.ndarray:
    """Each frame's similarity to the mean histogram of the box ``LAG_FAR`` .. ``LAG_NEAR + 1`` frames before, the
    first frame's (``first``, the histogram of the box the tracker was started on) counting as the frame before
    the first of ``desc``; while fewer than ``LAG_FAR`` frames are recorded, ``first`` alone."""
    hist = np.concatenate([np.asarray(first, np.float64)[None], np.asarray(desc, np.float64)])
    out = np.empty(len(desc))
    for t in range(len(desc)):
        n = t + 1  # frames recorded before this one, the first frame's included
        past = hist[n - LAG_FAR: n - LAG_NEAR] if n >= LAG_FAR else hist[:1]
        out[t] = similarity(hist[n], past.mean(axis=0))
    return out


def breaks(lag: np.ndarray) -> np.ndarray:
    """The lag's z-score against its values ``BASE`` to ``LAG_NEAR + 1`` frames before (``+inf`` with fewer than
    ``MIN_BASE`` of them), with a spread of at least ``MIN_SD``."""
    out = np.full(len(lag), np.inf)
    for t in range(len(lag)):
        past = lag[max(0, t - BASE): max(0, t - LAG_NEAR)]
        if len(past) >= MIN_BASE:
            out[t] = (lag[t] - past.mean()) / max(float(past.std()), MIN_SD)
    return out


def switches(tiou: np.ndarray, walker: np.ndarray) -> list[int]:
    """The frames where the box moved onto another walker (``walker >= 0``, overlap with the person under 0.3)
    within 10 frames of an overlap of 0.5 or more (one per such return to the target)."""
    out, last_on = [], None
    for t in range(len(tiou)):
        on = np.isfinite(tiou[t]) and tiou[t] >= 0.5
        if on:
            last_on = t
        off = not (np.isfinite(tiou[t]) and tiou[t] >= 0.3)
        if walker[t] >= 0 and off and last_on is not None and t - last_on <= 10:
            out.append(t)
            last_on = None
    return out


def doubt_flag(desc: np.ndarray, lag: np.ndarray, brk: np.ndarray, lost: np.ndarray, z: float, t_max: int,
               c: float) -> np.ndarray:
    """The flag with a simulated doubt: a break below ``z`` on a frame the tracker reports found raises it for at
    most ``t_max`` frames; it falls once the box's histogram is within ``c`` spreads of the lag's mean against the
    mean histogram before the break."""
    flag = lost.astype(bool).copy()
    left, ref, level = 0, None, 0.0
    for t in range(len(desc)):
        if left > 0:
            left = 0 if similarity(desc[t], ref) >= level else left - 1
        elif brk[t] < z and not lost[t]:
            past = lag[max(0, t - BASE): max(0, t - LAG_NEAR)]
            left = t_max
            ref = desc[max(0, t - LAG_FAR): max(1, t - LAG_NEAR)].mean(axis=0)  # the box before the break
            level = past.mean() - c * max(float(past.std()), MIN_SD)
        flag[t] |= left > 0
    return flag


def trace(folder: Path, tracker: str, seed: int, pets) -> dict[str, np.ndarray]:
    """One run: per frame the IoU with the person, the other walker the box is on (-1: none; on the PETS views, with
    ``pets = (annotation, width, height)`` of the PETS frames), the flag and the box's histogram."""
    seq = read_sequence(folder)
    frames = [as_bgr_uint8(read_image(p)) for p in seq.frames]
    window, others = None, {}
    if pets is not None and re.search(r"_(left|right|top|bottom)\d*_f.*_id\d+$", folder.name):
        gt_all, width, height = pets
        _, window, others = view_walkers(folder, seq, gt_all, width, height)
    gt = np.asarray(seq.groundtruth, float)
    i0 = seq.init_index
    tr = create_tracker(tracker, seed=seed)
    tr.init(frames[i0], seq.init_box)
    rec = {"tiou": [], "walker": [], "lost": [], "desc": [], "first": [descriptor(frames[i0], seq.init_box)]}
    for t in range(i0 + 1, len(frames)):
        st = tr.update(frames[t])
        b = st.box
        rec["tiou"].append(iou(b, gt[t]) if np.all(np.isfinite(gt[t])) else np.nan)
        who = walker_on(b, others.get(t, ()), window) if window is not None else None
        rec["walker"].append(-1 if who is None else who)
        rec["lost"].append(bool(st.lost))
        rec["desc"].append(descriptor(frames[t], b).astype(np.float32))
    return {k: np.asarray(v) for k, v in rec.items()}


def report(runs: list[tuple[str, dict]]) -> None:
    """The switches' breaks against the frames on the target, and the doubt flag's grid, per group of runs."""
    groups: dict[str, list[dict]] = {}
    for group, r in runs:
        groups.setdefault(group, []).append(r)
    for group, rs in groups.items():
        for r in rs:
            r["lag"] = lag_similarities(r["desc"], r["first"][0])
            r["brk"] = breaks(r["lag"])
        on = np.concatenate([r["brk"][np.nan_to_num(r["tiou"], nan=0) >= 0.5] for r in rs])
        lows = []
        for r in rs:
            for t in switches(r["tiou"], r["walker"]):
                lows.append(float(r["brk"][max(0, t - SWITCH_WINDOW[0]): t + SWITCH_WINDOW[1] + 1].min()))
        print(f"== {group}: {len(rs)} runs, {len(lows)} switches, {len(on)} frames on the target", flush=True)
        if lows:
            for q in (0.25, 0.5):
                thr = float(np.quantile(lows, q))
                print(f"   a break below {thr:.2f} catches {q:.2f} of the switches; frames on the target below it "
                      f"{np.mean(on < thr):.4f}")
        for z, t_max, c in GRID:
            absent = up0 = up1 = n_on = fl0 = fl1 = 0
            for r in rs:
                flag = doubt_flag(r["desc"].astype(np.float64), r["lag"], r["brk"], r["lost"], z, t_max, c)
                ab = ~np.isfinite(r["tiou"])
                good = np.nan_to_num(r["tiou"], nan=0) >= 0.5
                absent += int(ab.sum())
                up0 += int(r["lost"][ab].sum())
                up1 += int(flag[ab].sum())
                n_on += int(good.sum())
                fl0 += int(r["lost"][good].sum())
                fl1 += int(flag[good].sum())
            print(f"   doubt z {z:g}, T {t_max}, c {c:g}: lost recall {up0 / max(absent, 1):.3f} -> "
                  f"{up1 / max(absent, 1):.3f} ({absent} absent), false-lost {fl0 / max(n_on, 1):.4f} -> "
                  f"{fl1 / max(n_on, 1):.4f} ({n_on} on the target)", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folders", type=Path, nargs="+", help="folders of sequences (each a group of the tables)")
    ap.add_argument("--pets", type=Path, default=Path("../shared/data/pets09_s2l1_dev"),
                    help="the PETS sequence the views were cut from (its annotation names the other walkers)")
    ap.add_argument("--tracker", default="fusion-pf")
    ap.add_argument("--seeds", default="0,1")
    ap.add_argument("--out", type=Path, help="save the traces (.npz)")
    ap.add_argument("--load", type=Path, help="read the traces saved with --out instead of tracking")
    args = ap.parse_args()
    runs: list[tuple[str, dict]] = []
    if args.load:
        data = np.load(args.load, allow_pickle=False)
        for key in dict.fromkeys(k.rsplit("/", 1)[0] for k in data.files):  # the runs in the order traced
            group = key.split("|", 1)[0]
            if group not in {f.name for f in args.folders}:  # the folders asked for, of those saved
                continue
            runs.append((group, {f: data[f"{key}/{f}"] for f in ("tiou", "walker", "lost", "desc", "first")}))
    else:
        pets = None
        if args.pets.exists():
            ps = read_sequence(args.pets)
            height, width = cv2.imread(str(ps.frames[0])).shape[:2]
            pets = (ps.mot_gt, width, height)
        seeds = parse_seeds(args.seeds)
        for root in args.folders:
            for folder in sorted(p for p in root.iterdir() if (p / "groundtruth_rect.txt").exists()):
                for seed in seeds:
                    runs.append((root.name, trace(folder, args.tracker, seed, pets)))
                    runs[-1][1]["key"] = f"{root.name}|{folder.name}|{seed}"
                    print(f"{folder.name} seed {seed}", flush=True)
        if args.out:
            np.savez_compressed(args.out, **{f"{r['key']}/{f}": r[f] for _, r in runs
                                             for f in ("tiou", "walker", "lost", "desc", "first")})
    report(runs)


if __name__ == "__main__":
    main()
