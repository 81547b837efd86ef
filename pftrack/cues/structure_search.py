"""Where in a whole frame the structural cue's reference is: dense NCC at the reference's resolution.

A search that spreads samples over the frame (a lost colour particle filter) finds a small or
relit target only if a sample lands within a few pixels of it: the NCC of a textured patch falls
off within a fraction of the box, and a target whose light changed while it was hidden has lost
its colours. Template matching sees the whole frame at once (book ch. 14): the frame is reduced
so that a box of the searched size becomes the reference patch's ``(ph, pw)`` pixels, and OpenCV's
``matchTemplate`` (``TM_CCOEFF_NORMED``, the zero-mean NCC of ch. 14) gives the correlation at every
position; its few best separated peaks are proposed to the search, which scores them with every
cue like any other sample.
"""

from __future__ import annotations

import cv2
import numpy as np

from .reduced_region import gray_region


def ncc_map(image: np.ndarray, templates: np.ndarray) -> np.ndarray:
    """The zero-mean NCC of every ``(ph, pw)`` template at every position of ``image`` (top-left
    corners, ``(H - ph + 1, W - pw + 1)``), the best over the templates; flat windows score 0."""
    img = np.ascontiguousarray(image, dtype=np.float32)
    out = None
    for t in np.asarray(templates, dtype=np.float32):
        r = cv2.matchTemplate(img, np.ascontiguousarray(t), cv2.TM_CCOEFF_NORMED)
        r[~np.isfinite(r)] = 0.0
        out = r if out is None else np.maximum(out, r)
    return out


def map_peaks(score: np.ndarray, k: int, window: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """The ``k`` best positions of a score map, each at least a ``window`` ``(wh, ww)`` apart from the better
    ones (greedy non-maximum suppression): ``(rows, cols)`` as an ``(m, 2)`` int array, and their scores."""
    s = np.array(score, dtype=np.float32, copy=True)
    wh, ww = max(int(window[0]), 1), max(int(window[1]), 1)
    pos, val = [], []
    for _ in range(max(int(k), 0)):
        i = int(np.argmax(s))
        r, c = divmod(i, s.shape[1])
        v = float(s[r, c])
        if not np.isfinite(v):  # every position suppressed
            break
        pos.append((r, c))
        val.append(v)
        s[max(r - wh + 1, 0):r + wh, max(c - ww + 1, 0):c + ww] = -np.inf
    return np.array(pos, dtype=np.int64).reshape(-1, 2), np.array(val)


def propose_centres(frame: np.ndarray, templates: np.ndarray, half_axes: tuple[float, float],
                    k: int) -> tuple[np.ndarray, np.ndarray]:
    """Centres ``(m, 2)`` (frame pixels) of the ``k`` best separated matches of reference patches ``(T, ph, pw)``
    for a box of half-axes ``(hx, hy)``, and their NCC; empty when the frame is smaller than one box."""
    templates = np.asarray(templates, dtype=np.float32)
    _, ph, pw = templates.shape
    hx, hy = (max(float(v), 0.5) for v in half_axes)
    fx, fy = 2.0 * hx / pw, 2.0 * hy / ph  # frame pixels per patch pixel
    fh, fw = frame.shape[:2]
    sw, sh = int(round(fw / fx)), int(round(fh / fy))
    if sw < pw or sh < ph or k <= 0:
        return np.empty((0, 2)), np.empty(0)
    gray = gray_region(frame, (0, 0, fw, fh))
    interp = cv2.INTER_AREA if fx >= 1.0 and fy >= 1.0 else cv2.INTER_LINEAR
    small = cv2.resize(gray, (sw, sh), interpolation=interp).astype(np.float32)
    pos, val = map_peaks(ncc_map(small, templates), k, (ph // 2 + 1, pw // 2 + 1))
    # a window's top-left (c, r) in the reduced image: its centre is (c + pw / 2, r + ph / 2) reduced pixels
    centres = np.column_stack([(pos[:, 1] + pw / 2.0) * (fw / sw), (pos[:, 0] + ph / 2.0) * (fh / sh)])
    return centres, val
