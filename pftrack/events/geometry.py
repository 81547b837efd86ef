"""Polyline geometry of a tripwire: sides, ground patches, and crossings of point tracks (book ch. 10).

Conventions (ch10.md §1.2, image coordinates, x right, y down).  For a segment with unit
direction ``d`` the screen-right normal is ``n_R = (−d_y, d_x)``; the *inner* side is
``−n_R``, the *outer* side ``+n_R``, and a **positive** crossing moves from inner to outer.
With the issue's signed area ``s(P) = (x2 − x1)(Py − y1) − (y2 − y1)(Px − x1)`` this is a
move from ``s < 0`` to ``s > 0``.  A wire drawn left to right has its outer side below it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Crossing", "PatchLayout", "band_rects", "blocks_outside", "build_patches", "crossings_of_track",
           "parse_polyline", "polyline_project"]


def parse_polyline(text: str) -> np.ndarray:
    """``"x1,y1;x2,y2[;…]"`` → ``(K+1, 2)``; at least two distinct points (raises ``ValueError``)."""
    pts = []
    for part in str(text).split(";"):
        part = part.strip()
        if not part:
            continue
        vals = [v for v in part.replace(" ", ",").split(",") if v]
        if len(vals) != 2:
            raise ValueError(f"line points must look like x1,y1;x2,y2, got {part!r}")
        pts.append([float(v) for v in vals])
    arr = np.asarray(pts, dtype=np.float64)
    if len(arr) < 2:
        raise ValueError("a line needs at least two points x1,y1;x2,y2")
    if not np.all(np.isfinite(arr)):
        raise ValueError("line points must be finite")
    seg = np.hypot(*np.diff(arr, axis=0).T)
    if np.any(seg < 1e-9):
        raise ValueError("consecutive line points must differ")
    return arr


def _segments(pts: np.ndarray):
    a, b = pts[:-1], pts[1:]
    d = b - a
    length = np.hypot(d[:, 0], d[:, 1])
    u = d / length[:, None]
    n_r = np.stack([-u[:, 1], u[:, 0]], axis=1)
    cum = np.concatenate([[0.0], np.cumsum(length)])
    return a, b, u, n_r, length, cum


def polyline_project(p: np.ndarray, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                                                np.ndarray]:
    """For points ``p (n, 2)``: distance to the polyline, closest point, segment index, arc length of
    the closest point, and the signed offset ``(p − foot)·n_R`` measured on the closest segment
    (> 0 on the outer side).  Vectorised over points and segments."""
    p = np.atleast_2d(np.asarray(p, dtype=np.float64))
    a, _b, u, n_r, length, cum = _segments(pts)
    rel = p[:, None, :] - a[None, :, :]                       # (n, K, 2)
    t = np.clip(np.einsum("nkc,kc->nk", rel, u), 0.0, length[None, :])
    foot = a[None] + t[..., None] * u[None]
    dist = np.hypot(*(p[:, None, :] - foot).transpose(2, 0, 1))
    k = np.argmin(dist, axis=1)
    idx = np.arange(len(p))
    f = foot[idx, k]
    signed = np.einsum("nc,nc->n", p - f, n_r[k])
    return dist[idx, k], f, k, cum[k] + t[idx, k], signed


def band_rects(pts: np.ndarray, origin: tuple[int, int], shape: tuple[int, int], reach: float,
               rows: int = 8) -> list[tuple[int, int, int, int]]:
    """Rectangles ``(y0, y1, x0, x1)`` of a region of ``shape`` (h, w) whose top-left pixel is ``origin`` (x, y) in
    image coordinates, which together hold every pixel within ``reach`` of the polyline ``pts``: per band of
    ``rows`` rows, the columns from the first to the last such pixel; bands with the same columns are merged.
    The region of a horizontal or vertical wire is then one rectangle but for its ends; that of an oblique wire
    leaves out the corners of its bounding box."""
    h, w = int(shape[0]), int(shape[1])
    ys = np.arange(h, dtype=np.float64) + origin[1]
    xs = np.arange(w, dtype=np.float64) + origin[0]
    near = np.zeros((h, w), dtype=bool)
    for (ax, ay), (bx, by) in zip(pts[:-1], pts[1:]):
        dx, dy = bx - ax, by - ay
        t = np.clip(((xs[None, :] - ax) * dx + (ys[:, None] - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0)
        near |= np.hypot(xs[None, :] - ax - t * dx, ys[:, None] - ay - t * dy) <= reach
    rects: list[tuple[int, int, int, int]] = []
    for y0 in range(0, h, rows):
        cols = np.flatnonzero(near[y0:y0 + rows].any(axis=0))
        if not len(cols):
            continue
        y1, x0, x1 = min(y0 + rows, h), int(cols[0]), int(cols[-1]) + 1
        if rects and rects[-1][1] == y0 and rects[-1][2:] == (x0, x1):
            rects[-1] = (rects[-1][0], y1, x0, x1)
        else:
            rects.append((y0, y1, x0, x1))
    return rects


def blocks_outside(rects, inside: np.ndarray, k: int, rows: int = 8,
                   min_cols: int = 8) -> list[tuple[int, int, int, int]]:
    """``rects`` ``(y0, y1, x0, x1)`` of a region reduced by ``k`` (each of their pixels the block of ``k`` x ``k``
    pixels of the full region), cut into bands of ``rows`` rows, with each band's runs of at least ``min_cols``
    columns whose blocks lie wholly in ``inside`` (a boolean mask of the full region) left out: what another model
    labels at full size needs no label here (``bgs_outer_scale``). ``rects`` itself when nothing is left."""
    out: list[tuple[int, int, int, int]] = []
    for y0, y1, x0, x1 in rects:
        for ya in range(y0, y1, rows):
            yb = min(ya + rows, y1)
            blocks = inside[k * ya:k * yb, k * x0:k * x1]
            full = blocks.reshape(blocks.shape[0], x1 - x0, k).all(axis=(0, 2))
            edges = np.flatnonzero(np.diff(np.r_[0, full.astype(np.int8), 0]))
            drop = [(a, b) for a, b in zip(edges[::2], edges[1::2]) if b - a >= min_cols]
            start = 0
            for a, b in drop + [(x1 - x0, x1 - x0)]:
                if a > start:
                    out.append((ya, yb, x0 + start, x0 + int(a)))
                start = int(b)
    return out or [tuple(r) for r in rects]


@dataclass
class PatchLayout:
    """Ground patches on both sides of a wire (Eq. 1): centres, radius, unit vectors towards the wire,
    arc length of each centre's foot on the wire; ``side`` is −1 (inner) or +1 (outer)."""

    centres: np.ndarray   # (m, 2)
    w: np.ndarray         # (m, 2)
    arc: np.ndarray       # (m,)
    side: np.ndarray      # (m,) -1 inner, +1 outer
    r: float

    def of_side(self, side: int) -> np.ndarray:
        return np.flatnonzero(self.side == side)


def build_patches(pts: np.ndarray, *, r: float, spacing: float | None = None) -> PatchLayout:
    """Patches of radius ``r`` whose centres lie at distance ``r`` from the wire on both sides.

    Each side's offset curve (straight pieces plus round joins at convex vertices, no end
    caps) is sampled every ``spacing`` (default ``r``) of arc length; samples closer than
    ``r`` to the polyline (the concave side of a vertex) are dropped, so the two sides can
    have different numbers of patches (ch10.md §1.2).
    """
    pts = np.asarray(pts, dtype=np.float64)
    if r <= 0:
        raise ValueError("patch radius must be positive")
    s = float(spacing or r)
    a, b, u, n_r, length, _ = _segments(pts)
    centres, sides = [], []
    for side in (-1, 1):
        cand = []
        for j in range(len(a)):
            k = max(1, int(np.floor(length[j] / s + 1e-9)))
            ts = np.linspace(0.0, length[j], k + 1) if abs(k * s - length[j]) < 1e-6 else \
                np.concatenate([np.arange(0.0, length[j], s), [length[j]]])
            cand.append(a[j] + ts[:, None] * u[j] + side * r * n_r[j])
            if j + 1 < len(a):  # round join at the vertex between segment j and j+1 (convex side only)
                n0, n1 = side * n_r[j], side * n_r[j + 1]
                ang0, ang1 = np.arctan2(n0[1], n0[0]), np.arctan2(n1[1], n1[0])
                dang = (ang1 - ang0 + np.pi) % (2 * np.pi) - np.pi
                steps = int(np.floor(abs(dang) * r / s))
                if steps > 0:
                    angs = ang0 + dang * np.arange(1, steps + 1) / (steps + 1)
                    cand.append(b[j] + r * np.stack([np.cos(angs), np.sin(angs)], axis=1))
        c = np.concatenate(cand)
        dist, _, _, arc, _ = polyline_project(c, pts)
        c, arc = c[dist >= r - 1e-6], arc[dist >= r - 1e-6]
        order = np.argsort(arc, kind="stable")
        c, arc = c[order], arc[order]
        keep = [0]
        for i in range(1, len(c)):  # a sample shared by two pieces (a collinear vertex) counts once
            if np.hypot(*(c[i] - c[keep[-1]])) > 1e-6:
                keep.append(i)
        centres.append(c[keep])
        sides.append(np.full(len(keep), side))
    c = np.concatenate(centres)
    _, foot, _, arc, _ = polyline_project(c, pts)
    w = (foot - c) / r
    return PatchLayout(c, w, arc, np.concatenate(sides), float(r))


@dataclass(frozen=True)
class Crossing:
    """A crossing of the wire by a point track: frame (interpolated), direction (+1 positive)."""

    frame: float
    direction: int
    track: int = -1
    x: float = float("nan")
    y: float = float("nan")


def crossings_of_track(frames: np.ndarray, points: np.ndarray, pts: np.ndarray, *, hysteresis: float,
                       track: int = -1) -> list[Crossing]:
    """Crossings of one point track (ch10.md §5.3): the side state flips only when the point goes from
    ≤ −h to ≥ +h (or back) of the wire with its projection on the wire, so a point hovering on
    the line is counted once at most; the event frame is the interpolated zero crossing."""
    frames = np.asarray(frames, dtype=np.float64)
    points = np.asarray(points, dtype=np.float64)
    if len(points) == 0:
        return []
    _, _, seg, _, signed = polyline_project(points, pts)
    a, _b, u, _n, _l, _c = _segments(pts)
    # the projection must fall on the wire, not beyond its ends
    t0 = np.einsum("nc,c->n", points - a[0], u[0])
    t1 = np.einsum("nc,c->n", points - pts[-1], u[-1])
    on = ~((seg == 0) & (t0 < 0)) & ~((seg == len(a) - 1) & (t1 > 0))
    out: list[Crossing] = []
    state = 0
    last_i = -1
    for i in range(len(points)):
        if not on[i] or not np.isfinite(signed[i]):
            continue
        v = signed[i]
        new = -1 if v <= -hysteresis else (1 if v >= hysteresis else 0)
        if new == 0:
            continue
        if state != 0 and new != state:
            # interpolate the zero crossing between the last frame on the old side and this one
            j = i
            while j > last_i + 1 and np.sign(signed[j - 1]) == np.sign(v):
                j -= 1
            s0, s1 = signed[j - 1], signed[j]
            f0, f1 = frames[j - 1], frames[j]
            frac = 0.0 if s1 == s0 else float(np.clip(-s0 / (s1 - s0), 0.0, 1.0))
            fr = f0 + frac * (f1 - f0)
            xy = points[j - 1] + frac * (points[j] - points[j - 1])
            out.append(Crossing(fr, int(new), track, float(xy[0]), float(xy[1])))
        state = new
        last_i = i
    return out
