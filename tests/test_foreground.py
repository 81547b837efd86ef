"""MOG2 foreground with its shadow test only where it can work (pftrack.cues.foreground)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from pftrack.cues.foreground import GREY_SHADOW_THRESHOLD, OPENCV_SHADOW_THRESHOLD, Foreground
from pftrack.multi.detectors import MOG2Detector, MOG2DetectorParams


def _frames(ratio: float, *, grey: bool, n: int = 40, seed: int = 0):
    """A textured ground (mean 160) and, from frame 25 on, a 40-px square moving right by 6 px a frame (at x = 90 in
    the last frame) whose brightness is ``ratio`` times the ground's below it: in grey, or in colour with the
    ground's chromaticity (a darker copy, as a cast shadow is)."""
    rng = np.random.default_rng(seed)
    ground = np.clip(cv2.GaussianBlur(rng.normal(160, 40, (120, 160, 3)), (0, 0), 2), 0, 255)
    ground[..., 0] *= 0.7 if not grey else 1.0  # a colour ground unless grey
    if grey:
        ground[..., 1] = ground[..., 2] = ground[..., 0]
    out = []
    for t in range(n):
        f = ground.copy()
        if t >= 25:
            x0 = 6 + 6 * (t - 25)
            f[40:80, x0:x0 + 40] *= ratio
        noise = rng.normal(0, 2, (120, 160, 1 if grey else 3))
        out.append(np.clip(f + noise, 0, 255).astype(np.uint8))
    return out


def _square_fraction(fg_masks) -> float:
    return float(fg_masks[-1][40:80, 90:130].mean())  # the last frame's square


@pytest.mark.parametrize("ratio,expect_default,expect_opencv", [(0.65, True, False), (0.3, True, True)])
def test_grey_objects_up_to_twice_as_dark_as_the_ground_are_foreground(ratio, expect_default, expect_opencv):
    """OpenCV's threshold (0.5) calls a grey square at 0.65 of the ground's brightness a shadow; the grey
    threshold (0.85 by default, 1 for none) keeps it. A much darker square (0.3) is foreground either way."""
    frames = _frames(ratio, grey=True)
    for tau, expected in ((GREY_SHADOW_THRESHOLD, expect_default), (1.0, expect_default),
                          (OPENCV_SHADOW_THRESHOLD, expect_opencv)):
        fg = Foreground(grey_shadow_threshold=tau)
        masks = [fg.apply(f) for f in frames]
        assert (_square_fraction(masks) > 0.5) == expected, (ratio, tau, _square_fraction(masks))
        assert _square_fraction(masks) > 0.5 or _square_fraction(masks) < 0.05
        assert fg.grey == (tau != OPENCV_SHADOW_THRESHOLD)


def test_colour_frames_keep_mog2s_shadow_test_bit_for_bit():
    """On colour frames the mask is MOG2's foreground label, whatever the grey threshold: a darker copy of the
    ground (a shadow) stays background."""
    frames = _frames(0.65, grey=False)
    ref = cv2.createBackgroundSubtractorMOG2(history=500, varThreshold=16.0, detectShadows=True)
    fg = Foreground()
    for f in frames:
        np.testing.assert_array_equal(fg.apply(f), (ref.apply(f) == 255).astype(np.uint8))
    assert not fg.grey
    assert _square_fraction([fg.apply(frames[-1])]) < 0.1


def test_threshold_is_validated():
    with pytest.raises(ValueError):
        Foreground(grey_shadow_threshold=1.5)


def test_mog2_detector_finds_a_mid_grey_target_on_grey_video():
    frames = _frames(0.65, grey=True)
    boxes = {}
    for tau in (GREY_SHADOW_THRESHOLD, OPENCV_SHADOW_THRESHOLD):
        det = MOG2Detector(MOG2DetectorParams(grey_shadow_threshold=tau, downscale=1, min_area=200))
        boxes[tau] = [det(f) for f in frames][-1]
    assert MOG2DetectorParams().grey_shadow_threshold == GREY_SHADOW_THRESHOLD
    assert len(boxes[GREY_SHADOW_THRESHOLD]) == 1
    x, y, w, h = boxes[GREY_SHADOW_THRESHOLD][0][:4]
    assert max(abs(x - 90), abs(y - 40), abs(w - 40), abs(h - 40)) <= 2  # the last frame's square
    assert len(boxes[OPENCV_SHADOW_THRESHOLD]) == 0  # taken for a shadow


def test_rate_k_sets_mog2s_learning_schedule_and_keeps_a_still_object_foreground_longer():
    """rate_k = 2 is OpenCV's own schedule (the same masks); another k learns at 1 / min(k n, history), which is
    what OpenCV's MOG2 does when given that rate on each frame; a slower start keeps an object that stops in view
    foreground for more frames."""
    rng = np.random.default_rng(2)
    ground = np.clip(rng.normal(120, 10, (60, 80, 3)), 0, 255).astype(np.uint8)
    frames = []
    for t in range(60):
        f = ground.copy()
        x = min(10 + 3 * t, 40)  # moves in, then stands still from frame 10 on
        f[20:40, x:x + 15] = (30, 40, 200)
        frames.append(f)
    ref = cv2.createBackgroundSubtractorMOG2(history=100, varThreshold=16.0, detectShadows=True)
    two = Foreground(100, rate_k=2.0)
    for f in frames:
        np.testing.assert_array_equal(two.apply(f), (ref.apply(f) == 255).astype(np.uint8))
    ref = cv2.createBackgroundSubtractorMOG2(history=100, varThreshold=16.0, detectShadows=True)
    eight = Foreground(100, rate_k=8.0)
    still = {2: 0, 8: 0}
    two = Foreground(100)
    for n, f in enumerate(frames, 1):
        want = (ref.apply(f, learningRate=1.0 / min(8 * n, 100)) == 255).astype(np.uint8)
        got = eight.apply(f)
        np.testing.assert_array_equal(got, want)
        if n > 10:
            still[8] += int(got[22:38, 42:53].mean() > 0.5)
            still[2] += int(two.apply(f)[22:38, 42:53].mean() > 0.5)
        else:
            two.apply(f)
    assert still[8] > still[2] + 5, still
    with pytest.raises(ValueError):
        Foreground(rate_k=0)
