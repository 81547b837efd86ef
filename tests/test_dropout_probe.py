"""scripts/dropout_probe.py: scenes of a camera that drops out, fades or freezes, and what the probe reads."""

from __future__ import annotations

import numpy as np
import pytest

from .conftest import load_script


def test_the_scenes_blank_fade_and_freeze_where_they_say():
    dp = load_script("dropout_probe")
    frames, boxes, blank = dp.scene(0, "black")
    assert len(frames) == dp.N_FRAMES and blank.sum() == 10 and blank[100:110].all()
    assert all(frames[t].max() == 0 for t in range(100, 110)) and frames[110].max() > 0
    frames, boxes, blank = dp.scene(0, "frozen")
    assert not blank.any() and all(np.array_equal(frames[t], frames[99]) for t in range(100, 110))
    assert boxes[105] == boxes[99] and boxes[110] != boxes[99]
    frames, boxes, blank = dp.scene(0, "fade")
    assert blank[118:123].all() and not blank[:117].any() and frames[120].max() == 0
    x, y, w, h = boxes[0]
    assert np.array_equal(frames[0][y + 2, x + 2], [30, 40, 220])  # the box is drawn where its truth says
    with pytest.raises(ValueError):
        dp.scene(0, "snow")


def test_a_tracker_comes_through_a_blackout_and_raises_its_flag_on_it():
    dp = load_script("dropout_probe")
    before, width, after, lost_visible, lost_blank = dp.run("color-pf", "black", 0)
    assert before > 0.9 and after > 0.9 and lost_visible < 0.05 and lost_blank > 0.7
