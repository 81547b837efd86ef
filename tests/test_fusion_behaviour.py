"""fusion-pf and color-pf with the structural cue: the refined search, camouflage, the fused lost flag over varied
scenes, the bundled clip, automatic initialisation and relit colour."""

from __future__ import annotations

import numpy as np
import pytest

import pftrack
from pftrack.geometry import center_error
from pftrack.synth import camouflage_scene, leave_scene, vanish_scene

from .conftest import bundled_clip, cached_scene
from .test_structure_fusion import _texture


def _searching_after(name, frames, box, **params):
    """A tracker run on ``frames[:6]`` and then put into search mode, as if the loss were declared on frame 5."""
    t = pftrack.create_tracker(name, seed=5, **params)
    t.init(frames[0], box)
    for f in frames[1:6]:
        t.update(f)
    t.lost, t.mode = True, "searching"
    t.loss.lost = True
    t._search_since = t.frame_index
    return t


def test_refined_search_layer_samples_the_best_mode_and_is_reproducible():
    """search_refine: the second layer is drawn from the first layer's posterior and moved by a quarter of the
    half-axes, so its samples gather around the best first-layer sample; the search stays seeded."""
    scene = cached_scene(vanish_scene(3))
    frames, gt = scene.frames(), scene.groundtruth(0)

    def run(refine):
        t = _searching_after("fusion-pf", frames, tuple(gt[0]), search_refine=refine)
        return t, t._search(frames[6])

    t0, _ = run(0.0)
    t1, st1 = run(1.0)
    n0 = len(t0._search_states)
    assert len(t1._search_states) == 2 * n0
    first, second = t1._search_states[:n0], t1._search_states[n0:]
    ll_first, ll_second = t1._search_loglik[:n0], t1._search_loglik[n0:]
    # each refined sample is a first-layer sample moved by N(0, (h/4)^2): within 4 sd of one of them
    d = np.hypot(second[:, None, 0] - first[None, :, 0], second[:, None, 1] - first[None, :, 1]).min(axis=1)
    assert np.all(d <= first[:, 4:6].max())
    # drawn from the posterior: the refined layer sits on the first layer's best modes
    assert np.median(ll_second) > np.quantile(ll_first, 0.9)
    # the first layer's scores survive the second layer's scoring (the cue reuses its result buffers)
    ell = t1._ellipses(first)
    rho, tot, feats = t1._search_rho(frames[6], ell)
    want_rho, want_tot = rho.copy(), tot.copy()
    ll = t1._search_log_lik(frames[6], first, t1._log_lik(rho, tot), feats)
    out = t1._refine_layer(frames[6], first, ell, rho, tot, ll, None, feats)
    np.testing.assert_array_equal(out[2][:n0], want_rho)
    np.testing.assert_array_equal(out[3][:n0], want_tot)
    t2, st2 = run(1.0)
    np.testing.assert_array_equal(t1._search_states, t2._search_states)
    assert st1.box == st2.box


def test_color_pf_refines_its_search_on_grey_input_only():
    """grey_search_refine: color-pf's search gets the refined layer on grey input (0.5 of the first layer) and
    none on colour input (search_refine 0); None leaves search_refine in charge whatever the input."""
    def search_sizes(gray, **kw):
        scene = cached_scene(vanish_scene(3, gray=1.0 if gray else 0.0))
        frames, gt = scene.frames(), scene.groundtruth(0)
        t = _searching_after("color-pf", frames, tuple(gt[0]), search_particles=200, **kw)
        return t.cue.color_space, len(t._search_candidates(frames[6]).states)

    assert search_sizes(True) == ("gray", 300)
    assert search_sizes(False)[1] == 200 and search_sizes(False)[0] != "gray"
    assert search_sizes(True, grey_search_refine=None) == ("gray", 200)
    assert search_sizes(False, search_refine=1.0, grey_search_refine=0.0)[1] == 400
    assert pftrack.create_tracker("fusion-pf").params.grey_search_refine is None


def _track(spec, seed, **kw):
    scene = cached_scene(spec)
    frames, gt = scene.frames(), scene.groundtruth(0)
    t = pftrack.create_tracker("fusion-pf", seed=seed, **kw)
    t.init(frames[0], tuple(gt[0]))
    states = [t.update(f) for f in frames[1:]]
    boxes = np.array([gt[0]] + [s.box for s in states])
    lost = np.array([False] + [s.lost for s in states])
    return center_error(boxes, gt), lost


def test_fusion_pf_follows_camouflaged_targets_that_colour_cannot_see():
    """The target is a flipped patch of the background (same colours): the structural cue and the fused
    loss test keep fusion-pf on it; with the structural cue off it is lost at once (6 seeded scenes).
    Measured median errors 0.4-0.6 px and no lost frame on every seed, 31-88 px without the structural cue.
    (With color-pf's velocity noise, 0.1, two seeds lost the target when the constant-velocity prediction
    ran away: the reason fusion-pf's default is 0.025.)"""
    with_s, without, lost_share = [], [], []
    for seed in range(6):
        spec = camouflage_scene(seed, n_frames=60)
        # the colour bins without the still view's gain: these scenes' light drifts, and with the gain undone the
        # colour cue alone follows five of the six (below)
        err, lost = _track(spec, seed, color_normalize="none")
        with_s.append(np.median(err))
        lost_share.append(lost.mean())
        err0, _ = _track(spec, seed, structure=False, color_normalize="none")
        without.append(np.median(err0))
    with_s, without = np.array(with_s), np.array(without)
    assert np.all(with_s < 3.0), with_s
    assert np.all(np.array(lost_share) < 0.1), lost_share
    assert np.all(without > 20.0), without
    assert np.median(without) > 10 * np.median(with_s), (with_s, without)


@pytest.mark.parametrize("kind, seeds, min_recall, max_false", [
    ("vanish", range(200, 206), 0.7, 0.05),  # measured 0.82 / 0.00
    # measured 0.99 / 0.116 (0.130 with --param reenter_min_llr=10; with the grey-patch NCC on grey input
    # 0.99 / 0.075, earlier 0.99 / 0.06 with edge_share and 0.86 / 0.06 without): on the grey seed 203 neither cue
    # re-acquires the returning target, and the search's stale box lies on its path, which counts as raised on a
    # covered target (0.695 of its covered frames)
    ("leave", range(200, 210), 0.9, 0.12),
])


def test_fused_lost_flag_as_a_detector_over_varied_scenes(kind, seeds, min_recall, max_false):
    from .conftest import lost_flag_run

    make = vanish_scene if kind == "vanish" else leave_scene
    res = [lost_flag_run(make(seed), "fusion-pf", seed) for seed in seeds]
    recall = np.nanmean([r.recall for r in res])
    false = np.nanmean([r.false_rate for r in res])
    assert recall >= min_recall, recall
    assert false <= max_false, false


def test_bundled_clip_has_no_false_lost_frames():
    """The demo's real clip (OTB 'Crossing', a tune-split sequence): a car passing behind the walker drops the
    structural score for a few frames; the fused test must not call the visible target lost."""
    from pftrack.geometry import iou

    frames, gt = bundled_clip()
    t = pftrack.create_tracker("fusion-pf", seed=0)
    t.init(frames[0], tuple(gt[0]))
    states = [t.update(f) for f in frames[1:]]
    ious = np.array([iou(np.array(s.box), g) for s, g in zip(states, gt[1:])])
    lost = np.array([s.lost for s in states])
    assert not np.any(lost & (ious >= 0.5)), np.flatnonzero(lost)
    assert np.mean(ious >= 0.5) > 0.9


def test_fusion_pf_automatic_initialisation_runs_without_a_reference_patch():
    """init_auto gives a histogram, no patch: the structural cue gives no evidence (NaN in the fused test) and
    a reference left from an earlier target is dropped."""
    from pftrack.geometry import box_to_ellipse
    from pftrack.synth import entering_scene

    from .conftest import render_scene

    scene, frames, truths = render_scene(entering_scene(0, enter_at=15))
    gt = scene.groundtruth(0)
    tr = pftrack.create_tracker("fusion-pf", seed=0)
    tr.init(frames[40], tuple(gt[40]))  # an earlier target: leaves a reference patch behind
    assert tr.structure.ready
    q = tr.cue.histogram(frames[40], box_to_ellipse(gt[40]))
    st = tr.init_auto(frames[0], q, size=gt[40][2:])
    assert not tr.structure.ready
    states = [st] + [tr.update(f) for f in frames[1:]]
    lost = np.array([s.lost for s in states])
    assert lost[:15].all()
    found = int(np.argmax(~lost))
    assert 15 <= found <= 60
    tail = slice(found + 3, len(states))
    assert center_error(np.array([s.box for s in states])[tail], gt[tail]).mean() < 6.0


def test_relit_colour_undoes_a_global_gain_for_the_search():
    """While searching, the colour score of a candidate is also taken with the frame's per-channel gain undone
    (against the light of the last background refresh): a target whose colours drifted with the light while it
    was hidden still matches its colour model, so the colour cue does not veto its re-acquisition."""
    img = np.ascontiguousarray(_texture(5, (240, 320)))
    img[100:140, 140:170] = (40, 90, 200)  # a coloured target on grey texture
    box = (140.0, 100.0, 30.0, 40.0)
    t = pftrack.create_tracker("fusion-pf", seed=0)
    t.init(img, box)
    ell = np.array([155.0, 120.0, 15.0, 20.0])
    assert t._ref_levels is not None
    lit = np.clip(img.astype(np.float32) * np.array([1.45, 1.1, 0.7], np.float32), 0, 255).astype(np.uint8)
    rho_raw = float(t._rho(lit, ell[None], (0, 0, 320, 240))[0][0])
    rho_relit = t._relit_rho(lit, ell)
    rho_same = float(t._rho(img, ell[None], (0, 0, 320, 240))[0][0])
    assert rho_raw < 0.6 and rho_relit > 0.9, (rho_raw, rho_relit)
    assert rho_relit == pytest.approx(rho_same, abs=0.08)


@pytest.mark.parametrize("seed", [326, 418])
def test_relit_colour_reacquires_a_target_whose_colours_drifted_while_hidden(seed):
    """Two seeded vanish scenes with a global lighting drift (colour frames): with the relit colour score the
    target is re-acquired within 15 frames of coming out; without it the colour cue vetoes it (measured on
    seeds 300-419 when the rule came in: 19 of 27 such reappearances re-acquired against 18, lost-flag rates
    unchanged; with the refined search, before acquire_margin, 32 such scenes: 24 of 33 against 18)."""
    from .conftest import lost_flag_run

    spec = vanish_scene(seed)
    # the colour bins without the still view's gain, which undoes the drift on its own (fusion-pf's default since)
    on = lost_flag_run(spec, "fusion-pf", seed, color_normalize="none")
    off = lost_flag_run(spec, "fusion-pf", seed, relit_colour=False, color_normalize="none")
    assert on.reappearances == off.reappearances == 1
    assert (on.reacquired, off.reacquired) == (1, 0)
    assert on.recall == pytest.approx(off.recall) and on.false_rate <= off.false_rate + 1e-9


def test_box_bounds_compiled_and_numpy_agree_and_cover_uses_them():
    from pftrack._numba import set_numba_enabled
    from pftrack.cues.structure import Reduced, box_bounds

    rng = np.random.default_rng(7)
    ell = np.column_stack([rng.uniform(0, 100, 20), rng.uniform(0, 80, 20), rng.uniform(1, 9, 20),
                           rng.uniform(1, 9, 20)])
    ref = (np.min(ell[:, 0] - ell[:, 2]), np.min(ell[:, 1] - ell[:, 3]), np.max(ell[:, 0] + ell[:, 2]),
           np.max(ell[:, 1] + ell[:, 3]))
    assert box_bounds(ell) == pytest.approx(ref)
    prev = set_numba_enabled(False)
    try:
        assert box_bounds(ell) == pytest.approx(ref)
    finally:
        set_numba_enabled(prev)
    # a region inside the frame covers only what lies in it; one reaching the frame's edge covers beyond it
    red = Reduced(np.zeros((10, 10), np.float32), 20, 20, 2, (200, 100))
    assert red.covers(np.array([[30.0, 30.0, 5.0, 5.0]])) and not red.covers(np.array([[38.0, 30.0, 5.0, 5.0]]))
    edge = Reduced(np.zeros((10, 10), np.float32), 0, 0, 2, (21, 21))
    assert edge.covers(np.array([[18.0, 18.0, 6.0, 6.0]])) and edge.covers(np.array([[1.0, 1.0, 4.0, 4.0]]))
    assert not Reduced(np.zeros((10, 10), np.float32), 0, 0, 2).covers(np.array([[18.0, 18.0, 6.0, 6.0]]))
