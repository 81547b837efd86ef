"""Angiography-like sequences with exact ground truth: a real frame warped by a known motion (book ch. 14).

The chapter tracks an artery segment through a cine whose heart motion moves it by tens of
pixels while the contrast medium fills and washes out.  Real cines carry no per-frame truth, so
:func:`warped_sequence` makes one from a single grey frame, drawing from the seed:

* a smooth periodic translation (a "heart cycle" of 12-25 frames, amplitude up to ``amplitude``
  px, two harmonics per axis, plus a slow drift);
* a contrast drift: the vessels' darkness relative to the background (the deviation of each
  pixel from a heavily smoothed copy) is scaled by a factor that rises and falls over the
  sequence (0.5 to 1.1), as the contrast arrives and washes out;
* a global gain drift and Gaussian noise.

Ground truth: the displacement of every frame, hence the exact box of any region of the source
frame.  :func:`structured_box` picks a region with structure (the chapter: segments without
characteristic details fail).
"""

from __future__ import annotations

import math

import cv2
import numpy as np


def _motion(rng: np.random.Generator, n: int, amplitude: float) -> np.ndarray:
    t = np.arange(n, dtype=np.float64)
    period = float(rng.uniform(12, 25))
    out = np.zeros((n, 2))
    for axis in range(2):
        a1, a2 = rng.uniform(0.4, 1.0) * amplitude, rng.uniform(0.0, 0.3) * amplitude
        p1, p2 = rng.uniform(0, 2 * math.pi, 2)
        drift = rng.uniform(-0.1, 0.1) * amplitude / max(n, 1)
        out[:, axis] = a1 * np.sin(2 * math.pi * t / period + p1) + a2 * np.sin(4 * math.pi * t / period + p2) \
            + drift * t
    return out - out[0]  # the first frame is the source frame itself


def warped_sequence(image: np.ndarray, seed: int = 0, *, n_frames: int = 50, amplitude: float = 20.0,
                    noise: float = 4.0) -> tuple[list[np.ndarray], np.ndarray]:
    """Frames (grey uint8) and the per-frame displacement ``(n_frames, 2)`` as ``(dx, dy)`` of the content."""
    rng = np.random.default_rng([seed, 140])
    g = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    g = g.astype(np.float32)
    smooth = cv2.GaussianBlur(g, (0, 0), 15.0)
    detail = g - smooth
    shifts = _motion(rng, n_frames, amplitude)
    t = np.linspace(0.0, 1.0, n_frames)
    c_lo, c_hi = float(rng.uniform(0.5, 0.7)), float(rng.uniform(0.9, 1.1))
    contrast = c_lo + (c_hi - c_lo) * np.sin(math.pi * t) ** 2 if rng.random() < 0.5 else \
        c_hi - (c_hi - c_lo) * np.sin(math.pi * t) ** 2
    contrast[0] = 1.0
    gain = 1.0 + rng.uniform(-0.15, 0.15) * np.sin(2 * math.pi * t * rng.uniform(0.5, 1.5))
    gain[0] = 1.0
    frames = []
    h, w = g.shape
    for k in range(n_frames):
        img = (smooth + contrast[k] * detail) * gain[k]
        m = np.float32([[1, 0, shifts[k, 0]], [0, 1, shifts[k, 1]]])
        warped = cv2.warpAffine(img, m, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        if k > 0 and noise > 0:
            warped = warped + rng.normal(0.0, noise, warped.shape).astype(np.float32)
        frames.append(np.clip(warped + 0.5, 0, 255).astype(np.uint8))
    return frames, shifts


def structured_box(image: np.ndarray, size: int = 32, *, margin: int = 60) -> tuple[float, float, float, float]:
    """The ``size`` x ``size`` window (at least ``margin`` px from the border) with the largest grey-level spread."""
    g = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    g = g.astype(np.float64)
    mean = cv2.boxFilter(g, -1, (size, size), normalize=True, borderType=cv2.BORDER_REFLECT)
    sq = cv2.boxFilter(g * g, -1, (size, size), normalize=True, borderType=cv2.BORDER_REFLECT)
    var = sq - mean * mean
    h, w = g.shape
    inner = np.full_like(var, -1.0)
    inner[margin + size // 2:h - margin - size // 2, margin + size // 2:w - margin - size // 2] = \
        var[margin + size // 2:h - margin - size // 2, margin + size // 2:w - margin - size // 2]
    cy, cx = np.unravel_index(int(np.argmax(inner)), inner.shape)
    return (float(cx - size // 2), float(cy - size // 2), float(size), float(size))


def export_xray(image: np.ndarray, folder, seed: int, *, n_frames: int = 50, amplitude: float = 20.0,
                noise: float = 4.0, size: int = 32) -> None:
    """Write a warped sequence as an OTB folder: ``img/``, ``groundtruth_rect.txt`` (the box of the most
    structured ``size`` x ``size`` region, moved by the known motion) and ``meta.json``."""
    import json
    from pathlib import Path

    folder = Path(folder)
    (folder / "img").mkdir(parents=True, exist_ok=True)
    frames, shifts = warped_sequence(image, seed, n_frames=n_frames, amplitude=amplitude, noise=noise)
    box = structured_box(image, size)
    for k, f in enumerate(frames):
        cv2.imwrite(str(folder / "img" / f"{k + 1:04d}.png"), f)
    rows = [f"{box[0] + dx:.3f},{box[1] + dy:.3f},{box[2]:.3f},{box[3]:.3f}" for dx, dy in shifts]
    (folder / "groundtruth_rect.txt").write_text("\n".join(rows) + "\n", encoding="utf-8")
    meta = {"kind": "xray", "seed": seed, "hidden": [], "amplitude": amplitude, "noise": noise,
            "shifts": [[round(float(a), 4), round(float(b), 4)] for a, b in shifts]}
    (folder / "meta.json").write_text(json.dumps(meta) + "\n", encoding="utf-8")
