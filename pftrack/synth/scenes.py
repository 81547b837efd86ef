"""Seeded synthetic scenes with exact ground truth.

A :class:`SceneSpec` describes a textured background, coloured targets moving
along piecewise-linear paths (entering and leaving), static occluders drawn in
front of everything, and an optional illumination drift.  :class:`Scene`
renders it frame by frame; the same spec and seed always give the same pixels.

Ground truth per frame and target: the exact box ``(x, y, w, h)`` of the target
(NaN when it is outside the frame or not yet/no longer present) and its
visible fraction after occluders and targets in front of it.

>>> scene = Scene(crossing_scene(seed=0))
>>> frame, truth = scene.render(0)
>>> truth.boxes.shape
(2, 4)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from ..geometry import clip_box
from ..io.datasets import write_groundtruth

Color = tuple[int, int, int]

# Background hues are kept away from the target palette so that a correct tracker
# has a well-defined answer; distractors reuse the target's colours on purpose.
_BG_PALETTE = np.array([
    [90, 110, 95], [120, 125, 110], [70, 90, 120], [140, 140, 130], [100, 130, 150], [60, 80, 70],
    [150, 120, 100], [110, 100, 140],
], dtype=np.float64)


@dataclass(frozen=True)
class Target:
    """A moving object.

    ``path`` is a sequence of ``(frame, cx, cy)`` waypoints, linearly interpolated
    (held constant before the first and after the last).  ``size`` is ``(w, h)`` at
    frame 0 and changes by ``scale_rate`` per frame (multiplicatively).  The target
    exists for ``appear <= t < disappear``.  ``colors`` are the BGR colours of the
    upper and lower halves; ``texture`` adds a fixed speckle pattern of that
    amplitude that moves with the target.
    """

    path: tuple[tuple[float, float, float], ...]
    size: tuple[float, float] = (30.0, 60.0)
    colors: tuple[Color, Color] = ((40, 40, 200), (200, 120, 40))
    texture: float = 12.0
    scale_rate: float = 0.0
    appear: int = 0
    disappear: int | None = None
    shape: str = "ellipse"  # "ellipse" | "rect" | "camouflage" (a flipped patch of the background, rectangular)

    def center(self, t: float) -> tuple[float, float]:
        pts = np.asarray(self.path, dtype=np.float64).reshape(-1, 3)
        return float(np.interp(t, pts[:, 0], pts[:, 1])), float(np.interp(t, pts[:, 0], pts[:, 2]))

    def size_at(self, t: float) -> tuple[float, float]:
        f = (1.0 + self.scale_rate) ** t
        return self.size[0] * f, self.size[1] * f

    def present(self, t: int) -> bool:
        return t >= self.appear and (self.disappear is None or t < self.disappear)

    def box(self, t: int) -> np.ndarray:
        cx, cy = self.center(t)
        w, h = self.size_at(t)
        return np.array([cx - w / 2.0, cy - h / 2.0, w, h])


@dataclass(frozen=True)
class Occluder:
    """A static textured rectangle drawn in front of every target."""

    box: tuple[float, float, float, float]
    color: Color = (110, 110, 110)
    texture: float = 20.0


@dataclass(frozen=True)
class SceneSpec:
    width: int = 320
    height: int = 240
    n_frames: int = 100
    seed: int = 0
    targets: tuple[Target, ...] = ()
    occluders: tuple[Occluder, ...] = ()
    background: str = "texture"  # "texture" | "flat" | "noise" (smoothed colour noise)
    noise: float = 3.0  # std of per-frame pixel noise
    illumination: tuple[float, float, float] | None = None  # BGR gain reached at the last frame (linear drift)
    illumination_target_only: bool = False
    camera_path: tuple[tuple[float, float, float], ...] = ()  # (frame, dx, dy): background pan
    gray: bool = False  # render grey frames (all three channels equal), as from a monochrome camera
    kind: str = ""  # the generator's name, written to meta.json
    nuisances: tuple[tuple[str, object], ...] = ()  # what the generator drew from the seed (meta.json)


@dataclass(frozen=True)
class Truth:
    """Ground truth of one frame: one row per target."""

    boxes: np.ndarray  # (n_targets, 4), NaN when absent
    visible: np.ndarray  # (n_targets,) visible fraction in [0, 1]
    present: np.ndarray  # (n_targets,) bool: inside the frame and existing


def _speckle(rng: np.random.Generator, h: int, w: int, amp: float) -> np.ndarray:
    if amp <= 0:
        return np.zeros((h, w, 3), np.float32)
    small = rng.normal(0.0, 1.0, (max(2, h // 3), max(2, w // 3), 3)).astype(np.float32)
    big = cv2.resize(small, (w, h), interpolation=cv2.INTER_LINEAR)
    return big * amp


class Scene:
    """Renders a :class:`SceneSpec` (random access by frame index)."""

    def __init__(self, spec: SceneSpec):
        self.spec = spec
        rng = np.random.default_rng(spec.seed)
        pad = 64
        self._pad = pad
        H, W = spec.height + 2 * pad, spec.width + 2 * pad
        if spec.background == "noise":
            # colour noise smoothed with sigma 2 (book ch. 2's camouflage scene, ch02.md S1)
            bg = rng.normal(128.0, 90.0, (H, W, 3)).astype(np.float32)
            bg = cv2.GaussianBlur(bg, (0, 0), 2.0)
        elif spec.background == "texture":
            coarse = _BG_PALETTE[rng.integers(0, len(_BG_PALETTE), (H // 24 + 2, W // 24 + 2))]
            bg = cv2.resize(coarse.astype(np.float32), (W, H), interpolation=cv2.INTER_CUBIC)
            bg += _speckle(rng, H, W, 10.0)
            # a few structured blobs and lines (edges, texture for flow)
            for _ in range(12):
                c = _BG_PALETTE[rng.integers(0, len(_BG_PALETTE))] + rng.normal(0, 10, 3)
                x, y = int(rng.integers(0, W)), int(rng.integers(0, H))
                cv2.rectangle(bg, (x, y), (x + int(rng.integers(10, 60)), y + int(rng.integers(10, 60))),
                              tuple(float(v) for v in c), -1)
            fine = rng.normal(0.0, 8.0, (H, W, 1)).astype(np.float32)
            bg += fine
        else:
            bg = np.full((H, W, 3), 120.0, np.float32)
        self._bg = bg
        self._sprites = []
        for k, tgt in enumerate(spec.targets):
            srng = np.random.default_rng([spec.seed, 1000 + k])
            base_w, base_h = 64, int(round(64 * tgt.size[1] / tgt.size[0]))
            sprite = np.zeros((base_h, base_w, 3), np.float32)
            sprite[: base_h // 2] = tgt.colors[0]
            sprite[base_h // 2:] = tgt.colors[1]
            sprite += _speckle(srng, base_h, base_w, tgt.texture)
            if tgt.shape == "camouflage":
                # a patch of this very background, flipped on both axes: its colour histogram is a
                # background patch's, only its structure differs
                bw, bh = int(round(tgt.size[0])), int(round(tgt.size[1]))
                px = int(srng.integers(pad, W - pad - bw))
                py = int(srng.integers(pad, H - pad - bh))
                patch = bg[py:py + bh, px:px + bw][::-1, ::-1]
                sprite = cv2.resize(np.ascontiguousarray(patch), (base_w, base_h), interpolation=cv2.INTER_LINEAR)
            mask = np.zeros((base_h, base_w), np.float32)
            if tgt.shape == "ellipse":
                cv2.ellipse(mask, ((base_w / 2.0, base_h / 2.0), (float(base_w), float(base_h)), 0.0), 1.0, -1,
                            lineType=cv2.LINE_AA)
            else:
                mask[:] = 1.0
            self._sprites.append((sprite, mask))
        self._occ = []
        for k, occ in enumerate(spec.occluders):
            orng = np.random.default_rng([spec.seed, 2000 + k])
            x, y, w, h = occ.box
            patch = np.full((max(1, int(round(h))), max(1, int(round(w))), 3), occ.color, np.float32)
            patch += _speckle(orng, patch.shape[0], patch.shape[1], occ.texture)
            self._occ.append(patch)

    def __len__(self) -> int:
        return self.spec.n_frames

    def _alpha(self, k: int, box) -> tuple[np.ndarray, tuple[slice, slice], np.ndarray | None]:
        """Target ``k``'s coverage of the frame with its sprite warped into ``box`` (sub-pixel): the full-frame mask,
        the window of the frame outside which it is 0, and the affine map of the warp into that window (None when
        the window is empty)."""
        x, y, w, h = box
        mask = self._sprites[k][1]
        sh, sw = mask.shape
        H, W = self.spec.height, self.spec.width
        alpha_full = np.zeros((H, W), np.float32)
        x0, y0 = max(0, int(math.floor(x)) - 1), max(0, int(math.floor(y)) - 1)
        x1, y1 = min(W, int(math.ceil(x + w)) + 1), min(H, int(math.ceil(y + h)) + 1)
        if x1 <= x0 or y1 <= y0:
            return alpha_full, (slice(0, 0), slice(0, 0)), None
        M = np.array([[w / sw, 0.0, x - x0], [0.0, h / sh, y - y0]], dtype=np.float64)
        alpha_full[y0:y1, x0:x1] = cv2.warpAffine(mask, M, (x1 - x0, y1 - y0), flags=cv2.INTER_LINEAR,
                                                  borderMode=cv2.BORDER_CONSTANT)
        return alpha_full, (slice(y0, y1), slice(x0, x1)), M

    def _place(self, canvas: np.ndarray, k: int, alpha_full: np.ndarray, win: tuple[slice, slice], M) -> None:
        """Blend target ``k``'s sprite into ``canvas`` through its coverage (:meth:`_alpha`)."""
        if M is None:
            return
        region = canvas[win]
        size = (region.shape[1], region.shape[0])
        # the sprite's colours are replicated past its edge (the mask does the blending), so interpolation
        # does not draw a dark outline around the target
        warped = cv2.warpAffine(self._sprites[k][0], M, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        a3 = alpha_full[win][..., None]
        region *= 1.0 - a3
        region += warped * a3

    def _coverage(self, t: int) -> tuple[list, Truth]:
        """Each target's coverage on frame ``t`` (:meth:`_alpha`; None when absent) and the frame's truth: targets
        drawn later hide earlier ones, and the occluders, drawn last, hide them all."""
        spec = self.spec
        n = len(spec.targets)
        boxes = np.full((n, 4), np.nan)
        present = np.zeros(n, bool)
        areas = np.zeros(n)
        placed: list = [None] * n
        covers = [np.ones((spec.height, spec.width), np.float32) for _ in range(n)]
        for k, tgt in enumerate(spec.targets):
            if not tgt.present(t):
                continue
            box = tgt.box(t)
            placed[k] = alpha, win, _ = self._alpha(k, box)
            for j in range(k):  # only in the window: 1 - alpha is 1 outside it
                if placed[j] is not None:
                    covers[j][win] *= 1.0 - alpha[win]
            covers[k] = alpha.copy()
            areas[k] = float(alpha.sum())
            if areas[k] > 0:
                boxes[k] = box
                present[k] = True
        for _, _, (x0, y0, x1, y1) in self._occluder_windows():
            for c in covers:  # the occluder hides whatever lies under it
                c[y0:y1, x0:x1] *= 0.0
        visible = np.zeros(n)
        for k in range(n):
            if present[k] and areas[k] > 0:
                visible[k] = float(covers[k].sum()) / areas[k]
        return placed, Truth(boxes=boxes, visible=np.clip(visible, 0.0, 1.0), present=present)

    def _occluder_windows(self):
        """Per occluder that reaches into the frame: its patch, the patch's corner ``(x, y)`` on the frame and the
        window ``(x0, y0, x1, y1)`` of the frame it covers."""
        spec = self.spec
        for occ, patch in zip(spec.occluders, self._occ):
            x, y = int(round(occ.box[0])), int(round(occ.box[1]))
            x1, y1 = min(spec.width, x + patch.shape[1]), min(spec.height, y + patch.shape[0])
            x0, y0 = max(0, x), max(0, y)
            if x1 > x0 and y1 > y0:
                yield patch, (x, y), (x0, y0, x1, y1)

    def truth(self, t: int) -> Truth:
        """Frame ``t``'s ground truth alone (as :meth:`render` gives it, without drawing the frame)."""
        if not 0 <= t < self.spec.n_frames:
            raise IndexError(f"frame {t} outside 0..{self.spec.n_frames - 1}")
        return self._coverage(t)[1]

    def render(self, t: int) -> tuple[np.ndarray, Truth]:
        """Frame ``t`` (BGR uint8) and its ground truth."""
        spec = self.spec
        if not 0 <= t < spec.n_frames:
            raise IndexError(f"frame {t} outside 0..{spec.n_frames - 1}")
        pad = self._pad
        dx = dy = 0.0
        if spec.camera_path:
            pts = np.asarray(spec.camera_path, dtype=np.float64).reshape(-1, 3)
            dx = float(np.interp(t, pts[:, 0], pts[:, 1]))
            dy = float(np.interp(t, pts[:, 0], pts[:, 2]))
        M = np.array([[1.0, 0.0, -pad - dx], [0.0, 1.0, -pad - dy]])
        canvas = cv2.warpAffine(self._bg, M, (spec.width, spec.height), flags=cv2.INTER_LINEAR,
                                borderMode=cv2.BORDER_REFLECT)
        gain = np.ones(3, np.float32)
        if spec.illumination is not None and spec.n_frames > 1:
            f = t / (spec.n_frames - 1)
            gain = (1.0 - f) + f * np.asarray(spec.illumination, np.float32)
        placed, truth = self._coverage(t)
        tgt_layer = canvas.copy() if spec.illumination_target_only else None
        for k, pl in enumerate(placed):
            if pl is not None:
                self._place(tgt_layer if tgt_layer is not None else canvas, k, *pl)
        if tgt_layer is not None:
            tmask = np.zeros((spec.height, spec.width), np.float32)
            for pl in placed:
                if pl is not None:
                    tmask = np.maximum(tmask, pl[0])
            lit = tgt_layer * gain
            canvas = canvas * (1.0 - tmask[..., None]) + lit * tmask[..., None]
        else:
            canvas *= gain
        for patch, (x, y), (x0, y0, x1, y1) in self._occluder_windows():
            canvas[y0:y1, x0:x1] = patch[y0 - y: y1 - y, x0 - x: x1 - x] * gain
        if spec.noise > 0:
            nrng = np.random.default_rng([spec.seed, 3, t])
            canvas += nrng.standard_normal(canvas.shape, dtype=np.float32) * np.float32(spec.noise)
        frame = np.clip(canvas + 0.5, 0, 255).astype(np.uint8)
        if spec.gray:
            frame = cv2.cvtColor(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR)
        return frame, truth

    def __iter__(self):
        for t in range(self.spec.n_frames):
            yield self.render(t)

    def frames(self) -> list[np.ndarray]:
        return [self.render(t)[0] for t in range(self.spec.n_frames)]

    def groundtruth(self, target: int = 0) -> np.ndarray:
        """``(n_frames, 4)`` boxes of one target (NaN where absent)."""
        return np.array([self.spec.targets[target].box(t) if self.spec.targets[target].present(t) else
                         np.full(4, np.nan) for t in range(self.spec.n_frames)])


# ------------------------------------------------------------------------------ ready-made scenes

def _wander(rng: np.random.Generator, n: int, w: int, h: int, size, speed: float, start=None, k: int = 4):
    """Waypoints of a smooth random walk that stays inside the frame."""
    margin_x, margin_y = size[0], size[1] * 0.6
    pts = []
    x, y = start if start is not None else (rng.uniform(margin_x, w - margin_x), rng.uniform(margin_y, h - margin_y))
    for i in range(k + 1):
        t = i * (n - 1) / k
        pts.append((t, x, y))
        step = speed * (n - 1) / k
        ang = rng.uniform(0, 2 * math.pi)
        x = float(np.clip(x + step * math.cos(ang), margin_x, w - margin_x))
        y = float(np.clip(y + step * math.sin(ang), margin_y, h - margin_y))
    return tuple(pts)


def simple_scene(seed: int = 0, n_frames: int = 80, **kw) -> SceneSpec:
    """One target wandering over a textured background."""
    rng = np.random.default_rng(seed)
    tgt = Target(path=_wander(rng, n_frames, 320, 240, (30, 60), speed=2.0), size=(30, 60))
    return SceneSpec(n_frames=n_frames, seed=seed, targets=(tgt,), **kw)


def occlusion_scene(seed: int = 0, n_frames: int = 90, *, full: bool = False) -> SceneSpec:
    """A target walking left to right behind a static occluder.

    With ``full=False`` the occluder hides the lower part of the target (partial
    occlusion); with ``full=True`` it is taller than the target, which disappears
    completely for about 20 frames.
    """
    rng = np.random.default_rng(seed)
    y = float(rng.uniform(100, 140))
    path = ((0, 30.0, y), (n_frames - 1, 290.0, y))
    tgt = Target(path=path, size=(28, 56))
    if full:
        occ = Occluder(box=(140.0, y - 60.0, 80.0, 120.0))
    else:
        occ = Occluder(box=(130.0, y + 5.0, 60.0, 60.0))
    return SceneSpec(n_frames=n_frames, seed=seed, targets=(tgt,), occluders=(occ,))


def illumination_scene(seed: int = 0, n_frames: int = 120, gain=(0.45, 0.55, 0.7)) -> SceneSpec:
    """A wandering target whose colours drift as the light changes (target only)."""
    rng = np.random.default_rng(seed)
    tgt = Target(path=_wander(rng, n_frames, 320, 240, (30, 60), speed=1.5), size=(30, 60))
    return SceneSpec(n_frames=n_frames, seed=seed, targets=(tgt,), illumination=tuple(gain),
                     illumination_target_only=True)


def entering_scene(seed: int = 0, n_frames: int = 80, enter_at: int = 15) -> SceneSpec:
    """An empty scene that a target enters from the left edge at frame ``enter_at``."""
    rng = np.random.default_rng(seed)
    y = float(rng.uniform(90, 150))
    path = ((enter_at, -20.0, y), (n_frames - 1, 250.0, y + rng.uniform(-30, 30)))
    tgt = Target(path=path, size=(30, 60), appear=enter_at)
    return SceneSpec(n_frames=n_frames, seed=seed, targets=(tgt,))


def crossing_scene(seed: int = 0, n_frames: int = 80, *, same_colors: bool = True) -> SceneSpec:
    """The target and a visually identical distractor cross; the distractor passes in front.

    Speeds (2-4 px/frame each), heights and slopes are drawn from the seed, so the
    crossings differ in duration and geometry.
    """
    rng = np.random.default_rng(seed)
    y0 = float(rng.uniform(90, 150))
    ya, yb = y0 + rng.uniform(-8, 8), y0 + rng.uniform(-8, 8)
    va, vb = rng.uniform(2.0, 4.0), rng.uniform(2.0, 4.0)
    t_cross = (n_frames - 1) * rng.uniform(0.4, 0.6)
    xc = 160.0 + rng.uniform(-20, 20)
    t_end = n_frames - 1
    # keep both inside the frame for the whole clip
    vmax = min((xc - 16.0) / t_cross, (304.0 - xc) / (t_end - t_cross))
    va, vb = min(va, vmax), min(vb, vmax)
    tgt = Target(path=((0, xc - va * t_cross, ya - rng.uniform(-10, 10)), (t_end, xc + va * (t_end - t_cross), ya)),
                 size=(28, 56))
    colors = tgt.colors if same_colors else ((60, 180, 60), (180, 60, 160))
    dis = Target(path=((0, xc + vb * t_cross, yb), (t_end, xc - vb * (t_end - t_cross), yb + rng.uniform(-10, 10))),
                 size=(28, 56), colors=colors)
    return SceneSpec(n_frames=n_frames, seed=seed, targets=(tgt, dis))


def waving_scene(seed: int = 0, n_frames: int = 200, *, crossings: int = 6, amplitude: float = 70.0) -> SceneSpec:
    """Two visually identical targets swinging past each other like waving hands.

    They move in opposite phase along a horizontal sinusoid and cross ``crossings``
    times; the distractor (target 1) passes in front of the target (target 0) at
    every crossing, hiding it completely for a few frames.  This is the situation
    where colour alone is ambiguous (Kristan et al., hands experiment).
    """
    rng = np.random.default_rng(seed)
    cx, cy = 160.0 + rng.uniform(-15, 15), 120.0 + rng.uniform(-20, 20)
    omega = math.pi * crossings / (n_frames - 1)
    phase = rng.uniform(0.2, 0.5)
    dy = rng.uniform(-6, 6)
    ts = np.arange(n_frames, dtype=np.float64)
    xa = cx + amplitude * np.cos(omega * ts + phase)
    xb = cx - amplitude * np.cos(omega * ts + phase)
    ya = cy + 8.0 * np.sin(2.3 * omega * ts)
    tgt = Target(path=tuple(zip(ts, xa, ya)), size=(26, 52))
    dis = Target(path=tuple(zip(ts, xb, ya + dy)), size=(26, 52))
    return SceneSpec(n_frames=n_frames, seed=seed, targets=(tgt, dis))


#: A target with less than this visible fraction counts as fully hidden (``hidden`` frames of meta.json).
HIDDEN_BELOW = 0.1


def export_otb(spec: SceneSpec, folder, *, target: int = 0, ext: str = ".png") -> None:
    """Write a scene as an OTB sequence folder.

    ``img/``, ``groundtruth_rect.txt`` (the part of the target's box inside the frame; NaN rows where the
    target is out of the frame),
    ``attrs.txt`` and ``meta.json``: the generator, seed and nuisances, the target's
    visible fraction per frame and its ``hidden`` frames (numbers from 1: out of the
    frame, or less than :data:`HIDDEN_BELOW` visible), which ``pftrack eval`` uses to
    score the lost flag.
    """
    scene = Scene(spec)
    visible: list[float] = []

    def frames():
        for t in range(spec.n_frames):
            frame, truth = scene.render(t)
            visible.append(float(truth.visible[target]) if truth.present[target] else 0.0)
            yield frame

    write_otb_folder(folder, frames(), visible, lambda: scene.groundtruth(target), spec.width, spec.height,
                     {"kind": spec.kind, "seed": spec.seed, "gray": spec.gray,
                      "nuisances": {k: v for k, v in spec.nuisances}}, ext=ext)


def write_otb_folder(folder, frames, visible: list[float], boxes, width: int, height: int, meta: dict, *,
                     ext: str = ".png") -> None:
    """Write rendered frames as an OTB folder with the ``meta.json`` that ``pftrack eval`` scores the lost flag by.

    ``frames`` is iterated once (each frame written as it comes); ``visible`` holds the target's visible fraction
    per frame once they are written (the renderer may fill it while ``frames`` runs), and ``boxes`` is a callable
    giving the target's whole boxes ``(n, 4)`` then. ``meta`` (the generator, seed, ...) is completed with the
    visible fractions and the ``hidden`` frames.
    """
    import json
    from pathlib import Path

    folder = Path(folder)
    (folder / "img").mkdir(parents=True, exist_ok=True)
    for t, frame in enumerate(frames):
        cv2.imwrite(str(folder / "img" / f"{t + 1:04d}{ext}"), frame)
    hidden = [t + 1 for t, v in enumerate(visible) if v < HIDDEN_BELOW]
    meta = {**meta, "hidden_below": HIDDEN_BELOW, "hidden": hidden, "visible": [round(v, 4) for v in visible]}
    (folder / "meta.json").write_text(json.dumps(meta, default=_jsonable) + "\n", encoding="utf-8")
    # the box's part inside the frame, as single-object benchmarks annotate a target at the image's edge (the
    # whole box, beyond the edge, is the scene's own ``groundtruth``); NaN where nothing of the target is visible
    # (out of the frame, or wholly behind an occluder). A target partly hidden keeps its box
    gt = clip_box(np.asarray(boxes(), dtype=np.float64), width, height)
    gt[np.asarray(visible) <= 0.0] = np.nan
    write_groundtruth(folder / "groundtruth_rect.txt", gt, decimals=3)
    (folder / "attrs.txt").write_text(f"synthetic, seed {meta.get('seed')}\n", encoding="utf-8")


def _jsonable(v):
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    return str(v)
