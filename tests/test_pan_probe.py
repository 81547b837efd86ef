"""scripts/pan_probe.py (a camera panning to keep the target in view) and ``camera_share``, the share of the samples
moved with the camera."""

from __future__ import annotations

import numpy as np
import pytest

import pftrack
from pftrack.synth import Scene
from pftrack.trackers.camera_motion import camera_rows

from .conftest import load_script


def test_the_background_pans_and_the_target_stays_near_the_centre():
    pp = load_script("pan_probe")
    spec = pp.pan_scene(2, 12.0)
    cam = np.array(spec.camera_path)
    steps = np.hypot(*np.diff(cam[:, 1:], axis=0).T) / np.diff(cam[:, 0])
    assert np.median(steps) == pytest.approx(12.0, rel=0.05)
    gt = Scene(spec).groundtruth(0)
    centre = gt[:, :2] + gt[:, 2:] / 2
    assert np.abs(centre - [160, 120]).max() < 40  # the target a few pixels about the centre while the view moves 1200


def test_share_spreads_the_moved_samples_evenly():
    assert camera_rows(10, 0.5).tolist() == [1, 3, 5, 7, 9]
    assert len(camera_rows(100, 0.3)) == 30 and len(camera_rows(7, 1.0)) == 7
    rows = camera_rows(100, 0.25)
    assert np.all(np.diff(rows) == 4)


def test_half_the_samples_moved_hold_a_target_the_camera_follows():
    """At 12 px a frame every sample moved with the background leaves the target that the camera keeps in view;
    with half of them moved, the half left in place holds it (seeds 0-1: measured 0.79 against 0.86)."""
    pp = load_script("pan_probe")
    full = np.mean([pp.auc_of("a", "fusion-pf", {}, s, 12.0) for s in (0, 1)])
    half = np.mean([pp.auc_of("b", "fusion-pf", {"camera_share": "0.5"}, s, 12.0) for s in (0, 1)])
    assert half > full + 0.03, (full, half)


def test_a_still_camera_gives_the_same_track_whatever_the_share():
    from pftrack.synth.scenes import simple_scene

    scene = Scene(simple_scene(4, n_frames=40))
    frames, gt = scene.frames(), scene.groundtruth(0)
    boxes = []
    for share in (1.0, 0.5):
        t = pftrack.create_tracker("fusion-pf", seed=0, camera_share=share)
        boxes.append([t.init(frames[0], tuple(gt[0])).box] + [t.update(f).box for f in frames[1:]])
    assert boxes[0] == boxes[1]


def _levels(frames, gt, **params):
    t = pftrack.create_tracker("fusion-pf", seed=0, **params)
    t.init(frames[0], tuple(gt[0]))
    levels = []
    for f in frames[1:]:
        t.update(f)
        levels.append(t._camera_level)
    return np.array(levels)


def test_the_learnt_share_falls_when_the_camera_follows_the_target_and_stays_when_it_shakes():
    """``camera_adapt``: on a pan that keeps the target in view the samples left in place take the weight, and the
    share of moved samples falls to its floor; on a hand-held camera over a still target the moved ones do, and it
    stays at its top."""
    from .test_camera_motion import shaky_scene

    pp = load_script("pan_probe")
    scene = Scene(pp.pan_scene(0, 12.0))
    pan = _levels(scene.frames(), scene.groundtruth(0), camera_share=0.9, camera_adapt=0.2)
    frames, gt = shaky_scene(0)
    shake = _levels(frames, gt, camera_share=0.9, camera_adapt=0.2)
    assert pan[0] == pytest.approx(0.9) and np.median(pan[20:]) < 0.4, pan
    assert np.median(shake[20:]) > 0.75, shake
    assert pan.min() >= 0.2 - 1e-12 and shake.max() <= 0.9 + 1e-12


def test_a_still_camera_learns_nothing():
    from pftrack.synth.scenes import simple_scene

    scene = Scene(simple_scene(4, n_frames=30))
    frames, gt = scene.frames(), scene.groundtruth(0)
    assert np.all(_levels(frames, gt, camera_share=0.9, camera_adapt=0.2) == 0.9)
