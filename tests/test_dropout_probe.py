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


def test_local_motion_keeps_the_size_of_a_small_two_colour_box():
    """Kristan et al.'s size walk (at most 15 % a step) let the box shrink onto the edge between the two colours,
    where a small box holds both in the model's proportion; the default walk (5 %) keeps it on seeds 0-3 (on seed 4
    it still shrinks, to 8 px: docs/local-motion.md)."""
    dp = load_script("dropout_probe")
    now = np.array([dp.run("local-motion-pf", "none", seed) for seed in range(4)])
    paper = np.array([dp.run("local-motion-pf[max_size_change=0.15]", "none", seed) for seed in range(4)])
    assert now[:, 2].mean() > 0.9 and np.median(now[:, 1]) > 11  # IoU >= 0.5 after frame 150; the median width
    assert paper[:, 2].mean() < 0.2 and np.median(paper[:, 1]) < 8  # the paper's walk: the negative control
