"""scripts/reid_acquisitions.py: ch. 11's appearances scored at a tracker's acquisitions (a diagnosis)."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.synth import Scene
from pftrack.synth.scenes import SceneSpec, Target

from .conftest import load_script


@pytest.fixture(scope="module")
def mod():
    return load_script("reid_acquisitions")


def test_roc_auc_counts_pairs_and_ties(mod):
    assert mod.roc_auc([2.0, 3.0], [1.0]) == 1.0
    assert mod.roc_auc([1.0], [2.0, 3.0]) == 0.0
    assert mod.roc_auc([1.0, 3.0], [1.0, 2.0]) == pytest.approx((0.5 + 0.0 + 1.0 + 1.0) / 4)
    assert math.isnan(mod.roc_auc([], [1.0]))


def test_label_right_wrong_or_left_out(mod):
    truth = np.array([10.0, 10.0, 20.0, 40.0])
    assert mod.label((10, 10, 20, 40), truth) == "right"
    assert mod.label((200, 10, 20, 40), truth) == "wrong"
    assert mod.label((10, 10, 20, 40), np.full(4, np.nan)) == "wrong"  # the target is absent
    assert mod.label((22, 10, 20, 40), truth) is None  # IoU 0.25: neither


@pytest.mark.parametrize("feature,regions", [("whole", 1), ("ellipse2", 2), ("positional", 8)])
def test_histograms_are_coarse_normalised_region_histograms(mod, feature, regions):
    rng = np.random.default_rng(0)
    frame = rng.integers(0, 256, (60, 80, 3), dtype=np.uint8)
    h = mod.histograms(frame, (10, 5, 30, 50), feature, 32)
    assert h.shape == (regions, 3, 32)
    np.testing.assert_allclose(h.sum(axis=(0, 2)), 1.0)
    assert mod.sim(h, h) == pytest.approx(1.0)


@pytest.mark.parametrize("feature,regions", [("whole", 1), ("positional", 8)])
def test_joint_histograms_when_asked(mod, feature, regions):
    rng = np.random.default_rng(1)
    frame = rng.integers(0, 256, (60, 80, 3), dtype=np.uint8)
    h = mod.histograms(frame, (10, 5, 30, 50), feature, 0)
    assert h.shape == (regions * 512,) and h.sum() == pytest.approx(1.0)
    assert mod.sim(h, h) == pytest.approx(1.0)
    assert mod.sim(h, mod.histograms(frame[::-1].copy(), (10, 5, 30, 50), feature, 0)) < 1.0


def test_a_twin_taken_after_the_exit_is_a_wrong_acquisition_that_colour_cannot_tell(mod):
    """The target walks out through the right edge; its twin (the same colours) stands inside. Without the exit
    strip the search takes the twin: a wrong acquisition, whose whole-box colours match the target's, and which
    was elsewhere when the target was lost."""
    target = Target(path=((0, 230.0, 120.0), (30, 360.0, 120.0)), size=(26.0, 52.0))
    twin = Target(path=((0, 80.0, 150.0),), size=(26.0, 52.0))
    scene = Scene(SceneSpec(n_frames=60, seed=0, targets=(target, twin), background="flat", kind="exit"))
    frames = scene.frames()
    truth = np.asarray(scene.groundtruth(), dtype=np.float64)
    truth[28:] = np.nan  # out of view
    tracker = pftrack.create_tracker("color-pf", seed=0, reenter_border=0.0, static_ncc=0.0)
    recs = mod.acquisitions(frames, truth, tuple(truth[0]), tracker, 32)
    wrong = [r for r in recs if r["label"] == "wrong"]
    assert wrong
    for r in wrong:
        assert r["in_frame"] == pytest.approx(1.0)
        assert all(0.0 <= r[k]["gallery"] <= 1.0 for k in mod.FEATURES)
        assert r["whole"]["gallery"] > 0.8
    s = mod.summary(recs)
    assert all(r["delay"] >= 1 and isinstance(r["apart 0.5"], bool) for r in recs)
    assert all(r["apart 0.5"] for r in wrong)  # the twin stood elsewhere when the target was lost
    assert s["wrong"] == len(wrong) and set(s["auc"]) == {f"{k} {v}" for k in mod.FEATURES for v in mod.SCORES}
    assert all(r["rival"] is False and r["margin"] > 0 for r in wrong)  # the twin stood alone
    assert s["rival"] == (0, 0) and s["two_in_loss"] == (0, 0)


def test_two_twins_in_view_are_rivals_at_the_acquisition(mod):
    """The target leaves; two twins stand inside. The search takes one, and the other passed the acquisition test
    too (``acquire_unique``'s question); with the option on, that frame takes neither (a later one may, when the
    search's samples miss the other twin)."""
    target = Target(path=((0, 230.0, 120.0), (30, 360.0, 120.0)), size=(26.0, 52.0))
    twins = tuple(Target(path=((0, x, 150.0),), size=(26.0, 52.0)) for x in (60.0, 150.0))
    scene = Scene(SceneSpec(n_frames=60, seed=0, targets=(target, *twins), background="flat", kind="exit"))
    frames = scene.frames()
    truth = np.asarray(scene.groundtruth(), dtype=np.float64)
    truth[28:] = np.nan
    params = {"reenter_border": 0.0, "static_ncc": 0.0}
    recs = mod.acquisitions(frames, truth, tuple(truth[0]), pftrack.create_tracker("color-pf", seed=0, **params), 32)
    assert recs and recs[0]["label"] == "wrong" and recs[0]["rival"] is True and recs[0]["margin"] < 5.0
    assert isinstance(recs[0]["two_in_loss"], bool)
    unique = pftrack.create_tracker("color-pf", seed=0, acquire_unique=True, **params)
    later = mod.acquisitions(frames, truth, tuple(truth[0]), unique, 32)
    assert not later or (later[0]["t"] > recs[0]["t"] and later[0]["rival"] is False)


def test_traced_back_follows_a_moving_texture_and_loses_a_flat_patch(mod):
    rng = np.random.default_rng(1)
    texture = rng.integers(0, 256, (200, 260), dtype=np.uint8)
    texture = np.asarray(cv2.GaussianBlur(texture, (5, 5), 1.0))
    grays = [np.roll(texture, (2 * k, 3 * k), axis=(0, 1)) for k in range(4)]  # moves 3 px right, 2 down a frame
    box = (100.0 + 9, 80.0 + 6, 40.0, 60.0)  # on the last frame
    np.testing.assert_allclose(mod.traced_back(grays, box), [100.0, 80.0, 40.0, 60.0], atol=0.5)
    flat = [np.full((200, 260), 90, np.uint8)] * 3
    assert mod.traced_back(flat, box) is None


def test_the_command_prints_the_separations_of_a_sequence_folder(mod, tmp_path):
    """End to end on an OTB-style folder (img/ and groundtruth_rect.txt, NaN rows while the target is out)."""
    import json
    import subprocess
    import sys

    target = Target(path=((0, 230.0, 120.0), (30, 360.0, 120.0)), size=(26.0, 52.0))
    twin = Target(path=((0, 80.0, 150.0),), size=(26.0, 52.0))
    scene = Scene(SceneSpec(n_frames=60, seed=0, targets=(target, twin), background="flat", kind="exit"))
    seq = tmp_path / "exit_twin"
    (seq / "img").mkdir(parents=True)
    truth = np.asarray(scene.groundtruth(), dtype=np.float64)
    truth[28:] = np.nan
    for k, f in enumerate(scene.frames()):
        cv2.imwrite(str(seq / "img" / f"{k + 1:04d}.png"), f)
    np.savetxt(seq / "groundtruth_rect.txt", truth, fmt="%.2f", delimiter=",")
    out = tmp_path / "acq.json"
    script = Path(mod.__file__)
    run = subprocess.run([sys.executable, str(script), str(tmp_path),
                          "--tracker", "color-pf[reenter_border=0;static_ncc=0]",
                          "--seeds", "0", "--json", str(out)], capture_output=True, text=True, check=True)
    assert "ROC AUC" in run.stdout and "elsewhere at the loss" in run.stdout and "passed the acquisition" in run.stdout
    recs = json.loads(out.read_text())
    assert recs and {r["sequence"] for r in recs} == {"exit_twin"} and {r["label"] for r in recs} == {"wrong"}
    assert "0 right and 1 wrong acquisitions" in run.stdout
