"""``pftrack mot``: every object, detector + per-target particle filters, MOTChallenge text out."""

from __future__ import annotations

import sys

from ..errors import Interrupted
from .common import close_all, progress


def add_mot(sub) -> None:
    p = sub.add_parser("mot", help="track all the people/objects in a video, frame folder or MOTChallenge folder",
                       description="Multi-object tracking (detection + per-target colour particle filters). Writes "
                                   "MOTChallenge text rows frame,id,x,y,w,h,score,-1,-1,-1, flushed per frame.")
    p.add_argument("source", help="video file, frame folder, MOTChallenge folder or camera index")
    p.add_argument("--detector", choices=["motion", "mog2", "hog"], default="mog2", help="detector (default mog2)")
    p.add_argument("--out", default="tracks.txt", help="MOTChallenge text output (default tracks.txt)")
    p.add_argument("--video-out", help="annotated video output")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE", help="multi-pf parameter (repeatable)")
    p.add_argument("--identify", action="store_true",
                   help="book ch. 1 identification: give a returning person their old identity (colour and spatial "
                        "features of the upper and lower body)")
    p.add_argument("--skip-bad-frames", action="store_true", help="skip unreadable frames instead of stopping")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_mot)


def run_mot(source_spec, *, out, detector="mog2", video_out=None, seed=0, params=None, skip_bad_frames=False,
            quiet=False) -> dict:
    """The work behind ``pftrack mot``."""
    import time as _time

    from ..io.sinks import MotSink, VideoSink, prepare_output
    from ..io.sources import open_source
    from ..multi import create_multi_tracker
    from ..pipeline import interrupt_on_sigterm
    from ..viz.draw import color_for, draw_box

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
        bar = progress(source.length, "mot", quiet)
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
        close_all(bar, sinks, source)
    total = _time.perf_counter() - t_start
    return {"frames": frames, "rows": rows, "identities": len(ids), "update_fps": frames / upd if upd > 0 else 0.0,
            "end_to_end_fps": frames / total if total > 0 else 0.0, "source": source}


def cmd_mot(args) -> int:
    from ..params import parse_param_assignments

    params = parse_param_assignments(args.param)
    if args.identify:
        params["identify"] = True
    res = run_mot(args.source, out=args.out, detector=args.detector, video_out=args.video_out, seed=args.seed,
                  params=params, skip_bad_frames=args.skip_bad_frames, quiet=args.quiet)
    print(f"{res['frames']} frames, {res['identities']} identities, {res['rows']} boxes: {res['update_fps']:.0f} fps "
          f"(detection + tracking), {res['end_to_end_fps']:.0f} fps end to end -> {args.out}", file=sys.stderr)
    return 0
