"""Re-acquisition by persistence (pftrack.trackers.persistence; ``persist_frames``)."""

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.filtering.loss import FusedLoss, LossDetector
from pftrack.trackers.persistence import START_RADIUS, plausible, streak_step

from .conftest import grey_frames, shared_sequence


def _fused(mu_t=(0.95, 0.88), sd_t=(0.03, 0.06), background=(0.85, 0.55)):
    """A two-cue loss test (histogram, structure) with set target histories and backgrounds."""
    loss = FusedLoss(2)
    rng = np.random.default_rng(0)
    loss.set_background(np.column_stack([rng.normal(b, 0.03, 200) for b in background]))
    for m, mu, sd in zip(loss.members, mu_t, sd_t):
        m.mu_t, m.var_t = mu, sd * sd
    return loss


def test_plausible_asks_the_histogram_and_bounds_every_cue():
    loss = _fused()
    assert plausible(loss, [0.94, 0.80], z_max=2.5)           # structure 1.3 spreads below its history
    assert not plausible(loss, [0.94, 0.70], z_max=2.5)       # structure 3 spreads below
    assert plausible(loss, [0.94, 0.70], z_max=3.5)
    assert not plausible(loss, [0.86, 0.86], z_max=2.5)       # the histogram calls it background
    assert not plausible(loss, [np.nan, 0.86], z_max=2.5)
    assert plausible(loss, [0.94, np.nan], z_max=2.5)         # a cue without a score says nothing
    single = LossDetector()
    single.set_background(np.random.default_rng(1).normal(0.6, 0.05, 200))
    single.mu_t, single.var_t = 0.9, 0.05 ** 2
    assert plausible(single, 0.85, z_max=2.5) and not plausible(single, 0.7, z_max=2.5)


def test_a_streak_follows_one_place_near_the_loss():
    size, lost_at = (10.0, 20.0), (100.0, 100.0)
    s = streak_step(None, (120.0, 90.0), size, lost_at, True)           # starts: 2 half-axes from the loss
    assert s == (1, 120.0, 90.0)
    s = streak_step(s, (128.0, 105.0), size, lost_at, True)             # within one half-axis of the last
    assert s[0] == 2
    assert streak_step(s, (115.0, 130.0), size, lost_at, True) == (1, 115.0, 130.0)  # a jump: starts again
    far = (100.0 + (START_RADIUS + 1.5) * size[0], 100.0)
    assert streak_step(s, far, size, lost_at, True) is None             # a jump away from the loss: none
    assert streak_step(s, (128.0, 105.0), size, lost_at, False) is None  # not plausible: ends
    assert streak_step(None, (100.0, 100.0), size, None, True) is None  # nowhere to start from


@pytest.mark.shared_data
@pytest.mark.parametrize("seed", [0, 1])
def test_a_changed_target_in_grey_video_is_taken_again(seed):
    """Grey ``otb_dragonbaby`` (a tune sequence): the baby turns after six frames and ``fusion-pf`` loses it. Its
    search keeps finding the baby, but the structural history, learned on those six frames, refuses it, and without
    persistence the tracker searches on 106 of the 112 frames. With it (the default) the tracker starts again on the
    baby, and the search shrinks to less than half of that. Measured with the grey-patch structural cue; the
    gradient cue (the default on grey input) loses the turning baby on far fewer frames, with or without it."""
    path = shared_sequence("otb_dragonbaby")
    frames = grey_frames(list(pftrack.open_source(str(path))))
    gt = np.array(pftrack.io.datasets.read_sequence(path).groundtruth, dtype=np.float64)

    def lost_frames(**params):
        t = pftrack.create_tracker("fusion-pf", seed=seed, **params)
        t.init(frames[0], tuple(gt[0]))
        states = [t.update(f) for f in frames[1:]]
        return sum(st.lost for st in states), sum(bool(st.info.get("persist")) for st in states)

    off, none = lost_frames(persist_frames=0, structure_features="ncc")
    on, restarts = lost_frames(structure_features="ncc")
    assert none == 0 and off >= 100
    assert restarts >= 1 and on < 0.5 * off, (on, off)
    assert lost_frames()[0] < 0.5 * off


def test_a_still_piece_of_the_scene_is_not_taken():
    """A candidate whose streak is complete but whose grey patch is unchanged since the streak began is a piece of
    the scene (an occluder's edge near the place of the loss): no restart. The same candidate on a frame where that
    patch changed is taken."""
    rng = np.random.default_rng(3)
    scene = np.clip(rng.normal(120, 30, (160, 200)), 0, 255).astype(np.uint8)
    scene = cv2.GaussianBlur(scene, (5, 5), 1.0)
    frame = cv2.cvtColor(scene, cv2.COLOR_GRAY2BGR)
    t = pftrack.create_tracker("fusion-pf", seed=0, persist_frames=2)
    t.init(frame, (80, 60, 30, 40))
    t._lost_at = (0, np.array([95.0, 80.0]), np.zeros(2))
    t.size = (15.0, 20.0)
    t.loss = _fused()
    good = [0.95, 0.88]                                          # scores as the target's histories: plausible
    ell = np.array([95.0, 80.0, 15.0, 20.0])
    assert t._persist_step(frame, ell, good) is None             # the streak starts
    assert t._persist_step(frame, ell, good) is None             # complete, but the patch did not change
    changed = frame.copy()
    changed[60:100, 80:110] = np.flipud(changed[60:100, 80:110])
    assert t._persist_step(frame, ell, good) is None             # a new streak starts on the unchanged frame
    state = t._persist_step(changed, ell, good)
    assert state is not None and not state.lost and state.info["persist"]
    assert np.allclose(state.box, (80, 60, 30, 40), atol=1.0)
