"""Stabilised kymograms (book ch. 13, "Medical imaging", L11880-11915; ch13.md §4 and T6).

A kymogram stacks one scan line of every frame into an x-t image, so that a vibration along the line (the vocal
folds in the chapter's endoscopic video) shows as a wave. Camera motion moves the line over the tissue and smears
the wave. The chapter tracks the video with a stiff affine mesh, which follows the camera and parallax but not the
vibration, and maps a region of interest annotated in the first frame back onto itself by a rigid transform fitted
to the mesh's motion of that region. The scan line is then read from the stabilised frame.

Pure functions: :func:`roi_points`, :func:`rigid_fit`, :func:`stabilising_transform`, :func:`scan_line`; the
:class:`Kymograph` accumulates the rows.
"""

from __future__ import annotations

import cv2
import numpy as np

from .mesh import Grid, displacement_at


def roi_points(roi, step: float = 4.0) -> np.ndarray:
    """A regular lattice of points (P, 2) over the region ``roi = (x, y, w, h)``, ``step`` pixels apart."""
    x, y, w, h = map(float, roi)
    xs = np.arange(x + step / 2, x + w, step)
    ys = np.arange(y + step / 2, y + h, step)
    if len(xs) == 0 or len(ys) == 0:
        xs, ys = np.array([x + w / 2]), np.array([y + h / 2])
    X, Y = np.meshgrid(xs, ys)
    return np.stack([X.ravel(), Y.ravel()], 1)


def rigid_fit(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """The rotation and translation (2 x 3, no scale) that best maps ``src`` onto ``dst`` in least squares (Kabsch /
    Umeyama without scale). Exact for points related by a rigid motion."""
    src = np.asarray(src, np.float64)
    dst = np.asarray(dst, np.float64)
    cs, cd = src.mean(0), dst.mean(0)
    H = (src - cs).T @ (dst - cd)
    U, _, Vt = np.linalg.svd(H)
    D = np.diag([1.0, np.sign(np.linalg.det(Vt.T @ U.T))])   # a rotation, never a reflection
    R = Vt.T @ D @ U.T
    return np.c_[R, cd - R @ cs]


def stabilising_transform(grid: Grid, d: np.ndarray, roi, model: str = "affine", step: float = 4.0) -> np.ndarray:
    """The rigid transform (2 x 3) that maps the region ``roi`` of the current frame back onto where it was in the
    first frame: the region's lattice points ``x`` (first-frame coordinates) moved by the mesh's displacement field
    ``D(x)`` (Eq. 5, vertex displacements ``d`` (K, 2)) are fitted back onto ``x``. Points outside the mesh take
    the border cells' displacement."""
    pts = roi_points(roi, step)
    return rigid_fit(pts + displacement_at(grid, pts, d, model), pts)


def scan_line(image: np.ndarray, p0, p1, n: int | None = None) -> np.ndarray:
    """``n`` samples (default: one a pixel) of ``image`` along the segment ``p0 -> p1``, bilinear; (n,) for a grey
    image, (n, C) for a colour one."""
    p0, p1 = np.asarray(p0, np.float64), np.asarray(p1, np.float64)
    if n is None:
        n = max(int(np.ceil(np.hypot(*(p1 - p0)))) + 1, 2)
    t = np.linspace(0.0, 1.0, n)
    xs = (p0[0] + t * (p1[0] - p0[0])).astype(np.float32).reshape(1, -1)
    ys = (p0[1] + t * (p1[1] - p0[1])).astype(np.float32).reshape(1, -1)
    out = cv2.remap(image, xs, ys, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return out[0]


class Kymograph:
    """Rows of a kymogram: each frame's scan line, read from the frame warped by its stabilising transform (or
    from the frame itself when none is given)."""

    def __init__(self, p0, p1, n: int | None = None):
        self.p0, self.p1, self.n = p0, p1, n
        self.rows: list[np.ndarray] = []

    def add(self, frame: np.ndarray, transform: np.ndarray | None = None) -> np.ndarray:
        if transform is not None:
            h, w = frame.shape[:2]
            frame = cv2.warpAffine(frame, transform, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        row = scan_line(frame, self.p0, self.p1, self.n)
        self.rows.append(row)
        return row

    def image(self) -> np.ndarray:
        """The kymogram: one row per frame, time downwards."""
        return np.stack(self.rows) if self.rows else np.zeros((0, self.n or 0), np.uint8)
