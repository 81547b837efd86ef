"""scripts/fast_target_probe.py: scenes of a target moving fast from the first frame, and what the probe reads."""

from __future__ import annotations

import numpy as np
import pytest

from .conftest import load_script


@pytest.mark.parametrize("mode", ["bounce", "turns"])
def test_the_box_moves_at_the_asked_speed_and_stays_in_the_frame(mode):
    fp = load_script("fast_target_probe")
    frames, boxes = fp.scene(3, 8.0, mode)
    xy = np.array([b[:2] for b in boxes], float)
    steps = np.hypot(*np.diff(xy, axis=0).T)
    assert np.median(steps) == pytest.approx(8.0, abs=1.0)  # whole pixels of a speed of 8 a frame
    assert (xy[:, 0] >= 0).all() and (xy[:, 0] <= fp.W - fp.TW).all() and (xy[:, 1] <= fp.H - fp.TH).all()
    x, y, w, h = boxes[10]
    assert np.array_equal(frames[10][y + 2, x + 2], [40, 60, 210])  # drawn where its truth says
    with pytest.raises(ValueError):
        fp.scene(0, 8.0, "zigzag")


def test_a_slow_target_is_tracked_throughout():
    fp = load_script("fast_target_probe")
    assert fp.tracked_share("color-pf", 3.0, "bounce", 0) > 0.9
