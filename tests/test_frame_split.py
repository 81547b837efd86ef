"""scripts/frame_split.py: a tracked frame's time split between the compiled kernels (and OpenCV) and the rest."""

from __future__ import annotations

import cv2
import numpy as np

import pftrack.cues.color as color_module

from .conftest import load_script


def _clip(n=12):
    rng = np.random.default_rng(3)
    frames = []
    for t in range(n):
        f = rng.integers(60, 140, (120, 160, 3), dtype=np.uint8)
        f[40 + t:70 + t, 50 + 2 * t:80 + 2 * t] = (40, 60, 200)
        frames.append(f)
    return frames


def test_the_split_adds_up_and_names_the_kernels():
    fs = load_script("frame_split")
    split = fs.frame_split(_clip(), 0, (50.0, 40.0, 30.0, 30.0), "color-pf", 0)
    assert split.frames == 11
    assert 0 < split.wrapped < split.total
    assert abs(sum(split.per_name.values()) - split.wrapped) < 1e-9
    assert split.calls["_ellipse_rho_numba"] >= 11  # the particles' colour coefficients, once a frame at least
    assert all(split.calls[k] > 0 for k in split.per_name)


def test_the_timers_are_removed_afterwards():
    fs = load_script("frame_split")
    kernel, resize = color_module._ellipse_rho_numba, cv2.resize
    with fs.timed_calls(fs.Split()):
        assert color_module._ellipse_rho_numba is not kernel and cv2.resize is not resize
    assert color_module._ellipse_rho_numba is kernel and cv2.resize is resize


def test_each_wrapped_call_is_counted_once():
    fs = load_script("frame_split")
    split = fs.Split()
    img = np.zeros((8, 8), np.uint8)
    with fs.timed_calls(split):
        cv2.resize(img, (4, 4))
        cv2.resize(cv2.GaussianBlur(img, (3, 3), 0), (4, 4))
    assert split.calls["cv2.resize"] == 2 and split.calls["cv2.GaussianBlur"] == 1
