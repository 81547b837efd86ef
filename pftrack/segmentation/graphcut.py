"""Graph-cut segmentation of a tracked object (book ch. 9, ch09.md §1.2-1.4), as pure functions.

Energy ``E(A) = lam R(A) + B(A)`` (Eqs. 3-5) on the 8-connected pixel graph of a region of interest:

- regional t-links from object/background colour histograms, read as likelihoods (Eq. 6):
  ``H_hat_X(p) = H_X(bin(I_p)) / max H_X``; the object terminal gets ``lam H_hat_obj`` and the background
  terminal ``lam H_hat_bkg`` (ch09.md §1.2 fixes the orientation: the printed Table 2 read literally
  inverts the segmentation);
- temporal seeding (restored Table 3): ``w(p,s) = min(lam+1, lam H_hat_obj + lam D_obj)`` and
  ``w(p,t) = min(lam+1, lam H_hat_bkg + lam D_bkg)`` with ``D`` the distance transforms of the previous
  mask and of its complement, normalised by their maxima;
- n-links ``B_pq`` = ``exp(-|p-q|)`` (Eq. 8, RGB in [0, 1]), ``1 - |p-q|/3`` (Eq. 7), or Boykov-Jolly's
  ``exp(-beta |p-q|^2) / dist`` ("bj");
- hard background seeds (the ROI border and the pixels outside the dilated previous mask) carry
  ``K = 1 + max_p sum_q B_pq`` (Eq. 9), which no cut can afford.

The default max-flow backend is SciPy's (``scipy.sparse.csgraph.maximum_flow``, Dinic, BSD): integer
capacities (scaled by ``CAP_SCALE``), and the cut read from the residual graph by a breadth-first search
from the source.  PyMaxflow (Boykov-Kolmogorov, GPL) is used when asked for and installed.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import breadth_first_order, maximum_flow

OFFSETS = ((0, 1), (1, 0), (1, 1), (1, -1))     # the 4 forward offsets of the 8-neighbourhood
CAP_SCALE = 1000.0


def color_bins(img: np.ndarray, bins: int = 16) -> np.ndarray:
    """Index of each pixel's RGB bin (``bins`` per channel)."""
    q = (img.astype(np.int32) * bins) >> 8
    return (q[..., 0] * bins + q[..., 1]) * bins + q[..., 2]


def color_hist(bin_idx: np.ndarray, mask: np.ndarray, bins: int = 16) -> np.ndarray:
    h = np.bincount(bin_idx[mask].ravel(), minlength=bins ** 3).astype(np.float64)
    return h / max(h.sum(), 1.0)


def regional(bin_idx: np.ndarray, H_obj: np.ndarray, H_bkg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eq. (6): ``H_hat = H(bin) / max H`` for the object and the background, each in [0, 1]."""
    return (H_obj[bin_idx] / max(H_obj.max(), 1e-12), H_bkg[bin_idx] / max(H_bkg.max(), 1e-12))


def nlink_weights(img: np.ndarray, mode: str = "exp", diag_dist: bool = False) -> list[np.ndarray]:
    """``B_pq`` for each offset of :data:`OFFSETS`: an array over the pixels ``p`` whose neighbour
    ``q = p + offset`` is inside the image (shapes ``(h, w-1)``, ``(h-1, w)``, ``(h-1, w-1)``, ``(h-1, w-1)``)."""
    f = img.astype(np.float32) / 255.0
    diffs = [f[:, 1:] - f[:, :-1], f[1:, :] - f[:-1, :], f[1:, 1:] - f[:-1, :-1], f[1:, :-1] - f[:-1, 1:]]
    d2 = [np.sum(d * d, axis=-1) for d in diffs]
    out = []
    if mode == "bj":
        beta = 1.0 / (2.0 * max(np.mean(np.concatenate([a.ravel() for a in d2])), 1e-12))
        for k, a in enumerate(d2):
            out.append(np.exp(-beta * a) / (np.sqrt(2.0) if k >= 2 else 1.0))
        return out
    for k, a in enumerate(d2):
        n = np.sqrt(a)
        w = np.exp(-n) if mode == "exp" else 1.0 - n / 3.0 if mode == "linear" else None
        if w is None:
            raise ValueError(f"unknown boundary mode {mode!r} (exp, linear or bj)")
        out.append(w / (np.sqrt(2.0) if (diag_dist and k >= 2) else 1.0))
    return out


def neighbour_sum(nl: list[np.ndarray], shape) -> np.ndarray:
    """``sum_q B_pq`` per pixel (both directions of every n-link)."""
    h, w = shape
    s = np.zeros((h, w))
    a, b, c, d = nl
    s[:, :-1] += a
    s[:, 1:] += a
    s[:-1, :] += b
    s[1:, :] += b
    s[:-1, :-1] += c
    s[1:, 1:] += c
    s[:-1, 1:] += d
    s[1:, :-1] += d
    return s


def hard_capacity(nl: list[np.ndarray], shape) -> float:
    """Eq. (9): ``K = 1 + max_p sum_q B_pq``."""
    return 1.0 + float(neighbour_sum(nl, shape).max())


def seed_maps(prev_mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Temporal seeding: distance transforms of the previous mask and of its complement, each / its max."""
    m = prev_mask.astype(np.uint8)
    do = cv2.distanceTransform(m, cv2.DIST_L2, 5)
    db = cv2.distanceTransform(1 - m, cv2.DIST_L2, 5)
    return do / max(float(do.max()), 1e-12), db / max(float(db.max()), 1e-12)


def tlink_caps(Ro, Rb, lam: float, D_obj=None, D_bkg=None, hard_bkg=None, hard_obj=None, K: float = 0.0):
    """Source (object) and sink (background) capacities: restored Table 3 with Table 2's hard seeds."""
    cs = lam * Ro + (lam * D_obj if D_obj is not None else 0.0)
    ct = lam * Rb + (lam * D_bkg if D_bkg is not None else 0.0)
    if D_obj is not None or D_bkg is not None:
        cs = np.minimum(cs, lam + 1.0)
        ct = np.minimum(ct, lam + 1.0)
    cs = np.array(cs, dtype=np.float64)
    ct = np.array(ct, dtype=np.float64)
    if hard_bkg is not None:
        cs[hard_bkg] = 0.0
        ct[hard_bkg] = K
    if hard_obj is not None:
        cs[hard_obj] = K
        ct[hard_obj] = 0.0
    return cs, ct


def graph_size(h: int, w: int) -> tuple[int, int]:
    """(n-links, t-links) of the 8-connected graph: 4 h w - 3 (h + w) + 2 undirected n-links, 2 h w t-links."""
    return 4 * h * w - 3 * (h + w) + 2, 2 * h * w


def _edges(shape):
    h, w = shape
    idx = np.arange(h * w, dtype=np.int32).reshape(h, w)
    return [(idx[:, :-1], idx[:, 1:]), (idx[:-1, :], idx[1:, :]), (idx[:-1, :-1], idx[1:, 1:]),
            (idx[:-1, 1:], idx[1:, :-1])]


def min_cut(cap_s: np.ndarray, cap_t: np.ndarray, nl: list[np.ndarray], backend: str = "scipy") -> np.ndarray:
    """The minimum cut; True where a pixel stays on the source (object) side."""
    shape = cap_s.shape
    if backend == "pymaxflow":
        return _cut_pymaxflow(cap_s, cap_t, nl)
    if backend != "scipy":
        raise ValueError(f"unknown max-flow backend {backend!r} (scipy or pymaxflow)")
    n = cap_s.size
    S, T = n, n + 1
    us, vs, cs = [], [], []
    for (p, q), w in zip(_edges(shape), nl):
        c = np.rint(w * CAP_SCALE).astype(np.int32).ravel()
        keep = c > 0
        p, q, c = p.ravel()[keep], q.ravel()[keep], c[keep]
        us += [p, q]
        vs += [q, p]
        cs += [c, c]
    a = np.rint(cap_s.ravel() * CAP_SCALE).astype(np.int32)
    b = np.rint(cap_t.ravel() * CAP_SCALE).astype(np.int32)
    ks, kt = np.flatnonzero(a > 0).astype(np.int32), np.flatnonzero(b > 0).astype(np.int32)
    us += [np.full(len(ks), S, np.int32), kt]
    vs += [ks, np.full(len(kt), T, np.int32)]
    cs += [a[ks], b[kt]]
    G = csr_matrix((np.concatenate(cs), (np.concatenate(us), np.concatenate(vs))), shape=(n + 2, n + 2))
    flow = maximum_flow(G, S, T, method="dinic").flow
    R = (G - flow).tocsr()
    R.data[R.data < 0] = 0
    R.eliminate_zeros()
    reach = breadth_first_order(R, S, directed=True, return_predecessors=False)
    side = np.zeros(n + 2, bool)
    side[reach] = True
    return side[:n].reshape(shape)


def _cut_pymaxflow(cap_s, cap_t, nl):  # pragma: no cover - optional GPL backend
    try:
        import maxflow
    except ImportError:
        from ..errors import ParameterError

        raise ParameterError("the pymaxflow backend needs PyMaxflow (GPL): pip install PyMaxflow") from None
    h, w = cap_s.shape
    g = maxflow.Graph[float]()
    ids = g.add_grid_nodes((h, w))
    for (dy, dx), W in zip(OFFSETS, nl):
        full = np.zeros((h, w))
        ys, xs = slice(0, h - dy), slice(max(0, -dx), w - max(0, dx))
        full[ys, xs] = W
        s = np.zeros((3, 3))
        s[1 + dy, 1 + dx] = 1
        g.add_grid_edges(ids, weights=full, structure=s, symmetric=True)
    g.add_grid_tedges(ids, cap_s, cap_t)
    g.maxflow()
    return ~g.get_grid_segments(ids)


def energy(labels: np.ndarray, cap_s, cap_t, nl) -> float:
    """The cut's cost: t-links of the side each pixel is cut from, plus n-links between different labels."""
    obj = labels.astype(bool)
    e = float(np.sum(np.where(obj, cap_t, cap_s)))
    pairs = [(obj[:, :-1], obj[:, 1:]), (obj[:-1, :], obj[1:, :]), (obj[:-1, :-1], obj[1:, 1:]),
             (obj[:-1, 1:], obj[1:, :-1])]
    for (a, b), w in zip(pairs, nl):
        e += float(np.sum(w[a != b]))
    return e
