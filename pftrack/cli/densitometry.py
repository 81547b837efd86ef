"""``pftrack densitometry``: the densitometric curve along a line that follows a tracked segment (book ch. 14)."""

from __future__ import annotations

import itertools
import sys

from ..errors import Interrupted
from .common import close_all, counted, progress


def add_densitometry(sub) -> None:
    p = sub.add_parser("densitometry",
                       help="grey-level curve along a line that follows a tracked segment (book ch. 14)",
                       description="Track the segment in --box with template matching, translate --line with it and "
                                   "write per frame the line, A(t) of eq. (1), the vessel edges and the profile's "
                                   "statistics (CSV, one row per frame, flushed).")
    p.add_argument("source", help="video file, frame folder, OTB/VOT folder, camera index or stream "
                   "URL (rtsp://, http://, ...)")
    p.add_argument("--box", required=True, help="template window X,Y,W,H (around the artery segment)")
    p.add_argument("--line", required=True,
                   help="cross-sectional line X1,Y1,X2,Y2 in the first frame (or X1,Y1;X2,Y2, as tripwire takes it)")
    p.add_argument("--template-frame", type=int, default=1,
                   help="frame (from 1) where --box and --line are given, e.g. the end of the contrast injection; "
                        "frames before it are tracked backwards from it (rows are written as computed: that "
                        "frame, then back to frame 1, then forwards)")
    p.add_argument("--metric", default="ncc", help="matching criterion (ssd, ccorr, ncc, sad, morph, morph_normed, "
                                                   "mi, nmi; default ncc)")
    p.add_argument("--width", type=int, default=1, help="line width in pixels (the profile is averaged across it)")
    p.add_argument("--background", choices=["I", "II", "III"], default="II",
                   help="background line: I end pixels, II means of 3 end pixels (default), III least squares")
    p.add_argument("--out", default="curve.csv", help="CSV output (default curve.csv)")
    p.add_argument("--video-out", help="annotated video with the moving line and the template window")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE", help="template tracker parameter")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_densitometry)


def cmd_densitometry(args) -> int:
    import cv2

    from ..densitometry import DensitometrySink, run_densitometry
    from ..densitometry.run import check_line
    from ..errors import BoxError, ParameterError
    from ..geometry import parse_box, validate_box
    from ..io.sinks import VideoSink, prepare_output, prepare_video_output
    from ..io.sources import open_source
    from ..params import parse_param_assignments
    from ..pipeline import interrupt_on_sigterm
    from ..trackers.registry import create_tracker
    from ..viz.draw import draw_box

    if args.width < 1:
        raise ParameterError("--width must be >= 1")
    try:
        line = [float(v) for v in args.line.replace(" ", ",").replace(";", ",").split(",") if v]
    except ValueError:
        raise BoxError(f"line must be X1,Y1,X2,Y2 or X1,Y1;X2,Y2 (4 numbers), got {args.line!r}") from None
    if len(line) != 4:
        raise BoxError(f"line must be X1,Y1,X2,Y2 or X1,Y1;X2,Y2 (4 numbers), got {args.line!r}")
    tracker = create_tracker("template", params={"metric": args.metric, **parse_param_assignments(args.param)})
    box = parse_box(args.box)
    prepare_output(args.out)
    if args.video_out:
        prepare_video_output(args.video_out)
    source = open_source(args.source)
    frames = source.numbered()
    if args.template_frame < 1:
        source.close()
        raise ParameterError("--template-frame must be >= 1")
    before = []  # frames before the template frame, tracked backwards from it
    try:  # check the line and the box on the template frame, before any output is created
        first = next(frames)
        while first[0] < args.template_frame:
            before.append(first)
            first = next(frames)
    except StopIteration:
        source.close()
        raise BoxError(f"{args.source}: no frame {args.template_frame}") from None
    try:
        h, w = first[1].shape[:2]
        check_line(line, w, h)
        validate_box(box, w, h)
    except BoxError:
        source.close()
        raise
    sinks: list = []
    bar = None
    done = 0
    try:
        sink = DensitometrySink(args.out)
        sinks.append(sink)
        video = VideoSink(args.video_out, fps=source.fps) if args.video_out else None
        if video:
            sinks.append(video)
        bar = progress(source.length, "densitometry", args.quiet)

        with interrupt_on_sigterm() as stop:
            def on_frame(number, frame, state, moved):
                if video:
                    img = frame.copy()
                    draw_box(img, state.box, (0, 200, 255) if not state.lost else (0, 0, 255), 1)
                    cv2.line(img, (int(round(moved[0])), int(round(moved[1]))),
                             (int(round(moved[2])), int(round(moved[3]))), (0, 255, 0), 1, cv2.LINE_AA)
                    video.write(img)
                bar.update(1)
                stop.check()

            done = 0
            if before:  # the chapter's frame nr in the middle: first backwards to frame 1
                back = create_tracker("template", params={"metric": args.metric,
                                                          **parse_param_assignments(args.param)})
                done += run_densitometry(itertools.chain([first], reversed(before)), back, box, line, sink,
                                         width=args.width, background=args.background, on_frame=on_frame)
                before.clear()
            done += run_densitometry(itertools.chain([first], frames), tracker, box, line, sink, width=args.width,
                                     background=args.background, on_frame=on_frame, write_first=not done)
    except KeyboardInterrupt:
        raise Interrupted(f"interrupted; rows so far are in {args.out}") from None
    finally:
        close_all(bar, sinks, source)
    print(f"{counted(done, 'frame')} measured with template[{args.metric}] -> {args.out}", file=sys.stderr)
    return 0
