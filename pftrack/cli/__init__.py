"""The ``pftrack`` command line.  It only wires sources, trackers and sinks together.

One module per command group: :mod:`.track` (track, demo), :mod:`.mot`,
:mod:`.evaluate` (eval, list), :mod:`.bench` (bench), :mod:`.synth`, :mod:`.densitometry` (book ch. 14),
:mod:`.points` (points, stereo: book ch. 7), :mod:`.events` (tripwire: book ch. 10),
:mod:`.multicam` (handover: book ch. 11),
:mod:`.calibration` (calibrate-sim: book ch. 12), :mod:`.surface` (surface: book ch. 13),
:mod:`.segment` (segment: book ch. 9),
:mod:`.compressed` (activity: book ch. 8).

Exit codes: 0 success, 2 bad usage or bad input (one line on stderr, never a
traceback), 130 interrupted by Ctrl-C or SIGTERM (everything computed so far is
written and the video finalised), 1 when ``pftrack eval`` finished but some of its
runs failed (a tracker raised; the report names them).
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from collections.abc import Sequence

from .. import __version__
from ..errors import Interrupted, PftrackError
from .bench import add_bench
from .calibration import add_calibrate_sim
from .common import DEFAULT_TRACKER, ArgumentParser
from .compressed import add_activity
from .densitometry import add_densitometry
from .evaluate import add_eval, add_list
from .events import add_tripwire
from .mot import add_mot, run_mot
from .multicam import add_handover
from .points import add_points, add_stereo
from .segment import add_segment
from .surface import add_surface
from .synth import add_synth
from .track import add_demo, add_track, demo_clip, run_track

__all__ = ["DEFAULT_TRACKER", "build_parser", "demo_clip", "main", "run_mot", "run_track"]


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(prog="pftrack", description="Fast probabilistic visual object tracking.")
    parser.add_argument("--version", action="version", version=f"pftrack {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=ArgumentParser)
    sub.required = True
    add_track(sub)
    add_mot(sub)
    add_list(sub)
    add_demo(sub)
    add_eval(sub)
    add_bench(sub)
    add_synth(sub)
    add_densitometry(sub)
    add_points(sub)
    add_stereo(sub)
    add_tripwire(sub)
    add_handover(sub)
    add_calibrate_sim(sub)
    add_surface(sub)
    add_segment(sub)
    add_activity(sub)
    return parser


#: Options whose value is a list of coordinates, which may start with a minus sign (a line or box that begins left
#: of or above the frame).
COORDINATE_OPTIONS = ("--box", "--line", "--points", "--roi", "--strip")


def attach_negative_values(argv: Sequence[str]) -> list[str]:
    """``--line -50,120;400,120`` as ``--line=-50,120;400,120``: argparse takes a value that starts with a minus
    sign and holds a comma for an option of its own, so a coordinate option's value is attached to it first."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        a = argv[i]
        nxt = argv[i + 1] if i + 1 < len(argv) else ""
        if a in COORDINATE_OPTIONS and len(nxt) > 1 and nxt[0] == "-" and (nxt[1].isdigit() or nxt[1] == "."):
            out.append(f"{a}={nxt}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


def main(argv: Sequence[str] | None = None) -> int:
    # FFmpeg prints decoder chatter ("moov atom not found") for bad files; our one-line error says it all.
    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
    parser = build_parser()
    args = parser.parse_args(attach_negative_values(sys.argv[1:] if argv is None else list(argv)))
    warnings.simplefilter("default")
    warnings.formatwarning = lambda msg, cat, *a, **k: f"pftrack: warning: {msg}\n"
    try:
        return int(args.func(args) or 0)
    except Interrupted as exc:
        print(f"pftrack: {exc}", file=sys.stderr)
        return 130
    except PftrackError as exc:
        print(f"pftrack: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("pftrack: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 1
