"""Region covariance descriptors and the Log-Euclidean metric on SPD matrices (book ch. 6, §4).

Book *Object Tracking*, ch. 6 (``shared/seeds/002_*`` lines 5370-6238; specification
``shared/book/ch06.md`` §1.6-1.9), after Porikli, Tuzel & Meer (CVPR 2006), Tuzel et al.
(ECCV 2006) and Arsigny et al. (2005, 2007):

* **features** (restored from Porikli 2006; the chapter says only "pixel coordinates, RGB
  colours and gradients"): ``z = [x, y, R, G, B, |Ix|, |Iy|, |Ixx|, |Iyy|]`` (``kind="porikli9"``)
  or without the second derivatives (``"first_order"``); on grey input the three colour
  channels are one intensity channel (they would be identical and the covariance singular) —
  :func:`covariance_features`;
* **(27)** ``C_R = 1/(n-1) sum_k (z_k - mu)(z_k - mu)^T`` over the (optionally weighted or
  masked) pixels of a window, for thousands of windows at once from integral images of
  ``m``, ``m z_i`` and ``m z_i z_j`` (Tuzel 2006) — :class:`IntegralCovariance`;
* **standardisation** (ch06.md §1.6, P6): the Log-Euclidean distance is not invariant to
  per-feature units, so ``C <- D C D`` with ``D = diag(1/w, 1/h, 1/255, ..., 1/s_k)`` (``s_k``
  the frame-level spread of each derivative channel) and ``+ eps I`` — :func:`standardize`;
* **(24)-(26)** ``log C = U diag(ln lambda) U^T`` by a batched eigen-decomposition —
  :func:`spd_log`, :func:`spd_exp`;
* **(30)** the Log-Euclidean distance ``||log C1 - log C2||_F`` — :func:`le_distance`;
* **(28)-(29)** the affine-invariant distance ``sqrt(sum ln^2 lambda_i(C1, C2))`` with the
  generalised eigenproblem ``lambda C1 x = C2 x`` (the book prints ``C1`` twice; ch06.md P2) —
  :func:`airm_distance`;
* **(31)** the weighted Log-Euclidean mean ``exp(sum w_i log C_i)``, ``sum w_i = 1`` (restored
  from Arsigny 2007; the book prints ``exp(sum log C_i)``, which is not a mean) —
  :func:`le_mean`; and the affine-invariant (Karcher) mean it replaces — :func:`airm_mean`.
"""

from __future__ import annotations

import cv2
import numpy as np

from .._numba import njit, numba_enabled

FEATURE_KINDS = ("porikli9", "first_order")

#: The SPD regulariser added after standardisation (ch06.md §1.6 proposes 1e-6).  A constant
#: channel (a flat-coloured target) has zero variance, and ``log`` then magnifies differences of
#: a fraction of a grey level between windows into distances of several units; ``1e-4`` is the
#: variance of about 2.5 grey levels (8-bit camera noise) in standardised units, so a channel
#: flatter than the noise counts as flat, whatever its exact variance.
EPS = 1e-4


def feature_names(kind: str = "porikli9", *, gray: bool = False) -> tuple[str, ...]:
    """Names of the channels :func:`covariance_features` returns."""
    if kind not in FEATURE_KINDS:
        raise ValueError(f"unknown covariance feature kind {kind!r}; expected one of {FEATURE_KINDS}")
    colour = ("I",) if gray else ("R", "G", "B")
    deriv = ("|Ix|", "|Iy|", "|Ixx|", "|Iyy|") if kind == "porikli9" else ("|Ix|", "|Iy|")
    return ("x", "y") + colour + deriv


def covariance_features(frame: np.ndarray, *, kind: str = "porikli9", gray: bool = False,
                        origin: tuple[float, float] = (0.0, 0.0), pitch: float = 1.0) -> np.ndarray:
    """``(H, W, d)`` float64 feature image of a BGR (or grey) region, Eq. 27's ``z``.

    ``x, y`` are frame coordinates: ``origin + pitch * (column, row)`` (so a decimated region
    keeps frame units).  Derivatives of the grey image use the filters ``[-1 0 1]`` and
    ``[1 -2 1]`` (``cv2.Sobel`` with ``ksize=1``), Porikli 2006's choice.  With ``gray`` the
    colour channels are replaced by the intensity.
    """
    names = feature_names(kind, gray=gray)
    img = frame if frame.ndim == 3 else frame[..., None]
    h, w = img.shape[:2]
    g = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if img.shape[2] == 3 else img[..., 0]
    g = g.astype(np.float32)
    z = np.empty((h, w, len(names)), dtype=np.float64)
    z[..., 0] = origin[0] + pitch * np.arange(w, dtype=np.float64)[None, :]
    z[..., 1] = origin[1] + pitch * np.arange(h, dtype=np.float64)[:, None]
    k = 2
    if gray:
        z[..., 2] = g
        k = 3
    else:
        z[..., 2] = img[..., 2]
        z[..., 3] = img[..., 1]
        z[..., 4] = img[..., 0]
        k = 5
    z[..., k] = np.abs(cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=1))
    z[..., k + 1] = np.abs(cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=1))
    if kind == "porikli9":
        z[..., k + 2] = np.abs(cv2.Sobel(g, cv2.CV_32F, 2, 0, ksize=1))
        z[..., k + 3] = np.abs(cv2.Sobel(g, cv2.CV_32F, 0, 2, ksize=1))
    return z


def feature_scales(z: np.ndarray, *, gray: bool = False, floor: float = 1.0) -> np.ndarray:
    """``(d,)`` scales of the standardisation ``D`` (ch06.md §1.6): 255 for colour channels, the
    frame-level standard deviation (at least ``floor``) for each derivative channel.  The two
    coordinate entries are placeholders (they are set per window from its size)."""
    d = z.shape[-1]
    n_colour = 1 if gray else 3
    s = np.ones(d)
    s[2:2 + n_colour] = 255.0
    for k in range(2 + n_colour, d):
        s[k] = max(float(z[..., k].std()), floor)
    return s


def standardize(C: np.ndarray, sizes: np.ndarray, scales: np.ndarray, *, eps: float = EPS) -> np.ndarray:
    """``D C D + eps I`` with ``D = diag(1/w, 1/h, 1/scales[2:])`` per window (ch06.md §1.6, P6).

    ``C`` is ``(K, d, d)``, ``sizes`` ``(K, 2)`` window widths and heights.  After this the
    coordinate variances of a full window are ``1/12`` whatever its size, and a colour or
    gradient unit means the same in every frame.
    """
    C = np.asarray(C, dtype=np.float64)
    sizes = np.asarray(sizes, dtype=np.float64).reshape(-1, 2)
    dv = np.broadcast_to(1.0 / np.asarray(scales, dtype=np.float64), (C.shape[0], C.shape[-1])).copy()
    dv[:, 0] = 1.0 / sizes[:, 0]
    dv[:, 1] = 1.0 / sizes[:, 1]
    out = C * dv[:, :, None] * dv[:, None, :]
    out += eps * np.eye(C.shape[-1])
    return out


def region_covariance(z: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Eq. 27 directly on the pixels of one region (``z`` ``(..., d)``; the reference for
    :class:`IntegralCovariance`): ``sum m (z - mu)(z - mu)^T / (W - 1)`` with ``mu`` the weighted mean and
    ``W = sum m`` (all ones by default).  Two passes, element-wise sums in pixel order, not BLAS, so the
    result does not depend on the thread count; compiled when Numba is on."""
    zz = np.ascontiguousarray(z, dtype=np.float64).reshape(-1, z.shape[-1])
    m = np.ones(zz.shape[0]) if weights is None else np.ascontiguousarray(weights, dtype=np.float64).ravel()
    W = float(m.sum())
    if numba_enabled():
        C = np.zeros((zz.shape[1], zz.shape[1]))
        _weighted_cov(zz, m, W, C)
        return C
    zc = zz - np.einsum("n,ni->i", m, zz) / W
    return np.einsum("ni,nj->ij", zc * m[:, None], zc) / (W - 1.0)


@njit
def _weighted_cov(z, m, W, C):
    n, d = z.shape
    mu = np.zeros(d)
    for k in range(n):
        for i in range(d):
            mu[i] += m[k] * z[k, i]
    for i in range(d):
        mu[i] /= W
    for k in range(n):
        for i in range(d):
            a = m[k] * (z[k, i] - mu[i])
            for j in range(i, d):
                C[i, j] += a * (z[k, j] - mu[j])
    for i in range(d):
        for j in range(i, d):
            C[i, j] /= W - 1.0
            C[j, i] = C[i, j]


@njit
def _fill_channels(zc, m, iu, ju, chans):
    h, w, d = zc.shape
    for y in range(h):
        for x in range(w):
            mm = m[y, x]
            chans[y, x, 0] = mm
            for i in range(d):
                chans[y, x, 1 + i] = zc[y, x, i] * mm
            for k in range(iu.shape[0]):
                chans[y, x, 1 + d + k] = zc[y, x, iu[k]] * zc[y, x, ju[k]] * mm


class IntegralCovariance:
    """Covariances of many rectangular windows from integral images (Tuzel et al. 2006).

    Holds cumulative sums of ``m``, ``m z_i`` and ``m z_i z_j`` (``i <= j``) over a feature
    image ``z`` (``(H, W, d)``) whose pixel ``(0, 0)`` is at integer frame position ``origin``;
    ``m`` is a soft weight or a 0/1 mask (all ones by default).  Each channel is centred by its
    image mean first, which limits float64 cancellation (ch06.md P12); covariances do not
    depend on the centring.
    """

    def __init__(self, z: np.ndarray, weights: np.ndarray | None = None, origin: tuple[int, int] = (0, 0)):
        h, w, d = z.shape
        self.shape = (h, w)
        self.d = d
        self.origin = (int(origin[0]), int(origin[1]))
        zc = z - z.reshape(-1, d).mean(axis=0)
        iu, ju = np.triu_indices(d)
        self._iu, self._ju = iu, ju
        m = np.ones((h, w)) if weights is None else np.asarray(weights, dtype=np.float64)
        chans = np.empty((h, w, 1 + d + iu.size))
        if numba_enabled():  # the same products, without NumPy's strided gathers (~20x faster)
            _fill_channels(np.ascontiguousarray(zc, dtype=np.float64), np.ascontiguousarray(m), iu, ju, chans)
        else:
            chans[..., 0] = m
            chans[..., 1:1 + d] = zc * m[..., None]
            chans[..., 1 + d:] = zc[..., iu] * zc[..., ju] * m[..., None]
        if chans.shape[-1] <= 512:  # OpenCV's channel limit; its integral is ~5x faster than two cumsums
            table = cv2.integral(chans, sdepth=cv2.CV_64F)
            self._table = table.reshape(h + 1, w + 1, -1)
        else:
            table = np.zeros((h + 1, w + 1, chans.shape[-1]))
            np.cumsum(chans, axis=0, out=table[1:, 1:])
            np.cumsum(table[1:, 1:], axis=1, out=table[1:, 1:])
            self._table = table

    def sums(self, boxes: np.ndarray) -> np.ndarray:
        """``(K, C)`` sums of every channel over windows ``(x0, y0, x1, y1)`` (frame integers,
        ``x1``/``y1`` exclusive, clipped to the image)."""
        b = np.asarray(boxes, dtype=np.int64).reshape(-1, 4)
        ox, oy = self.origin
        h, w = self.shape
        x0 = np.clip(b[:, 0] - ox, 0, w)
        x1 = np.clip(b[:, 2] - ox, 0, w)
        y0 = np.clip(b[:, 1] - oy, 0, h)
        y1 = np.clip(b[:, 3] - oy, 0, h)
        t = self._table
        return t[y1, x1] - t[y0, x1] - t[y1, x0] + t[y0, x0]

    def cov(self, boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(C (K, d, d), W (K,))``: Eq. 27 for each window and its total weight (``W - 1`` is the
        denominator; windows with ``W <= 1`` get NaN)."""
        s = self.sums(boxes)
        d = self.d
        W = s[:, 0]
        S = s[:, 1:1 + d]
        Q = np.empty((s.shape[0], d, d))
        Q[:, self._iu, self._ju] = s[:, 1 + d:]
        Q[:, self._ju, self._iu] = s[:, 1 + d:]
        with np.errstate(divide="ignore", invalid="ignore"):
            C = (Q - S[:, :, None] * S[:, None, :] / W[:, None, None]) / (W - 1.0)[:, None, None]
        C[W <= 1.0] = np.nan
        return C, W


# -- SPD matrix functions (Eqs. 24-31) -----------------------------------------------------------
def _apply(C: np.ndarray, fn) -> np.ndarray:
    lam, U = np.linalg.eigh(C)
    return (U * fn(lam)[..., None, :]) @ np.swapaxes(U, -1, -2)


def spd_log(C: np.ndarray, *, floor: float = 1e-12) -> np.ndarray:
    """Matrix logarithm of symmetric positive-definite matrices ``(..., d, d)`` (Eqs. 24-26):
    ``U diag(ln lambda) U^T``, eigenvalues floored at ``floor``."""
    return _apply(np.asarray(C, dtype=np.float64), lambda lam: np.log(np.maximum(lam, floor)))


def spd_exp(A: np.ndarray) -> np.ndarray:
    """Matrix exponential of symmetric matrices (Eq. 26): ``U diag(exp d) U^T``."""
    return _apply(np.asarray(A, dtype=np.float64), np.exp)


def le_distance(L1: np.ndarray, L2: np.ndarray) -> np.ndarray:
    """Eq. 30: ``||log C1 - log C2||_F`` from precomputed logarithms (broadcast over leading axes)."""
    diff = np.asarray(L1) - np.asarray(L2)
    return np.sqrt(np.sum(diff * diff, axis=(-2, -1)))


def le_mean(Cs: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Eq. 31 (restored): the weighted Log-Euclidean mean ``exp(sum_i w_i log C_i)``, ``sum w = 1``.

    Compiled (one pass: an eigen-decomposition per matrix, the weighted sum of the logarithms, one more
    for the exponential) when Numba is on; equal to the NumPy form to rounding."""
    Cs = np.asarray(Cs, dtype=np.float64)
    w = np.full(Cs.shape[0], 1.0 / Cs.shape[0]) if weights is None else np.asarray(weights, dtype=np.float64)
    w = w / w.sum()
    if numba_enabled() and Cs.ndim == 3:
        return _le_mean(np.ascontiguousarray(Cs), w)
    return spd_exp(np.tensordot(w, spd_log(Cs), axes=1))


@njit(cache=True)
def _le_mean(Cs, w):
    n, d, _ = Cs.shape
    acc = np.zeros((d, d))
    for k in range(n):
        lam, U = np.linalg.eigh(Cs[k])
        acc += w[k] * ((U * np.log(np.maximum(lam, 1e-12))) @ U.T)
    lam, U = np.linalg.eigh(acc)
    return (U * np.exp(lam)) @ U.T


def airm_distance(C1: np.ndarray, C2: np.ndarray) -> float:
    """Eqs. 28-29: ``sqrt(sum_i ln^2 lambda_i)`` with ``lambda_i`` the generalised eigenvalues of
    ``lambda C1 x = C2 x`` (Förstner & Moonen 1999); affine-invariant."""
    from scipy.linalg import eigh

    lam = eigh(np.asarray(C2, dtype=np.float64), np.asarray(C1, dtype=np.float64), eigvals_only=True)
    return float(np.sqrt(np.sum(np.log(lam) ** 2)))


def airm_mean(Cs: np.ndarray, weights: np.ndarray | None = None, *, tol: float = 1e-8,
              max_iter: int = 50) -> np.ndarray:
    """The affine-invariant (Karcher) mean, by the fixed-point iteration of Pennec et al. (2006):
    ``M <- M^1/2 exp(sum w_i log(M^-1/2 C_i M^-1/2)) M^1/2``, started from the Log-Euclidean
    mean.  This is the mean of Porikli et al.'s model update that Eq. 31 replaces (claim C6.3)."""
    Cs = np.asarray(Cs, dtype=np.float64)
    w = np.full(Cs.shape[0], 1.0 / Cs.shape[0]) if weights is None else np.asarray(weights, dtype=np.float64)
    w = w / w.sum()
    M = le_mean(Cs, w)
    for _ in range(max_iter):
        lam, U = np.linalg.eigh(M)
        half = (U * np.sqrt(lam)) @ U.T
        ihalf = (U / np.sqrt(lam)) @ U.T
        T = np.tensordot(w, spd_log(ihalf @ Cs @ ihalf), axes=1)
        M = half @ spd_exp(T) @ half
        if np.linalg.norm(T) < tol:
            break
    return M


class SPDModel:
    """A covariance model to which windows are compared: Eq. 30 (``metric="le"``, the chapter's)
    or Eq. 28 (``"airm"``, Porikli et al.'s) against a fixed matrix, batched over windows.

    For the affine-invariant metric the model is whitened once, ``W = M^(-1/2)``, and
    ``d(M, C) = ||log(W C W)||_F`` costs one symmetric eigen-decomposition per window, like Eq. 30.
    """

    def __init__(self, C: np.ndarray, metric: str = "le"):
        if metric not in ("le", "airm"):
            raise ValueError(f"unknown SPD metric {metric!r}; expected 'le' or 'airm'")
        self.metric = metric
        self.C = np.asarray(C, dtype=np.float64)
        if metric == "le":
            self.L = spd_log(self.C)
        else:
            lam, U = np.linalg.eigh(self.C)
            self.W = (U / np.sqrt(lam)) @ U.T

    @classmethod
    def from_log(cls, L: np.ndarray) -> "SPDModel":
        """A Log-Euclidean model from its logarithm (e.g. the mean of logs, Eq. 31 before exp)."""
        m = cls.__new__(cls)
        m.metric, m.L = "le", np.asarray(L, dtype=np.float64)
        m.C = spd_exp(m.L)
        return m

    def distance(self, Cs: np.ndarray) -> np.ndarray:
        """``(K,)`` distances of ``(K, d, d)`` SPD matrices to the model."""
        if self.metric == "le":
            return le_distance(spd_log(Cs), self.L)
        lam = np.linalg.eigvalsh(self.W @ Cs @ self.W)
        return np.sqrt(np.sum(np.log(np.maximum(lam, 1e-300)) ** 2, axis=-1))
