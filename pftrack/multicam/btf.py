"""Brightness transfer functions between two cameras (book ch. 11, Sect. 3 and 5).

A BTF maps a brightness of camera 1 to the brightness the same surface has in camera 2.
Under the equal-percentile assumption (Eq. 11) it follows from the two normalised
cumulative histograms: ``f₁₂(B) = H₂⁻¹(H₁(B))`` (Eq. 12), per RGB channel, 256 bins.

* :func:`btf_from_hists` — one BTF from a histogram pair (Eq. 12, Eq. 20);
* :func:`mbtf` — the mean of the per-pair BTFs of known correspondences (Eq. 21; the text
  prints a plain sum, restored as the mean of Prosser et al. 2008);
* :func:`cbtf` — the BTF of the histograms accumulated over all training images of each
  camera (Eq. 22, Prosser et al.);
* :func:`apply_btf_hist` — the push-forward of a histogram through a BTF (what the text
  writes ``f(H)``), equal to histogramming the mapped pixels; :func:`apply_btf_image`.

The generalised inverse ``H⁻¹(y) = min{v : H(v) ≥ y}`` makes the recovery exact: for any
monotone f, ``H₂⁻¹(H₁(b)) = f(b)`` on every occupied bin b (ch11.md §1.3; tested).
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["apply_btf_hist", "apply_btf_image", "btf_from_hists", "cbtf", "cum_hist", "identity_btf",
           "inv_cum_hist", "mbtf"]


def identity_btf(channels: int = 3) -> np.ndarray:
    return np.tile(np.arange(256, dtype=np.float64), (channels, 1))


def cum_hist(h: np.ndarray) -> np.ndarray:
    """Normalised cumulative histogram(s) along the last axis."""
    h = np.asarray(h, dtype=np.float64)
    c = np.cumsum(h, axis=-1)
    return c / np.maximum(c[..., -1:], 1e-300)


def inv_cum_hist(H: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``min{v : H(v) ≥ y}`` for a 1-D cumulative histogram (a small tolerance absorbs float sums)."""
    return np.clip(np.searchsorted(H, np.asarray(y) - 1e-12, side="left"), 0, len(H) - 1)


def btf_from_hists(h_src: np.ndarray, h_dst: np.ndarray) -> np.ndarray:
    """Eq. 12 per channel: ``(C, 256)`` source and destination histograms → ``(C, 256)`` lookup tables."""
    hs, hd = np.atleast_2d(h_src), np.atleast_2d(h_dst)
    Hs, Hd = cum_hist(hs), cum_hist(hd)
    return np.stack([inv_cum_hist(Hd[c], Hs[c]) for c in range(len(hs))]).astype(np.float64)


def mbtf(src_hists, dst_hists, pairs) -> np.ndarray:
    """Mean BTF over the training pairs ``[(i, j), …]`` of source / destination histograms (Eq. 21)."""
    luts = [btf_from_hists(src_hists[i], dst_hists[j]) for i, j in pairs]
    if not luts:
        raise ValueError("MBTF needs at least one training pair")
    return np.mean(luts, axis=0)


def cbtf(src_hists, dst_hists, *, weight: str = "pixels") -> np.ndarray:
    """BTF of the accumulated histograms of each camera's training images (Eq. 22).

    ``weight="pixels"`` accumulates raw counts (ch11.md's restoration, as Prosser et al.): large and long-seen
    training objects weigh more. ``"people"`` scales each training histogram to unit mass per channel first,
    so every training object weighs the same (pftrack's variant; the default of the hand-over, docs/handover.md).
    """
    src = np.asarray(src_hists, dtype=np.float64)
    dst = np.asarray(dst_hists, dtype=np.float64)
    if weight == "people":
        src = src / np.maximum(src.sum(axis=-1, keepdims=True), 1e-12)
        dst = dst / np.maximum(dst.sum(axis=-1, keepdims=True), 1e-12)
    elif weight != "pixels":
        raise ValueError("CBTF weight must be 'pixels' or 'people'")
    return btf_from_hists(src.sum(axis=0), dst.sum(axis=0))


def apply_btf_hist(h: np.ndarray, lut: np.ndarray) -> np.ndarray:
    """Push a ``(..., C, 256)`` histogram through ``(C, 256)`` tables: mass at v moves to round(f(v))."""
    h = np.asarray(h, dtype=np.float64)
    idx = np.clip(np.round(lut), 0, 255).astype(np.int64)
    out = np.zeros_like(h)
    for c in range(idx.shape[0]):
        flat = h[..., c, :].reshape(-1, 256)
        moved = np.stack([np.bincount(idx[c], weights=row, minlength=256) for row in flat])
        out[..., c, :] = moved.reshape(h[..., c, :].shape)
    return out


def apply_btf_image(img: np.ndarray, lut: np.ndarray) -> np.ndarray:
    """Map a BGR image's channels through RGB tables ``(3, 256)`` (``cv2.LUT`` per channel)."""
    tables = np.clip(np.round(lut), 0, 255).astype(np.uint8)
    b, g, r = cv2.split(img)
    return cv2.merge([cv2.LUT(b, tables[2]), cv2.LUT(g, tables[1]), cv2.LUT(r, tables[0])])


# -- BTF subspace (Javed et al. 2005; ch11.md §1.2 "restored, optional": the chapter mentions it, L9674-9676) --


def fit_btf_subspace(luts: np.ndarray, q: int | None = None) -> dict:
    """Probabilistic PCA of per-pair BTFs ``luts`` (n, 3, 256): the BTFs of one camera pair lie near a
    low-dimensional subspace.  ``q`` principal directions (default ``min(n - 1, 5)``), the rest isotropic noise
    ``sigma^2`` (the mean of the discarded eigenvalues, floored).  Returns ``mean, W, sigma2, d``."""
    F = np.asarray(luts, np.float64).reshape(len(luts), -1)
    n, d = F.shape
    mean = F.mean(0)
    if n < 2:
        return {"mean": mean, "W": np.zeros((d, 0)), "sigma2": 25.0, "d": d}
    q = min(n - 1, 5) if q is None else int(q)
    X = (F - mean) / np.sqrt(n - 1)
    _, s, Vt = np.linalg.svd(X, full_matrices=False)
    ev = s ** 2
    rest = ev[q:]
    sigma2 = float(max(rest.sum() / max(d - q, 1), 1.0))       # floor: 1 grey level^2 per bin
    W = Vt[:q].T * np.sqrt(np.maximum(ev[:q] - sigma2, 0.0))
    return {"mean": mean, "W": W, "sigma2": sigma2, "d": d}


def btf_subspace_loglik(model: dict, lut: np.ndarray) -> float:
    """``log p(f)`` under the PPCA model, ``p(f) = N(mean, W W^T + sigma^2 I)`` (ch11.md §1.2), per dimension,
    computed through the Woodbury identity (no d x d matrix)."""
    f = np.asarray(lut, np.float64).ravel() - model["mean"]
    W, s2, d = model["W"], model["sigma2"], model["d"]
    q = W.shape[1]
    M = np.eye(q) * s2 + W.T @ W                      # q x q
    Wf = W.T @ f
    quad = (f @ f - Wf @ np.linalg.solve(M, Wf)) / s2
    logdet = (d - q) * np.log(s2) + np.linalg.slogdet(M)[1]
    return float(-0.5 * (quad + logdet + d * np.log(2 * np.pi)) / d)
