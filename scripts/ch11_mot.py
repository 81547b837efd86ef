"""Book ch. 11 end to end (docs/handover.md): `pftrack mot`'s own tracks of each camera handed to `pftrack handover`.

    python scripts/ch11_mot.py [--data ../shared/data] [--split report|tune] [--repeats 5] [--btf cbtf,none]
                               [--out reports/ch11_mot]

The scenes of scripts/ch11_experiments.py (`pftrack synth twocam`: the left and right parts of the PETS frames,
camera B through a seeded colour response; report: frames 201-400, colour seeds 100-104; tune: frames 1-200,
seeds 0-2; three positions of the blind strip) are written as MOTChallenge folders. Each camera is tracked by
`pftrack mot` with its defaults, and `pftrack handover` links the tracks, as a user would run them. Beside it, the
same commands with the ground-truth tracks (the figures of docs/handover.md's tables, on fewer splits).

Each track of `pftrack mot` is given the person of the ground-truth box it overlaps (IoU >= 0.5) on most of its
frames, where it overlaps one on at least 3 frames (else no person). In each scene the people seen in both cameras
are split `repeats` times at random into training people (40 %) and test people, as in ch11_experiments.py. The
training pairs are every (track of A, track of B) of one training person: the ground truth's tracks, or the mot
tracks given that person. A test person's hand-over is linked when a link joins a track of camera A and one of
camera B that are both that person's; links counts such hand-overs (each person at most as many as the ground truth
has) over the test hand-overs, precision the links that are right over all links made.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import tempfile
from pathlib import Path

import numpy as np

from pftrack.cli import main as pftrack
from pftrack.geometry import iou
from pftrack.io.datasets import read_mot_txt
from pftrack.synth.twocam import export_twocam, twocam_scene

SPLITS = ((300, 390), (340, 430), (380, 470))
SCENES = {"report": ((201, 400), (100, 101, 102, 103, 104)), "tune": ((1, 200), (0, 1, 2))}


def persons_of(rows: np.ndarray, gt: np.ndarray, identity: dict, cam: str, min_frames: int = 3) -> dict[int, int]:
    """Each track of ``rows`` (MOT) to the person of the ground-truth box it overlaps most often (IoU >= 0.5)."""
    out = {}
    for tid in np.unique(rows[:, 1]).astype(int):
        votes: dict[int, int] = {}
        for r in rows[rows[:, 1] == tid]:
            g = gt[gt[:, 0] == r[0]]
            if len(g) == 0:
                continue
            o = iou(r[2:6], g[:, 2:6])
            k = int(np.argmax(o))
            if o[k] >= 0.5:
                p = identity[(cam, int(g[k, 1]))]
                votes[p] = votes.get(p, 0) + 1
        if votes and max(votes.values()) >= min_frames:
            out[int(tid)] = max(votes, key=votes.get)
    return out


def handover(folder: Path, ta: Path, tb: Path, pairs: list, btf: str) -> list[tuple[int, int]]:
    """`pftrack handover` on the scene's folders with these tracks and training pairs; its links."""
    train, links = folder / "pairs.csv", folder / "links.csv"
    train.write_text("track_a,track_b\n" + "".join(f"{a},{b}\n" for a, b in pairs), encoding="utf-8")
    with contextlib.redirect_stderr(io.StringIO()):
        code = pftrack(["handover", str(folder / "cam_a"), str(folder / "cam_b"), "--tracks-a", str(ta),
                        "--tracks-b", str(tb), "--train-pairs", str(train), "--btf", btf, "--out", str(links),
                        "--quiet"])
    assert code == 0, code
    return [tuple(int(v) for v in line.split(",")[:2]) for line in links.read_text().splitlines()[1:]]


def scene_counts(sc, folder: Path, repeats: int, seed: int, methods: list[str]) -> dict:
    """``{(tracks, method): [right links, test hand-overs, links made]}`` over the repeats of one scene."""
    export_twocam(sc, folder)
    for cam in ("a", "b"):
        with contextlib.redirect_stderr(io.StringIO()):
            assert pftrack(["mot", str(folder / f"cam_{cam}"), "--out", str(folder / f"mot_{cam}.txt"),
                            "--quiet"]) == 0
    gt = {c: read_mot_txt(folder / f"cam_{c}" / "gt" / "gt.txt") for c in ("a", "b")}
    mot = {c: read_mot_txt(folder / f"mot_{c}.txt") for c in ("a", "b")}
    person = {("gt", c, int(t)): sc.identity[(c, int(t))] for c in ("a", "b") for t in np.unique(gt[c][:, 1])}
    for c in ("a", "b"):
        for t, p in persons_of(mot[c], gt[c], sc.identity, c).items():
            person[("mot", c, t)] = p
    ho = sc.handovers()
    crossing = sorted({sc.identity[("a", a)] for a, _ in ho})
    need: dict[int, int] = {}
    for a, _ in ho:
        need[sc.identity[("a", a)]] = need.get(sc.identity[("a", a)], 0) + 1
    out: dict = {}
    if len(crossing) < 2:
        return out
    rng = np.random.default_rng(seed)
    for _ in range(repeats):
        perm = rng.permutation(crossing)
        train = set(perm[:max(1, round(0.4 * len(crossing)))].tolist())
        test_need = sum(n for p, n in need.items() if p not in train)
        for tracks in ("gt", "mot"):
            ids = {c: [int(t) for t in np.unique((gt if tracks == "gt" else mot)[c][:, 1])] for c in ("a", "b")}
            pairs = [(a, b) for a in ids["a"] for b in ids["b"]
                     if person.get((tracks, "a", a)) is not None and person.get((tracks, "a", a)) in train
                     and person.get((tracks, "a", a)) == person.get((tracks, "b", b))]
            ta = folder / ("cam_a/gt/gt.txt" if tracks == "gt" else "mot_a.txt")
            tb = folder / ("cam_b/gt/gt.txt" if tracks == "gt" else "mot_b.txt")
            for method in methods:
                links = handover(folder, ta, tb, pairs, method)
                got: dict[int, int] = {}
                for a, b in links:
                    p = person.get((tracks, "a", a))
                    if p is not None and p not in train and p == person.get((tracks, "b", b)):
                        got[p] = got.get(p, 0) + 1
                right = sum(min(n, need.get(p, 0)) for p, n in got.items())
                acc = out.setdefault((tracks, method), [0, 0, 0])
                acc[0] += right
                acc[1] += test_need
                acc[2] += len(links)
    return out


def run(data: Path, split: str, repeats: int, methods: list[str], response: str) -> dict:
    numbers, seeds = SCENES[split]
    total: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        for sd in seeds:
            for sp in SPLITS:
                sc = twocam_scene(data / "pets09_s2l1_dev", sd, numbers=numbers, split=sp, response=response)
                folder = Path(tmp) / f"s{sd}_{sp[0]}"
                counts = scene_counts(sc, folder, repeats, sd, methods)
                for k, (r, n, nl) in counts.items():
                    t = total.setdefault(k, [0, 0, 0])
                    t[0] += r
                    t[1] += n
                    t[2] += nl
                print(split, sd, sp, {f"{a} {b}": round(r / n, 3) for (a, b), (r, n, _) in counts.items() if n},
                      flush=True)
    return {f"{tracks} {method}": {"links": r / n if n else None, "precision": r / nl if nl else None,
                                   "handovers": n, "links_made": nl}
            for (tracks, method), (r, n, nl) in total.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default="../shared/data")
    ap.add_argument("--split", choices=sorted(SCENES), default="report")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--btf", default="cbtf,none", help="comma-separated --btf methods (default cbtf,none)")
    ap.add_argument("--response", choices=["mild", "strong"], default="mild")
    ap.add_argument("--out", default="reports/ch11_mot")
    args = ap.parse_args()
    res = run(Path(args.data), args.split, args.repeats, args.btf.split(","), args.response)
    for k, v in sorted(res.items()):
        prec = "-" if v["precision"] is None else f"{v['precision']:.3f}"
        print(f"{k:12s} links {v['links']:.3f}  precision {prec}  (test hand-overs {v['handovers']}, "
              f"links made {v['links_made']})")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{args.split}_{args.response}.json").write_text(json.dumps(res, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
