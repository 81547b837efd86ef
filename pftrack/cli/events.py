"""``pftrack tripwire``: directional crossings of a line, trackerless (book ch. 10) or from tracks."""

from __future__ import annotations

import sys
import time

import numpy as np

from ..errors import Interrupted
from .common import close_all, counted, progress

EVENTS_HEADER = "frame,direction,time_s,to_patch,from_patch,tau_frame,score,s_color,s_motion,x,y,vx,vy"


def add_tripwire(sub) -> None:
    p = sub.add_parser(
        "tripwire", help="count directional crossings of a line without tracking (book ch. 10)",
        description="Count objects crossing a polyline. The line's points are given in order; a crossing is "
                    "'positive' when the object passes from the screen-left of the direction of travel along the "
                    "line to its screen-right, i.e. from s < 0 to s > 0 with s(P) = (x2-x1)(Py-y1) - (y2-y1)(Px-x1) "
                    "(for a line drawn left to right: moving down the image). Trackerless by default (ground "
                    "patches, colour histories and block-matching motion; with --point foot or centre also the "
                    "foot points of the foreground blobs near the line, --param feet=false to turn off); "
                    "--from-tracks runs the conventional tripwire on MOTChallenge tracks instead. Writes "
                    "frame,direction,... per crossing, flushed.")
    p.add_argument("source", nargs="?", help="video file, frame folder or MOTChallenge folder (not needed with "
                                             "--from-tracks)")
    p.add_argument("--line", required=True, help='polyline "X1,Y1;X2,Y2[;...]" (at least two points)')
    p.add_argument("--out", default="events.csv", help="CSV output (default events.csv)")
    p.add_argument("--from-tracks", help="MOTChallenge tracks file (frame,id,x,y,w,h,...): the tracker-based tripwire")
    p.add_argument("--point", choices=["foot", "centre", "match"], default="foot",
                   help="the object's point whose passage is the crossing: foot = bottom centre of its box (default; "
                        "upright objects seen obliquely), centre (views from above); 'match' (trackerless only): "
                        "the frame where the appearance is matched across the line, the book's rule")
    p.add_argument("--hysteresis", type=float, default=5.0,
                   help="with --from-tracks: pixels a point must pass beyond the line (default 5)")
    p.add_argument("--min-frames", type=int, default=3,
                   help="with --from-tracks: tracks seen on fewer frames are unconfirmed and ignored (default 3)")
    p.add_argument("--radius", default="auto", help="patch radius in pixels, or 'auto' (from the foreground blobs "
                                                     "near the line in the first 10 s)")
    p.add_argument("--v-max", default=None, metavar="PX_PER_S|auto",
                   help="fastest object speed in px/s, the block matching's range (default 600, for vehicles), or "
                        "'auto' (twice the 95th percentile of the blobs' speeds near the line in the first 10 s: "
                        "about twice as fast on walkers at 7 fps, at some cost in crossings found; docs/tripwire.md)")
    p.add_argument("--stride", type=int, default=1, help="process every K-th frame (a K times lower frame rate)")
    p.add_argument("--fps", type=float, help="frame rate when the source does not state it (default 25)")
    p.add_argument("--video-out", help="overlay video: patches by state, events")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                   help="tripwire parameter (repeatable; see pftrack.events.tripwire.TripwireParams)")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_tripwire)


def _line(text: str) -> np.ndarray:
    from ..errors import ParameterError
    from ..events.geometry import parse_polyline

    try:
        return parse_polyline(text)
    except ValueError as exc:
        raise ParameterError(f"--line: {exc}") from None


def _tracks_mode(args, line: np.ndarray) -> int:
    from ..events.eval import track_crossings
    from ..io.datasets import read_mot_txt
    from ..io.sinks import _TextSink, prepare_output

    prepare_output(args.out)
    rows = read_mot_txt(args.from_tracks)  # a missing or malformed file is a one-line error
    found = track_crossings(rows, line, hysteresis=args.hysteresis, min_frames=args.min_frames, stride=args.stride,
                            point=args.point)
    with _TextSink(args.out) as out:
        out._write("frame,direction,track,x,y")
        for c in found:
            out._write(f"{c.frame:.2f},{'positive' if c.direction > 0 else 'negative'},{c.track},{c.x:.1f},{c.y:.1f}")
    n_tracks = len(np.unique(rows[:, 1])) if len(rows) else 0
    print(f"{counted(len(found), 'crossing')} of {counted(n_tracks, 'track')} -> {args.out}", file=sys.stderr)
    return 0


def _event_row(e) -> str:
    return (f"{e.frame},{'positive' if e.direction > 0 else 'negative'},{e.time_s:.3f},{e.to_patch},{e.from_patch},"
            f"{e.tau_frame},{e.score:.4f},{e.s_color:.4f},{e.s_motion:.4f},{e.x:.1f},{e.y:.1f},{e.vx:.2f},{e.vy:.2f}")


def cmd_tripwire(args) -> int:
    import cv2

    from ..errors import ParameterError, SourceError
    from ..events.blobs import estimate_speed
    from ..events.tripwire import TrackerlessTripwire, TripwireParams, dark_levels, estimate_radius
    from ..io.sinks import VideoSink, _TextSink, prepare_output, prepare_video_output
    from ..io.sources import open_source
    from ..params import parse_param_assignments
    from ..pipeline import interrupt_on_sigterm

    line = _line(args.line)
    if args.stride < 1:
        raise ParameterError("--stride must be >= 1")
    if args.from_tracks:
        if args.point == "match":
            raise ParameterError("--point match is for the trackerless tripwire; with --from-tracks use foot or centre")
        return _tracks_mode(args, line)
    if not args.source:
        raise ParameterError("a SOURCE is needed (or --from-tracks)")
    extra = {"timing": args.point, **parse_param_assignments(args.param)}
    if args.radius != "auto":
        try:
            extra["radius"] = float(args.radius)
        except ValueError:
            raise ParameterError(f"--radius must be a number or 'auto', got {args.radius!r}") from None
    v_auto = args.v_max == "auto"
    if args.v_max is not None and not v_auto:
        try:
            extra["v_max"] = float(args.v_max)
        except ValueError:
            raise ParameterError(f"--v-max must be a number or 'auto', got {args.v_max!r}") from None
    prepare_output(args.out)
    if args.video_out:
        prepare_video_output(args.video_out)
    source = open_source(args.source)
    fps = float(args.fps or source.fps or 25.0)
    if args.radius == "auto" or v_auto:
        from ..io.sources import VideoSource

        if isinstance(source, VideoSource) and str(args.source).strip().isdigit():
            source.close()
            raise ParameterError("--radius auto and --v-max auto need a file or folder (they read the first 10 s "
                                 "twice); give --radius")
        calib = []
        for number, frame in source.numbered():
            if (number - 1) % args.stride == 0:
                calib.append(frame)
            if number >= 10 * fps:
                break
        source.close()
        early = TripwireParams.from_mapping({k: v for k, v in extra.items() if k != "radius"})
        gain, smooth = dark_levels(calib[0], early) if calib else (1.0, False)
        if args.radius == "auto":
            extra["radius"] = estimate_radius(calib, line, grey_shadow_threshold=early.bgs_grey_shadow_threshold,
                                              gain=gain, smooth=smooth)
        if v_auto:
            extra["v_max"] = estimate_speed(calib, line, fps / args.stride, gain=gain, smooth=smooth,
                                            grey_shadow_threshold=early.bgs_grey_shadow_threshold)
        del calib
        source = open_source(args.source)
    params = TripwireParams.from_mapping(extra)
    sinks: list = []
    bar = None
    count = {1: 0, -1: 0}
    try:
        frames = source.numbered()
        try:
            number, frame = next(frames)
        except StopIteration:
            raise SourceError(f"{args.source}: no frames") from None
        try:
            tw = TrackerlessTripwire(line, frame.shape[:2], fps, params, stride=args.stride)
        except ValueError as exc:
            raise ParameterError(f"--line: {exc}") from None
        out = _TextSink(args.out)
        out._write(EVENTS_HEADER)
        sinks.append(out)
        video = VideoSink(args.video_out, fps=fps / args.stride) if args.video_out else None
        if video:
            sinks.append(video)
        bar = progress(source.length, "tripwire", args.quiet)
        flash: list = []

        timed = [0, 0.0]  # frames processed, seconds inside the tripwire (decode and overlay excluded)

        def handle(num: int, img) -> None:
            t0 = time.perf_counter()
            found = tw.process(img, num)
            timed[0] += 1
            timed[1] += time.perf_counter() - t0
            for e in found:
                count[e.direction] += 1
                out._write(_event_row(e))
                flash.append([e, 6])
            if video:
                canvas = img.copy()
                pts = np.round(line).astype(np.int32).reshape(-1, 1, 2)
                cv2.polylines(canvas, [pts], False, (255, 255, 255), 2, cv2.LINE_AA)
                for k, c in enumerate(tw.layout.centres):
                    col = (0, 0, 255) if tw.patches[k].fg else ((255, 160, 0) if tw.layout.side[k] < 0 else (0, 200, 0))
                    cv2.circle(canvas, (round(float(c[0])), round(float(c[1]))), round(tw.params.radius), col, 1)
                for item in flash:
                    e = item[0]
                    cv2.circle(canvas, (int(e.x), int(e.y)), int(2 * tw.params.radius), (0, 255, 255), 3)
                    item[1] -= 1
                flash[:] = [f for f in flash if f[1] > 0]
                cv2.putText(canvas, f"+{count[1]}  -{count[-1]}", (10, 30), cv2.FONT_HERSHEY_SIMPLEX, 1.0,
                            (0, 255, 255), 2, cv2.LINE_AA)
                video.write(canvas)
            bar.update(args.stride)

        with interrupt_on_sigterm() as stop:
            handle(number, frame)
            for number, frame in frames:
                if (number - 1) % args.stride:
                    continue
                handle(number, frame)
                stop.check()
            for e in tw.finish():
                count[e.direction] += 1
                out._write(_event_row(e))
    except KeyboardInterrupt:
        raise Interrupted(f"interrupted; events so far are in {args.out}") from None
    finally:
        close_all(bar, sinks, source)
    noun = "crossing" if count[1] + count[-1] == 1 else "crossings"
    speed = f", {timed[0] / timed[1]:.0f} frames/s decode excluded" if timed[1] > 0 else ""
    print(f"{count[1]} positive and {count[-1]} negative {noun} (r = {params.radius:.1f} px, "
          f"v_max = {params.v_max:.0f} px/s{speed}) -> {args.out}", file=sys.stderr)
    return 0
