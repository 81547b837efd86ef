"""color-pf's structural check at re-acquisition on grey input (pftrack.trackers.structure_check, ``grey_check``)."""

from __future__ import annotations

import numpy as np
import pytest

import pftrack
from pftrack.cues.color import model_rho
from pftrack.filtering.loss import LossDetector
from pftrack.synth import Scene, teleport_scene, vanish_scene
from pftrack.trackers.structure_check import StructureCheck, ncc_score

from .conftest import lost_flag_run


def _frame(rng, objects):
    """A grey 240 x 320 frame of smooth clutter with noise, and the given objects: ("disc"|"square", cx, cy), a
    dark disc of radius 11 or a dark square of side 51 (an occluder), both with noise."""
    f = 128.0 + 12.0 * np.sin(np.arange(320)[None, :] / 23.0) * np.cos(np.arange(240)[:, None] / 17.0)
    f = f + rng.normal(0.0, 6.0, f.shape)
    yy, xx = np.mgrid[0:240, 0:320]
    for kind, cx, cy in objects:
        if kind == "disc":
            m = (xx - cx) ** 2 + (yy - cy) ** 2 <= 11 ** 2
        else:
            m = (np.abs(xx - cx) <= 25) & (np.abs(yy - cy) <= 25)
        f[m] = 60.0 + rng.normal(0.0, 6.0, int(m.sum()))
    g = np.clip(f, 0, 255).astype(np.uint8)
    return np.repeat(g[:, :, None], 3, axis=2)


def _background_grid(w=320, h=240, hx=12.0, hy=12.0, exclude=(80.0, 120.0)):
    xs, ys = np.meshgrid(np.arange(20, w, 30.0), np.arange(20, h, 30.0))
    ell = np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, hx), np.full(xs.size, hy)])
    far = np.hypot(ell[:, 0] - exclude[0], ell[:, 1] - exclude[1]) > 40
    return ell[far]


def test_ncc_score_maps_minus_one_to_one_onto_zero_to_one():
    assert np.allclose(ncc_score(np.array([-1.0, 0.0, 1.0])), [0.0, 0.5, 1.0])


def test_the_inside_of_a_dark_occluder_is_refused_where_the_dark_disc_it_imitates_is_accepted():
    """A dark noisy disc and a disc-sized box inside a dark noisy occluder have nearly the same grey histogram;
    their layouts differ. Learned on the disc over a few frames, the check calls the occluder's inside
    background and the disc (moved, on a new frame with new noise) the target."""
    rng = np.random.default_rng(0)
    check = StructureCheck(LossDetector())
    disc = np.array([[80.0, 120.0, 12.0, 12.0]])
    f0 = _frame(rng, [("disc", 80, 120), ("square", 230, 90)])
    check.init(f0, disc[0])
    for k in range(1, 8):
        f = _frame(rng, [("disc", 80 + k, 120), ("square", 230, 90)])
        check.new_frame()
        check.set_background(f, _background_grid(exclude=(80.0 + k, 120.0)))
        check.learn(f, disc[0] + [k, 0, 0, 0])
    f = _frame(rng, [("disc", 150, 60), ("square", 230, 90)])
    check.new_frame()
    assert not check.vetoes(f, np.array([[150.0, 60.0, 12.0, 12.0]]))
    assert check.vetoes(f, np.array([[230.0, 90.0, 12.0, 12.0]]))
    # and a patch of plain clutter
    assert check.vetoes(f, np.array([[40.0, 200.0, 12.0, 12.0]]))
    # the premise: color-pf's grey histogram finds the occluder's inside much like the disc
    t = pftrack.create_tracker("color-pf", seed=0, grey_check="off")
    t.init(f0, (68.0, 108.0, 24.0, 24.0))
    h = t.cue.histogram(f, np.array([230.0, 90.0, 12.0, 12.0]))
    assert model_rho(h / h.sum(), t._sqrt_q) > 0.8


def test_the_check_is_chosen_from_the_input():
    """Grey input gets the check with the default; colour input, fusion-pf and grey_check="off" do not; under the
    self-quotient illumination it sees the untransformed frames."""
    spec = vanish_scene(3, gray=0.0)  # a colour scene
    frame = Scene(spec).render(0)[0]
    grey = np.repeat(frame.mean(axis=2, keepdims=True).astype(np.uint8), 3, axis=2)
    box = tuple(Scene(spec).groundtruth(0)[0])
    for name, params, img, has in [("color-pf", {}, grey, True), ("color-pf", {}, frame, False),
                                   ("color-pf", {"grey_check": "off"}, grey, False), ("fusion-pf", {}, grey, False)]:
        t = pftrack.create_tracker(name, seed=0, **params)
        t.init(img, box)
        assert (t._structure_check is not None) == has, (name, params, img is grey)
    # with the self-quotient illumination the check sees the untransformed frames
    t = pftrack.create_tracker("color-pf", seed=0, illumination="quotient")
    t.init(grey, box)
    assert t._structure_check is not None
    assert t._structure_frame(np.zeros_like(grey)) is t._raw
    assert t.update(grey).box is not None


@pytest.mark.parametrize("make, seed", [(teleport_scene, 204), (vanish_scene, 211)])
def test_grey_scenes_the_target_is_reacquired_where_the_histogram_alone_takes_a_look_alike(make, seed):
    """Grey scenes of seeds in neither split: with the histogram alone color-pf takes another dark patch for
    the target and keeps its flag down while the target is away (it is never re-acquired); with the check that
    patch is refused, the flag goes up and the target is re-acquired."""
    spec = make(seed, gray=1.0)
    on = lost_flag_run(spec)
    off = lost_flag_run(spec, grey_check="off")
    assert on.reacquired == on.reappearances == 1 and on.recall >= 0.9
    assert off.reacquired == 0 and off.recall <= 0.1
