"""``pftrack points`` and ``pftrack stereo``: points tracked through occlusions (book ch. 7)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from ..errors import Interrupted
from .common import close_all, counted, first_frame, follow_frames, progress

POINTS_HEADER = "frame,point,x,y,source"
DIAG_HEADER = "frame,point,x,y,vx_of,vy_of,vx_af,vy_af,eps,delta_eps,e,qv,k,source"
STEREO_HEADER = "frame,point,xl,yl,xr,yr,Z"


def add_points(sub) -> None:
    p = sub.add_parser("points", help="track points through occlusions: LK gated by an RLS prediction (book ch. 7)",
                       description="Track the given points with Lucas-Kanade. With --method rls or fuzzy the flow "
                                   "is used only while it agrees with an RLS AR(2) prediction, so points are "
                                   "carried through occlusions. Writes frame,point,x,y,source (flow, prediction "
                                   "or lost) per point and frame, from frame 1, flushed per frame.")
    p.add_argument("source", help="video file, frame folder, OTB/VOT folder, camera index or stream "
                   "URL (rtsp://, http://, ...)")
    p.add_argument("--points", required=True, help='points in frame 1: "X1,Y1;X2,Y2;..."')
    p.add_argument("--method", choices=["lk", "rls", "fuzzy"], default="fuzzy",
                   help="lk: plain Lucas-Kanade; rls: the gate with k = 0.75; fuzzy: k tuned by the fuzzy "
                        "controller (default)")
    p.add_argument("--out", default="points.csv", help="CSV output (default points.csv)")
    p.add_argument("--diag", help="also write the gate's diagnostics per point and frame (" + DIAG_HEADER + ")")
    p.add_argument("--video-out", help="annotated video (points coloured by source, with their trails)")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                   help="point-tracker parameter (repeatable; see pftrack.trackers.point_gate.PointParams)")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_points)


def add_stereo(sub) -> None:
    p = sub.add_parser("stereo", help="track points in a rectified stereo pair with depth through occlusions "
                                      "(book ch. 7)",
                       description="Track points of the left view; the right points come from a correlation "
                                   "search along the row, both views are carried by a joint RLS while hidden, "
                                   "and Z = f*B/(xl - xr). Writes frame,point,xl,yl,xr,yr,Z, flushed per frame.")
    p.add_argument("left", help="left frames: folder or video")
    p.add_argument("right", help="right frames: folder or video (rectified, same size)")
    p.add_argument("--calib", required=True, help="JSON file with f (pixels), B (baseline, metres), cx, cy")
    p.add_argument("--points", required=True, help='points in the left image of frame 1: "X1,Y1;X2,Y2;..."')
    p.add_argument("--method", choices=["lk", "rls", "fuzzy"], default="fuzzy", help="as for 'pftrack points'")
    p.add_argument("--out", default="stereo.csv", help="CSV output (default stereo.csv)")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                   help="stereo-tracker parameter (repeatable; e.g. d_max=96)")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_stereo)


def parse_points(text: str, width: int, height: int) -> np.ndarray:
    """``"X1,Y1;X2,Y2"`` → ``(n, 2)``; every point finite and inside the image."""
    from ..errors import BoxError

    pts = []
    for part in str(text).split(";"):
        if not part.strip():
            continue
        vals = part.replace(" ", ",").split(",")
        vals = [v for v in vals if v]
        try:
            xy = [float(v) for v in vals]
        except ValueError:
            raise BoxError(f"points must look like X1,Y1;X2,Y2, got {text!r}") from None
        if len(xy) != 2 or not all(np.isfinite(xy)):
            raise BoxError(f"points must look like X1,Y1;X2,Y2 (two finite numbers each), got {part.strip()!r}")
        pts.append(xy)
    if not pts:
        raise BoxError("no points given")
    arr = np.asarray(pts, dtype=np.float64)
    for i, (x, y) in enumerate(arr):
        if not (0 <= x <= width - 1 and 0 <= y <= height - 1):
            raise BoxError(f"point {i} ({x:g},{y:g}) is outside the {width}x{height} image")
    return arr


def _fmt(v: float) -> str:
    return "nan" if not np.isfinite(v) else f"{v:.3f}".rstrip("0").rstrip(".")


def cmd_points(args) -> int:
    import cv2

    from ..io.sinks import VideoSink, _TextSink, prepare_output, prepare_video_output
    from ..io.sources import open_source
    from ..params import parse_param_assignments
    from ..trackers.point_gate import SOURCES, PointParams, PointTracker

    params = PointParams.from_mapping({"method": args.method, **parse_param_assignments(args.param)})
    prepare_output(args.out)
    if args.diag:
        prepare_output(args.diag)
    if args.video_out:
        prepare_video_output(args.video_out)
    source = open_source(args.source)
    frames, (number, frame) = first_frame(source, args.source)
    try:
        pts = parse_points(args.points, frame.shape[1], frame.shape[0])
    except Exception:
        source.close()
        raise
    tracker = PointTracker(params)
    sinks: list = []
    bar = None
    done = 0
    colours = {0: (0, 220, 0), 1: (0, 200, 255), 2: (0, 0, 255)}
    try:
        out = _TextSink(args.out)
        out._write(POINTS_HEADER)
        sinks.append(out)
        diag = _TextSink(args.diag) if args.diag else None
        if diag:
            diag._write(DIAG_HEADER)
            sinks.append(diag)
        video = VideoSink(args.video_out, fps=source.fps) if args.video_out else None
        if video:
            sinks.append(video)
        trails: list[np.ndarray] = []
        bar = progress(source.length, "points", args.quiet)

        def emit(num: int, img, step) -> None:
            names = step.source_names()
            out._write("\n".join(f"{num},{j},{_fmt(x)},{_fmt(y)},{names[j]}" for j, (x, y) in enumerate(step.pos)))
            if diag:
                rows = []
                for j in range(len(step.pos)):
                    vals = [*step.pos[j], *step.v_of[j], *step.v_af[j], step.eps[j], step.delta_eps[j], step.e[j]]
                    rows.append(f"{num},{j}," + ",".join(_fmt(float(v)) for v in vals)
                                + f",{int(step.qv[j])},{_fmt(float(step.k[j]))},{SOURCES[int(step.source[j])]}")
                diag._write("\n".join(rows))
            if video:
                trails.append(step.pos.copy())
                canvas = img.copy()
                hist = np.array(trails[-40:])
                for j in range(len(step.pos)):
                    line = hist[:, j].round().astype(np.int32)
                    cv2.polylines(canvas, [line.reshape(-1, 1, 2)], False, (255, 255, 255), 1, cv2.LINE_AA)
                    cx, cy = (round(float(v)) for v in step.pos[j])
                    cv2.circle(canvas, (cx, cy), 4, colours[int(step.source[j])], -1, cv2.LINE_AA)
                video.write(canvas)
            bar.update(1)

        done, _ = follow_frames(number, frame, frames, lambda f: tracker.init(f, pts), tracker.step, emit)
    except KeyboardInterrupt:
        raise Interrupted(f"interrupted; rows so far are in {args.out}") from None
    finally:
        close_all(bar, sinks, source)
    print(f"{counted(len(pts), 'point')} through {counted(done, 'frame')} ({args.method}) -> {args.out}",
          file=sys.stderr)
    return 0


def read_calib(path: str) -> dict:
    from ..errors import ParameterError

    p = Path(path)
    if not p.is_file():
        raise ParameterError(f"{path}: no such calibration file")
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ParameterError(f"{path}: not a JSON calibration ({exc})") from None
    missing = [k for k in ("f", "B", "cx", "cy") if not isinstance(data, dict) or k not in data]
    if missing:
        raise ParameterError(f"{path}: calibration lacks {', '.join(missing)} (needs f, B, cx, cy)")
    try:
        calib = {k: float(data[k]) for k in ("f", "B", "cx", "cy")}
    except (TypeError, ValueError):
        raise ParameterError(f"{path}: f, B, cx and cy must be numbers") from None
    if not (calib["f"] > 0 and calib["B"] > 0 and all(np.isfinite(list(calib.values())))):
        raise ParameterError(f"{path}: f and B must be positive")
    return calib


def cmd_stereo(args) -> int:
    from ..errors import BoxError, SourceError
    from ..io.sinks import _TextSink, prepare_output
    from ..io.sources import open_source
    from ..params import parse_param_assignments
    from ..pipeline import interrupt_on_sigterm
    from ..trackers.stereo import StereoParams, StereoTracker

    calib = read_calib(args.calib)
    params = StereoParams.from_mapping({"method": args.method, **parse_param_assignments(args.param)})
    prepare_output(args.out)
    left = open_source(args.left)
    try:
        right = open_source(args.right)
    except Exception:
        left.close()
        raise
    lf, (n0, l0) = first_frame(left, args.left)
    rf, (_, r0) = first_frame(right, args.right)
    sinks: list = []
    bar = None
    done = 0
    try:
        if l0.shape != r0.shape:
            raise SourceError(f"left frames are {l0.shape[1]}x{l0.shape[0]}, right frames {r0.shape[1]}x{r0.shape[0]}")
        pts = parse_points(args.points, l0.shape[1], l0.shape[0])
        tracker = StereoTracker(calib, params)
        try:
            step = tracker.init(l0, r0, pts)
        except ValueError as exc:
            raise BoxError(str(exc)) from None
        out = _TextSink(args.out)
        out._write(STEREO_HEADER)
        sinks.append(out)
        bar = progress(min(v for v in (left.length, right.length) if v) if left.length and right.length else None,
                       "stereo", args.quiet)

        def emit(num: int, s) -> None:
            out._write("\n".join(f"{num},{j},{_fmt(s.xl[j, 0])},{_fmt(s.xl[j, 1])},{_fmt(s.xr[j])},"
                                 f"{_fmt(s.xl[j, 1])},{_fmt(float(s.Z[j]))}" for j in range(len(s.xr))))
            bar.update(1)

        with interrupt_on_sigterm() as stop:
            emit(n0, step)
            done = 1
            for (num, lfr), (_, rfr) in zip(lf, rf):
                emit(num, tracker.step(lfr, rfr))
                done += 1
                stop.check()
    except KeyboardInterrupt:
        raise Interrupted(f"interrupted; rows so far are in {args.out}") from None
    finally:
        close_all(bar, sinks, left)
        right.close()
    print(f"{counted(len(pts), 'point')} through {counted(done, 'stereo frame')} ({args.method}) -> {args.out}",
          file=sys.stderr)
    return 0
