"""The lost flag of every registered tracker, measured as a detector on synthetic vanish scenes.

    python scripts/lost_flag_registry.py [--seeds 100-105] [--frames 90] [--trackers A,B,...] [--monitor]
                                         [--monitor-cues color,fused]

Each tracker (its defaults, tracker seed 0) follows the target of ``pftrack synth vanish`` scenes: it walks fully
behind a wide textured occluder among look-alike distractors and comes out again. Printed per tracker: *lost recall*,
the frames with the target hidden on which ``lost`` is raised, and *false-lost*, the frames with IoU >= 0.5 on which
it is raised (:func:`pftrack.eval.metrics.lost_detection`, as ``pftrack eval`` scores them, pooled over the scenes'
frames). With ``--monitor`` each tracker is run a second time with ``monitor=true``
(:mod:`pftrack.trackers.monitor`: the colour PFs' loss test on its boxes). Results: docs/evaluation.md.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import pftrack
from pftrack.eval.metrics import lost_detection
from pftrack.synth import Scene, hidden_frames, vanish_scene
from pftrack.trackers.registry import list_trackers


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="100-105")
    ap.add_argument("--frames", type=int, default=90)
    ap.add_argument("--trackers", default="", help="comma-separated names (default: every available tracker)")
    ap.add_argument("--monitor", action="store_true", help="also run each tracker with monitor=true")
    ap.add_argument("--monitor-cues", default="color", help=(
        "with --monitor: the monitor's cues to run, comma-separated (color, fused; default color)"))
    args = ap.parse_args()
    a, b = (int(v) for v in args.seeds.split("-"))
    scenes = []
    for seed in range(a, b + 1):
        spec = vanish_scene(seed, n_frames=args.frames)
        scenes.append(([(f, tr.boxes[0]) for f, tr in Scene(spec)], hidden_frames(spec)))
    names = [s for s in args.trackers.split(",") if s]
    print(f"| tracker | family | lost recall (hidden frames) | false-lost (IoU >= 0.5) | seconds |")
    print("|---|---|---|---|---|")
    for spec in list_trackers():
        if (names and spec.name not in names) or not spec.available():
            continue
        _row(spec, scenes, None)
        for cues in (args.monitor_cues.split(",") if args.monitor else ()):
            _row(spec, scenes, cues)


def _row(spec, scenes, monitor: str | None) -> None:
    """One tracker's flag pooled over the scenes; ``monitor``: None (its own flag) or the monitor's cues."""
    hid = absent = fl = covered = 0
    t0 = time.perf_counter()
    for pairs, hidden in scenes:
        wrap = {} if monitor is None else {"monitor": True, "monitor_cues": monitor}
        t = pftrack.create_tracker(spec.name, seed=0, **wrap)
        t.init(pairs[0][0], pairs[0][1])
        states = [t.update(frame) for frame, _ in pairs[1:]]  # the init frame is given, not detected
        h, w = pairs[0][0].shape[:2]
        ld = lost_detection([s.lost for s in states], np.array([s.box for s in states]),
                            np.array([gt for _, gt in pairs[1:]]), hidden[1:], bounds=(w, h))
        absent += ld.absent_frames
        covered += ld.covered_frames
        hid += round(ld.recall * ld.absent_frames) if ld.absent_frames else 0
        fl += round(ld.false_rate * ld.covered_frames) if ld.covered_frames else 0
    rec = f"{hid / absent:.2f} ({hid} of {absent})" if absent else "-"
    fls = f"{fl / covered:.3f} ({fl} of {covered})" if covered else "-"
    label = spec.name if monitor is None else f"{spec.name}[monitor=true" + (
        "]" if monitor == "color" else f";monitor_cues={monitor}]")
    print(f"| `{label}` | {spec.family} | {rec} | {fls} | {time.perf_counter() - t0:.1f} |", flush=True)


if __name__ == "__main__":
    main()
