"""The size a search looks for after a loss (``search_size_frames``, docs/robustness.md)."""

from __future__ import annotations

import pytest

import pftrack
from pftrack.synth import Scene
from pftrack.synth.scenes import Occluder, SceneSpec, Target

W, H = 30.0, 60.0


def _behind_occluder(seed: int) -> SceneSpec:
    """The target walks left, fully behind a textured occluder (frames ~38-62), and out again."""
    tgt = Target(path=((0, 250.0, 120.0), (89, 70.0, 120.0)), size=(W, H), colors=((40, 40, 200), (200, 120, 40)))
    occ = Occluder(box=(110.0, 60.0, 80.0, 120.0), color=(90, 160, 90), texture=15.0)
    return SceneSpec(n_frames=90, seed=seed, targets=(tgt,), occluders=(occ,), background="texture")


def _size_at_loss(tracker: str, seed: int, **params) -> tuple[float, float]:
    """The half-axes the tracker searches with on the frame it declares the loss."""
    scene = Scene(_behind_occluder(seed))
    gt = scene.groundtruth(0)
    t = pftrack.create_tracker(tracker, seed=seed, **params)
    t.init(scene.render(0)[0], tuple(gt[0]))
    for k in range(1, 90):
        if t.update(scene.render(k)[0]).lost:
            return t.size
    raise AssertionError("the loss was never declared")


@pytest.mark.parametrize("tracker", ["fusion-pf", "color-pf"])
def test_the_search_looks_for_the_size_seen_before_the_occlusion(tracker):
    """On its way behind the occluder the target is followed on its visible part, so the estimate shrinks while
    the loss test stays confident. The search looks for the largest confident size of the last 30 frames.
    (fusion-pf's NCC size search is off here: it follows the visible part faster, and with it seed 1 searches
    with 348 px^2 of 450; both seeds still re-acquire the target, one frame later than without it.)"""
    full = (W / 2) * (H / 2)
    own = {"scale_search": 0.0} if tracker == "fusion-pf" else {}
    for seed in (0, 1):
        hx, hy = _size_at_loss(tracker, seed, **own)
        hx0, hy0 = _size_at_loss(tracker, seed, search_size_frames=0, **own)
        # fusion-pf, measured: 453 and 438 px^2 of 450 with the window; 382 and 342 with the last confident size
        assert hx * hy >= 0.9 * full, (hx, hy)
        assert hx0 * hy0 < hx * hy, (hx0, hy0, hx, hy)
        assert 1.5 <= hy / hx <= 2.5  # one box of the window, not a mix of axes


def test_a_search_of_one_or_two_samples_runs():
    """search_particles = 1 or 2 leaves no sample for the refined layer (half of one rounds to none): the search
    then scores its first layer alone instead of failing."""
    from pftrack.synth import vanish_scene

    pairs = [(f, tr.boxes[0]) for f, tr in Scene(vanish_scene(1, n_frames=40))]
    for name in ("color-pf", "fusion-pf"):
        for n in (1, 2):
            t = pftrack.create_tracker(name, seed=0, search_particles=n, search_refine=0.5)
            t.init(pairs[0][0], pairs[0][1])
            assert any(t.update(f).lost for f, _ in pairs[1:])
