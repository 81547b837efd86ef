"""A grey face under strong illumination change, built from a real portrait (seeded, exact ground truth).

Grey face sequences with changing light are a standard test of trackers, and none is among the development data.
:func:`face_scene` makes a stand-in from scikit-image's ``astronaut`` portrait (NASA, public domain; scikit-image
is in the ``dev`` extra), or from any grey image and face box given:

* the image is seen through a camera that pans and zooms (0.8-1.2x) along a seeded smooth path, in 320 x 240
  frames, so the face moves and changes size in the frame;
* the frames are lit by a global gain that falls to 0.35 and comes back (seeded timing), a lamp drifting across
  the frame (as ``scripts/make_variants.py``'s), and a soft shadow edge sweeping across the view at a seeded angle
  (one side at 40 %);
* Gaussian noise (std 2 grey levels).

The face box is carried through the camera's motion: exact in every frame.  The face does not change expression,
and by default it does not turn, so the scene measures a tracker's tolerance of the light, not of pose.  With
``turn`` (degrees) the face region turns about a vertical axis, back and forth along a seeded smooth path up to that
angle: the region is drawn as a cylinder seen turned (:func:`turned_face`), one side foreshortened and the other
widened, a rough stand-in for a head that turns.  Its box stays the face box.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

#: x, y, w, h of the face and hair in the 512 x 512 ``astronaut`` portrait
ASTRONAUT_FACE = (170.0, 40.0, 112.0, 140.0)
#: x, y, w, h of the head (hair, face in profile, collar) in scikit-image's 512 x 512 ``camera`` photograph: a man
#: in a dark coat behind a video camera, outdoors (the head beside a dark coat, a bright sky and the camera)
CAMERA_FACE = (152.0, 62.0, 112.0, 136.0)
OUT_W, OUT_H = 320, 240


def _skimage_data():
    try:
        from skimage import data
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("the face scenes use scikit-image's portraits: pip install scikit-image "
                          "(or the 'dev' extra)") from e
    return data


def astronaut_grey() -> np.ndarray:
    """scikit-image's ``astronaut`` portrait in grey (needs scikit-image)."""
    return cv2.cvtColor(_skimage_data().astronaut()[:, :, ::-1].copy(), cv2.COLOR_BGR2GRAY)


def portrait(name: str = "astronaut") -> tuple[np.ndarray, tuple[float, float, float, float]]:
    """A grey portrait and its face box: ``astronaut`` (NASA, public domain; the default) or ``camera`` (the
    cameraman photograph of scikit-image's data, a second face for checking figures chosen on the first)."""
    if name == "astronaut":
        return astronaut_grey(), ASTRONAUT_FACE
    if name == "camera":
        return np.ascontiguousarray(_skimage_data().camera()), CAMERA_FACE
    raise ValueError(f"unknown portrait {name!r}: astronaut or camera")


def turned_face(base: np.ndarray, face: tuple[float, float, float, float], yaw: float) -> np.ndarray:
    """``base`` with the ``face`` box's pixels drawn as a vertical cylinder (its diameter the box's width) turned by
    ``yaw`` radians: the column at ``u`` in [-1, 1] across the box shows the surface point whose angle is
    ``asin(u) - yaw``, clamped to the visible half."""
    fx, fy, fw, fh = (int(round(v)) for v in face)
    out = base.copy()
    if yaw == 0.0 or fw < 2 or fh < 1:
        return out
    u = (np.arange(fw, dtype=np.float64) + 0.5) / fw * 2.0 - 1.0
    phi = np.clip(np.arcsin(np.clip(u, -1.0, 1.0)) - yaw, -np.pi / 2, np.pi / 2)
    src = (np.sin(phi) + 1.0) / 2.0 * fw - 0.5 + fx
    map_x = np.broadcast_to(src.astype(np.float32), (fh, fw)).copy()
    map_y = np.broadcast_to(np.arange(fy, fy + fh, dtype=np.float32)[:, None], (fh, fw)).copy()
    region = cv2.remap(base, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    out[fy:fy + fh, fx:fx + fw] = region
    return out


def face_scene(seed: int = 0, n_frames: int = 150, *, image: np.ndarray | None = None,
               face: tuple[float, float, float, float] = ASTRONAUT_FACE,
               turn: float = 0.0) -> tuple[list[np.ndarray], np.ndarray]:
    """Frames (grey uint8, 240 x 320) and the exact face boxes ``(n_frames, 4)`` of one seeded sequence; ``turn``:
    the largest angle, in degrees, the face turns to (0: it does not turn)."""
    rng = np.random.default_rng(seed)
    turn_rng = np.random.default_rng([seed, 7])  # its own draws: the scenes without a turn stay as they were
    tf, tp = turn_rng.uniform(0.5, 1.5), turn_rng.uniform(0, 2 * np.pi)
    base0 = (astronaut_grey() if image is None else image).astype(np.float32)
    base = base0
    fx, fy, fw, fh = (float(v) for v in face)
    f1, f2, f3 = rng.uniform(0.5, 1.5, 3)
    p1, p2, p3, p4 = rng.uniform(0, 2 * np.pi, 4)
    lamp0, lamp1 = rng.uniform((0, 0), (OUT_W, OUT_H)), rng.uniform((0, 0), (OUT_W, OUT_H))
    theta = rng.uniform(0, 2 * np.pi)
    dark_at = rng.uniform(0.3, 0.7)
    yy, xx = np.mgrid[0:OUT_H, 0:OUT_W].astype(np.float32)
    along = xx * np.cos(theta) + yy * np.sin(theta)
    lo, hi = float(along.min()), float(along.max())
    frames, boxes = [], []
    for k in range(n_frames):
        t = k / max(n_frames - 1, 1)
        if turn:
            base = turned_face(base0, face, np.radians(turn) * np.sin(2 * np.pi * tf * t + tp))
        s = 0.9 * (1.0 + 0.2 * np.sin(2 * np.pi * f3 * t + p3))  # image pixels -> frame pixels
        cx = fx + fw / 2 + 40 * np.sin(2 * np.pi * f1 * t + p1)  # the view's centre in the image
        cy = fy + fh / 2 + 20 * np.sin(2 * np.pi * f2 * t + p2) + 15
        m = np.array([[s, 0, OUT_W / 2 - s * cx], [0, s, OUT_H / 2 - s * cy]], dtype=np.float64)
        img = cv2.warpAffine(base, m, (OUT_W, OUT_H), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        gain = 1.0 - 0.65 * np.exp(-((t - dark_at) / 0.2) ** 2)
        lc = lamp0 + (lamp1 - lamp0) * t
        lamp = 0.55 + 0.9 * np.exp(-((xx - lc[0]) ** 2 + (yy - lc[1]) ** 2) / (0.35 * OUT_W) ** 2)
        edge = lo + (hi - lo) * (0.5 + 0.5 * np.sin(2 * np.pi * t + p4))
        shadow = 1.0 - 0.6 / (1.0 + np.exp(-(along - edge) / 10.0))
        img = img * gain * lamp * shadow + rng.normal(0, 2.0, img.shape)
        frames.append(np.clip(img, 0, 255).astype(np.uint8))
        boxes.append((s * fx + m[0, 2], s * fy + m[1, 2], s * fw, s * fh))
    return frames, np.array(boxes)


def export_face(frames: list[np.ndarray], boxes: np.ndarray, folder) -> Path:
    """Write a face scene as an OTB folder (``img/0001.png``..., ``groundtruth_rect.txt``)."""
    out = Path(folder)
    (out / "img").mkdir(parents=True, exist_ok=True)
    for i, f in enumerate(frames):
        cv2.imwrite(str(out / "img" / f"{i + 1:04d}.png"), f)
    np.savetxt(out / "groundtruth_rect.txt", boxes, fmt="%.2f", delimiter=",")
    return out
