"""The robot's colour markers in camera frames (book ch. 12 §1.5, Fig. 6, L10635-10663; ch12.md §4 and §5.2).

The chapter finds the robot in each camera by background subtraction and three coloured markers on the robot's
top, found by colour histograms (Swain & Ballard), which stay stable under deformation and partial occlusion. The
image point paired with the robot's world position is the centroid of the three markers (ch12.md pitfall 11).

Pure functions:
- :func:`render_robot_top` paints the three discs into a frame, anti-aliased, at a sub-pixel position (the truth
  of the experiment in ``scripts/ch12_markers.py``);
- :func:`marker_histograms` and :func:`learn_histograms` give one hue-saturation histogram per marker colour, from
  the colours or from sample images;
- :func:`detect_markers` back-projects them inside the foreground mask, keeps blobs of at least ``min_area``
  pixels and ``min_side`` x ``min_side``, and groups one blob of each colour into a robot top.
"""

from __future__ import annotations

from dataclasses import dataclass
import cv2
import numpy as np

#: The three marker colours (BGR): red, green, blue discs on the robot's top (Fig. 6 shows three discs).
MARKER_COLOURS = ((40, 40, 210), (60, 170, 40), (200, 110, 30))

_H_BINS, _S_BINS = 30, 32
_RANGES = [0, 180, 0, 256]


def disc_coverage(shape: tuple[int, int], centre, radius: float, ss: int = 8) -> np.ndarray:
    """The fraction (float32, ``shape``) of each pixel covered by the disc, from ``ss x ss`` samples a pixel.
    Pixel ``(x, y)`` spans ``[x - 0.5, x + 0.5]``, so the coverage's centroid is the disc's centre."""
    h, w = shape
    cx, cy = map(float, centre)
    cov = np.zeros((h, w), np.float32)
    x0, x1 = max(int(np.floor(cx - radius - 1)), 0), min(int(np.ceil(cx + radius + 1)), w - 1)
    y0, y1 = max(int(np.floor(cy - radius - 1)), 0), min(int(np.ceil(cy + radius + 1)), h - 1)
    if x1 < x0 or y1 < y0:
        return cov
    off = (np.arange(ss) + 0.5) / ss - 0.5
    xs = np.arange(x0, x1 + 1)[:, None] + off[None]          # (nx, ss)
    ys = np.arange(y0, y1 + 1)[:, None] + off[None]          # (ny, ss)
    inside = ((xs[None, :, None, :] - cx) ** 2 + (ys[:, None, :, None] - cy) ** 2) <= radius ** 2
    cov[y0:y1 + 1, x0:x1 + 1] = inside.mean(axis=(2, 3))
    return cov


def marker_centres(centre, spacing: float, angle: float) -> np.ndarray:
    """The three discs' centres (3, 2): on a circle of radius ``spacing`` around ``centre``, 120 degrees apart."""
    a = angle + np.array([0.0, 2 * np.pi / 3, 4 * np.pi / 3])
    return np.asarray(centre, np.float64) + spacing * np.c_[np.cos(a), np.sin(a)]


def render_robot_top(frame: np.ndarray, centre, *, radius: float = 5.0, spacing: float = 9.0, angle: float = 0.0,
                     colours=MARKER_COLOURS) -> tuple[np.ndarray, np.ndarray]:
    """``frame`` (BGR uint8) with the robot's three marker discs painted at ``centre`` (sub-pixel, anti-aliased),
    and the discs' true centres (3, 2). Their mean is ``centre``."""
    out = frame.astype(np.float32)
    centres = marker_centres(centre, spacing, angle)
    for c, colour in zip(centres, colours):
        cov = disc_coverage(frame.shape[:2], c, radius)[..., None]
        out = out * (1 - cov) + cov * np.asarray(colour, np.float32)
    return np.clip(out + 0.5, 0, 255).astype(np.uint8), centres


def marker_histograms(colours=MARKER_COLOURS, *, noise: float = 6.0, gains=(0.6, 1.1), seed: int = 0
                      ) -> list[np.ndarray]:
    """One normalised hue-saturation histogram (30 x 32 bins, maximum 255) per marker colour, learned from patches
    of that colour under the light ``gains`` (a range of brightness factors) with sensor noise of ``noise`` grey
    levels: the chapter learns them from sample images of the markers in the room."""
    rng = np.random.default_rng(seed)
    hists = []
    g = np.linspace(gains[0], gains[1], 40)[:, None, None]
    for colour in colours:
        base = g * np.asarray(colour, np.float64)[None, None] + np.zeros((40, 40, 3))
        patch = np.clip(base + rng.normal(0, noise, (40, 40, 3)), 0, 255).astype(np.uint8)
        hsv = cv2.cvtColor(patch, cv2.COLOR_BGR2HSV)
        hist = cv2.calcHist([hsv], [0, 1], None, [_H_BINS, _S_BINS], _RANGES)
        cv2.normalize(hist, hist, 0, 255, cv2.NORM_MINMAX)
        hists.append(hist)
    return hists


def learn_histograms(samples, radius: float, n_colours: int = 3) -> list[np.ndarray]:
    """Hue-saturation histograms (as :func:`marker_histograms`) learned from sample images of the robot's top:
    ``samples`` is a list of ``(bgr image, marker centres (3, 2))``; each colour takes the pixels within ``radius``
    of its centre in every sample, as the camera saw them (blur, noise and compression included)."""
    hists = []
    for k in range(n_colours):
        acc = np.zeros((_H_BINS, _S_BINS), np.float32)
        for img, centres in samples:
            mask = np.zeros(img.shape[:2], np.uint8)
            cx, cy = centres[k]
            cv2.circle(mask, (int(round(cx * 16)), int(round(cy * 16))), int(round(radius * 16)), 255, -1,
                       shift=4)
            hsv = cv2.cvtColor(img, cv2.COLOR_BGR2HSV)
            acc += cv2.calcHist([hsv], [0, 1], mask, [_H_BINS, _S_BINS], _RANGES)
        cv2.normalize(acc, acc, 0, 255, cv2.NORM_MINMAX)
        hists.append(acc)
    return hists


@dataclass(frozen=True)
class RobotTop:
    """A detected robot top: the centroid of its three markers and each marker's centroid (3, 2)."""

    centre: np.ndarray
    markers: np.ndarray


def _blobs(prob: np.ndarray, fg: np.ndarray | None, threshold: int, min_area: int, min_side: int) -> np.ndarray:
    """Centroids (n, 2) of the back-projection's blobs: pixels above ``threshold`` in the foreground, joined by a
    3 x 3 dilation (a Chebyshev gap of one pixel), weighted by the back-projection for sub-pixel centres."""
    mask = (prob > threshold).astype(np.uint8)
    if fg is not None:
        mask &= (fg > 0).astype(np.uint8)
    joined = cv2.dilate(mask, np.ones((3, 3), np.uint8))
    n, labels, stats, _ = cv2.connectedComponentsWithStats(joined, connectivity=8)
    out = []
    weight = prob.astype(np.float64) * mask
    for k in range(1, n):
        x, y, w, h, _ = stats[k]
        sel = labels[y:y + h, x:x + w] == k
        wk = weight[y:y + h, x:x + w] * sel
        if np.count_nonzero(mask[y:y + h, x:x + w] & sel) < min_area or w < min_side or h < min_side:
            continue
        m = wk.sum()
        if m <= 0:
            continue
        ys, xs = np.mgrid[y:y + h, x:x + w]
        out.append(((wk * xs).sum() / m, (wk * ys).sum() / m))
    return np.asarray(out, np.float64).reshape(-1, 2)


def detect_markers(frame: np.ndarray, fg_mask: np.ndarray | None, hists: list[np.ndarray], *, threshold: int = 10,
                   min_area: int = 15, min_side: int = 3, max_spread: float = 30.0) -> list[RobotTop]:
    """Robot tops in a BGR frame: each marker colour's histogram back-projected (hue, saturation), kept inside
    ``fg_mask`` (the background subtraction's foreground; None: everywhere), blobs of at least ``min_area`` pixels
    and ``min_side`` x ``min_side`` (ch12.md §3), then one blob of each colour with every pair at most
    ``max_spread`` px apart, tightest triplets first, each blob used once."""
    hsv = cv2.cvtColor(frame, cv2.COLOR_BGR2HSV)
    blobs = []
    for hist in hists:
        prob = cv2.calcBackProject([hsv], [0, 1], hist, _RANGES, scale=1)
        blobs.append(_blobs(prob, fg_mask, threshold, min_area, min_side))
    if any(len(b) == 0 for b in blobs):
        return []
    def dist(a, b):
        return np.linalg.norm(a[:, None] - b[None], axis=2)

    d01, d12, d02 = dist(blobs[0], blobs[1]), dist(blobs[1], blobs[2]), dist(blobs[0], blobs[2])
    perimeter = d01[:, :, None] + d12[None] + d02[:, None, :]
    ok = (d01[:, :, None] <= max_spread) & (d12[None] <= max_spread) & (d02[:, None, :] <= max_spread)
    idx = np.argwhere(ok)
    idx = idx[np.argsort(perimeter[ok], kind="stable")]          # tightest triplets first
    used: list[set] = [set(), set(), set()]
    tops = []
    for i, j, k in idx:
        if i in used[0] or j in used[1] or k in used[2]:
            continue
        used[0].add(i), used[1].add(j), used[2].add(k)
        p = np.stack([blobs[0][i], blobs[1][j], blobs[2][k]])
        tops.append(RobotTop(p.mean(0), p))
    return tops
