"""Synthetic scenes whose nuisances are drawn at random from the seed (GUIDE §8).

A claim tested on one hand-made scene overfits that scene.  These generators draw,
from the seed alone:

* the target's size, aspect, speed, colours and texture;
* distractors of a similar hue (0-3), wandering over the frame;
* the occluder's colour and texture;
* an illumination drift (global, or on the target only);
* grey frames (a monochrome camera).

Scenes:

* :func:`varied_scene` — a wandering target among distractors (accuracy, grey, light);
* :func:`vanish_scene` — the target walks fully behind a wide textured occluder for
  15-35 frames and comes out on the other side (the lost flag and re-acquisition);
* :func:`leave_scene` — the target walks out of the frame and comes back later
  (ground truth NaN while it is out);
* :func:`exit_scene` — the target walks out in a flow of look-alikes heading the same way (the lost
  flag after an exit, and what may be re-acquired);
* :func:`camouflage_scene` — a flipped patch of the background moves over it: only its
  structure tells it apart (book ch. 2).

Every scene records what was drawn in ``SceneSpec.nuisances`` (written to
``meta.json`` by :func:`~pftrack.synth.scenes.export_otb`).
"""

from __future__ import annotations

import cv2
import numpy as np

from .scenes import Occluder, SceneSpec, Target, _wander

W, H = 320, 240


def _hsv_to_bgr(h: float, s: float, v: float) -> tuple[int, int, int]:
    px = np.array([[[h % 180.0, np.clip(s, 0, 255), np.clip(v, 0, 255)]]], dtype=np.uint8)
    b, g, r = cv2.cvtColor(px, cv2.COLOR_HSV2BGR)[0, 0]
    return int(b), int(g), int(r)


def draw_nuisances(rng: np.random.Generator, *, gray: float = 0.3, illumination: float = 0.5,
                   distractors: tuple[int, int] = (0, 3)) -> dict:
    """Draw one scene's nuisances; probabilities of grey frames and of an illumination drift are given."""
    hue = float(rng.uniform(0, 180))
    w = float(rng.uniform(18, 40))
    aspect = float(rng.uniform(1.0, 2.2))
    top = _hsv_to_bgr(hue, rng.uniform(140, 255), rng.uniform(110, 230))
    hue2 = hue + float(rng.choice([0.0, rng.uniform(20, 160)]))
    bottom = _hsv_to_bgr(hue2, rng.uniform(100, 255), rng.uniform(60, 200))
    n_dis = int(rng.integers(distractors[0], distractors[1] + 1))
    dis_colors = []
    for _ in range(n_dis):  # similar hue, different saturation / value
        dh = float(rng.uniform(-12, 12))
        dis_colors.append((_hsv_to_bgr(hue + dh, rng.uniform(120, 255), rng.uniform(90, 240)),
                           _hsv_to_bgr(hue2 + dh, rng.uniform(80, 255), rng.uniform(60, 220))))
    illum = None
    illum_target_only = False
    if rng.random() < illumination:
        # a strong drift: overall gain 0.45-1.6, channels unequal (the light's colour changes too)
        g = float(rng.uniform(0.45, 1.6))
        illum = tuple(float(np.clip(g * rng.uniform(0.8, 1.2), 0.3, 2.0)) for _ in range(3))
        illum_target_only = bool(rng.random() < 0.3)
    return {
        "size": (w, w * aspect),
        "speed": float(rng.uniform(1.0, 4.0)),
        "colors": (top, bottom),
        "texture": float(rng.uniform(4, 20)),
        "distractor_colors": tuple(dis_colors),
        "occluder_color": tuple(int(v) for v in rng.integers(30, 226, 3)),
        "occluder_texture": float(rng.uniform(5, 40)),
        "illumination": illum,
        "illumination_target_only": illum_target_only,
        "gray": bool(rng.random() < gray),
    }


def _distractors(rng, nz: dict, n_frames: int, avoid: tuple[float, float] | None = None) -> list[Target]:
    out = []
    for colors in nz["distractor_colors"]:
        size = tuple(float(v) * rng.uniform(0.85, 1.15) for v in nz["size"])
        start = None
        if avoid is not None:  # start away from the target so the first frame is unambiguous
            for _ in range(20):
                x, y = rng.uniform(size[0], W - size[0]), rng.uniform(size[1] * 0.6, H - size[1] * 0.6)
                if abs(x - avoid[0]) > 2.5 * nz["size"][0] or abs(y - avoid[1]) > 1.5 * nz["size"][1]:
                    start = (x, y)
                    break
        path = _wander(rng, n_frames, W, H, size, speed=nz["speed"] * rng.uniform(0.5, 1.0), start=start, k=3)
        out.append(Target(path=path, size=size, colors=colors, texture=nz["texture"]))
    return out


def _spec(seed: int, n_frames: int, kind: str, nz: dict, targets, occluders=()) -> SceneSpec:
    record = {k: v for k, v in nz.items() if k != "distractor_colors"}
    record["distractors"] = len(nz["distractor_colors"])
    return SceneSpec(n_frames=n_frames, seed=seed, targets=tuple(targets), occluders=tuple(occluders),
                     illumination=nz["illumination"], illumination_target_only=nz["illumination_target_only"],
                     gray=nz["gray"], kind=kind, nuisances=tuple(sorted(record.items())))


def varied_scene(seed: int = 0, n_frames: int = 100, **draw) -> SceneSpec:
    """A target wandering among similar-hued distractors, with random light and grey frames."""
    rng = np.random.default_rng([seed, 71])
    nz = draw_nuisances(rng, **draw)
    path = _wander(rng, n_frames, W, H, nz["size"], speed=nz["speed"], k=4)
    tgt = Target(path=path, size=nz["size"], colors=nz["colors"], texture=nz["texture"])
    # distractors first in the list would be drawn behind; the target is target 0 and drawn first (behind them)
    return _spec(seed, n_frames, "varied", nz, [tgt, *_distractors(rng, nz, n_frames, avoid=path[0][1:])])


def vanish_scene(seed: int = 0, n_frames: int = 120, **draw) -> SceneSpec:
    """The target walks fully behind a wide textured occluder for 15-35 frames, then comes out.

    The occluder is taller than the target and wide enough to hide it completely
    for the drawn number of frames at the drawn speed; distractors of similar hue
    wander in the clutter.  ``meta.json`` lists the hidden frames.
    """
    rng = np.random.default_rng([seed, 72])
    nz = draw_nuisances(rng, **draw)
    w, h = nz["size"]
    hidden_frames = int(rng.integers(15, 36))
    # the run must fit the frame: a visible approach, the occluder, a visible exit
    speed = max(nz["speed"], 1.5)
    run = min(speed * (n_frames - 1), W - w - 4)
    speed = run / (n_frames - 1)
    w_max = speed * (n_frames - 1 - hidden_frames) / 3.4
    if w > w_max:  # shrink the target (keeping its aspect) until it can be hidden that long
        h, w = h * w_max / w, w_max
        run = min(speed * (n_frames - 1), W - w - 4)
    occ_w = w + speed * hidden_frames
    direction = 1.0 if rng.random() < 0.5 else -1.0
    x_start = (W - run) / 2.0 if direction > 0 else (W + run) / 2.0
    x_end = x_start + direction * run
    y = float(rng.uniform(h * 0.6 + 10, H - h * 0.6 - 10))
    y_end = float(np.clip(y + rng.uniform(-15, 15), h * 0.6, H - h * 0.6))
    t_mid = (n_frames - 1) * float(rng.uniform(0.4, 0.6))
    # put the occluder's centre where the target is at t_mid
    xc = x_start + direction * speed * t_mid
    xc = float(np.clip(xc, min(x_start, x_end) + w * 1.2 + occ_w / 2, max(x_start, x_end) - w * 1.2 - occ_w / 2))
    occ_h = h * float(rng.uniform(1.4, 2.2)) + abs(y_end - y)
    yc = (y + y_end) / 2.0
    occ = Occluder(box=(xc - occ_w / 2.0, yc - occ_h / 2.0, occ_w, occ_h), color=nz["occluder_color"],
                   texture=nz["occluder_texture"])
    tgt = Target(path=((0, x_start, y), (n_frames - 1, x_end, y_end)), size=(w, h), colors=nz["colors"],
                 texture=nz["texture"])
    nz = {**nz, "size": (w, h), "speed": speed, "occluder_width": occ_w, "hidden_frames": hidden_frames}
    return _spec(seed, n_frames, "vanish", nz, [tgt, *_distractors(rng, nz, n_frames, avoid=(x_start, y))], [occ])


def leave_scene(seed: int = 0, n_frames: int = 140, **draw) -> SceneSpec:
    """The target walks out of the frame, stays out for 15-40 frames and walks back in."""
    rng = np.random.default_rng([seed, 73])
    nz = draw_nuisances(rng, **draw)
    w, h = nz["size"]
    speed = float(np.clip(nz["speed"], 2.0, 4.0))
    out_frames = int(rng.integers(15, 41))
    side = -1.0 if rng.random() < 0.5 else 1.0
    edge_out = -w if side < 0 else W + w  # centre fully outside
    x0 = float(np.clip(edge_out - side * speed * rng.uniform(20, 35), w, W - w))
    y = float(rng.uniform(h * 0.6 + 5, H - h * 0.6 - 5))
    t_exit = abs(edge_out - x0) / speed
    t_back = t_exit + out_frames
    # comes back in (same side) and walks back towards the centre
    t_in = t_back + abs(edge_out - x0) * 0.6 / speed
    path = ((0, x0, y), (t_exit, edge_out, y), (t_back, edge_out, y + rng.uniform(-20, 20)),
            (t_in, edge_out - side * abs(edge_out - x0) * 0.6, y),
            (n_frames - 1, edge_out - side * abs(edge_out - x0) * 0.6, y))
    tgt = Target(path=path, size=(w, h), colors=nz["colors"], texture=nz["texture"])
    nz = {**nz, "speed": speed, "out_frames": out_frames}
    return _spec(seed, n_frames, "leave", nz, [tgt, *_distractors(rng, nz, n_frames, avoid=(x0, y))])


def camouflage_scene(seed: int = 0, n_frames: int = 150, **draw) -> SceneSpec:
    """A target cut from the background itself (flipped): colour cannot find it, structure can.

    Book ch. 2's decisive scene (ch02.md §5.2 S1): smoothed colour-noise background; the
    target (about 32x48, drawn from the seed) is a background patch flipped on both axes,
    so its colour histogram is a background patch's; it moves on a Lissajous path
    (at most ~4 px/frame) while a global illumination gain falls to 0.55-0.8.
    """
    rng = np.random.default_rng([seed, 75])
    w = float(rng.uniform(26, 38))
    h = w * float(rng.uniform(1.2, 1.7))
    ax, ay = float(rng.uniform(70, 100)), float(rng.uniform(40, 60))
    fx, fy = float(rng.uniform(0.02, 0.035)), float(rng.uniform(0.02, 0.035))
    ph = float(rng.uniform(0, 2 * np.pi))
    ts = np.arange(n_frames, dtype=np.float64)
    xs = W / 2 + ax * np.sin(fx * ts + ph)
    ys = H / 2 + ay * np.sin(fy * ts)
    gain = float(rng.uniform(0.55, 0.8))
    tgt = Target(path=tuple(zip(ts, xs, ys)), size=(w, h), texture=0.0, shape="camouflage")
    nz = {"size": (w, h), "speed": float(np.hypot(ax * fx, ay * fy)), "illumination_gain": gain}
    return SceneSpec(n_frames=n_frames, seed=seed, targets=(tgt,), background="noise", noise=2.0,
                     illumination=(gain, gain, gain), kind="camouflage", nuisances=tuple(sorted(nz.items())))


def exit_path(rng: np.random.Generator, n_frames: int, w: float, h: float, speed: float, grow: float = 1.0):
    """The path of a target of size ``(w, h)`` (up to ``grow`` times larger) that walks out through a side edge at
    ``speed`` and, with probability 0.5, comes back through it 15-40 frames later (an exit scene's target).

    Returns ``(path, side, edge_out, x0, t_exit, comes_back)``: the waypoints, the edge (-1 left, +1 right), the
    centre's x where the box is wholly outside, the start's x, the frame it is out at, and whether it comes back."""
    side = -1.0 if rng.random() < 0.5 else 1.0
    edge_out = -w * grow if side < 0 else W + w * grow  # the centre where the box is wholly outside
    x0 = float(np.clip(edge_out - side * speed * rng.uniform(25, 40), w * grow, W - w * grow))
    y0 = float(rng.uniform(h * grow * 0.6 + 5, H - h * grow * 0.6 - 5))
    t_exit = abs(edge_out - x0) / speed
    comes_back = bool(rng.random() < 0.5)
    if comes_back:
        t_back = t_exit + int(rng.integers(15, 41))
        x_in = edge_out - side * min(abs(edge_out - x0), 4.0 * w)
        t_in = t_back + abs(edge_out - x_in) / speed
        y_back = float(np.clip(y0 + rng.uniform(-20, 20), h * grow * 0.6 + 5, H - h * grow * 0.6 - 5))
        path = ((0, x0, y0), (t_exit, edge_out, y0), (t_back, edge_out, y_back), (t_in, x_in, y_back),
                (max(n_frames - 1, t_in + 1), x_in, y_back))
    else:
        path = ((0, x0, y0), (t_exit, edge_out, y0), (max(n_frames - 1, t_exit + 1), edge_out, y0))
    return path, side, edge_out, x0, t_exit, comes_back


def exit_walkers(rng: np.random.Generator, n_flow: int, n_frames: int, size: tuple[float, float], speed: float,
                 x0: float, side: float, edge_out: float, t_exit: float, comes_back: bool, out=None) -> list:
    """``(path, size)`` of ``n_flow`` look-alikes heading out through the exit edge of :func:`exit_path` behind the
    target (2-6 target widths behind, at 0.7-1.2 times its speed) and, when the target does not come back, of one
    more walking in through that edge at a drawn time. ``out(s)``: where a walker of size ``s`` ends (default the
    target's ``edge_out``)."""
    w, h = size
    walkers = []
    for _ in range(n_flow):
        s = (w * float(rng.uniform(0.85, 1.15)), h * float(rng.uniform(0.85, 1.15)))
        v = speed * float(rng.uniform(0.7, 1.2))
        xs = float(np.clip(x0 - side * w * rng.uniform(2.0, 6.0), -0.4 * w, W + 0.4 * w))
        ys = float(rng.uniform(s[1] * 0.6 + 5, H - s[1] * 0.6 - 5))
        end = edge_out if out is None else out(s)
        t = abs(end - xs) / v
        walkers.append((((0, xs, ys), (t, end, ys), (max(n_frames - 1, t + 1), end, ys)), s))
    if not comes_back:
        s = (w * float(rng.uniform(0.85, 1.15)), h * float(rng.uniform(0.85, 1.15)))
        t0 = float(t_exit + rng.integers(5, 40))
        ys = float(rng.uniform(s[1] * 0.6 + 5, H - s[1] * 0.6 - 5))
        x_in = edge_out - side * W * 0.5
        t1 = t0 + abs(edge_out - x_in) / speed
        walkers.append((((0, edge_out, ys), (t0, edge_out, ys), (t1, x_in, ys), (max(n_frames - 1, t1 + 1), x_in,
                                                                               ys)), s))
    return walkers


def exit_scene(seed: int = 0, n_frames: int = 140, **draw) -> SceneSpec:
    """The target walks out through a side edge in a flow of look-alikes heading the same way.

    1-3 walkers of similar hue follow it towards the same edge, 2-6 target widths behind, at 0.7-1.2 times its
    speed and a drawn height; they leave too.  With probability 0.5 the target comes back through that edge
    15-40 frames after it left and walks in; with probability 0.5 a look-alike walks in through that edge at a
    drawn time instead (a walker entering is not the target coming back, and nothing in its looks says so).
    Ground truth is NaN while the target is out (a pedestrian flow at an exit, as in PETS 2009 S2.L1)."""
    rng = np.random.default_rng([seed, 77])
    nz = draw_nuisances(rng, distractors=(3, 3), **draw)  # the look-alikes' colours: similar hue
    w, h = nz["size"]
    speed = float(np.clip(nz["speed"], 1.5, 4.0))
    path, side, edge_out, x0, t_exit, comes_back = exit_path(rng, n_frames, w, h, speed)
    tgt = Target(path=path, size=(w, h), colors=nz["colors"], texture=nz["texture"])
    hue_like = nz["distractor_colors"]
    n_flow = int(rng.integers(1, 4))
    colors = [hue_like[k] for k in range(n_flow)] + ([] if comes_back else [hue_like[2]])  # the last walks in
    walkers = [Target(path=p, size=size, colors=c, texture=nz["texture"]) for c, (p, size) in
               zip(colors, exit_walkers(rng, n_flow, n_frames, (w, h), speed, x0, side, edge_out, t_exit, comes_back))]
    nz = {**nz, "speed": speed, "comes_back": comes_back, "distractor_colors": tuple(t.colors for t in walkers)}
    return _spec(seed, n_frames, "exit", nz, [tgt, *walkers])


def teleport_scene(seed: int = 0, n_frames: int = 110, **draw) -> SceneSpec:
    """Sudden motion and full occlusion (book ch. 6's switching claims; ch06.md §5.2).

    The target moves smoothly, then at a drawn frame (30-45) jumps by 130-200 px (a "teleport":
    a camera cut or a dropped run of frames); later it walks behind a full occluder for 8-14
    frames; a distractor of similar hue wanders in the scene.  Nuisances (colours, texture,
    lighting, grey frames) are drawn from the seed.  ``meta.json`` records the jump frame.
    """
    rng = np.random.default_rng([seed, 76])
    nz = draw_nuisances(rng, distractors=(1, 1), **draw)
    w, h = nz["size"]
    jump_at = int(rng.integers(30, 46))
    occluded_for = int(rng.integers(8, 15))
    y0 = float(rng.uniform(h * 0.6 + 10, H - h * 0.6 - 10))
    left = rng.random() < 0.5
    x0 = float(rng.uniform(w + 5, 70)) if left else float(rng.uniform(W - 70, W - w - 5))
    speed = float(rng.uniform(0.8, 1.6)) * (1.0 if left else -1.0)
    x_jump = x0 + speed * (jump_at - 1)
    dist = float(rng.uniform(130, 200))
    x_land = float(np.clip(x_jump + (dist if left else -dist), w + 5, W - w - 5))
    y_land = float(np.clip(y0 + rng.uniform(-40, 40), h * 0.6 + 5, H - h * 0.6 - 5))
    # after landing it walks back towards the middle, behind an occluder
    back = -1.0 if left else 1.0
    t_occ = jump_at + int(rng.integers(12, 20))
    v2 = float(rng.uniform(1.5, 2.5)) * back
    x_occ = x_land + v2 * (t_occ - jump_at)
    occ_w = w + abs(v2) * occluded_for
    # centre the occluder on the run: the target enters at t_occ and leaves ~occluded_for frames later
    cx = x_occ + back * occ_w / 2.0
    occ = Occluder(box=(cx - occ_w / 2.0, y_land - h, occ_w, 2.0 * h), color=nz["occluder_color"],
                   texture=nz["occluder_texture"])
    x_end = float(np.clip(x_land + v2 * (n_frames - 1 - jump_at), w, W - w))
    path = ((0, x0, y0), (jump_at - 1, x_jump, y0), (jump_at, x_land, y_land), (n_frames - 1, x_end, y_land))
    tgt = Target(path=path, size=(w, h), colors=nz["colors"], texture=nz["texture"])
    nz = {**nz, "jump_at": jump_at, "jump_px": abs(x_land - x_jump), "occluder_width": occ_w}
    return _spec(seed, n_frames, "teleport", nz, [tgt, *_distractors(rng, nz, n_frames, avoid=(x0, y0))], [occ])


#: the scenes whose nuisances (grey frames among them) come from draw_nuisances, so they accept its arguments
DRAWN_NUISANCE_SCENES = ("exit", "leave", "teleport", "vanish", "varied")

VARIED_SCENES = {
    "camouflage": camouflage_scene,
    "teleport": teleport_scene,
    "varied": varied_scene,
    "vanish": vanish_scene,
    "leave": leave_scene,
    "exit": exit_scene,
}


def hidden_frames(spec: SceneSpec, target: int = 0, below: float | None = None) -> np.ndarray:
    """Bool per frame: the target is out of the frame or less than ``below`` visible."""
    from .scenes import HIDDEN_BELOW, Scene

    thr = HIDDEN_BELOW if below is None else below
    scene = Scene(spec)
    out = np.zeros(spec.n_frames, dtype=bool)
    for t in range(spec.n_frames):
        truth = scene.truth(t)
        out[t] = (not truth.present[target]) or truth.visible[target] < thr
    return out

