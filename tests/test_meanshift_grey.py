"""The mean-shift baselines on grey video: the colour cue picks its features from the input (color_space="auto")."""

from __future__ import annotations

import numpy as np
import pytest

import pftrack
from pftrack.eval.metrics import ope_scores
from pftrack.synth import Scene, simple_scene

from .conftest import grey_frames


def _auc(name, frames, gt, **params):
    t = pftrack.create_tracker(name, **params)
    t.init(frames[0], tuple(gt[0]))
    boxes = np.array([gt[0]] + [t.update(f).box for f in frames[1:]], float)
    return ope_scores(boxes, gt).auc


@pytest.mark.parametrize("name", ["meanshift", "kalman-meanshift"])
def test_mean_shift_follows_a_grey_target_with_grey_features(name):
    """On grey frames the RGB histogram keeps 8 grey levels and mean shift drifts (AUC 0.12-0.71 on these
    scenes); equalised intensity x gradient orientation, as color-pf's, keeps the target (0.65-0.88)."""
    auto, rgb = [], []
    for seed in (0, 3):
        sc = Scene(simple_scene(seed, n_frames=40))
        frames, gt = sc.frames(), sc.groundtruth(0)
        grey = grey_frames(frames)
        auto.append(_auc(name, grey, gt))
        rgb.append(_auc(name, grey, gt, color_space="rgb"))
        # colour frames: "auto" is RGB, the same boxes as before
        assert _auc(name, frames, gt) == _auc(name, frames, gt, color_space="rgb")
    assert min(auto) > 0.6 and np.mean(auto) > np.mean(rgb) + 0.1, (auto, rgb)
