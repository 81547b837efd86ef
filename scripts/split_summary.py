"""Group a pftrack eval results.csv by kind of sequence: real, PETS pedestrians, grey, grey+light, synthetic scenes.

    python scripts/split_summary.py reports/split/report/results.csv [--scenes reports/split/report_synth]

Columns: mean OTB AUC per group; lost recall and false-lost rate (means over the runs where each is defined);
the fraction of reappearances re-acquired within 15 frames; the median update fps on the real sequences.
A second table gives the tracking percentage (the fraction of frames with IoU > 0.5, book ch. 6 Table 1's
measure, read from the ``runs/`` records beside results.csv).  With ``--scenes DIR`` (the folder the synthetic
scenes were written to by ``pftrack synth``), a third table splits the re-acquisitions by the scenes' drawn
nuisance ``gray`` (``meta.json``): grey scenes, colour scenes, and the rest (real and PETS sequences); a fourth by
the scenes' light as well: no change, a drift of the whole frame's light, or a drift on the objects alone.

Synthetic scenes of the other kinds of ``pftrack synth`` (simple, crossing, face, photo-vanish, ...: a name
``kind-NNN``) make the column ``othersynth``, not ``real``. ``--by-kind`` adds a table of the mean AUC per scene kind
(the name without its seed; the other sequences by their group), and with ``--scenes`` the size of the boxes: the
median over the runs of each run's median of sqrt(box area / true area) over the second half of its frames where
both boxes are defined (a box that shrinks or grows on a target of constant size).
"""

from __future__ import annotations

import argparse
import csv
import json
import re
from pathlib import Path
from collections import defaultdict

import numpy as np

GROUPS = ["real", "pets", "gray", "graylight", "varied", "vanish", "leave", "exit", "camouflage", "teleport",
          "othersynth"]
SPLIT_KINDS = ("vanish", "leave", "exit", "varied", "camouflage", "teleport")
#: a synthetic scene's name: its kind (lower-case words joined by hyphens) and its seed
SCENE_NAME = re.compile(r"^([a-z]+(?:-[a-z]+)*)-(\d+)$")


def group_of(sequence: str) -> str:
    for g in SPLIT_KINDS:
        if sequence.startswith(g + "-"):
            return g
    if SCENE_NAME.match(sequence):
        return "othersynth"  # a scene of another kind of pftrack synth (simple, face, photo-vanish, ...)
    if sequence.startswith("pets"):
        return "pets"  # single people of PETS 2009 S2.L1 (scripts/make_mot_sot.py)
    if sequence.endswith("-gray-light"):
        return "graylight"
    if sequence.endswith("-gray"):
        return "gray"
    return "real"


def _mean(vals: list[float]) -> float:
    return sum(vals) / len(vals) if vals else float("nan")


def _scene_nuisances(roots: list[str]) -> dict[str, dict]:
    """``sequence -> nuisances`` from the ``meta.json`` of the synthetic scenes under ``roots``."""
    out = {}
    for root in roots:
        for meta in sorted(Path(root).glob("**/meta.json")):
            out[meta.parent.name] = json.loads(meta.read_text()).get("nuisances") or {}
    return out


def scene_colours(roots: list[str], nuisances: dict[str, dict] | None = None) -> dict[str, str]:
    """``sequence -> "grey" | "colour"`` from the ``meta.json`` of the synthetic scenes under ``roots`` (or from
    their ``nuisances``, already read)."""
    nuisances = _scene_nuisances(roots) if nuisances is None else nuisances
    return {s: "grey" if nz.get("gray") else "colour" for s, nz in nuisances.items()}


def scene_lights(roots: list[str], nuisances: dict[str, dict] | None = None) -> dict[str, str]:
    """``sequence -> "<colour> <light>"``: the scene's colour and its drawn light (``none``, ``frame``: the whole
    frame's light drifts, ``objects``: the light drifts on the target and look-alikes alone)."""
    out = {}
    nuisances = _scene_nuisances(roots) if nuisances is None else nuisances
    for s, nz in nuisances.items():
        light = "none" if nz.get("illumination") is None else (
            "objects" if nz.get("illumination_target_only") else "frame")
        out[s] = f"{'grey' if nz.get('gray') else 'colour'} {light}"
    return out


def reacquired_by(rows: list[dict], kinds: dict[str, str], columns: list[str], title: str) -> None:
    """Re-acquired / reappearances per tracker in each of ``columns`` of ``kinds`` (sequences not in ``kinds``:
    ``"other"``)."""
    counts: dict[tuple[str, str], list[float]] = defaultdict(lambda: [0.0, 0.0])
    for r in rows:
        if r.get("reappearances") in ("", None):
            continue
        c = counts[(r["tracker"], kinds.get(r["sequence"], "other"))]
        c[0] += float(r["reacquired"] or 0)
        c[1] += float(r["reappearances"])
    print(f"\nre-acquired / reappearances, {title}")
    print(f"{'tracker':40s} " + " ".join(f"{k:>14s}" for k in columns))
    for t in sorted({t for t, _ in counts}):
        cells = [counts.get((t, k), [0.0, 0.0]) for k in columns]
        print(f"{t:40s} " + " ".join(f"{int(a):>7d} / {int(b):<4d}" for a, b in cells))


def reacquired_by_colour(rows: list[dict], kinds: dict[str, str]) -> None:
    """Re-acquired / reappearances per tracker in grey scenes, colour scenes and the other sequences."""
    reacquired_by(rows, kinds, ["grey", "colour", "other"], "by the scenes' colour")


def kind_of(sequence: str) -> str:
    """A synthetic scene's kind (its name without the seed); another sequence's group (:func:`group_of`)."""
    m = SCENE_NAME.match(sequence)
    return m.group(1) if m else group_of(sequence)


def _truths(roots: list[str]) -> dict[str, Path]:
    """``sequence -> folder`` of the synthetic scenes under ``roots`` (the folders of their ``meta.json``)."""
    return {meta.parent.name: meta.parent for root in roots for meta in sorted(Path(root).glob("**/meta.json"))}


def size_ratio(boxes: np.ndarray, truth: np.ndarray) -> float:
    """The median of sqrt(box area / true area) over the second half of the frames where both are defined (NaN
    when fewer than 5)."""
    n = min(len(boxes), len(truth))
    b, t = boxes[:n], truth[:n]
    ok = np.isfinite(b).all(axis=1) & np.isfinite(t).all(axis=1) & (t[:, 2] * t[:, 3] > 0)
    ok &= np.arange(n) >= n // 2
    if ok.sum() < 5:
        return float("nan")
    return float(np.median(np.sqrt(np.abs(b[ok, 2] * b[ok, 3]) / (t[ok, 2] * t[ok, 3]))))


def column_labels(names: list[str], width: int = 24) -> list[str]:
    """The names as column headings when each fits ``width`` characters; otherwise the letters A, B, ... (the
    table then prints which tracker each letter is), so that no two columns read alike."""
    if all(len(n) <= width for n in names):
        return list(names)
    return [chr(ord("A") + i) if i < 26 else f"T{i}" for i in range(len(names))]


def kind_table_head(title: str, trackers: list[str]) -> None:
    """Print a by-kind table's title, the letters' key when the names are lettered (:func:`column_labels`), and its
    header row."""
    print(title)
    labels = column_labels(trackers)
    for label, t in zip(labels, trackers):
        if label != t:
            print(f"  {label}: {t}")
    print(f"{'kind':16s} " + " ".join(f"{t:>24s}" for t in labels))


def by_kind(rows: list[dict], runs: Path, scenes: list[str] | None) -> None:
    """Mean AUC per tracker and scene kind; with ``scenes``, the boxes' size against the truth's (:func:`size_ratio`,
    the median over the runs of a kind)."""
    auc: dict[tuple[str, str], list[float]] = defaultdict(list)
    for r in rows:
        if r.get("auc") not in ("", None):
            auc[(r["tracker"], kind_of(r["sequence"]))].append(float(r["auc"]))
    sizes: dict[tuple[str, str], list[float]] = defaultdict(list)
    if scenes and runs.is_dir():
        from pftrack.io import discover_sequences

        folders = _truths(scenes)
        truth: dict[str, np.ndarray] = {}
        for f in sorted(runs.glob("ope__*.json")):
            rec = json.loads(f.read_text())
            seq = rec["sequence"]
            if seq not in folders or not rec.get("boxes"):
                continue
            if seq not in truth:
                truth[seq] = discover_sequences(folders[seq])[0].groundtruth
            boxes = np.array([np.nan if v is None else v for v in rec["boxes"]], dtype=np.float64).reshape(-1, 4)
            v = size_ratio(boxes, truth[seq])
            if v == v:
                sizes[(rec["tracker"], kind_of(seq))].append(v)
    trackers = sorted({t for t, _ in auc})
    kinds = sorted({k for _, k in auc})
    kind_table_head("\nmean AUC by kind" + (" (box size against the truth's, sqrt of the areas, second half)"
                                             if sizes else ""), trackers)
    for k in kinds:
        cells = []
        for t in trackers:
            a = _mean(auc.get((t, k), []))
            z = sizes.get((t, k))
            cells.append(f"{a:.3f}" + (f" ({np.median(z):.2f})" if z else ""))
        print(f"{k:16s} " + " ".join(f"{c:>24s}" for c in cells))


def flags_by_kind(rows: list[dict]) -> None:
    """The lost flag per tracker and scene kind, pooled over the frames as ``pftrack eval`` pools them: lost recall
    over the absent frames and false-lost rate over the frames with IoU >= 0.5 (each run's rate weighted by its
    frames; "-" where a kind has no such frame)."""
    sums: dict[tuple[str, str, str], list[float]] = defaultdict(lambda: [0.0, 0.0])
    for r in rows:
        for rate, frames in (("lost_recall", "absent_frames"), ("false_lost", "covered_frames")):
            n = float(r.get(frames) or 0)
            if n > 0 and r.get(rate) not in ("", None, "nan"):
                cell = sums[(r["tracker"], kind_of(r["sequence"]), rate)]
                cell[0] += float(r[rate]) * n
                cell[1] += n
    if not sums:
        return
    trackers = sorted({t for t, _, _ in sums})
    kinds = sorted({k for _, k, _ in sums})

    def rate(t: str, k: str, name: str) -> str:
        v, n = sums.get((t, k, name), (0.0, 0.0))
        return f"{v / n:.2f}" if n else "-"

    kind_table_head("\nlost recall / false-lost by kind, pooled over the frames", trackers)
    for k in kinds:
        print(f"{k:16s} " + " ".join(f"{rate(t, k, 'lost_recall') + ' / ' + rate(t, k, 'false_lost'):>24s}"
                                     for t in trackers))


def main(path: str, scenes: list[str] | None = None, kinds: bool = False) -> None:
    with open(path, encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    cells: dict[tuple[str, str], dict[str, list[float]]] = defaultdict(lambda: defaultdict(list))
    for r in rows:
        cell = cells[(r["tracker"], group_of(r["sequence"]))]
        for key in ("auc", "lost_recall", "false_lost", "fps", "reappearances", "reacquired"):
            if r.get(key) not in ("", None):
                cell[key].append(float(r[key]))
    trackers = sorted({t for t, _ in cells})
    print(f"{'tracker':40s} " + " ".join(f"{g:>10s}" for g in GROUPS) + "   recall  falseL  reacq   fps")
    for t in trackers:
        per = [cells.get((t, g), {}) for g in GROUPS]
        aucs = " ".join(f"{_mean(c.get('auc', [])):10.3f}" for c in per)
        recall = _mean([v for c in per for v in c.get("lost_recall", [])])
        false = _mean([v for c in per for v in c.get("false_lost", [])])
        reapp = sum(v for c in per for v in c.get("reappearances", []))
        reacq = sum(v for c in per for v in c.get("reacquired", []))
        fps = sorted(cells.get((t, "real"), {}).get("fps", []))
        med = fps[len(fps) // 2] if fps else float("nan")
        print(f"{t:40s} {aucs}   {recall:.3f}   {false:.3f}  {reacq / max(reapp, 1):.2f}  {med:.0f}")
    runs = Path(path).parent / "runs"
    if runs.is_dir():
        tp: dict[tuple[str, str], list[float]] = defaultdict(list)
        for f in sorted((p for pat in ("ope__*.json", "sre__*.json") for p in runs.glob(pat))):
            rec = json.loads(f.read_text())
            curve = rec.get("success") or []
            if len(curve) == 21:  # thresholds 0, 0.05, ..., 1: index 10 is IoU > 0.5
                tp[(rec["tracker"], group_of(rec["sequence"]))].append(float(curve[10]))
        print("\ntracking percentage (frames with IoU > 0.5)")
        print(f"{'tracker':40s} " + " ".join(f"{g:>10s}" for g in GROUPS) + "        all")
        for t in trackers:
            vals = [tp.get((t, g), []) for g in GROUPS]
            allv = [v for vs in vals for v in vs]
            print(f"{t:40s} " + " ".join(f"{100 * _mean(v):10.1f}" for v in vals) + f" {100 * _mean(allv):10.1f}")
    if scenes:
        nuisances = _scene_nuisances(scenes)      # every meta.json read once
        reacquired_by_colour(rows, scene_colours(scenes, nuisances))
        lights = [f"{c} {li}" for c in ("colour", "grey") for li in ("none", "frame", "objects")]
        reacquired_by(rows, scene_lights(scenes, nuisances), lights, "by the scenes' colour and light")
    if kinds:
        by_kind(rows, runs, scenes)
        flags_by_kind(rows)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", help="a pftrack eval results.csv")
    ap.add_argument("--scenes", nargs="+", help="folders of the synthetic scenes (their meta.json)")
    ap.add_argument("--by-kind", action="store_true", help="mean AUC (and with --scenes the boxes' size) and the "
                                                          "pooled lost-flag rates by scene kind")
    a = ap.parse_args()
    main(a.results, a.scenes, a.by_kind)
