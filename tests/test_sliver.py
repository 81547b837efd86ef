"""A target that comes back and stays at the view's edge, a sliver of it in view (``acquire_sliver_frames``,
``acquire_sliver_llr``)."""

from __future__ import annotations

import pytest

import pftrack
from pftrack.geometry import iou
from pftrack.synth.scenes import SceneSpec, Target

from .conftest import cached_scene


def _sliver_scene(seed: int) -> SceneSpec:
    """The target walks out through the right edge of the 320 px view (gone from frame 27), waits outside, comes
    back to stand from frame 50 on with its centre at x = 324: 31 % of its width in view."""
    target = Target(path=((0, 230.0, 120.0), (25, 370.0, 120.0), (40, 370.0, 120.0), (50, 324.0, 120.0),
                          (75, 324.0, 120.0)), size=(26.0, 52.0))
    return SceneSpec(n_frames=75, seed=seed, targets=(target,), background="flat", kind="exit")


def _covered_after_return(seed: int, **params) -> tuple[list[int], bool]:
    """One run of fusion-pf (``params``) on the sliver scene: the frames from 45 on where its box covers the target
    (IoU > 0.3) with the flag down, and whether the flag was up on every frame the target was out of view."""
    scene = cached_scene(_sliver_scene(seed))
    frames = scene.frames()
    gt = scene.groundtruth()
    t = pftrack.create_tracker("fusion-pf", seed=seed, **params)
    t.init(frames[0], tuple(gt[0]))
    states = [t.update(f) for f in frames[1:]]
    away = all(s.lost for s in states[29:42])  # frames 30-42: the target is out of view
    return [i for i, s in enumerate(states, start=1) if i >= 45 and not s.lost and iou(s.box, gt[i]) > 0.3], away


@pytest.mark.parametrize("seed", range(6))
def test_a_target_that_stays_at_the_edge_is_taken_after_k_frames(seed):
    """acquire_in_frame = 0.5 (default), without acquire_sliver_llr, never takes the target standing a third in
    view; with acquire_sliver_frames = 3 it is taken within the 15 frames of the re-acquisition measure
    (measured: frames 51-53 on five seeds, 65 on seed 1), and nothing is taken while it is away. Tracked as a
    sliver, its estimate counts for little with edge_share (fusion-pf's default), so the flag may rise again
    (covered on 1-10 of the 25 frames). The camera's shift is off here: on this featureless view the projections
    are mostly noise, and the few shifts read from them (``camera_motion``, fusion-pf's default) moved the samples
    off the sliver after its acquisition on seed 1, which was taken again at frame 67. So is the size read from the
    map's mass (``mass_size``, the default since), measured before it: with it seed 3's sliver is not taken."""
    covered = {}
    for k in (0, 3):
        covered[k], away = _covered_after_return(seed, acquire_sliver_frames=k, acquire_sliver_llr=0,
                                                 camera_motion=False, mass_size=0.0)
        assert away, k
    assert not covered[0], covered
    back = covered[3]
    assert back and back[0] <= 65, covered


def test_a_sliver_with_an_unambiguous_ratio_is_taken_at_once():
    """acquire_sliver_llr = 19.5 (fusion-pf's default; the fused ratio's cap is 20): the target standing a third in
    view is taken on the first frames of its return where both cues are at their clip (measured: frames 50-54 on
    seeds 1-4; seeds 0 and 5 stay below 19.5, and 15 takes seed 5 too), never while it is away. Off (0), it is
    never taken: the test above, whose runs set it to 0."""
    taken = 0
    for seed in range(6):
        covered, away = _covered_after_return(seed)
        assert away, seed
        taken += bool(covered and covered[0] <= 55)
    assert taken >= 4, taken
