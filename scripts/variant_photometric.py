"""The photometric copies of ``make_variants.py`` (a dark, noisy camera with lamps or a settling exposure, haze, a
white balance that jumps), and what every copy shares: its frames as JPEG and its ground truth."""

from __future__ import annotations

import shutil
import zlib
from pathlib import Path

import cv2
import numpy as np

from pftrack.io.datasets import write_groundtruth


def write_jpeg(dest: Path, i: int, img: np.ndarray) -> None:
    """Frame ``i`` (from 0) of the OTB folder ``dest`` as JPEG 92: ``img`` as it is when 8-bit, else its levels
    rounded and clipped to 0-255."""
    if img.dtype != np.uint8:
        img = np.clip(np.rint(img), 0, 255).astype(np.uint8)
    cv2.imwrite(str(dest / "img" / f"{i + 1:04d}.jpg"), img, [cv2.IMWRITE_JPEG_QUALITY, 92])


def copy_truth(seq, dest: Path, scale: float = 1.0, stride: int = 1) -> None:
    """The ground truth (times ``scale``, every ``stride``-th row from the first) and attribution of ``seq`` into
    the OTB folder ``dest``."""
    gt = seq.groundtruth[::stride]
    write_groundtruth(dest / "groundtruth_rect.txt", gt if scale == 1.0 else gt * scale)
    for extra in ("ATTRIBUTION.md", "provenance.json"):
        if (seq.path / extra).is_file():
            shutil.copy(seq.path / extra, dest / extra)


def lamp_field(h: int, w: int, k: int, name: str, boxes: np.ndarray | None = None) -> np.ndarray:
    """``(h, w, 3)`` light added by ``k`` lamps of a ``--lamps`` copy (street lamps at night): each a glow of level
    up to 2 x 255 (a saturated core) with a radius of 2 % of the frame's diagonal, warm or white, at a place drawn from
    the sequence name where it lies over the target's box (``boxes``, x y w h per frame) on at most 10 % of the
    frames."""
    rng = np.random.default_rng(zlib.crc32(f"{name}#lamps".encode()))
    r = 0.02 * float(np.hypot(h, w))
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    out = np.zeros((h, w, 3), np.float32)
    gt = None if boxes is None else np.asarray(boxes, dtype=np.float64)
    for _ in range(k):
        for _attempt in range(200):
            cx, cy = rng.uniform(0, w), rng.uniform(0, h)
            if gt is None or not len(gt):
                break
            near = ((gt[:, 0] - 2 * r < cx) & (cx < gt[:, 0] + gt[:, 2] + 2 * r) & (gt[:, 1] - 2 * r < cy)
                    & (cy < gt[:, 1] + gt[:, 3] + 2 * r))
            if near.mean() <= 0.1:
                break
        colour = np.array([0.55, 0.8, 1.0] if rng.random() < 0.5 else [1.0, 1.0, 1.0], np.float32)
        glow = 2.0 * 255.0 * np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2) / (r * r))
        out += glow[..., None] * colour
    return out


def ramp_gain(i: int, gain: float, ramp: int) -> float:
    """The gain of frame ``i`` (from 0) of a ``--dim G --ramp N`` copy: ``G`` on the first frame, rising linearly to 1
    at frame ``N`` and staying there; ``G`` throughout without a ramp (``N = 0``)."""
    return gain if ramp <= 0 else gain + (1.0 - gain) * min(1.0, i / ramp)


def write_dim(seq, dest: Path, gain: float, noise: float, lamps: int = 0, ramp: int = 0) -> None:
    """``seq``'s colour frames times ``gain`` plus Gaussian noise of ``noise`` levels (a dark, noisy camera), and the
    light of ``lamps`` street lamps (:func:`lamp_field`), as an OTB folder; with ``ramp`` the gain rises to 1 over
    that many frames (:func:`ramp_gain`)."""
    (dest / "img").mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(zlib.crc32(f"{seq.name}#dim".encode()))
    light = None
    for i, path in enumerate(seq.frames):
        img = cv2.imread(str(path), cv2.IMREAD_COLOR).astype(np.float32) * ramp_gain(i, gain, ramp)
        if lamps:
            if light is None:
                light = lamp_field(img.shape[0], img.shape[1], lamps, seq.name, seq.groundtruth)
            img += light
        img += rng.normal(0.0, noise, img.shape).astype(np.float32)
        write_jpeg(dest, i, img)
    copy_truth(seq, dest)


def airlight(name: str) -> np.ndarray:
    """The haze's colour (B, G, R levels) for the sequence ``name``: a bright grey with a slight blue cast, each
    channel drawn from the name in [215, 245] and ordered B >= G >= R."""
    rng = np.random.default_rng(zlib.crc32(f"{name}#haze".encode()))
    return np.sort(rng.uniform(215.0, 245.0, 3))[::-1].astype(np.float32)


def write_hazy(seq, dest: Path, haze: float, noise: float) -> None:
    """``seq``'s colour frames seen through a uniform haze: ``(1 - haze)`` times the frame plus ``haze`` times the
    :func:`airlight`, plus Gaussian noise of ``noise`` levels (drawn from the name), as an OTB folder."""
    (dest / "img").mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(zlib.crc32(f"{seq.name}#hazenoise".encode()))
    veil = haze * airlight(seq.name)
    for i, path in enumerate(seq.frames):
        img = cv2.imread(str(path), cv2.IMREAD_COLOR).astype(np.float32) * (1.0 - haze) + veil
        img += rng.normal(0.0, noise, img.shape).astype(np.float32)
        write_jpeg(dest, i, img)
    copy_truth(seq, dest)


def cast_gains(name: str, strength: float) -> np.ndarray:
    """The ``--cast`` copy's channel gains (B, G, R) for the sequence ``name``: a warm cast (B ``1 - S``,
    R ``1 + S``) or a cool one (the reverse), drawn from the name; green unchanged."""
    warm = np.random.default_rng(zlib.crc32(f"{name}#cast".encode())).random() < 0.5
    s = strength if warm else -strength
    return np.array([1.0 - s, 1.0, 1.0 + s], np.float32)


def write_cast(seq, dest: Path, strength: float, *, gains: np.ndarray | None = None) -> None:
    """``seq``'s colour frames with the :func:`cast_gains` (or ``gains``, B, G, R) applied from frame floor(n/3)
    (from 0) on, as an OTB folder: a white balance that jumps a third of the way through (or lamps switched)."""
    (dest / "img").mkdir(parents=True, exist_ok=True)
    gains = cast_gains(seq.name, strength) if gains is None else np.asarray(gains, np.float32)
    start = len(seq.frames) // 3
    for i, path in enumerate(seq.frames):
        img = cv2.imread(str(path), cv2.IMREAD_COLOR).astype(np.float32) * (gains if i >= start else 1.0)
        write_jpeg(dest, i, img)
    copy_truth(seq, dest)


if __name__ == "__main__":
    raise SystemExit("variant_photometric.py is a module of make_variants.py: run "
                     "`python scripts/make_variants.py --help`")
