"""The trackerless tripwire's overlay video frame (``pftrack tripwire --video-out``)."""

from __future__ import annotations

import cv2
import numpy as np


def tripwire_overlay(img: np.ndarray, tws: list, flash: list, count: dict, counts: list[dict]) -> np.ndarray:
    """The frame with each line, its patches by state (red: foreground; orange / green: the inner / outer side) and
    the recent events (yellow), and the counts so far (with several lines, each line's beside its first point)."""
    canvas = img.copy()
    for k, tw in enumerate(tws):
        pts = np.round(tw.polyline).astype(np.int32).reshape(-1, 1, 2)
        cv2.polylines(canvas, [pts], False, (255, 255, 255), 2, cv2.LINE_AA)
        if len(tws) > 1:
            x, y = int(pts[0, 0, 0]), int(pts[0, 0, 1])
            for colour, width in (((0, 0, 0), 4), ((0, 255, 255), 2)):  # yellow on a dark outline
                cv2.putText(canvas, f"{k + 1}: +{counts[k][1]} -{counts[k][-1]}", (x + 4, max(y - 8, 20)),
                            cv2.FONT_HERSHEY_SIMPLEX, 0.7, colour, width, cv2.LINE_AA)
        for j, c in enumerate(tw.layout.centres):
            col = (0, 0, 255) if tw.patches[j].fg else ((255, 160, 0) if tw.layout.side[j] < 0 else (0, 200, 0))
            cv2.circle(canvas, (round(float(c[0])), round(float(c[1]))), round(tw.params.radius), col, 1)
    for item in flash:
        e, r = item[0], item[2]
        cv2.circle(canvas, (int(e.x), int(e.y)), int(2 * r), (0, 255, 255), 3)
        item[1] -= 1
    flash[:] = [f for f in flash if f[1] > 0]
    cv2.putText(canvas, f"+{count[1]}  -{count[-1]}", (10, 30), cv2.FONT_HERSHEY_SIMPLEX, 1.0,
                (0, 255, 255), 2, cv2.LINE_AA)
    return canvas
