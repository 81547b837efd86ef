"""A target of one flat colour: the fused loss test's structural history starts from the target's scores when its
prior (a self-match, 1) does not hold for ``SEED_AFTER`` confident frames (``FusedLoss._learn``).

The grey-patch correlation of a patch of one colour is 0 on every frame (with sensor noise, about 0): the
structural cue scores such a target at 0.5, far below the prior of 1 its history started from. Before, that history
never learned (every score was more than ``learn_z`` spreads below it, and its own ratio said background), so the
cue vetoed every model update and every re-acquisition: ``fusion-pf`` lost a plain red box after its first
occlusion and never found it again, while ``color-pf`` did every time.
"""

from __future__ import annotations

import numpy as np
import pytest

from pftrack.filtering.loss import SEED_AFTER, FusedLoss
from pftrack.trackers.registry import create_tracker

from .conftest import HIDDEN_BOX_START, HIDDEN_FRAMES, HIDDEN_PERIOD, hidden_box_frame

H, W = 120, 160
PERIOD, HIDDEN = HIDDEN_PERIOD, HIDDEN_FRAMES


def _fused(rng) -> FusedLoss:
    loss = FusedLoss(2, cue_clip=10.0, cue_floor=2.0, acquire_z=4.0)  # fusion-pf's bounds
    bg = np.column_stack([rng.normal(0.1, 0.03, 300), rng.normal(0.5, 0.01, 300)])
    loss.set_background(bg)
    return loss


def test_a_cue_that_never_scores_near_its_prior_starts_its_history_from_its_refused_scores():
    rng = np.random.default_rng(0)
    loss = _fused(rng)
    colour, structure = loss.members
    scores = [0.50, 0.49, 0.52, 0.50, 0.51, 0.48, 0.50, 0.53, 0.50, 0.47]
    for k, v in enumerate(scores[:-1]):  # colour far above its background, the structure at its background's level
        loss.step([0.97, v])
        assert structure.mu_t == 1.0 and not structure.learned  # refused, and still the prior
        assert not loss.confident([0.97, v])  # which vetoes the models' update
    loss.step([0.97, scores[-1]])
    assert structure.learned and structure.mu_t == pytest.approx(float(np.median(scores)))
    assert SEED_AFTER == len(scores)
    assert colour.mu_t < 1.0  # the colour learned as usual all along
    for _ in range(20):
        loss.step([0.97, 0.5])
    assert structure.evaluate(0.5) == 0.0  # a cue at its background's level adds no evidence
    assert loss.confident([0.97, 0.5])  # and vetoes nothing: the models update
    loss.lost = True
    assert loss.acquire([0.97, 0.5])  # a candidate that matches in colour is taken back


def test_a_history_that_learned_keeps_the_usual_rule():
    rng = np.random.default_rng(1)
    loss = _fused(rng)
    structure = loss.members[1]
    loss.step([0.97, 0.95])  # the first confident score is learned as usual (near the prior)
    mu = structure.mu_t
    assert mu == pytest.approx(1.0 + 0.05 * (0.95 - 1.0))
    for _ in range(2 * SEED_AFTER):  # later, scores far below the history (a cover) are not learned, nor seeded
        loss.step([0.97, 0.5])
    assert structure.mu_t == mu


def test_no_seed_before_a_confident_frame_nor_while_frozen():
    rng = np.random.default_rng(2)
    loss = _fused(rng)
    structure = loss.members[1]
    for _ in range(2 * SEED_AFTER):  # the colour sees background: the fused ratio is not confident
        loss.step([0.1, 0.5])
    assert structure.mu_t == 1.0 and not structure.learned and not structure.refused
    loss.frozen = True  # a candidate on probation learns nothing
    for _ in range(2 * SEED_AFTER):
        loss.step([0.97, 0.5])
    assert structure.mu_t == 1.0 and not structure.learned


@pytest.mark.parametrize("noise", [0.0, 2.0])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_fusion_pf_finds_a_flat_target_again_after_each_occlusion(seed, noise):
    rng = np.random.default_rng(100 + seed)
    bg = rng.integers(0, 255, (H, W, 3), dtype=np.uint8)
    tracker = create_tracker("fusion-pf", seed=seed)
    tracker.init(hidden_box_frame(bg, 0, noise, rng), HIDDEN_BOX_START)
    lost = np.array([tracker.update(hidden_box_frame(bg, t, noise, rng)).lost for t in range(1, 2 * PERIOD)])
    hidden = np.array([t % PERIOD >= PERIOD - HIDDEN for t in range(1, 2 * PERIOD)])
    assert lost[hidden].mean() > 0.9  # raised while the box is hidden
    second = np.arange(1, 2 * PERIOD) >= PERIOD + 15  # the second cycle, from 15 frames after the return
    assert lost[second & ~hidden].mean() < 0.05  # and found again after it came back
