"""``pftrack track`` and ``pftrack demo``: one object through a source, CSV/JSON/video sinks."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ..errors import Interrupted
from .common import (DEFAULT_TRACKER, add_reconnect, close_all, counted, progress, reconnected_note, seed_value,
                     target_id)


def add_track(sub) -> None:
    p = sub.add_parser("track", help="track one object through a video, frame folder or sequence",
                       description="Track one object. Writes CSV rows frame,x,y,w,h,score,lost, flushed per frame.")
    p.add_argument("source", help="video file, frame folder, OTB/VOT/MOTChallenge folder, a folder holding a video "
                   "and its ground truth, camera index or stream URL (rtsp://, http://, ...)")
    p.add_argument("--box", help="initial box X,Y,W,H (default: the sequence's first ground-truth box)")
    p.add_argument("--target", type=target_id, metavar="ID", help=(
        "the ground truth to start from (instead of --box): a track id of a MOTChallenge folder's gt/gt.txt, or "
        "the N of an OTB folder's groundtruth_rect.N.txt; tracking starts on that target's first annotated frame"))
    p.add_argument("--detect", choices=["hog", "mog2", "motion"], help=(
        "instead of --box: start on the first detection (hog: OpenCV's people detector; mog2 or motion: a moving "
        "object), the rows lost until one appears, e.g. on a camera or stream (trackers with a detector hand-off: "
        "color-pf, fusion-pf, local-motion-pf)"))
    p.add_argument("--tracker", default=DEFAULT_TRACKER,
                   help=f"tracker name (default {DEFAULT_TRACKER}; see 'pftrack list')")
    p.add_argument("--out", default="track.csv", help="CSV output (default track.csv)")
    p.add_argument("--json-out", help="also write JSON Lines (one object per frame, with particles summary)")
    p.add_argument("--video-out", help="annotated video output (ellipse, particles, trajectory)")
    p.add_argument("--show-map", action="store_true", help=(
        "with --video-out: put the tracker's confidence map beside each frame (trackers that learn a map, "
        "e.g. cotrain-pf)"))
    p.add_argument("--seed", type=seed_value, default=0, help="random seed (default 0)")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE", help="tracker parameter (repeatable)")
    p.add_argument("--skip-bad-frames", action="store_true", help="skip unreadable frames instead of stopping")
    add_reconnect(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_track)


def scalar_info(info: dict) -> dict:
    """The entries of a state's ``info`` that are plain scalars (the tracker's mode, the loss test's ratio, the
    Bhattacharyya coefficient, flags such as ``probation``) or lists of words (the search's ``vetoes``), non-finite
    numbers as None, for the JSON Lines."""
    import math

    out = {}
    for k, v in info.items():
        if isinstance(v, (bool, str)) or v is None:
            out[k] = v
        elif isinstance(v, (list, tuple)) and all(isinstance(x, str) for x in v):
            out[k] = list(v)
        elif isinstance(v, (int, float, np.integer, np.floating)):
            f = float(v)
            out[k] = (int(v) if isinstance(v, (int, np.integer)) else f) if math.isfinite(f) else None
    return out


def run_track(source_spec, *, box, tracker_name, out, video_out=None, json_out=None, seed=0, params=None,
              skip_bad_frames=False, quiet=False, gt_overlay=False, show_map=False, target=None,
              reconnect: int = 0, detect: str | None = None) -> dict:
    """The work behind ``pftrack track`` (also used by ``pftrack demo``)."""
    from ..errors import BoxError, ParameterError
    from ..geometry import parse_box
    from ..io.sinks import CsvTrackSink, JsonLinesSink, VideoSink, prepare_output, prepare_video_output
    from ..io.sources import open_source
    from ..pipeline import TrackRun, interrupt_on_sigterm, missing_box_message, track_source
    from ..trackers.registry import create_tracker
    from ..trackers.warmup import warm_up
    from ..viz.draw import TrackDrawer, map_panel

    if box is not None and target is not None:
        raise ParameterError("--box and --target both give the initial box; give one of them")
    extras = {}
    if detect is not None:
        from ..multi.detectors import create_detector
        from ..trackers.registry import get_spec

        if box is not None or target is not None:
            raise ParameterError("--detect starts from a detection; give it without --box or --target")
        if "detector" not in get_spec(tracker_name).extra_kwargs:
            raise ParameterError(f"--detect: tracker '{tracker_name}' cannot start from a detector (color-pf, "
                                 "fusion-pf and local-motion-pf can)")
        extras["detector"] = create_detector(detect)
    tracker = create_tracker(tracker_name, seed=seed, params=params or {}, **extras)
    if show_map and not hasattr(tracker, "confidence_map"):
        raise ParameterError(f"--show-map: tracker '{tracker_name}' has no confidence map (try cotrain-pf)")
    if show_map and not video_out:
        raise ParameterError("--show-map needs --video-out")
    # kernels are compiled (first run) or loaded from the on-disk cache here, never inside the timed loop
    warm_seconds = warm_up(tracker_name, params or {})
    init_box = parse_box(box) if isinstance(box, str) else box
    # check every output before any work starts
    prepare_output(out)
    if video_out:
        prepare_video_output(video_out)
    if json_out:
        prepare_output(json_out)
    source = open_source(source_spec, skip_bad_frames=skip_bad_frames, target=target, reconnect=reconnect)
    if detect is None and init_box is None and source.init_box is None:  # said before any output file is created
        source.close()
        raise BoxError(missing_box_message(source))
    run = TrackRun()
    sinks: list = []
    drawer = TrackDrawer()
    bar = None
    lost = 0
    size = None
    try:
        csv = CsvTrackSink(out)
        sinks.append(csv)
        jsonl = JsonLinesSink(json_out) if json_out else None
        if jsonl:
            sinks.append(jsonl)
        video = VideoSink(video_out, fps=source.fps) if video_out else None
        if video:
            sinks.append(video)
        bar = progress(source.length, f"{tracker_name}", quiet)
        gt = source.groundtruth if gt_overlay else None
        with interrupt_on_sigterm() as stop:
            for number, frame, state in track_source(source, tracker, init_box, run=run, detect=detect is not None):
                size = (frame.shape[1], frame.shape[0])
                csv.write_state(number, state)
                lost += int(state.lost)
                if jsonl:
                    rec = {"frame": number, "box": list(state.box), "score": state.score, "lost": state.lost}
                    if "box_full" in state.info:  # the whole estimate where it reaches past the frame's edge
                        rec["box_full"] = list(state.info["box_full"])
                    if state.particles is not None and state.weights is not None:
                        rec["n_particles"] = len(state.particles)
                    info = scalar_info(state.info)
                    if info:
                        rec["info"] = info
                    jsonl.write(rec)
                if video:
                    g = gt[number - 1] if gt is not None and number - 1 < len(gt) else None
                    img = drawer.draw(frame, state, number, gt_box=g)
                    if show_map:
                        cm = tracker.confidence_map()
                        img = np.hstack([img, map_panel(frame, *(cm if cm is not None else (None, None)))])
                    video.write(img)
                bar.update(1)
                stop.check()
    except KeyboardInterrupt:
        raise Interrupted(f"interrupted after {run.frames} frames; rows so far are in {out}") from None
    finally:
        close_all(bar, sinks, source)
    return {"frames": run.frames, "warmup_seconds": warm_seconds, "update_fps": run.update_fps,
            "end_to_end_fps": run.end_to_end_fps,
            "lost_frames": lost, "skipped": list(source.skipped), "source": source, "frame_size": size}


def cmd_track(args) -> int:
    from ..params import parse_param_assignments

    res = run_track(args.source, box=args.box, tracker_name=args.tracker, out=args.out, video_out=args.video_out,
                    json_out=args.json_out, seed=args.seed, params=parse_param_assignments(args.param),
                    skip_bad_frames=args.skip_bad_frames, quiet=args.quiet, show_map=args.show_map,
                    target=args.target, reconnect=args.reconnect, detect=args.detect)
    n = res["frames"]
    speed = (f"{res['update_fps']:.0f} update fps, {res['end_to_end_fps']:.0f} fps end to end" if n > 1
             else "no update to time")  # one frame is the initialisation only
    msg = (f"{counted(n, 'frame')} tracked with {args.tracker}: {speed}, lost in "
           f"{counted(res['lost_frames'], 'frame')} -> {args.out}")
    if res["skipped"]:
        msg += f" ({counted(len(res['skipped']), 'unreadable frame')} skipped)"
    print(msg + reconnected_note(res["source"]), file=sys.stderr)
    return 0


def add_demo(sub) -> None:
    p = sub.add_parser("demo", help="run the default tracker on the bundled real clip")
    p.add_argument("--out", default="demo_out", help="output folder (default demo_out)")
    p.add_argument("--tracker", default=DEFAULT_TRACKER, help=f"tracker name (default {DEFAULT_TRACKER})")
    p.add_argument("--seed", type=seed_value, default=0)
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_demo)


def demo_clip() -> tuple[Path, Path]:
    """Paths of the bundled clip and its ground truth."""
    from importlib import resources

    base = resources.files("pftrack") / "data" / "crossing"
    return Path(str(base / "crossing.mp4")), Path(str(base / "groundtruth_rect.txt"))


def cmd_demo(args) -> int:
    import numpy as np

    from ..eval.metrics import ope_scores
    from ..io.datasets import read_number_rows
    from ..io.sinks import read_track_csv

    clip, gt_path = demo_clip()
    gt = np.array(read_number_rows(gt_path, widths=(4,)), dtype=np.float64)
    out = Path(args.out)
    csv_path, video_path = out / "track.csv", out / "track.mp4"
    res = run_track(str(clip), box=tuple(gt[0]), tracker_name=args.tracker, out=csv_path, video_out=video_path,
                    seed=args.seed, quiet=args.quiet)
    rows = read_track_csv(csv_path)
    scores = ope_scores(rows[:, 1:5], gt, bounds=res["frame_size"])
    print(f"pftrack demo: {res['frames']} frames of the bundled clip 'Crossing' (OTB) with {args.tracker}")
    if res["warmup_seconds"] > 1.0:
        print(f"  compiled kernels {res['warmup_seconds']:.1f} s before timing "
              "(first run; cached on disk for the next)")
    print(f"  update speed     {res['update_fps']:.0f} fps "
          f"({res['end_to_end_fps']:.0f} fps end to end, decode included)")
    print(f"  OTB success AUC  {scores.auc:.3f}   precision@20px {scores.precision:.3f}")
    print(f"  results          {csv_path}  (frame,x,y,w,h,score,lost)")
    print(f"  annotated video  {video_path}")
    return 0
