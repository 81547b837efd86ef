"""Analysis by synthesis in frame coordinates (book ch. 13 §5.5, ch13.md §1.8 "Synthesis"): which model
point every frame pixel inside the deformed mesh shows, the synthesised frame ``I_hat_n``, its RMSE
against ``I_n`` (the chapter's Fig. 5 metric), and re-texturing with another image (the "virtual mirror").
"""

from __future__ import annotations

import cv2
import numpy as np

from .mesh import Grid, displacement_at, interp_weights


def frame_to_model(V0: np.ndarray, V: np.ndarray, tris: np.ndarray, shape: tuple[int, int]):
    """Model coordinates ``(mx, my)`` (float32 maps over the deformed mesh's bounding box), the mask of
    pixels inside the mesh, and the box's top-left ``(x0, y0)``.  ``None`` when the mesh is degenerate."""
    from matplotlib.tri import Triangulation

    h, w = shape
    lo = np.maximum(np.floor(V.min(0)).astype(int), 0)
    hi = np.minimum(np.ceil(V.max(0)).astype(int), [w - 1, h - 1])
    if np.any(hi <= lo):
        return None
    ys, xs = np.mgrid[lo[1]:hi[1] + 1, lo[0]:hi[0] + 1]
    try:
        tri = Triangulation(V[:, 0], V[:, 1], tris)
        t = tri.get_trifinder()(xs.ravel().astype(float), ys.ravel().astype(float))
    except (ValueError, RuntimeError):        # a folded mesh is no valid triangulation
        return None
    inside = t >= 0
    tt = np.where(inside, t, 0)
    a, b, c = V[tris[tt, 0]], V[tris[tt, 1]], V[tris[tt, 2]]
    p = np.stack([xs.ravel(), ys.ravel()], 1).astype(np.float64)
    v0, v1, v2 = b - a, c - a, p - a
    den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
    den = np.where(np.abs(den) < 1e-12, 1e-12, den)
    l1 = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / den
    l2 = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / den
    l0 = 1 - l1 - l2
    m = (l0[:, None] * V0[tris[tt, 0]] + l1[:, None] * V0[tris[tt, 1]] + l2[:, None] * V0[tris[tt, 2]])
    mx = m[:, 0].reshape(xs.shape).astype(np.float32)
    my = m[:, 1].reshape(xs.shape).astype(np.float32)
    return mx, my, inside.reshape(xs.shape), (int(lo[0]), int(lo[1]))


def to_model(frame_gray: np.ndarray, grid: Grid, d: np.ndarray, model: str = "affine") -> np.ndarray:
    """The frame seen in model coordinates: ``R(x) = I_n(x + D(x))`` for every pixel ``x`` of the model image, with
    ``D`` the mesh's displacement field (Eq. 5) from vertex displacements ``d`` (K, 2).  Outside the mesh the border
    cells' displacement is carried on unchanged (the points are clamped to the mesh before interpolation).  This is
    the reference of frame-to-frame chaining (ch13.md T4): the previous real frame registered onto the model."""
    h, w = frame_gray.shape[:2]
    ys, xs = np.mgrid[0:h, 0:w]
    pts = np.stack([xs.ravel(), ys.ravel()], 1).astype(np.float64)
    D = displacement_at(grid, pts, d, model)
    mx = (pts[:, 0] + D[:, 0]).reshape(h, w).astype(np.float32)
    my = (pts[:, 1] + D[:, 1]).reshape(h, w).astype(np.float32)
    return cv2.remap(frame_gray.astype(np.float32), mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def synthesize(I0: np.ndarray, V0, V, tris, rho=None, pgrid: Grid | None = None, model: str = "affine"):
    """``I_hat_n`` on the deformed mesh's bounding box: ``rho * I_0`` sampled at the model points.
    Returns ``(image, mask, (x0, y0))`` or ``None``."""
    fm = frame_to_model(V0, V, tris, I0.shape[:2])
    if fm is None:
        return None
    mx, my, mask, org = fm
    img = cv2.remap(I0.astype(np.float32), mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    if rho is not None and pgrid is not None:
        idx, w = interp_weights(pgrid, np.stack([mx.ravel(), my.ravel()], 1), model)
        img = img * np.sum(w * np.asarray(rho)[idx], 1).reshape(img.shape).astype(np.float32)
    return img, mask, org


def frame_rmse(I0, In, V0, V, tris, rho=None, pgrid=None, model: str = "affine") -> float:
    """RMSE between ``I_hat_n`` and ``I_n`` over the mesh region in frame coordinates (ch13.md §3)."""
    s = synthesize(I0, V0, V, tris, rho, pgrid, model)
    if s is None:
        return float("nan")
    img, mask, (x0, y0) = s
    h, w = img.shape
    crop = In[y0:y0 + h, x0:x0 + w]
    return float(np.sqrt(np.mean((img[mask] - crop[mask]) ** 2))) if mask.any() else float("nan")


def retexture(frame: np.ndarray, texture: np.ndarray, box, V0, V, tris, rho=None, pgrid=None,
              model: str = "affine") -> np.ndarray:
    """Paint ``texture`` (stretched over the initial box) onto the deformed surface, shaded by ``rho``."""
    fm = frame_to_model(V0, V, tris, frame.shape[:2])
    out = frame.copy()
    if fm is None:
        return out
    mx, my, mask, (x0, y0) = fm
    bx, by, bw, bh = box
    th, tw = texture.shape[:2]
    tx = ((mx - bx) / max(bw, 1e-6) * (tw - 1)).astype(np.float32)
    ty = ((my - by) / max(bh, 1e-6) * (th - 1)).astype(np.float32)
    tex = cv2.remap(texture, tx, ty, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).astype(np.float32)
    if rho is not None and pgrid is not None:
        idx, w = interp_weights(pgrid, np.stack([mx.ravel(), my.ravel()], 1), model)
        shade = np.sum(w * np.asarray(rho)[idx], 1).reshape(mx.shape).astype(np.float32)
        tex = tex * (shade[..., None] if tex.ndim == 3 else shade)
    h, w = mask.shape
    region = out[y0:y0 + h, x0:x0 + w]
    region[mask] = np.clip(tex[mask], 0, 255).astype(np.uint8)
    return out


def draw_mesh(frame: np.ndarray, V: np.ndarray, grid: Grid, colour=(0, 255, 0), lost: bool = False) -> np.ndarray:
    out = frame.copy()
    P = V.reshape(grid.rows, grid.cols, 2)
    col = (0, 0, 255) if lost else colour
    for r in range(grid.rows):
        cv2.polylines(out, [np.round(P[r]).astype(np.int32).reshape(-1, 1, 2)], False, col, 1, cv2.LINE_AA)
    for c in range(grid.cols):
        cv2.polylines(out, [np.round(P[:, c]).astype(np.int32).reshape(-1, 1, 2)], False, col, 1, cv2.LINE_AA)
    return out
