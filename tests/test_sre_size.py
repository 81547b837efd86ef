"""scripts/sre_size.py: the side ratio a tracker holds from a perturbed first box."""

from __future__ import annotations

import numpy as np

from pftrack.synth import Scene, simple_scene

from .conftest import load_script


def test_a_tight_start_is_read_as_a_small_side_ratio_and_the_truth_as_one():
    ss = load_script("sre_size")
    pairs = [(f, tr.boxes[0]) for f, tr in Scene(simple_scene(0, n_frames=30))]
    frames = [f for f, _ in pairs]
    gt = np.array([b for _, b in pairs], dtype=float)
    truth, m_truth = ss.size_run(frames, gt, "template", -1)  # the template tracker keeps its first box's size
    tight, m_tight = ss.size_run(frames, gt, "template", 8)   # SRE's scale 0.8
    assert len(truth) == len(tight) == 29
    assert np.allclose(truth, 1.0, atol=0.05) and np.allclose(tight, 0.8, atol=0.05)
    assert m_truth > 0.9 and 0.6 < m_tight < 0.68   # 0.8 of the side, centred: IoU 0.64
    assert ss.iou((0, 0, 10, 10), (5, 0, 10, 10)) == 1 / 3
