"""What ``ssim-pf`` and ``dssim`` share (book ch. 2): the reference patch, the grey frame, the loss test's
background positions, and the parameters of all three."""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from ..cues import ssim as S
from ..params import Params, param


@dataclass(frozen=True, kw_only=True)
class SSIMTemplateParams(Params):
    """Parameters shared by the fixed-reference SSIM trackers (values the text leaves open are ch02.md §2's)."""

    template_pixels: int = param(1000, ge=144, le=1_000_000, doc=(
        "Speed bound: the reference patch keeps the box's aspect with at most this many pixels (larger boxes "
        "are compared at reduced resolution). At least 12 px per side remain for the 11x11 window. 1000 and "
        "2500 gave the same accuracy on the tune split (docs/ssim.md); the cost is linear in it."))
    template_update: float = param(0.0, ge=0, le=1, doc=(
        "Rate of the gated template update t <- (1 - a) t + a p_est while the loss test is confident; "
        "0 keeps the chapter's fixed reference."))
    min_scale: float = param(0.2, gt=0, le=1, doc="Smallest scale s relative to the initial box.")
    max_scale: float = param(5.0, ge=1, le=100, doc="Largest scale s relative to the initial box.")
    background_positions: int = param(60, ge=4, le=10_000, doc=(
        "Background positions (a grid over the frame, away from the target) whose scores define the loss "
        "test's absent hypothesis."))
    background_interval: int = param(10, ge=1, le=10_000, doc="Recompute the background scores every this many frames.")
    lost_frames: int = param(3, ge=1, le=1000, doc="Frames with LLR < 0 before lost (pftrack.filtering.loss).")
    reacquire_margin: float = param(1.0, ge=0, le=20, doc="LLR that ends a loss (hysteresis).")
    smooth: float = param(0.0, ge=0, le=10, doc=(
        "sigma (px) of a Gaussian pre-smoothing of the grey frame (0: none, as in the chapter). Smoothing "
        "widens the SSIM peak: more tolerant to noise and small deformations, less precise."))
    history_prior_sd: float = param(0.25, gt=0, le=1, doc=(
        "Spread of the loss test's prior on the target's score before any frame is learned: the template "
        "scores 1 against itself, but a frame later a real target's SSIM is typically 0.6-0.9."))
    score_sd_floor: float = param(0.05, gt=0, le=1, doc=(
        "Floor on the spreads of the target's and the background's score distributions in the loss test. "
        "A fixed template's SSIM varies more from frame to frame than a colour histogram's rho."))


def reference_shape(w: float, h: float, template_pixels: int) -> tuple[tuple[int, int], float]:
    """``((rows, cols), pitch)``: the reference patch of a ``w x h`` box with at most ``template_pixels``
    pixels (at least 12 per side) and the frame pixels per reference pixel."""
    area = w * h
    f = min(1.0, math.sqrt(template_pixels / area)) if area > 0 else 1.0
    tw, th = max(12, int(round(w * f))), max(12, int(round(h * f)))
    return (th, tw), w / tw


def smoothed_gray(frame: np.ndarray, smooth: float) -> np.ndarray:
    """Grey frame, pre-smoothed by ``smooth`` (a wider SSIM peak, less sensitive to noise and misalignment)."""
    g = S.to_gray(frame)
    if smooth > 0:
        g = cv2.GaussianBlur(g, (0, 0), smooth)
    return g


def background_grid(width: int, height: int, centre, size, n: int) -> np.ndarray:
    """``(M, 2)`` centres ``(x, y)`` of about ``n`` grid positions over the frame, away from the target.

    A position is kept when it is at least one target size from ``centre`` on some axis.
    """
    nx = max(2, int(math.sqrt(n * width / height)))
    ny = max(2, int(math.ceil(n / nx)))
    gx, gy = np.meshgrid((np.arange(nx) + 0.5) * width / nx, (np.arange(ny) + 0.5) * height / ny)
    far = (np.abs(gx - centre[0]) >= size[0]) | (np.abs(gy - centre[1]) >= size[1])
    return np.column_stack([gx[far], gy[far]])
