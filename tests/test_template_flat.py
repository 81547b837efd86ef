"""A template of one flat colour (``template``'s ``flat_fallback``).

NCC and mutual information see a template's structure only: a flat template's correlation with any window is its
noise's, about 0, and its entropy is 0, so with them the tracker cannot follow a plain red box for a single frame.
When the template's variance is below twice the camera noise's plus 1 (the noise read from the first two frames),
those criteria give way to SAD, read as the bounded score 1 - mean |R - S| / d (d twice the first frame's grey
spread) that the loss test takes.
"""

from __future__ import annotations

import numpy as np
import pytest

import pftrack
from pftrack.eval.metrics import frame_ious
from pftrack.synth import Scene, camouflage_scene, simple_scene

from .conftest import HIDDEN_BOX_START, HIDDEN_PERIOD, hidden_box, hidden_box_frame

H, W = 120, 160


def _run(seed: int, noise: float, frames: int, **params) -> tuple[np.ndarray, np.ndarray, list]:
    """IoU with the box (NaN while hidden) and the lost flag of ``template`` on frames 1 .. frames - 1."""
    rng = np.random.default_rng(100 + seed)
    bg = rng.integers(0, 255, (H, W, 3), dtype=np.uint8)
    tracker = pftrack.create_tracker("template", **params)
    tracker.init(hidden_box_frame(bg, 0, noise, rng), HIDDEN_BOX_START)
    iou, lost, metrics = [], [], []
    for t in range(1, frames):
        state = tracker.update(hidden_box_frame(bg, t, noise, rng))
        box = hidden_box(t)
        iou.append(np.nan if box is None else frame_ious(np.array([state.box]), np.array([box], float))[0])
        lost.append(state.lost)
        metrics.append(state.info["metric"])
    return np.array(iou), np.array(lost), metrics


@pytest.mark.parametrize("metric", ["ncc", "mi"])
@pytest.mark.parametrize(("seed", "noise"), [(0, 0.0), (1, 2.0), (2, 5.0)])
def test_a_flat_template_falls_back_to_its_level_and_is_followed(seed, noise, metric):
    iou, lost, metrics = _run(seed, noise, HIDDEN_PERIOD, metric=metric)
    assert set(metrics) == {"sad"}  # from the first update on
    seen = ~np.isnan(iou)
    assert (iou[seen] >= 0.5).mean() > 0.95  # on the box while it is in view
    assert lost[seen].mean() < 0.05
    assert lost[~seen].mean() > 0.9  # and the flag raised while it is hidden


@pytest.mark.parametrize("seed", [0, 1])
def test_without_the_fallback_ncc_cannot_follow_a_flat_template(seed):
    iou, lost, metrics = _run(seed, 2.0, 100, flat_fallback="off")
    assert set(metrics) == {"ncc"}
    assert (iou >= 0.5).mean() < 0.2  # the negative control: the first test fails on the old behaviour


@pytest.mark.parametrize("metric", ["ncc", "mi"])
@pytest.mark.parametrize("make", [simple_scene, camouflage_scene])
def test_a_textured_template_keeps_its_criterion(make, metric):
    scene = Scene(make(3, n_frames=12))
    frames, gt = scene.frames(), scene.groundtruth(0)
    tracker = pftrack.create_tracker("template", metric=metric)
    tracker.init(frames[0], tuple(gt[0]))
    assert {tracker.update(f).info["metric"] for f in frames[1:]} == {metric}


def test_criteria_that_see_the_level_never_fall_back():
    _, _, metrics = _run(0, 0.0, 5, metric="ssd")
    assert set(metrics) == {"ssd"}


def test_search_frame_finds_the_box_again_where_it_returns():
    """The box comes back about 60 px from where it was hidden: the frame search finds it within a few frames of
    its return on every seed; the local search only where its held box happened to lie near the return."""
    late = 0
    for seed in (0, 1, 2):
        returns = {}
        for search in ("local", "frame"):
            iou, lost, _ = _run(seed, 2.0, 2 * HIDDEN_PERIOD, search=search)
            back = np.arange(1, 2 * HIDDEN_PERIOD) >= HIDDEN_PERIOD  # the second cycle, from the return on
            returns[search] = int(np.argmax(back & (iou >= 0.5) & ~lost)) + 1 - HIDDEN_PERIOD
        assert returns["frame"] <= 5
        late += returns["local"] > 15
    assert late >= 2
