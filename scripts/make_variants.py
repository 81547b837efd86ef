"""Write grey and grey + illumination-change copies of OTB-layout sequences (for the tune/report experiments).

    python scripts/make_variants.py ../shared/data/otb_crossing ../shared/data/otb_couple --out variants/

For each sequence two folders are written next to each other in ``--out``:

* ``NAME-gray``: every frame converted to grey (a monochrome camera);
* ``NAME-gray-light``: grey, with a strong smooth illumination change: a global gain that
  falls from 1.0 to 0.4 and back over the sequence, times a bright spot that drifts across the
  frame (a lamp), seeded by the sequence name.

With ``--light-seeds A-B`` only grey + illumination copies are written, one per seed K, named
``NAME-gray-light-sK``: the same kind of light with a lamp drawn afresh from the sequence name and K (fresh
draws of the lighting that no choice was made on; without the option the lamp is drawn from the name alone).

With ``--h264 CRF`` a third folder, ``NAME-h264``, holds the colour frames encoded as H.264 at that constant rate
factor (libx264, in memory) and decoded again, saved as PNG: a recorder's file instead of clean frames (needs
PyAV, the ``mv`` extra).

With ``--switch`` four copies are written instead, whose input switches between colour and grey mid-sequence (as a
camera that turns to monochrome at dusk; docs/rules/input_switch_rule.txt), with n frames:

* ``NAME-switch-after``: colour, grey from frame floor(n/3)+1 to the end (frame numbers from 1);
* ``NAME-switch-before``: grey up to frame floor(n/3), colour after it;
* ``NAME-switch-block``: colour, grey for frames floor(n/3)+1 .. floor(2n/3);
* ``NAME-switch-random``: colour, each frame after the first grey with probability 0.2 (seeded by the name).

With ``--scale F`` one copy is written instead, ``NAME-xF``: every colour frame resized by the factor F (area
averaging when shrinking, bilinear when enlarging; JPEG quality 92) and the ground truth scaled with it, for the
same targets at another resolution (a smaller or a larger target in pixels).

With ``--stride K`` one copy is written instead, ``NAME-sK``: frames 1, 1 + K, 1 + 2K, ... of the sequence with
their ground truth rows, for the same targets at a K times lower frame rate (K times the motion between frames).
The frames are copied as they are, not re-encoded; a ``meta.json`` goes along with its frame numbers (``hidden``,
``unannotated``) renumbered and its per-frame lists taken at the kept frames.

With ``--shake PX`` one copy is written instead, ``NAME-shakePX``: each frame is the original cut by PX pixels on
every side and moved by up to PX pixels along each axis (integer offsets drawn per frame from the sequence name; none
on the first frame), as a hand-held camera shakes, with the ground truth moved alike (NaN where a box falls wholly
outside the cut). JPEG quality 92.

With ``--blur PX`` one copy is written instead, ``NAME-blurPX``: every frame after the first is, with probability 1/2,
smeared by a straight motion-blur kernel (a line of length drawn in [PX/2, PX] pixels at an angle drawn in [0, 180)
degrees; both drawn per frame from the sequence name), as a camera that jerks or a target that darts now and then.
JPEG quality 92.

With ``--dim G`` one copy is written instead, ``NAME-dimG-noiseSD``: every colour frame times the gain G, plus
Gaussian noise of standard deviation SD grey levels on each pixel and channel (``--noise SD``, default 3; drawn from
the sequence name), rounded and clipped: a camera at night without gain, whose colours crowd into the bottom
levels. JPEG quality 92. With ``--lamps K`` as well (``NAME-dimG-noiseSD-lampsK``), K street lamps light the scene:
fixed glows with a saturated core, 2 % of the frame's diagonal in radius, warm or white, placed away from the
target's path (drawn from the name). With ``--ramp N`` (``NAME-dimG-noiseSD-rampN``) the gain rises linearly from G on
the first frame to 1 at frame N + 1: a camera whose exposure settles, or lights coming on.

With ``--haze H`` one copy is written instead, ``NAME-hazeH-noiseSD``: every colour frame seen through a uniform
haze, ``(1 - H)`` times the frame plus ``H`` times a bright, slightly bluish airlight (each channel in [215, 245],
drawn from the name), plus the noise of ``--noise``; fog, smoke, a dirty or misted lens, glare on a window. The
levels crowd into the top part of the range with their contrast cut to ``1 - H``. JPEG quality 92.

With ``--cast S`` one copy is written instead, ``NAME-castS``: from frame floor(n/3)+1 (frame numbers from 1) to the
end, the blue and red channels times ``1 - S`` and ``1 + S`` (a warm cast) or the reverse (a cool one; drawn from the
name), green as it is: a camera's automatic white balance that jumps, or daylight giving way to lamps. JPEG 92.
With ``--light G`` one copy ``NAME-lightG``: from the same frame on every channel times G (lamps switched on, G > 1,
or off, G < 1), levels clipped at 255.

With ``--zoom Z`` one copy is written instead, ``NAME-zoomZ``: a camera that zooms steadily about the first frame's
target centre, so that the target's size changes Z times over the sequence (Z > 1: zooming in, from the full view
to a Z times magnified one; Z < 1: zooming out, from a 1/Z times magnified view to the full one). Frame i shows the
view magnified m_i times, m_i geometric between the two ends, cut where it lies in the frame and resampled
bilinearly to the frame's size (JPEG quality 92); the ground truth goes through the same map (NaN where a box falls
wholly outside the view). A zoom is a change of scale that every target of the sequence undergoes at once.

Ground truth (``groundtruth_rect.txt``) is copied unchanged, but for ``--scale``, ``--stride``, ``--shake`` and
``--zoom``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import zlib
from pathlib import Path

import cv2
import numpy as np

from pftrack.cli.common import parse_seeds
from pftrack.io.codec import h264_round_trip
from pftrack.io.datasets import read_sequence, write_groundtruth
from pftrack.io.sequence import read_meta

sys.path.insert(0, str(Path(__file__).resolve().parent))
from variant_photometric import (airlight, cast_gains, copy_truth, lamp_field, ramp_gain, write_cast,  # noqa: E402,F401
                                 write_dim, write_hazy, write_jpeg)


def light_field(t: float, h: int, w: int, rng_seed: int) -> np.ndarray:
    rng = np.random.default_rng(rng_seed)
    x0, y0 = rng.uniform(0, w), rng.uniform(0, h)
    x1, y1 = rng.uniform(0, w), rng.uniform(0, h)
    cx, cy = x0 + (x1 - x0) * t, y0 + (y1 - y0) * t
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    r2 = ((xx - cx) ** 2 + (yy - cy) ** 2) / (0.35 * max(h, w)) ** 2
    gain = 1.0 - 0.6 * np.sin(np.pi * t)  # 1 -> 0.4 -> 1
    return (gain * (0.55 + 0.9 * np.exp(-r2))).astype(np.float32)


def write_h264(seq, dest: Path, crf: int) -> None:
    """``seq``'s colour frames through an H.264 encoder at ``crf``, as PNG frames of an OTB folder."""
    (dest / "img").mkdir(parents=True, exist_ok=True)
    frames = h264_round_trip([cv2.imread(str(p), cv2.IMREAD_COLOR) for p in seq.frames], crf, fps=seq.fps or 25.0)
    for i, f in enumerate(frames):
        cv2.imwrite(str(dest / "img" / f"{i + 1:04d}.png"), f)
    copy_truth(seq, dest)


def write_scaled(seq, dest: Path, factor: float) -> None:
    """``seq``'s colour frames resized by ``factor``, with its ground truth scaled alike, as an OTB folder."""
    (dest / "img").mkdir(parents=True, exist_ok=True)
    interp = cv2.INTER_AREA if factor < 1 else cv2.INTER_LINEAR
    for i, path in enumerate(seq.frames):
        img = cv2.resize(cv2.imread(str(path), cv2.IMREAD_COLOR), None, fx=factor, fy=factor, interpolation=interp)
        write_jpeg(dest, i, img)
    copy_truth(seq, dest, factor)


def write_strided(seq, dest: Path, stride: int) -> int:
    """Every ``stride``-th frame of ``seq`` from the first, copied as it is and numbered afresh, with its ground truth
    rows, as an OTB folder; returns the number of frames written."""
    (dest / "img").mkdir(parents=True, exist_ok=True)
    kept = seq.frames[::stride]
    for i, path in enumerate(kept):
        shutil.copy(path, dest / "img" / f"{i + 1:04d}{Path(path).suffix.lower()}")
    copy_truth(seq, dest, stride=stride)
    meta = read_meta(seq.path)
    if meta:  # frame numbers (from 1) of the kept frames renumbered, per-frame lists taken at the kept frames
        for key in ("hidden", "unannotated"):
            if key in meta:
                meta[key] = [(k - 1) // stride + 1 for k in meta[key] if (k - 1) % stride == 0]
        for key, value in meta.items():
            if isinstance(value, list) and len(value) == len(seq.frames) and key not in ("hidden", "unannotated"):
                meta[key] = value[::stride]
        (dest / "meta.json").write_text(json.dumps(meta) + "\n", encoding="utf-8")
    return len(kept)


def shake_offsets(n: int, px: int, name: str) -> np.ndarray:
    """``(n, 2)`` integer offsets ``(dx, dy)`` in ``[-px, px]`` of a ``--shake`` copy, drawn from the sequence name;
    the first frame's is ``(0, 0)``."""
    off = np.random.default_rng(zlib.crc32(f"{name}#shake".encode())).integers(-px, px + 1, size=(n, 2))
    off[0] = 0
    return off


def write_shaken(seq, dest: Path, px: int) -> None:
    """``seq``'s colour frames cut by ``px`` on every side at a per-frame offset (a shaking camera), with the ground
    truth moved alike, as an OTB folder."""
    (dest / "img").mkdir(parents=True, exist_ok=True)
    off = shake_offsets(len(seq.frames), px, seq.name)
    h = w = 0
    for i, path in enumerate(seq.frames):
        img = cv2.imread(str(path), cv2.IMREAD_COLOR)
        h, w = img.shape[:2]
        x0, y0 = px + off[i, 0], px + off[i, 1]
        write_jpeg(dest, i, img[y0:h - 2 * px + y0, x0:w - 2 * px + x0])
    gt = np.array(seq.groundtruth, dtype=np.float64)
    m = min(len(gt), len(off))
    gt[:m, 0] -= px + off[:m, 0]
    gt[:m, 1] -= px + off[:m, 1]
    if len(seq.frames):  # the frames' size, as read above (one size for the whole sequence)
        out = (gt[:, 0] + gt[:, 2] <= 0) | (gt[:, 1] + gt[:, 3] <= 0) | (gt[:, 0] >= w - 2 * px) | \
              (gt[:, 1] >= h - 2 * px)
        gt[out] = np.nan
    write_groundtruth(dest / "groundtruth_rect.txt", gt)
    for extra in ("ATTRIBUTION.md", "provenance.json", "meta.json"):
        if (seq.path / extra).is_file():
            shutil.copy(seq.path / extra, dest / extra)


def zoom_views(n: int, zoom: float, centre: tuple[float, float], size: tuple[int, int]) -> np.ndarray:
    """``(n, 3)`` rows ``(m, x0, y0)`` of a ``--zoom`` copy: frame i shows the original's pixels ``(x, y)`` at
    ``((x - x0) m, (y - y0) m)``; ``m`` geometric from 1 to ``zoom`` (from ``1 / zoom`` to 1 when ``zoom < 1``), the
    view of ``w / m`` by ``h / m`` pixels centred on ``centre`` and moved inside the frame of ``size = (w, h)``."""
    w, h = size
    lo, hi = (1.0, zoom) if zoom >= 1 else (1.0 / zoom, 1.0)
    m = lo * (hi / lo) ** (np.arange(n) / max(n - 1, 1))
    x0 = np.clip(centre[0] - w / (2 * m), 0.0, w - w / m)
    y0 = np.clip(centre[1] - h / (2 * m), 0.0, h - h / m)
    return np.stack([m, x0, y0], axis=1)


def write_zoomed(seq, dest: Path, zoom: float) -> None:
    """``seq``'s colour frames seen through a steady zoom (:func:`zoom_views`) about the first frame's target centre,
    with the ground truth mapped alike, as an OTB folder."""
    (dest / "img").mkdir(parents=True, exist_ok=True)
    gt = np.array(seq.groundtruth, dtype=np.float64)
    first = gt[np.isfinite(gt).all(axis=1)]
    h, w = cv2.imread(str(seq.frames[0]), cv2.IMREAD_COLOR).shape[:2]
    centre = (first[0, 0] + first[0, 2] / 2, first[0, 1] + first[0, 3] / 2) if len(first) else (w / 2, h / 2)
    views = zoom_views(len(seq.frames), zoom, centre, (w, h))
    for i, path in enumerate(seq.frames):
        m, x0, y0 = views[i]
        # output pixel centre u shows the original at x0 + (u + 0.5) / m - 0.5 (pixel centres at integers)
        a = np.array([[m, 0.0, (0.5 - x0) * m - 0.5], [0.0, m, (0.5 - y0) * m - 0.5]])
        img = cv2.warpAffine(cv2.imread(str(path), cv2.IMREAD_COLOR), a, (w, h), flags=cv2.INTER_LINEAR,
                             borderMode=cv2.BORDER_REPLICATE)
        write_jpeg(dest, i, img)
    k = min(len(gt), len(views))
    m, x0, y0 = views[:k, 0], views[:k, 1], views[:k, 2]
    gt[:k, 0] = (gt[:k, 0] - x0) * m
    gt[:k, 1] = (gt[:k, 1] - y0) * m
    gt[:k, 2:4] *= m[:, None]
    out = (gt[:, 0] + gt[:, 2] <= 0) | (gt[:, 1] + gt[:, 3] <= 0) | (gt[:, 0] >= w) | (gt[:, 1] >= h)
    gt[out] = np.nan
    write_groundtruth(dest / "groundtruth_rect.txt", gt)
    for extra in ("ATTRIBUTION.md", "provenance.json", "meta.json"):
        if (seq.path / extra).is_file():
            shutil.copy(seq.path / extra, dest / extra)


def blur_kernels(n: int, px: int, name: str) -> list[np.ndarray | None]:
    """The ``--blur`` copy's kernel for each of ``n`` frames (``None``: the frame is kept sharp; never the first): a
    normalised line of length in [px/2, px] at an angle in [0, 180) degrees, drawn from the sequence name."""
    rng = np.random.default_rng(zlib.crc32(f"{name}#blur".encode()))
    draws = rng.random((n, 3))
    kernels: list[np.ndarray | None] = []
    for i, (u, v, a) in enumerate(draws):
        if i == 0 or u >= 0.5:
            kernels.append(None)
            continue
        length = max(2, int(round(px / 2 + v * (px - px / 2))))
        size = 2 * (int(np.ceil((length - 1) / 2)) + 1) + 1  # odd, with a margin: the line's middle is the centre
        c = (size - 1) / 2
        d = np.array([np.cos(np.pi * a), np.sin(np.pi * a)])
        yy, xx = np.mgrid[0:size, 0:size].astype(np.float64) - c
        along = np.clip(xx * d[0] + yy * d[1], -(length - 1) / 2, (length - 1) / 2)
        dist = np.hypot(xx - along * d[0], yy - along * d[1])  # to the segment of length - 1 through the centre
        k = np.maximum(0.0, 1.0 - dist).astype(np.float32)  # an anti-aliased line one pixel wide
        kernels.append(k / k.sum())
    return kernels


def write_blurred(seq, dest: Path, px: int) -> int:
    """``seq``'s colour frames, about half of them motion-blurred (``blur_kernels``), as an OTB folder; returns the
    number of blurred frames."""
    (dest / "img").mkdir(parents=True, exist_ok=True)
    kernels = blur_kernels(len(seq.frames), px, seq.name)
    for i, path in enumerate(seq.frames):
        img = cv2.imread(str(path), cv2.IMREAD_COLOR)
        if kernels[i] is not None:
            img = cv2.filter2D(img, -1, kernels[i], borderType=cv2.BORDER_REFLECT)
        write_jpeg(dest, i, img)
    copy_truth(seq, dest)
    return sum(k is not None for k in kernels)


SWITCH_KINDS = ("after", "before", "block", "random")


def switch_grey_frames(kind: str, n: int, name: str) -> np.ndarray:
    """Which of ``n`` frames (from index 0) a ``--switch`` copy of kind ``kind`` turns grey."""
    i = np.arange(n)
    third, two_thirds = n // 3, (2 * n) // 3
    if kind == "after":
        return i >= third
    if kind == "before":
        return i < third
    if kind == "block":
        return (i >= third) & (i < two_thirds)
    if kind == "random":
        grey = np.random.default_rng(zlib.crc32(f"{name}#switch".encode())).random(n) < 0.2
        grey[0] = False
        return grey
    raise ValueError(f"unknown switch kind {kind!r}")


def write_switch(seq, out: Path) -> list[str]:
    """The four ``--switch`` copies of ``seq`` in ``out``; returns their names."""
    n = len(seq.frames)
    names = []
    for kind in SWITCH_KINDS:
        grey = switch_grey_frames(kind, n, seq.name)
        dest = out / f"{seq.name}-switch-{kind}"
        (dest / "img").mkdir(parents=True, exist_ok=True)
        for i, path in enumerate(seq.frames):
            img = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE if grey[i] else cv2.IMREAD_COLOR)
            write_jpeg(dest, i, img)
        copy_truth(seq, dest)
        names.append(dest.name)
    return names


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sequences", nargs="+")
    ap.add_argument("--out", required=True)
    ap.add_argument("--h264", type=int, metavar="CRF", help="only the H.264 copies (NAME-h264), at this CRF")
    ap.add_argument("--switch", action="store_true", help="only the copies whose input switches between colour "
                    "and grey mid-sequence (NAME-switch-after, -before, -block, -random)")
    ap.add_argument("--light-seeds", metavar="A-B", help="only grey + illumination copies, one per seed "
                    "(NAME-gray-light-sK, the lamp drawn afresh)")
    ap.add_argument("--scale", type=float, metavar="F", help="only a copy resized by the factor F (NAME-xF), "
                    "its ground truth scaled alike")
    ap.add_argument("--shake", type=int, metavar="PX", help="only a copy seen by a shaking camera (NAME-shakePX): "
                    "cut by PX on every side and moved by up to PX each frame")
    ap.add_argument("--stride", type=int, metavar="K", help="only a copy of every K-th frame (NAME-sK), a K times "
                    "lower frame rate")
    ap.add_argument("--blur", type=int, metavar="PX", help="only a copy with about half its frames motion-blurred "
                    "(NAME-blurPX), by lines of PX/2 to PX pixels")
    ap.add_argument("--dim", type=float, metavar="G", help="only a dark, noisy copy (NAME-dimG-noiseSD): the frames "
                    "times G plus Gaussian noise (--noise)")
    ap.add_argument("--haze", type=float, metavar="H", help="only a hazy copy (NAME-hazeH-noiseSD): the frames "
                    "times 1 - H plus H times a bright, bluish airlight, plus Gaussian noise (--noise)")
    ap.add_argument("--noise", type=float, default=3.0, metavar="SD", help="the --dim or --haze copy's noise, in "
                    "grey levels (default 3)")
    ap.add_argument("--lamps", type=int, default=0, metavar="K", help="the --dim copy lit by K street lamps "
                    "(NAME-dimG-noiseSD-lampsK; default 0)")
    ap.add_argument("--ramp", type=int, default=0, metavar="N", help="the --dim copy's gain rises from G to 1 over "
                    "the first N frames (NAME-dimG-noiseSD-rampN; default 0: no ramp)")
    ap.add_argument("--cast", type=float, metavar="S", help="only a copy whose white balance jumps a third of the "
                    "way through (NAME-castS): blue and red times 1 -/+ S, warm or cool")
    ap.add_argument("--light", type=float, metavar="G", help="only a copy whose light jumps a third of the way "
                    "through (NAME-lightG): every channel times G")
    ap.add_argument("--zoom", type=float, metavar="Z", help="only a copy through a steady zoom (NAME-zoomZ) that "
                    "changes the target's size Z times over the sequence (Z > 1 in, Z < 1 out)")
    args = ap.parse_args()
    if args.zoom is not None and not (0.25 <= args.zoom <= 4 and args.zoom != 1):
        ap.error(f"--zoom must be a factor in [0.25, 4] other than 1, got {args.zoom}")
    if args.blur is not None and args.blur < 2:
        ap.error(f"--blur must be a whole number of pixels of at least 2, got {args.blur}")
    if args.dim is not None and not 0 < args.dim <= 1:
        ap.error(f"--dim must be a gain in (0, 1], got {args.dim}")
    if args.haze is not None and not 0 < args.haze < 1:
        ap.error(f"--haze must be a fraction in (0, 1), got {args.haze}")
    if args.cast is not None and not 0 < args.cast <= 0.6:
        ap.error(f"--cast must be a strength in (0, 0.6], got {args.cast}")
    if args.light is not None and not (0.25 <= args.light <= 4 and args.light != 1):
        ap.error(f"--light must be a gain in [0.25, 4] other than 1, got {args.light}")
    if args.haze is not None and args.dim is not None:
        ap.error("--haze and --dim write different copies: give one")
    if not args.noise >= 0:
        ap.error(f"--noise must be at least 0, got {args.noise}")
    if args.lamps < 0 or (args.lamps and args.dim is None):
        ap.error(f"--lamps must be a whole number of at least 0, with --dim, got {args.lamps}")
    if args.ramp < 0 or (args.ramp and args.dim is None):
        ap.error(f"--ramp must be a whole number of at least 0, with --dim, got {args.ramp}")
    if args.scale is not None and not args.scale > 0:
        ap.error(f"--scale must be a positive factor, got {args.scale}")
    if args.shake is not None and args.shake < 1:
        ap.error(f"--shake must be a whole number of pixels of at least 1, got {args.shake}")
    if args.stride is not None and args.stride < 1:
        ap.error(f"--stride must be a whole number of at least 1, got {args.stride}")
    light_seeds = parse_seeds(args.light_seeds) if args.light_seeds else None
    out = Path(args.out)
    for spec in args.sequences:
        seq = read_sequence(spec)
        n = len(seq.frames)
        seed = zlib.crc32(seq.name.encode())
        if args.switch:
            print(f"{seq.name}: {n} frames -> " + ", ".join(f"{out}/{v}" for v in write_switch(seq, out)))
            continue
        if args.scale is not None:
            write_scaled(seq, out / f"{seq.name}-x{args.scale:g}", args.scale)
            print(f"{seq.name}: {n} frames -> {out}/{seq.name}-x{args.scale:g}")
            continue
        if args.zoom is not None:
            write_zoomed(seq, out / f"{seq.name}-zoom{args.zoom:g}", args.zoom)
            print(f"{seq.name}: {n} frames -> {out}/{seq.name}-zoom{args.zoom:g}")
            continue
        if args.shake is not None:
            write_shaken(seq, out / f"{seq.name}-shake{args.shake}", args.shake)
            print(f"{seq.name}: {n} frames -> {out}/{seq.name}-shake{args.shake}")
            continue
        if args.blur is not None:
            blurred = write_blurred(seq, out / f"{seq.name}-blur{args.blur}", args.blur)
            print(f"{seq.name}: {n} frames ({blurred} blurred) -> {out}/{seq.name}-blur{args.blur}")
            continue
        if args.dim is not None:
            name = (f"{seq.name}-dim{args.dim:g}-noise{args.noise:g}" + (f"-lamps{args.lamps}" if args.lamps else "")
                    + (f"-ramp{args.ramp}" if args.ramp else ""))
            write_dim(seq, out / name, args.dim, args.noise, args.lamps, args.ramp)
            print(f"{seq.name}: {n} frames -> {out}/{name}")
            continue
        if args.haze is not None:
            name = f"{seq.name}-haze{args.haze:g}-noise{args.noise:g}"
            write_hazy(seq, out / name, args.haze, args.noise)
            print(f"{seq.name}: {n} frames -> {out}/{name}")
            continue
        if args.cast is not None:
            write_cast(seq, out / f"{seq.name}-cast{args.cast:g}", args.cast)
            print(f"{seq.name}: {n} frames -> {out}/{seq.name}-cast{args.cast:g}")
            continue
        if args.light is not None:
            write_cast(seq, out / f"{seq.name}-light{args.light:g}", 0.0, gains=np.full(3, args.light))
            print(f"{seq.name}: {n} frames -> {out}/{seq.name}-light{args.light:g}")
            continue
        if args.stride is not None:
            kept = write_strided(seq, out / f"{seq.name}-s{args.stride}", args.stride)
            print(f"{seq.name}: {kept} of {n} frames -> {out}/{seq.name}-s{args.stride}")
            continue
        if args.h264 is not None:
            write_h264(seq, out / f"{seq.name}-h264", args.h264)
            print(f"{seq.name}: {n} frames -> {out}/{seq.name}-h264 (crf {args.h264})")
            continue
        variants = ([("gray", None), ("gray-light", seed)] if light_seeds is None else
                    [(f"gray-light-s{k}", zlib.crc32(f"{seq.name}#{k}".encode())) for k in light_seeds])
        for variant, lamp in variants:
            dest = out / f"{seq.name}-{variant}"
            (dest / "img").mkdir(parents=True, exist_ok=True)
            for i, path in enumerate(seq.frames):
                img = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
                if lamp is not None:
                    f = light_field(i / max(n - 1, 1), img.shape[0], img.shape[1], lamp)
                    img = np.clip(img.astype(np.float32) * f, 0, 255).astype(np.uint8)
                write_jpeg(dest, i, img)
            copy_truth(seq, dest)
        print(f"{seq.name}: {n} frames -> " + ", ".join(f"{out}/{seq.name}-{v}" for v, _ in variants))


if __name__ == "__main__":
    main()
