"""Scenes cut from photographs: a second, independent family for the lost flag (seeded, exact ground truth).

The scenes of :mod:`pftrack.synth.varied` draw every target as a two-coloured speckled ellipse over a synthetic
texture, and the defaults of the colour trackers were chosen on scenes of that style. A tracker may have learnt
the style rather than the task. These scenes share none of its drawing: everything in them is a piece of a real
photograph of scikit-image's data (public domain, CC0 or without known restrictions; see :data:`PHOTOS`).

* **Background.** A crop of one photograph, resized to 320 x 240, panned slowly by the camera in half the scenes.
* **Target.** A textured piece of another photograph (18-48 px wide, aspect 0.7-2.2), feathered to an ellipse or
  a rounded rectangle. It grows or shrinks by up to a fifth over the scene.
* **Look-alikes** (0-3). Copies of the target's piece with its hue turned by 4-15 degrees (of 180), saturation and
  brightness changed by up to a fifth and mirrored, or other pieces of the target's photograph; they wander over
  the frame and pass in front of the target.
* **Occluder** (``photo-vanish``). An opaque band cut from a third photograph or a tinted texture (brick, grass,
  gravel), wide enough to hide the target for 12-35 frames.
* **Light and camera.** In half the scenes a global gain drifts to 0.5-1.6 with unequal channels, in a third a
  lamp (a broad bright spot) drifts across the view; a third of the scenes are grey; sensor noise of 1.5-4
  levels, and JPEG compression (quality 55-90) in half of them.

Three kinds:

* :func:`photo_vanish_scene` — the target walks fully behind the occluder and comes out on the other side;
* :func:`photo_leave_scene` — the target walks out of the frame, stays out 15-40 frames and walks back in;
* :func:`photo_exit_scene` — the target walks out in a flow of look-alikes heading the same way, and comes back or a
  look-alike walks in instead.

The box is the target's piece, carried through its motion and scale; the visible fraction counts the occluder,
the look-alikes in front and the frame's edge. :func:`export_photo` writes the OTB folder with the ``meta.json``
``pftrack eval`` scores the lost flag by (:func:`pftrack.synth.scenes.write_otb_folder`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import cv2
import numpy as np

from .scenes import _wander, write_otb_folder
from .varied import exit_path, exit_walkers

__all__ = ["PHOTOS", "PhotoScene", "export_photo", "photo_exit_scene", "photo_leave_scene", "photo_vanish_scene",
           "render_photo"]

W, H = 320, 240
#: scikit-image's colour photographs the scenes are cut from, as its data module describes them (astronaut: NASA,
#: public domain; chelsea: Stefan van der Walt, CC0; coffee: Rachel Michetti, CC0; rocket: SpaceX, public domain;
#: motorcycle: the Middlebury 2014 stereo benchmark, down-sampled; ihc: the Center for Microscopy And Molecular
#: Imaging, no known copyright restrictions)
PHOTOS = ("astronaut", "chelsea", "coffee", "rocket", "motorcycle", "ihc")
#: grey textures of scikit-image (from CC0Textures, CC0), tinted, for occluders
TEXTURES = ("brick", "grass", "gravel")


@lru_cache(maxsize=None)
def photo(name: str) -> np.ndarray:
    """One of :data:`PHOTOS` or :data:`TEXTURES` as BGR uint8 (needs scikit-image)."""
    try:
        from skimage import data
    except ImportError as e:  # pragma: no cover - scikit-image is a dev dependency
        raise ImportError("the photo scenes are cut from scikit-image's photographs: pip install scikit-image "
                          "(or pip install -e '.[dev]')") from e
    if name == "motorcycle":
        img = data.stereo_motorcycle()[0]
    elif name == "ihc":
        img = data.immunohistochemistry()
    elif name in PHOTOS or name in TEXTURES:
        img = getattr(data, name)()
    else:
        raise ValueError(f"unknown photograph {name!r}: one of {', '.join(PHOTOS + TEXTURES)}")
    if img.ndim == 2:
        img = np.repeat(img[:, :, None], 3, axis=2)
    return np.ascontiguousarray(img[:, :, :3][:, :, ::-1])


@dataclass
class Piece:
    """A moving piece of a photograph: its pixels, its alpha (both at ``pixels``' size) and its box per frame."""

    pixels: np.ndarray  # (ph, pw, 3) float32
    alpha: np.ndarray  # (ph, pw) float32 in [0, 1]
    boxes: np.ndarray  # (n_frames, 4): x, y, w, h of the piece's whole extent


@dataclass
class PhotoScene:
    """What :func:`render_photo` draws: the target (first), look-alikes in front of it, an occluder in front of all."""

    kind: str
    seed: int
    n_frames: int
    background: np.ndarray  # (H + pan, W + pan, 3) float32, panned by ``camera``
    camera: np.ndarray  # (n_frames, 2): the view's top-left corner in ``background``
    target: Piece
    lookalikes: list[Piece]
    occluder: tuple[np.ndarray, tuple[int, int]] | None  # pixels (h, w, 3) float32 and top-left (x, y)
    gain: np.ndarray  # (n_frames, 3) BGR gain
    lamp: tuple[float, float, float, float, float, float] | None  # x0, y0, x1, y1, radius, strength
    gray: bool
    noise: float
    jpeg: int  # 0: none
    nuisances: dict = field(default_factory=dict)


def _crop(rng: np.random.Generator, img: np.ndarray, w: float, h: float, scale: tuple[float, float],
          min_std: float = 18.0) -> np.ndarray:
    """A textured crop of ``img`` resized to (round(h), round(w)): the first of 40 draws whose grey spread is at
    least ``min_std`` and whose mean is not dark (else the most textured draw)."""
    ih, iw = img.shape[:2]
    best, best_std = None, -1.0
    for _ in range(40):
        s = float(rng.uniform(*scale))
        cw, ch = min(iw - 1, w * s), min(ih - 1, h * s)
        x, y = rng.uniform(0, iw - cw), rng.uniform(0, ih - ch)
        cut = img[int(y):int(y + ch), int(x):int(x + cw)]
        out = cv2.resize(cut, (max(2, round(w)), max(2, round(h))), interpolation=cv2.INTER_AREA)
        grey = cv2.cvtColor(out, cv2.COLOR_BGR2GRAY)
        sd = float(grey.std())
        if sd >= min_std and grey.mean() >= 45:
            return out.astype(np.float32)
        if sd > best_std:
            best, best_std = out, sd
    return best.astype(np.float32)


def _alpha(pw: int, ph: int, ellipse: bool, feather: float = 1.2) -> np.ndarray:
    yy, xx = np.mgrid[0:ph, 0:pw].astype(np.float32) + 0.5
    u, v = (xx - pw / 2) / (pw / 2), (yy - ph / 2) / (ph / 2)
    if ellipse:
        inside = u * u + v * v <= 1.0
    else:  # a rectangle with rounded corners
        inside = (np.maximum(np.abs(u) - 0.7, 0) ** 2 + np.maximum(np.abs(v) - 0.7, 0) ** 2) <= 0.09
    return cv2.GaussianBlur(inside.astype(np.float32), (0, 0), feather)


def _lookalike(rng: np.random.Generator, target: np.ndarray, src: np.ndarray) -> np.ndarray:
    """The target's piece with its hue turned, saturation and brightness changed, mirrored; or another piece of
    its photograph."""
    th, tw = target.shape[:2]
    if rng.random() < 0.35:
        return _crop(rng, src, tw, th, (1.0, 3.0))
    hsv = cv2.cvtColor(np.clip(target, 0, 255).astype(np.uint8), cv2.COLOR_BGR2HSV).astype(np.float32)
    dh = float(rng.uniform(4, 15)) * (1 if rng.random() < 0.5 else -1)
    hsv[:, :, 0] = np.mod(hsv[:, :, 0] + dh, 180)
    hsv[:, :, 1] = np.clip(hsv[:, :, 1] * rng.uniform(0.8, 1.2), 0, 255)
    hsv[:, :, 2] = np.clip(hsv[:, :, 2] * rng.uniform(0.8, 1.2), 0, 255)
    out = cv2.cvtColor(hsv.astype(np.uint8), cv2.COLOR_HSV2BGR).astype(np.float32)
    return out[:, ::-1].copy() if rng.random() < 0.7 else out[::-1].copy()


def _boxes(path, n: int, size: tuple[float, float], scale_end: float) -> np.ndarray:
    pts = np.asarray(path, dtype=np.float64).reshape(-1, 3)
    t = np.arange(n, dtype=np.float64)
    cx, cy = np.interp(t, pts[:, 0], pts[:, 1]), np.interp(t, pts[:, 0], pts[:, 2])
    f = 1.0 + (scale_end - 1.0) * t / max(n - 1, 1)
    w, h = size[0] * f, size[1] * f
    return np.stack([cx - w / 2, cy - h / 2, w, h], axis=1)


def _draw(rng: np.random.Generator, n_frames: int, gray: float) -> dict:
    """The seed's photographs, pieces, sizes and nuisances (everything but the paths)."""
    names = list(PHOTOS)
    bg_name = names.pop(int(rng.integers(len(names))))
    tgt_name = names.pop(int(rng.integers(len(names))))
    pan = float(rng.uniform(10, 40)) if rng.random() < 0.5 else 0.0
    pad = int(math.ceil(pan)) + 1
    bg = _crop(rng, photo(bg_name), W + pad, H + pad, (1.0, 2.2), min_std=0.0)
    w = float(rng.uniform(18, 48))
    aspect = float(rng.uniform(0.7, 2.2))
    size = (w, w * aspect)
    tsrc = photo(tgt_name)
    pixels = _crop(rng, tsrc, *size, (1.5, 5.0))
    ellipse = bool(rng.random() < 0.6)
    n_look = int(rng.integers(0, 4))
    looks = [_lookalike(rng, pixels, tsrc) for _ in range(n_look)]
    if rng.random() < 0.5:
        g = float(rng.uniform(0.5, 1.6))
        g_end = np.array([np.clip(g * rng.uniform(0.85, 1.15), 0.35, 2.0) for _ in range(3)])
    else:
        g_end = np.ones(3)
    ramp = np.linspace(0.0, 1.0, n_frames)[:, None]
    lamp = None
    if rng.random() < 1 / 3:
        lamp = (float(rng.uniform(0, W)), float(rng.uniform(0, H)), float(rng.uniform(0, W)),
                float(rng.uniform(0, H)), float(rng.uniform(60, 140)), float(rng.uniform(0.3, 0.8)))
    return {"bg_name": bg_name, "tgt_name": tgt_name, "pan": pan, "bg": bg, "size": size, "pixels": pixels,
            "ellipse": ellipse, "looks": looks, "gain": 1.0 + ramp * (g_end - 1.0), "gain_end": g_end, "lamp": lamp,
            "gray": bool(rng.random() < gray), "noise": float(rng.uniform(1.5, 4.0)),
            "jpeg": int(rng.integers(55, 91)) if rng.random() < 0.5 else 0,
            "scale_end": float(rng.uniform(0.8, 1.2)), "speed": float(rng.uniform(1.0, 3.5))}


def _scene(rng, d: dict, kind: str, seed: int, n_frames: int, path, occluder=None, extra=None,
           look_paths=None) -> PhotoScene:
    """The scene of drawn pieces ``d`` and the target's ``path``; the look-alikes wander unless ``look_paths`` gives
    each one's ``(path, size)``."""
    size = d["size"]
    pix = d["pixels"]
    target = Piece(pix, _alpha(pix.shape[1], pix.shape[0], d["ellipse"]), _boxes(path, n_frames, size,
                                                                                 d["scale_end"]))
    start = path[0][1:]
    looks = []
    for i, lp in enumerate(d["looks"]):
        if look_paths is not None:
            lpath, s = look_paths[i]
            looks.append(Piece(lp, _alpha(lp.shape[1], lp.shape[0], rng.random() < 0.6), _boxes(lpath, n_frames, s,
                                                                                                  1.0)))
            continue
        s = tuple(v * rng.uniform(0.85, 1.15) for v in size)
        p0 = None
        for _ in range(20):  # start away from the target, so that the first frame is unambiguous
            x, y = rng.uniform(s[0], W - s[0]), rng.uniform(s[1] * 0.6, H - s[1] * 0.6)
            if abs(x - start[0]) > 2.5 * size[0] or abs(y - start[1]) > 1.5 * size[1]:
                p0 = (x, y)
                break
        lpath = _wander(rng, n_frames, W, H, s, speed=d["speed"] * rng.uniform(0.5, 1.0), start=p0, k=3)
        looks.append(Piece(lp, _alpha(lp.shape[1], lp.shape[0], rng.random() < 0.6),
                           _boxes(lpath, n_frames, s, float(rng.uniform(0.85, 1.15)))))
    t = np.linspace(0.0, 1.0, n_frames)[:, None]
    direction = rng.uniform(-1, 1, 2)
    direction /= max(np.linalg.norm(direction), 1e-9)
    corner = d["pan"] / 2 + (t - 0.5) * d["pan"] * direction[None, :]
    nz = {"background": d["bg_name"], "target": d["tgt_name"], "size": size, "speed": d["speed"],
          "shape": "ellipse" if d["ellipse"] else "rounded rectangle", "lookalikes": len(looks), "pan": d["pan"],
          "gain_end": d["gain_end"].round(3).tolist(), "lamp": d["lamp"] is not None, "noise": d["noise"],
          "jpeg": d["jpeg"], "scale_end": d["scale_end"], **(extra or {})}
    return PhotoScene(kind=kind, seed=seed, n_frames=n_frames, background=d["bg"], camera=corner, target=target,
                      lookalikes=looks, occluder=occluder, gain=d["gain"], lamp=d["lamp"], gray=d["gray"],
                      noise=d["noise"], jpeg=d["jpeg"], nuisances=nz)


def photo_vanish_scene(seed: int = 0, n_frames: int = 120, *, gray: float = 0.3) -> PhotoScene:
    """The target walks fully behind an opaque band for 12-35 frames and comes out on the other side."""
    rng = np.random.default_rng([seed, 91])
    d = _draw(rng, n_frames, gray)
    w, h = d["size"]
    hidden = int(rng.integers(12, 36))
    grow = max(1.0, d["scale_end"])
    # a visible approach, the band, a visible exit: the run fits the frame and the band hides the largest box
    speed = min(max(d["speed"], 1.5), (W - w * grow - 6) / (n_frames - 1))
    w_max = speed * (n_frames - 1 - hidden) / (3.4 * grow)
    if w > w_max:  # shrink the target (keeping its aspect) until it can be hidden that long
        d["pixels"] = cv2.resize(d["pixels"], (max(2, round(w_max)), max(2, round(h * w_max / w))),
                                 interpolation=cv2.INTER_AREA)
        d["looks"] = [cv2.resize(p, d["pixels"].shape[1::-1], interpolation=cv2.INTER_AREA) for p in d["looks"]]
        w, h = w_max, h * w_max / w
        d["size"] = (w, h)
    run = speed * (n_frames - 1)
    band_w = w * grow + speed * hidden
    direction = 1.0 if rng.random() < 0.5 else -1.0
    x0 = (W - run) / 2.0 if direction > 0 else (W + run) / 2.0
    x1 = x0 + direction * run
    y0 = float(rng.uniform(h * grow * 0.6 + 8, H - h * grow * 0.6 - 8))
    y1 = float(np.clip(y0 + rng.uniform(-15, 15), h * grow * 0.6, H - h * grow * 0.6))
    t_mid = (n_frames - 1) * float(rng.uniform(0.4, 0.6))
    xc = x0 + direction * speed * t_mid
    lo, hi = min(x0, x1) + w * grow * 1.2 + band_w / 2, max(x0, x1) - w * grow * 1.2 - band_w / 2
    xc = float(np.clip(xc, lo, max(lo, hi)))
    band_h = h * grow * float(rng.uniform(1.4, 2.2)) + abs(y1 - y0)
    yc = (y0 + y1) / 2.0
    bx, by = int(round(xc - band_w / 2)), int(round(yc - band_h / 2))
    bw, bh = int(math.ceil(band_w)) + 1, int(math.ceil(band_h)) + 1
    if rng.random() < 0.5:  # a piece of a third photograph
        others = [p for p in PHOTOS if p not in (d["bg_name"], d["tgt_name"])]
        occ = _crop(rng, photo(others[int(rng.integers(len(others)))]), bw, bh, (1.0, 2.0), min_std=0.0)
        occ_kind = "photo"
    else:  # a tinted texture
        tex = photo(TEXTURES[int(rng.integers(len(TEXTURES)))])
        tint = rng.uniform(0.4, 1.3, 3).astype(np.float32)
        occ = _crop(rng, tex, bw, bh, (1.0, 2.0), min_std=0.0) * tint
        occ_kind = "texture"
    path = ((0, x0, y0), (n_frames - 1, x1, y1))
    return _scene(rng, d, "photo-vanish", seed, n_frames, path, occluder=(occ, (bx, by)),
                  extra={"hidden_frames": hidden, "occluder": occ_kind, "occluder_width": band_w})


def photo_leave_scene(seed: int = 0, n_frames: int = 140, *, gray: float = 0.3) -> PhotoScene:
    """The target walks out through a side edge, stays out 15-40 frames and walks back in through it."""
    rng = np.random.default_rng([seed, 92])
    d = _draw(rng, n_frames, gray)
    w, h = d["size"]
    grow = max(1.0, d["scale_end"])
    speed = float(np.clip(d["speed"], 2.0, 3.5))
    out_frames = int(rng.integers(15, 41))
    side = -1.0 if rng.random() < 0.5 else 1.0
    edge_out = -w * grow if side < 0 else W + w * grow  # the centre where the box is wholly outside
    x0 = float(np.clip(edge_out - side * speed * rng.uniform(20, 35), w * grow, W - w * grow))
    y0 = float(rng.uniform(h * grow * 0.6 + 5, H - h * grow * 0.6 - 5))
    t_exit = abs(edge_out - x0) / speed
    t_back = t_exit + out_frames
    x_in = x0  # back to where it started, wholly in view
    t_in = t_back + abs(edge_out - x_in) / speed
    y_back = float(np.clip(y0 + rng.uniform(-20, 20), h * grow * 0.6, H - h * grow * 0.6))
    path = ((0, x0, y0), (t_exit, edge_out, y0), (t_back, edge_out, y_back), (t_in, x_in, y_back),
            (n_frames - 1, x_in, y_back))
    return _scene(rng, d, "photo-leave", seed, n_frames, path, extra={"out_frames": out_frames})


def photo_exit_scene(seed: int = 0, n_frames: int = 140, *, gray: float = 0.3) -> PhotoScene:
    """The target walks out through a side edge in a flow of look-alikes heading the same way.

    1-3 look-alikes follow it towards that edge, 2-6 target widths behind, at 0.7-1.2 times its speed, and leave
    too. With probability 0.5 the target comes back through that edge 15-40 frames after it left; otherwise a
    look-alike walks in through it at a drawn time instead (nothing in its looks says it is not the target). The
    flow at an exit of :func:`pftrack.synth.varied.exit_scene`, cut from photographs."""
    rng = np.random.default_rng([seed, 94])
    d = _draw(rng, n_frames, gray)
    w, h = d["size"]
    grow = max(1.0, d["scale_end"])
    speed = float(np.clip(d["speed"], 1.5, 3.5))
    path, side, edge_out, x0, t_exit, comes_back = exit_path(rng, n_frames, w, h, speed, grow)
    tsrc = photo(d["tgt_name"])
    n_flow = int(rng.integers(1, 4))
    d["looks"] = [_lookalike(rng, d["pixels"], tsrc) for _ in range(n_flow + (0 if comes_back else 1))]
    # the flow ends wholly outside too
    look_paths = exit_walkers(rng, n_flow, n_frames, (w, h), speed, x0, side, edge_out, t_exit, comes_back,
                              out=lambda s: edge_out - side * (w * grow - s[0]))
    return _scene(rng, d, "photo-exit", seed, n_frames, path, look_paths=look_paths,
                  extra={"comes_back": comes_back, "flow": n_flow})


def _paste(canvas: np.ndarray, cover: np.ndarray | None, piece: Piece, t: int) -> np.ndarray:
    """Draw ``piece`` at frame ``t`` over ``canvas`` (in place); returns its alpha in the frame. ``cover`` (the
    pieces drawn over the target so far) is raised by it when given."""
    x, y, w, h = piece.boxes[t]
    ph, pw = piece.alpha.shape
    sx, sy = w / pw, h / ph
    # pixel centres: the piece's pixel i spans [i - 0.5, i + 0.5] in warpAffine's coordinates, the box [x, x + w)
    m = np.array([[sx, 0.0, x - 0.5 + 0.5 * sx], [0.0, sy, y - 0.5 + 0.5 * sy]])
    a = cv2.warpAffine(piece.alpha, m, (W, H), flags=cv2.INTER_LINEAR, borderValue=0.0)
    px = cv2.warpAffine(piece.pixels, m, (W, H), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    # the alpha is 0 beyond the box's pixels and their neighbours: blend only there
    x0, y0 = min(max(int(math.floor(x)) - 1, 0), W), min(max(int(math.floor(y)) - 1, 0), H)
    x1, y1 = min(max(int(math.ceil(x + w)) + 1, 0), W), min(max(int(math.ceil(y + h)) + 1, 0), H)
    ar = a[y0:y1, x0:x1, None]
    roi = canvas[y0:y1, x0:x1]
    roi *= 1.0 - ar
    roi += px[y0:y1, x0:x1] * ar
    if cover is not None:
        np.maximum(cover[y0:y1, x0:x1], a[y0:y1, x0:x1], out=cover[y0:y1, x0:x1])
    return a


@lru_cache(maxsize=1)
def _grid() -> tuple[np.ndarray, np.ndarray]:
    """The frame's pixel rows and columns (float32), for the lamp."""
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float32)
    yy.flags.writeable = xx.flags.writeable = False
    return yy, xx


def render_photo(scene: PhotoScene, t: int) -> tuple[np.ndarray, float]:
    """Frame ``t`` (BGR uint8, 240 x 320) and the target's visible fraction in it."""
    rng = np.random.default_rng([scene.seed, 93, t])
    cx, cy = scene.camera[t]
    m = np.array([[1.0, 0.0, -cx], [0.0, 1.0, -cy]])
    canvas = cv2.warpAffine(scene.background, m, (W, H), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    a_t = _paste(canvas, None, scene.target, t)
    cover = np.zeros((H, W), np.float32)
    for piece in scene.lookalikes:
        _paste(canvas, cover, piece, t)
    if scene.occluder is not None:
        occ, (ox, oy) = scene.occluder
        oh, ow = occ.shape[:2]
        x0, y0, x1, y1 = max(ox, 0), max(oy, 0), min(ox + ow, W), min(oy + oh, H)
        if x1 > x0 and y1 > y0:
            canvas[y0:y1, x0:x1] = occ[y0 - oy:y1 - oy, x0 - ox:x1 - ox]
            cover[y0:y1, x0:x1] = 1.0
    _, _, w, h = scene.target.boxes[t]
    whole = float(scene.target.alpha.sum()) * (w / scene.target.alpha.shape[1]) * (h / scene.target.alpha.shape[0])
    visible = float((a_t * (1.0 - cover)).sum()) / whole if whole > 0 else 0.0
    light = scene.gain[t].astype(np.float32)[None, None, :]
    if scene.lamp is not None:
        lx0, ly0, lx1, ly1, r, s = scene.lamp
        f = t / max(scene.n_frames - 1, 1)
        lx, ly = lx0 + (lx1 - lx0) * f, ly0 + (ly1 - ly0) * f
        yy, xx = _grid()
        light = light * (1.0 + s * np.exp(-((xx - lx) ** 2 + (yy - ly) ** 2) / (2 * r * r)))[:, :, None]
    canvas *= light
    canvas += rng.normal(0.0, scene.noise, canvas.shape).astype(np.float32)
    frame = np.clip(canvas + 0.5, 0, 255).astype(np.uint8)
    if scene.gray:
        frame = cv2.cvtColor(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR)
    if scene.jpeg:
        ok, buf = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, scene.jpeg])
        frame = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    return frame, min(max(visible, 0.0), 1.0)


def export_photo(scene: PhotoScene, folder) -> None:
    """Write a photo scene as an OTB folder (``img/``, ``groundtruth_rect.txt``, ``meta.json`` with the hidden
    frames, ``attrs.txt``)."""
    visible: list[float] = []

    def frames():
        for t in range(scene.n_frames):
            frame, v = render_photo(scene, t)
            visible.append(v)
            yield frame

    write_otb_folder(folder, frames(), visible, lambda: scene.target.boxes, W, H,
                     {"kind": scene.kind, "seed": scene.seed, "gray": scene.gray, "nuisances": scene.nuisances})


#: ``pftrack synth`` kinds of this module
PHOTO_SCENES = {"photo-vanish": photo_vanish_scene, "photo-leave": photo_leave_scene, "photo-exit": photo_exit_scene}
