"""Point-tracking scenes with an obstacle, and rectified stereo pairs of them (book ch. 7 experiments).

:func:`occluder_scene` renders a textured object moving on a line or a curve over a
textured static background and passing behind a static bar (solid or textured), with the
exact position of chosen points on the object in every frame and whether each point's
LK window is covered by the bar.  :func:`stereo_rail_scene` renders the same kind of
scene as a rectified stereo pair (pinhole cameras, baseline ``B`` along x): fronto-parallel
textured layers for a far wall, the object moving in 3-D and a near bar, with every
point's left and right image positions and its depth.

Everything that is not fixed by an argument is drawn from the seed: speed, occluder
width, trajectory curvature, object size and texture, bar style, illumination gain
and drift, grey or colour, sensor noise.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

__all__ = ["PointScene", "StereoScene", "export_point_scene", "export_stereo_scene", "occluder_scene",
           "paste_sprite", "stereo_rail_scene", "texture"]


def texture(rng: np.random.Generator, h: int, w: int, *, blur: float = 1.2, contrast: float = 60.0,
            mean: float = 128.0, color: bool = True) -> np.ndarray:
    """A smooth random texture (float32, ``(h, w, 3)``) with corners everywhere."""
    ch = 3 if color else 1
    noise = rng.normal(0.0, 1.0, (h, w, ch)).astype(np.float32)
    sm = cv2.GaussianBlur(noise, (0, 0), blur)
    if sm.ndim == 2:
        sm = sm[:, :, None]
    sm = sm / (sm.std() + 1e-6)
    out = mean + contrast * sm
    if color:
        out = out + rng.uniform(-25, 25, 3).astype(np.float32)
    else:
        out = np.repeat(out, 3, axis=2)
    return out.astype(np.float32)


@dataclass
class PointScene:
    """Frames and exact ground truth of a point-tracking scene."""

    frames: list[np.ndarray]
    points: np.ndarray          # (T, P, 2) true positions
    occluded: np.ndarray        # (T, P) the point's LK window overlaps the obstacle
    obstacle: tuple[float, float]  # x-range of the bar
    meta: dict = field(default_factory=dict)

    def exit_frames(self) -> np.ndarray:
        """Per point, the first frame after its last occluded frame (-1 if never occluded)."""
        out = np.full(self.points.shape[1], -1)
        for j in range(self.points.shape[1]):
            idx = np.flatnonzero(self.occluded[:, j])
            if len(idx):
                out[j] = idx[-1] + 1
        return out


def paste_sprite(canvas: np.ndarray, sprite: np.ndarray, x0: float, y0: float) -> None:
    """Draw ``sprite`` with its top-left corner at sub-pixel ``(x0, y0)`` (bilinear, anti-aliased edges).

    Only the window of the canvas the sprite can touch is warped and blended (outside it the warped sprite and its
    mask are 0, which leaves the canvas as it is). The shift is the float32 one of a warp of the whole canvas, less
    the window's integer corner, so every pixel is the one that warp gives (OpenCV's warp is fixed-point with integer
    steps per pixel)."""
    h, w = canvas.shape[:2]
    sh, sw = sprite.shape[:2]
    fx, fy = float(np.float32(x0)), float(np.float32(y0))
    wx0, wy0 = max(math.floor(fx) - 1, 0), max(math.floor(fy) - 1, 0)
    wx1, wy1 = min(math.floor(fx) + sw + 2, w), min(math.floor(fy) + sh + 2, h)
    if wx1 <= wx0 or wy1 <= wy0:  # wholly outside the canvas
        return
    m = np.array([[1.0, 0.0, fx - wx0], [0.0, 1.0, fy - wy0]])
    size = (wx1 - wx0, wy1 - wy0)
    img = cv2.warpAffine(sprite, m, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    mask = cv2.warpAffine(np.ones((sh, sw), np.float32), m, size, flags=cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_CONSTANT)[:, :, None]
    win = canvas[wy0:wy1, wx0:wx1]
    win *= 1.0 - mask
    win += img * mask


def _finish(rng, img: np.ndarray, gain: float, gray: bool, noise: float) -> np.ndarray:
    out = img * gain + rng.normal(0.0, noise, img.shape).astype(np.float32)
    out = np.clip(out, 0, 255).astype(np.uint8)
    if gray:
        g = cv2.cvtColor(out, cv2.COLOR_BGR2GRAY)
        out = cv2.cvtColor(g, cv2.COLOR_GRAY2BGR)
    return out


def _pick_points(rng, sprite: np.ndarray, n: int, margin: int) -> np.ndarray:
    """``n`` well-textured offsets inside the sprite, at least ``margin`` px from its border."""
    g = cv2.cvtColor(np.clip(sprite, 0, 255).astype(np.uint8), cv2.COLOR_BGR2GRAY)
    sh, sw = g.shape
    inner = g[margin:sh - margin, margin:sw - margin]
    pts = cv2.goodFeaturesToTrack(inner, maxCorners=n, qualityLevel=0.05, minDistance=4, blockSize=7)
    pts = np.zeros((0, 2)) if pts is None else pts.reshape(-1, 2).astype(np.float64)
    while len(pts) < n:  # a flat sprite: random inner points
        pts = np.vstack([pts, rng.uniform([0, 0], [inner.shape[1] - 1, inner.shape[0] - 1])])
    return pts[:n] + margin


def occluder_scene(seed: int = 0, *, trajectory: str | None = None, vel: float | None = None,
                   occlusion_frames: int | None = None, size: int | None = None, n_points: int = 5,
                   shape: tuple[int, int] = (240, 320), gray: bool | None = None, bar: str | None = None,
                   win: int = 7, after: int = 25) -> PointScene:
    """A textured object crossing a vertical bar (ch07.md §4, E7.1–E7.3).

    ``trajectory`` is ``line`` (horizontal with a random slope) or ``curve`` (an arc of a
    circle); ``vel`` the speed in px/frame (random in [2, 4]); the bar's width is chosen so
    that a point is hidden for about ``occlusion_frames`` frames (random in [8, 12]).  The
    object reaches the bar after at least ``n_init + 8`` frames and runs ``after`` frames
    past it.  ``bar`` is ``solid`` or ``textured`` (random).
    """
    rng = np.random.default_rng(seed)
    h, w = shape
    trajectory = trajectory or str(rng.choice(["line", "curve"]))
    if trajectory not in ("line", "curve"):
        raise ValueError("trajectory must be 'line' or 'curve'")
    vel = float(vel if vel is not None else rng.uniform(2.0, 4.0))
    n_occ = int(occlusion_frames if occlusion_frames is not None else rng.integers(8, 13))
    size = int(size if size is not None else rng.integers(22, 36))
    gray = bool(rng.random() < 0.4) if gray is None else bool(gray)
    bar = bar or str(rng.choice(["solid", "textured"]))
    color = not gray
    bg = texture(rng, h, w, blur=rng.uniform(1.0, 2.0), contrast=rng.uniform(25, 45), color=color)
    sprite = texture(rng, size, size, blur=rng.uniform(0.8, 1.4), contrast=rng.uniform(45, 70),
                     mean=rng.uniform(90, 170), color=color)
    bar_w = max(6.0, n_occ * vel - win)  # hidden while the window overlaps: (bar_w + win) / vel frames
    lead = 15 + int(rng.integers(0, 8))  # frames before the bar
    total = lead + n_occ + after
    # the path of the object's top-left corner, parameterised by arc length s = vel * t
    s = vel * np.arange(total, dtype=np.float64)
    if trajectory == "line":
        slope = rng.uniform(-0.25, 0.25)
        direc = np.array([1.0, slope]) / np.hypot(1.0, slope)
        rel = s[:, None] * direc[None]
    else:
        radius = max(rng.uniform(110, 200), s[-1] / 1.3) * rng.choice([-1, 1])
        ang = s / abs(radius)
        rel = np.stack([abs(radius) * np.sin(ang), radius * (1 - np.cos(ang))], axis=1)
    pts_off = _pick_points(rng, sprite, n_points, margin=max(3, win // 2 + 1))
    # place the bar where the object's centre is at frame lead + n_occ/2, then shift the path into the image
    mid = lead + n_occ // 2
    centre_rel = rel + size / 2.0
    bar_x0 = w * rng.uniform(0.42, 0.58) - bar_w / 2.0
    start = np.array([bar_x0 + bar_w / 2.0 - centre_rel[mid, 0], h / 2.0 - centre_rel[mid, 1]
                      + rng.uniform(-20, 20)])
    corner = rel + start
    pad = 4.0
    lo = corner.min(0)
    hi = corner.max(0) + size
    shift = np.array([0.0, 0.0])
    shift[1] = max(0.0, pad - lo[1]) - max(0.0, hi[1] - (h - pad))
    corner[:, 1] += shift[1]
    points = corner[:, None, :] + pts_off[None, :, :]
    half = win / 2.0
    occluded = (points[:, :, 0] + half > bar_x0) & (points[:, :, 0] - half < bar_x0 + bar_w)
    bar_tex = (np.full((h, int(np.ceil(bar_w)) + 2, 3), rng.uniform(40, 220), np.float32) if bar == "solid" else
               texture(rng, h, int(np.ceil(bar_w)) + 2, blur=1.5, contrast=50, color=color))
    gain0, drift = rng.uniform(0.8, 1.15), rng.uniform(-0.25, 0.25)
    noise = rng.uniform(1.0, 3.0)
    frames = []
    for t in range(total):
        canvas = bg.copy()
        paste_sprite(canvas, sprite, corner[t, 0], corner[t, 1])
        x0 = int(np.floor(bar_x0))
        frac = bar_x0 - x0
        bw = int(np.ceil(bar_w + frac))
        strip = bar_tex[:, :bw]
        x1 = min(w, x0 + bw)
        cov = np.ones((1, bw), np.float32)
        cov[0, 0] = 1.0 - frac  # anti-aliased left edge
        right = bar_x0 + bar_w - (x0 + bw - 1)
        cov[0, -1] = min(cov[0, -1], right)
        a = cov[:, :x1 - x0, None]
        canvas[:, x0:x1] = canvas[:, x0:x1] * (1 - a) + strip[:, :x1 - x0] * a
        gain = gain0 * (1.0 + drift * t / max(1, total - 1))
        frames.append(_finish(rng, canvas, gain, gray, noise))
    meta = {"kind": "occluder", "seed": seed, "trajectory": trajectory, "vel": round(vel, 4), "size": size,
            "occlusion_frames": n_occ, "bar": bar, "bar_x": [round(bar_x0, 3), round(bar_x0 + bar_w, 3)],
            "gray": gray, "gain": round(gain0, 4), "drift": round(drift, 4), "noise": round(noise, 3)}
    return PointScene(frames, points, occluded, (bar_x0, bar_x0 + bar_w), meta)


@dataclass
class StereoScene:
    """A rectified stereo sequence with exact per-point ground truth."""

    left: list[np.ndarray]
    right: list[np.ndarray]
    calib: dict                 # f (px), B (m), cx, cy
    xl: np.ndarray              # (T, P, 2) left image positions
    xr: np.ndarray              # (T, P) right image x
    depth: np.ndarray           # (T, P) Z in metres
    occluded_left: np.ndarray   # (T, P)
    occluded_right: np.ndarray  # (T, P)
    meta: dict = field(default_factory=dict)


def _render_layer(canvas: np.ndarray, tex: np.ndarray, *, Z: float, X0: float, Y0: float, res: float,
                  f: float, cx: float, cy: float, bx: float) -> np.ndarray:
    """Paint a fronto-parallel textured rectangle at depth Z onto ``canvas``; returns its coverage mask.

    ``tex`` covers world x ∈ [X0, X0 + w/res], y ∈ [Y0, Y0 + h/res]; the camera sits at x = bx.
    Image x = f (X − bx) / Z + cx.  The map texture → image is affine: scale f/(Z res).
    """
    h, w = canvas.shape[:2]
    s = f / (Z * res)
    tx = f * (X0 - bx) / Z + cx
    ty = f * Y0 / Z + cy
    m = np.float32([[s, 0, tx], [0, s, ty]])
    img = cv2.warpAffine(tex, m, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    mask = cv2.warpAffine(np.ones(tex.shape[:2], np.float32), m, (w, h), flags=cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_CONSTANT)[:, :, None]
    canvas *= 1.0 - mask
    canvas += img * mask
    return mask[:, :, 0]


def stereo_rail_scene(seed: int = 0, *, f: float | None = None, baseline: float | None = None,
                      depth: tuple[float, float] | None = None, n_points: int = 5, shape: tuple[int, int] = (240, 320),
                      n_frames: int | None = None, win: int = 7) -> StereoScene:
    """An object moving on a rail in 3-D behind a near vertical bar, seen by a rectified pair (E7.4).

    f ≈ 300 px, B ≈ 0.12 m and depths in [2, 5] m unless given; the object (0.25–0.4 m,
    textured) moves across the view while its depth changes linearly between two values
    drawn from ``depth``; the bar stands at 1.0–1.5 m and hides the object in both views
    for several frames.  ``n_frames`` defaults to as many as keep the object inside both
    views (at most 90).
    """
    rng = np.random.default_rng(seed)
    h, w = shape
    f = float(f if f is not None else rng.uniform(280, 320))
    B = float(baseline if baseline is not None else rng.uniform(0.10, 0.14))
    zr = depth or (2.0, 5.0)
    cx, cy = w / 2.0 + rng.uniform(-4, 4), h / 2.0 + rng.uniform(-4, 4)
    color = bool(rng.random() >= 0.4)
    Z0, Z1 = rng.uniform(zr[0], zr[1], 2)
    size = rng.uniform(0.25, 0.4)
    speed_px = rng.uniform(2.0, 4.0)
    res = 90.0  # texture pixels per metre
    obj = texture(rng, int(size * res), int(size * res), blur=1.0, contrast=rng.uniform(45, 70),
                  mean=rng.uniform(90, 170), color=color)
    wall_Z = 9.0
    wall = texture(rng, int(h * wall_Z / f * 40 * 1.6), int(w * wall_Z / f * 40 * 1.6), blur=1.2, contrast=35,
                   color=color)
    wall_res = 40.0
    wall_X0 = -(wall.shape[1] / wall_res) / 2.0
    wall_Y0 = -(wall.shape[0] / wall_res) / 2.0
    # image-space speed 2–4 px/frame at the mean depth; the object crosses the bar's line of sight at t = 0,
    # its depth changes by Z1 - Z0 over 80 frames; the sequence is the longest run around t = 0 (at most
    # n_frames, or 90) that keeps the whole object inside both views
    Zm = 0.5 * (Z0 + Z1)
    vX = speed_px * Zm / f * rng.choice([-1, 1])
    Zb = rng.uniform(1.0, 1.5)
    Xb_c = rng.uniform(-0.1, 0.1) * Zb  # bar centre, near the optical axis
    tt = np.arange(-75, 76, dtype=np.float64)
    Zall = np.clip(Zm + (Z1 - Z0) * tt / 80.0, min(zr), max(zr))
    Xall = Xb_c * Zm / Zb + B / 2.0 * (1 - Zm / Zb) + vX * tt
    edges = [f * (Xall + sx * size / 2 - bx) / Zall + cx for sx in (-1, 1) for bx in (0.0, B)]
    inside = np.all([(e >= 2) & (e <= w - 3) for e in edges], axis=0)
    c0 = 75
    lo, hi = c0, c0
    cap = min(90, n_frames or 90)
    while hi - lo + 1 < cap:
        grow_lo = lo > 0 and inside[lo - 1]
        grow_hi = hi < len(tt) - 1 and inside[hi + 1]
        if not (grow_lo or grow_hi):
            break
        if grow_hi and (not grow_lo or (hi - c0) <= (c0 - lo)):
            hi += 1
        else:
            lo -= 1
    n_frames = hi - lo + 1
    Zt, Xc = Zall[lo:hi + 1], Xall[lo:hi + 1]
    Z0, Z1 = float(Zt[0]), float(Zt[-1])
    Yc = np.full(n_frames, rng.uniform(-0.25, 0.25) * h / 2.0 * Zm / f)
    bar_w = rng.uniform(0.10, 0.16)
    bar_tex_w = max(3, int(bar_w * res))
    solid = bool(rng.random() < 0.5)
    bar_tex = (np.full((int(2 * h * Zb / f * res), bar_tex_w, 3), rng.uniform(40, 220), np.float32) if solid else
               texture(rng, int(2 * h * Zb / f * res), bar_tex_w, blur=1.5, contrast=50, color=color))
    offs = _pick_points(rng, obj, n_points, margin=4) / res - size / 2.0  # world offsets from the centre
    X = Xc[:, None] + offs[None, :, 0]
    Y = Yc[:, None] + offs[None, :, 1]
    xl = np.stack([f * X / Zt[:, None] + cx, f * Y / Zt[:, None] + cy], axis=2)
    xr = f * (X - B) / Zt[:, None] + cx
    depth_arr = np.repeat(Zt[:, None], n_points, axis=1)
    half = win / 2.0

    def bar_span(bx: float) -> tuple[float, float]:
        x0 = f * (Xb_c - bar_w / 2 - bx) / Zb + cx
        return x0, x0 + f * bar_w / Zb

    bl, br = bar_span(0.0), bar_span(B)
    occ_l = (xl[:, :, 0] + half > bl[0]) & (xl[:, :, 0] - half < bl[1])
    occ_r = (xr + half > br[0]) & (xr - half < br[1])
    gain0, drift, noise = rng.uniform(0.85, 1.15), rng.uniform(-0.2, 0.2), rng.uniform(1.0, 2.5)
    lefts, rights = [], []
    for t in range(n_frames):
        views = []
        for bx in (0.0, B):
            canvas = np.zeros((h, w, 3), np.float32)
            _render_layer(canvas, wall, Z=wall_Z, X0=wall_X0, Y0=wall_Y0, res=wall_res, f=f, cx=cx, cy=cy, bx=bx)
            _render_layer(canvas, obj, Z=Zt[t], X0=Xc[t] - size / 2, Y0=Yc[t] - size / 2, res=res, f=f, cx=cx,
                          cy=cy, bx=bx)
            _render_layer(canvas, bar_tex, Z=Zb, X0=Xb_c - bar_w / 2, Y0=-bar_tex.shape[0] / res / 2, res=bar_tex_w
                          / bar_w, f=f, cx=cx, cy=cy, bx=bx)
            gain = gain0 * (1.0 + drift * t / max(1, n_frames - 1))
            views.append(_finish(rng, canvas, gain, not color, noise))
        lefts.append(views[0])
        rights.append(views[1])
    calib = {"f": round(f, 4), "B": round(B, 5), "cx": round(cx, 4), "cy": round(cy, 4)}
    meta = {"kind": "stereo-rail", "seed": seed, "Z": [round(Z0, 4), round(Z1, 4)], "bar_Z": round(Zb, 4),
            "bar_width_m": round(bar_w, 4), "speed_px": round(speed_px, 4), "gray": not color, "solid_bar": solid}
    return StereoScene(lefts, rights, calib, xl, xr, depth_arr, occ_l, occ_r, meta)


def _points_arg(pts: np.ndarray) -> str:
    return ";".join(f"{x:.2f},{y:.2f}" for x, y in pts)


def export_point_scene(scene: PointScene, folder) -> None:
    """``img/NNNN.png``, ``points_gt.csv`` (``frame,point,x,y,occluded``, frames from 1) and ``meta.json``
    (the scene's draw and the ``--points`` argument for frame 1)."""
    folder = Path(folder)
    (folder / "img").mkdir(parents=True, exist_ok=True)
    for t, fr in enumerate(scene.frames):
        cv2.imwrite(str(folder / "img" / f"{t + 1:04d}.png"), fr)
    rows = ["frame,point,x,y,occluded"]
    for t in range(scene.points.shape[0]):
        for j in range(scene.points.shape[1]):
            x, y = scene.points[t, j]
            rows.append(f"{t + 1},{j},{x:.3f},{y:.3f},{int(scene.occluded[t, j])}")
    (folder / "points_gt.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    meta = dict(scene.meta, points=_points_arg(scene.points[0]))
    (folder / "meta.json").write_text(json.dumps(meta) + "\n", encoding="utf-8")


def export_stereo_scene(scene: StereoScene, folder) -> None:
    """``left/``, ``right/``, ``calib.json``, ``stereo_gt.csv`` (``frame,point,xl,yl,xr,yr,Z,occ_l,occ_r``)
    and ``meta.json`` (with the ``--points`` argument for frame 1)."""
    folder = Path(folder)
    for side, frames in (("left", scene.left), ("right", scene.right)):
        (folder / side).mkdir(parents=True, exist_ok=True)
        for t, fr in enumerate(frames):
            cv2.imwrite(str(folder / side / f"{t + 1:04d}.png"), fr)
    (folder / "calib.json").write_text(json.dumps(scene.calib) + "\n", encoding="utf-8")
    rows = ["frame,point,xl,yl,xr,yr,Z,occ_l,occ_r"]
    for t in range(scene.xl.shape[0]):
        for j in range(scene.xl.shape[1]):
            x, y = scene.xl[t, j]
            rows.append(f"{t + 1},{j},{x:.3f},{y:.3f},{scene.xr[t, j]:.3f},{y:.3f},{scene.depth[t, j]:.4f},"
                        f"{int(scene.occluded_left[t, j])},{int(scene.occluded_right[t, j])}")
    (folder / "stereo_gt.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    meta = dict(scene.meta, points=_points_arg(scene.xl[0]))
    (folder / "meta.json").write_text(json.dumps(meta) + "\n", encoding="utf-8")
