"""The trackerless tripwire's tune families, for choosing a parameter on the tune data only (docs/tripwire.md).

    python scripts/ch10_tune.py bgs_bootstrap 2,4,8                      # the six families
    python scripts/ch10_tune.py group_blob 0.2,0.5 --families pets,walkers
    python scripts/ch10_tune.py foot_hold 1,2 --with bgs_bootstrap=4   # every row with another setting too
    python scripts/ch10_tune.py v_max auto,300                          # auto: read from each scene's first 10 s
    python scripts/ch10_tune.py bgs_reach 6,8 --speed                   # frames/s on the PETS tune frames

For each value (and the current default beside them), F1 (events one-to-one, right direction, within +-10 frames)
of each family, and the mean over the families:

* ``pets``: PETS 2009 S2.L1 frames 1-200 only (the report frames are not processed), the four lines of
  scripts/ch10_experiments.py, ``--radius auto`` as there, strides 1, 2 and 3 (three families);
* ``walkers``: ``pftrack synth walkers`` seeds 0-9 (one family; ``--walker-seeds`` for others);
* ``traffic``: ``pftrack synth traffic-sparse`` and ``traffic-dense`` seeds 0-2 at stride 1, the book's timing
  (``timing=match``; ``bgs_history=100`` for dense), as scripts/ch10_experiments.py runs them (two families).

Two worker processes; a few minutes. It chooses nothing: the rule that reads its table is written beforehand
(``reports/*_rule.txt``).
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from ch10_experiments import PETS_LINES, add, ntt, score, summarise  # noqa: E402

from pftrack.cli.common import parse_seeds  # noqa: E402
from pftrack.events.blobs import estimate_speed  # noqa: E402
from pftrack.events.eval import track_crossings  # noqa: E402
from pftrack.events.geometry import parse_polyline  # noqa: E402
from pftrack.events.tripwire import TripwireParams, dark_levels, estimate_radius  # noqa: E402
from pftrack.io.datasets import read_sequence  # noqa: E402


def _radius(frames, line, kw: dict) -> float:
    """``--radius auto`` on the frames as the tripwire of the setting ``kw`` sees them (``dark_stretch``)."""
    gain, smooth = dark_levels(frames[0], TripwireParams(**kw))
    return estimate_radius(frames, line, gain=gain, smooth=smooth)


def _setting(frames, line, fps: float, key: str, value, fixed: dict) -> dict:
    """``{key: value}``, or for ``v_max`` = ``"auto"`` the speed limit read from ``frames`` (the first 10 s, ``fps``
    processed frames a second) as ``pftrack tripwire --v-max auto`` reads it."""
    if key != "v_max" or value != "auto":
        return {key: value}
    gain, smooth = dark_levels(frames[0], TripwireParams(**fixed))
    return {"v_max": estimate_speed(frames, line, fps, gain=gain, smooth=smooth)}


def _pets(args) -> dict:
    data, stride, key, values, fixed = args
    seq = read_sequence(Path(data) / "pets09_s2l1_dev")
    frames = [cv2.imread(str(p)) for p in seq.frames[:200]]
    numbers = list(range(1, 201, stride))
    sub = [frames[n - 1] for n in numbers]
    acc: dict = {}
    for text in PETS_LINES:
        line = parse_polyline(text)
        truth = track_crossings(seq.mot_gt, line, hysteresis=5)
        for v in values:
            calib = sub[:max(1, 70 // stride)]
            kv = _setting(calib, line, 7.0 / stride, key, v, fixed)
            r = _radius(calib, line, {**fixed, **kv})
            ev, _ = ntt(sub, numbers, line, 7.0, stride, radius=r, **fixed, **kv)
            add(acc, f"pets stride {stride} | {v}", score([(e.frame, e.direction) for e in ev], truth, 1, 200))
    return acc


def _walkers(args) -> dict:
    from pftrack.synth.walkers import walkers_scene

    seed, key, values, fixed = args
    sc = walkers_scene(seed)
    truth = track_crossings(sc.tracks, sc.wire, hysteresis=3)
    numbers = list(range(1, len(sc.frames) + 1))
    acc: dict = {}
    for v in values:
        kv = _setting(sc.frames[:int(10 * sc.fps)], sc.wire, sc.fps, key, v, fixed)
        r = _radius(sc.frames[:int(10 * sc.fps)], sc.wire, {**fixed, **kv})
        ev, _ = ntt(sc.frames, numbers, sc.wire, sc.fps, 1, radius=r, **fixed, **kv)
        add(acc, f"walkers | {v}", score([(e.frame, e.direction) for e in ev], truth, 0, 1e9))
    return acc


def _traffic(args) -> dict:
    from pftrack.synth.traffic import traffic_scene

    kind, seed, key, values, fixed = args
    sc = traffic_scene(seed, kind=kind)
    truth = track_crossings(sc.tracks, sc.wire, hysteresis=3, point="centre")
    numbers = list(range(1, len(sc.frames) + 1))
    acc: dict = {}
    for v in values:
        kw = {"timing": "match", **({"bgs_history": 100} if kind == "dense" else {}), **fixed,
              **_setting(sc.frames[:int(10 * sc.fps)], sc.wire, sc.fps, key, v, fixed)}
        ev, _ = ntt(sc.frames, numbers, sc.wire, sc.fps, 1, **kw)
        add(acc, f"traffic {kind} | {v}", score([(e.frame, e.direction) for e in ev], truth, 0, 1e9))
    return acc


SPEED_LINES = PETS_LINES + ["0,300;768,300", "100,500;700,80"]


def speed(data: str, key: str, values: list, fixed: dict, rounds: int = 2, runs: int = 2) -> None:
    """``--speed``: the trackerless tripwire's frames per second on the PETS tune frames 1-200 (stride 1, decode
    excluded, this process, OpenCV on one thread, ``--radius auto``) on the four lines and two more, per line the best
    of ``runs`` runs, ``rounds`` rounds alternating the settings; each setting's median over the lines of its rate
    over the default's."""
    import time

    from pftrack.events.tripwire import TrackerlessTripwire

    seq = read_sequence(Path(data) / "pets09_s2l1_dev")
    frames = [cv2.imread(str(p)) for p in seq.frames[:200]]
    best: dict = {}
    for _ in range(rounds):
        for text in SPEED_LINES:
            line = parse_polyline(text)
            for v in values:
                kv = {**fixed, **_setting(frames[:70], line, 7.0, key, v, fixed)}
                params = TripwireParams(**{**kv, "radius": _radius(frames[:70], line, kv)})
                for _ in range(runs):
                    tw = TrackerlessTripwire(line, frames[0].shape[:2], 7.0, params)
                    t0 = time.perf_counter()
                    for n, f in enumerate(frames, 1):
                        tw.process(f, n)
                    fps = len(frames) / (time.perf_counter() - t0)
                    best[(text, v)] = max(best.get((text, v), 0.0), fps)
    print(f"{key}: frames/s on the PETS tune frames (best of {runs} runs x {rounds} rounds), per line; the first "
          f"value is the default")
    for v in values:
        rates = [best[(t, v)] for t in SPEED_LINES]
        ratio = np.median([best[(t, v)] / best[(t, values[0])] for t in SPEED_LINES])
        print(f"{v}: median ratio {ratio:.3f} | " + " | ".join(f"{t} {r:.0f}" for t, r in zip(SPEED_LINES, rates)),
              flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("param", help="a TripwireParams field")
    ap.add_argument("values", help="comma-separated values to try beside the default")
    ap.add_argument("--families", default="pets,walkers,traffic")
    ap.add_argument("--data", default="../shared/data")
    ap.add_argument("--walker-seeds", default="0-9", metavar="A-B", help="the walkers family's seeds (default 0-9)")
    ap.add_argument("--with", dest="fixed", action="append", default=[], metavar="KEY=VALUE",
                    help="another setting for every row (repeatable)")
    ap.add_argument("--speed", action="store_true",
                    help="time the settings on the PETS tune frames instead (six lines, one thread)")
    args = ap.parse_args()
    fixed = dict(TripwireParams.from_mapping(dict(kv.split("=", 1) for kv in args.fixed)).as_dict().items())
    fixed = {k: v for k, v in fixed.items() if k in {kv.split("=", 1)[0] for kv in args.fixed}}
    field = TripwireParams.__dataclass_fields__.get(args.param)
    if field is None:
        raise SystemExit(f"unknown tripwire parameter {args.param!r}")
    default = getattr(TripwireParams(), args.param)
    kind = type(default)
    values = [default] + [v if (args.param, v) == ("v_max", "auto") else kind(v) if kind is not bool
                          else v.lower() in ("1", "true") for v in args.values.split(",")]
    if args.speed:
        speed(args.data, args.param, values, fixed)
        return
    fams = set(args.families.split(","))
    jobs = []
    with ProcessPoolExecutor(2) as ex:
        if "pets" in fams:
            jobs += [ex.submit(_pets, (args.data, s, args.param, values, fixed)) for s in (1, 2, 3)]
        if "walkers" in fams:
            jobs += [ex.submit(_walkers, (s, args.param, values, fixed)) for s in parse_seeds(args.walker_seeds)]
        if "traffic" in fams:
            jobs += [ex.submit(_traffic, (k, s, args.param, values, fixed)) for k in ("sparse", "dense")
                     for s in range(3)]
        total: dict = {}
        for j in jobs:
            for k, (g, d, t) in j.result().items():
                x = total.setdefault(k, [0, 0, 0])
                x[0] += g
                x[1] += d
                x[2] += t
    res = summarise(total)
    families = sorted({k.split(" | ")[0] for k in res})
    print(f"{args.param}: F1 (found of gt, events) per family; the first value is the default"
          + (f"; every row with {fixed}" if fixed else ""))
    for v in values:
        cells = [f"{f} {res[f'{f} | {v}']['f1']:.3f} ({res[f'{f} | {v}']['tp']} of {res[f'{f} | {v}']['gt']}, "
                 f"{res[f'{f} | {v}']['det']})" for f in families]
        mean = np.mean([res[f"{f} | {v}"]["f1"] for f in families])
        print(f"{v}: mean {mean:.4f} | " + " | ".join(cells), flush=True)


if __name__ == "__main__":
    cv2.setNumThreads(1)
    main()
