"""Upright walkers crossing a ground line seen obliquely, with exact tracks (tripwire tests, book ch. 10).

The chapter's scenes are vehicles seen from above; pedestrian surveillance sees upright people, whose
head reaches the far side of a ground line long before their feet do. Each seeded scene draws:

* textured ground with a soft brightness gradient;
* 8–13 walkers, each a textured figure (head, torso and legs of seeded colours) 45–85 px tall and
  about 0.3 of that wide, walking a straight path across the view at 1.5–4 px per frame in a seeded
  direction, a soft shadow at its feet, entering at a seeded frame; nearer (lower) walkers are drawn
  over farther ones;
* one wire through the middle of the view: horizontal, vertical or oblique (seeded).

The boxes are exact. Ground-truth crossings come from the boxes' foot points
(:func:`pftrack.events.eval.track_crossings`, ``point="foot"``), as for the PETS lines.
:func:`export_walkers` writes a MOTChallenge folder with ``wire.txt`` (like ``pftrack synth traffic-*``).
"""

from __future__ import annotations

import cv2
import numpy as np

from .occluder import paste_sprite
from .traffic import TrafficScene, export_traffic

__all__ = ["export_walkers", "walkers_scene"]


def _walker_sprite(rng, h: int) -> np.ndarray:
    w = max(8, int(round(0.3 * h)))
    img = np.empty((h, w, 3), np.float32)
    head, torso = int(0.18 * h), int(0.55 * h)
    skin = rng.uniform((60, 90, 130), (140, 170, 220))
    top = rng.uniform(20, 235, 3)
    legs = rng.uniform(20, 200, 3)
    img[:head], img[head:torso], img[torso:] = skin, top, legs
    img += rng.normal(0, 12, (h, w, 1)).astype(np.float32)       # cloth texture
    img[:, : max(1, w // 6)] *= 0.85                              # shading at the sides
    img[:, w - max(1, w // 6):] *= 0.85
    return np.clip(img, 0, 255)


def _path(rng, shape, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """A straight path of the foot point across the view: start, unit direction."""
    h, w = shape
    ang = rng.uniform(0, 2 * np.pi)
    d = np.array([np.cos(ang), np.sin(ang)])
    centre = np.array([rng.uniform(0.3, 0.7) * w, rng.uniform(0.45, 0.8) * h])
    # back up from a point in the middle until outside the view
    t = 0.0
    while True:
        p = centre - t * d
        if p[0] < -margin or p[0] > w + margin or p[1] < -margin or p[1] > h + margin:
            return p, d
        t += 2.0


def walkers_scene(seed: int = 0, *, shape=(240, 320), n_frames: int = 200, fps: float = 10.0,
                  wire: str | None = None) -> TrafficScene:
    """One seeded scene (frames, MOT rows of every walker's box, the wire; see the module docstring).
    ``wire``: ``"horizontal"``, ``"vertical"`` or ``"oblique"`` (default: seeded)."""
    rng = np.random.default_rng(seed)
    h, w = shape
    kind = wire or ["horizontal", "vertical", "oblique"][int(rng.integers(0, 3))]
    cx, cy = w * rng.uniform(0.4, 0.6), h * rng.uniform(0.5, 0.65)
    if kind == "horizontal":
        line = np.array([[0.1 * w, cy], [0.9 * w, cy]])
    elif kind == "vertical":
        line = np.array([[cx, 0.25 * h], [cx, 0.95 * h]])
    else:
        a = rng.uniform(np.pi / 8, 3 * np.pi / 8) * rng.choice([-1, 1])
        half = 0.4 * min(w, h) / max(abs(np.cos(a)), abs(np.sin(a))) * 0.8
        line = np.array([[cx - half * np.cos(a), cy - half * np.sin(a)],
                         [cx + half * np.cos(a), cy + half * np.sin(a)]])
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    g = rng.uniform(-0.25, 0.25, 2)
    bg = np.clip(rng.normal(110, 10, (h, w, 3)), 0, 255).astype(np.float32)
    bg = cv2.GaussianBlur(bg, (0, 0), 1.0)
    bg *= (1.0 + g[0] * (xx / w - 0.5) + g[1] * (yy / h - 0.5))[:, :, None]
    walkers = []
    for k in range(int(rng.integers(8, 14))):
        height = int(rng.integers(45, 86))
        start, d = _path(rng, shape, margin=0.4 * height)
        walkers.append({"id": k + 1, "sprite": _walker_sprite(rng, height), "p": start, "v": d * rng.uniform(1.5, 4.0),
                        "t0": int(rng.integers(0, max(1, n_frames - 60)))})
    frames, rows = [], []
    for t in range(n_frames):
        canvas = bg.copy()
        live = [wk for wk in walkers if t >= wk["t0"]]
        for wk in sorted(live, key=lambda wk: wk["p"][1] + wk["v"][1] * (t - wk["t0"])):
            foot = wk["p"] + wk["v"] * (t - wk["t0"])
            sh, sw = wk["sprite"].shape[:2]
            x0, y0 = foot[0] - sw / 2, foot[1] - sh
            if x0 > w or x0 + sw < 0 or y0 > h or y0 + sh < 0:
                continue
            cv2.ellipse(canvas, (int(round(foot[0] + 0.2 * sw)), int(round(foot[1]))),
                        (int(0.6 * sw), max(2, sh // 14)),
                        0, 0, 360, tuple(float(c) * 0.7 for c in bg[min(h - 1, max(0, int(foot[1]))),
                                                                     min(w - 1, max(0, int(foot[0])))]), -1)
            paste_sprite(canvas, wk["sprite"], float(x0), float(y0))
            bx0, by0 = max(0.0, x0), max(0.0, y0)
            bx1, by1 = min(float(w), x0 + sw), min(float(h), y0 + sh)
            if bx1 - bx0 >= 0.5 * sw and by1 - by0 >= 0.5 * sh:
                rows.append([t + 1, wk["id"], x0, y0, sw, sh, 1, -1, -1, -1])
        frames.append(np.clip(canvas + rng.normal(0, 2.0, canvas.shape), 0, 255).astype(np.uint8))
    meta = {"kind": "walkers", "wire": kind, "seed": seed, "walkers": len(walkers), "fps": fps}
    return TrafficScene(frames, np.asarray(rows, dtype=np.float64).reshape(-1, 10), line, fps, meta)


def export_walkers(scene: TrafficScene, folder) -> None:
    """A MOTChallenge folder plus ``wire.txt`` and ``meta.json`` (as :func:`~.traffic.export_traffic`)."""
    export_traffic(scene, folder)
