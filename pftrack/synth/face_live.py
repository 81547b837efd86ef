"""A grey head moving in front of a still room, seen by a camera with automatic gain (seeded, exact ground truth).

:func:`~pftrack.synth.face.face_scene` pans one photograph: the face and its surroundings move together, and the
only noise is a constant 2 grey levels. Real grey face sequences under changing light differ in two ways that
matter to a tracker, and :func:`live_face_scene` adds both:

* **The head moves against the scene.** The portrait's head is cut out (an ellipse inscribed in its face box,
  feathered) and drawn over a backdrop that another photograph of scikit-image's data provides (``coffee``,
  ``rocket`` or ``motorcycle``, by seed), on its own smooth path across the frame, nearer and farther
  (0.75-1.25x), turning if asked. The backdrop pans slowly on its own (up to 20 px).
* **The camera's gain follows the light.** The scene is lit by a global light that dims to 10-25 % and comes back,
  a lamp drifting across the frame and a soft shadow edge sweeping across the view (as in ``face_scene``). The
  sensor adds shot noise (variance 0.6 times the signal) and read noise (2 levels), and an automatic gain brings
  the frame's mean back toward 110 grey levels with a lag (a quarter of the way each frame, at most 4x): in the
  dark frames the target keeps its mean level but the noise is amplified up to four times.

The box is the head's face box, carried through its motion: exact in every frame.
"""

from __future__ import annotations

import cv2
import numpy as np

from .face import ASTRONAUT_FACE, OUT_H, OUT_W, _skimage_data, astronaut_grey, turned_face

__all__ = ["BACKDROPS", "backdrop_image", "live_face_scene"]

#: scikit-image's photographs used as backdrops (a table with cups, a rocket outdoors, a motorcycle in a room)
BACKDROPS = ("coffee", "rocket", "motorcycle")


def backdrop_image(name: str) -> np.ndarray:
    """One of :data:`BACKDROPS` in grey (needs scikit-image)."""
    if name not in BACKDROPS:
        raise ValueError(f"unknown backdrop {name!r}: one of {', '.join(BACKDROPS)}")
    data = _skimage_data()
    rgb = data.stereo_motorcycle()[0] if name == "motorcycle" else getattr(data, name)()
    return cv2.cvtColor(np.ascontiguousarray(rgb[:, :, :3]), cv2.COLOR_RGB2GRAY)


def _head(image: np.ndarray, face: tuple[float, float, float, float], margin: int = 6
          ) -> tuple[np.ndarray, np.ndarray, tuple[float, float]]:
    """The head's pixels (float32), its alpha (the face box's inscribed ellipse, feathered) and the face box's
    top-left corner within that cut-out."""
    fx, fy, fw, fh = face
    x0, y0 = int(np.floor(fx)) - margin, int(np.floor(fy)) - margin
    x1, y1 = int(np.ceil(fx + fw)) + margin, int(np.ceil(fy + fh)) + margin
    padded = cv2.copyMakeBorder(image, margin, margin, margin, margin, cv2.BORDER_REFLECT)
    cut = padded[y0 + margin:y1 + margin, x0 + margin:x1 + margin].astype(np.float32)
    yy, xx = np.mgrid[y0:y1, x0:x1].astype(np.float32) + 0.5
    inside = (((xx - fx - fw / 2) / (fw / 2)) ** 2 + ((yy - fy - fh / 2) / (fh / 2)) ** 2 <= 1.0)
    alpha = cv2.GaussianBlur(inside.astype(np.float32), (0, 0), 1.5)
    return cut, alpha, (fx - x0, fy - y0)


def live_face_scene(seed: int = 0, n_frames: int = 150, *, image: np.ndarray | None = None,
                    face: tuple[float, float, float, float] = ASTRONAUT_FACE, turn: float = 0.0,
                    backdrop: np.ndarray | None = None) -> tuple[list[np.ndarray], np.ndarray]:
    """Frames (grey uint8, 240 x 320) and the exact face boxes ``(n_frames, 4)`` of one seeded sequence (see the
    module docstring); ``backdrop``: a grey image behind the head (default: one of :data:`BACKDROPS`, by seed)."""
    rng = np.random.default_rng([seed, 11])
    base0 = (astronaut_grey() if image is None else image).astype(np.float32)
    name = BACKDROPS[int(rng.integers(len(BACKDROPS)))]
    back = (backdrop_image(name) if backdrop is None else backdrop).astype(np.float32)
    cover = max(1.3 * OUT_W / back.shape[1], 1.3 * OUT_H / back.shape[0])
    back = cv2.resize(back, None, fx=cover, fy=cover, interpolation=cv2.INTER_AREA)
    fx, fy, fw, fh = (float(v) for v in face)
    s0 = rng.uniform(0.30, 0.42) * OUT_H / fh  # the face box 30-42 % of the frame's height at the mean distance
    f1, f2, f3, f4, f5 = rng.uniform(0.4, 1.2, 5)
    p1, p2, p3, p4, p5, p6, p7 = rng.uniform(0, 2 * np.pi, 7)
    ax, ay = rng.uniform(0.18, 0.28) * OUT_W, rng.uniform(0.08, 0.14) * OUT_H
    tf, tp = rng.uniform(0.5, 1.5), rng.uniform(0, 2 * np.pi)
    lamp0, lamp1 = rng.uniform((0, 0), (OUT_W, OUT_H)), rng.uniform((0, 0), (OUT_W, OUT_H))
    theta = rng.uniform(0, 2 * np.pi)
    dark_at, depth = rng.uniform(0.3, 0.7), rng.uniform(0.75, 0.9)
    yy, xx = np.mgrid[0:OUT_H, 0:OUT_W].astype(np.float32)
    along = xx * np.cos(theta) + yy * np.sin(theta)
    lo, hi = float(along.min()), float(along.max())
    bx_max, by_max = back.shape[1] - OUT_W, back.shape[0] - OUT_H
    agc = 1.0
    still = None if turn else _head(base0, (fx, fy, fw, fh))  # a head that does not turn is cut out once
    frames, boxes = [], []
    for k in range(n_frames):
        t = k / max(n_frames - 1, 1)
        # the backdrop pans slowly (up to 20 px), the head moves on its own path
        bx = int(round(bx_max / 2 + min(20, bx_max / 2) * np.sin(2 * np.pi * f4 * t + p4)))
        by = int(round(by_max / 2 + min(10, by_max / 2) * np.sin(2 * np.pi * f5 * t + p5)))
        scene = back[by:by + OUT_H, bx:bx + OUT_W].copy()
        if still is None:
            src = turned_face(base0, face, np.radians(turn) * np.sin(2 * np.pi * tf * t + tp))
            head, alpha, (ox, oy) = _head(src, (fx, fy, fw, fh))
        else:
            head, alpha, (ox, oy) = still
        s = s0 * (1.0 + 0.25 * np.sin(2 * np.pi * f3 * t + p3))
        cx = OUT_W / 2 + ax * np.sin(2 * np.pi * f1 * t + p1)
        cy = OUT_H / 2 + ay * np.sin(2 * np.pi * f2 * t + p2)
        box = (cx - s * fw / 2, cy - s * fh / 2, s * fw, s * fh)
        # head pixel (u, v) of the cut-out -> frame (box x + s (u - ox), box y + s (v - oy))
        m = np.array([[s, 0, box[0] - s * ox], [0, s, box[1] - s * oy]], dtype=np.float64)
        warped = cv2.warpAffine(head, m, (OUT_W, OUT_H), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
        a = cv2.warpAffine(alpha, m, (OUT_W, OUT_H), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
        scene = scene * (1.0 - a) + warped * a
        # the light: a global dimming, a drifting lamp, a sweeping shadow edge
        gain = 1.0 - depth * np.exp(-((t - dark_at) / 0.2) ** 2)
        lc = lamp0 + (lamp1 - lamp0) * t
        lamp = 0.55 + 0.9 * np.exp(-((xx - lc[0]) ** 2 + (yy - lc[1]) ** 2) / (0.35 * OUT_W) ** 2)
        edge = lo + (hi - lo) * (0.5 + 0.5 * np.sin(2 * np.pi * t + p6 + p7))
        shadow = 1.0 - 0.6 / (1.0 + np.exp(-(along - edge) / 10.0))
        signal = np.clip(scene * (gain * lamp * shadow), 0.0, None)
        # the sensor: shot and read noise, then the automatic gain (lagging, at most 4x)
        noisy = signal + rng.standard_normal(signal.shape).astype(np.float32) * np.sqrt(0.6 * signal + 4.0)
        agc += 0.25 * (float(np.clip(110.0 / max(float(signal.mean()), 1e-3), 1.0, 4.0)) - agc)
        frames.append(np.clip(agc * noisy, 0, 255).astype(np.uint8))
        boxes.append(box)
    return frames, np.array(boxes)
