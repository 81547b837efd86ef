"""Per-pixel colour and texture features and online real AdaBoost (book ch. 3, §3.1–3.2).

Features (ch03.md §1.1): 4 colour channels (R, G, B and grey Y, each quantised into
``colour_blocks`` equal-width blocks) and 9 cross-channel local ternary patterns (LTP_{8,1},
Tan & Triggs 2010, restored): for the channel pair (centre c, neighbour n), with
``x = g_u − g_c``, the upper code sets bit u where ``x ≥ t`` and the lower code where
``x ≤ −t``; neighbours u = 0…7 run clockwise from the right-hand one.  Each code is mapped
to its rotation-invariant uniform class (``riu2``: the number of set bits if the code has at
most two circular 0/1 transitions, else 9), and the feature value is the block
``10·riu2(U) + riu2(L)`` ∈ [0, 100) (a design choice, ch03.md §1.1).

Online real AdaBoost (Algorithm 1, restored as in Oza & Russell 2001 and Grabner & Bischof
2006): ``N`` selectors, each holding one weak learner per feature (a per-block log-odds
table); a labelled pixel updates every selector in turn with importance λ, the selector
keeps its least erroneous learner (voting weight ``α = ln((1 − e)/e)``), λ is divided by
``2(1 − e)`` or ``2e``.  The worst learner of each selector is reset once per ``update`` call
(a frame's samples; ``replace="sample"`` is the text's per-sample rule, ch03.md §1.2).
``confidence(x) = Σ α_n h_n(x)``.
"""

from __future__ import annotations

import cv2
import numpy as np

from .._numba import njit

__all__ = ["LTP_PAIRS", "OnlineRealBoost", "colour_features", "ltp_codes", "ltp_features", "pixel_features",
           "riu2_table"]

#: (centre channel, neighbour channel) of the nine LTP features, RGB indices (L2119–2121)
LTP_PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1))
#: the 8 neighbours, clockwise from the right-hand one (row, column offsets)
_NEIGHBOURS = ((0, 1), (1, 1), (1, 0), (1, -1), (0, -1), (-1, -1), (-1, 0), (-1, 1))


def riu2_table() -> np.ndarray:
    """``(256,)`` rotation-invariant uniform class (0…9) of every 8-bit code."""
    out = np.zeros(256, dtype=np.int64)
    for code in range(256):
        bits = [(code >> u) & 1 for u in range(8)]
        transitions = sum(bits[u] != bits[(u + 1) % 8] for u in range(8))
        out[code] = sum(bits) if transitions <= 2 else 9
    return out


_RIU2 = riu2_table()


def ltp_codes(centre: np.ndarray, neighbour: np.ndarray, t: float, radius: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Upper and lower LTP codes (uint8) of every pixel; borders use replicated pixels.

    ``radius`` r > 1 takes the 8 neighbours on the square ring at distance r (the grey-input set)."""
    c = centre.astype(np.int32)
    r = int(radius)
    n = cv2.copyMakeBorder(neighbour.astype(np.int32), r, r, r, r, cv2.BORDER_REPLICATE)
    h, w = c.shape
    up = np.zeros((h, w), np.int32)
    lo = np.zeros((h, w), np.int32)
    for u, (dy, dx) in enumerate(_NEIGHBOURS):
        x = n[r + r * dy:r + r * dy + h, r + r * dx:r + r * dx + w] - c
        up |= (x >= t).astype(np.int32) << u
        lo |= (x <= -t).astype(np.int32) << u
    return up.astype(np.uint8), lo.astype(np.uint8)


_NY = np.array([dy for dy, _ in _NEIGHBOURS], dtype=np.int64)
_NX = np.array([dx for _, dx in _NEIGHBOURS], dtype=np.int64)


@njit
def _ltp_features(img, ci, ni, radius, thr, riu2, out):
    """``out[y, x, k] = 10 riu2(up_k) + riu2(lo_k)``: the LTP codes of :func:`ltp_codes` with centre channel
    ``ci[k]``, neighbour channel ``ni[k]``, ring ``radius[k]`` and threshold ``thr[k]`` of ``img`` (H, W, C),
    replicated borders, for every feature ``k`` in one pass."""
    h, w = img.shape[0], img.shape[1]
    for y in range(h):
        for x in range(w):
            for k in range(ci.shape[0]):
                r = radius[k]
                c = np.int32(img[y, x, ci[k]])
                up = 0
                lo = 0
                for u in range(8):
                    yy = min(max(y + r * _NY[u], 0), h - 1)
                    xx = min(max(x + r * _NX[u], 0), w - 1)
                    d = np.int32(img[yy, xx, ni[k]]) - c
                    if d >= thr[k]:
                        up |= 1 << u
                    if d <= -thr[k]:
                        lo |= 1 << u
                out[y, x, k] = 10 * riu2[up] + riu2[lo]
    return out


def ltp_features(img: np.ndarray, pairs, *, t: float | np.ndarray, radius: int | np.ndarray = 1) -> np.ndarray:
    """``(H, W, K)`` texture blocks ``10 riu2(up) + riu2(lo)`` of the LTP codes of K (centre, neighbour)
    channel pairs of ``img`` (H, W) or (H, W, C) — the same numbers as :func:`ltp_codes` pair by pair.
    ``t`` and ``radius`` are scalars or one per pair."""
    a = np.ascontiguousarray(img if img.ndim == 3 else img[..., None])
    pr = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    k = len(pr)
    thr = np.broadcast_to(np.asarray(t, dtype=np.float64), (k,)).copy()
    rad = np.broadcast_to(np.asarray(radius, dtype=np.int64), (k,)).copy()
    out = np.empty(a.shape[:2] + (k,), dtype=np.int64)
    return _ltp_features(a, np.ascontiguousarray(pr[:, 0]), np.ascontiguousarray(pr[:, 1]), rad, thr, _RIU2, out)


def colour_features(bgr: np.ndarray, blocks: int = 32) -> np.ndarray:
    """``(H, W, 4)`` block indices of R, G, B and grey Y."""
    rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
    y = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)
    chans = np.dstack([rgb, y[..., None]]).astype(np.int64)
    return np.minimum(chans * blocks // 256, blocks - 1)


#: grey input: (radius, multiple of t) of the nine texture features, in place of the nine channel pairs
GREY_LTP = ((1, 0.5), (1, 1.0), (1, 2.0), (2, 0.5), (2, 1.0), (2, 2.0), (3, 0.5), (3, 1.0), (3, 2.0))


def grey_texture(gray: np.ndarray, *, t: float = 5.0) -> np.ndarray:
    """``(H, W, 9)`` LTP blocks of one channel at radii 1, 2, 3 and thresholds t/2, t, 2t."""
    return ltp_features(gray, [(0, 0)] * len(GREY_LTP), t=np.array([tm * t for _, tm in GREY_LTP]),
                        radius=np.array([r for r, _ in GREY_LTP]))


def grey_features(gray: np.ndarray, *, t: float = 5.0, blocks: int = 32) -> tuple[np.ndarray, np.ndarray]:
    """The two groups for grey input, where the chapter's cross-channel set collapses (R = G = B = Y, and
    the nine channel pairs give one code nine times).

    Intensity group (4): Y, Y smoothed over 3x3 and 7x7 windows, and the gradient magnitude (Sobel), each
    in ``blocks`` blocks, after dividing Y by its mean over the given region (times 128), so that a global
    gain change of the light leaves the blocks in place.  Texture group (9): LTP codes of Y at radii 1, 2, 3
    and thresholds t/2, t, 2t."""
    y = gray.astype(np.float32)
    y *= 128.0 / max(float(y.mean()), 1.0)
    gx = cv2.Sobel(y, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(y, cv2.CV_32F, 0, 1, ksize=3)
    mag = np.minimum(np.sqrt(gx * gx + gy * gy) / 4.0, 255.0)  # 3x3 Sobel: |g| <= 4 * 255 * sqrt(2)
    chans = np.dstack([y, cv2.blur(y, (3, 3)), cv2.blur(y, (7, 7)), mag]).astype(np.int64)
    col = np.minimum(np.clip(chans, 0, 255) * blocks // 256, blocks - 1)
    return col, grey_texture(gray, t=t)


def pixel_features(bgr: np.ndarray, *, t: float = 5.0, colour_blocks: int = 32,
                   gray: bool = False, texture: str = "pairs") -> tuple[np.ndarray, np.ndarray]:
    """Colour group ``(H, W, 4)`` and texture group ``(H, W, 9)`` block indices (ch03.md §1.1).

    ``gray=True`` (grey input) gives :func:`grey_features` instead: the same group sizes, with features
    that still differ from one another.  ``texture="radii"`` keeps the colour group and takes the texture
    group of :func:`grey_texture` on Y (multi-radius LTP) instead of the nine channel pairs."""
    if gray:
        return grey_features(cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY) if bgr.ndim == 3 else bgr, t=t,
                             blocks=colour_blocks)
    if texture == "radii":
        return colour_features(bgr, colour_blocks), grey_texture(cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY), t=t)
    rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
    return colour_features(bgr, colour_blocks), ltp_features(rgb, LTP_PAIRS, t=t)


@njit
def _update(w, corr, wrong, sel, alpha, x, y, eps, count_errors, replace):
    """Algorithm 1 for one sample ``x`` (M,) with label ``y`` ∈ {+1, −1}; ``w`` is (N, M, B, 2)."""
    n_sel, m_feat = w.shape[0], w.shape[1]
    yi = 0 if y > 0 else 1
    lam = 1.0
    for n in range(n_sel):
        best, worst = 0, 0
        e_best, e_worst = 2.0, -1.0
        for m in range(m_feat):
            b = x[m]
            w[n, m, b, yi] += lam
            h = 0.5 * np.log((w[n, m, b, 0] + eps) / (w[n, m, b, 1] + eps))
            inc = lam if count_errors else lam * abs(h)
            if h * y >= 0:
                corr[n, m] += inc
            else:
                wrong[n, m] += inc
            e = wrong[n, m] / (wrong[n, m] + corr[n, m])
            if e < e_best:
                e_best, best = e, m
            if e > e_worst:
                e_worst, worst = e, m
        sel[n] = best
        if e_best <= 0.0 or e_best > 0.5:
            # (the text: stop this sample here; earlier votes stay)
            break
        alpha[n] = np.log((1.0 - e_best) / e_best)
        b = x[best]
        h = 0.5 * np.log((w[n, best, b, 0] + eps) / (w[n, best, b, 1] + eps))
        if h * y >= 0:
            lam = lam / (2.0 * (1.0 - e_best))
        else:
            lam = lam / (2.0 * e_best)
        if replace and worst != best:  # replace the worst weak learner (L2248-2259, the literal rule)
            w[n, worst, :, :] = 0.0
            corr[n, worst] = 1.0
            wrong[n, worst] = 1.0


@njit
def _update_all(w, corr, wrong, sel, alpha, x, y, eps, count_errors, replace):
    """:func:`_update` for each row of ``x`` (S, M) in order, with its label in ``y`` (S,)."""
    for k in range(x.shape[0]):
        _update(w, corr, wrong, sel, alpha, x[k], y[k], eps, count_errors, replace)


class OnlineRealBoost:
    """Online real AdaBoost over ``n_features`` block-valued features (one feature group)."""

    def __init__(self, n_features: int, n_blocks: int, *, n_selectors: int = 30, eps: float = 0.01,
                 error_weighting: str = "confidence", replace: str = "update", forgetting: float = 1.0):
        if error_weighting not in ("confidence", "count"):
            raise ValueError("error_weighting must be 'confidence' or 'count'")
        if replace not in ("update", "sample"):
            raise ValueError("replace must be 'update' (once per update call, e.g. per frame) or 'sample'")
        self.replace = replace
        self.forgetting = float(forgetting)
        self.m, self.b = int(n_features), int(n_blocks)
        self.n = int(n_selectors)
        self.eps = float(eps)
        self.count_errors = error_weighting == "count"
        self.w = np.zeros((self.n, self.m, self.b, 2))
        self.corr = np.ones((self.n, self.m))
        self.wrong = np.ones((self.n, self.m))
        self.sel = np.zeros(self.n, dtype=np.int64)
        self.alpha = np.zeros(self.n)
        self._tables: np.ndarray | None = None  # cache of tables(), dropped whenever the learners change

    def update(self, x: np.ndarray, y) -> None:
        """Learn labelled samples in order: ``x`` ``(S, M)`` block indices, ``y`` ``(S,)`` in {+1, −1}."""
        x = np.atleast_2d(np.asarray(x, dtype=np.int64))
        y = np.broadcast_to(np.asarray(y, dtype=np.float64), (len(x),))
        if x.size and (x.min() < 0 or x.max() >= self.b):
            raise ValueError(f"block indices must lie in [0, {self.b})")
        per_sample = self.replace == "sample"
        self._tables = None
        if self.forgetting < 1.0 and len(x):  # beta of ch03.md P4: old block counts fade once per update call
            self.w *= self.forgetting
        _update_all(self.w, self.corr, self.wrong, self.sel, self.alpha, np.ascontiguousarray(x),
                    np.ascontiguousarray(y), self.eps, self.count_errors, per_sample)
        if not per_sample and len(x):
            self._replace_worst()

    def _replace_worst(self) -> None:
        """Reset each selector's most erroneous weak learner unless it is the selected one (once per
        update call: ch03.md's repair of the per-sample rule, which wipes a learner at every pixel)."""
        e = self.wrong / (self.wrong + self.corr)
        worst = np.argmax(e, axis=1)
        for n in range(self.n):
            if worst[n] != self.sel[n]:
                self.w[n, worst[n]] = 0.0
                self.corr[n, worst[n]] = 1.0
                self.wrong[n, worst[n]] = 1.0

    def tables(self) -> np.ndarray:
        """``(M, B)`` per-feature vote tables: ``T[m, b] = Σ_{n: sel_n = m} α_n h_{n,m}(b)``.

        The strong classifier's confidence is ``Σ_m T[m, x_m]``: M gathers per pixel instead of one per
        selector (selectors that share a feature are summed once).  Cached until the next ``update``."""
        if self._tables is not None:
            return self._tables
        t = np.zeros((self.m, self.b))
        for n in range(self.n):
            if self.alpha[n] == 0.0:
                continue
            m = self.sel[n]
            wn = self.w[n, m]
            t[m] += self.alpha[n] * 0.5 * np.log((wn[:, 0] + self.eps) / (wn[:, 1] + self.eps))
        self._tables = t
        return t

    def confidence(self, x: np.ndarray) -> np.ndarray:
        """``Σ_n α_n h_n(x)`` for ``(..., M)`` block indices (vectorised over pixels)."""
        x = np.asarray(x)
        t = self.tables()
        conf = np.zeros(x.shape[:-1])
        for m in np.flatnonzero(np.any(t != 0.0, axis=1)):
            conf += t[m][x[..., m]]
        return conf
