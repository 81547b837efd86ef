"""``pftrack handover``: link people between two cameras with disjoint views (book ch. 11)."""

from __future__ import annotations

import sys

import numpy as np

from .common import counted, progress


def add_handover(sub) -> None:
    p = sub.add_parser("handover", help="link tracks of two cameras with disjoint views by appearance (book ch. 11)",
                       description="Each track gets a colour appearance; a brightness transfer function fitted on "
                                   "known correspondences (--train-pairs) brings camera A's colours into camera B's; "
                                   "a track that starts in one camera after a track of the other ended is linked to "
                                   "it one-to-one, or judged a new person. Writes track_a,track_b,similarity.")
    p.add_argument("cam_a", help="camera A: MOTChallenge folder, frame folder or video")
    p.add_argument("cam_b", help="camera B: MOTChallenge folder, frame folder or video")
    p.add_argument("--tracks-a", required=True, help="camera A tracks, MOTChallenge text (frame,id,x,y,w,h,...)")
    p.add_argument("--tracks-b", required=True, help="camera B tracks, MOTChallenge text")
    p.add_argument("--train-pairs", help="CSV track_a,track_b of known correspondences (fit the BTF; not linked)")
    p.add_argument("--btf", choices=["cbtf", "cbtf-pixels", "mbtf", "none"], default="cbtf",
                   help="transfer function (default cbtf: the training tracks' histograms pooled at equal weight; "
                        "cbtf-pixels pools raw pixel counts)")
    p.add_argument("--features", choices=["whole", "ellipse1", "ellipse2", "positional"], default="positional",
                   help="appearance: whole box, one or two ellipses, or 2 rings x 4 sectors (default positional)")
    p.add_argument("--histogram", choices=["marginal", "joint"], default="joint",
                   help="compare each region's joint (R, G, B) colours, carried through the BTF cell by cell "
                        "(default; a grey camera's tracks are compared channel by channel), or its three channels "
                        "one by one, as the chapter does (docs/handover.md)")
    p.add_argument("--foreground", choices=["mog2", "none"], default="mog2",
                   help="count only foreground pixels of each box (MOG2 over each camera), or all of them")
    p.add_argument("--new-threshold", default="auto",
                   help="similarity below which a probe is a new person: a number; 'auto' (default: the lower "
                        "quartile of the similarities of tracks seen at the same time in the two cameras, who are "
                        "different people; 'pairs' without such tracks); 'pairs' (the threshold that best separates "
                        "the training pairs from their impostors); or 'none'")
    p.add_argument("--transit", action="store_true",
                   help="also weigh each candidate by a log-normal transit-time model fitted on the training pairs "
                        "(helps where people cross the blind zone at a steady pace; it hurt on the PETS two-camera "
                        "scenes, whose walkers wander: see docs/handover.md)")
    p.add_argument("--out", default="links.csv", help="CSV output (default links.csv)")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_handover)


class _Forward:
    """Frames of a source by increasing number (each frame read once), with an optional MOG2 mask."""

    def __init__(self, source, foreground: bool):
        from ..cues.foreground import Foreground

        self._it = source.numbered()
        self._n, self._frame, self._fg = 0, None, None
        self._bgs = Foreground(500, 16.0) if foreground else None  # shadows are background (pftrack.cues.foreground)
        self._kernel = np.ones((3, 3), np.uint8)

    def _advance(self, n: int) -> None:
        import cv2

        while self._n < n:
            try:
                self._n, self._frame = next(self._it)
            except StopIteration:
                self._n, self._frame = 10 ** 12, None
                return
            if self._bgs is not None:
                self._fg = cv2.morphologyEx(self._bgs.apply(self._frame), cv2.MORPH_OPEN, self._kernel)

    def frame(self, n: int):
        self._advance(n)
        return self._frame if self._n == n else None

    def fg(self, n: int):
        self._advance(n)
        return self._fg if self._n == n else None


def read_pairs(path: str) -> list[tuple[int, int]]:
    from pathlib import Path

    from ..errors import FormatError, SourceError

    p = Path(path)
    if not p.is_file():
        raise SourceError(f"{path}: no such file")
    out = []
    for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1):
        line = line.strip()
        if not line or line.lower().startswith("track_a"):
            continue
        parts = [v for v in line.replace(";", ",").split(",") if v.strip()]
        try:
            a, b = (int(float(v)) for v in parts[:2])  # fewer than two values: ValueError too
        except ValueError:
            raise FormatError(f"{path}:{i}: expected track_a,track_b") from None
        out.append((a, b))
    return out


_TRANSIT_NEEDS_PAIRS = "--transit needs training pairs (--train-pairs) whose tracks follow each other in time"


def _fixed_threshold(text: str) -> float | None:
    """``--new-threshold``: its number (0 for ``none``), or None for ``auto`` and ``pairs``; ParameterError for
    anything else."""
    from ..errors import ParameterError

    if text in ("auto", "pairs"):
        return None
    if text == "none":
        return 0.0
    try:
        return float(text)
    except ValueError:
        raise ParameterError(f"--new-threshold must be a number, 'auto', 'pairs' or 'none', got {text!r}") from None


def cmd_handover(args) -> int:
    from ..errors import ParameterError
    from ..io.datasets import read_mot_txt
    from ..io.sinks import _TextSink, prepare_output
    from ..io.sources import open_source
    from ..multicam.handover import (
        cooccur_threshold,
        describe_tracks,
        fit_btf,
        fit_transit,
        link_tracks,
        new_threshold,
    )

    fixed_tau = _fixed_threshold(args.new_threshold)  # bad options are refused before the frames are read
    rows_a, rows_b = read_mot_txt(args.tracks_a), read_mot_txt(args.tracks_b)
    if len(rows_a) == 0 or len(rows_b) == 0:
        raise ParameterError("both cameras need at least one track")
    pairs = read_pairs(args.train_pairs) if args.train_pairs else []
    if args.transit and not pairs:
        raise ParameterError(_TRANSIT_NEEDS_PAIRS)
    ids_a, ids_b = set(rows_a[:, 1].astype(int)), set(rows_b[:, 1].astype(int))
    for a, b in pairs:
        if a not in ids_a or b not in ids_b:
            raise ParameterError(f"training pair {a},{b}: no such track in camera {'A' if a not in ids_a else 'B'}")
    prepare_output(args.out)
    apps = []
    for cam, rows in ((args.cam_a, rows_a), (args.cam_b, rows_b)):
        source = open_source(cam)
        try:
            fwd = _Forward(source, args.foreground == "mog2")
            bar = progress(None, f"appearance {cam}", args.quiet)
            apps.append(describe_tracks(fwd.frame, rows, args.features,
                                        fg=fwd.fg if args.foreground == "mog2" else None, histogram=args.histogram))
            bar.close()
        finally:
            source.close()
    app_a, app_b = apps
    lut = fit_btf(app_a, app_b, pairs, args.btf)
    tau = cooccur_threshold(app_a, app_b, lut) if args.new_threshold == "auto" else None
    if args.new_threshold == "pairs" or (args.new_threshold == "auto" and tau is None):
        tau = new_threshold(app_a, app_b, pairs, args.btf)
    elif fixed_tau is not None:
        tau = fixed_tau
    transit = fit_transit(app_a, app_b, pairs) if args.transit else None
    if args.transit and transit is None:
        raise ParameterError(_TRANSIT_NEEDS_PAIRS)
    links = link_tracks(app_a, app_b, lut, tau_new=tau, exclude_a=[a for a, _ in pairs],
                        exclude_b=[b for _, b in pairs], transit=transit)
    with _TextSink(args.out) as out:
        out._write("track_a,track_b,similarity")
        for a, b, s in links:
            out._write(f"{a},{b},{s:.5f}")
    print(f"{counted(len(links), 'link')} ({args.btf}, {args.features}, {args.histogram}, new below {tau:.3f}) -> "
          f"{args.out}",
          file=sys.stderr)
    return 0
