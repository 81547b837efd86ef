"""Structural similarity (SSIM) for a whole particle set at once, and its gradient for DSSIM (book ch. 2).

Book *Object Tracking*, ch. 2 (``shared/seeds/002_*`` lines 754-1953; specification
``shared/book/ch02.md``), after Wang, Bovik, Sheikh & Simoncelli (IEEE TIP 2004):

* **(21)** ``S(I, J) = (2 mu_I mu_J + C1)/(mu_I^2 + mu_J^2 + C1) * (2 sigma_IJ + C2)/(sigma_I^2 + sigma_J^2 + C2)``
  with ``C3 = C2/2``, ``C1 = (0.01 * 255)^2``, ``C2 = (0.03 * 255)^2``;
* computed **locally** in an 11x11 Gaussian window (sigma 1.5, restored from Wang 2004) and
  averaged over the map (MSSIM), optionally after cropping the 5-px border (scikit-image's
  convention) — :func:`ssim_batch`;
* **(25)** the dissimilarity ``D = (1 - S)/2`` and **(29)** the likelihood
  ``exp(-D^2 / D_min^2)`` with ``D_min`` the smallest ``D`` of the frame's particles —
  :func:`log_likelihood_dmin`;
* **(18)-(20)** global statistics over the L pixels of a region (``L - 1`` denominators) for a
  batch (:func:`ssim_global_stack`) and for every placement in an image (:func:`ssim_global_map`);
  the single-region form, its gradient (31)-(39) and the DSSIM ascent are in
  :mod:`pftrack.cues.ssim_ascent`.

Speed (GUIDE §3): every particle's patch is sampled with one ``cv2.remap`` over stacked
maps, and the five local statistics of the whole batch come from separable Gaussian
filters over a ``(h, w, N)`` stack (``cv2.sepFilter2D`` filters all channels at once).
"""

from __future__ import annotations

import cv2
import numpy as np

from .._numba import njit, numba_enabled

K1, K2, DATA_RANGE = 0.01, 0.03, 255.0
C1 = (K1 * DATA_RANGE) ** 2
C2 = (K2 * DATA_RANGE) ** 2
WINDOW, WINDOW_SIGMA = 11, 1.5
_MAX_CHANNELS = 512  # OpenCV's CV_CN_MAX
_MAX_ROWS = 32000  # remap sizes must stay below SHRT_MAX


def to_gray(frame: np.ndarray) -> np.ndarray:
    """float32 grey image of a BGR or grey frame (levels 0-255)."""
    if frame.ndim == 2:
        return frame.astype(np.float32, copy=False)
    if frame.shape[2] == 1:
        return frame[..., 0].astype(np.float32)
    return cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY).astype(np.float32)


def gaussian_window(size: int = WINDOW, sigma: float = WINDOW_SIGMA) -> np.ndarray:
    """The normalised 1-D Gaussian of the separable SSIM window (Wang 2004: 11 taps, sigma 1.5)."""
    return cv2.getGaussianKernel(size, sigma, cv2.CV_64F).ravel()


# ------------------------------------------------------------------------------ patches

def patch_grid(shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Offsets ``(u, v)`` of the pixel centres of a ``(h, w)`` reference patch from its centre."""
    h, w = shape
    u = np.arange(w, dtype=np.float64) - (w - 1) / 2.0
    v = np.arange(h, dtype=np.float64) - (h - 1) / 2.0
    return u, v


def sample_patches(image: np.ndarray, states: np.ndarray, shape: tuple[int, int], *,
                   border: int = cv2.BORDER_REFLECT) -> np.ndarray:
    """Every state's region resampled to the reference size: ``(N, h, w[, c])`` float32.

    ``states`` rows are ``(cx, cy, s[, angle])``: a region of size ``s * (w, h)`` centred
    at ``(cx, cy)`` (pixel-centre coordinates: pixel ``(i, j)`` has its centre at
    ``(i + 0.5, j + 0.5)``), rotated by ``angle`` radians when given.  Bilinear
    sampling through one ``cv2.remap`` per chunk of states.
    """
    st = np.asarray(states, dtype=np.float64).reshape(len(states), -1)
    n = st.shape[0]
    h, w = shape
    u, v = patch_grid(shape)
    uu, vv = np.meshgrid(u.astype(np.float32), v.astype(np.float32))  # (h, w)
    out_shape = (n, h, w) + image.shape[2:]
    out = np.empty(out_shape, dtype=np.float32)
    if n == 0:
        return out
    src = image if image.dtype == np.float32 else image.astype(np.float32)
    per = max(1, _MAX_ROWS // h)
    stf = st.astype(np.float32)
    for a in range(0, n, per):
        b = min(n, a + per)
        cx = (stf[a:b, 0] - 0.5)[:, None, None]
        cy = (stf[a:b, 1] - 0.5)[:, None, None]
        sc = stf[a:b, 2, None, None]
        if st.shape[1] > 3:
            ca, sa = np.cos(stf[a:b, 3])[:, None, None], np.sin(stf[a:b, 3])[:, None, None]
            mx = cx + sc * (ca * uu - sa * vv)
            my = cy + sc * (sa * uu + ca * vv)
        else:
            mx = sc * uu
            mx += cx
            my = sc * vv
            my += cy
        res = cv2.remap(src, mx.reshape((b - a) * h, w), my.reshape((b - a) * h, w), cv2.INTER_LINEAR,
                        borderMode=border)
        out[a:b] = res.reshape((b - a, h, w) + image.shape[2:])
    return out


def sample_stack(gray: np.ndarray, states: np.ndarray, shape: tuple[int, int], *,
                 border: int = cv2.BORDER_REFLECT) -> np.ndarray:
    """As :func:`sample_patches` for a grey image, laid out as an ``(h, w, N)`` stack (no rotation).

    The maps are built column-interleaved (``(h, w * N)``), so the remapped image is the
    stack that :func:`ssim_stack` filters, without a transpose.
    """
    st = np.asarray(states, dtype=np.float32).reshape(len(states), -1)
    n = st.shape[0]
    h, w = shape
    u, v = patch_grid(shape)
    src = gray if gray.dtype == np.float32 else gray.astype(np.float32)
    out = np.empty((h, w, n), dtype=np.float32)
    per = max(1, _MAX_ROWS // w)
    for a in range(0, n, per):
        b = min(n, a + per)
        cx, cy, sc = st[a:b, 0] - 0.5, st[a:b, 1] - 0.5, st[a:b, 2]
        mx = np.broadcast_to((u.astype(np.float32)[:, None] * sc[None, :] + cx[None, :])[None], (h, w, b - a))
        my = np.broadcast_to((v.astype(np.float32)[:, None] * sc[None, :] + cy[None, :])[:, None, :], (h, w, b - a))
        res = cv2.remap(src, np.ascontiguousarray(mx).reshape(h, w * (b - a)),
                        np.ascontiguousarray(my).reshape(h, w * (b - a)), cv2.INTER_LINEAR, borderMode=border)
        out[:, :, a:b] = res.reshape(h, w, b - a)
    return out


# ------------------------------------------------------------------------------ SSIM

def _filter_stack(stack: np.ndarray, k: np.ndarray, border: int) -> np.ndarray:
    """Separable filter of every channel of an ``(h, w, N)`` float32 stack (chunks of 512 channels)."""
    n = stack.shape[2]
    if n <= _MAX_CHANNELS:  # (OpenCV returns a single channel as a 2-D array)
        return cv2.sepFilter2D(stack, cv2.CV_32F, k, k, borderType=border).reshape(stack.shape)
    return np.concatenate([_filter_stack(np.ascontiguousarray(stack[..., a:a + _MAX_CHANNELS]), k, border)
                           for a in range(0, n, _MAX_CHANNELS)], axis=2)


def ssim_batch(patches: np.ndarray, template: np.ndarray, *, crop: bool = True, sigma: float = WINDOW_SIGMA,
               size: int = WINDOW, c1: float = C1, c2: float = C2, border: int = cv2.BORDER_REFLECT) -> np.ndarray:
    """MSSIM of each of ``N`` grey patches ``(N, h, w)`` against one template ``(h, w)``: ``(N,)``.

    Local statistics in a ``size`` x ``size`` Gaussian window (Wang 2004, weighted, no
    ``L - 1``), eq. (21), averaged over the map; ``crop`` drops ``(size - 1)/2`` pixels
    at each border first (scikit-image's ``structural_similarity`` convention).
    ``border=cv2.BORDER_REFLECT_101`` with ``crop=False`` is OpenCV's ``quality.QualitySSIM``.
    """
    p = np.asarray(patches, dtype=np.float32)
    if p.shape[0] == 0:
        return np.empty(0)
    n, h, w = p.shape
    # (N, h*w) -> (h*w, N): OpenCV's blocked transpose is ~14x faster than NumPy's strided copy here
    stack = cv2.transpose(np.ascontiguousarray(p).reshape(n, h * w)).reshape(h, w, n)
    return ssim_stack(stack, template, crop=crop, sigma=sigma, size=size, c1=c1, c2=c2, border=border)


def ssim_stack(stack: np.ndarray, template: np.ndarray, *, crop: bool = True, sigma: float = WINDOW_SIGMA,
               size: int = WINDOW, c1: float = C1, c2: float = C2, border: int = cv2.BORDER_REFLECT) -> np.ndarray:
    """:func:`ssim_batch` on an ``(h, w, N)`` float32 stack of patches (the layout of :func:`sample_stack`)."""
    stack = np.ascontiguousarray(stack, dtype=np.float32)
    t = np.asarray(template, dtype=np.float32)
    h, w, n = stack.shape
    if t.shape != (h, w):
        raise ValueError(f"template {t.shape} and patches {(h, w)} differ in size")
    if n == 0:
        return np.empty(0)
    k = cv2.getGaussianKernel(size, sigma, cv2.CV_32F)
    mu_p = _filter_stack(stack, k, border)
    e_pp = _filter_stack(stack * stack, k, border)
    e_pt = _filter_stack(stack * t[..., None], k, border)
    mu_t = cv2.sepFilter2D(t, cv2.CV_32F, k, k, borderType=border)[..., None]
    e_tt = cv2.sepFilter2D(t * t, cv2.CV_32F, k, k, borderType=border)[..., None]
    r = (size - 1) // 2 if crop else 0
    if h <= 2 * r or w <= 2 * r:
        raise ValueError(f"patches of {h}x{w} px leave nothing after the {r}-px crop of the SSIM window")
    if numba_enabled():
        out = np.empty(n)
        _combine(mu_p, e_pp, e_pt, mu_t[..., 0], e_tt[..., 0], r, c1, c2, out)
        return out
    # float32 is enough: levels <= 255, so E[x^2] - mu^2 keeps ~1e-2 absolute against C2 = 58.5
    mu_pt = mu_p * mu_t
    mu_pp = mu_p * mu_p
    mu_tt = mu_t * mu_t
    num = mu_pt * 2 + np.float32(c1)
    num *= (e_pt - mu_pt) * 2 + np.float32(c2)
    den = mu_pp + mu_tt + np.float32(c1)
    den *= (e_pp - mu_pp) + (e_tt - mu_tt) + np.float32(c2)
    smap = num
    smap /= den
    return smap[r:h - r, r:w - r].mean(axis=(0, 1), dtype=np.float64)


@njit(fastmath=True)
def _combine(mu_p, e_pp, e_pt, mu_t, e_tt, r, c1, c2, out):
    """Eq. (21) per pixel from the filtered statistics, averaged over the cropped map, in one pass."""
    h, w, n = mu_p.shape
    for k in range(n):
        out[k] = 0.0
    for i in range(r, h - r):
        for j in range(r, w - r):
            mt = np.float64(mu_t[i, j])
            vt = np.float64(e_tt[i, j]) - mt * mt
            for k in range(n):
                mp = np.float64(mu_p[i, j, k])
                vp = np.float64(e_pp[i, j, k]) - mp * mp
                cv = np.float64(e_pt[i, j, k]) - mp * mt
                out[k] += ((2 * mp * mt + c1) * (2 * cv + c2)) / ((mp * mp + mt * mt + c1) * (vp + vt + c2))
    m = (h - 2 * r) * (w - 2 * r)
    for k in range(n):
        out[k] /= m


def ssim_global_stack(stack: np.ndarray, template: np.ndarray, *, c1: float = C1, c2: float = C2) -> np.ndarray:
    """Eq. (21) with global statistics (18)-(20) for every patch of an ``(h, w, N)`` stack: ``(N,)``."""
    x = np.asarray(stack, dtype=np.float64).reshape(-1, stack.shape[2])
    t = np.asarray(template, dtype=np.float64).ravel()
    n = t.size
    mt = t.mean()
    dt = t - mt
    vt = float(dt @ dt) / (n - 1)
    mx = x.mean(axis=0)
    vx = (np.einsum("ij,ij->j", x, x) - n * mx * mx) / (n - 1)
    cxt = (dt @ x) / (n - 1)  # sum (x - mx)(t - mt) = sum x (t - mt)
    return (2 * mx * mt + c1) * (2 * cxt + c2) / ((mx * mx + mt * mt + c1) * (vx + vt + c2))


def ssim_global_map(image: np.ndarray, template: np.ndarray, *, c1: float = C1, c2: float = C2,
                    work: dict | None = None) -> np.ndarray:
    """Eq. (21) with global statistics (18)-(20) for every placement of ``template`` in ``image``.

    Returns the ``(H - h + 1, W - w + 1)`` map (top-left anchored, as ``cv2.matchTemplate``): the
    covariance term is one ``matchTemplate`` with the zero-mean template, the window means and
    variances come from integral images.  The placement with top-left ``(x0, y0)`` is the state
    ``(x0 + w / 2, y0 + h / 2, 1)`` of :func:`ssim_global_stack`.

    ``work``: a dict the caller keeps between calls; the integral images, the correlation and the returned
    map are written into arrays cached there while the sizes stay the same (the returned array is then
    overwritten by the next call).  A search repeated every frame saves the allocation and first touch of
    megabytes of fresh memory per call, which cost more than the arithmetic."""
    img = np.ascontiguousarray(image, dtype=np.float32)
    t = np.asarray(template, dtype=np.float64)
    h, w = t.shape
    n = h * w
    mt = t.mean()
    dt = t - mt
    vt = float(np.sum(dt * dt)) / (n - 1)
    H, W = img.shape
    mh, mw = H - h + 1, W - w + 1
    if work is None:
        cxt = cv2.matchTemplate(img, dt.astype(np.float32), cv2.TM_CCORR)
        s1, s2 = cv2.integral2(img, sdepth=cv2.CV_64F, sqdepth=cv2.CV_64F)
        out = np.empty(cxt.shape)
    else:
        if work.get("shape") != (H, W, h, w):
            work.update(shape=(H, W, h, w), sum=np.empty((H + 1, W + 1)), sqsum=np.empty((H + 1, W + 1)),
                        corr=np.empty((max(mh, 1), max(mw, 1)), np.float32), out=np.empty((max(mh, 1), max(mw, 1))))
        cxt = cv2.matchTemplate(img, dt.astype(np.float32), cv2.TM_CCORR, result=work["corr"])
        s1, s2 = cv2.integral2(img, sum=work["sum"], sqsum=work["sqsum"], sdepth=cv2.CV_64F, sqdepth=cv2.CV_64F)
        out = work["out"]
    if not numba_enabled():  # the same arithmetic, array by array
        mx = (s1[h:, w:] - s1[:-h, w:] - s1[h:, :-w] + s1[:-h, :-w]) / n
        vx = np.maximum(s2[h:, w:] - s2[:-h, w:] - s2[h:, :-w] + s2[:-h, :-w] - n * mx * mx, 0.0) / (n - 1)
        cx = cxt.astype(np.float64) / (n - 1)
        out[...] = (2 * mx * mt + c1) * (2 * cx + c2) / ((mx * mx + mt * mt + c1) * (vx + vt + c2))
        return out
    _global_map(s1, s2, cxt, h, w, float(mt), vt, float(c1), float(c2), out)
    return out


@njit
def _global_map(s1, s2, cxt, h, w, mt, vt, c1, c2, out):
    """The per-placement part of :func:`ssim_global_map` in one pass: window means and variances from the
    integral images, the covariance from the correlation map (float64 throughout)."""
    n = h * w
    for r in range(out.shape[0]):
        for c in range(out.shape[1]):
            a = s1[r + h, c + w] - s1[r, c + w] - s1[r + h, c] + s1[r, c]
            b = s2[r + h, c + w] - s2[r, c + w] - s2[r + h, c] + s2[r, c]
            mx = a / n
            vx = max(b - n * mx * mx, 0.0) / (n - 1)
            cx = np.float64(cxt[r, c]) / (n - 1)
            out[r, c] = (2 * mx * mt + c1) * (2 * cx + c2) / ((mx * mx + mt * mt + c1) * (vx + vt + c2))


def top_peaks(score: np.ndarray, k: int, radius: tuple[int, int], *, inplace: bool = False) -> np.ndarray:
    """Row-major ``(row, col)`` of up to ``k`` maxima of ``score``, each at least ``radius = (ry, rx)`` from
    the ones before it (greedy non-maximum suppression).  ``inplace``: suppress in ``score`` itself (a
    float64 array the caller no longer needs) instead of a copy."""
    a = score if inplace and score.dtype == np.float64 else np.array(score, dtype=np.float64, copy=True)
    ry, rx = max(int(radius[0]), 0), max(int(radius[1]), 0)
    out = []
    for _ in range(k):
        i = int(np.argmax(a))
        r, c = divmod(i, a.shape[1])
        if not np.isfinite(a[r, c]) or a[r, c] == -np.inf:
            break
        out.append((r, c))
        a[max(r - ry, 0):r + ry + 1, max(c - rx, 0):c + rx + 1] = -np.inf
    return np.array(out, dtype=np.int64).reshape(-1, 2)


def ssim_reference(a: np.ndarray, b: np.ndarray, *, crop: bool = True, sigma: float = WINDOW_SIGMA,
                   size: int = WINDOW, c1: float = C1, c2: float = C2, border: int = cv2.BORDER_REFLECT) -> float:
    """Wang et al.'s MSSIM of one pair, written straight from the formula (float64; the tests' oracle)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    k = cv2.getGaussianKernel(size, sigma, cv2.CV_64F)

    def g(x):
        return cv2.sepFilter2D(x, cv2.CV_64F, k, k, borderType=border)

    mu_a, mu_b = g(a), g(b)
    va, vb, cab = g(a * a) - mu_a ** 2, g(b * b) - mu_b ** 2, g(a * b) - mu_a * mu_b
    smap = ((2 * mu_a * mu_b + c1) * (2 * cab + c2)) / ((mu_a ** 2 + mu_b ** 2 + c1) * (va + vb + c2))
    if crop:
        r = (size - 1) // 2
        smap = smap[r:-r, r:-r]
    return float(smap.mean())


def dissimilarity(s: np.ndarray) -> np.ndarray:
    """Eq. (25): ``D = (1 - S) / 2`` in ``[0, 1]``."""
    return (1.0 - np.asarray(s, dtype=np.float64)) / 2.0


def log_likelihood_dmin(d: np.ndarray, *, floor: float = 1e-3) -> np.ndarray:
    """Eq. (29) in the log domain: ``-D^2 / max(D_min, floor)^2`` (the best particle scores -1)."""
    d = np.asarray(d, dtype=np.float64)
    finite = np.isfinite(d)
    dmin = max(float(d[finite].min()) if finite.any() else 1.0, floor)
    out = -(d * d) / (dmin * dmin)
    out[~finite] = -np.inf
    return out
