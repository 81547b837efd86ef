"""``pftrack segment``: track an object as a segmentation mask with graph cuts (book ch. 9)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ..errors import Interrupted
from .common import close_all, counted, first_frame, first_truth_box, follow_frames, image_file, progress


def add_segment(sub) -> None:
    p = sub.add_parser("segment", help="track an object as a segmentation mask with graph cuts (book ch. 9)",
                       description="Every frame, a graph cut of colour-histogram and contrast terms on a region "
                                   "around the previous mask, seeded by its distance transform. Writes one 0/255 "
                                   "PNG mask per frame (000001.png, ... by frame number from 1), as it goes.")
    p.add_argument("source", help="video file, frame folder, OTB/VOT folder, camera index or stream "
                   "URL (rtsp://, http://, ...)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--box", help="X,Y,W,H of the object in the first frame (GrabCut finds the first mask)")
    g.add_argument("--mask", help="first-frame mask (PNG, non-zero = object), the same size as the frames")
    p.epilog = ("Without --box or --mask, a sequence folder gives the object itself: its first frame's mask in "
                "masks/ (DAVIS), else its first frame's ground-truth box.")
    p.add_argument("--out-dir", default="masks", help="folder of the mask PNGs (default masks/)")
    p.add_argument("--video-out", help="video with the mask's contour overlaid")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                   help="graphcut parameter (repeatable; see 'pftrack list graphcut')")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_segment)


def cmd_segment(args) -> int:
    import cv2

    from ..errors import BoxError, InputError, ParameterError, SourceError
    from ..geometry import parse_box, validate_box
    from ..io.sinks import VideoSink, prepare_output, prepare_video_output
    from ..io.sources import open_source
    from ..params import parse_param_assignments
    from ..segmentation.tracker import GraphCutParams, GraphCutTracker

    params = GraphCutParams.from_mapping(parse_param_assignments(args.param))
    source = open_source(args.source)
    mask_path, box_spec = args.mask, args.box
    if not mask_path and not box_spec:  # the sequence's own first mask or box, said before any output is made
        mask_path, box_spec = _sequence_object(source)
        if mask_path is None and box_spec is None:
            source.close()
            raise ParameterError("give the first frame's object with --box X,Y,W,H or --mask FIRST.png")
        if not args.quiet:
            print(f"first object: {mask_path or 'the ground-truth box ' + box_spec}", file=sys.stderr)
    first_mask = None
    try:
        if mask_path:
            img = image_file(mask_path)
            first_mask = (img if img.ndim == 2 else img.max(axis=2)) > 0
            if not first_mask.any():
                raise InputError(f"{mask_path}: the mask is empty")
        out_dir = Path(args.out_dir)
        prepare_output(out_dir / "000001.png")
        if args.video_out:
            prepare_video_output(args.video_out)
    except Exception:
        source.close()
        raise
    frames, (number, frame) = first_frame(source, args.source)
    H, W = frame.shape[:2]
    try:
        if first_mask is not None and first_mask.shape != (H, W):
            raise InputError(f"{mask_path}: mask size {first_mask.shape[1]}x{first_mask.shape[0]} differs from the "
                             f"frames' {W}x{H}")
        box = validate_box(parse_box(box_spec), W, H) if box_spec else None
    except (InputError, BoxError):
        source.close()
        raise
    tracker = GraphCutTracker(params)
    sinks: list = []
    bar = None
    done = lost = 0
    try:
        video = VideoSink(args.video_out, fps=source.fps) if args.video_out else None
        if video:
            sinks.append(video)
        bar = progress(source.length, "segment", args.quiet)

        def emit(num, img, st) -> None:
            m = st.info["mask"]
            if not cv2.imwrite(str(out_dir / f"{num:06d}.png"), m.astype(np.uint8) * 255):
                raise SourceError(f"{out_dir}: cannot write masks there")
            if video:
                canvas = img.copy()
                cs, _ = cv2.findContours(m.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
                cv2.drawContours(canvas, cs, -1, (0, 0, 255) if st.lost else (0, 255, 0), 2, cv2.LINE_AA)
                video.write(canvas)
            bar.update(1)

        done, lost = follow_frames(
            number, frame, frames,
            lambda f: tracker.init_mask(f, first_mask) if first_mask is not None else tracker.init(f, box),
            tracker.update, emit)
    except KeyboardInterrupt:
        raise Interrupted(f"interrupted; masks so far are in {out_dir}") from None
    finally:
        close_all(bar, sinks, source)
    print(f"{counted(done, 'mask')} ({counted(lost, 'frame')} lost) -> {out_dir}", file=sys.stderr)
    return 0


def _sequence_object(source) -> tuple[str | None, str | None]:
    """The first frame's object of a sequence folder: ``(mask file, None)`` when the folder has a ``masks/`` image
    of its first frame (DAVIS), ``(None, "X,Y,W,H")`` when its ground truth starts on the first frame, else
    ``(None, None)``."""
    seq = source.sequence
    if seq is None or not seq.frames:
        return None, None
    first = seq.frames[0]
    if isinstance(first, Path):
        for name in (first.stem + ".png", first.name):
            for folder in (first.parent.parent / "masks", first.parent / "masks"):
                if (folder / name).is_file():
                    return str(folder / name), None
    truth = first_truth_box(source)
    return None, (None if truth is None else truth[1])
