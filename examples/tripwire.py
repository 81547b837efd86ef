"""Count directional crossings of a line without tracking (book ch. 10), and score them against the truth.

    python examples/tripwire.py [--seed S] [--wire horizontal|vertical|oblique]

The scene is ``pftrack synth walkers``'s: seeded upright walkers on a textured ground, with every walker's exact
box, and a wire drawn across their paths.  The trackerless tripwire watches patches along the wire, frame by
frame; the true crossings come from the walkers' foot points.  Events are matched one to one within 10 frames
with the right direction: accuracy (TP / GT, the chapter's Eq. 8), precision and F1.
"""

from __future__ import annotations

import argparse

from pftrack.events.eval import match_events, track_crossings
from pftrack.events.tripwire import TrackerlessTripwire, TripwireParams, estimate_radius
from pftrack.synth.walkers import walkers_scene


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--wire", choices=("horizontal", "vertical", "oblique"), default="horizontal")
    args = ap.parse_args(argv)

    scene = walkers_scene(args.seed, wire=args.wire)
    truth = [(c.frame, c.direction) for c in track_crossings(scene.tracks, scene.wire, hysteresis=3)]
    # the patch radius from the size of what moves over the wire in the first 10 s (--radius auto)
    radius = estimate_radius(scene.frames[:int(10 * scene.fps)], scene.wire)
    wire = TrackerlessTripwire(scene.wire, scene.frames[0].shape[:2], scene.fps, TripwireParams(radius=radius))
    events = []

    def report(found):
        for ev in found:
            side = "positive" if ev.direction > 0 else "negative"
            print(f"frame {ev.frame:4d}  {side}  at ({ev.x:.0f}, {ev.y:.0f})")
            events.append(ev)

    for number, frame in enumerate(scene.frames, start=1):
        report(wire.process(frame, number))  # events as they are found
    report(wire.finish())  # crossings still waiting for their confirmation at the end
    s = match_events([(e.frame, e.direction) for e in events], truth, tol=10)
    print(f"{s.gt} true crossings, {s.detected} events, {s.tp} matched: accuracy {s.accuracy:.2f}, "
          f"precision {s.precision:.2f}, F1 {s.f1:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
