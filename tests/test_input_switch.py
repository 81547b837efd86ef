"""Input that turns grey mid-sequence: the colour trackers' grey features taken up (pftrack.trackers.input_switch).

Scenes: colour synthetic scenes of seeds no choice was made on (2100-2104), turned grey from frame 20, as a camera
switching to monochrome at dusk.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import pftrack
from pftrack._numba import numba_enabled, set_numba_enabled
from pftrack.cues.intensity import is_gray
from pftrack.eval.metrics import frame_ious
from pftrack.synth import Scene, hidden_frames
from pftrack.synth.varied import vanish_scene, varied_scene
from pftrack.trackers.input_switch import ColourReturn, InputSwitch, frame_is_blank, frame_is_grey, grey_copy

SWITCH = 20  # the first grey frame


def _grey(frame):
    g = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    return cv2.cvtColor(g, cv2.COLOR_GRAY2BGR)


def _turning_grey(spec, at=SWITCH):
    scene = Scene(spec)
    frames = [f if i < at else _grey(f) for i, f in enumerate(scene.frames())]
    return frames, scene.groundtruth(0)


def _run(name, frames, gt, **params):
    t = pftrack.create_tracker(name, seed=0, params=params)
    t.init(frames[0], tuple(gt[0]))
    states = [t.update(f) for f in frames[1:]]
    return t, states


# ------------------------------------------------------------------ the frame check
@pytest.mark.parametrize("compiled", [True, False])
def test_frame_is_grey_agrees_with_is_gray(compiled):
    if compiled and not numba_enabled():
        pytest.skip("numba not available")
    rng = np.random.default_rng(0)
    colour = (rng.random((240, 320, 3)) * 255).astype(np.uint8)
    grey = _grey(colour)
    ok, jpeg = cv2.imencode(".jpg", grey, [cv2.IMWRITE_JPEG_QUALITY, 80])
    grey_jpeg = cv2.imdecode(jpeg, cv2.IMREAD_COLOR)  # a grey source through a colour JPEG: a level or two apart
    speck = grey.copy()
    speck[:4, :4] = (0, 0, 255)  # 16 of 76 800 pixels coloured: still a grey frame
    patch = grey.copy()
    patch[:, :40] = colour[:, :40]  # an eighth of the frame in colour
    faint = grey.astype(np.int16)
    faint[..., 2] += 4  # a colour cast of four levels over the whole frame
    faint = np.clip(faint, 0, 255).astype(np.uint8)
    previous = set_numba_enabled(compiled)
    try:
        for frame in (colour, grey, grey_jpeg, speck, patch, faint):
            assert frame_is_grey(frame) == is_gray(frame)
        assert [frame_is_grey(f) for f in (colour, grey, grey_jpeg, speck, patch, faint)] == [
            False, True, True, True, False, False]
        assert frame_is_grey(grey[..., 0])  # a 2-D frame is grey
        assert frame_is_blank(np.zeros_like(colour)) and frame_is_blank(np.full_like(colour, 255))
        assert frame_is_blank(np.full_like(colour, 90)) and not frame_is_blank(grey)
    finally:
        set_numba_enabled(previous)


def test_grey_copy_is_the_grey_image_in_three_channels():
    rng = np.random.default_rng(1)
    colour = (rng.random((60, 80, 3)) * 255).astype(np.uint8)
    g = grey_copy(colour)
    assert g.shape == colour.shape and frame_is_grey(g)
    np.testing.assert_array_equal(g[..., 0], cv2.cvtColor(colour, cv2.COLOR_BGR2GRAY))
    assert grey_copy(g) is g


def test_the_switch_waits_for_n_grey_frames_and_ignores_blank_ones():
    rng = np.random.default_rng(2)
    colour = (rng.random((60, 80, 3)) * 255).astype(np.uint8)
    grey, black = _grey(colour), np.zeros_like(colour)
    s = InputSwitch(3)
    assert [s.observe(f) for f in (grey, grey, colour, grey, black, grey)] == [False] * 6  # the row was broken
    assert s.observe(grey)  # grey, black (no evidence), grey, grey: three grey frames in a row
    with pytest.raises(ValueError):
        InputSwitch(0)


# ------------------------------------------------------------------ the trackers
@pytest.mark.parametrize("seed", [2100, 2101, 2102])
def test_color_pf_keeps_a_target_in_view_when_the_input_turns_grey(seed):
    frames, gt = _turning_grey(varied_scene(seed, n_frames=50, gray=0.0, illumination=0.0))
    results = {}
    for n in (0, 1):
        t, states = _run("color-pf", frames, gt, input_switch=n)
        after = states[SWITCH - 1:]
        iou = frame_ious(np.array([s.box for s in after]), gt[SWITCH:])
        results[n] = (float(np.mean([s.lost for s in after])), float(iou.mean()), t.cue.color_space)
    assert results[0][0] > 0.5  # colour features on grey frames: the target in view called lost
    lost, iou, space = results[1]
    assert lost <= 0.05 and iou >= 0.6 and space == "gray"


@pytest.mark.parametrize("name", ["fusion-pf", "local-motion-pf"])
def test_default_trackers_switch_and_keep_the_target(name):
    flags, ious = [], []
    for seed in (2103, 2104):
        frames, gt = _turning_grey(varied_scene(seed, n_frames=50, gray=0.0, illumination=0.0))
        t, states = _run(name, frames, gt)  # input_switch = 1 is their default
        assert t.cue.color_space == "gray" and t.frame_index == len(frames) - 1
        assert states[SWITCH - 1].info.get("input_switch") == "grey"
        after = states[SWITCH - 1:]
        flags += [s.lost for s in after]
        ious.append(frame_ious(np.array([s.box for s in after]), gt[SWITCH:]).mean())
    assert np.mean(flags) <= 0.05 and min(ious) >= 0.5


def test_colour_input_without_grey_frames_is_tracked_as_before():
    scene = Scene(varied_scene(2105, n_frames=30, gray=0.0))
    frames, gt = scene.frames(), scene.groundtruth(0)
    frames[12] = np.zeros_like(frames[12])  # a cut to black: no evidence of a monochrome camera
    runs = [_run("fusion-pf", frames, gt, input_switch=n) for n in (0, 1)]
    assert runs[1][0].cue.color_space == "rgb"
    for a, b in zip(runs[0][1], runs[1][1]):
        assert a.box == b.box and a.lost == b.lost and a.score == b.score
        np.testing.assert_array_equal(a.particles, b.particles)


def test_grey_input_from_the_start_keeps_its_features():
    scene = Scene(varied_scene(2106, n_frames=20, gray=1.0))
    frames, gt = scene.frames(), scene.groundtruth(0)
    t, _ = _run("fusion-pf", frames, gt)
    assert t._input is None and t.cue.color_space == "gray"


def test_a_switch_while_the_target_is_hidden_starts_from_where_it_was_seen_and_searches():
    for seed in range(2110, 2130):
        spec = vanish_scene(seed, n_frames=120, gray=0.0, illumination=0.0)
        hid = np.flatnonzero(hidden_frames(spec))
        if hid.size >= 10 and hid[0] >= 15:
            break
    at = int(hid[0]) + 5
    frames, gt = _turning_grey(spec, at=at)
    t = pftrack.create_tracker("fusion-pf", seed=0)
    t.init(frames[0], tuple(gt[0]))
    states = [t.update(f) for f in frames[1:at + 1]]
    if not states[at - 2].lost:
        pytest.skip("the tracker had not declared the loss before the switch")
    seen = [k + 1 for k, s in enumerate(states[:at - 1]) if not s.lost][-1]  # last frame with the target seen
    assert states[-1].lost and t.mode == "searching" and t.cue.color_space == "gray"
    assert t.frame_index == at
    # the grey features were started on the frame where the target was last seen, at its box there
    np.testing.assert_allclose(t.size, (states[seen - 1].box[2] / 2, states[seen - 1].box[3] / 2), rtol=1e-6)


# ------------------------------------------------------------------ input_switch_return
def test_colour_return_waits_for_n_colour_frames_and_ignores_blank_ones():
    rng = np.random.default_rng(3)
    colour = (rng.random((60, 80, 3)) * 255).astype(np.uint8)
    grey, white = _grey(colour), np.full_like(colour, 255)
    back = ColourReturn(None, 2)
    assert [back.observe(f) for f in (colour, grey, colour, white)] == [False] * 4  # grey broke the row
    assert back.observe(colour)  # colour, white (no evidence), colour: two colour frames in a row


def _switch_during_a_search(name="fusion-pf"):
    """A vanish scene whose frames are grey for a block that starts while the tracker searches (frames, gt, at,
    end): the target hidden from ``hid[0]``, the frames grey on ``at .. end - 1``."""
    for seed in range(2110, 2140):
        spec = vanish_scene(seed, n_frames=120, gray=0.0, illumination=0.0)
        hid = np.flatnonzero(hidden_frames(spec))
        if hid.size < 10 or hid[0] < 15:
            continue
        at, end = int(hid[0]) + 5, int(hid[0]) + 35
        scene = Scene(spec)
        frames = [_grey(f) if at <= i < end else f for i, f in enumerate(scene.frames())]
        gt = scene.groundtruth(0)
        _, states = _run(name, frames[:at], gt)
        if states[-1].lost:
            return frames, gt, at, end
    pytest.skip("no scene with the loss declared before the switch")


def _same(a, b):
    assert a.box == b.box and a.lost == b.lost and a.score == b.score
    np.testing.assert_array_equal(a.particles, b.particles)


def test_a_switch_during_a_search_goes_on_by_colour_once_colour_returns():
    frames, gt, at, end = _switch_during_a_search()
    grey_only = _run("fusion-pf", frames, gt, input_switch_return=0)[1]  # grey features to the end
    colour_only = _run("fusion-pf", frames, gt, input_switch=0)[1]  # no switch: colour features throughout
    t, states = _run("fusion-pf", frames, gt, input_switch_return=1)
    assert states[at - 1].info.get("input_switch") == "grey"
    assert states[end - 1].info.get("input_switch") == "colour"
    for k in range(end - 1):  # up to the frame before colour returns: the grey-featured tracker's output
        _same(states[k], grey_only[k])
    for k in range(end - 1, len(states)):  # from it: exactly the tracker that never switched
        _same(states[k], colour_only[k])
    assert t.cue.color_space == "rgb" and t._return is None and t._input is None
    assert t.frame_index == len(frames) - 1


def test_a_tracker_that_cannot_be_copied_keeps_grey_features():
    frames, gt, at, end = _switch_during_a_search()
    grey_only = _run("fusion-pf", frames, gt, input_switch_return=0)[1]
    t = pftrack.create_tracker("fusion-pf", seed=0, params={"input_switch_return": 1})
    t.init(frames[0], tuple(gt[0]))
    t._native = cv2.createBackgroundSubtractorMOG2()  # a library object without a copy
    states = [t.update(f) for f in frames[1:]]
    assert t._return is None and t.cue.color_space == "gray"
    for a, b in zip(states, grey_only):
        _same(a, b)


def test_a_switch_while_tracking_is_unchanged_by_input_switch_return():
    frames, gt = _turning_grey(varied_scene(2103, n_frames=50, gray=0.0, illumination=0.0))
    runs = [_run("fusion-pf", frames, gt, input_switch_return=n) for n in (0, 1)]
    assert runs[1][1][SWITCH - 1].info.get("input_switch") == "grey" and runs[1][0]._return is None
    for a, b in zip(runs[0][1], runs[1][1]):
        _same(a, b)


# ------------------------------------------------------------------ any tracker: grey_restart
def test_grey_restart_wraps_any_tracker_without_turning_the_monitor_on():
    from pftrack.eval.runner import parse_tracker_list
    from pftrack.trackers.input_switch import GreyRestarted
    from pftrack.trackers.monitor import Monitored

    t = pftrack.create_tracker("meanshift", grey_restart=2)
    assert isinstance(t, GreyRestarted) and t.after == 2
    both = pftrack.create_tracker("meanshift", params={"grey_restart": 1, "monitor": True})
    assert isinstance(both, Monitored) and isinstance(both.inner, GreyRestarted)
    assert not isinstance(pftrack.create_tracker("meanshift"), GreyRestarted)
    cotrain = pftrack.create_tracker("cotrain-pf")  # its default, chosen on the tune data
    assert isinstance(cotrain, GreyRestarted) and cotrain.name == "cotrain-pf" and cotrain.params.margin > 0
    assert hasattr(cotrain, "confidence_map")  # the tracker's own methods pass through
    assert not isinstance(pftrack.create_tracker("cotrain-pf", grey_restart=0), GreyRestarted)
    assert parse_tracker_list("meanshift[grey_restart=1]")[0].param_dict == {"grey_restart": "1"}


def test_grey_restart_keeps_a_mean_shift_on_its_target_when_the_input_turns_grey():
    frames, gt = _turning_grey(varied_scene(2100, n_frames=50, gray=0.0, illumination=0.0))
    ious = {}
    for n in (0, 1):
        _, states = _run("meanshift", frames, gt, grey_restart=n)
        ious[n] = frame_ious(np.array([s.box for s in states[SWITCH - 1:]]), gt[SWITCH:]).mean()
        if n:
            assert states[SWITCH - 1].info.get("input_switch") == "grey"
    assert ious[0] < 0.3 and ious[1] >= 0.6


def test_grey_restart_leaves_colour_input_as_it_was():
    scene = Scene(varied_scene(2105, n_frames=25, gray=0.0))
    frames, gt = scene.frames(), scene.groundtruth(0)
    plain = _run("meanshift", frames, gt)[1]
    wrapped = _run("meanshift", frames, gt, grey_restart=1)[1]
    assert [s.box for s in plain] == [s.box for s in wrapped]


def test_no_switch_on_the_bundled_clip_or_the_development_sequences():
    """The check agrees with the first frame on real colour video (the bundled clip, every frame; every fourth frame of
    the development sequences when they are at hand) and on their grey copies: input that never turns grey is
    tracked as before."""
    from pftrack.cli.track import demo_clip
    from pftrack.io.sources import open_source

    from .conftest import SHARED_DATA

    with open_source(str(demo_clip()[0])) as source:
        clip = list(source)
    assert not any(frame_is_grey(f) for f in clip)
    assert all(frame_is_grey(grey_copy(f)) and not frame_is_blank(grey_copy(f)) for f in clip[::10])
    names = ("davis16_blackswan", "otb_couple", "otb_motorrolling", "tld_pedestrian2", "vot_bag")
    folders = [SHARED_DATA / n for n in names if (SHARED_DATA / n).is_dir()]
    for folder in folders:
        paths = sorted((folder / "img").glob("*.jpg")) or sorted(folder.rglob("*.jpg"))
        for p in paths[::4]:
            f = cv2.imread(str(p), cv2.IMREAD_COLOR)
            assert not frame_is_grey(f), p.name
            assert frame_is_grey(_grey(f)), p.name
