"""Template matching with the six criteria of book ch. 14 (and the score maps the trackers search).

Book *Object Tracking*, ch. 14 (``shared/seeds/002_*`` lines 11974-12674; ``shared/book/ch14.md``),
equations restored from Gonzalez & Wintz and Maragos (ch14.md §1.4).  ``R`` is the m x n
template, ``S_kl`` the window of the search image at offset ``(k, l)``:

* **(3) SSD** ``sum (R - S_kl)^2`` (minimise) — ``cv2.TM_SQDIFF``;
* **(4) correlation** ``sum R S_kl`` (maximise) — ``cv2.TM_CCORR``;
* **(5) normalised correlation** (Pearson, maximise) — ``cv2.TM_CCOEFF_NORMED``;
* **(6) SAD** ``sum |R - S_kl|`` (minimise) — compiled kernel;
* **(7) morphological correlation** ``sum min(R, S_kl)`` (maximise), and its normalised form
  ``2 sum min / (sum R + sum S_kl) = 1 - SAD / (sum R + sum S_kl)`` — compiled kernel;
* **(9) mutual information** ``E(R) + E(S_kl) - E(R, S_kl)`` on ``bins`` grey levels (maximise),
  and the normalised ``(E(R) + E(S))/E(R, S)`` — compiled kernel.

:func:`match_surface` returns the score map over every offset with the sign made uniform
(**higher is better** for every method: SSD and SAD are negated), so callers never get the
direction wrong.  :func:`best_offset` finds the peak, refines it to sub-pixel precision with a
parabola through its neighbours and says whether it sits on the border of the search window
(the chapter's main failure cause: a search area that is too small).  :func:`peak_to_sidelobe`
measures the peak's sharpness.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

import cv2
import numpy as np

from .._numba import njit, numba_enabled
from ..geometry import parabola_peak

METHODS = ("ssd", "ccorr", "ncc", "ncc_uncentred", "sad", "morph", "morph_normed", "mi", "nmi")
_OPENCV = {"ssd": cv2.TM_SQDIFF, "ccorr": cv2.TM_CCORR, "ncc": cv2.TM_CCOEFF_NORMED,
           "ncc_uncentred": cv2.TM_CCORR_NORMED}


# ------------------------------------------------------------------------------ compiled kernels

@njit
def _sad_morph(search, tmpl, out, normed, morph):
    hs, ws = search.shape
    m, n = tmpl.shape
    rsum = 0.0
    for i in range(m):
        for j in range(n):
            rsum += tmpl[i, j]
    for k in range(hs - m + 1):
        for l in range(ws - n + 1):
            acc = 0.0
            ssum = 0.0
            for i in range(m):
                for j in range(n):
                    a = tmpl[i, j]
                    b = search[k + i, l + j]
                    if morph:
                        acc += a if a < b else b
                    else:
                        acc += abs(a - b)
                    ssum += b
            if morph and normed:
                den = rsum + ssum
                out[k, l] = 2.0 * acc / den if den > 0 else 0.0
            else:
                out[k, l] = acc
    return out


@njit
def _mutual_information(sq, tq, bins, out, normalised):
    """MI (9) of the quantised template ``tq`` with every window of the quantised search image ``sq``.

    Entropies from counts: ``E = log T - (1/T) sum c log c`` with ``c log c`` tabulated for every
    count up to ``T = m n``, so the inner loops do no logarithms.
    """
    hs, ws = sq.shape
    m, n = tq.shape
    total = m * n
    clog = np.zeros(total + 1)
    for c in range(1, total + 1):
        clog[c] = c * math.log(c)
    logt = math.log(total)
    pr = np.zeros(bins, np.int64)
    for i in range(m):
        for j in range(n):
            pr[tq[i, j]] += 1
    sr = 0.0
    for b in range(bins):
        sr += clog[pr[b]]
    er = logt - sr / total
    for k in range(hs - m + 1):
        joint = np.zeros((bins, bins), np.int64)
        ps = np.zeros(bins, np.int64)
        for l in range(ws - n + 1):
            for i in range(m):
                for j in range(n):
                    joint[tq[i, j], sq[k + i, l + j]] += 1
                    ps[sq[k + i, l + j]] += 1
            ss = 0.0
            for b in range(bins):
                ss += clog[ps[b]]
                ps[b] = 0
            sj = 0.0
            for i in range(m):  # visit (and clear) only the cells this window filled
                for j in range(n):
                    a = tq[i, j]
                    b = sq[k + i, l + j]
                    c = joint[a, b]
                    if c > 0:
                        sj += clog[c]
                        joint[a, b] = 0
            es = logt - ss / total
            ej = logt - sj / total
            if normalised:
                out[k, l] = (er + es) / ej if ej > 0 else 2.0
            else:
                out[k, l] = er + es - ej
    return out


def quantize_levels(img: np.ndarray, bins: int, lo: float = 0.0, hi: float = 256.0) -> np.ndarray:
    """Grey levels to ``bins`` equal bins over ``[lo, hi)`` (the fixed binning of the MI criterion)."""
    q = np.floor((np.asarray(img, dtype=np.float64) - lo) * (bins / (hi - lo))).astype(np.int64)
    return np.clip(q, 0, bins - 1)


# ------------------------------------------------------------------------------ reference (tests, no Numba)

def match_surface_reference(search: np.ndarray, template: np.ndarray, method: str, *, bins: int = 32) -> np.ndarray:
    """Direct double loop over offsets of the ch. 14 definitions (higher is better); the tests' oracle."""
    s = np.asarray(search, dtype=np.float64)
    r = np.asarray(template, dtype=np.float64)
    m, n = r.shape
    out = np.empty((s.shape[0] - m + 1, s.shape[1] - n + 1))
    rq = quantize_levels(r, bins)
    sq = quantize_levels(s, bins)

    def entropy(counts):
        p = counts[counts > 0] / counts.sum()
        return float(-(p * np.log(p)).sum())

    for k in range(out.shape[0]):
        for l in range(out.shape[1]):
            w = s[k:k + m, l:l + n]
            if method == "ssd":
                v = -np.sum((r - w) ** 2)
            elif method == "ccorr":
                v = np.sum(r * w)
            elif method == "ncc":
                a, b = r - r.mean(), w - w.mean()
                den = math.sqrt(np.sum(a * a) * np.sum(b * b))
                v = np.sum(a * b) / den if den > 0 else 0.0
            elif method == "ncc_uncentred":
                den = math.sqrt(np.sum(r * r) * np.sum(w * w))
                v = np.sum(r * w) / den if den > 0 else 0.0
            elif method == "sad":
                v = -np.sum(np.abs(r - w))
            elif method in ("morph", "morph_normed"):
                v = np.sum(np.minimum(r, w))
                if method == "morph_normed":
                    v = 2 * v / (r.sum() + w.sum()) if r.sum() + w.sum() > 0 else 0.0
            else:
                wq = sq[k:k + m, l:l + n]
                er = entropy(np.bincount(rq.ravel(), minlength=bins).astype(float))
                es = entropy(np.bincount(wq.ravel(), minlength=bins).astype(float))
                ej = entropy(np.bincount((rq * bins + wq).ravel(), minlength=bins * bins).astype(float))
                v = (er + es - ej) if method == "mi" else ((er + es) / ej if ej > 0 else 2.0)
            out[k, l] = v
    return out


# ------------------------------------------------------------------------------ public API

def match_surface(search: np.ndarray, template: np.ndarray, method: str = "ncc", *, bins: int = 32) -> np.ndarray:
    """Score of every offset of ``template`` inside ``search`` (both grey), higher is better.

    Shape ``(Hs - m + 1, Ws - n + 1)``.  OpenCV computes SSD, correlation and the normalised
    correlations; compiled kernels compute SAD, morphological correlation and mutual
    information (``bins`` equal grey-level bins over 0-255).
    """
    if method not in METHODS:
        raise ValueError(f"unknown matching criterion {method!r}; choose from {', '.join(METHODS)}")
    s = np.ascontiguousarray(search, dtype=np.float32)
    r = np.ascontiguousarray(template, dtype=np.float32)
    if s.shape[0] < r.shape[0] or s.shape[1] < r.shape[1]:
        raise ValueError(f"search window {s.shape} smaller than the template {r.shape}")
    if method in _OPENCV:
        out = cv2.matchTemplate(s, r, _OPENCV[method]).astype(np.float64)
        return -out if method == "ssd" else out
    if not numba_enabled():
        return match_surface_reference(search, template, method, bins=bins)
    out = np.empty((s.shape[0] - r.shape[0] + 1, s.shape[1] - r.shape[1] + 1))
    s64 = np.ascontiguousarray(search, dtype=np.float64)
    r64 = np.ascontiguousarray(template, dtype=np.float64)
    if method in ("sad", "morph", "morph_normed"):
        _sad_morph(s64, r64, out, method == "morph_normed", method != "sad")
        return -out if method == "sad" else out
    _mutual_information(quantize_levels(s64, bins), quantize_levels(r64, bins), int(bins), out, method == "nmi")
    return out


@dataclass(frozen=True)
class Peak:
    """The best offset of a score map."""

    k: float  # row offset (sub-pixel)
    l: float  # column offset (sub-pixel)
    value: float
    on_border: bool  # the integer peak lies on the border of the map: the search window may be too small
    psr: float  # peak-to-sidelobe ratio


def best_offset(surface: np.ndarray, *, exclude: int = 5) -> Peak:
    """Peak of a higher-is-better score map, refined by a parabola through its 4-neighbours."""
    s = np.asarray(surface, dtype=np.float64)
    k, l = np.unravel_index(int(np.argmax(s)), s.shape)
    h, w = s.shape
    dk = parabola_peak(s[k - 1, l], s[k, l], s[k + 1, l]) if 0 < k < h - 1 else 0.0
    dl = parabola_peak(s[k, l - 1], s[k, l], s[k, l + 1]) if 0 < l < w - 1 else 0.0
    border = (k == 0 or l == 0 or k == h - 1 or l == w - 1) and (h > 1 and w > 1)
    return Peak(k + dk, l + dl, float(s[k, l]), bool(border), peak_to_sidelobe(s, (int(k), int(l)), exclude=exclude))


def peak_to_sidelobe(surface: np.ndarray, peak: tuple[int, int] | None = None, *, exclude: int = 5) -> float:
    """``(peak - mean(sidelobe)) / std(sidelobe)``; the sidelobe excludes a ``(2 exclude + 1)^2`` box.

    Invariant to an affine rescaling of the scores, so it compares criteria fairly (ch14.md §4.1).
    """
    s = np.asarray(surface, dtype=np.float64)
    if peak is None:
        peak = np.unravel_index(int(np.argmax(s)), s.shape)
    k, l = peak
    mask = np.ones(s.shape, dtype=bool)
    mask[max(k - exclude, 0):k + exclude + 1, max(l - exclude, 0):l + exclude + 1] = False
    side = s[mask]
    if side.size < 2:
        return 0.0
    sd = float(side.std())
    return float((s[k, l] - side.mean()) / sd) if sd > 0 else float("inf")


def batch_scores(patches: np.ndarray, template: np.ndarray, method: str = "ncc") -> np.ndarray:
    """Score of each of ``N`` patches ``(N, m, n)`` against the template (higher is better), vectorised.

    For the particle filters: the patches come from :func:`pftrack.cues.ssim.sample_patches`.
    Criteria: ``ncc``, ``ncc_uncentred``, ``ssd``, ``sad``, ``morph``, ``morph_normed``, ``ccorr``.
    """
    p = np.asarray(patches, dtype=np.float64).reshape(len(patches), -1)
    r = np.asarray(template, dtype=np.float64).ravel()
    if method == "ncc":
        a = p - p.mean(axis=1, keepdims=True)
        b = r - r.mean()
        den = np.sqrt((a * a).sum(axis=1) * (b @ b))
        return np.where(den > 0, (a @ b) / np.where(den > 0, den, 1.0), 0.0)
    if method == "ncc_uncentred":
        den = np.sqrt((p * p).sum(axis=1) * (r @ r))
        return np.where(den > 0, (p @ r) / np.where(den > 0, den, 1.0), 0.0)
    if method == "ssd":
        return -((p - r) ** 2).sum(axis=1)
    if method == "sad":
        return -np.abs(p - r).sum(axis=1)
    if method == "ccorr":
        return p @ r
    if method in ("morph", "morph_normed"):
        v = np.minimum(p, r).sum(axis=1)
        if method == "morph":
            return v
        den = r.sum() + p.sum(axis=1)
        return np.where(den > 0, 2 * v / np.where(den > 0, den, 1.0), 0.0)
    raise ValueError(f"batch scores are not available for {method!r}")


def patch_shift(prev_gray: np.ndarray, gray: np.ndarray, box, radius: int, *, min_score: float = 0.5
                ) -> np.ndarray | None:
    """How far the content of ``box`` (x, y, w, h on ``gray``) moved since ``prev_gray``: ``(dx, dy)``, the
    in-frame part of the box found again (normalised correlation, Eq. 5, sub-pixel peak) within ``radius`` px in
    the previous frame.  ``None`` when the part is flat or smaller than 4 x 4 px, or the peak is below
    ``min_score``."""
    h, w = gray.shape[:2]
    bx, by, bw, bh = (float(v) for v in box)
    x0, y0 = max(int(round(bx)), 0), max(int(round(by)), 0)
    x1, y1 = min(int(round(bx + bw)), w), min(int(round(by + bh)), h)
    if x1 - x0 < 4 or y1 - y0 < 4:
        return None
    tmpl = gray[y0:y1, x0:x1].astype(np.float32)
    if float(tmpl.std()) < 2.0:
        return None
    r = int(radius)
    sx0, sy0 = max(x0 - r, 0), max(y0 - r, 0)
    area = prev_gray[sy0:min(y1 + r, h), sx0:min(x1 + r, w)].astype(np.float32)
    score = cv2.matchTemplate(area, tmpl, cv2.TM_CCOEFF_NORMED)
    peak = best_offset(score)
    if peak.value < min_score:
        return None
    return np.array([x0 - (sx0 + peak.l), y0 - (sy0 + peak.k)])


def trace_back(earlier_grays: Iterable[np.ndarray], gray: np.ndarray, box, core, radius: int, *,
               min_score: float = 0.5) -> Iterator[np.ndarray | None]:
    """``box`` (x, y, w, h on ``gray``) followed back through ``earlier_grays`` (newest first) by its part ``core``
    (a box, usually its central part, mostly the object rather than the still scene around it): on each earlier
    frame, the box moved by :func:`patch_shift` of the core. Yields the box on each earlier frame in turn, or
    ``None`` once the trace is lost (a flat core, no match), and then stops; lazily, so a caller that has its
    answer stops the searches."""
    box = np.array(box, dtype=np.float64)
    core = np.array(core, dtype=np.float64)
    cur = gray
    for prev in earlier_grays:
        d = patch_shift(prev, cur, core, radius, min_score=min_score)
        if d is None:
            yield None
            return
        box[:2] -= d
        core[:2] -= d
        cur = prev
        yield box.copy()
