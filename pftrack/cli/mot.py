"""``pftrack mot``: every object, detector + per-target particle filters, MOTChallenge text out."""

from __future__ import annotations

import sys

from ..errors import Interrupted, ParameterError
from .common import add_reconnect, close_all, counted, progress, reconnected_note, seed_value


def add_mot(sub) -> None:
    p = sub.add_parser("mot", help="track all the people/objects in a video, frame folder or MOTChallenge folder",
                       description="Multi-object tracking (detection + per-target colour particle filters). Writes "
                                   "MOTChallenge text rows frame,id,x,y,w,h,score,-1,-1,-1, flushed per frame.")
    p.add_argument("source", help="video file, frame folder, MOTChallenge folder, camera index or stream "
                   "URL (rtsp://, http://, ...)")
    p.add_argument("--detector", choices=["motion", "mog2", "hog", "mv"], default="mog2",
                   help="detector (default mog2); mv: groups of moving 4x4 blocks from the stream's motion vectors "
                        "(book ch. 8), each drawn as the silhouettes of a background learnt away from the moving "
                        "blocks (--param shape=blocks: the chapter's block boxes); SOURCE must be an H.264 or MPEG-4 "
                        "file; needs PyAV")
    p.add_argument("--tracker", choices=["multi-pf", "cd"], default="multi-pf",
                   help="multi-pf: per-target colour particle filters (default); cd: the compressed-domain labelling "
                        "of book ch. 8 (motion-vector groups, 5-frame refinement, labels kept through occlusions by "
                        "direction and energy; implies --detector mv)")
    p.add_argument("--out", default="tracks.txt", help="MOTChallenge text output (default tracks.txt)")
    p.add_argument("--video-out", help="annotated video output")
    p.add_argument("--seed", type=seed_value, default=0)
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE", help="multi-pf parameter (repeatable)")
    p.add_argument("--mpeg7", help="with --tracker cd: also write an MPEG-7 XML description (a trajectory per label, "
                                    "segments of high motion activity)")
    p.add_argument("--identify", action="store_true",
                   help="book ch. 1 identification: give a returning person their old identity (colour and spatial "
                        "features of the upper and lower body)")
    p.add_argument("--skip-bad-frames", action="store_true", help="skip unreadable frames instead of stopping")
    add_reconnect(p)
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_mot)


def run_mot(source_spec, *, out, detector="mog2", video_out=None, seed=0, params=None, skip_bad_frames=False,
            quiet=False, tracker_name: str = "multi-pf", mpeg7: str | None = None, reconnect: int = 0) -> dict:
    """The work behind ``pftrack mot``."""
    if reconnect and (tracker_name == "cd" or detector == "mv"):
        raise ParameterError("--reconnect reopens streams read by OpenCV; the motion-vector paths (--detector mv, "
                             "--tracker cd) read theirs with PyAV and end with the feed")
    if tracker_name == "cd":
        return run_cd(source_spec, out=out, video_out=video_out, params=params, quiet=quiet, mpeg7=mpeg7)
    if mpeg7:
        raise ParameterError("--mpeg7 needs --tracker cd")
    import time as _time

    from ..io.sinks import MotSink, VideoSink, prepare_output, prepare_video_output
    from ..io.sources import open_source
    from ..multi import create_multi_tracker
    from ..pipeline import interrupt_on_sigterm
    from ..viz.draw import color_for, draw_box

    prepare_output(out)
    if video_out:
        prepare_video_output(video_out)
    cv_threads = None
    if detector == "mv":
        from ..io.motion_vectors import MVSource
        from ..multi.compressed import CDParams, MVDetector

        params = dict(params or {})
        cd_keys = {f for f in CDParams.__dataclass_fields__}
        cd = CDParams.from_mapping({k: params.pop(k) for k in list(params) if k in cd_keys})
        source = MVSource(source_spec)
        tracker = create_multi_tracker("multi-pf", seed=seed, detector_fn=MVDetector(source, cd), **params)
        # the pipeline runs its own two threads (decoding with the block analysis, and tracking); OpenCV's pool
        # on the same cores only adds hand-over cost to its calls on small images (restored on return)
        import cv2

        cv_threads = cv2.getNumThreads()
        cv2.setNumThreads(1)
    else:
        tracker = create_multi_tracker("multi-pf", seed=seed, **{"detector": detector, **(params or {})})
        source = open_source(source_spec, skip_bad_frames=skip_bad_frames, reconnect=reconnect)
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
        # bootstrap_frames: the first frames read ahead for the detector's background
        numbered, upd = tracker.read_ahead(source.numbered(), lambda item: item[1])
        with interrupt_on_sigterm() as stop:
            for number, frame in numbered:
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
        if cv_threads is not None:
            cv2.setNumThreads(cv_threads)
    total = _time.perf_counter() - t_start
    return {"frames": frames, "rows": rows, "identities": len(ids), "update_fps": frames / upd if upd > 0 else 0.0,
            "end_to_end_fps": frames / total if total > 0 else 0.0, "source": source}


def run_cd(source_spec, *, out, video_out=None, params=None, quiet=False, mpeg7: str | None = None) -> dict:
    """``pftrack mot --tracker cd``: the chapter's compressed-domain labelling, rows delayed by 2 frames
    (the temporal refinement needs f+1 and f+2) but written with their own frame numbers."""
    import time as _time

    import numpy as np

    from ..io.motion_vectors import iter_mv_frames
    from ..io.sinks import MotSink, VideoSink, prepare_output, prepare_video_output
    from ..multi.compressed import BlockAnalyser, CDParams, CDTracker, TemporalRefiner
    from ..multi.motion_activity import intensity_level, motion_sigma
    from ..pipeline import interrupt_on_sigterm
    from ..viz.draw import color_for, draw_box

    p = CDParams.from_mapping(params or {})
    prepare_output(out)
    if video_out:
        prepare_video_output(video_out)
    if mpeg7:
        prepare_output(mpeg7)
    trajectories: dict[int, list] = {}
    sigmas: list[tuple[int, float]] = []
    from ..io.motion_vectors import MVSource

    fps = MVSource(source_spec).fps or 25.0
    analyser, refiner, labeler = BlockAnalyser(p), TemporalRefiner(), None
    frames = rows = 0
    ids: set[int] = set()
    images: dict[int, object] = {}
    sinks: list = []
    bar = progress(None, "mot cd", quiet)
    t_start = _time.perf_counter()
    sink = MotSink(out)
    sinks.append(sink)
    video = None

    def emit(batch) -> None:
        nonlocal rows, labeler
        for number, groups in batch:
            if labeler is None:
                labeler = CDTracker(size, p)
            objs = labeler.step(groups)
            for o in objs:
                sink.write(number, o.label, o.group.box, 1.0)
                x, y, w, h = o.group.box
                trajectories.setdefault(o.label, []).append((number, x + w / 2, y + h / 2))
                ids.add(o.label)
                rows += 1
            if video is not None:
                img = images.pop(number).copy()
                for o in objs:
                    draw_box(img, o.group.box, color_for(o.label), 2, str(o.label))
                video.write(img)

    try:
        with interrupt_on_sigterm() as stop:
            for mvf in iter_mv_frames(source_spec, bgr=bool(video_out)):
                size = (mvf.y.shape[1], mvf.y.shape[0])
                if video_out and video is None:
                    video = VideoSink(video_out, fps=fps)
                    sinks.append(video)
                if video_out:
                    images[mvf.number] = mvf.bgr
                emit(refiner.push(mvf.number, analyser(mvf)))
                if mpeg7:
                    sigmas.append((mvf.number, motion_sigma(mvf.mvs, size[0], size[1])))
                frames += 1
                bar.update(1)
                stop.check()
            emit(refiner.flush())
        if mpeg7:
            from scipy.ndimage import median_filter

            from ..io.mpeg7 import write_mpeg7

            sig = median_filter(np.array([v for _, v in sigmas]), size=5, mode="nearest") if sigmas else []
            levels = [(n, int(lv)) for (n, _), lv in zip(sigmas, intensity_level(sig))]
            write_mpeg7(trajectories, levels, mpeg7, fps=fps)
    except KeyboardInterrupt:
        raise Interrupted(f"interrupted after {frames} frames; rows so far are in {out}") from None
    finally:
        bar.close()
        for s_ in sinks:
            s_.close()
    total = _time.perf_counter() - t_start
    return {"frames": frames, "rows": rows, "identities": len(ids), "update_fps": frames / total if total else 0.0,
            "end_to_end_fps": frames / total if total > 0 else 0.0, "source": None}


def cmd_mot(args) -> int:
    from ..params import parse_param_assignments

    params = parse_param_assignments(args.param)
    if args.identify:
        params["identify"] = True
    res = run_mot(args.source, out=args.out, detector=args.detector, video_out=args.video_out, seed=args.seed,
                  params=params, skip_bad_frames=args.skip_bad_frames, quiet=args.quiet, tracker_name=args.tracker,
                  mpeg7=args.mpeg7, reconnect=args.reconnect)
    n, ids, rows = res["frames"], res["identities"], res["rows"]
    counts = f"{counted(n, 'frame')}, {counted(ids, 'identity', 'identities')}, {counted(rows, 'box', 'boxes')}"
    print(f"{counts}: {res['update_fps']:.0f} fps (detection + tracking), {res['end_to_end_fps']:.0f} fps end to end "
          f"-> {args.out}{reconnected_note(res.get('source'))}", file=sys.stderr)
    return 0
