"""``pftrack tripwire``: directional crossings of a line, trackerless (book ch. 10) or from tracks."""

from __future__ import annotations

import itertools
import sys
import time

import numpy as np

from ..errors import Interrupted
from .common import add_reconnect, close_all, counted, progress, reconnected_note

EVENTS_HEADER = "frame,direction,time_s,to_patch,from_patch,tau_frame,score,s_color,s_motion,x,y,vx,vy,line"
TRACK_EVENTS_HEADER = "frame,direction,track,x,y,line"


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
                    "frame,direction,... per crossing, flushed; the last column, line, numbers the --line options "
                    "from 1 (several lines are counted in one pass over the video).")
    p.add_argument("source", nargs="?", help="video file, frame folder, MOTChallenge folder, camera index or "
                                             "stream URL (rtsp://, http://, ...; not needed with --from-tracks; from a "
                                             "camera or live stream, --radius auto reads its first 10 s, which are "
                                             "then counted)")
    p.add_argument("--line", required=True, action="append",
                   help='polyline "X1,Y1;X2,Y2[;...]" (at least two points); repeat to count several lines, each with '
                        "its own patches and radius")
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
    add_reconnect(p)
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_tripwire)


def _option(k: int, n: int) -> str:
    """``--line``, or ``--line K`` when several lines are given."""
    return f"--line {k}" if n > 1 else "--line"


def _lines(texts: list[str]) -> list[np.ndarray]:
    from ..errors import ParameterError
    from ..events.geometry import parse_polyline

    out = []
    for k, text in enumerate(texts, 1):
        try:
            out.append(parse_polyline(text))
        except ValueError as exc:
            raise ParameterError(f"{_option(k, len(texts))}: {exc}") from None
    return out


def _tracks_mode(args, lines: list[np.ndarray]) -> int:
    from ..events.eval import track_crossings
    from ..io.datasets import read_mot_txt
    from ..io.sinks import _TextSink, prepare_output

    prepare_output(args.out)
    rows = read_mot_txt(args.from_tracks)  # a missing or malformed file is a one-line error
    found = sorted(((c, k) for k, line in enumerate(lines, 1)
                    for c in track_crossings(rows, line, hysteresis=args.hysteresis, min_frames=args.min_frames,
                                             stride=args.stride, point=args.point)),
                   key=lambda ck: (ck[0].frame, ck[1]))
    with _TextSink(args.out) as out:
        out._write(TRACK_EVENTS_HEADER)
        for c, k in found:
            out._write(f"{c.frame:.2f},{'positive' if c.direction > 0 else 'negative'},{c.track},{c.x:.1f},{c.y:.1f},"
                       f"{k}")
    n_tracks = len(np.unique(rows[:, 1])) if len(rows) else 0
    per_line = (" (" + ", ".join(f"line {k}: {sum(1 for _, j in found if j == k)}" for k in range(1, len(lines) + 1))
                + ")") if len(lines) > 1 else ""
    print(f"{counted(len(found), 'crossing')}{per_line} of {counted(n_tracks, 'track')} -> {args.out}",
          file=sys.stderr)
    return 0


def _event_row(e, line: int) -> str:
    return (f"{e.frame},{'positive' if e.direction > 0 else 'negative'},{e.time_s:.3f},{e.to_patch},{e.from_patch},"
            f"{e.tau_frame},{e.score:.4f},{e.s_color:.4f},{e.s_motion:.4f},{e.x:.1f},{e.y:.1f},{e.vx:.2f},{e.vy:.2f},"
            f"{line}")


#: a camera cannot be read twice: at most this many bytes of its first 10 s are kept to be counted after calibration
CAMERA_CALIBRATION_BYTES = 512 * 2 ** 20


def _calibration(args, source, fps: float) -> tuple[list, list, object]:
    """``(calib, kept, rest)``: the processed frames of the first 10 s of ``source`` (``--radius auto``, ``--v-max
    auto``); for a camera or live stream those frames numbered, to be counted first, and its stream from there
    (else None)."""
    camera = source.live
    calib, kept, size = [], [], 0
    stream = source.numbered()
    for number, frame in stream:
        if (number - 1) % args.stride == 0:
            calib.append(frame)
            size += frame.nbytes
            if camera:
                kept.append((number, frame))
        if number >= 10 * fps or (camera and size >= CAMERA_CALIBRATION_BYTES):
            break
    return calib, kept, stream if camera else None


def _let_go(items: list):
    """Yield the items of ``items`` in order, removing each from the list as it goes."""
    items.reverse()
    while items:
        yield items.pop()


def _line_params(args, calib: list, fps: float, lines: list[np.ndarray], extra: dict, v_auto: bool) -> list:
    """Each line's TripwireParams: ``extra``, with the radius (``--radius auto``) and the speed limit (``--v-max
    auto``) read per line from the processed frames ``calib`` of the first 10 s (:func:`_calibration`)."""
    from ..events.blobs import estimate_speed
    from ..events.tripwire import TripwireParams, dark_levels, estimate_radius

    if args.radius != "auto" and not v_auto:
        return [TripwireParams.from_mapping(extra) for _ in lines]
    early = TripwireParams.from_mapping({k: v for k, v in extra.items() if k != "radius"})
    gain, smooth = dark_levels(calib[0], early) if calib else (1.0, False)
    out = []
    for line in lines:
        mine = dict(extra)
        if args.radius == "auto":
            mine["radius"] = estimate_radius(calib, line, grey_shadow_threshold=early.bgs_grey_shadow_threshold,
                                             gain=gain, smooth=smooth)
        if v_auto:
            mine["v_max"] = estimate_speed(calib, line, fps / args.stride, gain=gain, smooth=smooth,
                                           grey_shadow_threshold=early.bgs_grey_shadow_threshold)
        out.append(TripwireParams.from_mapping(mine))
    return out


def cmd_tripwire(args) -> int:
    from ..errors import ParameterError, SourceError
    from ..events.tripwire import TrackerlessTripwire
    from ..io.sinks import VideoSink, _TextSink, prepare_output, prepare_video_output
    from ..io.sources import open_source
    from ..params import parse_param_assignments
    from ..pipeline import interrupt_on_sigterm
    from ..viz.tripwire import tripwire_overlay

    lines = _lines(args.line)
    if args.stride < 1:
        raise ParameterError("--stride must be >= 1")
    if args.fps is not None and not (np.isfinite(args.fps) and args.fps > 0):
        raise ParameterError(f"--fps must be a positive number, got {args.fps:g}")
    if args.from_tracks:
        if args.point == "match":
            raise ParameterError("--point match is for the trackerless tripwire; with --from-tracks use foot or centre")
        return _tracks_mode(args, lines)
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
    source = open_source(args.source, reconnect=args.reconnect)
    stated = source.fps if source.fps is not None and np.isfinite(source.fps) and source.fps > 0 else None
    fps = float(args.fps or stated or 25.0)
    calib, kept, rest = [], [], None
    if args.radius == "auto" or v_auto:
        calib, kept, rest = _calibration(args, source, fps)
        if rest is None:  # a file or folder: read again from the start
            source.close()
            source = open_source(args.source, reconnect=args.reconnect)
    params = _line_params(args, calib, fps, lines, extra, v_auto)
    del calib  # not held for the whole run (a camera's kept frames are let go as they are counted)
    sinks: list = []
    bar = None
    counts = [{1: 0, -1: 0} for _ in lines]
    total = {1: 0, -1: 0}
    try:
        # a camera's first seconds, read for the radius or speed limit, are counted first, then the live stream
        frames = itertools.chain(_let_go(kept), rest if rest is not None else source.numbered())
        try:
            number, frame = next(frames)
        except StopIteration:
            raise SourceError(f"{args.source}: no frames") from None
        tws = []
        for k, (line, par) in enumerate(zip(lines, params), 1):
            try:
                tws.append(TrackerlessTripwire(line, frame.shape[:2], fps, par, stride=args.stride))
            except ValueError as exc:
                raise ParameterError(f"{_option(k, len(lines))}: {exc}") from None
        out = _TextSink(args.out)
        out._write(EVENTS_HEADER)
        sinks.append(out)
        video = VideoSink(args.video_out, fps=fps / args.stride) if args.video_out else None
        if video:
            sinks.append(video)
        bar = progress(source.length, "tripwire", args.quiet)
        flash: list = []
        timed = [0, 0.0]  # frames processed, seconds inside the tripwires (decode and overlay excluded)

        def emit(found, k: int, radius: float) -> None:
            for e in found:
                counts[k - 1][e.direction] += 1
                total[e.direction] += 1
                out._write(_event_row(e, k))
                if video:  # drawn around the event for its next 6 frames
                    flash.append([e, 6, radius])

        def handle(num: int, img) -> None:
            t0 = time.perf_counter()
            found = [tw.process(img, num) for tw in tws]
            timed[0] += 1
            timed[1] += time.perf_counter() - t0
            for k, (tw, f) in enumerate(zip(tws, found), 1):
                emit(f, k, tw.params.radius)
            if video:
                video.write(tripwire_overlay(img, tws, flash, total, counts))
            bar.update(args.stride)

        with interrupt_on_sigterm() as stop:
            handle(number, frame)
            for number, frame in frames:
                if (number - 1) % args.stride:
                    continue
                handle(number, frame)
                stop.check()
            for k, tw in enumerate(tws, 1):
                emit(tw.finish(), k, tw.params.radius)
    except KeyboardInterrupt:
        raise Interrupted(f"interrupted; events so far are in {args.out}") from None
    finally:
        close_all(bar, sinks, source)
    rate = f"{timed[0] / timed[1]:.0f} frames/s decode excluded" if timed[1] > 0 else ""

    def said(c: dict, par, *more: str) -> str:
        noun = "crossing" if c[1] + c[-1] == 1 else "crossings"
        what = ", ".join([f"r = {par.radius:.1f} px", f"v_max = {par.v_max:.0f} px/s", *filter(None, more)])
        return f"{c[1]} positive and {c[-1]} negative {noun} ({what})"

    if len(lines) == 1:
        print(f"{said(counts[0], params[0], rate)} -> {args.out}{reconnected_note(source)}", file=sys.stderr)
    else:
        for k, (c, par) in enumerate(zip(counts, params), 1):
            print(f"line {k}: {said(c, par)}", file=sys.stderr)
        print(f"{total[1]} positive and {total[-1]} negative on {len(lines)} lines" + (f" ({rate})" if rate else "")
              + f" -> {args.out}{reconnected_note(source)}", file=sys.stderr)
    return 0
