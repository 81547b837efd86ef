"""Top-down traffic across a tripwire, with exact tracks (book ch. 10 experiments, ch10.md §5.2).

Vehicles are textured rectangles with a saturated body colour and dark windows, driving
along vertical lanes over textured asphalt with lane marks; a horizontal wire crosses the
road.  ``sparse``: well-separated vehicles down one lane group and a few in the opposite
direction on another lane.  ``dense``: bumper-to-bumper queues with a red light that
stops them for ``stop_frames`` with the queue heads just past the wire (the stopped
vehicles sit on the wire and the background model absorbs them), a few long buses.

The scene is written as a MOTChallenge folder (``img1/``, ``gt/gt.txt``, ``seqinfo.ini``)
plus ``wire.txt`` holding the wire as ``x1,y1;x2,y2``; ground-truth crossings come from
the tracks' centres (:func:`pftrack.events.eval.track_crossings` with ``point="centre"``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from ..io.datasets import write_mot_groundtruth, write_seqinfo
from .occluder import paste_sprite

__all__ = ["TrafficScene", "export_traffic", "traffic_scene"]


@dataclass
class TrafficScene:
    frames: list[np.ndarray]
    tracks: np.ndarray          # MOT rows frame,id,x,y,w,h,1,-1,-1,-1 (frames from 1)
    wire: np.ndarray            # (2, 2)
    fps: float
    meta: dict


def _vehicle_sprite(rng, w: int, h: int) -> np.ndarray:
    hue = rng.uniform(0, 180)
    body = cv2.cvtColor(np.uint8([[[hue, rng.uniform(150, 255), rng.uniform(120, 240)]]]), cv2.COLOR_HSV2BGR)[0, 0]
    img = np.empty((h, w, 3), np.float32)
    img[:] = body
    img += rng.normal(0, 6, (h, w, 1)).astype(np.float32)
    wy0, wy1 = int(0.2 * h), int(0.35 * h)
    img[wy0:wy1, int(0.15 * w):int(0.85 * w)] = (40, 40, 45)   # windscreen
    ry0, ry1 = int(0.75 * h), int(0.85 * h)
    img[ry0:ry1, int(0.2 * w):int(0.8 * w)] = (50, 50, 55)     # rear window
    return np.clip(img, 0, 255)


def _background(rng, h: int, w: int, lanes_x: list[float], lane_w: float) -> np.ndarray:
    bg = np.clip(rng.normal(90, 6, (h, w, 3)), 0, 255).astype(np.float32)
    bg = cv2.GaussianBlur(bg, (0, 0), 0.8)
    bg[:, :, 1] += 2
    for x in lanes_x[:-1]:
        xm = int(round(x + lane_w / 2))
        for y in range(0, h, 24):
            bg[y:y + 12, xm - 1:xm + 1] = 200
    return bg


def traffic_scene(seed: int = 0, *, kind: str = "sparse", n_vehicles: int | None = None, shape=(240, 320),
                  fps: float = 30.0, stop_frames: int = 300) -> TrafficScene:
    """Render a seeded traffic scene (see the module docstring)."""
    if kind not in ("sparse", "dense"):
        raise ValueError("kind must be 'sparse' or 'dense'")
    rng = np.random.default_rng(seed)
    h, w = shape
    n_lanes = 3
    lane_w = 34.0
    x_start = w / 2 - n_lanes * lane_w / 2
    lanes_x = [x_start + k * lane_w for k in range(n_lanes)]
    wire_y = h / 2
    wire = np.array([[x_start - 10, wire_y], [x_start + n_lanes * lane_w + 10, wire_y]])
    n = n_vehicles or (40 if kind == "sparse" else 100)
    # vehicles: lane, direction (+1 down), length, width, speed, sprite
    vehicles = []
    for k in range(n):
        if kind == "sparse":
            lane = int(rng.integers(0, 2)) if k % 4 else 2
        else:
            lane = int(rng.integers(0, n_lanes))
        direction = -1 if (kind == "sparse" and lane == 2) else 1
        bus = kind == "dense" and rng.random() < 0.05
        length = int(rng.integers(40, 71)) if not bus else 150
        width = int(rng.integers(20, 27))
        speed = rng.uniform(2.0, 6.0) if kind == "sparse" else rng.uniform(3.0, 5.0)
        vehicles.append({"lane": lane, "dir": direction, "len": length, "wid": width, "speed": speed,
                         "sprite": _vehicle_sprite(rng, width, length), "y": None, "done": False, "id": k + 1})
    # arrival times: sparse = gaps of >= 3 vehicle lengths; dense = as soon as the lane entry is free
    t_arrive = np.zeros(n)
    if kind == "sparse":
        last = {}
        for k, v in enumerate(vehicles):
            key = (v["lane"], v["dir"])
            gap = 3 * 70 / v["speed"] + rng.exponential(15)
            t_arrive[k] = last.get(key, 0.0) + gap
            last[key] = t_arrive[k]
    bg = _background(rng, h, w, lanes_x, lane_w)
    stop_line = wire_y + 20
    t_red0 = 200 if kind == "dense" else -1
    frames, rows = [], []
    t = 0
    max_frames = 4000
    while t < max_frames:
        red = t_red0 <= t < t_red0 + stop_frames
        # advance the vehicles lane by lane, front first (car following with a 10 px gap)
        for lane in range(n_lanes):
            for d in (1, -1):
                queue = [v for v in vehicles if v["lane"] == lane and v["dir"] == d and v["y"] is not None
                         and not v["done"]]
                queue.sort(key=lambda v: -v["y"] * d)  # the front vehicle first
                ahead = None
                for v in queue:
                    nxt = v["y"] + d * v["speed"]
                    if ahead is not None:  # keep 10 px behind the one ahead
                        limit = ahead["y"] - d * (ahead["len"] / 2 + v["len"] / 2 + 10)
                        nxt = min(nxt, limit) if d > 0 else max(nxt, limit)
                    if red and d > 0 and v["y"] + v["len"] / 2 <= stop_line:
                        nxt = min(nxt, stop_line - v["len"] / 2)
                    v["y"] = nxt
                    ahead = v
                    if (d > 0 and v["y"] - v["len"] / 2 > h) or (d < 0 and v["y"] + v["len"] / 2 < 0):
                        v["done"] = True
        # new arrivals
        for k, v in enumerate(vehicles):
            if v["y"] is not None:
                continue
            start = -v["len"] / 2 if v["dir"] > 0 else h + v["len"] / 2
            if kind == "sparse":
                if t >= t_arrive[k]:
                    v["y"] = start
            else:
                same = [u for u in vehicles if u["lane"] == v["lane"] and u["dir"] == v["dir"] and u["y"] is not None
                        and not u["done"]]
                free = all(abs(u["y"] - start) > (u["len"] + v["len"]) / 2 + 10 for u in same)
                earlier_waiting = any(vehicles[j]["y"] is None and vehicles[j]["lane"] == v["lane"] for j in range(k))
                if free and not earlier_waiting:
                    v["y"] = start
        canvas = bg.copy()
        for v in vehicles:
            if v["y"] is None or v["done"]:
                continue
            cx = lanes_x[v["lane"]] + lane_w / 2
            x0, y0 = cx - v["wid"] / 2, v["y"] - v["len"] / 2
            sprite = v["sprite"] if v["dir"] > 0 else v["sprite"][::-1]
            paste_sprite(canvas, np.ascontiguousarray(sprite), x0, y0)
            bx0, by0 = max(0.0, x0), max(0.0, y0)
            bx1, by1 = min(float(w), x0 + v["wid"]), min(float(h), y0 + v["len"])
            if bx1 - bx0 >= 2 and by1 - by0 >= 2:
                rows.append([t + 1, v["id"], bx0, by0, bx1 - bx0, by1 - by0, 1, -1, -1, -1])
        frame = np.clip(canvas + rng.normal(0, 2.0, canvas.shape), 0, 255).astype(np.uint8)
        frames.append(frame)
        t += 1
        if all(v["done"] for v in vehicles):
            break
    meta = {"kind": kind, "seed": seed, "vehicles": n, "fps": fps, "red": [t_red0, t_red0 + stop_frames]}
    return TrafficScene(frames, np.asarray(rows, dtype=np.float64), wire, fps, meta)


def export_traffic(scene: TrafficScene, folder) -> None:
    """Write a MOTChallenge folder plus ``wire.txt``."""
    import json

    folder = Path(folder)
    (folder / "img1").mkdir(parents=True, exist_ok=True)
    (folder / "gt").mkdir(parents=True, exist_ok=True)
    for t, fr in enumerate(scene.frames):
        cv2.imwrite(str(folder / "img1" / f"{t + 1:06d}.jpg"), fr, [cv2.IMWRITE_JPEG_QUALITY, 95])
    write_mot_groundtruth(folder / "gt" / "gt.txt", scene.tracks)
    h, w = scene.frames[0].shape[:2]
    write_seqinfo(folder, name=folder.name, fps=scene.fps, length=len(scene.frames), width=w, height=h)
    (folder / "wire.txt").write_text(";".join(f"{x:g},{y:g}" for x, y in scene.wire) + "\n", encoding="utf-8")
    (folder / "meta.json").write_text(json.dumps(scene.meta) + "\n", encoding="utf-8")
