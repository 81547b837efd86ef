"""Online discriminative feature selection and back-projection mean shift (book ch. 6, §3).

Book *Object Tracking*, ch. 6 (``shared/seeds/002_*`` lines 5370-6238; specification
``shared/book/ch06.md`` §1.1-1.5), after Collins, Liu & Leordeanu (PAMI 2005) and Wang & Yagi
(TIP 2008):

* **candidate features** (§1.1): R, G, B, H, S, normalised r, g, each in ``m = 12`` bins, and the
  Scharr gradient orientation (Eqs. 6-7, unsigned, 12 bins plus a 13th "flat" bin for pixels
  whose magnitude is below ``T_D``) — :func:`bin_images`;
* **(8)/(11)** the clamped log-likelihood ratio ``L = clip(log(max(zeta_f, delta)/max(zeta_b, delta)), -1, 1)``
  and **(12)** Collins' variance ratio ``var(L; (zeta_f+zeta_b)/2) / (var(L; zeta_f) + var(L; zeta_b))``
  that ranks them — :func:`log_likelihood_ratio`, :func:`variance_ratio`, :func:`rank_features`;
* the **replacement rule** (§3.3.2): only the second of the two selected features is ever
  replaced, by the best current feature other than the first — :func:`select_pair`;
* **(16)-(18)** the joint 12x12 target histogram, the search-region histogram and their
  normalised division, back-projected onto the pixels — :func:`joint_histogram`,
  :func:`division_histogram`, :func:`backproject`;
* **(19)-(20)** mean shift on the back-projection weights with the Epanechnikov kernel (``g``
  constant: the weighted centroid of the ellipse) and a damped step ``y1 <- (y0 + y1)/2`` —
  :func:`weighted_meanshift`.

Grey input needs no special case: H, S, r and g are constant and their variance ratios are 0.  R, G, B
and the equalised grey level are then one intensity, so Eq. 12 alone would pair two copies of it;
:func:`rank_partners` ranks the second feature by the pair's joint histogram instead, which prefers
one that adds information (orientation, on grey frames).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .._numba import njit, numba_enabled

FEATURES = ("R", "G", "B", "H", "S", "r", "g", "orient")
#: Candidates beyond the chapter's: "Ieq", the grey level after the frame's histogram equalisation (its
#: rank in the frame), which a global monotonic lighting change leaves almost unchanged.
EXTRA_FEATURES = ("Ieq",)


def n_bins(name: str, bins: int = 12) -> int:
    """Bins of a feature: ``bins``, plus the "flat" bin for the orientation."""
    return bins + 1 if name == "orient" else bins


def bin_images(region: np.ndarray, names: tuple[str, ...] = FEATURES, *, bins: int = 12,
               grad_threshold: float = 64.0, eq_lut: np.ndarray | None = None) -> np.ndarray:
    """``(H, W, len(names))`` uint8 bin indices of a BGR region, one channel per feature (§1.1).

    Hue uses OpenCV's 8-bit range 0-179; r and g are ``R/(R+G+B)``, ``G/(R+G+B)`` (1/3 on black
    pixels); the orientation is ``atan2(Dy, Dx) mod pi`` of Scharr derivatives (a unit ramp has
    magnitude 32), with pixels below ``grad_threshold`` in bin ``bins``.  ``Ieq`` maps the grey level
    through ``eq_lut`` (the frame's equalisation table, :func:`pftrack.cues.intensity.equalization_lut`).
    """
    h, w = region.shape[:2]
    out = np.empty((h, w, len(names)), dtype=np.uint8)
    need_hsv = any(n in ("H", "S") for n in names)
    hsv = cv2.cvtColor(region, cv2.COLOR_BGR2HSV) if need_hsv else None
    total = None
    for k, name in enumerate(names):
        if name in ("R", "G", "B"):
            ch = region[..., {"R": 2, "G": 1, "B": 0}[name]]
            out[..., k] = (ch.astype(np.uint16) * bins) >> 8
        elif name == "H":
            out[..., k] = (hsv[..., 0].astype(np.uint16) * bins) // 180
        elif name == "S":
            out[..., k] = (hsv[..., 1].astype(np.uint16) * bins) >> 8
        elif name in ("r", "g"):
            if total is None:
                # B + G + R (exact in float32); NumPy's reduction over a 3-long last axis is ~6x slower
                total = region[..., 0].astype(np.float32)
                total += region[..., 1]
                total += region[..., 2]
            ch = region[..., 2 if name == "r" else 1].astype(np.float32)
            frac = np.where(total > 0, ch / np.maximum(total, 1.0), 1.0 / 3.0)
            out[..., k] = np.minimum((frac * bins).astype(np.int32), bins - 1)
        elif name == "Ieq":
            g = cv2.cvtColor(region, cv2.COLOR_BGR2GRAY) if region.ndim == 3 else region
            lut = np.arange(256, dtype=np.uint8) if eq_lut is None else eq_lut
            out[..., k] = (lut[g].astype(np.uint16) * bins) >> 8
        elif name == "orient":
            g = cv2.cvtColor(region, cv2.COLOR_BGR2GRAY) if region.ndim == 3 else region
            dx = cv2.Scharr(g, cv2.CV_32F, 1, 0)
            dy = cv2.Scharr(g, cv2.CV_32F, 0, 1)
            mag = cv2.magnitude(dx, dy)
            theta = np.mod(np.arctan2(dy, dx), np.pi)
            ob = np.minimum((theta * (bins / np.pi)).astype(np.int32), bins - 1)
            out[..., k] = np.where(mag >= grad_threshold, ob, bins)
        else:
            raise ValueError(f"unknown feature {name!r}; expected one of {FEATURES + EXTRA_FEATURES}")
    return out


def log_likelihood_ratio(count_f: np.ndarray, count_b: np.ndarray, *, delta: float = 1e-3,
                         clip: float | None = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eqs. 9-11: ``(L, zeta_f, zeta_b)`` from raw (or weighted) bin counts of object and background."""
    cf = np.asarray(count_f, dtype=np.float64)
    cb = np.asarray(count_b, dtype=np.float64)
    zf = cf / max(cf.sum(), 1e-300)
    zb = cb / max(cb.sum(), 1e-300)
    L = np.log(np.maximum(zf, delta) / np.maximum(zb, delta))
    if clip is not None:
        L = np.clip(L, -clip, clip)
    return L, zf, zb


def _var(L: np.ndarray, a: np.ndarray) -> float:
    m = float(np.dot(a, L))
    return max(float(np.dot(a, L * L)) - m * m, 0.0)


def variance_ratio(L: np.ndarray, zeta_f: np.ndarray, zeta_b: np.ndarray) -> float:
    """Eq. 12: ``var(L; (zf+zb)/2) / (var(L; zf) + var(L; zb) + 1e-12)``; 0 when ``L`` is constant."""
    num = _var(L, 0.5 * (zeta_f + zeta_b))
    if num == 0.0:
        return 0.0
    return num / (_var(L, zeta_f) + _var(L, zeta_b) + 1e-12)


def feature_counts(bins: np.ndarray, mask: np.ndarray, names: tuple[str, ...], *, n: int = 12,
                   weights: np.ndarray | None = None) -> list[np.ndarray]:
    """Per-feature bin counts of the pixels under ``mask`` (optionally weighted)."""
    sel = bins[mask]
    wv = None if weights is None else weights[mask]
    return [np.bincount(sel[:, k], weights=wv, minlength=n_bins(name, n)).astype(np.float64)
            for k, name in enumerate(names)]


def rank_features(bins: np.ndarray, obj_mask: np.ndarray, bg_mask: np.ndarray,
                  names: tuple[str, ...] = FEATURES, *, n: int = 12, delta: float = 1e-3,
                  clip: float | None = 1.0, obj_weights: np.ndarray | None = None
                  ) -> tuple[tuple[str, ...], np.ndarray]:
    """Names sorted by decreasing variance ratio (Eq. 12), and the ratios in ``names`` order."""
    cf = feature_counts(bins, obj_mask, names, n=n, weights=obj_weights)
    cb = feature_counts(bins, bg_mask, names, n=n)
    vr = np.array([variance_ratio(*log_likelihood_ratio(f, b, delta=delta, clip=clip)) for f, b in zip(cf, cb)])
    order = np.argsort(-vr, kind="stable")
    return tuple(names[i] for i in order), vr


def rank_partners(bins: np.ndarray, obj_mask: np.ndarray, bg_mask: np.ndarray, names: tuple[str, ...], first: str,
                  *, n: int = 12, delta: float = 1e-3, clip: float | None = 1.0) -> tuple[tuple[str, ...], np.ndarray]:
    """The candidates other than ``first``, sorted by the variance ratio (Eq. 12) of the *joint* histogram of
    ``(first, candidate)`` (Eq. 16's pair), and those ratios in the returned order.

    Eq. 12 ranks each feature alone, so the second pick can repeat the first: on grey frames R, G, B and the
    equalised grey level are all functions of one intensity, and the pair adds nothing.  Ranking the partner by
    the pair's own separability keeps the chapter's rule (the first feature stays, the second is replaced) and
    prefers a partner that adds information (pftrack's choice, ``partner="joint"``)."""
    k0 = names.index(first)
    n0 = n_bins(first, n)
    base = bins[..., k0].astype(np.int32)
    sel_f, sel_b = base[obj_mask], base[bg_mask]
    others, vr = [], []
    for k, name in enumerate(names):
        if name == first:
            continue
        nk = n_bins(name, n)
        cf = np.bincount(sel_f * nk + bins[..., k][obj_mask], minlength=n0 * nk)
        cb = np.bincount(sel_b * nk + bins[..., k][bg_mask], minlength=n0 * nk)
        others.append(name)
        vr.append(variance_ratio(*log_likelihood_ratio(cf, cb, delta=delta, clip=clip)))
    order = np.argsort(-np.asarray(vr), kind="stable")
    return tuple(others[i] for i in order), np.asarray(vr)[order]


def select_pair(previous: tuple[str, ...] | None, ranking: tuple[str, ...], *, k: int = 2,
                replace: str = "second") -> tuple[str, ...]:
    """The features to use (§3.3.2).

    At start (``previous`` None) the top ``k``.  After that, with ``replace="second"`` (the
    chapter's rule) the first feature is kept and the rest are the best current features other
    than it; ``replace="all"`` takes the new top ``k`` (the ablation of claim C6.5).
    """
    if previous is None or replace == "all" or k == 1 and replace == "all":
        return tuple(ranking[:k])
    first = previous[0]
    if k == 1:
        return (first,)
    rest = [f for f in ranking if f != first][:k - 1]
    return (first, *rest)


def joint_index(bins: np.ndarray, idx: tuple[int, ...], sizes: tuple[int, ...]) -> np.ndarray:
    """Flat joint bin of the selected channels (row-major over ``sizes``), int32."""
    out = bins[..., idx[0]].astype(np.int32)
    for k, s in zip(idx[1:], sizes[1:]):
        out = out * s + bins[..., k]
    return out


def joint_histogram(joint: np.ndarray, n_joint: int, weights: np.ndarray | None = None) -> np.ndarray:
    """Eqs. 16-17: normalised histogram of flat joint bins (``weights`` e.g. the Epanechnikov kernel)."""
    h = np.bincount(joint.ravel(), weights=None if weights is None else weights.ravel(),
                    minlength=n_joint).astype(np.float64)
    s = h.sum()
    return h / s if s > 0 else h


def division_histogram(zeta_f: np.ndarray, zeta_b: np.ndarray, *, delta: float = 1e-3) -> np.ndarray:
    """Eq. 18 with a guard: ``zeta_f / max(zeta_b, delta)`` scaled so its maximum is 1."""
    pd = zeta_f / np.maximum(zeta_b, delta)
    m = pd.max()
    return pd / m if m > 0 else pd


def backproject(pd: np.ndarray, joint: np.ndarray) -> np.ndarray:
    """``p_w(x) = p_d(bin(x))``: a float32 weight image."""
    return pd.astype(np.float32)[joint]


def kernel_histogram(joint: np.ndarray, n_joint: int, window: tuple[int, int, int, int], cx: float, cy: float,
                     hx: float, hy: float) -> np.ndarray:
    """Eqs. 16-17 with the Epanechnikov kernel: the normalised kernel-weighted histogram of the flat joint bins
    in ``joint[j0:j1, i0:i1]`` (``window = (i0, j0, i1, j1)``), the ellipse centred at ``(cx, cy)`` in window
    coordinates with half-axes ``hx, hy``.  The same as ``joint_histogram(joint[j0:j1, i0:i1], n_joint,
    epanechnikov(j1 - j0, i1 - i0, cx, cy, hx, hy))``, without the kernel image."""
    i0, j0, i1, j1 = (int(v) for v in window)
    if not numba_enabled():
        k = epanechnikov(j1 - j0, i1 - i0, cx, cy, hx, hy)
        return joint_histogram(joint[j0:j1, i0:i1], n_joint, k)
    h = np.zeros(n_joint)
    _kernel_hist(joint, i0, j0, i1, j1, float(cx), float(cy), float(hx), float(hy), h)
    s = h.sum()
    return h / s if s > 0 else h


@njit
def _kernel_hist(joint, i0, j0, i1, j1, cx, cy, hx, hy, h):
    dx2 = np.empty(i1 - i0)
    for c in range(i1 - i0):
        dx2[c] = ((c + 0.5 - cx) / hx) ** 2
    for r in range(j1 - j0):
        dy2 = ((r + 0.5 - cy) / hy) ** 2
        row = joint[j0 + r]
        for c in range(i1 - i0):
            r2 = dx2[c] + dy2
            if r2 <= 1.0:
                h[row[i0 + c]] += 1.0 - r2


def kernel_window(shape: tuple[int, int], cx: float, cy: float, sx: float, sy: float):
    """The pixels of a region of ``shape`` ``(h, w)`` under the ellipse of size ``(sx, sy)`` centred at ``(cx, cy)``
    (region coordinates): ``(i0, j0, i1, j1, wcx, wcy)``, the window and the centre in window coordinates.  A window
    partly outside the region keeps its inside part; an empty one has ``i1 <= i0`` or ``j1 <= j0``."""
    h, w = shape
    i0, i1 = max(int(cx - sx / 2), 0), min(int(math.ceil(cx + sx / 2)) + 1, w)
    j0, j1 = max(int(cy - sy / 2), 0), min(int(math.ceil(cy + sy / 2)) + 1, h)
    return i0, j0, i1, j1, cx - i0, cy - j0


def kernel_rhos_at(joint: np.ndarray, model: np.ndarray, centres: np.ndarray, sx: float, sy: float) -> np.ndarray:
    """:func:`kernel_rhos` of the ellipses of size ``(sx, sy)`` at ``centres`` ``(M, 2)`` (region coordinates); NaN
    where the window is empty or holds no kernel weight."""
    if numba_enabled():
        out = np.empty(len(centres))
        _kernel_rhos_at(joint, np.ascontiguousarray(model, dtype=np.float64),
                        np.ascontiguousarray(centres, dtype=np.float64).reshape(-1, 2), float(sx), float(sy), out)
        return out
    out = np.full(len(centres), np.nan)
    wins = [kernel_window(joint.shape, float(cx), float(cy), sx, sy) for cx, cy in centres]
    ok = np.array([i1 > i0 and j1 > j0 for i0, j0, i1, j1, _, _ in wins], dtype=bool)
    if ok.any():
        sel = [wn for wn, good in zip(wins, ok) if good]
        out[ok] = kernel_rhos(joint, model, np.array([wn[:4] for wn in sel]), np.array([wn[4:] for wn in sel]),
                              sx / 2, sy / 2)
    return out


@njit
def _kernel_rhos_at(joint, model, centres, sx, sy, out):
    """:func:`kernel_rhos_at` compiled: :func:`kernel_window` and :func:`_kernel_rhos` per centre."""
    h, w = joint.shape
    hist = np.empty(model.shape[0])
    for m in range(centres.shape[0]):
        cx, cy = centres[m, 0], centres[m, 1]
        i0, i1 = max(int(cx - sx / 2), 0), min(int(math.ceil(cx + sx / 2)) + 1, w)
        j0, j1 = max(int(cy - sy / 2), 0), min(int(math.ceil(cy + sy / 2)) + 1, h)
        if i1 <= i0 or j1 <= j0:
            out[m] = np.nan
            continue
        hist[:] = 0.0
        _kernel_hist(joint, i0, j0, i1, j1, cx - i0, cy - j0, sx / 2, sy / 2, hist)
        out[m] = _rho_of(hist, model)


@njit
def _rho_of(hist, model):
    """Bhattacharyya coefficient of the normalised ``hist`` with ``model``; NaN for an empty ``hist``."""
    s = 0.0
    for b in range(hist.shape[0]):
        s += hist[b]
    if s <= 0:
        return np.nan
    r = 0.0
    for b in range(hist.shape[0]):
        r += math.sqrt(hist[b] / s * model[b])
    return r


def refine_centre(joint: np.ndarray, model: np.ndarray, origin: tuple[int, int], c, size, *, radius: int = 2,
                  step: float = 0.05) -> np.ndarray:
    """The centre of highest Bhattacharyya coefficient (Eqs. 13-14) on a ``(2 radius + 1)^2`` grid around ``c``,
    spaced ``step`` times the box (at least 1 px); ``c`` itself unless a grid point beats it.

    Mean shift on the back-projection (Eqs. 19-20) climbs to a mode of the weight image, which leans towards
    the target's most discriminative part, not to the window whose histogram matches the model best; this
    local search on rho itself corrects that (pftrack's addition)."""
    c = np.asarray(c, dtype=np.float64)
    size = np.asarray(size, dtype=np.float64)
    d = np.maximum(size * step, 1.0)
    offs = np.arange(-radius, radius + 1, dtype=np.float64)
    gx, gy = np.meshgrid(c[0] + offs * d[0], c[1] + offs * d[1])
    cands = np.column_stack([gx.ravel(), gy.ravel()])
    rho = kernel_rhos_at(joint, model, cands - np.asarray(origin, dtype=np.float64), float(size[0]), float(size[1]))
    rho = np.where(np.isfinite(rho), rho, -1.0)
    k = int(np.argmax(rho))
    centre = len(cands) // 2
    return cands[k].copy() if rho[k] > rho[centre] else c


def kernel_rhos(joint: np.ndarray, model: np.ndarray, windows: np.ndarray, centres: np.ndarray, hx: float,
                hy: float) -> np.ndarray:
    """Bhattacharyya coefficient of ``model`` with :func:`kernel_histogram` at each of ``M`` windows:
    ``windows`` ``(M, 4)`` rows ``(i0, j0, i1, j1)``, ``centres`` ``(M, 2)`` in window coordinates; NaN where
    a window holds no kernel weight."""
    windows = np.asarray(windows, dtype=np.int64).reshape(-1, 4)
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 2)
    out = np.empty(len(windows))
    if not numba_enabled():
        for m, (w, c) in enumerate(zip(windows, centres)):
            h = kernel_histogram(joint, len(model), tuple(w), c[0], c[1], hx, hy)
            out[m] = float(np.sum(np.sqrt(h * model))) if h.sum() > 0 else np.nan
        return out
    _kernel_rhos(joint, np.ascontiguousarray(model, dtype=np.float64), windows, centres, float(hx), float(hy), out)
    return out


@njit
def _kernel_rhos(joint, model, windows, centres, hx, hy, out):
    h = np.empty(model.shape[0])
    for m in range(windows.shape[0]):
        h[:] = 0.0
        _kernel_hist(joint, windows[m, 0], windows[m, 1], windows[m, 2], windows[m, 3], centres[m, 0], centres[m, 1],
                     hx, hy, h)
        out[m] = _rho_of(h, model)


def epanechnikov(h: int, w: int, cx: float, cy: float, hx: float, hy: float) -> np.ndarray:
    """Eq. 1 up to its constant: ``1 - r^2`` inside the ellipse (pixel centres), 0 outside."""
    dx = (np.arange(w) + 0.5 - cx) / hx
    dy = (np.arange(h) + 0.5 - cy) / hy
    r2 = dx[None, :] ** 2 + dy[:, None] ** 2
    return np.where(r2 <= 1.0, 1.0 - r2, 0.0)


def weighted_meanshift(weights: np.ndarray, center: tuple[float, float], half_axes: tuple[float, float], *,
                       origin: tuple[int, int] = (0, 0), max_iter: int = 15, eps: float = 0.5,
                       damping: float = 0.5) -> tuple[np.ndarray, int, float]:
    """Eqs. 19-20: mean shift of an ellipse on a weight image.

    ``weights`` covers the frame region whose pixel ``(0, 0)`` is at ``origin``.  Each step moves
    to ``(1 - damping) y0 + damping * centroid`` (the chapter's ``1/2``), the centroid being the
    weight-weighted mean of the pixel centres inside the ellipse (Epanechnikov: ``g`` constant).
    Returns ``(centre, iterations, mass)`` with ``mass`` the mean weight inside the final ellipse.
    """
    hgt, wid = weights.shape
    hx, hy = max(float(half_axes[0]), 0.5), max(float(half_axes[1]), 0.5)
    if numba_enabled():
        cx, cy, it, mass = _meanshift(np.ascontiguousarray(weights), float(center[0]), float(center[1]), hx, hy,
                                      float(origin[0]), float(origin[1]), int(max_iter), float(eps), float(damping))
        return np.array([cx, cy]), it, mass
    y = np.array(center, dtype=np.float64)
    it = 0
    mass = 0.0
    for it in range(1, max_iter + 1):
        lcx, lcy = y[0] - origin[0], y[1] - origin[1]
        i0, i1 = max(int(math.floor(lcx - hx)), 0), min(int(math.ceil(lcx + hx)) + 1, wid)
        j0, j1 = max(int(math.floor(lcy - hy)), 0), min(int(math.ceil(lcy + hy)) + 1, hgt)
        if i1 <= i0 or j1 <= j0:
            return y, it, 0.0
        xs = np.arange(i0, i1) + 0.5
        ys = np.arange(j0, j1) + 0.5
        inside = ((xs[None, :] - lcx) / hx) ** 2 + ((ys[:, None] - lcy) / hy) ** 2 <= 1.0
        wv = weights[j0:j1, i0:i1] * inside
        s = float(wv.sum())
        n_in = int(inside.sum())
        mass = s / max(n_in, 1)
        if s <= 0:
            return y, it, 0.0
        cx = float((wv.sum(axis=0) * xs).sum() / s) + origin[0]
        cy = float((wv.sum(axis=1) * ys).sum() / s) + origin[1]
        new = (1.0 - damping) * y + damping * np.array([cx, cy])
        moved = float(np.hypot(*(new - y)))
        y = new
        if moved < eps:
            break
    return y, it, mass


@njit
def _meanshift(weights, x, y, hx, hy, ox, oy, max_iter, eps, damping):
    """:func:`weighted_meanshift`'s loop, compiled (sums in row order instead of NumPy's pairwise order)."""
    hgt, wid = weights.shape
    it = 0
    mass = 0.0
    for it in range(1, max_iter + 1):
        lcx, lcy = x - ox, y - oy
        i0, i1 = max(int(math.floor(lcx - hx)), 0), min(int(math.ceil(lcx + hx)) + 1, wid)
        j0, j1 = max(int(math.floor(lcy - hy)), 0), min(int(math.ceil(lcy + hy)) + 1, hgt)
        if i1 <= i0 or j1 <= j0:
            return x, y, it, 0.0
        s = 0.0
        sx = 0.0
        sy = 0.0
        n_in = 0
        for j in range(j0, j1):
            yy = j + 0.5
            dy = ((yy - lcy) / hy) ** 2
            for i in range(i0, i1):
                xx = i + 0.5
                if ((xx - lcx) / hx) ** 2 + dy <= 1.0:
                    v = weights[j, i]
                    s += v
                    sx += v * xx
                    sy += v * yy
                    n_in += 1
        mass = s / max(n_in, 1)
        if s <= 0:
            return x, y, it, 0.0
        cx = sx / s + ox
        cy = sy / s + oy
        nx = (1.0 - damping) * x + damping * cx
        ny = (1.0 - damping) * y + damping * cy
        moved = math.hypot(nx - x, ny - y)
        x, y = nx, ny
        if moved < eps:
            break
    return x, y, it, mass


def ring_masks(shape: tuple[int, int], box: tuple[float, float, float, float], *, inner: float = 1.1,
               outer: float = 2.0, origin: tuple[int, int] = (0, 0)) -> tuple[np.ndarray, np.ndarray]:
    """Object mask (the box) and background ring (box x ``outer`` minus box x ``inner``) over a
    region of ``shape`` whose pixel ``(0, 0)`` is at frame position ``origin`` (ch06.md §1.3)."""
    h, w = shape
    x, y, bw, bh = box
    cx, cy = x + bw / 2 - origin[0], y + bh / 2 - origin[1]
    xs = np.arange(w) + 0.5 - cx
    ys = np.arange(h) + 0.5 - cy
    ax, ay = np.abs(xs)[None, :], np.abs(ys)[:, None]
    obj = (ax <= bw / 2) & (ay <= bh / 2)
    ring = ((ax <= outer * bw / 2) & (ay <= outer * bh / 2)) & ~((ax <= inner * bw / 2) & (ay <= inner * bh / 2))
    return obj, ring
