"""``pftrack activity``: MPEG-7 motion activity from a stream's motion vectors (book ch. 8)."""

from __future__ import annotations

import sys

import numpy as np

from ..errors import Interrupted
from .common import counted, progress


def add_activity(sub) -> None:
    p = sub.add_parser("activity", help="MPEG-7 motion activity (levels 1-5) per frame from the motion vectors of "
                                        "an H.264 / MPEG-4 stream (book ch. 8)",
                       description="sigma = standard deviation of the (weighted) motion-vector magnitudes of a "
                                   "frame, median-filtered over 5 frames and quantised at 3.9 / 10.7 / 17.1 / 32. "
                                   "Weighting: 'far' weighs small square partitions up (a far camera sees small "
                                   "objects), 'near' also damps repeated partitions of one class (a large, slow "
                                   "object), 'auto' picks by the share of moving blocks. Writes frame,activity,sigma.")
    p.add_argument("source", help="H.264 or MPEG-4 Part 2 video file or stream URL (rtsp://, http://, ...)")
    p.add_argument("--weighting", choices=["none", "far", "near", "auto"], default="none")
    p.add_argument("--kappa", type=float, default=4.0, help="penalty strength of Eq. (15) (default 4)")
    p.add_argument("--out", default="activity.csv", help="CSV output (default activity.csv)")
    p.add_argument("--plot", help="PNG plot of sigma and the levels over time")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_activity)


def cmd_activity(args) -> int:
    from ..io.motion_vectors import MVSource, iter_mv_frames, mv_field
    from ..io.sinks import _TextSink, prepare_output
    from ..multi.motion_activity import intensity_level, motion_sigma

    length = MVSource(args.source).length  # checks the file, its stream and codec before any output exists
    prepare_output(args.out)
    if args.plot:
        prepare_output(args.plot)
    mode = args.weighting
    sig: list[float] = []
    nums: list[int] = []
    series: list[tuple[int, float, int]] = []
    backlog: list = []
    shares: list[float] = []
    out = _TextSink(args.out)
    out._write("frame,activity,sigma")
    bar = progress(length, "activity", args.quiet)

    def flush(upto: int) -> None:
        """Write frames up to ``upto`` (exclusive): the centred 5-frame median (edges repeated), quantised."""
        arr = np.asarray(sig)
        while len(series) < upto:
            k = len(series)
            s = float(np.median(arr[np.clip(np.arange(k - 2, k + 3), 0, len(arr) - 1)]))
            lev = int(intensity_level(s))
            out._write(f"{nums[k]},{lev},{s:.4f}")
            series.append((nums[k], s, lev))

    def process(number, mvs, w, h) -> None:
        sig.append(motion_sigma(mvs, w, h, weighted=mode != "none", penalty=mode == "near", kappa=args.kappa))
        nums.append(number)
        flush(len(sig) - 2)

    try:
        for mvf in iter_mv_frames(args.source):
            h, w = mvf.y.shape
            bar.update(1)
            if mode == "auto":
                fwd, _ = mv_field(mvf.mvs, mvf.y.shape)
                shares.append(float(np.mean(np.hypot(fwd[..., 0], fwd[..., 1]) >= 1.0)))
                backlog.append((mvf.number, mvf.mvs))
                if len(backlog) < 30:
                    continue
                mode = "near" if np.mean(shares) > 0.10 else "far"
                print(f"pftrack: weighting 'auto' chose '{mode}' ({100 * np.mean(shares):.1f} % moving blocks)",
                      file=sys.stderr)
                for number, mvs in backlog:
                    process(number, mvs, w, h)
                backlog.clear()
                continue
            process(mvf.number, mvf.mvs, w, h)
        if backlog:                                # a clip shorter than 30 frames
            mode = "near" if np.mean(shares) > 0.10 else "far"
            for number, mvs in backlog:
                process(number, mvs, w, h)
        if sig:
            flush(len(sig))
    except KeyboardInterrupt:
        raise Interrupted(f"interrupted; rows so far are in {args.out}") from None
    finally:
        bar.close()
        out.close()
    if args.plot and series:
        from ..viz.activity import plot_activity

        plot_activity(series, args.plot, title=f"motion activity (weighting: {mode})")
    levels = np.bincount([s[2] for s in series], minlength=6)[1:]
    print(f"{counted(len(series), 'frame')}, frames per level 1-5: {levels.tolist()} -> {args.out}", file=sys.stderr)
    return 0
