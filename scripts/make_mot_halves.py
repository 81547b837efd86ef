"""PETS 2009 S2.L1's two halves as MOTChallenge folders renumbered from 1 (docs/mot.md).

    python scripts/make_mot_halves.py [--data ../shared/data] [--out reports/mot_halves]
    pftrack eval reports/mot_halves/pets_tune --protocol mot --trackers "multi-pf,multi-pf[bootstrap_frames=56]" \
        --seeds 3 --workers 2 --report reports/mot_halves/tune

``OUT/pets_tune/pets_tune`` holds frames 1-200 and ``OUT/pets_report/pets_report`` frames 201-400, each as
``img1/`` (links to the dataset's frames), ``gt/gt.txt`` (the annotation of those frames, renumbered) and
``seqinfo.ini``: each half is tracked from a fresh start, as a recording that begins there. scripts/grey_foreground.py
writes grey copies the same way (:func:`write_halves` with a conversion). With ``--dim G`` the halves are written as
from a dark, noisy camera under the prefix ``dark`` (every frame times G plus Gaussian noise of ``--noise SD``
levels, seeded; as scripts/make_variants.py --dim). With ``--cast S`` they are written under the prefix ``castS``
(``cast0.2``) with a white balance that jumps at each half's frame 67 of 200: blue times 1 - S and red times 1 + S
from there on, a warm cast, as scripts/make_variants.py --cast. With ``--light G`` (prefix ``lightG``) every channel
is multiplied by G from that frame on: lamps switched on (G > 1) or off (G < 1). ``--grey`` converts the frames to
grey first (one channel, as scripts/grey_foreground.py; prefix ``grey``, ``greylightG`` with ``--light``): a grey
camera whose lamps switch.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from pftrack.io.datasets import write_mot_groundtruth, write_seqinfo

HALVES = {"tune": (1, 200), "report": (201, 400)}


def write_halves(pets: Path, out: Path, *, prefix: str = "pets", convert=None,
                 indexed: bool = False) -> dict[str, Path]:
    """The two halves under ``OUT/PREFIX_HALF/PREFIX_HALF``: frames linked (``convert`` None), or written as PNG
    after ``convert(frame)`` (e.g. a grey conversion; ``convert(frame, i)`` with ``indexed``, ``i`` counted from 0
    within the half); their folder per half."""
    import cv2

    gt = np.loadtxt(pets / "gt" / "gt.txt", delimiter=",", ndmin=2)
    folders = {}
    ext = ".jpg" if convert is None else ".png"
    for half, (lo, hi) in HALVES.items():
        d = out / f"{prefix}_{half}" / f"{prefix}_{half}"
        (d / "img1").mkdir(parents=True, exist_ok=True)
        (d / "gt").mkdir(exist_ok=True)
        for n in range(lo, hi + 1):
            src, dst = pets / "img1" / f"{n:06d}.jpg", d / "img1" / f"{n - lo + 1:06d}{ext}"
            if convert is not None:
                img = cv2.imread(str(src))
                cv2.imwrite(str(dst), convert(img, n - lo) if indexed else convert(img))
            elif not dst.exists():
                os.symlink(os.path.relpath(src.resolve(), dst.parent.resolve()), dst)
        rows = gt[(gt[:, 0] >= lo) & (gt[:, 0] <= hi)].copy()
        rows[:, 0] -= lo - 1
        write_mot_groundtruth(d / "gt" / "gt.txt", rows)
        write_seqinfo(d, name=d.name, fps=7, length=hi - lo + 1, width=768, height=576, ext=ext)
        folders[half] = d.parent
    return folders


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default="../shared/data")
    ap.add_argument("--out", default="reports/mot_halves")
    ap.add_argument("--dim", type=float, metavar="G", help="dark, noisy copies (prefix 'dark'): frames times G")
    ap.add_argument("--noise", type=float, default=3.0, metavar="SD", help="--dim's noise in grey levels (3)")
    ap.add_argument("--cast", type=float, metavar="S", help="copies whose white balance jumps (prefix castS): blue "
                    "and red times 1 -/+ S from each half's frame 67 on")
    ap.add_argument("--light", type=float, metavar="G", help="copies whose light jumps (prefix lightG): every "
                    "channel times G from each half's frame 67 on")
    ap.add_argument("--grey", action="store_true", help="grey copies (prefix grey): the frames converted to grey "
                    "first, with --light or --dim applied after")
    args = ap.parse_args()
    convert, prefix, indexed = None, "pets", False
    if sum(a is not None for a in (args.dim, args.cast, args.light)) > 1:
        ap.error("--dim, --cast and --light write different copies: give one")
    if args.grey and args.cast is not None:
        ap.error("--cast is a white balance: a grey copy has none")
    if args.cast is not None or args.light is not None:
        if args.cast is not None and not 0 < args.cast < 1:
            ap.error(f"--cast must be in (0, 1), got {args.cast}")
        if args.light is not None and not 0 < args.light <= 4:
            ap.error(f"--light must be in (0, 4], got {args.light}")
        gains = (np.array([1.0 - args.cast, 1.0, 1.0 + args.cast], np.float32) if args.cast is not None
                 else np.full(3, args.light, np.float32))
        start = 200 // 3

        def convert(frame, i):
            if i < start:
                return frame
            g = gains if frame.ndim == 3 else gains[1]  # a grey frame: --light's common gain
            return np.clip(np.rint(frame.astype(np.float32) * g), 0, 255).astype(np.uint8)

        prefix = f"cast{args.cast:g}" if args.cast is not None else f"light{args.light:g}"
        indexed = True
    if args.dim is not None:
        if not 0 < args.dim <= 1 or args.noise < 0:
            ap.error(f"--dim must be in (0, 1] and --noise at least 0, got {args.dim} and {args.noise}")
        rng = np.random.default_rng(5)

        def convert(frame):
            x = frame.astype(np.float32) * args.dim + rng.normal(0, args.noise, frame.shape).astype(np.float32)
            return np.clip(np.rint(x), 0, 255).astype(np.uint8)

        prefix = "dark"
    if args.grey:
        import cv2

        inner = convert

        def convert(frame, *i):
            g = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
            return g if inner is None else inner(g, *i)

        prefix = "grey" if prefix == "pets" else "grey" + prefix
    for half, folder in write_halves(Path(args.data) / "pets09_s2l1_dev", Path(args.out), prefix=prefix,
                                     convert=convert, indexed=indexed).items():
        print(f"{half}: {folder}")


if __name__ == "__main__":
    main()
