"""The structural (grey-patch NCC) cue, the fused loss test and fusion-pf on structure-only scenes."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.cues.structure import StructureCue, ncc_scores, patch_shape, sample_boxes, standardize
from pftrack.filtering.loss import FusedLoss, LossDetector
from pftrack.geometry import center_error
from pftrack.synth import Scene, camouflage_scene, vanish_scene
from pftrack.synth.varied import hidden_frames


def _texture(seed=0, shape=(120, 160)):
    rng = np.random.default_rng(seed)
    g = cv2.GaussianBlur(rng.uniform(0, 255, shape), (0, 0), 2.0)
    g = cv2.normalize(g, None, 0, 255, cv2.NORM_MINMAX)
    return np.repeat(g.astype(np.uint8)[..., None], 3, axis=2)


def test_patch_shape_keeps_aspect_and_size():
    ph, pw = patch_shape(40, 80, 256)
    assert ph * pw == pytest.approx(256, rel=0.1) and ph / pw == pytest.approx(2.0, rel=0.15)
    assert patch_shape(1, 1000, 16)[1] >= 4  # never degenerate


def test_ncc_is_one_on_the_template_and_invariant_to_gain_and_offset():
    rng = np.random.default_rng(1)
    t = rng.uniform(0, 255, (1, 64)).astype(np.float32)
    p = np.concatenate([t, 0.5 * t + 40, 1.7 * t - 30, rng.uniform(0, 255, (1, 64)).astype(np.float32)])
    r = ncc_scores(p, standardize(t))
    assert r[:3] == pytest.approx([1.0, 1.0, 1.0], abs=2e-3)
    assert abs(r[3]) < 0.5
    flat = ncc_scores(np.full((1, 64), 100.0, np.float32), standardize(t))
    assert flat[0] == pytest.approx(0.0, abs=1e-6)  # no structure, no evidence (no 0/0)


def test_sampled_box_equals_the_area_resized_crop():
    img = _texture()
    box = (40, 30, 64, 48)  # x, y, w, h: a 4x reduction to a 16x12 patch
    ell = np.array([[box[0] + box[2] / 2, box[1] + box[3] / 2, box[2] / 2, box[3] / 2]])
    got = sample_boxes(img, (0, 0, 160, 120), ell, (12, 16)).reshape(12, 16)
    crop = cv2.cvtColor(img[30:78, 40:104], cv2.COLOR_BGR2GRAY).astype(np.float32)
    ref = cv2.resize(crop, (16, 12), interpolation=cv2.INTER_AREA)
    # the reduced grid is not aligned with the box's edges, so equal up to a sub-pixel resampling
    assert np.mean(np.abs(got - ref)) < 6.0
    assert ncc_scores(got.reshape(1, -1), standardize(ref.reshape(1, -1)))[0] > 0.95


def test_structure_cue_peaks_at_the_target_and_keeps_its_anchor():
    img = _texture(2)
    cue = StructureCue(256)
    true = np.array([80.0, 60.0, 15.0, 12.0])
    cue.init(img, true)
    offs = np.array([[0, 0], [6, 0], [0, -6], [20, 15], [-30, 10]], dtype=float)
    ell = np.column_stack([true[:2] + offs, np.tile(true[2:], (len(offs), 1))])
    r = cue.scores(img, (0, 0, 160, 120), ell)
    assert int(np.argmax(r)) == 0 and r[0] == pytest.approx(1.0, abs=0.01)
    # a bad update (the reference blended fully into clutter) cannot erase the first frame's patch
    cue.update(img, ell[4], 1.0)
    assert cue.scores(img, (0, 0, 160, 120), ell[:1])[0] == pytest.approx(1.0, abs=0.01)


def test_fused_loss_adds_likelihood_ratios_and_ignores_a_blind_cue():
    kw = dict(lost_frames=2, reacquire_margin=1.0)
    fused, single = FusedLoss(2, **kw), LossDetector(**kw)
    rng = np.random.default_rng(0)
    bg_colour = rng.uniform(0.2, 0.5, 200)
    bg_blind = np.r_[rng.uniform(0.9, 1.0, 180), np.ones(20)]  # as high on the background as on the target
    fused.set_background(np.column_stack([bg_colour, bg_blind]))
    single.set_background(bg_colour)
    for s in (0.9, 0.6, 0.55):
        assert fused.evaluate([s, 0.97]) == pytest.approx(single.evaluate(s), abs=1e-9)
    # two informative cues: the ratios add
    two = FusedLoss(2, **kw)
    two.set_background(np.column_stack([bg_colour, bg_colour]))
    assert two.evaluate([0.6, 0.6]) == pytest.approx(2 * single.evaluate(0.6))
    # a missing cue (NaN) gives no evidence; all missing is absence
    assert fused.evaluate([0.6, np.nan]) == pytest.approx(single.evaluate(0.6))
    assert fused.evaluate([np.nan, np.nan]) < -10


def test_fused_loss_hysteresis_and_reacquisition():
    det = FusedLoss(2, lost_frames=3, reacquire_margin=1.0)
    det.set_background(np.column_stack([np.linspace(0.2, 0.5, 50), np.linspace(0.4, 0.6, 50)]))
    assert det.step([0.95, 0.98]) == (False, pytest.approx(1.0, abs=1e-3))
    flags = [det.step([0.3, 0.5])[0] for _ in range(3)]
    assert flags == [False, False, True]
    assert not det.acquire([0.45, 0.55])  # background-like: stays lost
    assert det.acquire([0.95, 0.97]) and not det.lost


def _track(spec, seed, **kw):
    scene = Scene(spec)
    frames, gt = scene.frames(), scene.groundtruth(0)
    t = pftrack.create_tracker("fusion-pf", seed=seed, **kw)
    t.init(frames[0], tuple(gt[0]))
    states = [t.update(f) for f in frames[1:]]
    boxes = np.array([gt[0]] + [s.box for s in states])
    lost = np.array([False] + [s.lost for s in states])
    return center_error(boxes, gt), lost


def test_fusion_pf_follows_camouflaged_targets_that_colour_cannot_see():
    """The target is a flipped patch of the background (same colours): the structural cue and the fused
    loss test keep fusion-pf on it; with the structural cue off it is lost (seeded, varied scenes)."""
    with_s, without = [], []
    for seed in range(3):
        spec = camouflage_scene(seed, n_frames=60)
        err, lost = _track(spec, seed)
        with_s.append(np.median(err))
        assert lost.mean() < 0.1, (seed, lost.mean())
        err0, _ = _track(spec, seed, structure=False)
        without.append(np.median(err0))
    assert max(with_s) < 5.0, with_s
    assert np.mean(without) > 3 * np.mean(with_s), (with_s, without)


def test_fused_lost_flag_is_raised_while_the_target_is_hidden():
    recall = []
    for seed in range(5):
        spec = vanish_scene(100 + seed)
        _, lost = _track(spec, seed)
        hidden = hidden_frames(spec)
        if hidden.any():
            recall.append(lost[hidden].mean())
    assert np.mean(recall) >= 0.6, recall
