"""``pftrack synth``: seeded synthetic scenes with exact ground truth, written as OTB (or other) folders."""

from __future__ import annotations

import sys
from pathlib import Path

from .common import counted, parse_seeds


#: Scenes whose length is free (a target wandering, nothing timed): ``pftrack synth KIND --length N``.
LENGTH_SCENES = ("simple", "varied")


def add_synth(sub) -> None:
    from ..synth import SCENES
    from ..synth.photo import PHOTO_SCENES
    from ..synth.varied import DRAWN_NUISANCE_SCENES

    p = sub.add_parser("synth", help="write seeded synthetic scenes with exact ground truth as OTB folders",
                       description="Write synthetic scenes (exact ground truth) as OTB sequence folders, e.g. to "
                                   "evaluate trackers on them with 'pftrack eval'.")
    p.add_argument("kind", choices=sorted(SCENES) + ["occluder", "stereo-rail", "traffic-dense", "traffic-sparse",
                                                             "twocam", "walkers", "xray", "deform", "kymo", "face",
                                                             *PHOTO_SCENES],
                   help="scene generator; 'xray' warps the grey frame given with --source by a known motion (book "
                        "ch. 14); 'occluder' (points behind a bar: img/, points_gt.csv) and 'stereo-rail' (left/, "
                        "right/, calib.json, stereo_gt.csv) are the point-tracking scenes of book ch. 7; "
                        "'traffic-sparse' and 'traffic-dense' (MOTChallenge folders with wire.txt) are the tripwire "
                        "scenes of book ch. 10, and 'walkers' (the same layout) has upright walkers crossing a ground "
                        "line seen obliquely; 'twocam' cuts the MOTChallenge sequence given with --source into two "
                        "cameras with disjoint views and a seeded colour response (cam_a/, cam_b/, identity.csv; book "
                        "ch. 11); 'deform' is a deforming textured sheet under changing shading (img/, mesh_gt.csv "
                        "of a 7x7 mesh, shading_gt.csv, box.txt; book ch. 13); 'kymo' is a sheet under camera "
                        "jitter with a patch vibrating inside it (img/, box.txt, roi.txt, scanline.txt, truth.json; "
                        "the stabilised kymogram of book ch. 13); 'face' is a grey face under a dimming light, a "
                        "drifting lamp and a sweeping shadow, seen by a panning and zooming camera (built from "
                        "scikit-image's portrait); "
                        "'photo-vanish', 'photo-leave' and 'photo-exit' cut everything from photographs (a target "
                        "that walks behind an opaque band, out of the view and back, or out in a flow of look-alikes, "
                        "among hue-turned look-alikes: a scene family independent of the others, "
                        "pftrack.synth.photo; needs scikit-image)")
    p.add_argument("--source", help="xray: the grey image to warp (an angiography frame); twocam: a MOTChallenge "
                                    "sequence folder")
    p.add_argument("--response", choices=["mild", "strong"], default="mild",
                   help="twocam: camera B's colour response ('strong': wider gamma, gain and offset; a stress test)")
    p.add_argument("--frames", metavar="FIRST-LAST",
                   help="twocam: the source's frames to use (default all; docs/handover.md uses 1-200 and 201-400)")
    p.add_argument("--strip", metavar="X[,WIDTH]",
                   help="twocam: the blind strip between the cameras starts at pixel X and is WIDTH pixels wide "
                        "(default: at 44 %% of the frame's width, 12 %% wide: 340,90 on PETS 2009)")
    p.add_argument("--turn", type=float, default=0.0, metavar="DEGREES",
                   help="face: the face turns back and forth up to this angle (a rough stand-in; default 0: it "
                        "does not turn)")
    p.add_argument("--live", action="store_true",
                   help="face: the head moves in front of a still room (another photograph), seen by a camera whose "
                        "automatic gain amplifies the noise of the dark frames (pftrack.synth.face_live)")
    p.add_argument("--portrait", choices=["astronaut", "camera"], default="astronaut",
                   help="face: scikit-image's portrait to build the scene from (default astronaut; camera: the "
                        "cameraman, a face in profile beside a dark coat)")
    p.add_argument("--fine", action="store_true",
                   help="deform: bumps 0.4 times as wide and up to ~6 px, finer than a 7x7 mesh's cells (the scenes "
                        "of the dense model's comparison, docs/surfaces.md)")
    p.add_argument("--seeds", default="0-9", help="seeds, e.g. 0-9 or 1,4,7 (default 0-9)")
    p.add_argument("--out", required=True, help="output folder (one sub-folder per seed)")
    p.add_argument("--gray", type=float, default=None, metavar="P",
                   help="probability that a scene is grey (the scenes with drawn nuisances: "
                        f"{', '.join(DRAWN_NUISANCE_SCENES + tuple(PHOTO_SCENES))}; default 0.3). The other nuisances "
                        "of a seed stay the same, so --gray 1 gives each seed's scene in grey")
    p.add_argument("--length", type=int, default=None, metavar="N",
                   help=f"frames per scene of {', '.join(LENGTH_SCENES)} (default: the generator's; a long scene "
                        "shows slow drift, docs/robustness.md)")
    p.set_defaults(func=cmd_synth)


def _twocam_ranges(args) -> tuple[tuple[int, int] | None, tuple[int, int] | None]:
    """``--frames FIRST-LAST`` and ``--strip X[,WIDTH]`` of ``pftrack synth twocam`` (None: the defaults)."""
    from ..errors import ParameterError
    from ..io.datasets import read_sequence
    from ..synth.twocam import check_frames, default_split

    if args.kind != "twocam":
        if args.frames or args.strip:
            raise ParameterError("--frames and --strip apply to twocam scenes")
        return None, None
    numbers = split = None
    seq = read_sequence(args.source)
    if args.frames:
        try:
            a, b = (int(v) for v in args.frames.split("-"))
        except ValueError:
            raise ParameterError(f"--frames must look like 1-200, got {args.frames!r}") from None
        numbers = (a, b)
        try:
            check_frames(numbers, len(seq.frames))
        except ValueError as e:
            raise ParameterError(f"--{e}") from None
    if args.strip:
        try:
            vals = [float(v) for v in args.strip.split(",")]
            if len(vals) > 2:
                raise ValueError
        except ValueError:
            raise ParameterError(f"--strip must look like 340 or 340,90, got {args.strip!r}") from None
        width = seq.size[0] if seq.size else None
        if width is None:
            from ..io.sources import read_image

            width = read_image(seq.frames[0]).shape[1]
        try:
            split = default_split(width, vals[0], vals[1] if len(vals) > 1 else None)
        except ValueError as e:
            raise ParameterError(f"--strip: {e}") from None
    return numbers, split


def cmd_synth(args) -> int:
    from ..errors import ParameterError
    from ..io.sinks import prepare_output
    from ..synth import SCENES, export_otb
    from ..synth.photo import PHOTO_SCENES
    from ..synth.varied import DRAWN_NUISANCE_SCENES

    try:
        seeds = parse_seeds(args.seeds)
    except ValueError:
        raise ParameterError(f"--seeds must look like 0-9 or 1,4,7 (integers >= 0), got {args.seeds!r}") from None
    out = Path(args.out)
    image = None
    draw = {}
    drawn = DRAWN_NUISANCE_SCENES + tuple(PHOTO_SCENES)
    if args.gray is not None:
        if args.kind not in drawn:
            raise ParameterError(f"--gray applies to the scenes {', '.join(drawn)}, not {args.kind!r}")
        if not 0.0 <= args.gray <= 1.0:
            raise ParameterError(f"--gray is a probability in [0, 1], got {args.gray}")
        draw["gray"] = args.gray
    if args.length is not None:
        if args.kind not in LENGTH_SCENES:
            raise ParameterError(f"--length applies to the scenes {', '.join(LENGTH_SCENES)}, not {args.kind!r}")
        if args.length < 2:
            raise ParameterError(f"--length must be at least 2 frames, got {args.length}")
        draw["n_frames"] = args.length
    if args.kind == "twocam":
        from ..errors import SourceError
        from ..io.datasets import detect_layout

        if not args.source:
            raise ParameterError("twocam scenes need --source SEQUENCE (a MOTChallenge folder with ground truth)")
        if detect_layout(Path(args.source)) != "mot":
            raise SourceError(f"{args.source}: not a MOTChallenge folder")
    numbers, split = _twocam_ranges(args)
    if args.fine and args.kind != "deform":
        raise ParameterError("--fine applies to deform scenes")
    if args.kind == "xray":
        from .common import image_file

        if not args.source:
            raise ParameterError("xray scenes need --source IMAGE (the grey frame to warp)")
        image = image_file(args.source)
    if args.kind == "face":
        from ..synth.face import portrait

        try:
            face_image, face_box = portrait(args.portrait)  # loaded once for every seed
        except ImportError as e:
            raise ParameterError(str(e)) from None
    if args.kind in PHOTO_SCENES:
        from ..synth.photo import photo

        try:
            photo("astronaut")  # scikit-image present, before any folder is written
        except ImportError as e:
            raise ParameterError(str(e)) from None
    prepare_output(out / "README.txt")
    for sd in seeds:
        if image is not None:
            from ..synth.xray import export_xray

            export_xray(image, out / f"xray-{sd:03d}", sd)
        elif args.kind == "occluder":
            from ..synth.occluder import export_point_scene, occluder_scene

            export_point_scene(occluder_scene(sd), out / f"occluder-{sd:03d}")
        elif args.kind == "twocam":
            from ..synth.twocam import export_twocam, twocam_scene

            export_twocam(twocam_scene(args.source, sd, response=args.response, numbers=numbers, split=split),
                          out / f"twocam-{sd:03d}")
        elif args.kind == "walkers":
            from ..synth.walkers import export_walkers, walkers_scene

            export_walkers(walkers_scene(sd), out / f"walkers-{sd:03d}")
        elif args.kind.startswith("traffic-"):
            from ..synth.traffic import export_traffic, traffic_scene

            export_traffic(traffic_scene(sd, kind=args.kind.split("-", 1)[1]), out / f"{args.kind}-{sd:03d}")
        elif args.kind == "deform":
            from ..synth.deform import FINE, deform_scene, export_deform

            export_deform(deform_scene(sd, **(FINE if args.fine else {})),
                          out / f"deform-{'fine-' if args.fine else ''}{sd:03d}")
        elif args.kind == "kymo":
            from ..synth.deform import export_kymo, kymo_scene

            export_kymo(kymo_scene(sd), out / f"kymo-{sd:03d}")
        elif args.kind == "face":
            from ..synth.face import export_face, face_scene
            from ..synth.face_live import live_face_scene

            scene = live_face_scene if args.live else face_scene
            export_face(*scene(sd, image=face_image, face=face_box, turn=args.turn),
                        out / f"{'live-face' if args.live else 'face'}-{sd:03d}")
        elif args.kind in PHOTO_SCENES:
            from ..synth.photo import export_photo

            export_photo(PHOTO_SCENES[args.kind](sd, **draw), out / f"{args.kind}-{sd:03d}")
        elif args.kind == "stereo-rail":
            from ..synth.occluder import export_stereo_scene, stereo_rail_scene

            export_stereo_scene(stereo_rail_scene(sd), out / f"stereo-rail-{sd:03d}")
        else:
            export_otb(SCENES[args.kind](sd, **draw), out / f"{args.kind}-{sd:03d}")
    (out / "README.txt").write_text(f"Synthetic '{args.kind}' scenes, seeds {args.seeds}, written by pftrack synth.\n",
                                    encoding="utf-8")
    print(f"wrote {counted(len(seeds), 'sequence')} of '{args.kind}' to {out}", file=sys.stderr)
    return 0
