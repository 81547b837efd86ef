"""``acquire_shape_step``: while searching, the structural score of the candidate to acquire is the best over the
3 x 3 shapes around its box, so a target that comes back with another shape is not refused by the structure."""

from __future__ import annotations

import numpy as np
import pytest

import pftrack
from pftrack.synth import Scene
from pftrack.synth.scenes import SceneSpec, Target


def _tracker(step: float):
    """fusion-pf started on a two-colour textured target (50 x 90 px) of a flat scene, then put in search mode."""
    spec = SceneSpec(n_frames=2, seed=5, targets=(Target(path=((0, 160.0, 120.0),), size=(50.0, 90.0)),),
                     background="flat")
    scene = Scene(spec)
    frame = scene.frames()[0]
    t = pftrack.create_tracker("fusion-pf", seed=0, acquire_shape_step=step)
    t.init(frame, tuple(scene.groundtruth()[0]))
    t.mode = "searching"
    return t, frame


def _structure(t, frame, ellipse) -> float:
    """The structural score (second column, (NCC + 1) / 2) the loss test gets for one candidate ellipse."""
    e = np.array([ellipse], dtype=np.float64)
    return float(t._loss_scores(frame, e, np.array([0.9]), (0, 0, frame.shape[1], frame.shape[0]))[0, 1])


def test_the_candidates_structure_is_the_best_of_nine_shapes():
    """A candidate on the target but 30 % too wide and 20 % too short scores the target's NCC at the nearest of
    the 3 x 3 shapes: above its own shape's score with the option, the best of a direct scoring of the nine
    shapes, and next to the same with and without the option on the right shape."""
    on, frame = _tracker(0.25)
    off, _ = _tracker(0.0)
    wrong = (160.0, 120.0, 25.0 * 1.3, 45.0 / 1.2)
    right = (160.0, 120.0, 25.0, 45.0)
    f = (1 / 1.25, 1.0, 1.25)
    direct = max(on.structure.scores(frame, None, np.array([[160.0, 120.0, wrong[2] * a, wrong[3] * b]]))[0]
                 for a in f for b in f)
    # (the nine are scored on one block-averaged region that holds the largest, the direct scores each on its own)
    assert _structure(on, frame, wrong) == pytest.approx((direct + 1) / 2, abs=0.005)
    assert _structure(on, frame, wrong) > _structure(off, frame, wrong) + 0.05
    assert _structure(off, frame, right) <= _structure(on, frame, right) < _structure(off, frame, right) + 0.01
    assert _structure(off, frame, right) > 0.95  # (NCC + 1) / 2 of the target on its own first frame


def test_shapes_reaching_past_the_frame_are_not_tried():
    """Near the frame's edge, where the largest shape leaves the frame, the score is the candidate's own."""
    on, frame = _tracker(0.25)
    off, _ = _tracker(0.0)
    edge = (frame.shape[1] - 30.0, 120.0, 25.0 * 1.3, 45.0 / 1.2)
    assert _structure(on, frame, edge) == _structure(off, frame, edge)


def test_tracking_frames_are_untouched():
    """Only a search's single candidate is rescored: while tracking, the estimate's score is the same."""
    on, frame = _tracker(0.25)
    off, _ = _tracker(0.0)
    on.mode = off.mode = "tracking"
    wrong = (160.0, 120.0, 25.0 * 1.3, 45.0 / 1.2)
    assert _structure(on, frame, wrong) == _structure(off, frame, wrong)
