"""Drawing tracker output on frames (no GUI calls: frames are written to files)."""

from __future__ import annotations

from collections import deque

import cv2
import numpy as np

from ..geometry import box_to_ellipse

_PALETTE = [(0, 0, 255), (0, 200, 0), (255, 128, 0), (0, 215, 255), (255, 0, 255), (255, 255, 0),
            (128, 0, 255), (0, 128, 255), (128, 255, 0), (255, 0, 128)]


def color_for(track_id: int) -> tuple[int, int, int]:
    """A stable BGR colour per identity."""
    return _PALETTE[int(track_id) % len(_PALETTE)]


def _pt(x: float, y: float) -> tuple[int, int]:
    return int(round(x)), int(round(y))


def draw_box(img: np.ndarray, box, color=(0, 0, 255), thickness: int = 2, label: str | None = None) -> None:
    x, y, w, h = (float(v) for v in box)
    if not all(np.isfinite([x, y, w, h])) or w <= 0 or h <= 0:
        return
    cv2.rectangle(img, _pt(x, y), _pt(x + w, y + h), color, thickness, cv2.LINE_AA)
    if label:
        cv2.putText(img, label, _pt(x, max(y - 4, 10)), cv2.FONT_HERSHEY_SIMPLEX, 0.45, color, 1, cv2.LINE_AA)


def draw_ellipse(img: np.ndarray, box, color=(0, 0, 255), thickness: int = 2) -> None:
    cx, cy, hx, hy = box_to_ellipse(box)
    if not np.all(np.isfinite([cx, cy, hx, hy])) or hx <= 0 or hy <= 0:
        return
    cv2.ellipse(img, ((float(cx), float(cy)), (2 * float(hx), 2 * float(hy)), 0.0), color, thickness, cv2.LINE_AA)


def draw_particles(img: np.ndarray, particles: np.ndarray | None, weights: np.ndarray | None = None,
                   color=(0, 255, 255), max_points: int = 400) -> None:
    if particles is None or len(particles) == 0:
        return
    pts = np.asarray(particles)[:max_points, :2]
    h, w = img.shape[:2]
    ok = np.all(np.isfinite(pts), axis=1) & (pts[:, 0] >= 0) & (pts[:, 0] < w) & (pts[:, 1] >= 0) & (pts[:, 1] < h)
    pts = pts[ok].astype(np.int32)
    img[pts[:, 1], pts[:, 0]] = color
    if len(pts) <= 200:
        for x, y in pts:
            cv2.circle(img, (int(x), int(y)), 1, color, -1)


class TrackDrawer:
    """Draws one target's ellipse, particles and a bounded trajectory (memory stays flat)."""

    def __init__(self, trail: int = 64, color=(0, 0, 255)):
        self.trail: deque = deque(maxlen=trail)
        self.color = color

    def draw(self, frame: np.ndarray, state, frame_number: int | None = None, gt_box=None) -> np.ndarray:
        img = frame.copy()
        if gt_box is not None:
            draw_box(img, gt_box, (0, 255, 0), 1)
        draw_particles(img, state.particles)
        x, y, w, h = state.box
        color = (128, 128, 128) if state.lost else self.color
        if not state.lost:
            self.trail.append(_pt(x + w / 2, y + h / 2))
        if len(self.trail) > 1:
            cv2.polylines(img, [np.array(self.trail, np.int32)], False, self.color, 1, cv2.LINE_AA)
        draw_ellipse(img, state.box, color, 2)
        text = f"{'LOST ' if state.lost else ''}score {state.score:.2f}"
        if frame_number is not None:
            text = f"#{frame_number} " + text
        cv2.putText(img, text, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(img, text, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
        return img


def map_panel(frame: np.ndarray, values: np.ndarray | None, region) -> np.ndarray:
    """A panel the size of ``frame``: the frame dimmed to grey, with a ``[0, 1]`` map (a tracker's
    confidence map over its candidate region ``(x0, y0, x1, y1)``) drawn in colour where it was computed."""
    g = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY) // 3
    panel = cv2.cvtColor(g, cv2.COLOR_GRAY2BGR)
    if values is None or region is None:
        return panel
    x0, y0, x1, y1 = (int(v) for v in region)
    if x1 <= x0 or y1 <= y0:
        return panel
    m = cv2.resize(np.clip(np.asarray(values, np.float32), 0, 1), (x1 - x0, y1 - y0),
                   interpolation=cv2.INTER_NEAREST)
    panel[y0:y1, x0:x1] = cv2.applyColorMap((m * 255).astype(np.uint8), cv2.COLORMAP_INFERNO)
    cv2.rectangle(panel, (x0, y0), (x1 - 1, y1 - 1), (255, 255, 255), 1)
    return panel

