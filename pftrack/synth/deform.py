"""Seeded deforming textured sheets with exact mesh ground truth (book ch. 13, ch13.md §5.2).

Frame ``n`` satisfies ``I_n(x + D_n(x)) = s_n(x) I_0(x)`` for every model point ``x``: ``D_n`` is a smooth
displacement (a sum of Gaussian RBF bumps plus a slow global drift, zero at frame 0), ``s_n`` a
multiplicative shading field (1 at frame 0), plus Gaussian noise.  Frames are rendered by inverting
``x + D_n(x)`` with a fixed-point iteration.  The truth of a mesh vertex ``v`` is ``v + D_n(v)`` and
``rho = s_n(v)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


def band_limited_texture(rng, size=(360, 480), scales=(2.0, 5.0, 12.0)) -> np.ndarray:
    """Noise summed over a few Gaussian scales, stretched to [0.1, 0.9]."""
    h, w = size
    img = np.zeros((h, w), np.float64)
    for s in scales:
        n = cv2.GaussianBlur(rng.standard_normal((h, w)), (0, 0), s)
        img += n / n.std()
    img = (img - img.min()) / (np.ptp(img) + 1e-12)
    return 0.1 + 0.8 * img


def _bilinear(a: np.ndarray, fx: np.ndarray, fy: np.ndarray) -> np.ndarray:
    """``a`` sampled at fractional (row fy, column fx) grid coordinates, separably."""
    x0 = np.clip(np.floor(fx).astype(int), 0, a.shape[1] - 2)
    y0 = np.clip(np.floor(fy).astype(int), 0, a.shape[0] - 2)
    tx, ty = fx - x0, fy - y0
    rows = a[y0] * (1 - ty)[:, None] + a[y0 + 1] * ty[:, None]
    return rows[:, x0] * (1 - tx)[None] + rows[:, x0 + 1] * tx[None]


@dataclass
class DeformScene:
    frames: list[np.ndarray]        # BGR uint8
    box: tuple[float, float, float, float]
    centers: np.ndarray             # (B, 2) RBF centres
    sigmas: np.ndarray              # (B,)
    amps: np.ndarray                # (n_frames, B, 2)
    drift: np.ndarray               # (n_frames, 2)
    shade: list                     # per frame (a, phase, b)
    size: tuple[int, int]
    texture: np.ndarray | None = None   # the model texture in [0, 1]

    def displacement(self, n: int, pts: np.ndarray) -> np.ndarray:
        pts = np.asarray(pts, np.float64)
        d2 = np.sum((pts[:, None, :] - self.centers[None]) ** 2, -1)
        g = np.exp(-0.5 * d2 / self.sigmas[None] ** 2)
        return g @ self.amps[n] + self.drift[n]

    def shading(self, n: int, pts: np.ndarray) -> np.ndarray:
        a, ph, b = self.shade[n]
        w = self.size[1]
        x, y = pts[:, 0], pts[:, 1]
        s = 1 + a * np.sin(2 * np.pi * x / 300 + ph) * np.cos(2 * np.pi * y / 250) + b * (x / w - 0.5)
        return np.clip(s, 0.6, 1.3)

    def truth(self, n: int, V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """True vertex positions and shading ratios in frame ``n`` of model vertices ``V``."""
        return V + self.displacement(n, V), self.shading(n, V)


#: The "fine" sheets of the dense model's comparison (``pftrack synth deform --fine``): bumps 0.4 times as wide
#: (14-24 px on the default box, finer than a 7 x 7 mesh's cells) and up to ~6 px.
FINE = {"bump_scale": 0.4, "amplitude": 6.0}


def deform_scene(seed: int, n_frames: int = 60, size=(360, 480), amplitude: float = 12.0, shading: bool = True,
                 noise: float = 0.01, texture: np.ndarray | None = None, jpeg: int | None = None,
                 bump_scale: float = 1.0) -> DeformScene:
    """A sequence of ``n_frames`` (the first is the model) of a sheet deforming by up to ~``amplitude`` px
    with shading in [0.6, 1.3] (``shading=False``: constant brightness).  The four Gaussian bumps have widths of
    0.18-0.3 of the box's shorter side times ``bump_scale`` (below 1: deformations finer than a 7 x 7 mesh)."""
    rng = np.random.default_rng(seed)
    h, w = size
    tex = band_limited_texture(rng, size) if texture is None else cv2.resize(texture.astype(np.float64), (w, h))
    box = (w * 0.25, h * 0.22, w * 0.5, h * 0.56)
    B = 4
    centers = np.c_[rng.uniform(box[0], box[0] + box[2], B), rng.uniform(box[1], box[1] + box[3], B)]
    sigmas = rng.uniform(0.18, 0.3, B) * min(box[2], box[3]) * bump_scale
    t = np.arange(n_frames)
    omega = rng.uniform(2 * np.pi / 80, 2 * np.pi / 30, (B, 2))
    phase = rng.uniform(0, 2 * np.pi, (B, 2))
    A = rng.uniform(0.4, 1.0, (B, 2)) * amplitude * rng.choice([-1, 1], (B, 2)) * 0.5
    amps = A[None] * (np.sin(omega[None] * t[:, None, None] + phase[None]) - np.sin(phase)[None])
    dr_w = rng.uniform(2 * np.pi / 120, 2 * np.pi / 60, 2)
    drift = amplitude * 0.5 * np.sin(dr_w[None] * t[:, None]) * rng.choice([-1, 1], 2)
    ramp = np.minimum(t / 15.0, 1.0)
    a0, b0 = rng.uniform(0.15, 0.3), rng.uniform(-0.3, 0.3)
    shade = [(a0 * ramp[n] if shading else 0.0, 0.05 * n, b0 * ramp[n] if shading else 0.0) for n in t]
    sc = DeformScene([], box, centers, sigmas, amps, drift, shade, size, tex)
    sc.frames = render_frames(sc, rng, noise=noise, jpeg=jpeg)
    return sc


@dataclass
class KymoScene:
    """A deforming-sheet scene for a stabilised kymogram (ch13.md T6): the scene, the mesh's box, the region of
    interest, the oscillating patch's centre, the oscillation's amplitude (px, along x) and period (frames)."""

    scene: DeformScene
    box: tuple[float, float, float, float]
    roi: tuple[float, float, float, float]
    centre: np.ndarray
    amplitude: float
    period: float


def kymo_scene(seed: int, n_frames: int = 100, size=(360, 480), jitter: float = 5.0, amplitude: float = 3.0,
               noise: float = 0.01) -> KymoScene:
    """ch13.md T6: a textured sheet under global camera jitter (a translation of at most ``jitter`` px: a slow
    sway with a per-frame shake) with a local oscillation of ``amplitude`` px along x in a 40 x 40 patch (a
    Gaussian bump, sigma 10 px, so 3 px at its centre and 0.4 px at the patch's edge), period 5-9 frames, no
    shading change. The vocal folds of the chapter's kymography vibrate inside a view that the camera shakes."""
    rng = np.random.default_rng(seed)
    h, w = size
    tex = band_limited_texture(rng, size)
    box = (w * 0.125, h * 0.14, w * 0.75, h * 0.72)
    roi = (w * 0.25, h * 0.25, w * 0.5, h * 0.5)
    centre = np.array([rng.uniform(roi[0] + 0.3 * roi[2], roi[0] + 0.7 * roi[2]),
                       rng.uniform(roi[1] + 0.3 * roi[3], roi[1] + 0.7 * roi[3])])
    period = rng.uniform(5.0, 9.0)
    t = np.arange(n_frames)
    sway = np.zeros((n_frames, 2))
    for _ in range(3):
        f = rng.uniform(1 / 60, 1 / 15, 2)
        sway += np.sin(2 * np.pi * f * t[:, None] + rng.uniform(0, 2 * np.pi, 2))
    sway -= sway[0]
    drift = sway + rng.uniform(-1, 1, (n_frames, 2))
    drift[0] = 0.0
    peak = np.max(np.linalg.norm(drift, axis=1))
    drift *= jitter / peak if peak > jitter else 1.0
    amps = np.zeros((n_frames, 1, 2))
    amps[:, 0, 0] = amplitude * np.sin(2 * np.pi * t / period)
    shade = [(0.0, 0.0, 0.0)] * n_frames
    sc = DeformScene([], box, centre[None], np.array([10.0]), amps, drift, shade, size, tex)
    sc.frames = render_frames(sc, rng, noise=noise)
    return KymoScene(sc, box, roi, centre, amplitude, period)


def kymo_scores(ks: KymoScene, transforms, roi=None) -> dict:
    """ch13.md T6's figures from the scene's exact motion, for the stabilising transforms (2 x 3, frame -> first
    frame) of frames 1, 2, ...: ``residual`` (mean over frames) and ``residual_max`` (worst frame), the distance of
    the region's background points (more than 30 px from the vibrating patch) from where they were in frame 0;
    ``raw``, the same without stabilisation; ``survival``, the amplitude of a sine of the scene's period fitted to
    the stabilised x position of the patch's centre, over the vibration's amplitude."""
    from ..surfaces.kymograph import roi_points

    sc = ks.scene
    pts = roi_points(ks.roi if roi is None else roi)
    bg = pts[np.linalg.norm(pts - ks.centre, axis=1) > 30]
    res, raw, xs = [], [], []
    for n, M in enumerate(transforms, start=1):
        y = bg + sc.displacement(n, bg)
        res.append(float(np.mean(np.linalg.norm(y @ M[:, :2].T + M[:, 2] - bg, axis=1))))
        raw.append(float(np.mean(np.linalg.norm(y - bg, axis=1))))
        c = ks.centre + sc.displacement(n, ks.centre[None])[0]
        xs.append(float((M[:, :2] @ c + M[:, 2])[0] - ks.centre[0]))
    t = np.arange(1, len(xs) + 1)
    A = np.c_[np.sin(2 * np.pi * t / ks.period), np.cos(2 * np.pi * t / ks.period), np.ones(len(t))]
    coef = np.linalg.lstsq(A, np.array(xs), rcond=None)[0]
    return {"residual": float(np.mean(res)), "residual_max": float(np.max(res)), "raw": float(np.mean(raw)),
            "survival": float(np.hypot(coef[0], coef[1]) / ks.amplitude)}


def render_frames(sc: DeformScene, rng, noise: float = 0.01, jpeg: int | None = None) -> list[np.ndarray]:
    """Render every frame of ``sc`` from its texture: invert ``y = x + D_n(x)`` by fixed-point iteration on a
    2-px grid (D is smooth), sample the texture there, multiply by the shading, add noise."""
    h, w = sc.size
    tex = sc.texture.astype(np.float32)
    step = 2
    ys, xs = np.mgrid[0:h + step:step, 0:w + step:step].astype(np.float64)
    grid = np.stack([xs.ravel(), ys.ravel()], 1)
    frames = []
    for n in range(len(sc.amps)):
        x = grid.copy()
        for _ in range(80):                      # x + D(x) = y  =>  x = y - D(x)
            x_new = grid - sc.displacement(n, x)
            done = np.max(np.abs(x_new - x)) < 1e-6
            x = x_new
            if done:
                break
        cx = x.reshape(*xs.shape, 2)
        mx = _bilinear(cx[..., 0], np.arange(w) / step, np.arange(h) / step).astype(np.float32)
        my = _bilinear(cx[..., 1], np.arange(w) / step, np.arange(h) / step).astype(np.float32)
        img = cv2.remap(tex, mx, my, cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
        pts = np.stack([mx.ravel(), my.ravel()], 1)
        img = img * sc.shading(n, pts).reshape(h, w) + rng.normal(0, noise, (h, w))
        u8 = np.clip(img * 255 + 0.5, 0, 255).astype(np.uint8)
        if jpeg:
            u8 = cv2.imdecode(cv2.imencode(".jpg", u8, [cv2.IMWRITE_JPEG_QUALITY, int(jpeg)])[1], cv2.IMREAD_GRAYSCALE)
        frames.append(cv2.cvtColor(u8, cv2.COLOR_GRAY2BGR))
    return frames


def export_deform(sc: DeformScene, out, mesh: tuple[int, int] = (7, 7)) -> None:
    """An OTB-like folder: ``img/0001.png``..., ``groundtruth_rect.txt`` (bounding box of the true mesh),
    ``mesh_gt.csv`` (``frame,x0,y0,...`` of a ``rows x cols`` mesh over the first box, frame from 1),
    ``shading_gt.csv`` (the true shading ratio at those vertices) and ``box.txt`` (the initial box)."""
    from pathlib import Path

    from ..surfaces.mesh import Grid

    out = Path(out)
    (out / "img").mkdir(parents=True, exist_ok=True)
    grid = Grid.for_box(sc.box, *mesh)
    V0 = grid.vertices()
    head = "frame," + ",".join(f"x{k},y{k}" for k in range(len(V0)))
    rows, shades, boxes = [head], ["frame," + ",".join(f"s{k}" for k in range(len(V0)))], []
    for n, frame in enumerate(sc.frames):
        cv2.imwrite(str(out / "img" / f"{n + 1:04d}.png"), frame)
        V, s = sc.truth(n, V0)
        rows.append(f"{n + 1}," + ",".join(f"{v:.4f}" for v in V.ravel()))
        shades.append(f"{n + 1}," + ",".join(f"{v:.4f}" for v in s))
        lo, hi = V.min(0), V.max(0)
        boxes.append(f"{lo[0]:.2f},{lo[1]:.2f},{hi[0] - lo[0]:.2f},{hi[1] - lo[1]:.2f}")
    (out / "mesh_gt.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    (out / "shading_gt.csv").write_text("\n".join(shades) + "\n", encoding="utf-8")
    (out / "groundtruth_rect.txt").write_text("\n".join(boxes) + "\n", encoding="utf-8")
    (out / "box.txt").write_text(",".join(f"{v:.2f}" for v in sc.box) + "\n", encoding="utf-8")


def export_kymo(ks: KymoScene, out) -> None:
    """A frame folder for ``pftrack surface --kymogram``: ``img/0001.png``..., ``box.txt`` (the mesh's box),
    ``roi.txt``, ``scanline.txt`` (a horizontal line through the vibrating patch, 80 px long) and ``truth.json``
    (the patch's centre, the vibration's amplitude and period, and the camera's translation per frame)."""
    import json
    from pathlib import Path

    out = Path(out)
    (out / "img").mkdir(parents=True, exist_ok=True)
    for n, frame in enumerate(ks.scene.frames):
        cv2.imwrite(str(out / "img" / f"{n + 1:04d}.png"), frame)
    cx, cy = ks.centre
    (out / "box.txt").write_text(",".join(f"{v:.2f}" for v in ks.box) + "\n", encoding="utf-8")
    (out / "roi.txt").write_text(",".join(f"{v:.2f}" for v in ks.roi) + "\n", encoding="utf-8")
    (out / "scanline.txt").write_text(f"{cx - 40:.2f},{cy:.2f};{cx + 40:.2f},{cy:.2f}\n", encoding="utf-8")
    truth = {"centre": [float(cx), float(cy)], "amplitude": ks.amplitude, "period": ks.period,
             "camera": ks.scene.drift.round(4).tolist()}
    (out / "truth.json").write_text(json.dumps(truth) + "\n", encoding="utf-8")
