"""Hand-over of people between two cameras with disjoint views (book ch. 11, Sect. 5–6).

1. Every track of each camera gets an appearance: the mean of its per-frame region
   histograms (:mod:`.appearance`; by default also joint colour histograms, :mod:`.joint`), and
   the raw counts of its whole-foreground histogram (for the BTF).
2. A BTF from camera A to camera B is fitted on known correspondences (``pairs``): MBTF
   (mean of the per-pair BTFs, Eq. 21) or CBTF (BTF of the accumulated histograms, Eq. 22),
   or none.
3. Camera A's appearances are brought into camera B's colours (push-forward, Eqs. 25–26)
   and compared with camera B's (Eqs. 23–24; joint histograms cell by cell, one ``1 − D_B``).
   Eq. 2 under the one-to-one constraint is a linear assignment (``scipy.optimize.linear_sum_assignment``) on
   −log similarity, with a "new person" option of cost −log τ_new per track (proposed; the text gives no rule).
   τ_new is the lower quartile of the similarities of track pairs seen at the same time in the two
   cameras, which are different people because the views are disjoint
   (:func:`cooccur_threshold`); :func:`new_threshold`, the threshold that best separates the
   training set's genuine and impostor pairs, is the alternative.  Only pairs whose tracks
   follow each other in time (one ends before the other starts) can be linked.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

from ..cues.intensity import is_gray
from .appearance import box_regions, region_histograms, region_labels, rgb_patch, similarity_matrix
from .btf import apply_btf_hist, cbtf, identity_btf, mbtf
from .joint import joint_histogram, joint_similarity_matrix, mean_sparse, push_joint, transfer_matrices

__all__ = ["HISTOGRAMS", "TrackAppearance", "cooccur_threshold", "describe_tracks", "fit_btf", "fit_transit",
           "link_tracks", "new_threshold", "similarities"]

#: How a track's colours are compared: the chapter's three channels one by one, or joint (R, G, B) cells
#: (:mod:`.joint`)
HISTOGRAMS = ("marginal", "joint")


@dataclass
class TrackAppearance:
    track: int
    first: int
    last: int
    hist: np.ndarray                      # (regions, 3, 256) mean normalised histogram
    raw: np.ndarray                       # (3, 256) whole-foreground pixel counts
    samples: int = 0
    joint: tuple[np.ndarray, np.ndarray] | None = None  # histogram="joint": sparse mean (cells, masses), .joint
    regions: int = 1
    joint_plain: np.ndarray | None = None  # that histogram as compared, through no BTF (camera B's side)
    _acc: list = field(default_factory=list, repr=False)


def describe_tracks(frames: Callable[[int], np.ndarray | None], rows: np.ndarray, feature: str, *,
                    fg: Callable[[int], np.ndarray | None] | None = None, every: int = 2,
                    numbers: list[int] | None = None, histogram: str = "joint") -> dict[int, TrackAppearance]:
    """Appearances of every track of MOT rows ``frame,id,x,y,w,h,...``; ``frames(n)`` gives frame n
    (``fg(n)`` its foreground mask); every ``every``-th frame of a track is sampled. With ``histogram="joint"``
    (default, chosen on the tune scenes under docs/rules/handover_joint_rule.txt) each appearance also keeps the
    mean joint histogram of its regions (:mod:`.joint`), which the links then compare instead of the channels'
    histograms; ``"marginal"`` compares the channels one by one, as the chapter does. A grey camera (most of the
    frames read without colour) keeps no joint histograms: its colours lie on the grey diagonal, which the joint
    cells cut into 8 levels where a channel histogram has 256, so its links compare the channels' histograms."""
    if histogram not in HISTOGRAMS:
        raise ValueError(f"histogram must be one of {', '.join(HISTOGRAMS)}")
    joint = histogram == "joint"
    joints: dict[int, list] = {}
    n_regions = region_labels(4, 4, feature)[1]
    frames_read = grey_frames = 0
    rows = np.asarray(rows, dtype=np.float64)
    out: dict[int, TrackAppearance] = {}
    by_frame: dict[int, list] = {}
    for tid in np.unique(rows[:, 1]).astype(int):
        r = rows[rows[:, 1] == tid]
        r = r[np.argsort(r[:, 0])]
        out[int(tid)] = TrackAppearance(int(tid), int(r[0, 0]), int(r[-1, 0]), np.zeros(0), np.zeros((3, 256)))
        for k, row in enumerate(r):
            if k % every == 0 or k == len(r) - 1:
                by_frame.setdefault(int(row[0]), []).append((int(tid), row[2:6]))
    order = sorted(by_frame) if numbers is None else [n for n in numbers if n in by_frame]
    for n in order:
        img = frames(n)
        if img is None:
            continue
        mask = fg(n) if fg is not None else None
        frames_read += 1
        grey_frames += bool(joint and is_gray(img))
        # once most of the frames to read are grey, the camera is grey whatever the rest: no more joint cells
        joint = joint and 2 * grey_frames <= len(order)
        for tid, box in by_frame[n]:
            if box[2] < 4 or box[3] < 4:
                continue
            a = out[tid]
            parts = box_regions(img, box, feature, fg=mask)  # the region map, once for both histograms
            rgb = rgb_patch(parts[0])  # and the patch in RGB, once for the three
            a._acc.append(region_histograms(img, box, feature, fg=mask, parts=parts, rgb=rgb))
            a.raw += region_histograms(img, box, "whole", fg=mask, raw=True, rgb=rgb)[0]
            a.samples += 1
            if joint:
                cells, masses, _ = joint_histogram(img, box, feature, fg=mask, parts=parts, rgb=rgb)
                if len(cells):
                    joints.setdefault(tid, []).append((cells, masses))
    joint = joint and 2 * grey_frames <= frames_read  # a grey camera: the channels' histograms
    for tid, a in out.items():
        a.hist = np.mean(a._acc, axis=0) if a._acc else np.full((1, 3, 256), 1.0 / 256)
        a._acc = []
        if joint:
            a.joint, a.regions = mean_sparse(joints.get(tid, []), a.samples), n_regions  # empty frames count
            a.joint_plain = push_joint(*a.joint, a.regions, identity_btf())
    return out


def fit_btf(app_a: dict[int, TrackAppearance], app_b: dict[int, TrackAppearance], pairs, method: str) -> np.ndarray:
    """``(3, 256)`` BTF from camera A to camera B fitted on the ``pairs`` (track_a, track_b). ``method``:
    ``none``, ``mbtf``, ``cbtf`` (each training track's histogram at unit mass before pooling) or ``cbtf-pixels``
    (raw pixel counts pooled, Eq. 22 as restored in ch11.md)."""
    if method == "none" or not pairs:
        return identity_btf()
    src = [app_a[a].raw for a, _ in pairs]
    dst = [app_b[b].raw for _, b in pairs]
    if method == "mbtf":
        return mbtf(src, dst, [(k, k) for k in range(len(pairs))])
    if method == "cbtf":
        return cbtf(src, dst, weight="people")
    if method == "cbtf-pixels":
        return cbtf(src, dst, weight="pixels")
    raise ValueError("btf must be none, mbtf, cbtf or cbtf-pixels")


def similarities(app_a, app_b, lut) -> tuple[list[int], list[int], np.ndarray]:
    """The track ids of each camera, sorted, and the similarities ``(len(A), len(B))`` of camera A's appearances
    carried through ``lut`` with camera B's: joint histograms where both cameras' appearances have them, else the
    channels' histograms (Eqs. 23–26)."""
    ka, kb = sorted(app_a), sorted(app_b)
    if ka and kb and all(app_a[k].joint is not None for k in ka) and all(app_b[k].joint is not None for k in kb):
        T = transfer_matrices(lut)
        A = np.stack([push_joint(*app_a[k].joint, app_a[k].regions, lut, transfer=T) for k in ka])
        B = np.stack([app_b[k].joint_plain for k in kb])
        return ka, kb, joint_similarity_matrix(A, B)
    A = np.stack([apply_btf_hist(app_a[k].hist, lut) for k in ka]) if ka else np.zeros((0, 1, 3, 256))
    B = np.stack([app_b[k].hist for k in kb]) if kb else np.zeros((0, 1, 3, 256))
    S = similarity_matrix(A, B) if len(A) and len(B) else np.zeros((len(ka), len(kb)))
    return ka, kb, S


def cooccur_threshold(app_a: dict[int, TrackAppearance], app_b: dict[int, TrackAppearance], lut: np.ndarray,
                      quantile: float = 0.25) -> float | None:
    """τ_new from pairs known to be different people, without labels (proposed; the text gives no rule).

    The two views are disjoint, so a track of camera A and a track of camera B whose time spans overlap are
    two people.  Their similarities (through ``lut``, as the links are scored) sample the impostor
    distribution of this very recording, cameras and BTF included; a probe whose best affordable match is
    less similar than their lower ``quantile`` is a new person.  This needs no training pairs and does not
    depend on the 2–4 people a BTF is usually fitted on.  The quartile was chosen on the tune scenes
    (docs/handover.md).  None when no two tracks co-occur.
    """
    if not 0.0 <= quantile <= 1.0:
        raise ValueError("quantile must be in [0, 1]")
    ka, kb, S = similarities(app_a, app_b, lut)
    if not ka or not kb:
        return None
    fa = np.array([app_a[k].first for k in ka])[:, None]
    la = np.array([app_a[k].last for k in ka])[:, None]
    fb = np.array([app_b[k].first for k in kb])[None, :]
    lb = np.array([app_b[k].last for k in kb])[None, :]
    overlap = (fa <= lb) & (fb <= la)
    if not overlap.any():
        return None
    return float(np.quantile(S[overlap], quantile))


def new_threshold(app_a, app_b, pairs, method: str) -> float:
    """τ_new from the training tracks (proposed; the text gives no rule): the similarity threshold with the
    fewest errors between genuine pairs (the training correspondences) and impostor pairs (a training track
    of one camera against another person's training track in the other camera), ties to the lowest.

    A genuine pair is scored with the BTF fitted *without* it (leave one pair out): the BTF fitted on a
    pair makes that pair look more alike than any unseen person will, and a threshold taken from such
    similarities rejects the true links of new people.  0 (no "new person" decision) without pairs.
    """
    if not pairs:
        return 0.0
    a_ids = sorted({a for a, _ in pairs})
    b_ids = sorted({b for _, b in pairs})
    lut = fit_btf(app_a, app_b, pairs, method)
    ka, kb, S = similarities({a: app_a[a] for a in a_ids}, {b: app_b[b] for b in b_ids}, lut)
    same = set(pairs)
    genuine = []
    for a, b in pairs:
        rest = [(x, y) for x, y in pairs if x != a and y != b]
        lut_k = fit_btf(app_a, app_b, rest, method) if rest else identity_btf()
        _, _, s_k = similarities({a: app_a[a]}, {b: app_b[b]}, lut_k)
        genuine.append(float(s_k[0, 0]))
    partners = {a: {y for x, y in same if x == a} for a in a_ids}
    impostor = []
    for i, a in enumerate(ka):
        for j, b in enumerate(kb):
            related = any(b in partners[x] for x in a_ids if partners[x] & partners[a])
            if not related:
                impostor.append(S[i, j])
    g, im = np.asarray(genuine), np.asarray(impostor)
    if len(im) == 0:
        return float(g.min()) * 0.9
    cands = np.unique(np.concatenate([g, im, [0.0]]))
    errs = [np.mean(g < t) + np.mean(im >= t) for t in cands]
    return float(cands[int(np.argmin(errs))])


def fit_transit(app_a: dict[int, TrackAppearance], app_b: dict[int, TrackAppearance], pairs,
                min_sigma: float = 1.0) -> tuple[float, float] | None:
    """A log-normal model of the transit time between the cameras from the training pairs (the optional
    transit-time cue of the chapter's hand-over, after Javed et al.): ``(mean, std)`` of ``log(gap)``, gap in
    frames from the end of one track to the start of the other; the spread is at least ``min_sigma``
    (a factor e either way), since a handful of pairs under-estimates it.  None without a usable pair."""
    gaps = []
    for a, b in pairs:
        ta, tb = app_a[a], app_b[b]
        g = tb.first - ta.last if ta.last < tb.first else ta.first - tb.last
        if g > 0:
            gaps.append(np.log(g))
    if not gaps:
        return None
    return float(np.mean(gaps)), float(max(np.std(gaps), min_sigma))


def link_tracks(app_a: dict[int, TrackAppearance], app_b: dict[int, TrackAppearance], lut: np.ndarray, *,
                tau_new: float = 0.0, exclude_a=(), exclude_b=(),
                transit: tuple[float, float] | None = None) -> list[tuple[int, int, float]]:
    """One-to-one links ``(track_a, track_b, similarity)``.

    A track that has ended in one camera is in the gallery; a track that starts later in the
    other camera is a probe for it.  Every probe takes at most one gallery track and every
    gallery track serves at most one probe (Eq. 2 as an assignment); a probe whose best
    affordable match is below ``tau_new`` is a new person (no link).  With ``transit``
    (:func:`fit_transit`) a candidate's cost also carries ``z^2/2`` of its log transit time, so that
    a look-alike who arrives far too early or too late loses to the right person.
    """
    a_ids = {k: v for k, v in app_a.items() if k not in set(exclude_a)}
    b_ids = {k: v for k, v in app_b.items() if k not in set(exclude_b)}
    ka, kb, S = similarities(a_ids, b_ids, lut)
    if not ka or not kb:
        return []
    tracks = [("a", k) for k in ka] + [("b", k) for k in kb]
    first = {("a", k): a_ids[k].first for k in ka} | {("b", k): b_ids[k].first for k in kb}
    last = {("a", k): a_ids[k].last for k in ka} | {("b", k): b_ids[k].last for k in kb}

    def sim(p, g):
        a, b = (p, g) if p[0] == "a" else (g, p)
        return S[ka.index(a[1]), kb.index(b[1])]

    probes = [p for p in tracks if any(g[0] != p[0] and last[g] < first[p] for g in tracks)]
    if not probes:
        return []
    gallery = [g for g in tracks if any(p[0] != g[0] and last[g] < first[p] for p in probes)]
    big = 1e6
    span = max(np.log(max(max(first.values()) - min(last.values()), 2)), 1.0)
    cost = np.full((len(probes), len(gallery)), big)
    for i, p in enumerate(probes):
        for j, g in enumerate(gallery):
            if g[0] != p[0] and last[g] < first[p]:
                cost[i, j] = -np.log(max(sim(p, g), 1e-9))
                if transit is not None:   # -log of the likelihood ratio against log-gaps uniform over [0, log span]
                    z = (np.log(first[p] - last[g]) - transit[0]) / transit[1]
                    cost[i, j] += 0.5 * z * z + np.log(transit[1] * np.sqrt(2 * np.pi)) - np.log(span)
    new_cost = -np.log(max(tau_new, 1e-9)) if tau_new > 0 else big / 2
    full = np.hstack([cost, np.full((len(probes), len(probes)), big)])
    full[np.arange(len(probes)), len(gallery) + np.arange(len(probes))] = new_cost
    ri, ci = linear_sum_assignment(full)
    links = []
    for r, c in zip(ri, ci):
        if c < len(gallery) and cost[r, c] < big:
            p, g = probes[r], gallery[c]
            sv = float(sim(p, g))
            if sv >= tau_new:
                a, b = (p, g) if p[0] == "a" else (g, p)
                links.append((a[1], b[1], sv))
    return links
