"""Probation after a weak re-acquisition (pftrack.trackers.probation) and the loss test's parts it uses."""

from __future__ import annotations

import numpy as np
import pytest

import pftrack
from pftrack.filtering.loss import FusedLoss, LossDetector


def _trained(det):
    det.reset(1.0)
    rng = np.random.default_rng(1)
    det.set_background(rng.normal(0.3, 0.05, (200, 2)) if isinstance(det, FusedLoss) else rng.normal(0.3, 0.05, 200))
    for _ in range(30):
        det.step(np.array([0.92, 0.9]) if isinstance(det, FusedLoss) else 0.92)
    return det


def _histories(det):
    members = det.members if isinstance(det, FusedLoss) else [det]
    return [(m.mu_t, m.var_t, m.unseen) for m in members]


@pytest.mark.parametrize("det", [LossDetector(lost_frames=3), FusedLoss(2, acquire_z=4.0, acquire_margin=2.0)])
def test_frozen_histories_learn_nothing_and_reset_thaws_them(det):
    _trained(det)
    before = _histories(det)
    det.frozen = True
    for s in (0.95, 0.8, 0.2):  # confident, doubtful and absent scores alike
        det.step(np.array([s, s]) if isinstance(det, FusedLoss) else s)
    assert _histories(det) == before
    det.frozen = False
    det.step(np.array([0.95, 0.95]) if isinstance(det, FusedLoss) else 0.95)
    assert _histories(det) != before
    det.frozen = True
    det.reset(1.0)
    assert not det.frozen


@pytest.mark.parametrize("det", [LossDetector(lost_frames=3), FusedLoss(2, acquire_z=4.0, acquire_margin=2.0)])
@pytest.mark.parametrize("s, log_prior", [(0.9, 0.0), (0.9, -30.0), (0.6, 0.0), (0.3, 0.0), (float("nan"), 0.0)])
def test_would_acquire_answers_as_acquire_without_changing_state(det, s, log_prior):
    _trained(det)
    score = np.array([s, s]) if isinstance(det, FusedLoss) else s
    state = (_histories(det), det.llr, det.lost, det.miss)
    ok, llr = det.would_acquire(score, log_prior)
    assert (_histories(det), det.llr, det.lost, det.miss) == state
    det.lost = True
    assert det.acquire(score, log_prior) == ok
    assert det.llr == pytest.approx(llr)


def test_probation_defaults_and_only_for_weak_acquisitions():
    assert pftrack.create_tracker("fusion-pf").params.probation_llr == 15.0
    assert pftrack.create_tracker("color-pf").params.probation_llr == 15.0
    assert pftrack.create_tracker("local-motion-pf").params.probation_llr == 0.0  # off there
    t = pftrack.create_tracker("color-pf", seed=0, probation_llr=0.0)
    frame = np.full((120, 160, 3), 90, np.uint8)
    frame[40:70, 50:80] = (30, 40, 200)
    t.init(frame, (50, 40, 30, 30))
    t.loss.llr = 2.0
    t._begin_probation(None)
    assert not t.on_probation and not t.loss.frozen
    on = pftrack.create_tracker("color-pf", seed=0, probation_llr=6.0, probation_frames=4)
    on.init(frame, (50, 40, 30, 30))
    lost_at = (0, np.array([65.0, 55.0]), np.zeros(2))
    on.loss.llr = 7.0  # a strong acquisition
    on._begin_probation(lost_at)
    assert not on.on_probation
    on.loss.llr = 2.0  # a weak one: frozen, and the search beside it keeps the prior of the loss
    on._begin_probation(lost_at)
    assert on.on_probation and on.loss.frozen and on._lost_at is lost_at
    # the first frame whose ratio reaches probation_llr ends it (the target is in view: the ratio is high)
    on.update(frame)
    assert not on.on_probation and not on.loss.frozen


def _blue_square_frames(n):
    """``n`` noisy frames of a still blue square on grey (seeded)."""
    rng = np.random.default_rng(0)
    frames = []
    for _ in range(n):
        f = np.clip(rng.normal(90, 20, (120, 160, 3)), 0, 255).astype(np.uint8)
        f[40:70, 50:80] = np.clip(rng.normal((30, 40, 200), 25, (30, 30, 3)), 0, 255).astype(np.uint8)
        frames.append(f)
    return frames


def test_on_probation_nothing_is_learned_and_it_ends_after_probation_frames():
    frames = _blue_square_frames(6)
    # a ratio no frame reaches (the ratio is clipped at 30): only probation_frames ends the probation
    t = pftrack.create_tracker("color-pf", seed=0, probation_llr=50.0, probation_frames=4, probation_interval=2)
    t.init(frames[0], (50, 40, 30, 30))
    t.loss.llr = 2.0
    t._begin_probation(None)
    searches = []
    search = t._search_candidates
    t._search_candidates = lambda frame, exclude=None: searches.append(exclude) or search(frame, exclude)
    q, hist = t.q.copy(), (t.loss.mu_t, t.loss.var_t)
    for f in frames[1:4]:
        st = t.update(f)
        assert t.on_probation and not st.lost and st.info["probation"]
    np.testing.assert_array_equal(t.q, q)
    assert (t.loss.mu_t, t.loss.var_t) == hist
    t.update(frames[4])
    assert not t.on_probation
    assert len(searches) == 1 and searches[0] is not None  # beside the track, on every 2nd probation frame
    st = t.update(frames[5])
    assert not np.array_equal(t.q, q) and "probation" not in st.info  # learning resumed


def test_probation_lost_llr_reports_a_doubtful_candidate_absent_while_following_it():
    """``probation_lost_llr``: a frame on probation whose ratio stays below it is reported lost (score at most 0.5)
    while the candidate is followed as before (the same boxes); off (0), the candidate is reported as the target."""
    frames = _blue_square_frames(5)
    runs = {}
    for t_llr in (0.0, 40.0):  # 40: above any ratio (clipped at 30), so every frame on probation is doubtful
        t = pftrack.create_tracker("color-pf", seed=0, probation_llr=50.0, probation_frames=10,
                                   probation_lost_llr=t_llr)
        t.init(frames[0], (50, 40, 30, 30))
        t.loss.llr = 2.0
        t._begin_probation(None)
        runs[t_llr] = [t.update(f) for f in frames[1:]]
    assert all(st.info["probation"] for st in runs[40.0])
    assert all(st.lost and st.score <= 0.5 and st.info["doubtful"] for st in runs[40.0])
    assert not any(st.lost for st in runs[0.0])
    assert [st.box for st in runs[40.0]] == [st.box for st in runs[0.0]]
    # scoped to exits: a probation that did not follow an exit through the edge reports the candidate
    scoped = pftrack.create_tracker("color-pf", seed=0, probation_llr=50.0, probation_frames=10,
                                    probation_lost_llr=40.0, probation_lost_exit_only=True)
    scoped.init(frames[0], (50, 40, 30, 30))
    scoped.loss.llr = 2.0
    scoped._begin_probation(None, exited=False)
    assert scoped.on_probation and not scoped._doubtful()
    scoped._begin_probation(None, exited=True)
    assert scoped._doubtful() and scoped.update(frames[1]).lost


@pytest.mark.parametrize("kind, seed", [("vanish", 315), ("teleport", 301), ("teleport", 317)])
def test_fusion_pf_reacquires_after_a_weak_wrong_acquisition_with_probation(kind, seed):
    """Fresh scenes (seeds of neither split, picked from a run over seeds 300-319 as the scenes where probation makes
    the difference for fusion-pf): without probation the target is not re-acquired within 15 frames of coming
    back; with it (the default) it is. Picked with the grey-patch structural cue, which they keep: two of them are
    grey, where the gradient cue (the default on grey input since) re-acquires without probation too. Picked before
    acquire_shape_step too, which they leave off: with it (the default since) teleport 317's target is taken on the
    same frame, but 12-15 frames later the box covers it at IoU 0.47 where it was 0.51, so it does not count as
    re-acquired, with or without probation."""
    from pftrack.synth import teleport_scene, vanish_scene

    from .conftest import lost_flag_run

    spec = {"vanish": vanish_scene, "teleport": teleport_scene}[kind](seed)
    # the settings the scenes were picked with (color_normalize="none": before the still view's gain; mass_size 0:
    # before the size read from the map's mass)
    then = {"static_ncc": 0.0, "structure_features": "ncc", "acquire_shape_step": 0.0, "color_normalize": "none",
            "mass_size": 0.0}
    off = lost_flag_run(spec, "fusion-pf", probation_llr=0.0, **then)
    on = lost_flag_run(spec, "fusion-pf", **then)
    assert off.reappearances == on.reappearances == 1
    assert off.reacquired == 0 and on.reacquired == 1
