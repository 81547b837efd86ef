"""Local-motion cue from sparse optical flow (Kristan et al., ``shared/seeds/000_*.txt``).

Per frame, once, inside the region the particles can reach (:meth:`LocalMotionCue.prepare`):

1. **Shi-Tomasi features**: the smallest eigenvalue of the covariation matrix of the
   intensity gradients (intensities in [0, 1], central differences) averaged over
   3x3 neighbourhoods; pixels whose eigenvalue exceeds ``lambda_th = 1e-3`` are
   features.  To bound the cost the eigenvalue is evaluated on a regular lattice
   (every pixel in small regions) with about twice ``max_features`` points, and the
   strongest ``max_features`` qualifying points are kept.
2. **Pyramidal Lucas-Kanade flow** at those features with a 9x9 window and one
   pyramid level (two for fast motion), computed *from the current image back to the
   previous one* and reversed (§3), so that each vector lives at its feature in the
   current frame.

Per particle, for all particles at once (:func:`local_motion`): the **local-motion
feature** of the region ``E`` (a rectangle over the particle's ellipse, as the paper
does) is the Epanechnikov-weighted mean of the flow vectors at the features inside it,
summed in Cartesian coordinates (Eq. 4).

Against a reference motion ``v_ref``: the angular and amplitude similarities (Eqs. 5–6)

    G_theta = angle(v_E, v_ref) / pi   if r_E > eps and r_ref > eps, else 1
    G_r     = |r_ref - r_E| / (r_ref + r_E)   if r_E > eps or r_ref > eps, else 0

with ``eps = 1e-2`` px; a region without features gives ``G_theta = G_r = 1``; and the
likelihood (Eq. 7)

    p(G_theta, G_r) = (1 - w_noise) exp(-(G_theta / sigma_theta + G_r / sigma_r)) + w_noise

with ``sigma_theta = 0.1``, ``sigma_r = 0.3``, ``w_noise = 0.01``.  Its maximum is 1,
so it doubles as the adaptation intensity of Eq. 9.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .._numba import njit, numba_enabled
from .grey_patch import GreyPatch, as_patch, grey_patch


@dataclass
class FlowField:
    """Sparse flow: features at ``(x, y)`` (pixel centres, pftrack convention) with vectors ``(vx, vy)``."""

    x: np.ndarray
    y: np.ndarray
    vx: np.ndarray
    vy: np.ndarray

    @property
    def n(self) -> int:
        return int(self.x.size)

    @classmethod
    def empty(cls) -> "FlowField":
        e = np.empty(0)
        return cls(e, e, e, e)


def to_gray(frame: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)


def min_eigenvalue_reference(gray: np.ndarray) -> np.ndarray:
    """Shi-Tomasi map written out: smallest eigenvalue of the 3x3-averaged covariance of the
    central-difference gradients of intensities in [0, 1]."""
    g = gray.astype(np.float32) * np.float32(1.0 / 255.0)
    ix = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=1, scale=0.5, borderType=cv2.BORDER_REFLECT_101)
    iy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=1, scale=0.5, borderType=cv2.BORDER_REFLECT_101)
    a = cv2.boxFilter(ix * ix, -1, (3, 3), borderType=cv2.BORDER_REFLECT_101)
    b = cv2.boxFilter(ix * iy, -1, (3, 3), borderType=cv2.BORDER_REFLECT_101)
    c = cv2.boxFilter(iy * iy, -1, (3, 3), borderType=cv2.BORDER_REFLECT_101)
    half = (a - c) * 0.5
    return (a + c) * 0.5 - np.sqrt(half * half + b * b)


def min_eigenvalue(gray: np.ndarray) -> np.ndarray:
    """Shi-Tomasi map (same values as :func:`min_eigenvalue_reference`, one optimised OpenCV call).

    ``cv2.cornerMinEigenVal`` with a 3x3 block and the ``[-1, 0, 1]`` derivative sums
    the products of twice the central difference over the block, scaled by
    ``1 / (3 * 255)``: exactly 4 times the average covariance on [0, 1] intensities.
    """
    return cv2.cornerMinEigenVal(gray, 3, ksize=1) * np.float32(0.25)


@njit
def _lattice_min_eig_numba(gray, ox, oy, w, h, x0, y0, x1, y1, pitch, out_x, out_y, out_l):
    """Smallest eigenvalue of the 3x3-averaged gradient covariance at lattice points (intensities in [0, 1]).

    Frame coordinates; ``gray[0, 0]`` is the frame's pixel ``(ox, oy)`` of a ``w`` × ``h`` frame."""
    n = 0
    sy = max(y0, 2)
    sy += (-sy) % pitch
    sx = max(x0, 2)
    sx += (-sx) % pitch
    inv = 1.0 / 255.0
    for y in range(sy, min(y1, h - 2), pitch):
        for x in range(sx, min(x1, w - 2), pitch):
            a = 0.0
            b = 0.0
            c = 0.0
            for dy in range(-1, 2):
                for dx in range(-1, 2):
                    yy = y + dy - oy
                    xx = x + dx - ox
                    gx = (float(gray[yy, xx + 1]) - float(gray[yy, xx - 1])) * 0.5 * inv
                    gy = (float(gray[yy + 1, xx]) - float(gray[yy - 1, xx])) * 0.5 * inv
                    a += gx * gx
                    b += gx * gy
                    c += gy * gy
            a /= 9.0
            b /= 9.0
            c /= 9.0
            half = (a - c) * 0.5
            out_x[n] = x
            out_y[n] = y
            out_l[n] = (a + c) * 0.5 - math.sqrt(half * half + b * b)
            n += 1
    return n


def lattice_min_eigenvalues(gray, roi: tuple[int, int, int, int], pitch: int
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(xs, ys, lambda_min)`` at the lattice points ``x % pitch == y % pitch == 0`` inside ``roi``
    (at least 2 px from the frame's border), in frame coordinates.

    ``gray`` is a grey frame or a :class:`GreyPatch` of one that holds ``roi`` grown by 2 px (cut to the frame)."""
    patch = as_patch(gray)
    ox, oy, w, h = patch.x0, patch.y0, patch.frame_w, patch.frame_h
    x0, y0, x1, y1 = roi
    if not patch.covers(max(x0 - 2, 0), max(y0 - 2, 0), min(x1 + 2, w), min(y1 + 2, h)):
        raise ValueError(f"the grey patch does not hold the region {roi} and its 2 px border")
    img = patch.img
    if numba_enabled():
        cap = ((y1 - y0) // pitch + 2) * ((x1 - x0) // pitch + 2)
        xs, ys, lam = np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap)
        n = _lattice_min_eig_numba(img, ox, oy, w, h, int(x0), int(y0), int(x1), int(y1), int(pitch), xs, ys, lam)
        return xs[:n], ys[:n], lam[:n]
    gx0, gy0, gx1, gy1 = max(x0, 2), max(y0, 2), min(x1, w - 2), min(y1, h - 2)
    xs = np.arange(gx0 + (-gx0) % pitch, gx1, pitch)
    ys = np.arange(gy0 + (-gy0) % pitch, gy1, pitch)
    if xs.size == 0 or ys.size == 0:
        e = np.empty(0, np.int64)
        return e, e, np.empty(0)
    sub = patch.view(gx0 - 2, gy0 - 2, gx1 + 2, gy1 + 2)
    lam = min_eigenvalue_reference(sub).astype(np.float64)
    yy, xx = np.meshgrid(ys, xs, indexing="ij")
    return xx.ravel(), yy.ravel(), lam[yy.ravel() - gy0 + 2, xx.ravel() - gx0 + 2]


def shi_tomasi_features(gray, roi: tuple[int, int, int, int], *, lambda_th: float = 1e-3,
                        max_features: int = 300, density: float = 2.0) -> np.ndarray:
    """Shi-Tomasi feature locations (OpenCV pixel-index coordinates of the frame, float32 ``(M, 2)``) inside ``roi``
    of a grey frame or :class:`GreyPatch` ``gray``.

    The smallest eigenvalue is evaluated on a regular lattice (anchored to the image
    grid) with about ``density * max_features`` points — every pixel for small
    regions — and the points above ``lambda_th`` are kept, the strongest
    ``max_features`` of them when more qualify.
    """
    x0, y0, x1, y1 = roi
    area = max(x1 - x0, 0) * max(y1 - y0, 0)
    if area == 0:
        return np.empty((0, 2), np.float32)
    pitch = max(1, int(math.sqrt(area / max(density * max_features, 1.0))))
    xs, ys, lam = lattice_min_eigenvalues(gray, roi, pitch)
    keep = lam > lambda_th
    xs, ys, lam = xs[keep], ys[keep], lam[keep]
    if xs.size > max_features > 0:
        strongest = np.argpartition(-lam, max_features - 1)[:max_features]
        strongest.sort()
        xs, ys = xs[strongest], ys[strongest]
    return np.column_stack([xs, ys]).astype(np.float32)


#: The flow reads the previous frame's grey levels around this frame's features, so each frame's grey patch
#: holds the particles' region grown by the flow's reach and by this much more, for the region's move to the next
#: frame.  With 32 px, 3 of 153,312 features of 25 tune and report sequences found no levels in the previous patch,
#: and so no flow (16 px: 157 features; 8 px: 2,751).
PATCH_SLACK = 32


def lk_reach(window: int = 9, levels: int = 1) -> int:
    """How far (px) from a feature :func:`lucas_kanade_flow` reads the two images: the window, the pyramid's
    borders and a displacement of up to about 25 px (times the coarsest level's scale)."""
    return (window // 2 + 28) * 2 ** max(levels - 1, 0)


def lucas_kanade_flow(prev_gray, gray, points: np.ndarray, *, window: int = 9, levels: int = 1) -> FlowField:
    """Flow at ``points`` of the current image, estimated current → previous and reversed (§3).

    ``prev_gray`` and ``gray`` are grey frames or :class:`GreyPatch` es of them, ``points`` frame coordinates.
    The flow is computed on the one rectangle that holds every point's reach (:func:`lk_reach`), on a grid
    aligned to the coarsest level, so the result is the whole frames' as long as no point travels further, up to
    single-precision rounding (LK iterates in float32, and other coordinates round differently: 1e-4 to 3e-2 px).
    A point whose reach a patch lacks (the previous frame's patch, after a jump of the particles) gets no flow.
    """
    if points.shape[0] == 0:
        return FlowField.empty()
    prev, cur = as_patch(prev_gray), as_patch(gray)
    w, h = cur.frame_w, cur.frame_h
    step = 2 ** max(levels - 1, 0)
    m = lk_reach(window, levels)
    x0, y0 = (max(int(v), 0) for v in np.floor((points.min(0) - m) / step) * step)
    x1, y1 = (int(v) for v in np.minimum(np.ceil((points.max(0) + m) / step) * step, (w, h)))
    if not (prev.covers(x0, y0, x1, y1) and cur.covers(x0, y0, x1, y1)):
        lo = np.maximum(np.floor((points - m) / step) * step, 0).astype(np.int64)
        hi = np.minimum(np.ceil((points + m) / step) * step, (w, h)).astype(np.int64)
        keep = np.ones(len(points), dtype=bool)
        for pa in (prev, cur):
            keep &= ((lo[:, 0] >= pa.x0) & (lo[:, 1] >= pa.y0) & (hi[:, 0] <= pa.x0 + pa.img.shape[1])
                     & (hi[:, 1] <= pa.y0 + pa.img.shape[0]))
        points, lo, hi = points[keep], lo[keep], hi[keep]
        if points.shape[0] == 0:
            return FlowField.empty()
        x0, y0 = (int(v) for v in lo.min(0))
        x1, y1 = (int(v) for v in hi.max(0))
    off = np.array([x0, y0], dtype=np.float32)
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 20, 0.03)
    back, status, _ = cv2.calcOpticalFlowPyrLK(cur.view(x0, y0, x1, y1), prev.view(x0, y0, x1, y1),
                                               (points - off).reshape(-1, 1, 2), None, winSize=(window, window),
                                               maxLevel=max(levels - 1, 0), criteria=crit)
    back = back.reshape(-1, 2) + off
    ok = (status.ravel() == 1) & np.all(np.isfinite(back), axis=1)
    pts = points[ok].astype(np.float64)
    v = pts - back[ok].astype(np.float64)  # reversed: motion from the previous frame to the current one
    return FlowField(pts[:, 0] + 0.5, pts[:, 1] + 0.5, v[:, 0], v[:, 1])


# ------------------------------------------------------------------------------------------ Eq. 4

@njit
def _region_sums(fx, fy, fvx, fvy, cx, cy, hx, hy):
    """Epanechnikov-weighted sums of the flow vectors in the rectangle |x - cx| < hx, |y - cy| < hy."""
    sx = 0.0
    sy = 0.0
    sw = 0.0
    if hx > 0.0 and hy > 0.0:
        ihx = 1.0 / hx
        ihy = 1.0 / hy
        for i in range(fx.shape[0]):
            u = (fx[i] - cx) * ihx
            if u <= -1.0 or u >= 1.0:
                continue
            v = (fy[i] - cy) * ihy
            if v <= -1.0 or v >= 1.0:
                continue
            wgt = (1.0 - u * u) * (1.0 - v * v)
            sx += wgt * fvx[i]
            sy += wgt * fvy[i]
            sw += wgt
    return sx, sy, sw


@njit
def _local_motion_numba(fx, fy, fvx, fvy, ell, out, weight):
    n = ell.shape[0]
    for k in range(n):
        cx = ell[k, 0]
        cy = ell[k, 1]
        hx = ell[k, 2]
        hy = ell[k, 3]
        sx, sy, sw = _region_sums(fx, fy, fvx, fvy, cx, cy, hx, hy)
        weight[k] = sw
        if sw > 0.0:
            out[k, 0] = sx / sw
            out[k, 1] = sy / sw
        else:
            out[k, 0] = 0.0
            out[k, 1] = 0.0
    return out


def _local_motion_numpy(fx, fy, fvx, fvy, ell, out, weight):
    u = (fx[None, :] - ell[:, 0:1]) / ell[:, 2:3]
    v = (fy[None, :] - ell[:, 1:2]) / ell[:, 3:4]
    inside = (np.abs(u) < 1.0) & (np.abs(v) < 1.0)
    wgt = np.where(inside, (1.0 - u * u) * (1.0 - v * v), 0.0)
    sw = wgt.sum(axis=1)
    weight[:] = sw
    safe = np.where(sw > 0, sw, 1.0)
    out[:, 0] = np.where(sw > 0, wgt @ fvx / safe, 0.0)
    out[:, 1] = np.where(sw > 0, wgt @ fvy / safe, 0.0)
    return out


def local_motion(flow: FlowField, ellipses: np.ndarray, *, backend: str | None = None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Local-motion feature ``v_E`` (Eq. 4) of every particle region.

    ``E`` is the rectangle ``|x - cx| < hx, |y - cy| < hy`` over the particle's
    ellipse; the Epanechnikov kernel on it is ``(1 - u^2)(1 - v^2)`` with
    ``u = (x - cx)/hx``, ``v = (y - cy)/hy``.  Returns ``(v (N, 2), defined (N,))``;
    an undefined region (no feature inside) has ``v = 0``.
    """
    ell = np.ascontiguousarray(ellipses, dtype=np.float64).reshape(-1, 4)
    n = ell.shape[0]
    out = np.empty((n, 2))
    weight = np.empty(n)
    use_numba = numba_enabled() if backend is None else backend == "numba"
    args = (flow.x, flow.y, flow.vx, flow.vy, ell, out, weight)
    if flow.n == 0:
        out[:] = 0.0
        weight[:] = 0.0
    elif use_numba:
        _local_motion_numba(*args)
    else:
        _local_motion_numpy(*args)
    return out, weight > 0


# ------------------------------------------------------------------------------------------ Eqs. 5-7

def similarities(v: np.ndarray, v_ref, defined: np.ndarray | None = None, *, eps: float = 1e-2
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Angular and amplitude similarities ``G_theta``, ``G_r`` (Eqs. 5–6) of vectors ``v`` to ``v_ref``."""
    v = np.atleast_2d(np.asarray(v, dtype=np.float64))
    vr = np.asarray(v_ref, dtype=np.float64)
    r = np.hypot(v[:, 0], v[:, 1])
    r_ref = float(np.hypot(vr[0], vr[1]))
    both = (r > eps) & (r_ref > eps)
    cosang = np.where(both, (v[:, 0] * vr[0] + v[:, 1] * vr[1]) / np.where(both, r * r_ref, 1.0), 1.0)
    g_theta = np.where(both, np.arccos(np.clip(cosang, -1.0, 1.0)) / math.pi, 1.0)
    either = (r > eps) | (r_ref > eps)
    g_r = np.where(either, np.abs(r_ref - r) / np.where(either, r_ref + r, 1.0), 0.0)
    if defined is not None:
        g_theta = np.where(defined, g_theta, 1.0)
        g_r = np.where(defined, g_r, 1.0)
    return g_theta, g_r


def _similarity_pair(vx: float, vy: float, rx: float, ry: float, eps: float) -> tuple[float, float]:
    """:func:`similarities` of one vector ``(vx, vy)`` to ``(rx, ry)``, in scalar arithmetic."""
    r, r_ref = math.hypot(vx, vy), math.hypot(rx, ry)
    if r > eps and r_ref > eps:
        g_theta = math.acos(min(max((vx * rx + vy * ry) / (r * r_ref), -1.0), 1.0)) / math.pi
    else:
        g_theta = 1.0
    g_r = abs(r_ref - r) / (r_ref + r) if (r > eps or r_ref > eps) else 0.0
    return g_theta, g_r


def motion_likelihood(g_theta, g_r, *, sigma_theta: float = 0.1, sigma_r: float = 0.3,
                      w_noise: float = 0.01) -> np.ndarray:
    """``p(G_theta, G_r) = (1 - w_noise) exp(-(G_theta/sigma_theta + G_r/sigma_r)) + w_noise`` (Eq. 7)."""
    return (1.0 - w_noise) * np.exp(-(np.asarray(g_theta) / sigma_theta + np.asarray(g_r) / sigma_r)) + w_noise


@njit
def _motion_loglik_numba(fx, fy, fvx, fvy, ell, rx, ry, eps, s_t, s_r, w_noise, out):
    n = ell.shape[0]
    r_ref = math.sqrt(rx * rx + ry * ry)
    for k in range(n):
        cx = ell[k, 0]
        cy = ell[k, 1]
        hx = ell[k, 2]
        hy = ell[k, 3]
        sx, sy, sw = _region_sums(fx, fy, fvx, fvy, cx, cy, hx, hy)
        if sw > 0.0:
            vx = sx / sw
            vy = sy / sw
            r = math.sqrt(vx * vx + vy * vy)
            if r > eps and r_ref > eps:
                c = (vx * rx + vy * ry) / (r * r_ref)
                c = min(max(c, -1.0), 1.0)
                g_t = math.acos(c) / math.pi
            else:
                g_t = 1.0
            if r > eps or r_ref > eps:
                g_r = abs(r_ref - r) / (r_ref + r)
            else:
                g_r = 0.0
        else:
            g_t = 1.0
            g_r = 1.0
        out[k] = math.log((1.0 - w_noise) * math.exp(-(g_t / s_t + g_r / s_r)) + w_noise)
    return out


def motion_log_likelihood(flow: FlowField, ellipses: np.ndarray, v_ref, *, eps: float = 1e-2,
                          sigma_theta: float = 0.1, sigma_r: float = 0.3, w_noise: float = 0.01,
                          backend: str | None = None) -> np.ndarray:
    """``log p(y_mot | x)`` of every particle: Eq. 4, Eqs. 5-6 and Eq. 7 fused (compiled), or composed (NumPy)."""
    ell = np.ascontiguousarray(ellipses, dtype=np.float64).reshape(-1, 4)
    vr = np.asarray(v_ref, dtype=np.float64)
    use_numba = numba_enabled() if backend is None else backend == "numba"
    if use_numba:
        out = np.empty(ell.shape[0])
        return _motion_loglik_numba(flow.x, flow.y, flow.vx, flow.vy, ell, float(vr[0]), float(vr[1]), float(eps),
                                    float(sigma_theta), float(sigma_r), float(w_noise), out)
    v, defined = local_motion(flow, ell, backend="numpy")
    g_t, g_r = similarities(v, vr, defined, eps=eps)
    return np.log(motion_likelihood(g_t, g_r, sigma_theta=sigma_theta, sigma_r=sigma_r, w_noise=w_noise))


def blend_angle(a: float, b: float, t: float) -> float:
    """Interpolate from angle ``a`` towards ``b`` by ``t`` along the shorter arc."""
    d = math.atan2(math.sin(b - a), math.cos(b - a))
    return a + t * d


@dataclass
class LocalMotionCue:
    """Flow features and the local-motion likelihood with the paper's defaults."""

    lambda_th: float = 1e-3
    window: int = 9
    levels: int = 1
    max_features: int = 300
    eps: float = 1e-2
    sigma_theta: float = 0.1
    sigma_r: float = 0.3
    w_noise: float = 0.01

    def prepare(self, prev_gray, gray, roi: tuple[int, int, int, int]) -> FlowField:
        """Features in ``roi`` of the current image and their flow (once per frame).

        The images are grey frames or :class:`GreyPatch` es; the current one must hold ``roi`` grown by
        :meth:`margin`, the previous one as much of it as it can (:func:`lucas_kanade_flow`)."""
        pts = shi_tomasi_features(gray, roi, lambda_th=self.lambda_th, max_features=self.max_features)
        return lucas_kanade_flow(prev_gray, gray, pts, window=self.window, levels=self.levels)

    def margin(self) -> int:
        """How far around ``roi`` :meth:`prepare` reads the images: the flow's reach."""
        return lk_reach(self.window, self.levels)

    def frame_patch(self, frame: np.ndarray, roi: tuple[int, int, int, int]) -> GreyPatch:
        """The grey levels of ``frame`` that :meth:`prepare` reads now, with ``roi`` the particles' region, and
        again on the next frame, as the previous one: ``roi`` grown by the flow's reach and by
        :data:`PATCH_SLACK`."""
        return grey_patch(frame, roi, self.margin() + PATCH_SLACK)

    def log_likelihood(self, flow: FlowField, ellipses: np.ndarray, v_ref) -> np.ndarray:
        """``log p(y_mot | x)`` of every particle (Eq. 12): Eq. 7 at the particle's local motion."""
        return motion_log_likelihood(flow, ellipses, v_ref, eps=self.eps, sigma_theta=self.sigma_theta,
                                     sigma_r=self.sigma_r, w_noise=self.w_noise)

    def adapt(self, v_ref, v_est, v_obs) -> np.ndarray:
        """Reference adaptation (Eqs. 8–9).

        ``v_est`` is the tracker's estimated velocity, ``v_obs`` the local motion
        observed at the estimate.  The intensities ``alpha_theta = p(G_theta(v_est, v_obs), 0)``
        and ``alpha_r = p(0, G_r(v_est, v_obs))`` are high when the tracker's motion
        agrees with the observed motion and fall to ``w_noise`` when they disagree
        (an occluder moving differently); the reference then moves towards the
        observation by that much.  (The printed Eq. 8 writes the weights the other way
        round, which contradicts its own explanation in §3.2; we follow the text.)
        """
        v_ref = np.asarray(v_ref, dtype=np.float64)
        v_obs = np.asarray(v_obs, dtype=np.float64)
        g_t, g_r = _similarity_pair(float(v_obs[0]), float(v_obs[1]), float(v_est[0]), float(v_est[1]), self.eps)
        # Eq. 7 at (g_t, 0) and at (0, g_r), in scalar arithmetic (once a frame: NumPy's call costs more)
        w = self.w_noise
        a_t = (1.0 - w) * math.exp(-(g_t / self.sigma_theta)) + w
        a_r = (1.0 - w) * math.exp(-(g_r / self.sigma_r)) + w
        th_ref, r_ref = math.atan2(v_ref[1], v_ref[0]), math.hypot(v_ref[0], v_ref[1])
        th_obs, r_obs = math.atan2(v_obs[1], v_obs[0]), math.hypot(v_obs[0], v_obs[1])
        if r_ref <= self.eps:  # no direction yet: take the observed one
            th = th_obs
        elif r_obs <= self.eps:
            th = th_ref
        else:
            th = blend_angle(th_ref, th_obs, a_t)
        r = (1.0 - a_r) * r_ref + a_r * r_obs
        return np.array([r * math.cos(th), r * math.sin(th)])
