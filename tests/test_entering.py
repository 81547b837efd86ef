"""A first box at the frame's edge: the target's extent measured while it comes in (``enter_extent``)."""

from __future__ import annotations

import numpy as np
import pytest

import pftrack
import pftrack.trackers.entering as entering_mod
from pftrack.cues.extent import (SURROUND, SURROUND_GREY, band_profile, edge_sides, extent_box, grow_run,
                                 object_surround_lut, surround_roi)
from pftrack.geometry import iou, visible_box
from pftrack.synth import entering_scene, simple_scene

from .conftest import render_scene


# ------------------------------------------------------------------------------ pure functions
def test_edge_sides():
    assert edge_sides((0, 50, 3, 60), 320, 240) == "L"
    assert edge_sides((0.8, 0, 10, 10), 320, 240) == "LT"
    assert edge_sides((300, 200, 20, 40), 320, 240) == "RB"
    assert edge_sides((2, 2, 10, 10), 320, 240) == ""
    assert edge_sides((0, 10, 320, 20), 320, 240) == "LR"


def test_surround_roi_is_cut_to_the_frame():
    assert surround_roi((0, 100, 4, 60), 320, 240, 0.5) == (0, 70, 34, 190)
    assert surround_roi((10, 10, 20, 10), 320, 240, 0.5) == (0, 0, 40, 30)
    assert SURROUND == 0.75
    assert surround_roi((0, 100, 4, 60), 320, 240) == (0, 55, 49, 205)
    assert surround_roi((300, 10, 20, 10), 320, 240) == (285, 0, 320, 35)


def test_object_surround_lut():
    bins = np.full((20, 30), 2, dtype=np.uint16)
    bins[5:15, 0:4] = 1  # the box
    bins[0, 0] = 3  # one surround pixel of a bin also seen... nowhere inside
    lut = object_surround_lut(bins, 100, 50, (100, 55, 4, 10), 5)
    assert lut[1] == 1.0 and lut[2] == 0.0 and lut[3] == 0.0
    assert lut[0] == lut[4] == 0.5  # seen in neither
    # a bin shared half and half is not object-like
    bins[5:15, 2:4] = 2
    bins[0:10, 20:22] = 1
    lut = object_surround_lut(bins, 100, 50, (100, 55, 4, 10), 5)
    assert lut[1] == pytest.approx(0.5) and lut[2] < 0.5


def test_band_profile_rows_and_columns():
    bins = np.zeros((10, 12), dtype=np.uint16)
    bins[:, 3:7] = 1
    bins[:5, 7] = 1  # half a column
    lut = np.array([0.0, 1.0], dtype=np.float32)
    cols = band_profile(bins, lut, 1)
    assert cols.shape == (12,)
    raw = np.array([0, 0, 0, 1, 1, 1, 1, 0.5, 0, 0, 0, 0])
    padded = np.concatenate(([raw[0]], raw, [raw[-1]]))
    np.testing.assert_allclose(cols, (padded[:-2] + padded[1:-1] + padded[2:]) / 3)
    rows = band_profile(bins.T.copy(), lut, 0)
    np.testing.assert_allclose(rows, cols)


def test_grow_run():
    prof = np.array([0.9, 0.8, 0.9, 0.5, 0.1, 0.0, 0.3, 0.9, 0.9])
    assert grow_run(prof, 1, 3) == (0, 4)  # peak 0.9 at line 2; 0.1 < 0.2 * 0.9 stops it at line 4
    assert grow_run(prof, 7, 9) == (6, 9)  # runs to the band's end
    assert grow_run(prof, 4, 6, min_peak=0.25) is None  # nothing object-like on those lines
    assert grow_run(prof, 1, 3, share=0.6) == (0, 3)
    assert grow_run(prof, 5, 5) is None


def test_extent_box_and_its_cap():
    assert extent_box((0, 50, 4, 60), (0, 25), 0, 1, 180) == (0.0, 50, 25.0, 60)
    assert extent_box((10, 5, 30, 8), (2, 40), 100, 0, 1000) == (10, 102.0, 30, 38.0)
    x, y, w, h = extent_box((0, 50, 4, 60), (0, 300), 0, 1, 180)
    assert (x, y, w, h) == (0, 50, 180, 60)  # centred on the box as far as the run allows
    assert extent_box((150, 50, 4, 60), (0, 300), 0, 1, 180)[:3] == (62.0, 50, 180.0)
    assert extent_box((290, 50, 4, 60), (0, 300), 0, 1, 180)[:3] == (120.0, 50, 180.0)
    # with keep, never narrower than the box
    assert extent_box((0, 50, 30, 60), (0, 10), 0, 1, 180, keep=True) == (0.0, 50, 30.0, 60)
    assert extent_box((0, 50, 30, 60), (0, 45), 0, 1, 180, keep=True) == (0.0, 50, 45.0, 60)
    assert extent_box((5, 10, 40, 20), (0, 12), 8, 0, 100, keep=True) == (5, 8.0, 40, 22.0)


# ------------------------------------------------------------------------------ trackers
def _scene(seed: int, orient: str):
    """An entering scene (from the left), mirrored (from the right) or transposed (from the top): frames and the
    boxes in view."""
    scene, frames, _ = render_scene(entering_scene(seed, enter_at=15))
    gt = scene.groundtruth(0)
    if orient == "right":
        frames = [np.ascontiguousarray(f[:, ::-1]) for f in frames]
        gt = np.column_stack([frames[0].shape[1] - gt[:, 0] - gt[:, 2], gt[:, 1], gt[:, 2], gt[:, 3]])
    elif orient == "top":
        frames = [np.ascontiguousarray(f.transpose(1, 0, 2)) for f in frames]
        gt = gt[:, [1, 0, 3, 2]]
    h, w = frames[0].shape[:2]
    cut = np.full_like(gt, np.nan)
    for t, b in enumerate(gt):
        if np.isfinite(b[0]) and b[0] < w and b[1] < h and b[0] + b[2] > 0 and b[1] + b[3] > 0:
            cut[t] = visible_box(tuple(b), w, h) or tuple(b)
    return frames, cut


def _run(name, frames, gt, **params):
    first = int(np.flatnonzero(np.isfinite(gt[:, 0]))[0])
    tr = pftrack.create_tracker(name, seed=0, **params)
    states = [tr.init(frames[first], gt[first])]
    states += [tr.update(f) for f in frames[first + 1:]]
    overlap = np.array([iou(s.box, g) for s, g in zip(states, gt[first:])])
    return states, overlap


@pytest.mark.parametrize("orient", ["left", "right", "top"])
@pytest.mark.parametrize("name", ["color-pf", "fusion-pf"])
def test_a_sliver_at_the_edge_grows_to_the_target(name, orient):
    means_on, means_off = [], []
    for seed in (0, 1, 2):
        frames, gt = _scene(seed, orient)
        assert np.nanmin(gt[:, 2 if orient != "top" else 3]) < 5  # the first box is a sliver
        states, on = _run(name, frames, gt, enter_extent=30)
        _, off = _run(name, frames, gt, enter_extent=0)
        means_on.append(on[10:].mean())
        means_off.append(off[10:].mean())
        flags = [s.info.get("entering", False) for s in states]
        assert any(flags) and not flags[0]
        assert sum(bool(s.info.get("entered")) for s in states) == 1  # one restart, once the target is in
        assert not any(s.lost for s in states)
    assert min(means_on) > 0.7, means_on
    assert np.mean(means_on) > np.mean(means_off) + 0.4, (means_on, means_off)


def test_while_entering_the_box_reaches_the_edge_and_the_target():
    frames, gt = _scene(3, "left")
    states, overlap = _run("color-pf", frames, gt, enter_extent=30)
    entering = [i for i, s in enumerate(states) if s.info.get("entering")]
    assert entering
    for i in entering:
        assert states[i].box[0] == 0.0
    assert overlap[entering].mean() > 0.75


def test_a_box_off_the_edges_changes_nothing():
    scene, frames, _ = render_scene(simple_scene(4))
    gt = scene.groundtruth(0)
    a = pftrack.create_tracker("fusion-pf", seed=1, enter_extent=0)
    b = pftrack.create_tracker("fusion-pf", seed=1, enter_extent=30)
    sa, sb = a.init(frames[0], gt[0]), b.init(frames[0], gt[0])
    assert b._entering is None
    for f in frames[1:25]:
        sa, sb = a.update(f), b.update(f)
        assert sa.box == sb.box and sa.score == sb.score
        np.testing.assert_array_equal(sa.particles, sb.particles)


def test_a_box_spanning_the_frame_is_not_armed_across_it():
    frames, gt = _scene(0, "left")
    h, w = frames[0].shape[:2]
    tr = pftrack.create_tracker("color-pf", seed=0, enter_extent=30)
    tr.init(frames[40], (0, 50, w, 60))
    assert tr._entering is None
    tr.init(frames[40], (0, 0, w, 60))  # only its other axis may be measured
    assert tr._entering is not None and (tr._entering["side"], tr._entering["axis"]) == ("T", 0)
    tr.init(frames[40], (0, 0, w, h))
    assert tr._entering is None


def test_the_phase_ends_after_its_frames():
    frames, gt = _scene(0, "left")
    first = int(np.flatnonzero(np.isfinite(gt[:, 0]))[0])
    tr = pftrack.create_tracker("color-pf", seed=0, enter_extent=3)
    tr.init(frames[first], gt[first])
    states = [tr.update(f) for f in frames[first + 1:first + 6]]
    assert [bool(s.info.get("entering")) for s in states[:2]] == [True, True]
    assert states[2].info.get("entered")  # restarted from the box still at the edge
    assert tr._entering is None and not any(s.info.get("entering") for s in states[3:])


def test_a_whole_target_at_the_edge_is_not_cut_to_its_most_distinct_part():
    """A first box holding the whole target, at the edge; only its left third has colours the surround lacks (the
    rest is the surround's colour): the box reported is never narrower than the tracked one, and no restart."""
    rng = np.random.default_rng(5)
    frames = []
    for t in range(12):
        f = rng.normal(120, 6, (240, 320, 3)).clip(0, 255).astype(np.uint8)
        f[:, 45:] = (40, 160, 40)  # the surround's colour beyond a gap
        f[100:160, 0:10] = (30, 30, 200)
        f[100:160, 10:30] = (40, 160, 40)
        frames.append(f)
    box = (0.0, 100.0, 30.0, 60.0)
    tr = pftrack.create_tracker("color-pf", seed=0, enter_extent=8)
    tr.init(frames[0], box)
    assert tr._entering is not None
    states = [tr.update(f) for f in frames[1:]]
    for s in states:
        tracked = s.info.get("box_tracked", s.box)
        tracked = visible_box(tracked, 320, 240) or tracked  # the part in view
        assert s.box[2] >= tracked[2] - 1e-9
    assert not any(s.info.get("entered") for s in states)
    assert tr._entering is None  # the frames were spent


def _walker_leaving_the_edge(n: int = 14):
    """A walker (red over blue, 20 x 60) whose first box, at the right edge, holds a strip of ground whose colour the
    first box's near surround lacks (it lies 36-56 px to the left); he walks away from the edge at 4 px a frame."""
    rng = np.random.default_rng(11)
    ground = (60, 110, 150)
    frames, boxes = [], []
    for t in range(n):
        f = rng.normal(128, 10, (240, 320, 3)).clip(0, 255).astype(np.uint8)
        f[100:180, 236:256] = ground
        f[100:180, 290:320] = ground
        x = 296 - 4 * t
        f[110:140, x:x + 20] = (40, 40, 210)
        f[140:170, x:x + 20] = (200, 90, 30)
        frames.append(f)
        boxes.append((x - 4.0, 105.0, 28.0, 70.0))
    boxes[0] = (292.0, 105.0, 28.0, 70.0)  # touches the right edge
    return frames, boxes


@pytest.mark.parametrize("name", ["color-pf", "fusion-pf"])
def test_ground_a_walker_hid_at_the_edge_is_not_taken_for_him(name, monkeypatch):
    """Ground that the first box hid reads as background on the first frame's table when the surround reaches far
    enough (SURROUND): the walker's box is not widened to the edge.  With the former half side it was."""
    frames, boxes = _walker_leaving_the_edge()

    def run():
        tr = pftrack.create_tracker(name, seed=0, enter_extent=8)
        tr.init(frames[0], boxes[0])
        assert tr._entering is not None
        states = [tr.update(f) for f in frames[1:]]
        return states, [s.box[2] for s in states]

    states, widths = run()
    assert not any(s.info.get("entered") for s in states)
    assert max(widths) < 1.25 * 28
    assert np.mean([iou(s.box, b) for s, b in zip(states, boxes[1:])]) > 0.5
    monkeypatch.setattr(entering_mod, "SURROUND", 0.5)
    states, widths = run()
    assert max(widths) > 1.25 * 28  # the former surround took the ground for him


def test_grey_features_keep_the_former_surround():
    """The wider surround was chosen on colour input; a grey frame's table is taken over the former half side."""
    frames, boxes = _walker_leaving_the_edge()
    grey = np.repeat(frames[0].mean(axis=2, keepdims=True).astype(np.uint8), 3, axis=2)
    for frame, margin in ((frames[0], SURROUND), (grey, SURROUND_GREY)):
        tr = pftrack.create_tracker("color-pf", seed=0, enter_extent=8)
        tr.init(frame, boxes[0])
        assert (tr.cue.color_space == "gray") == (frame is grey)
        feats = tr.cue.prepare(frame, surround_roi(boxes[0], 320, 240, margin), 1)
        expect = object_surround_lut(feats.bins, feats.x0, feats.y0, boxes[0], tr.cue.feature_bins)
        np.testing.assert_array_equal(tr._entering["lut"], expect)
    assert SURROUND_GREY == 0.5 < SURROUND


def test_a_detectors_first_box_at_the_edge_arms_it():
    """A detection that starts the tracking after frames without one is a box given, as the first frame's is."""
    frames, gt = _scene(1, "left")
    first = int(np.flatnonzero(np.isfinite(gt[:, 0]))[0])

    def detector(frame):
        t = next(i for i, f in enumerate(frames) if f is frame)
        return [] if t < first else [tuple(gt[t]) + (0.9,)]

    tr = pftrack.create_tracker("color-pf", seed=0, detector=detector)
    assert tr.init_detect(frames[0]).lost
    states = [tr.update(f) for f in frames[1:first + 8]]
    assert tr.mode == "tracking"
    entering = [bool(s.info.get("entering")) for s in states[first:]]
    assert entering[:3] == [True, True, True]
    assert states[first + 2].box[2] > 2 * gt[first][2]  # grown beyond the sliver detected


def test_change_mask():
    from pftrack.cues.extent import change_mask

    first = np.full((10, 20), 100, np.uint8)
    now = first.copy()
    now[2:8, 3:9] = 130
    now[0, 0] = 110  # within the levels
    mask = change_mask(now, first)
    assert mask.dtype == np.uint8 and mask.sum() == 36 and mask[2:8, 3:9].all()
    assert change_mask(np.full_like(first, 160), first) is None  # the light changed, not a target


@pytest.mark.parametrize("name", ["color-pf", "fusion-pf"])
def test_a_grey_sliver_grows_by_what_changed(name):
    """On grey input the entering targets have their ground's levels: the extent is read on what changed against
    the first frame, and the filter restarts as soon as that has grown."""
    means_on, means_off = [], []
    for seed in (0, 1, 2):
        frames, gt = _scene(seed, "left")
        frames = [np.repeat(f.mean(axis=2, keepdims=True).astype(np.uint8), 3, axis=2) for f in frames]
        states, on = _run(name, frames, gt, enter_extent=30, enter_grey=True)
        _, off = _run(name, frames, gt, enter_extent=30, enter_grey=False)
        means_on.append(on.mean())
        means_off.append(off.mean())
        assert any(s.info.get("entered") for s in states)
    assert np.mean(means_on) > np.mean(means_off) + 0.3, (means_on, means_off)


def test_a_grey_view_whose_light_changes_measures_nothing():
    frames, gt = _scene(0, "left")
    frames = [np.repeat(f.mean(axis=2, keepdims=True).astype(np.uint8), 3, axis=2) for f in frames]
    first = int(np.flatnonzero(np.isfinite(gt[:, 0]))[0])
    lit = [frames[first]] + [np.clip(f.astype(np.int16) + 60, 0, 255).astype(np.uint8) for f in frames[first + 1:]]
    tr = pftrack.create_tracker("fusion-pf", seed=0, enter_extent=30, enter_grey=True)
    tr.init(lit[0], gt[first])
    assert tr._entering is not None and "first" in tr._entering
    states = [tr.update(f) for f in lit[1:6]]
    assert not any(s.info.get("entered") for s in states)
    for s in states:
        assert s.box[2] <= 2 * gt[first][2] + 2  # nothing measured: the box followed
