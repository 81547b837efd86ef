"""``pftrack surface``: track a deforming textured surface with a mesh (book ch. 13)."""

from __future__ import annotations

import sys

import numpy as np

from ..errors import Interrupted
from .common import close_all, first_frame, first_truth_box, follow_frames, image_file, progress


def add_surface(sub) -> None:
    p = sub.add_parser("surface", help="track a deforming textured surface (cloth, paper) with a 2-D mesh and a "
                                       "shading warp (book ch. 13)",
                       description="The box of the first frame is the model; every frame, robust Gauss-Newton "
                                   "finds the mesh's vertex positions (and a multiplicative shading on a coarser "
                                   "mesh) that map it onto the frame. Writes frame,x0,y0,x1,y1,... (vertices "
                                   "row-major, top row first) from frame 1, flushed per frame.")
    p.add_argument("source", help="video file, frame folder, OTB/VOT folder, camera index or stream "
                   "URL (rtsp://, http://, ...)")
    p.add_argument("--box", help="X,Y,W,H of the surface in the first frame (default: a sequence folder's "
                                 "first ground-truth box)")
    p.add_argument("--mesh", default="7x7", help="vertices COLSxROWS spanning the box (default 7x7; at least 2x2)")
    p.add_argument("--no-photometric", action="store_true", help="no shading warp (classical optical flow)")
    p.add_argument("--lambda", dest="lam", type=float,
                   help="smoothness weight (default 0.005 for the meshes, 3.0 for --model dense; see docs/surfaces.md)")
    p.add_argument("--model", choices=["affine", "bilinear", "dense"], default="affine",
                   help="warp per mesh cell, or 'dense': one displacement per pixel (seconds per frame), "
                        "the CSV then holds that field at the --mesh vertices")
    p.add_argument("--out", default="mesh.csv", help="CSV output (default mesh.csv)")
    p.add_argument("--video-out", help="video with the mesh drawn (red while lost)")
    p.add_argument("--texture", help="with --video-out: an image painted onto the surface, shaded (virtual mirror)")
    p.add_argument("--kymogram", help="PNG: a stabilised kymogram, the --scanline of every frame warped back by the "
                                      "rigid motion of --roi (book ch. 13, kymography; use a stiff --lambda, e.g. 0.5)")
    p.add_argument("--scanline", help="with --kymogram: the scan line X1,Y1;X2,Y2 in first-frame pixels")
    p.add_argument("--roi", help="with --kymogram: X,Y,W,H of the region whose motion is undone (default: --box)")
    p.add_argument("--kymogram-raw", help="with --kymogram: also the kymogram of the frames as they are (PNG)")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_surface)


def cmd_surface(args) -> int:

    from ..errors import BoxError, ParameterError
    from ..geometry import parse_box
    from ..io.sinks import VideoSink, _TextSink, prepare_output, prepare_video_output
    from ..io.sources import open_source
    from ..surfaces.kymograph import Kymograph, stabilising_transform
    from ..surfaces.mesh import parse_mesh
    from ..surfaces.render import draw_mesh, retexture
    from ..surfaces.tracker import DeformableMesh, MeshParams

    try:
        rows, cols = parse_mesh(args.mesh)
    except ValueError as exc:
        raise ParameterError(f"--mesh: {exc}") from None
    source = None
    if args.box:
        box, box_text = parse_box(args.box), args.box
    else:  # a sequence folder's first ground-truth box, said before any output is made
        source = open_source(args.source)
        truth = first_truth_box(source)
        if truth is None:
            source.close()
            raise ParameterError("give the surface's first-frame box with --box X,Y,W,H (the source has no ground "
                                 "truth on its first frame)")
        box, box_text = truth
        if not args.quiet:
            print(f"first box: the ground truth's {box_text}", file=sys.stderr)
    try:
        kw = {"rows": rows, "cols": cols, "photometric": not args.no_photometric, "model": args.model}
        if args.lam is not None:
            kw["dense_lam" if args.model == "dense" else "lam"] = args.lam
        params = MeshParams.from_mapping(kw)
        texture = image_file(args.texture) if args.texture else None
        kymo = _kymogram_options(args, box)
        prepare_output(args.out)
        if args.video_out:
            prepare_video_output(args.video_out)
    except Exception:
        if source is not None:
            source.close()
        raise
    if source is None:
        source = open_source(args.source)
    frames, (number, frame) = first_frame(source, args.source)
    H, W = frame.shape[:2]
    x, y, w, h = box
    if x < 0 or y < 0 or x + w > W or y + h > H or w < 8 or h < 8:
        source.close()
        raise BoxError(f"box {box_text} is not inside the {W}x{H} image with at least 8x8 pixels")
    tracker = DeformableMesh(params)
    if kymo is not None:
        (p0, p1), roi = kymo
        stab, raw = Kymograph(p0, p1), Kymograph(p0, p1)
    sinks: list = []
    bar = None
    done = lost_frames = 0
    try:
        out = _TextSink(args.out)
        K = rows * cols
        out._write("frame," + ",".join(f"x{k},y{k}" for k in range(K)))
        sinks.append(out)
        video = VideoSink(args.video_out, fps=source.fps) if args.video_out else None
        if video:
            sinks.append(video)
        bar = progress(source.length, "surface", args.quiet)

        def emit(num, img, state) -> None:
            V = state.info["mesh"]
            if kymo is not None:
                stab.add(img, stabilising_transform(tracker.grid, V - tracker.V0, roi, tracker.mesh_model))
                raw.add(img)
            out._write(f"{num}," + ",".join(f"{v:.3f}" for v in V.ravel()))
            if video:
                canvas = img
                if texture is not None and not state.lost:
                    grid, V0, Vs, rho, pgrid, model = tracker.surface_mesh()
                    canvas = retexture(img, texture, box, V0, Vs, grid.triangles(), rho, pgrid, model)
                video.write(draw_mesh(canvas, V, tracker.grid, lost=state.lost))
            bar.update(1)

        done, lost_frames = follow_frames(number, frame, frames, lambda f: tracker.init(f, box), tracker.update, emit)
    except KeyboardInterrupt:
        raise Interrupted(f"interrupted; rows so far are in {args.out}") from None
    finally:
        close_all(bar, sinks, source)
        if kymo is not None:      # what was computed, also after an interruption
            _write_png(args.kymogram, stab.image())
            if args.kymogram_raw:
                _write_png(args.kymogram_raw, raw.image())
    print(f"mesh {cols}x{rows} through {done} frames ({lost_frames} lost) -> {args.out}", file=sys.stderr)
    if kymo is not None:
        print(f"kymogram of {done} frames -> {args.kymogram}", file=sys.stderr)
    return 0


def _kymogram_options(args, box):
    """``((p0, p1), roi)`` of the kymogram options, checked (one-line errors), or None without ``--kymogram``."""
    from ..errors import ParameterError
    from ..events.geometry import parse_polyline
    from ..geometry import parse_box
    from ..io.sinks import prepare_output

    if not args.kymogram:
        for opt in ("scanline", "roi", "kymogram_raw"):
            if getattr(args, opt):
                raise ParameterError(f"--{opt.replace('_', '-')} needs --kymogram")
        return None
    if not args.scanline:
        raise ParameterError("--kymogram needs --scanline X1,Y1;X2,Y2")
    try:
        line = parse_polyline(args.scanline)
    except ValueError as exc:
        raise ParameterError(f"--scanline: {exc}") from None
    if len(line) != 2:
        raise ParameterError("--scanline: one segment X1,Y1;X2,Y2")
    roi = parse_box(args.roi) if args.roi else box
    prepare_output(args.kymogram)
    if args.kymogram_raw:
        prepare_output(args.kymogram_raw)
    return (line[0], line[1]), roi


def _write_png(path, image) -> None:
    import cv2

    if image.size:
        cv2.imwrite(str(path), image)


def read_mesh_csv(path) -> tuple[np.ndarray, np.ndarray]:
    """``(frames, vertices (T, K, 2))`` of a mesh CSV written by ``pftrack surface``."""
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return data[:, 0].astype(int), data[:, 1:].reshape(len(data), -1, 2)
