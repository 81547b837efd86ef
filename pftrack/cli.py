"""The ``pftrack`` command line.  It only wires sources, trackers and sinks together.

Exit codes: 0 success, 2 bad usage or bad input (one line on stderr, never a
traceback), 130 interrupted by Ctrl-C or SIGTERM (everything computed so far is
written and the video finalised).
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from pathlib import Path
from typing import Sequence

from . import __version__
from .errors import Interrupted, PftrackError

DEFAULT_TRACKER = "fusion-pf"


class _ArgumentParser(argparse.ArgumentParser):
    def error(self, message: str):  # one line, exit 2
        self.exit(2, f"pftrack: error: {message}\n")


def _progress(total: int | None, desc: str, quiet: bool):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="frame", file=sys.stderr, disable=quiet or None,
                dynamic_ncols=True, leave=False)


# ---------------------------------------------------------------------------------------------- track

def _add_track(sub) -> None:
    p = sub.add_parser("track", help="track one object through a video, frame folder or sequence",
                       description="Track one object. Writes CSV rows frame,x,y,w,h,score,lost, flushed per frame.")
    p.add_argument("source", help="video file, frame folder, OTB/VOT/MOTChallenge folder or camera index")
    p.add_argument("--box", help="initial box X,Y,W,H (default: the sequence's first ground-truth box)")
    p.add_argument("--tracker", default=DEFAULT_TRACKER, help=f"tracker name (default {DEFAULT_TRACKER}; see 'pftrack list')")
    p.add_argument("--out", default="track.csv", help="CSV output (default track.csv)")
    p.add_argument("--json-out", help="also write JSON Lines (one object per frame, with particles summary)")
    p.add_argument("--video-out", help="annotated video output (ellipse, particles, trajectory)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE", help="tracker parameter (repeatable)")
    p.add_argument("--skip-bad-frames", action="store_true", help="skip unreadable frames instead of stopping")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_track)


def _close_all(bar, sinks, source) -> None:
    """Finish the progress bar, then every sink (flushing and finalising videos), then the source."""
    if bar is not None:
        bar.close()
    for sink in sinks:
        sink.close()
    source.close()


def run_track(source_spec, *, box, tracker_name, out, video_out=None, json_out=None, seed=0, params=None,
              skip_bad_frames=False, quiet=False, gt_overlay=False) -> dict:
    """The work behind ``pftrack track`` (also used by ``pftrack demo``)."""
    from .geometry import parse_box
    from .io.sinks import CsvTrackSink, JsonLinesSink, VideoSink, prepare_output
    from .io.sources import open_source
    from .pipeline import TrackRun, interrupt_on_sigterm, track_source
    from .trackers.registry import create_tracker
    from .viz.draw import TrackDrawer

    tracker = create_tracker(tracker_name, seed=seed, params=params or {})
    init_box = parse_box(box) if isinstance(box, str) else box
    # check every output before any work starts
    prepare_output(out)
    if video_out:
        prepare_output(video_out)
    if json_out:
        prepare_output(json_out)
    source = open_source(source_spec, skip_bad_frames=skip_bad_frames)
    run = TrackRun()
    sinks: list = []
    drawer = TrackDrawer()
    bar = None
    lost = 0
    try:
        csv = CsvTrackSink(out)
        sinks.append(csv)
        jsonl = JsonLinesSink(json_out) if json_out else None
        if jsonl:
            sinks.append(jsonl)
        video = VideoSink(video_out, fps=source.fps) if video_out else None
        if video:
            sinks.append(video)
        bar = _progress(source.length, f"{tracker_name}", quiet)
        gt = source.groundtruth if gt_overlay else None
        with interrupt_on_sigterm() as stop:
            for number, frame, state in track_source(source, tracker, init_box, run=run):
                csv.write_state(number, state)
                lost += int(state.lost)
                if jsonl:
                    rec = {"frame": number, "box": list(state.box), "score": state.score, "lost": state.lost}
                    if state.particles is not None and state.weights is not None:
                        rec["n_particles"] = int(len(state.particles))
                    jsonl.write(rec)
                if video:
                    g = gt[number - 1] if gt is not None and number - 1 < len(gt) else None
                    video.write(drawer.draw(frame, state, number, gt_box=g))
                bar.update(1)
                stop.check()
    except KeyboardInterrupt:
        raise Interrupted(f"interrupted after {run.frames} frames; rows so far are in {out}") from None
    finally:
        _close_all(bar, sinks, source)
    return {"frames": run.frames, "update_fps": run.update_fps, "end_to_end_fps": run.end_to_end_fps,
            "lost_frames": lost, "skipped": list(source.skipped), "source": source}


def cmd_track(args) -> int:
    from .params import parse_param_assignments

    res = run_track(args.source, box=args.box, tracker_name=args.tracker, out=args.out, video_out=args.video_out,
                    json_out=args.json_out, seed=args.seed, params=parse_param_assignments(args.param),
                    skip_bad_frames=args.skip_bad_frames, quiet=args.quiet)
    msg = (f"{res['frames']} frames tracked with {args.tracker}: {res['update_fps']:.0f} update fps, "
           f"{res['end_to_end_fps']:.0f} fps end to end, lost in {res['lost_frames']} frames -> {args.out}")
    if res["skipped"]:
        msg += f" ({len(res['skipped'])} unreadable frames skipped)"
    print(msg, file=sys.stderr)
    return 0


# ---------------------------------------------------------------------------------------------- mot

def _add_mot(sub) -> None:
    p = sub.add_parser("mot", help="track all the people/objects in a video, frame folder or MOTChallenge folder",
                       description="Multi-object tracking (detection + per-target colour particle filters). Writes "
                                   "MOTChallenge text rows frame,id,x,y,w,h,score,-1,-1,-1, flushed per frame.")
    p.add_argument("source", help="video file, frame folder, MOTChallenge folder or camera index")
    p.add_argument("--detector", choices=["motion", "mog2", "hog"], default="mog2", help="detector (default mog2)")
    p.add_argument("--out", default="tracks.txt", help="MOTChallenge text output (default tracks.txt)")
    p.add_argument("--video-out", help="annotated video output")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE", help="multi-pf parameter (repeatable)")
    p.add_argument("--skip-bad-frames", action="store_true", help="skip unreadable frames instead of stopping")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_mot)


def run_mot(source_spec, *, out, detector="mog2", video_out=None, seed=0, params=None, skip_bad_frames=False,
            quiet=False) -> dict:
    """The work behind ``pftrack mot``."""
    import time as _time

    from .io.sinks import MotSink, VideoSink, prepare_output
    from .io.sources import open_source
    from .multi import create_multi_tracker
    from .pipeline import interrupt_on_sigterm
    from .viz.draw import color_for, draw_box

    tracker = create_multi_tracker("multi-pf", seed=seed, **{"detector": detector, **(params or {})})
    prepare_output(out)
    if video_out:
        prepare_output(video_out)
    source = open_source(source_spec, skip_bad_frames=skip_bad_frames)
    frames = rows = 0
    ids: set[int] = set()
    upd = 0.0
    t_start = _time.perf_counter()
    sinks: list = []
    bar = None
    try:
        sink = MotSink(out)
        sinks.append(sink)
        video = VideoSink(video_out, fps=source.fps) if video_out else None
        if video:
            sinks.append(video)
        bar = _progress(source.length, "mot", quiet)
        with interrupt_on_sigterm() as stop:
            for number, frame in source.numbered():
                t0 = _time.perf_counter()
                outs = tracker.update(frame)
                upd += _time.perf_counter() - t0
                frames += 1
                for o in outs:
                    sink.write(number, o.track_id, o.box, o.score)
                    ids.add(o.track_id)
                    rows += 1
                if video:
                    img = frame.copy()
                    for o in outs:
                        draw_box(img, o.box, color_for(o.track_id), 2, f"{o.track_id}{'*' if o.occluded else ''}")
                    video.write(img)
                bar.update(1)
                stop.check()
    except KeyboardInterrupt:
        raise Interrupted(f"interrupted after {frames} frames; rows so far are in {out}") from None
    finally:
        _close_all(bar, sinks, source)
    total = _time.perf_counter() - t_start
    return {"frames": frames, "rows": rows, "identities": len(ids), "update_fps": frames / upd if upd > 0 else 0.0,
            "end_to_end_fps": frames / total if total > 0 else 0.0, "source": source}


def cmd_mot(args) -> int:
    from .params import parse_param_assignments

    res = run_mot(args.source, out=args.out, detector=args.detector, video_out=args.video_out, seed=args.seed,
                  params=parse_param_assignments(args.param), skip_bad_frames=args.skip_bad_frames, quiet=args.quiet)
    print(f"{res['frames']} frames, {res['identities']} identities, {res['rows']} boxes: {res['update_fps']:.0f} fps "
          f"(detection + tracking), {res['end_to_end_fps']:.0f} fps end to end -> {args.out}", file=sys.stderr)
    return 0


# ---------------------------------------------------------------------------------------------- list

def _add_list(sub) -> None:
    p = sub.add_parser("list", help="registered trackers and their parameters")
    p.add_argument("name", nargs="?", help="show the parameters of one tracker")
    p.set_defaults(func=cmd_list)


def cmd_list(args) -> int:
    import textwrap

    from .trackers.registry import get_spec, list_trackers

    specs = [get_spec(args.name)] if args.name else list_trackers()
    for spec in specs:
        avail = "" if spec.available() else "  (not available here)"
        print(f"{spec.name:20s} {spec.summary}{avail}")
        if args.name:
            for name, typ, default, doc in spec.params_cls.describe():
                print(f"  {name} ({typ}, default {default!r})")
                for line in textwrap.wrap(doc, 88):
                    print(f"      {line}")
    if not args.name:
        print("\n'pftrack list NAME' shows a tracker's parameters; set them with --param KEY=VALUE.")
    return 0


# ---------------------------------------------------------------------------------------------- demo

def _add_demo(sub) -> None:
    p = sub.add_parser("demo", help="run the default tracker on the bundled real clip")
    p.add_argument("--out", default="demo_out", help="output folder (default demo_out)")
    p.add_argument("--tracker", default=DEFAULT_TRACKER, help=f"tracker name (default {DEFAULT_TRACKER})")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_demo)


def demo_clip() -> tuple[Path, Path]:
    """Paths of the bundled clip and its ground truth."""
    from importlib import resources

    base = resources.files("pftrack") / "data" / "crossing"
    return Path(str(base / "crossing.mp4")), Path(str(base / "groundtruth_rect.txt"))


def cmd_demo(args) -> int:
    import numpy as np

    from .eval.metrics import ope_scores
    from .io.datasets import read_number_rows
    from .io.sinks import read_track_csv

    clip, gt_path = demo_clip()
    gt = np.array(read_number_rows(gt_path, widths=(4,)), dtype=np.float64)
    out = Path(args.out)
    csv_path, video_path = out / "track.csv", out / "track.mp4"
    res = run_track(str(clip), box=tuple(gt[0]), tracker_name=args.tracker, out=csv_path, video_out=video_path,
                    seed=args.seed, quiet=args.quiet)
    rows = read_track_csv(csv_path)
    scores = ope_scores(rows[:, 1:5], gt)
    print(f"pftrack demo: {res['frames']} frames of the bundled clip 'Crossing' (OTB) with {args.tracker}")
    print(f"  update speed     {res['update_fps']:.0f} fps ({res['end_to_end_fps']:.0f} fps end to end, decode included)")
    print(f"  OTB success AUC  {scores.auc:.3f}   precision@20px {scores.precision:.3f}")
    print(f"  results          {csv_path}  (frame,x,y,w,h,score,lost)")
    print(f"  annotated video  {video_path}")
    return 0


# ---------------------------------------------------------------------------------------------- eval

def _reproduce_command(drop: tuple[str, ...] = ()) -> str | None:
    """The command line that produced a report, without output-destination options (``drop``)."""
    import shlex

    if not sys.argv or Path(sys.argv[0]).name != "pftrack":
        return None
    args, skip = [], False
    for a in sys.argv[1:]:
        if skip:
            skip = False
            continue
        if a in drop:
            skip = True
            continue
        if any(a.startswith(d + "=") for d in drop):
            continue
        args.append(a)
    return "pftrack " + shlex.join(args)


def _add_eval(sub) -> None:
    p = sub.add_parser("eval", help="rank trackers on OTB/VOT sequences (one-pass or reset protocol)",
                       description="Run trackers x sequences x seeds and report accuracy and speed.")
    p.add_argument("data", nargs="+", help="sequence folders or folders of sequences (OTB, VOT, MOTChallenge)")
    p.add_argument("--trackers", required=True,
                   help="comma-separated tracker specs: NAME or NAME[key=value;...]; 'all', 'ours', 'baselines', "
                        "'opencv' expand to registered families; with --protocol mot: multi-pf[...]")
    p.add_argument("--protocol", choices=["ope", "vot", "mot"], default="ope",
                   help="OTB one-pass (default), VOT reset, or MOTChallenge multi-object (trackers: multi-pf[...])")
    p.add_argument("--seeds", type=int, default=1, help="seeds per stochastic tracker (default 1)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="local worker processes")
    g.add_argument("--scheduler", help="Dask distributed scheduler address (e.g. tcp://host:8786)")
    p.add_argument("--threads", type=int, default=1, help="OpenCV threads per run (default 1: per-core speed)")
    p.add_argument("--report", help="report folder: results.csv, summary.md, plots, index.html; runs are cached "
                                    "there so an interrupted evaluation resumes")
    p.add_argument("--doc", help="also write the Markdown summary (with the command) to this file")
    p.add_argument("--title", default="pftrack evaluation", help="title of the report")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_eval)


def cmd_eval(args) -> int:
    from .errors import ParameterError, SourceError
    from .eval.report import summary_markdown, write_report
    from .eval.runner import Runner, build_jobs, parse_tracker_list
    from .io.datasets import discover_sequences
    from .io.sinks import prepare_output

    if args.seeds < 1:
        raise ParameterError("--seeds must be >= 1")
    if args.workers is not None and args.workers < 1:
        raise ParameterError("--workers must be >= 1")
    trackers = parse_tracker_list(args.trackers, protocol=args.protocol)
    seqs = []
    mot = args.protocol == "mot"
    for d in args.data:
        for seq in discover_sequences(d):
            if (seq.mot_gt is None) if mot else (seq.groundtruth is None):
                kind = "MOTChallenge" if mot else "single-object"
                warnings.warn(f"{seq.name}: no {kind} ground truth, skipped for --protocol {args.protocol}")
                continue
            seqs.append(seq)
    if not seqs:
        raise SourceError(f"no sequences with {'MOTChallenge' if mot else 'single-object'} ground truth to evaluate")
    names = [s.name for s in seqs]
    if len(set(names)) != len(names):
        raise SourceError("two sequences share a name; evaluate them separately")
    if args.doc:
        prepare_output(args.doc)
    report_dir = Path(args.report) if args.report else None
    if report_dir is not None:
        prepare_output(report_dir / "results.csv")
    jobs = build_jobs(seqs, trackers, seeds=args.seeds, protocol=args.protocol, threads=args.threads)
    runner = Runner(report_dir=report_dir, workers=args.workers or 1, scheduler=args.scheduler,
                    progress=not args.quiet)
    try:
        records = runner.run(jobs)
    except KeyboardInterrupt:
        where = f"; finished runs are kept in {report_dir / 'runs'} and reused next time" if report_dir else ""
        raise Interrupted(f"evaluation interrupted after {runner.ran} new runs{where}") from None
    command = _reproduce_command(drop=("--doc",))
    md = summary_markdown(records, command=command, title=args.title)
    print(md)
    if report_dir is not None:
        write_report(records, report_dir, sequences={s.name: str(s.path) for s in seqs}, command=command,
                     title=args.title)
        print(f"report: {report_dir / 'index.html'} ({runner.ran} runs computed, {runner.reused} reused)",
              file=sys.stderr)
    if args.doc:
        Path(args.doc).write_text(md, encoding="utf-8")
    return 0


# ---------------------------------------------------------------------------------------------- bench

DEFAULT_PEERS = "opencv-csrt,opencv-kcf,opencv-mil,opencv-medianflow"


def _int_list(text: str) -> list[int]:
    from .errors import ParameterError

    try:
        vals = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ParameterError(f"expected comma-separated integers, got {text!r}") from None
    if not vals or min(vals) < 1:
        raise ParameterError(f"expected positive integers, got {text!r}")
    return vals


def _size_list(text: str) -> list[tuple[int, int]]:
    from .errors import ParameterError

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


def _add_bench(sub) -> None:
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

    from .bench import report_markdown, run_sequences, run_synthetic, scaling_plot
    from .errors import ParameterError
    from .eval.runner import parse_tracker_list
    from .io.datasets import discover_sequences
    from .io.sinks import prepare_output
    from .trackers.registry import list_trackers

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
    command = _reproduce_command(drop=("--out",))
    peer = "opencv-csrt" if "opencv-csrt" in names else names[-1]
    md = report_markdown(synth, real, reference_peer=peer, command=command, machine=machine)
    print(md)
    if out is not None:
        (out / "bench.md").write_text(md, encoding="utf-8")
        scaling_plot(synth, out / "scaling.png")
        say(f"wrote {out / 'bench.md'} and {out / 'scaling.png'}")
    return 0


# ---------------------------------------------------------------------------------------------- synth

def _add_synth(sub) -> None:
    from .synth import SCENES

    p = sub.add_parser("synth", help="write seeded synthetic scenes with exact ground truth as OTB folders",
                       description="Write synthetic scenes (exact ground truth) as OTB sequence folders, e.g. to "
                                   "evaluate trackers on them with 'pftrack eval'.")
    p.add_argument("kind", choices=sorted(SCENES), help="scene generator")
    p.add_argument("--seeds", default="0-9", help="seeds, e.g. 0-9 or 1,4,7 (default 0-9)")
    p.add_argument("--out", required=True, help="output folder (one sub-folder per seed)")
    p.set_defaults(func=cmd_synth)


def cmd_synth(args) -> int:
    from .errors import ParameterError
    from .io.sinks import prepare_output
    from .synth import SCENES, export_otb

    seeds: list[int] = []
    try:
        for part in args.seeds.split(","):
            if "-" in part:
                a, b = (int(v) for v in part.split("-", 1))
                seeds.extend(range(a, b + 1))
            elif part.strip():
                seeds.append(int(part))
    except ValueError:
        raise ParameterError(f"--seeds must look like 0-9 or 1,4,7, got {args.seeds!r}") from None
    if not seeds:
        raise ParameterError("no seeds given")
    out = Path(args.out)
    prepare_output(out / "README.txt")
    for sd in seeds:
        export_otb(SCENES[args.kind](sd), out / f"{args.kind}-{sd:03d}")
    (out / "README.txt").write_text(f"Synthetic '{args.kind}' scenes, seeds {args.seeds}, written by pftrack synth.\n",
                                    encoding="utf-8")
    print(f"wrote {len(seeds)} '{args.kind}' sequences to {out}", file=sys.stderr)
    return 0


# ---------------------------------------------------------------------------------------------- main

def build_parser() -> argparse.ArgumentParser:
    parser = _ArgumentParser(prog="pftrack", description="Fast probabilistic visual object tracking.")
    parser.add_argument("--version", action="version", version=f"pftrack {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_ArgumentParser)
    sub.required = True
    _add_track(sub)
    _add_mot(sub)
    _add_list(sub)
    _add_demo(sub)
    _add_eval(sub)
    _add_bench(sub)
    _add_synth(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    # FFmpeg prints decoder chatter ("moov atom not found") for bad files; our one-line error says it all.
    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
    parser = build_parser()
    args = parser.parse_args(argv)
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


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
