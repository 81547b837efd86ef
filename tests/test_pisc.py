"""Book ch. 1: PISC codes (Eqs. 7-9) and the ``pisc`` block-matching tracker."""

from __future__ import annotations

import numpy as np

import pftrack
from pftrack.cues import pisc as P
from pftrack.geometry import center_error
from pftrack.synth import Scene, illumination_scene


def test_codes_are_invariant_to_monotonic_brightness_changes():
    rng = np.random.default_rng(0)
    g = rng.uniform(1, 255, (30, 40))
    base = P.dense_codes(g)
    for changed in (0.6 * g + 20, 255 * (g / 255) ** 0.5, np.exp(g / 80)):
        assert np.array_equal(P.dense_codes(changed), base)
    # inversion: only the centre (and ties) agree
    inv = P.block_correlation(P.dense_codes(255 - g), base)
    assert inv[5:-5, 5:-5].max() == 1


def test_popcount_correlation_equals_the_literal_eq9():
    rng = np.random.default_rng(1)
    for _ in range(200):
        a = rng.integers(0, 6, (9, 9)).astype(float)  # many ties
        b = rng.integers(0, 6, (9, 9)).astype(float)
        ca = P.dense_codes(a)[4, 4]
        cb = P.dense_codes(b)[4, 4]
        assert int(P.block_correlation(ca, cb)) == P.block_correlation_reference(a, b)
    assert int(P.block_correlation(ca, ca)) == 81


def test_region_offset_recovers_a_shift_under_a_light_change():
    rng = np.random.default_rng(2)
    import cv2

    g = cv2.GaussianBlur(rng.uniform(0, 255, (80, 90)), (0, 0), 1.5)
    centres = np.array([[r, c] for r in range(25, 50, 9) for c in range(25, 60, 9)])
    prev = P.dense_codes(g)[centres[:, 0], centres[:, 1]]
    moved = np.roll(np.roll(g, 3, axis=0), -2, axis=1) * 0.7 + 30  # shift (3, -2) and a gain/offset change
    off, corr = P.region_offset(prev, P.dense_codes(moved), centres, 6)
    assert np.allclose(off, [3, -2], atol=0.25) and corr.min() >= 70


def test_pisc_tracker_follows_a_target_whose_light_changes():
    errs = []
    for seed in range(3):
        scene = Scene(illumination_scene(seed, n_frames=60))
        frames, gt = scene.frames(), scene.groundtruth(0)
        t = pftrack.create_tracker("pisc")
        t.init(frames[0], tuple(gt[0]))
        boxes = [gt[0]] + [t.update(f).box for f in frames[1:]]
        errs.append(center_error(np.array(boxes), gt).mean())
    assert np.mean(errs) < 4.0, errs


def test_per_block_offsets_recover_a_shift():
    import cv2

    rng = np.random.default_rng(4)
    g = cv2.GaussianBlur(rng.uniform(0, 255, (80, 90)), (0, 0), 1.5)
    centres = np.array([[r, c] for r in range(25, 50, 9) for c in range(25, 60, 9)])
    prev = P.dense_codes(g)[centres[:, 0], centres[:, 1]]
    moved = np.roll(np.roll(g, -2, axis=0), 4, axis=1) ** 0.9  # shift (-2, 4) and a gamma change
    off, corr = P.match_blocks(prev, P.dense_codes(moved), centres, 6)
    assert abs(np.median(off[:, 0]) + 2) < 0.3 and abs(np.median(off[:, 1]) - 4) < 0.3
    assert np.mean(np.all(np.abs(off - [-2, 4]) < 0.5, axis=1)) > 0.8  # a flat block may match elsewhere
