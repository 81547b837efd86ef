"""``pftrack bench``: speed with OpenCV peers in the same run."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from .common import reproduce_command

DEFAULT_PEERS = "opencv-csrt,opencv-kcf,opencv-mil,opencv-medianflow"


def _int_list(text: str) -> list[int]:
    from ..errors import ParameterError

    try:
        vals = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ParameterError(f"expected comma-separated integers, got {text!r}") from None
    if not vals or min(vals) < 1:
        raise ParameterError(f"expected positive integers, got {text!r}")
    return vals


def _size_list(text: str) -> list[tuple[int, int]]:
    from ..errors import ParameterError

    out = []
    for item in text.split(","):
        try:
            w, h = (int(v) for v in item.lower().split("x"))
        except ValueError:
            raise ParameterError(f"frame sizes are WxH, got {item!r}") from None
        if w < 64 or h < 64:
            raise ParameterError(f"frame size {item} is too small (at least 64x64)")
        out.append((w, h))
    return out


def add_bench(sub) -> None:
    p = sub.add_parser("bench", help="update and end-to-end speed of trackers, with OpenCV peers in the same run",
                       description="Speed benchmark on synthetic clips (N, target size and frame size varied one "
                                   "at a time) and optionally on real sequences; OpenCV peers interleaved.")
    p.add_argument("--trackers", default=None, help=f"tracker names (default: ours and {DEFAULT_PEERS})")
    p.add_argument("--particles", default="50,100,200,400,800", help="particle counts to sweep")
    p.add_argument("--targets", default="25,50,100", help="target sides (px) to sweep")
    p.add_argument("--frames", default="320x240,640x480,1280x720", help="frame sizes to sweep")
    p.add_argument("--rounds", type=int, default=3, help="interleaved rounds per configuration (median reported)")
    p.add_argument("--n-frames", type=int, default=120, help="frames per synthetic clip")
    p.add_argument("--dev", nargs="*", default=[], help="real sequence folders (or folders of them) to time too")
    p.add_argument("--threads", type=int, default=1, help="OpenCV threads (default 1: one core)")
    p.add_argument("--out", default=None, help="folder for bench.md and scaling.png")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_bench)


def cmd_bench(args) -> int:
    import platform

    import cv2

    from ..bench import report_markdown, run_sequences, run_synthetic, scaling_plot
    from ..errors import ParameterError
    from ..eval.runner import parse_tracker_list
    from ..io.datasets import discover_sequences
    from ..io.sinks import prepare_output
    from ..trackers.registry import list_trackers

    if args.rounds < 1 or args.n_frames < 20 or args.threads < 1:
        raise ParameterError("--rounds >= 1, --n-frames >= 20 and --threads >= 1 are required")
    if args.trackers:
        names = [c.name for c in parse_tracker_list(args.trackers)]
    else:
        names = [s.name for s in list_trackers("pftrack") if s.available()] + DEFAULT_PEERS.split(",")
    particles, targets, frames = _int_list(args.particles), _int_list(args.targets), _size_list(args.frames)
    seqs = [seq for d in args.dev for seq in discover_sequences(d) if seq.groundtruth is not None]
    out = Path(args.out) if args.out else None
    if out is not None:
        prepare_output(out / "bench.md")
    cv2.setNumThreads(args.threads)
    say = (lambda m: None) if args.quiet else (lambda m: print(f"bench: {m}", file=sys.stderr))
    synth = run_synthetic(names, particles=particles, targets=targets, frames=frames, rounds=args.rounds,
                          n_frames=args.n_frames, progress=say)
    real = run_sequences(names, seqs, rounds=args.rounds, progress=say) if seqs else []
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            cpu = next((ln.split(":", 1)[1].strip() for ln in fh if ln.startswith("model name")), cpu)
    except OSError:
        pass
    machine = f"Machine: {cpu}, {os.cpu_count()} logical cores; OpenCV {cv2.__version__}, threads {args.threads}."
    command = reproduce_command(drop=("--out",))
    peer = "opencv-csrt" if "opencv-csrt" in names else names[-1]
    md = report_markdown(synth, real, reference_peer=peer, command=command, machine=machine)
    print(md)
    if out is not None:
        (out / "bench.md").write_text(md, encoding="utf-8")
        scaling_plot(synth, out / "scaling.png")
        say(f"wrote {out / 'bench.md'} and {out / 'scaling.png'}")
    return 0
