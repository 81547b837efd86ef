"""Would a re-identification check at acquisition tell the target coming back from a look-alike?

    python scripts/reid_acquisitions.py reports/views_tune reports/views_tune_more --tracker fusion-pf --seeds 0,1

Runs a tracker over single-object sequences and, at every acquisition (the lost flag going down), compares the
acquired box with the target's appearance before the loss, by the book's ch. 11 appearances
(:mod:`pftrack.multicam.appearance`: whole box, two ellipses, positional rings x sectors; RGB histograms of
``--bins`` bins per channel, similarity ``1 - D_B``; with ``--histogram joint`` the hand-over's joint colour
histograms instead, :mod:`pftrack.multicam.joint`, compared at 8 levels a channel):

* ``gallery``: the mean histogram of the last 50 frames tracked with the flag down before the loss;
* ``first``: the first frame's box;
* ``relative``: the gallery similarity minus the median of the tracked frames' own similarities to the gallery
  (each frame against the gallery before it), so that a target that varies a lot is not held to a steady one's
  standard.

A second check judges where the acquired object was when the target was lost: the box's central half is traced
back frame by frame (normalised correlation, :func:`pftrack.cues.template.patch_shift`, within 16 px, peak at least
``min_score``) to the last frame tracked before the loss, for acquisitions at most 5 frames after it. An object
traced all the way to a box that does not overlap the tracker's box there was elsewhere while the tracker still
held the target: such a check would refuse it (``apart``).

A third records whether another candidate elsewhere in the frame passed the acquisition test too when the search
took its candidate (``rival``: the question of ``acquire_unique``, asked here with the tracker's own test, whatever
the option's setting), and the margin of the two ratios (``margin``; infinite without a candidate elsewhere).

An acquisition is *right* when the box overlaps the ground truth (IoU >= 0.3), *wrong* when the target is absent
or the overlap is below 0.1 (others are left out). For each score it prints the area under the ROC curve of
right against wrong (0.5: no separation; 1: every right acquisition scores above every wrong one).

Diagnosis only: it chooses nothing and changes no tracker.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import cv2
import numpy as np

from pftrack.cues.template import trace_back
from pftrack.eval.runner import parse_tracker_list
from pftrack.geometry import in_frame_fraction, iou
from pftrack.io.datasets import read_sequence
from pftrack.multicam.appearance import region_histograms, similarity_matrix
from pftrack.multicam.btf import identity_btf
from pftrack.multicam.joint import joint_histogram, joint_similarity_matrix, push_joint
from pftrack.trackers import create_tracker

FEATURES = ("whole", "ellipse2", "positional")
SCORES = ("gallery", "first", "relative")
GALLERY = 50
TRACE_FRAMES = 5
MIN_SCORES = (0.5, 0.8)


def histograms(frame: np.ndarray, box, feature: str, bins: int) -> np.ndarray:
    """``(regions, 3, bins)`` normalised RGB histograms of ``box``'s regions (ch. 11's appearance, coarser bins);
    ``bins == 0``: the joint colour histogram ``(regions * 512,)`` (8 levels a channel) instead."""
    if bins == 0:
        cells, masses, n = joint_histogram(frame, box, feature)
        return push_joint(cells, masses, n, identity_btf())
    h = region_histograms(frame, box, feature)
    return h.reshape(h.shape[0], 3, bins, 256 // bins).sum(axis=-1)


def sim(a: np.ndarray, b: np.ndarray) -> float:
    if a.ndim == 1:  # joint colour histograms
        return float(joint_similarity_matrix(a[None], b[None])[0, 0])
    return float(similarity_matrix(a[None], b[None])[0, 0])


def roc_auc(right, wrong) -> float:
    """The probability that a right acquisition scores above a wrong one (ties count half)."""
    r, w = np.asarray(right, float)[:, None], np.asarray(wrong, float)[None, :]
    if r.size == 0 or w.size == 0:
        return float("nan")
    return float(np.mean((r > w) + 0.5 * (r == w)))


def label(box, truth) -> str | None:
    """``right`` / ``wrong`` / ``None`` (ambiguous) for an acquired ``box`` against the ground-truth row."""
    present = bool(np.all(np.isfinite(truth)) and truth[2] > 0 and truth[3] > 0)
    o = iou(tuple(box), tuple(truth)) if present else 0.0
    return "right" if o >= 0.3 else ("wrong" if o < 0.1 else None)


def traced_back(grays: list[np.ndarray], box, radius: int = 16, min_score: float = 0.5) -> np.ndarray | None:
    """``box`` on ``grays[-1]`` traced back to ``grays[0]`` by its central half (``None`` when the trace is lost)."""
    start = np.asarray(box, dtype=np.float64)
    core = (start[0] + start[2] / 4, start[1] + start[3] / 4, start[2] / 2, start[3] / 2)
    out = start
    for out in trace_back(reversed(grays[:-1]), grays[-1], start, core, radius, min_score=min_score):
        if out is None:
            return None
    return out


def watch_rivals(tracker) -> dict:
    """Wrap a colour tracker's choice of a search candidate (its ``_choose``, on this instance only) so that, on a
    frame whose search acquires its best candidate, the returned dict holds ``rival`` (did a candidate elsewhere
    pass the acquisition test too: ``_rival``) and ``margin`` (the candidate's ratio minus that one's). Emptied on
    every search frame; stays empty for other trackers. Its list ``"two"`` keeps the frame indices on which the
    search's first candidate and a rival both passed (``acquire_unique_hold``'s question)."""
    seen: dict = {}
    two: list[int] = []
    choose = getattr(tracker, "_choose", None)
    if choose is None or not hasattr(tracker, "_rival"):
        return seen

    def wrapped(frame, c, supporters):
        seen.clear()
        seen["two"] = two
        ok, llr = tracker.loss.would_acquire(c.s_best, c.lp)
        rival, margin = tracker._rival(frame, c, c.best, llr), math.inf  # before the loss test moves
        if rival and ok:
            two.append(tracker.frame_index)
        found = tracker._rival_sample(frame, c, c.best)
        if found is not None:
            margin = llr - tracker.loss.would_acquire(*found[1])[1]
        a = choose(frame, c, supporters)
        if a.found and a.best == c.best:
            seen.update(rival=bool(rival), margin=float(margin))
        return a

    tracker._choose = wrapped
    return seen


def acquisitions(frames, truth, init_box, tracker, bins: int) -> list[dict]:
    """The scores of every acquisition of ``tracker`` (already created) over ``frames``."""
    tracker.init(frames[0], init_box)
    rivals = watch_rivals(tracker)
    first = {k: histograms(frames[0], init_box, k, bins) for k in FEATURES}
    gallery = {k: [first[k]] for k in FEATURES}
    own = {k: [] for k in FEATURES}
    out, was_lost = [], False
    grays = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in frames]
    last_box, lost_at, box_before = tuple(init_box), 0, tuple(init_box)
    for t in range(1, len(frames)):
        strip = getattr(tracker, "_exit_strip", lambda: None)() is not None  # the loss taken for an exit
        st = tracker.update(frames[t])
        if st.lost and not was_lost:
            lost_at, box_before = t, last_box
        if was_lost and not st.lost and (lab := label(st.box, truth[t])) is not None:
            fh, fw = frames[t].shape[:2]
            whole = tuple(st.info.get("box_full", st.box))  # the whole estimate (st.box is its part in the frame)
            rec = {"t": t, "label": lab, "in_frame": in_frame_fraction(whole, fw, fh), "delay": t - lost_at,
                   "exit_strip": strip, "rival": rivals.get("rival"), "margin": rivals.get("margin"),
                   "two_in_loss": any(lost_at <= f < t for f in rivals.get("two", ()))}
            for ms in MIN_SCORES:
                b = traced_back(grays[lost_at - 1:t + 1], st.box, min_score=ms) if t - lost_at <= TRACE_FRAMES else None
                rec[f"apart {ms}"] = bool(b is not None and iou(tuple(b), box_before) == 0.0)
            for k in FEATURES:
                h, g = histograms(frames[t], st.box, k, bins), np.mean(gallery[k][-GALLERY:], axis=0)
                rec[k] = {"gallery": sim(h, g), "first": sim(h, first[k]),
                          "relative": sim(h, g) - (float(np.median(own[k])) if own[k] else 1.0)}
            out.append(rec)
        if not st.lost and not was_lost:
            for k in FEATURES:
                h = histograms(frames[t], st.box, k, bins)
                own[k].append(sim(h, np.mean(gallery[k][-GALLERY:], axis=0)))
                gallery[k].append(h)
        if not st.lost:
            last_box = tuple(st.box)
        was_lost = bool(st.lost)
    return out


def summary(records: list[dict]) -> dict:
    """ROC AUC of right against wrong acquisitions for every appearance and score."""
    right = [r for r in records if r["label"] == "right"]
    wrong = [r for r in records if r["label"] == "wrong"]
    return {"right": len(right), "wrong": len(wrong),
            "in_frame": {"right": float(np.median([r["in_frame"] for r in right])) if right else float("nan"),
                         "wrong": float(np.median([r["in_frame"] for r in wrong])) if wrong else float("nan")},
            "auc": {f"{k} {s}": roc_auc([r[k][s] for r in right], [r[k][s] for r in wrong])
                    for k in FEATURES for s in SCORES},
            "wrong_no_strip": [r["delay"] for r in wrong if not r["exit_strip"]],
            "apart": {ms: (sum(r[f"apart {ms}"] for r in right), sum(r[f"apart {ms}"] for r in wrong))
                      for ms in MIN_SCORES},
            "rival": (sum(bool(r["rival"]) for r in right), sum(bool(r["rival"]) for r in wrong)),
            "two_in_loss": (sum(r["two_in_loss"] for r in right), sum(r["two_in_loss"] for r in wrong)),
            "margin_auc": roc_auc([r["margin"] for r in right if r["margin"] is not None],
                                  [r["margin"] for r in wrong if r["margin"] is not None])}


def sequence_folders(paths: list[Path]) -> list[Path]:
    out = []
    for p in paths:
        is_seq = (p / "groundtruth_rect.txt").exists() or (p / "img").is_dir()
        out += [p] if is_seq else sorted(q for q in p.iterdir() if q.is_dir())
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("sequences", nargs="+", type=Path, help="sequence folders, or folders of them")
    ap.add_argument("--tracker", default="fusion-pf", help="a tracker, with parameters as NAME[key=value;...]")
    ap.add_argument("--seeds", default="0,1")
    ap.add_argument("--bins", type=int, default=32, help="histogram bins per channel (a divisor of 256)")
    ap.add_argument("--histogram", choices=["marginal", "joint"], default="marginal",
                    help="the channels' histograms (of --bins bins) or joint colour histograms")
    ap.add_argument("--json", type=Path, help="also write every acquisition's scores here")
    args = ap.parse_args()
    bins = 0 if args.histogram == "joint" else args.bins
    config = parse_tracker_list(args.tracker)[0]  # NAME or NAME[key=value;...], as pftrack eval
    records = []
    for folder in sequence_folders(args.sequences):
        seq = read_sequence(folder)
        frames = [cv2.imread(str(p)) for p in seq.frames[seq.init_index:]]
        truth = np.asarray(seq.groundtruth, dtype=np.float64)[seq.init_index:]
        for seed in (int(s) for s in args.seeds.split(",")):
            tracker = create_tracker(config.name, seed=seed, **config.param_dict)
            for rec in acquisitions(frames, truth, seq.init_box, tracker, bins):
                records.append({"sequence": folder.name, "seed": seed, **rec})
    if args.json:
        args.json.write_text(json.dumps(records) + "\n", encoding="utf-8")
    s = summary(records)
    print(f"{args.tracker}: {s['right']} right and {s['wrong']} wrong acquisitions; median share of the box in the "
          f"frame {s['in_frame']['right']:.2f} and {s['in_frame']['wrong']:.2f}")
    for name, a in s["auc"].items():
        print(f"  {name:22s} ROC AUC {a:.3f}")
    d = s["wrong_no_strip"]
    print(f"  wrong acquisitions with no exit strip: {len(d)}, a median of "
          f"{np.median(d) if d else float('nan'):.0f} frames after the loss")
    for ms, (r, w) in s["apart"].items():
        print(f"  elsewhere at the loss (min_score {ms}): {r} right and {w} wrong acquisitions")
    r, w = s["rival"]
    print(f"  a candidate elsewhere passed the acquisition test too: {r} right and {w} wrong acquisitions; "
          f"margin of the ratios ROC AUC {s['margin_auc']:.3f}")
    r, w = s["two_in_loss"]
    print(f"  two candidates passed together on an earlier search frame of the loss: {r} right and {w} wrong")


if __name__ == "__main__":
    main()
