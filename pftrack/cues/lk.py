"""Lucas–Kanade velocities of points, with an honest validity flag (book ch. 7, Sect. 2.1).

:func:`lk_flow` wraps ``cv2.calcOpticalFlowPyrLK`` (Eqs. 6–10: the weighted least-squares
flow on a window, solved by iterated pyramidal LK) and fixes what it leaves to the caller:

* a point whose window fails the eigenvalue test ``min(λ₁, λ₂) > λ_eig`` (L6385–6391) is
  invalid (OpenCV's ``minEigThreshold``, normalised by the window area);
* a point whose result lies outside the image is invalid (OpenCV reports it as found);
* optionally, the forward–backward check: the point is tracked back to the previous
  frame and rejected when it does not return within ``fb_threshold`` pixels.
"""

from __future__ import annotations

import cv2
import numpy as np

from ..frames import grey_origin
from ..geometry import parabola_peak

__all__ = ["LKConfig", "gray_of", "lk_flow", "ncc", "patches_at", "reanchor"]


def gray_of(frame: np.ndarray) -> np.ndarray:
    """A uint8 grey image of a BGR or grey frame (not to be changed in place: for a BGR frame made from a grey
    image it is that image, :func:`pftrack.frames.grey_origin`)."""
    if frame.ndim == 2:
        return frame if frame.dtype == np.uint8 else np.clip(frame, 0, 255).astype(np.uint8)
    if frame.shape[2] == 1:
        return frame[:, :, 0]
    origin = grey_origin(frame)
    if origin is not None:
        return origin
    return cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)


class LKConfig:
    """The LK options of ch07.md §2: 7×7 windows, ``levels`` pyramid levels (0 is the book's
    plain LK), OpenCV's eigenvalue threshold and termination criteria."""

    __slots__ = ("criteria", "fb_check", "fb_threshold", "levels", "min_eig", "win")

    def __init__(self, win: int = 7, levels: int = 2, min_eig: float = 1e-4, iterations: int = 30,
                 epsilon: float = 0.01, fb_check: bool = False, fb_threshold: float = 1.0):
        if win < 3 or win % 2 == 0:
            raise ValueError("the LK window must be odd and >= 3")
        self.win, self.levels, self.min_eig = int(win), int(levels), float(min_eig)
        self.criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, int(iterations), float(epsilon))
        self.fb_check, self.fb_threshold = bool(fb_check), float(fb_threshold)


def _call(prev: np.ndarray, cur: np.ndarray, pts: np.ndarray, cfg: LKConfig) -> tuple[np.ndarray, np.ndarray]:
    p0 = np.ascontiguousarray(pts, dtype=np.float32).reshape(-1, 1, 2)
    p1, status, _err = cv2.calcOpticalFlowPyrLK(
        prev, cur, p0, None, winSize=(cfg.win, cfg.win), maxLevel=cfg.levels, criteria=cfg.criteria,
        flags=cv2.OPTFLOW_LK_GET_MIN_EIGENVALS, minEigThreshold=cfg.min_eig)
    return p1.reshape(-1, 2).astype(np.float64), status.reshape(-1).astype(bool)


def lk_flow(prev_gray: np.ndarray, gray: np.ndarray, pts: np.ndarray, cfg: LKConfig | None = None
            ) -> tuple[np.ndarray, np.ndarray]:
    """New positions ``(n, 2)`` of ``pts`` and a validity mask ``(n,)``.

    Invalid points (status 0, eigenvalue test, outside the image, failed forward–backward
    check) keep NaN positions, so no caller can use them by accident.
    """
    cfg = cfg or LKConfig()
    pts = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
    if len(pts) == 0:
        return np.zeros((0, 2)), np.zeros(0, dtype=bool)
    h, w = gray.shape[:2]
    inside0 = (np.isfinite(pts).all(1) & (pts[:, 0] >= 0) & (pts[:, 0] <= w - 1)
               & (pts[:, 1] >= 0) & (pts[:, 1] <= h - 1))
    if not inside0.any():
        return np.full_like(pts, np.nan), np.zeros(len(pts), dtype=bool)
    # LK only needs the pyramid around the points: crop both frames to their bounding box plus the
    # reach of the coarsest level, on a grid aligned to that level so the pyramids are the full
    # frame's (GUIDE §3: touch only the pixels the estimate can reach)
    step = 2 ** cfg.levels
    margin = (cfg.win // 2 + 2) * step * 2 + 16
    lo = np.floor((pts[inside0].min(0) - margin) / step) * step
    hi = np.ceil((pts[inside0].max(0) + margin) / step) * step
    x0, y0 = (int(max(0, v)) for v in lo)
    x1, y1 = int(min(w, hi[0])), int(min(h, hi[1]))
    if (x1 - x0) * (y1 - y0) < 0.6 * w * h:
        prev_gray, gray = prev_gray[y0:y1, x0:x1], gray[y0:y1, x0:x1]
        off = np.array([x0, y0], dtype=np.float64)
    else:
        off = np.zeros(2)
    safe = np.where(inside0[:, None], pts, off) - off
    new, ok = _call(prev_gray, gray, safe, cfg)
    new += off
    ok &= inside0 & np.isfinite(new).all(1)
    ok &= (new[:, 0] >= 0) & (new[:, 0] <= w - 1) & (new[:, 1] >= 0) & (new[:, 1] <= h - 1)
    if cfg.fb_check and ok.any():
        back, ok_b = _call(gray, prev_gray, np.where(ok[:, None], new, off) - off, cfg)
        ok &= ok_b & (np.hypot(*(back + off - pts).T) <= cfg.fb_threshold)
    new[~ok] = np.nan
    return new, ok


def patches_at(gray: np.ndarray, pts: np.ndarray, half: int) -> np.ndarray:
    """``(n, 2·half+1, 2·half+1)`` float32 patches centred (sub-pixel) on ``pts`` (NaN points give zeros)."""
    pts = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
    size = 2 * half + 1
    src = gray if gray.dtype == np.float32 else gray.astype(np.float32)
    out = np.zeros((len(pts), size, size), np.float32)
    for i, (x, y) in enumerate(pts):
        if np.isfinite(x) and np.isfinite(y):
            out[i] = cv2.getRectSubPix(src, (size, size), (float(x), float(y)))
    return out


def ncc(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Zero-mean normalised cross-correlation of paired patches ``(n, s, s)`` (0 where one is flat)."""
    a = a.reshape(len(a), -1).astype(np.float64)
    b = b.reshape(len(b), -1).astype(np.float64)
    a = a - a.mean(1, keepdims=True)
    b = b - b.mean(1, keepdims=True)
    den = np.sqrt((a * a).sum(1) * (b * b).sum(1))
    return np.where(den > 1e-9, (a * b).sum(1) / np.where(den > 1e-9, den, 1.0), 0.0)


def reanchor(ref_gray: np.ndarray, gray: np.ndarray, ref_pts: np.ndarray, guess: np.ndarray, *, half: int = 7,
             max_shift: float = 8.0, min_score: float = 0.7) -> tuple[np.ndarray, np.ndarray]:
    """Correct drift by finding each point's pre-occlusion patch again near its current estimate.

    The ``(2·half+1)²`` patch around ``ref_pts`` on ``ref_gray`` is matched by normalised
    cross-correlation (``TM_CCOEFF_NORMED``: insensitive to gain and offset, which LK is not
    over many frames) within ``max_shift`` pixels of ``guess`` on ``gray``, with parabolic
    sub-pixel refinement.  Returns the positions and which points were corrected (peak
    score at least ``min_score``).
    """
    ref_pts = np.asarray(ref_pts, dtype=np.float64).reshape(-1, 2)
    guess = np.asarray(guess, dtype=np.float64).reshape(-1, 2)
    out, ok = guess.copy(), np.zeros(len(guess), dtype=bool)
    r = int(np.ceil(max_shift))
    size = 2 * half + 1
    ref_f, cur_f = ref_gray.astype(np.float32), gray.astype(np.float32)
    h, w = gray.shape[:2]
    for i, ((rx, ry), (gx, gy)) in enumerate(zip(ref_pts, guess)):
        if not (np.isfinite([rx, ry, gx, gy]).all() and half <= gx <= w - 1 - half and half <= gy <= h - 1 - half):
            continue
        tmpl = cv2.getRectSubPix(ref_f, (size, size), (float(rx), float(ry)))
        area = cv2.getRectSubPix(cur_f, (size + 2 * r, size + 2 * r), (float(gx), float(gy)))
        if tmpl.std() < 1.0:
            continue
        score = cv2.matchTemplate(area, tmpl, cv2.TM_CCOEFF_NORMED)
        _, best, _, (bx, by) = cv2.minMaxLoc(score)
        if best < min_score:
            continue
        dx = parabola_peak(score[by, bx - 1], best, score[by, bx + 1]) if 0 < bx < score.shape[1] - 1 else 0.0
        dy = parabola_peak(score[by - 1, bx], best, score[by + 1, bx]) if 0 < by < score.shape[0] - 1 else 0.0
        shift = np.array([bx + dx - r, by + dy - r])
        if np.hypot(*shift) <= max_shift:
            out[i] = (gx, gy) + shift
            ok[i] = True
    return out, ok
