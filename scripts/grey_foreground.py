"""MOG2's shadow threshold on grey video: multi-pf and both tripwires (pftrack.cues.foreground, docs/mot.md).

    python scripts/grey_foreground.py [--taus 0.5,0.7,0.85,1] [--data ../shared/data] [--out reports/grey_fg]

On grey frames MOG2 cannot tell a cast shadow from an object up to twice as dark as the ground, and with OpenCV's
threshold (0.5) such objects are dropped as shadows. For each threshold ``tau`` given, this script measures, on
the PETS 2009 S2.L1 frames converted to grey (three equal channels), split into the tune half (frames 1-200) and
the report half (201-400):

* ``pftrack mot`` (multi-pf, mog2): MOTA, IDF1, FP and FN of one ``pftrack eval --protocol mot`` run per half, 2
  seeds, on grey MOTChallenge copies of the halves written to ``OUT/pets_grey_{tune,report}``;
* the trackerless tripwire (default, ``--radius auto`` as scripts/ch10_experiments.py takes it) and the
  tracker-based one on multi-pf's tracks, on the four lines of docs/tripwire.md at strides 1-3: crossings found,
  events, accuracy, precision, F1 pooled over the strides;

and on the synthetic traffic of ``pftrack synth traffic-*`` in grey (tune seeds 0-2, report seeds 100-102,
sparse and dense): the trackerless tripwire with the book's timing. Prints one line per figure and writes
``OUT/grey_foreground.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from ch10_experiments import PETS_LINES, add, mot_tracks, ntt, score, summarise  # noqa: E402
from make_mot_halves import HALVES, write_halves  # noqa: E402

from pftrack.cli import main as cli_main  # noqa: E402
from pftrack.events.eval import track_crossings  # noqa: E402
from pftrack.events.geometry import parse_polyline  # noqa: E402
from pftrack.events.tripwire import estimate_radius  # noqa: E402
from pftrack.io.datasets import read_sequence  # noqa: E402
from pftrack.synth.traffic import traffic_scene  # noqa: E402

def write_mot_halves(pets: Path, out: Path) -> dict[str, Path]:
    """Grey MOTChallenge copies of the two halves (frames and ground truth renumbered from 1)."""
    return write_halves(pets, out, prefix="pets_grey", convert=lambda f: cv2.cvtColor(f, cv2.COLOR_BGR2GRAY))


def grey(frame: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR)


def mot(folders: dict[str, Path], taus: list[float], out: Path) -> dict:
    specs = ",".join(f"multi-pf[grey_shadow_threshold={t:g}]" for t in taus)
    res: dict = {}
    for half, folder in folders.items():
        report = out / f"mot_{half}"
        code = cli_main(["eval", str(folder), "--protocol", "mot", "--trackers", specs, "--seeds", "2",
                         "--workers", "2", "--quiet", "--report", str(report)])
        if code:
            raise SystemExit(code)
        lines = (report / "summary.md").read_text(encoding="utf-8").splitlines()
        head = next(i for i, x in enumerate(lines) if x.startswith("| tracker"))
        cols = [c.strip() for c in lines[head].strip("|").split("|")]
        for row in lines[head + 2:]:
            if not row.startswith("| `"):
                break
            cells = [c.strip().strip("`") for c in row.strip("|").split("|")]
            tau = float(cells[0].split("=")[1].rstrip("]"))
            rec = dict(zip(cols[1:], cells[1:]))
            res[f"{half} tau={tau:g}"] = {k: float(rec[k]) for k in ("MOTA", "IDF1", "FP", "FN")}
            print(f"multi-pf | {half} | tau {tau:g}: {res[f'{half} tau={tau:g}']}", flush=True)
    return res


def pets_tripwires(pets: Path, taus: list[float]) -> dict:
    seq = read_sequence(pets)
    frames = [grey(cv2.imread(str(p))) for p in seq.frames]
    res: dict = {}
    for tau in taus:
        acc: dict = {}
        for stride in (1, 2, 3):
            numbers = list(range(1, len(frames) + 1, stride))
            sub = [frames[n - 1] for n in numbers]
            tracks, _ = mot_tracks(sub, numbers, grey_shadow_threshold=tau)
            for text in PETS_LINES:
                line = parse_polyline(text)
                r = estimate_radius(sub[:max(1, 70 // stride)], line, grey_shadow_threshold=tau)
                truth = track_crossings(seq.mot_gt, line, hysteresis=5)
                ev, _ = ntt(sub, numbers, line, 7.0, stride, radius=r, bgs_grey_shadow_threshold=tau)
                cft = [(c.frame, c.direction) for c in track_crossings(tracks, line, hysteresis=5)]
                for half, (lo, hi) in HALVES.items():
                    for key, det in (("ntt", [(e.frame, e.direction) for e in ev]), ("cft", cft)):
                        add(acc, f"{key} | {half} | stride {stride}", score(det, truth, lo, hi))
                        add(acc, f"{key} | {half}", score(det, truth, lo, hi))
        for k, v in summarise(acc).items():
            res[f"{k} | tau={tau:g}"] = v
            if k.count("|") == 1:
                print(f"PETS grey {k} | tau {tau:g}: {v['tp']} of {v['gt']} found, {v['det']} events, "
                      f"accuracy {v['accuracy']:.3f} precision {v['precision']:.3f} F1 {v['f1']:.3f}", flush=True)
    return res


def traffic(taus: list[float]) -> dict:
    res: dict = {}
    for half, seeds in (("tune", (0, 1, 2)), ("report", (100, 101, 102))):
        for kind in ("sparse", "dense"):
            acc: dict = {}
            for sd in seeds:
                sc = traffic_scene(sd, kind=kind)
                frames = [grey(f) for f in sc.frames]
                truth = track_crossings(sc.tracks, sc.wire, hysteresis=3, point="centre")
                numbers = list(range(1, len(frames) + 1))
                for tau in taus:
                    ev, _ = ntt(frames, numbers, sc.wire, sc.fps, 1, timing="match", bgs_grey_shadow_threshold=tau)
                    add(acc, f"tau={tau:g}", score([(e.frame, e.direction) for e in ev], truth, 0, 1e9))
            for k, v in summarise(acc).items():
                res[f"{half} | {kind} | {k}"] = v
                print(f"traffic grey {half} seeds {seeds} | {kind} | {k}: {v['tp']} of {v['gt']} found, "
                      f"precision {v['precision']:.3f} F1 {v['f1']:.3f}", flush=True)
    return res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--taus", default="0.5,0.7,0.85,1")
    ap.add_argument("--data", default="../shared/data")
    ap.add_argument("--out", default="reports/grey_fg")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    taus = [float(t) for t in args.taus.split(",")]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    pets = Path(args.data) / "pets09_s2l1_dev"
    res = {"mot": mot(write_mot_halves(pets, out), taus, out), "pets_tripwires": pets_tripwires(pets, taus),
           "traffic": traffic(taus)}
    (out / "grey_foreground.json").write_text(json.dumps(res, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
