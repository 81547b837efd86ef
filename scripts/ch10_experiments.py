"""Book ch. 10 experiments (docs/tripwire.md): trackerless tripwire (NTT) vs the tracker-based one (CFT).

    python scripts/ch10_experiments.py [--data ../shared/data] [--seeds 100] [--json reports/ch10.json]
    python scripts/ch10_experiments.py --walkers     # synthetic upright walkers (reports/ch10_walkers.json)
    python scripts/ch10_experiments.py --angles      # PETS crossings found, by the walkers' angle to the line
    python scripts/ch10_experiments.py --grey        # PETS in grey (reports/ch10_grey.json)
    python scripts/ch10_experiments.py --h264 28     # PETS through an H.264 encoder at CRF 28 (needs PyAV)
    python scripts/ch10_experiments.py --lines "X1,Y1;X2,Y2" ...   # PETS, stride 1, other lines (default: five
                                                     # lines used for no choice, docs/tripwire.md)

* PETS 2009 S2.L1 (7 fps, 768x576): four lines across the walkways; frames 1-200 are the tune
  half (the defaults were chosen there), 201-400 the report half; strides 1-3.
* Synthetic top-down traffic (`pftrack synth traffic-sparse|traffic-dense`), report seeds
  100+: 30 fps and strides 2, 3, 5 (15, 10, 6 fps), the chapter's E10.1 / E10.2.
NTT = the trackerless tripwire with its defaults (foot-point timing, confirmed) on PETS, and with
``timing=match`` (the chapter's rule) on the top-down traffic, where CFT takes the centre point.
CFT = `pftrack mot` (multi-pf, MOG2 detector) on the same frames, then the hysteresis state
machine on each track's foot (PETS) or centre (top-down) point.  Ground truth = the same
state machine on the annotated tracks.  Events match one-to-one, same direction, within
+-10 frames of the original frame rate.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import cv2
import numpy as np

from pftrack.cli.common import parse_seeds
from pftrack.events.eval import match_events, track_crossings
from pftrack.events.geometry import parse_polyline
from pftrack.events.tripwire import TrackerlessTripwire, TripwireParams, estimate_radius
from pftrack.io.codec import h264_round_trip
from pftrack.io.datasets import read_sequence
from pftrack.multi import create_multi_tracker
from pftrack.synth.traffic import traffic_scene

PETS_LINES = ["384,150;384,450", "550,120;550,420", "150,250;700,250", "250,300;650,300"]
TOL = 10


def mot_tracks(frames, numbers, **params) -> np.ndarray:
    """multi-pf tracks (MOT rows) on the given frames, and its update time."""
    tr = create_multi_tracker("multi-pf", seed=0, **params)
    rows = []
    t0 = time.perf_counter()
    for n, f in zip(numbers, frames):
        for o in tr.update(f):
            rows.append([n, o.track_id, *o.box, 1, -1, -1, -1])
    dt = time.perf_counter() - t0
    return np.asarray(rows, dtype=np.float64).reshape(-1, 10), len(frames) / dt


def ntt(frames, numbers, line, fps, stride, **kw):
    tw = TrackerlessTripwire(line, frames[0].shape[:2], fps, TripwireParams(**kw), stride=stride)
    ev = []
    t0 = time.perf_counter()
    for n, f in zip(numbers, frames):
        ev += tw.process(f, n)
    ev += tw.finish()
    return ev, len(frames) / (time.perf_counter() - t0)


def score(events, truth, lo, hi):
    d = [(f, s) for f, s in events if lo <= f <= hi]
    g = [(c.frame, c.direction) for c in truth if lo <= c.frame <= hi]
    return match_events(d, g, tol=TOL)


def add(acc: dict, key: str, s) -> None:
    a = acc.setdefault(key, [0, 0, 0])
    a[0] += s.gt
    a[1] += s.detected
    a[2] += s.tp


def summarise(acc: dict) -> dict:
    return {k: {"gt": g, "det": d, "tp": t, "accuracy": t / g if g else None, "precision": t / d if d else None,
                "f1": 2 * t / (g + d) if g + d else None} for k, (g, d, t) in acc.items()}


def pets(data: Path, grey: bool = False, crf: int | None = None) -> dict:
    seq = read_sequence(data / "pets09_s2l1_dev")
    frames = [cv2.imread(str(p)) for p in seq.frames]
    if crf is not None:  # the frames through an H.264 encoder
        frames = h264_round_trip(frames, crf, fps=7.0)
    if grey:  # grey video, three equal channels
        frames = [cv2.cvtColor(cv2.cvtColor(f, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR) for f in frames]
    res: dict = {}
    for stride in (1, 2, 3):
        numbers = list(range(1, len(frames) + 1, stride))
        sub = [frames[n - 1] for n in numbers]
        tracks, mot_fps = mot_tracks(sub, numbers)
        acc: dict = {}
        fps_ntt = []
        for li, text in enumerate(PETS_LINES):
            line = parse_polyline(text)
            orient = "vertical lines" if li < 2 else "horizontal lines"
            r = estimate_radius(sub[:max(1, 70 // stride)], line)
            truth = track_crossings(seq.mot_gt, line, hysteresis=5)
            cft = [(c.frame, c.direction) for c in track_crossings(tracks, line, hysteresis=5)]
            for name, kw in (("ntt", {}), ("ntt feet=false", {"feet": False}), ("ntt match", {"timing": "match"}),
                             ("ntt faithful", {"faithful": True})):
                ev, f = ntt(sub, numbers, line, 7.0, stride, radius=r, **kw)
                if name == "ntt":
                    fps_ntt.append(f)
                det = [(e.frame, e.direction) for e in ev]
                for half, (lo, hi) in (("tune 1-200", (1, 200)), ("report 201-400", (201, 400))):
                    add(acc, f"{name} | {half}", score(det, truth, lo, hi))
                    add(acc, f"{name} | {half} | {orient}", score(det, truth, lo, hi))
            for half, (lo, hi) in (("tune 1-200", (1, 200)), ("report 201-400", (201, 400))):
                add(acc, f"cft (pftrack mot) | {half}", score(cft, truth, lo, hi))
                add(acc, f"cft (pftrack mot) | {half} | {orient}", score(cft, truth, lo, hi))
        res[f"stride {stride}"] = {"scores": summarise(acc), "ntt_fps_per_line": float(np.median(fps_ntt)),
                                   "ntt_fps_4_lines": float(1.0 / sum(1.0 / f for f in fps_ntt)),
                                   "mot_fps": mot_fps}
        print("PETS stride", stride, json.dumps(res[f"stride {stride}"]), flush=True)
    return res


def synthetic(seeds: list[int]) -> dict:
    res: dict = {}
    for kind in ("sparse", "dense"):
        for sd in seeds:
            sc = traffic_scene(sd, kind=kind)
            truth = track_crossings(sc.tracks, sc.wire, hysteresis=3, point="centre")
            for stride in (1, 2, 3, 5):
                numbers = list(range(1, len(sc.frames) + 1, stride))
                sub = [sc.frames[n - 1] for n in numbers]
                tracks, mot_fps = mot_tracks(sub, numbers, object_aspect=0.5)
                cft = [(c.frame, c.direction) for c in track_crossings(tracks, sc.wire, hysteresis=3, point="centre")]
                row = {"cft": score(cft, truth, 0, 1e9).row(), "mot_fps": mot_fps}
                # seen from above, the crossing is the matching frame (the chapter's rule): blob timing by the
                # centre merges queued vehicles ("ntt centre" shows the cost)
                for name, kw in (("ntt", {"timing": "match"}), ("ntt centre", {"timing": "centre"}),
                                 ("ntt faithful", {"faithful": True})):
                    if kind == "dense":
                        kw = {**kw, "bgs_history": 100}  # so that stopped vehicles are absorbed (ch10.md P10)
                    ev, f = ntt(sub, numbers, sc.wire, sc.fps, stride, **kw)
                    row[name] = score([(e.frame, e.direction) for e in ev], truth, 0, 1e9).row()
                    if name == "ntt":
                        row["ntt_fps"] = f
                res[f"{kind} seed {sd} fps {sc.fps / stride:.0f}"] = row
                print(kind, sd, stride, json.dumps(row), flush=True)
    return res


def walkers(seeds: list[int], wire: str | None = None) -> dict:
    """Synthetic upright walkers (`pftrack synth walkers`): NTT default, unconfirmed and `match`, and CFT."""
    from pftrack.synth.walkers import walkers_scene

    acc: dict = {}
    for sd in seeds:
        sc = walkers_scene(sd, wire=wire)
        truth = track_crossings(sc.tracks, sc.wire, hysteresis=3)
        numbers = list(range(1, len(sc.frames) + 1))
        r = estimate_radius(sc.frames[:int(10 * sc.fps)], sc.wire)
        for name, kw in (("ntt", {}), ("ntt feet=false", {"feet": False}), ("ntt confirm=false", {"confirm": False}),
                         ("ntt match", {"timing": "match"})):
            ev, _ = ntt(sc.frames, numbers, sc.wire, sc.fps, 1, radius=r, **kw)
            add(acc, name, score([(e.frame, e.direction) for e in ev], truth, 0, 1e9))
        if wire is None:
            tracks, _ = mot_tracks(sc.frames, numbers)
            add(acc, "cft (pftrack mot)",
                score([(c.frame, c.direction) for c in track_crossings(tracks, sc.wire, hysteresis=3)], truth, 0, 1e9))
    return summarise(acc)


def crossing_angles(data: Path) -> dict:
    """PETS, stride 1: ground-truth crossings found by the default NTT and by CFT, by the angle between the walker's
    foot motion (over +-5 frames) and the line's normal, below or from 60 degrees (the C_d test's away_angle)."""
    seq = read_sequence(data / "pets09_s2l1_dev")
    frames = [cv2.imread(str(p)) for p in seq.frames]
    gt = seq.mot_gt
    numbers = list(range(1, len(frames) + 1))
    tracks, _ = mot_tracks(frames, numbers)
    out: dict = {}
    for li, text in enumerate(PETS_LINES):
        line = parse_polyline(text)
        ev, _ = ntt(frames, numbers, line, 7.0, 1, radius=estimate_radius(frames[:70], line))
        cft = track_crossings(tracks, line, hysteresis=5)
        d = line[1] - line[0]
        normal = np.array([-d[1], d[0]]) / np.hypot(*d)
        for c in track_crossings(gt, line, hysteresis=5):
            tr = gt[gt[:, 1] == c.track]
            near = tr[np.abs(tr[:, 0] - c.frame) <= 5]
            foot = np.c_[near[:, 2] + near[:, 4] / 2, near[:, 3] + near[:, 5]]
            v = (foot[-1] - foot[0]) / max(near[-1, 0] - near[0, 0], 1.0)
            angle = float(np.degrees(np.arccos(min(abs(v @ normal) / max(np.hypot(*v), 1e-9), 1.0))))
            key = f"{'vertical' if li < 2 else 'horizontal'} lines, angle {'< 60' if angle < 60 else '>= 60'}"
            cell = out.setdefault(key, [0, 0, 0])
            for k, events in enumerate((ev, cft)):  # an event of the crossing's direction within TOL frames
                cell[k] += any(e.direction == c.direction and abs(e.frame - c.frame) <= TOL for e in events)
            cell[2] += 1
    return {k: {"ntt": f, "cft": fc, "gt": g} for k, (f, fc, g) in sorted(out.items())}


FRESH_LINES = ["150,200;700,200", "200,350;700,350", "300,120;300,450", "460,120;460,450", "200,150;650,420"]


def pets_lines(data: Path, lines: list[str]) -> dict:
    """PETS at 7 fps on the given lines: NTT (default and without ``feet``) and CFT, per half and per line."""
    seq = read_sequence(data / "pets09_s2l1_dev")
    frames = [cv2.imread(str(p)) for p in seq.frames]
    numbers = list(range(1, len(frames) + 1))
    tracks, _ = mot_tracks(frames, numbers)
    acc: dict = {}
    for text in lines:
        line = parse_polyline(text)
        truth = track_crossings(seq.mot_gt, line, hysteresis=5)
        r = estimate_radius(frames[:70], line)
        found = {"cft (pftrack mot)": [(c.frame, c.direction) for c in track_crossings(tracks, line, hysteresis=5)]}
        for name, kw in (("ntt", {}), ("ntt feet=false", {"feet": False})):
            ev, _ = ntt(frames, numbers, line, 7.0, 1, radius=r, **kw)
            found[name] = [(e.frame, e.direction) for e in ev]
        for name, det in found.items():
            for half, (lo, hi) in (("frames 1-200", (1, 200)), ("frames 201-400", (201, 400))):
                add(acc, f"{name} | {half}", score(det, truth, lo, hi))
                add(acc, f"{name} | {half} | {text}", score(det, truth, lo, hi))
    return summarise(acc)


def speed(data: Path) -> dict:
    """NTT frames per second at 768x576 (decode excluded), one line and four lines."""
    seq = read_sequence(data / "pets09_s2l1_dev")
    frames = [cv2.imread(str(p)) for p in seq.frames[:200]]
    out = {}
    for text in PETS_LINES[:1]:
        _, f = ntt(frames, range(1, 201), parse_polyline(text), 7.0, 1, radius=12.0)
        out["one line, r = 12"] = f
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default="../shared/data")
    ap.add_argument("--seeds", default="100")
    ap.add_argument("--json", default="reports/ch10.json")
    ap.add_argument("--walkers", action="store_true", help="only the synthetic walkers (pftrack synth walkers)")
    ap.add_argument("--angles", action="store_true",
                    help="only PETS crossings found by the angle of the walker's motion to the line's normal")
    ap.add_argument("--grey", action="store_true", help="only PETS, its frames in grey (reports/ch10_grey.json)")
    ap.add_argument("--h264", type=int, metavar="CRF",
                    help="only PETS, its frames encoded as H.264 at this CRF and decoded (reports/ch10_h264_CRF.json)")
    ap.add_argument("--lines", nargs="*", metavar="LINE",
                    help="only PETS at 7 fps on these lines (none given: five lines used for no choice)")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    seeds = parse_seeds(args.seeds)
    out: dict = {}
    data = Path(args.data)
    if args.grey:
        out = pets(data, grey=True)
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).with_name("ch10_grey.json").write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
        return
    if args.h264 is not None:
        out = pets(data, crf=args.h264)
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).with_name(f"ch10_h264_{args.h264}.json").write_text(json.dumps(out, indent=1) + "\n",
                                                                           encoding="utf-8")
        return
    if args.lines is not None:
        for k, v in pets_lines(data, args.lines or FRESH_LINES).items():
            acc, prec = ("-" if x is None else f"{x:.2f}" for x in (v["accuracy"], v["precision"]))
            print(f"PETS {k}: accuracy {acc} precision {prec} (gt {v['gt']}, detected {v['det']})", flush=True)
        return
    if args.angles:
        for k, v in crossing_angles(data).items():
            print(f"PETS frames 1-400, {k}: NTT {v['ntt']}, CFT {v['cft']} of {v['gt']} found", flush=True)
        return
    if args.walkers:
        for name, sds, wire in (("tune seeds 0-9", range(10), None), ("report seeds 100-109", range(100, 110), None),
                                ("tune seeds 0-9, horizontal wires", range(10), "horizontal")):
            out[name] = walkers(list(sds), wire)
            for k, v in out[name].items():
                print(f"walkers {name} | {k}: accuracy {v['accuracy']:.2f} precision {v['precision']:.2f} "
                      f"(gt {v['gt']}, detected {v['det']})", flush=True)
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).with_name("ch10_walkers.json").write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
        return
    if (data / "pets09_s2l1_dev").is_dir():
        out["pets"] = pets(data)
        out["speed"] = speed(data)
        print("speed", json.dumps(out["speed"]), flush=True)
    out["synthetic"] = synthetic(seeds)
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
