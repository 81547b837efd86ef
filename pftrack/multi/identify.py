"""Identification of people by colour and spatial features of their upper and lower bodies (book ch. 1 §4).

Book *Object Tracking*, ch. 1 (``shared/seeds/002_*`` lines 495-620; ``shared/book/ch01.md`` §1.5):

* **Features** (Eqs. 10-15): the box ``(B_min, B_max)`` and, for the upper and the lower part of the
  body (the head excluded), the per-channel mean (Eqs. 11-12) and standard deviation (Eqs. 13-14)
  of the pixels — :func:`person_features`.  The body ratio of the lost Fig. 12 is a parameter
  (default head 1/8, upper 3/8, lower 4/8 of the box height).
* **Similarity** (Eqs. 16-19, lost; **reconstructed** in ch01.md from the text's description):
  membership functions ``M_c(d) = max(0, 1 - d/Thr_c)`` on the mean colour difference of each
  part, ``M_sd`` likewise on the standard deviations, ``M_p(d) = max(0, 1 - d/W)`` on each box
  coordinate (``W`` the image width or height), combined by their mean (or product) —
  :func:`similarity`.
* **Feature queue** (L604-619): every identity keeps its last features; a detected object takes the
  identity of maximum similarity — :class:`IdentityMemory`, used by ``multi-pf`` with
  ``identify=true`` to give a person who returns after a long occlusion, or who left and came back,
  their old identity.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Features:
    """Eq. 15: ``F = (B_min, B_max, mu_U, mu_L, sigma_U, sigma_L)``."""

    box: np.ndarray  # (4,) x_min, y_min, x_max, y_max
    mu_u: np.ndarray  # (3,) BGR
    mu_l: np.ndarray
    sd_u: np.ndarray
    sd_l: np.ndarray


def person_features(frame: np.ndarray, box, *, head: float = 0.125, upper: float = 0.375,
                    mask: np.ndarray | None = None) -> Features | None:
    """Features of the person in ``box = (x, y, w, h)`` (None when a part has no pixel in the image).

    ``mask`` (same size as the frame, non-zero = object) restricts the statistics to object pixels
    (ch01.md P10); without it every pixel of the part counts.
    """
    x, y, w, h = (float(v) for v in box)
    fh, fw = frame.shape[:2]
    x0, x1 = int(max(np.floor(x), 0)), int(min(np.ceil(x + w), fw))
    ys = [y + head * h, y + (head + upper) * h, y + h]
    parts = []
    for a, b in ((ys[0], ys[1]), (ys[1], ys[2])):
        r0, r1 = int(max(np.floor(a), 0)), int(min(np.ceil(b), fh))
        if r1 <= r0 or x1 <= x0:
            return None
        px = frame[r0:r1, x0:x1].reshape(-1, frame.shape[2] if frame.ndim == 3 else 1).astype(np.float64)
        if mask is not None:
            keep = mask[r0:r1, x0:x1].reshape(-1) > 0
            if keep.sum() >= 4:
                px = px[keep]
        parts.append((px.mean(axis=0), px.std(axis=0)))
    return Features(np.array([x, y, x + w, y + h]), parts[0][0], parts[1][0], parts[0][1], parts[1][1])


@dataclass(frozen=True)
class SimilarityParams:
    """Thresholds of the reconstructed membership functions (ch01.md §1.5, §2)."""

    thr_colour: float = 60.0  # grey levels: mean colours further apart than this have membership 0
    thr_sd: float = 30.0
    combine: str = "mean"  # "mean" | "product"
    spatial: bool = True  # include M_p on the box coordinates


def similarity(a: Features, b: Features, width: int, height: int, p: SimilarityParams = SimilarityParams()) -> float:
    """Reconstructed Eq. 16: the mean (or product) of the membership functions, in ``[0, 1]``."""
    m = [max(0.0, 1.0 - float(np.mean(np.abs(a.mu_u - b.mu_u))) / p.thr_colour),
         max(0.0, 1.0 - float(np.mean(np.abs(a.mu_l - b.mu_l))) / p.thr_colour),
         max(0.0, 1.0 - float(np.mean(np.abs(a.sd_u - b.sd_u))) / p.thr_sd),
         max(0.0, 1.0 - float(np.mean(np.abs(a.sd_l - b.sd_l))) / p.thr_sd)]
    if p.spatial:
        d = np.abs(a.box - b.box)
        m += [max(0.0, 1.0 - float(d[0]) / width), max(0.0, 1.0 - float(d[1]) / height),
              max(0.0, 1.0 - float(d[2]) / width), max(0.0, 1.0 - float(d[3]) / height)]
    return float(np.prod(m)) if p.combine == "product" else float(np.mean(m))


@dataclass
class IdentityMemory:
    """Features of identities that are no longer tracked, for re-identification (the feature queue).

    ``threshold``: the least similarity to take an old identity (below it a new one is created);
    ``memory``: frames an identity is remembered after its track ended.  By default the similarity
    leaves out the spatial memberships: a person who left on one side may come back on the other,
    and the box of an ended track says little about where its owner reappears.
    """

    threshold: float = 0.8
    memory: int = 300
    params: SimilarityParams = field(default_factory=lambda: SimilarityParams(spatial=False))
    entries: dict[int, tuple[Features, int]] = field(default_factory=dict)

    def remember(self, track_id: int, features: Features | None, frame_index: int) -> None:
        if features is not None:
            self.entries[track_id] = (features, frame_index)

    def recall(self, features: Features | None, frame_index: int, width: int, height: int) -> int | None:
        """The remembered identity most similar to ``features`` (removed from memory), or None."""
        for tid in [t for t, (_, k) in self.entries.items() if frame_index - k > self.memory]:
            del self.entries[tid]
        if features is None or not self.entries:
            return None
        best, best_s = None, -1.0
        for tid, (f, _) in self.entries.items():
            s = similarity(features, f, width, height, self.params)
            if s > best_s:
                best, best_s = tid, s
        if best is not None and best_s >= self.threshold:
            del self.entries[best]
            return best
        return None
