"""The trackerless tripwire on PETS halves from a dark camera (docs/tripwire.md, "A dark, noisy camera").

    python scripts/make_mot_halves.py --dim 0.2 --noise 5 --out dark02     # dark02/dark_tune, dark02/dark_report
    python scripts/ch10_dark.py dark02/dark_report/dark_report --set dark_stretch=0 --set dark_stretch=2,dark_denoise=8.66

For each MOTChallenge folder (a PETS half renumbered from 1, as make_mot_halves.py writes it) and each ``--set`` of
tripwire parameters (``--set ''``: the defaults), the trackerless tripwire runs on the four lines of
scripts/ch10_experiments.py at strides 1, 2 and 3, ``--radius auto`` as there (on the frames as the tripwire sees
them: ``pftrack.events.tripwire.dark_levels``). Crossings are scored against the folder's ground-truth tracks (foot
point, hysteresis 5 px; one-to-one, right direction, within +-10 frames). With ``--cft`` the tracker-based tripwire
on ``pftrack mot``'s tracks of the same frames is scored too. Prints one JSON line per folder, setting and stride,
then the totals per setting (accuracy = TP / GT, precision, F1).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import cv2

sys.path.insert(0, str(Path(__file__).parent))
from ch10_experiments import PETS_LINES, add, mot_tracks, ntt, score, summarise  # noqa: E402

from pftrack.events.eval import track_crossings  # noqa: E402
from pftrack.events.geometry import parse_polyline  # noqa: E402
from pftrack.events.tripwire import TripwireParams, dark_levels, estimate_radius  # noqa: E402
from pftrack.io.datasets import read_sequence  # noqa: E402
from pftrack.params import parse_param_assignments  # noqa: E402


def run(folder: Path, settings: list[dict], cft: bool, strides=(1, 2, 3)) -> dict:
    seq = read_sequence(folder)
    frames = [cv2.imread(str(p)) for p in seq.frames]
    total: dict = {}
    for stride in strides:
        numbers = list(range(1, len(frames) + 1, stride))
        sub = [frames[n - 1] for n in numbers]
        acc: dict = {}
        tracks = mot_tracks(sub, numbers)[0] if cft else None
        for text in PETS_LINES:
            line = parse_polyline(text)
            truth = track_crossings(seq.mot_gt, line, hysteresis=5)
            for kw in settings:
                gain, smooth = dark_levels(sub[0], TripwireParams(**kw))
                r = estimate_radius(sub[:max(1, 70 // stride)], line, gain=gain, smooth=smooth)
                ev, _ = ntt(sub, numbers, line, 7.0, stride, radius=r, **kw)
                s = score([(e.frame, e.direction) for e in ev], truth, 1, len(frames))
                add(acc, json.dumps(kw), s)
                add(total, json.dumps(kw), s)
            if cft:
                s = score([(c.frame, c.direction) for c in track_crossings(tracks, line, hysteresis=5)], truth, 1,
                          len(frames))
                add(acc, "cft (pftrack mot)", s)
                add(total, "cft (pftrack mot)", s)
        for k, v in summarise(acc).items():
            print(json.dumps({"folder": str(folder), "stride": stride, "setting": k, **v}), flush=True)
    return total


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+", type=Path)
    ap.add_argument("--set", action="append", default=None, metavar="K=V[,K=V]",
                    help="tripwire parameters of one setting (repeatable; '' for the defaults)")
    ap.add_argument("--cft", action="store_true", help="also the tracker-based tripwire on pftrack mot's tracks")
    args = ap.parse_args()
    settings = []
    for text in args.set or [""]:
        raw = parse_param_assignments([t for t in text.split(",") if t])
        p = TripwireParams.from_mapping(raw)
        settings.append({k: getattr(p, k) for k in raw})
    total: dict = {}
    for folder in args.folders:
        for k, (g, d, t) in run(folder, settings, args.cft).items():
            a = total.setdefault(k, [0, 0, 0])
            a[0] += g
            a[1] += d
            a[2] += t
    for k, v in summarise(total).items():
        print(json.dumps({"total": k, **v}), flush=True)


if __name__ == "__main__":
    main()
