"""``pftrack eval`` and ``pftrack list``: accuracy of trackers on sequences, and the registry."""

from __future__ import annotations

import os
import sys
import warnings
from pathlib import Path

from ..errors import Interrupted
from .common import counted, reproduce_command


def add_eval(sub) -> None:
    p = sub.add_parser("eval", help="rank trackers on OTB/VOT sequences (one-pass or reset protocol)",
                       description="Run trackers x sequences x seeds and report accuracy and speed.")
    p.add_argument("data", nargs="+", help="sequence folders or folders of sequences (OTB, VOT, MOTChallenge, "
                   "a video with its ground truth)")
    p.add_argument("--trackers", required=True,
                   help="comma-separated tracker specs: NAME or NAME[key=value;...]; 'all', 'ours', 'baselines', "
                        "'opencv' expand to registered families; with --protocol mot: multi-pf[...]")
    p.add_argument("--protocol", choices=["ope", "sre", "tre", "vot", "mot"], default="ope",
                   help="OTB one-pass (default); OTB spatial robustness (sre: every tracker from 12 perturbed first "
                        "boxes, --seeds ignored); OTB temporal robustness (tre: every tracker from 20 start frames "
                        "spread over the sequence, --seeds ignored); VOT reset; or MOTChallenge multi-object "
                        "(trackers: multi-pf[...])")
    p.add_argument("--people", type=int, nargs="?", const=30, metavar="MIN_FRAMES", help=(
        "single-object protocols: cut each MOTChallenge folder into one sequence per person with at least MIN_FRAMES "
        "annotated frames (default 30), from the person's first box to the folder's end; the frames after they "
        "leave are absent, and those on which a person whose annotation stopped is still in view are not scored"))
    p.add_argument("--seeds", type=int, default=1, help="seeds per stochastic tracker (default 1)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="local worker processes")
    g.add_argument("--scheduler", help="Dask distributed scheduler address (e.g. tcp://host:8786)")
    p.add_argument("--threads", type=int, default=1, help="OpenCV threads per run (default 1: per-core speed)")
    p.add_argument("--timeout", type=float, metavar="SECONDS",
                   help="time limit of one run: every run then has a process of its own, and a run that takes "
                        "longer (a tracker hanging in native code) or whose process crashes is recorded as failed "
                        "while the evaluation goes on (not with --scheduler)")
    p.add_argument("--report", help="report folder: results.csv, summary.md, plots, index.html; runs are cached "
                                    "there so an interrupted evaluation resumes")
    p.add_argument("--fresh", action="store_true",
                   help="compute every run again instead of reusing the runs cached in --report (which may have been "
                        "made by other code: the command says how many)")
    p.add_argument("--doc", help="also write the Markdown summary (with the command) to this file")
    p.add_argument("--title", default="pftrack evaluation", help="title of the report")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_eval)


def cmd_eval(args) -> int:
    from ..errors import ParameterError, SourceError
    from ..eval.report import summary_markdown, write_report
    from ..eval.runner import Runner, build_jobs, failed, parse_tracker_list
    from ..io.datasets import discover_sequences
    from ..io.sinks import prepare_output

    if args.seeds < 1:
        raise ParameterError("--seeds must be >= 1")
    if args.workers is not None and args.workers < 1:
        raise ParameterError("--workers must be >= 1")
    if args.timeout is not None and not args.timeout > 0:
        raise ParameterError("--timeout must be a positive number of seconds")
    if args.timeout is not None and args.scheduler:
        raise ParameterError("--timeout does not apply to a Dask scheduler's runs (use Dask's own limits)")
    if args.people is not None and args.protocol == "mot":
        raise ParameterError("--people cuts MOTChallenge folders for the single-object protocols, not --protocol mot")
    if args.people is not None and args.people < 1:
        raise ParameterError("--people: MIN_FRAMES must be >= 1")
    trackers = parse_tracker_list(args.trackers, protocol=args.protocol)
    seqs = []
    mot = args.protocol == "mot"
    for d in args.data:
        for seq in discover_sequences(d):
            if args.people is not None and seq.mot_gt is not None and seq.groundtruth is None:
                from ..io.person_sequences import people_of

                people = people_of(seq, min_frames=args.people)
                if not people:
                    warnings.warn(f"{seq.name}: no person with {args.people} or more annotated frames")
                seqs.extend(people)
                continue
            if (seq.mot_gt is None) if mot else (seq.groundtruth is None):
                kind = "MOTChallenge" if mot else "single-object"
                hint = ("; a MOTChallenge folder is scored with --protocol mot (multi-target trackers), or one "
                        "sequence per person with --people") if seq.mot_gt is not None else ""
                warnings.warn(f"{seq.name}: no {kind} ground truth, skipped for --protocol {args.protocol}{hint}")
                continue
            seqs.append(seq)
    if not seqs:
        raise SourceError(f"no sequences with {'MOTChallenge' if mot else 'single-object'} ground truth to evaluate")
    seen: dict[str, Path] = {}
    for s in seqs:
        if s.name in seen:
            raise SourceError(f"two sequences share the name {s.name!r} ({seen[s.name]} and {s.path}): results are "
                              "kept by name; rename one folder or evaluate them separately")
        seen[s.name] = s.path
    if args.doc:
        prepare_output(args.doc)
    report_dir = Path(args.report) if args.report else None
    if report_dir is not None:
        prepare_output(report_dir / "results.csv")
    jobs = build_jobs(seqs, trackers, seeds=args.seeds, protocol=args.protocol, threads=args.threads)
    runner = Runner(report_dir=report_dir, workers=args.workers or 1, scheduler=args.scheduler,
                    progress=not args.quiet, timeout=args.timeout, fresh=args.fresh)
    try:
        records = runner.run(jobs)
    except KeyboardInterrupt:
        where = f"; finished runs are kept in {report_dir / 'runs'} and reused next time" if report_dir else ""
        raise Interrupted(f"evaluation interrupted after {runner.ran} new runs{where}") from None
    command = reproduce_command(drop=("--doc",))
    md = summary_markdown(records, command=command, title=args.title)
    print(md)
    if report_dir is not None:
        write_report(records, report_dir, sequences={s.name: s for s in seqs}, command=command,
                     title=args.title)
        print(f"report: {report_dir / 'index.html'} ({counted(runner.ran, 'run')} computed, "
              f"{runner.reused} reused)", file=sys.stderr)
        if runner.reused_other_code:
            print(f"pftrack: warning: {runner.reused_other_code} of the {runner.reused} reused runs were made by other "
                  f"pftrack code than this; --fresh computes them again", file=sys.stderr)
    if args.doc:
        Path(args.doc).write_text(md, encoding="utf-8")
    bad = [r for r in records if failed(r)]
    if bad:
        r = bad[0]
        where = f"; tracebacks in {report_dir / 'failed'}" if report_dir else ""
        frame = f", frame {r['error_frame']}" if r.get("error_frame") is not None else ""
        print(f"pftrack: error: {len(bad)} of {len(records)} runs failed, first {r['tracker']} on {r['sequence']} "
              f"(seed {r['seed']}{frame}): {r['error']}{where}", file=sys.stderr)
        return 1
    return 0


def add_list(sub) -> None:
    p = sub.add_parser("list", help="registered trackers and their parameters")
    p.add_argument("name", nargs="?", help="show the parameters of one tracker")
    p.set_defaults(func=cmd_list)


def cmd_list(args) -> int:
    import textwrap

    from ..trackers.monitor import WrapperOptions
    from ..trackers.registry import get_spec, list_trackers

    specs = [get_spec(args.name)] if args.name else list_trackers()
    for spec in specs:
        avail = "" if spec.available() else "  (not available here)"
        plugin = f"  (plugin: {spec.cls.__module__})" if spec.family == "plugin" else ""
        print(f"{spec.name:20s} {spec.summary}{avail}{plugin}")
        if args.name:
            for name, typ, default, doc in [*spec.params_cls.describe(), *WrapperOptions.describe()]:
                if name == "grey_restart":  # a tracker may have its own default (Tracker.grey_restart)
                    default = spec.cls.grey_restart
                print(f"  {name} ({typ}, default {default!r})")
                for line in textwrap.wrap(doc, 88):
                    print(f"      {line}")
    if not args.name:
        print("\n'pftrack list NAME' shows a tracker's parameters; set them with --param KEY=VALUE. Every tracker "
              "also takes monitor=true: a calibrated lost flag on its boxes (monitor_cues=fused: with fusion-pf's "
              "structural score; monitor_search=frame: while lost, a whole-frame search that starts the tracker "
              "again on the target), and grey_restart=N: grey features once N frames in a row are grey.")
    return 0
