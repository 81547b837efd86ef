"""``cast_jump``: a white balance that jumps between two frames, read from the frames and undone in the RGB bins
(pftrack.cues.still_gain.frame_jump, pftrack.cues.histogram_cue; docs/rules/cast_jump_rule.txt)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.cues.color import bhattacharyya_coefficient
from pftrack.cues.histogram_cue import ColorCue
from pftrack.cues.still_gain import frame_jump, reference_lattice
from pftrack.errors import ParameterError
from pftrack.eval.metrics import lost_detection
from pftrack.geometry import box_to_ellipse, iou
from pftrack.synth import hidden_frames, vanish_scene

from .conftest import render_scene

#: a warm cast: blue times 0.75, red times 1.25 (BGR), green as it is
WARM = np.array([0.75, 1.0, 1.25], np.float32)


def _cast(frame: np.ndarray, gains=WARM) -> np.ndarray:
    return np.clip(frame.astype(np.float32) * gains, 0, 255).astype(np.uint8)


def _shift(frame: np.ndarray, dx: float, dy: float) -> np.ndarray:
    m = np.float32([[1, 0, dx], [0, 1, dy]])
    return cv2.warpAffine(frame, m, (frame.shape[1], frame.shape[0]), borderMode=cv2.BORDER_REFLECT)


def _colour_frame(seed: int = 2) -> tuple[np.ndarray, np.ndarray]:
    scene, frames, _ = render_scene(vanish_scene(seed, gray=0.0))
    return frames[0], scene.groundtruth(0)[0]


def test_frame_jump_reads_a_cast_and_not_a_camera_move():
    f, _ = _colour_frame()
    med, mad = frame_jump(reference_lattice(f), reference_lattice(_cast(f)))
    # the levels are rounded to integers, so the log-ratios of dark pixels scatter: medians within 0.03
    np.testing.assert_allclose(med, np.log(WARM), atol=0.03)
    assert np.all(mad < 0.1), mad
    med, _ = frame_jump(reference_lattice(f), reference_lattice(_shift(f, 6, -4)))
    assert med.max() - med.min() < 0.05, med  # a camera move: no chromatic jump
    med, _ = frame_jump(reference_lattice(f), reference_lattice(f))
    np.testing.assert_array_equal(med, 0.0)


@pytest.mark.parametrize("normalize", ["none", "still"])
def test_the_bins_undo_a_jump_on_a_moving_view(normalize):
    """After a cast on a frame the camera has moved for (no still view), the target's histogram read through the
    cue is the one before the cast; without cast_jump it is not."""
    f, box = _colour_frame()
    ell = box_to_ellipse(box)
    coeff = {}
    for cj in (0.0, 0.2):
        cue = ColorCue("rgb", normalize=normalize, cast_jump=cj)
        cue.adapt_to(f)
        cue.new_frame(f)
        q = cue.histogram(f, ell)
        moved = _shift(f, 5, 3)  # the view moves, so "still" holds its gain (1)
        cue.new_frame(moved)
        g = _shift(_cast(f), 5, 3)
        cue.new_frame(g)  # the cast comes on the next frame
        e = np.array([ell[0] + 5, ell[1] + 3, *ell[2:]])
        h = cue.histogram(g, e)
        coeff[cj] = float(bhattacharyya_coefficient(q / q.sum(), h / h.sum()))
    assert coeff[0.2] > 0.95, coeff
    assert coeff[0.0] < coeff[0.2] - 0.1, coeff


def test_a_still_view_gain_replaces_the_jumps():
    """With "still", a still view's gain against the first frame (which holds the cast) replaces the jumps' product,
    so the gain is not applied twice."""
    f, _ = _colour_frame()
    cue = ColorCue("rgb", normalize="still", cast_jump=0.2)
    cue.adapt_to(f)
    cue.new_frame(f)
    cue.new_frame(_cast(f))  # still view: the still gain takes the cast
    np.testing.assert_allclose(cue._still_gain, WARM, atol=0.04)
    np.testing.assert_array_equal(cue._cast_gain, 1.0)
    cue.new_frame(_shift(_cast(f), 6, 2))  # moving: held, no jump
    np.testing.assert_allclose(cue._still_gain * cue._cast_gain, WARM, atol=0.04)


def test_cast_jump_is_checked():
    with pytest.raises(ValueError):
        ColorCue("rgb", normalize="gain", cast_jump=0.2)
    with pytest.raises(ValueError):
        ColorCue("rgb", cast_jump=-1.0)
    with pytest.raises(ParameterError):
        pftrack.create_tracker("color-pf", cast_jump=0.2, color_normalize="equalize")
    t = pftrack.create_tracker("color-pf", cast_jump=0.2)
    assert t.cue.cast_jump == 0.2


def _handheld(frames, gt, seed: int, step: float = 3.0):
    """The frames seen by a camera that wanders (a random walk of ``step`` px a frame, within 20 px) and the ground
    truth carried with it."""
    rng = np.random.default_rng([seed, 5])
    off = np.cumsum(rng.normal(0, step, (len(frames), 2)), 0)
    off = np.clip(off - off[0], -20, 20)
    gt = gt.copy()
    gt[:, :2] += off
    return [_shift(f, *o) for f, o in zip(frames, off)], gt


def _cast_run(tracker: str, seed: int, cast_jump: float, *, handheld: bool):
    """A colour vanish scene whose white balance jumps 3 frames after the target is hidden (so it comes out in the
    new colours): mean IoU over the visible frames and the lost flag scored as a detector."""
    spec = vanish_scene(seed, gray=0.0)
    scene, frames, _ = render_scene(spec)
    gt, hid = scene.groundtruth(0), hidden_frames(spec)
    start = int(np.flatnonzero(hid)[0]) + 3
    frames = [_cast(f) if k >= start else f for k, f in enumerate(frames)]
    if handheld:
        frames, gt = _handheld(frames, gt, seed)
    t = pftrack.create_tracker(tracker, seed=seed, cast_jump=cast_jump)
    t.init(frames[0], tuple(gt[0]))
    states = [t.update(f) for f in frames[1:]]
    boxes = np.array([s.box for s in states])
    lost = np.array([s.lost for s in states])
    d = lost_detection(lost, boxes, gt[1:], hid[1:])
    ious = [iou(b, g) for b, g in zip(boxes, gt[1:]) if np.all(np.isfinite(g))]
    return float(np.mean(ious)), d.false_rate


def test_color_pf_keeps_a_target_whose_light_jumped_while_hidden():
    """color-pf (no other normalisation) on four colour vanish scenes, the cast while the target is hidden.
    Measured over seeds 0-3: mean IoU 0.421 -> 0.525, mean false-lost rate 0.021 -> 0.010 (seeds 0-5: 0.433 -> 0.502,
    0.035 -> 0.007)."""
    runs = {cj: [_cast_run("color-pf", s, cj, handheld=False) for s in range(4)] for cj in (0.0, 0.2)}
    iou_off, iou_on = (np.mean([r[0] for r in runs[cj]]) for cj in (0.0, 0.2))
    false_off, false_on = (np.nanmean([r[1] for r in runs[cj]]) for cj in (0.0, 0.2))
    assert iou_on > iou_off + 0.03, (iou_off, iou_on)
    assert false_on < 0.02 and false_on < false_off, (false_off, false_on)


def test_fusion_pf_follows_a_jump_of_the_light_on_a_hand_held_view():
    """fusion-pf's still gain cannot read a moving view; the jump can. Four colour vanish scenes seen by a wandering
    camera, the cast while the target is hidden. Measured over seeds 0-3: mean IoU 0.425 -> 0.554 (seeds 0-5: 0.394
    -> 0.505). Not every scene gains: cut to 80 frames, seed 4 is not re-acquired with the jump undone (its light
    also drifts, and the cast had cancelled part of that drift; docs/robustness.md)."""
    runs = {cj: [_cast_run("fusion-pf", s, cj, handheld=True) for s in range(4)] for cj in (0.0, 0.2)}
    iou_off, iou_on = (np.mean([r[0] for r in runs[cj]]) for cj in (0.0, 0.2))
    assert iou_on > iou_off + 0.06, (iou_off, iou_on)


def test_no_jump_read_on_a_scene_without_one():
    """The same hand-held scene without a cast: the gain stays 1 and the tracks are those of cast_jump = 0."""
    spec = vanish_scene(3, gray=0.0)
    scene, frames, _ = render_scene(spec)
    frames, gt = _handheld(list(frames), scene.groundtruth(0), 3)
    boxes = {}
    for cj in (0.0, 0.2):
        t = pftrack.create_tracker("fusion-pf", seed=0, cast_jump=cj)
        t.init(frames[0], tuple(gt[0]))
        boxes[cj] = np.array([t.update(f).box for f in frames[1:]])
        if cj:
            np.testing.assert_array_equal(t.cue._cast_gain, 1.0)
    np.testing.assert_array_equal(boxes[0.0], boxes[0.2])


def test_a_channel_clipped_almost_everywhere_reads_no_jump():
    """A saturated view (blue above the counted levels but for a few pixels, as on tld_pedestrian2's sky) must not
    read a jump from those few pixels."""
    f, _ = _colour_frame()
    f = f.copy()
    f[..., 0] = 250  # blue clipped everywhere
    g = f.copy()
    f[:48:16, :48:16, 0] = 100  # nine lattice pixels counted, whose blue then drops by a quarter
    g[:48:16, :48:16, 0] = 75
    med, mad = frame_jump(reference_lattice(f), reference_lattice(g))
    assert med[0] == 0.0 and np.isinf(mad[0]), (med, mad)
    cue = ColorCue("rgb", cast_jump=0.2)
    cue.adapt_to(f)
    cue.new_frame(f)
    cue.new_frame(g)
    np.testing.assert_array_equal(cue._cast_gain, 1.0)
    assert cue.lut is cue._base_lut


def test_cast_undo_returns_the_frame_before_the_jump():
    from pftrack.cues.still_gain import CastUndo

    f, _ = _colour_frame()
    undo = CastUndo(0.2)
    assert undo(f) is f  # the first frame: nothing to compare with
    g = undo(_cast(f))
    np.testing.assert_allclose(undo.gain, WARM, atol=0.03)
    ok = (f > 20) & (f < 200)  # away from the clipped and the darkest levels
    assert np.abs(g.astype(int) - f)[ok].max() <= 3
    h = _shift(_cast(f), 4, 2)  # later frames stay undone
    assert undo(h).mean() == pytest.approx(_shift(f, 4, 2).mean(), abs=1.0)
    with pytest.raises(ValueError):
        CastUndo(0.0)
    lamps = CastUndo(0.0, light=0.18)  # the common jump only
    lamps(f)
    lamps(_cast(f))  # a cast: not read
    lamps(f)
    np.testing.assert_array_equal(lamps.gain, 1.0)
    bright = np.clip(np.rint(f * 1.3), 0, 255).astype(np.uint8)
    g = lamps(bright)
    np.testing.assert_allclose(lamps.gain, 1.3, atol=0.03)
    ok = (f > 20) & (f < 190)
    assert np.abs(g.astype(int) - f)[ok].max() <= 3


def _mot_on_walkers(seed: int, change, **params):
    """multi-pf with ``params`` on two synthetic walkers (tests/test_mot.py's movers, 60 frames), frame ``t`` seen
    as ``change(t, frame)``: py-motmetrics' scores against the walkers' boxes."""
    from pftrack.eval.mot import mot_scores
    from pftrack.multi import create_multi_tracker

    from .test_mot import movers

    _, frames, truths = render_scene(movers(seed, n=60))
    tr = create_multi_tracker(seed=seed, **params)
    gt, hyp = [], []
    for t, f in enumerate(frames):
        gt.extend([t + 1, k + 1, *truths[t].boxes[k], 1] for k in range(2) if truths[t].present[k])
        hyp.extend([t + 1, o.track_id, *o.box, o.score] for o in tr.update(change(t, f)))
    return mot_scores(np.array(gt), np.array(hyp).reshape(-1, 7))


@pytest.mark.parametrize("gains, option", [(WARM, "cast_jump"), (np.full(3, 1.3, np.float32), "light_jump")])
def test_pftrack_mot_keeps_its_people_through_a_jump_of_the_light(gains, option):
    """multi-pf (MOG2 and colour models) on two walkers whose white balance jumps halfway (a warm cast), or whose
    lamps are switched on (every channel times 1.3): with the jump undone MOG2 does not take the view for foreground.
    Measured over seeds 0-3, both: MOTA 0.70-0.76 -> 0.875-0.883, false positives 3-9 -> 0."""
    from pftrack.multi import create_multi_tracker

    scores = {cj: [_mot_on_walkers(seed, lambda t, f: _cast(f, gains) if t >= 30 else f, **{option: cj})
                   for seed in range(4)] for cj in (0.0, 0.2)}
    mota = {cj: np.mean([s.mota for s in r]) for cj, r in scores.items()}
    assert mota[0.2] > mota[0.0] + 0.08, mota
    assert sum(s.num_false_positives for s in scores[0.2]) < sum(s.num_false_positives for s in scores[0.0])
    assert create_multi_tracker().params.cast_jump == 0.2 and create_multi_tracker().params.light_jump == 0.18


def test_a_switch_to_grey_and_back_reads_no_jump():
    """A camera switching to its grey night mode and back changes every channel differently between two frames, but
    it is no white balance: nothing is read, and the frames pass unchanged."""
    import cv2

    from pftrack.cues.still_gain import CastUndo

    f, _ = _colour_frame(4)
    grey = cv2.cvtColor(cv2.cvtColor(f, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR)
    med, mad = frame_jump(reference_lattice(f), reference_lattice(grey))
    assert np.isinf(mad).all(), (med, mad)
    undo = CastUndo(0.2)
    for frame in (f, grey, grey, f, _cast(f)):
        undo(frame)
    np.testing.assert_allclose(undo.gain, WARM, atol=0.03)  # the real cast at the end is still read
    undo = CastUndo(0.2)
    for frame in (f, grey, f):
        assert undo(frame) is frame
    np.testing.assert_array_equal(undo.gain, 1.0)


def test_a_grey_camera_s_lamps_are_read_only_when_asked():
    """Between two grey frames the channels' medians are equal: no chromatic jump, but lamps switched on move them
    together. ``grey=True`` (the tripwire's ``light_jump_grey``) reads that common jump and undoes it; by default grey
    frames read nothing (docs/rules/grey_light_rule.txt)."""
    from pftrack.cues.still_gain import CastUndo

    f, _ = _colour_frame(5)
    grey = cv2.cvtColor(cv2.cvtColor(f, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR)
    lit = _cast(grey, np.full(3, 1.3, np.float32))
    med, mad = frame_jump(reference_lattice(grey), reference_lattice(lit), grey=True)
    np.testing.assert_allclose(med, np.log(1.3), atol=0.03)
    assert med[0] == med[1] == med[2] and np.all(mad < 0.1), (med, mad)
    assert np.isinf(frame_jump(reference_lattice(grey), reference_lattice(lit))[1]).all()
    on, off = CastUndo(0.2, light=0.18, grey=True), CastUndo(0.2, light=0.18)
    for frame in (grey, grey, lit):
        back, kept = on(frame), off(frame)
    np.testing.assert_allclose(on.gain, 1.3, atol=0.04)
    assert np.abs(back.astype(int) - grey).mean() < 1.5  # the frame before the lamps, up to rounding and clipping
    assert np.all(back[..., 0] == back[..., 2])  # still grey
    assert kept is lit and np.all(off.gain == 1.0)
    # a switch from colour to grey is no jump, with or without grey=True
    undo = CastUndo(0.2, light=0.18, grey=True)
    for frame in (f, grey):
        assert undo(frame) is frame
    np.testing.assert_array_equal(undo.gain, 1.0)


def test_a_switch_to_grey_drops_the_cast_read_before_and_keeps_the_light():
    """A warm cast read on colour frames, then lamps: at a switch to a grey night mode the per-channel part of the
    gain goes (an undo channel by channel would colour the grey frames), the common part stays."""
    from pftrack.cues.still_gain import CastUndo

    f, _ = _colour_frame(6)
    undo = CastUndo(0.2, light=0.18)
    for frame in (f, _cast(f), _cast(f, WARM * 1.3)):
        undo(frame)
    np.testing.assert_allclose(undo.gain, WARM * 1.3, atol=0.05)
    grey = cv2.cvtColor(cv2.cvtColor(_cast(f, WARM * 1.3), cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR)
    out = undo(grey)
    g = undo.gain
    assert g[0] == g[1] == g[2], g
    np.testing.assert_allclose(g[0], np.exp(np.log(WARM * 1.3).mean()), atol=0.05)
    assert np.all(out[..., 0] == out[..., 1]) and np.all(out[..., 1] == out[..., 2])  # the grey frame stays grey


def test_clip_fill_gives_clipped_levels_their_level_before_the_jump():
    """Lamps times 1.5 on a bright view: levels above 170 clip at 255 and, undone, read 170. With ``clip_fill`` they
    take the level seen just before the jump (the truth is at least 255 / 1.5), so the undone frame is the frame
    before the lamps up to rounding; a level that was lower stays at 255 / gain."""
    from pftrack.cues.still_gain import CastUndo

    f, _ = _colour_frame(7)
    f = np.clip(f.astype(np.int16) + 30, 0, 255).astype(np.uint8)
    lit = _cast(f, np.full(3, 1.5, np.float32))
    clipped = lit == 255
    assert clipped.mean() > 0.1
    outs = {}
    for fill in (False, True):
        undo = CastUndo(0.2, light=0.18, clip_fill=fill)
        for frame in (f, f, lit, lit):
            out = undo(frame)
        outs[fill] = out.astype(int)
    assert np.abs(outs[True] - f).max() <= 1
    assert np.abs(outs[False] - f)[clipped].mean() > 10
    np.testing.assert_array_equal(outs[True][~clipped], outs[False][~clipped])
    # a frame drawn on after the call does not change what is filled later
    undo = CastUndo(0.2, light=0.18, clip_fill=True)
    g = f.copy()
    undo(f)
    undo(g)
    g[:] = 0
    assert np.abs(undo(lit).astype(int) - f).max() <= 1


@pytest.mark.parametrize("grey", [False, True])
def test_pftrack_mot_keeps_its_people_when_lamps_clip_a_bright_view(grey):
    """multi-pf on two walkers over a bright ground (levels 60 higher) whose lamps go to 1.4 halfway, so that most of
    the ground clips; and on the same walkers seen by a grey camera whose lamps go to 1.3. The defaults
    (``clip_fill``, ``light_jump_grey``) against each switched off, seeds 0-2. Measured: colour MOTA 0.71-0.72
    against 0.29-0.39 (false positives 11-16 against 45-66); grey -0.06 to 0.28 against -0.26 to 0.12 (these grey
    walkers are hard for MOG2 with or without lamps)."""
    from pftrack.multi import create_multi_tracker

    option = "light_jump_grey" if grey else "clip_fill"
    assert getattr(create_multi_tracker().params, option) is True
    lamps = np.full(3, 1.3 if grey else 1.4, np.float32)

    def change(t, f):
        if grey:
            f = cv2.cvtColor(cv2.cvtColor(f, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR)
        else:
            f = np.clip(f.astype(np.int16) + 60, 0, 255).astype(np.uint8)
        return _cast(f, lamps) if t >= 30 else f

    mota = {on: float(np.mean([_mot_on_walkers(seed, change, **{option: on}).mota for seed in range(3)]))
            for on in (True, False)}
    assert mota[True] > mota[False] + (0.1 if grey else 0.3), mota


def test_fill_clipped_raises_only_the_clipped_levels_of_the_brightened_channels():
    from pftrack.cues.still_gain import _fill_clipped

    rng = np.random.default_rng(1)
    for _ in range(20):
        raw = np.clip(rng.normal(200, 60, (37, 53, 3)), 0, 255).astype(np.uint8)
        ref = rng.integers(0, 256, raw.shape, dtype=np.uint8)
        out = rng.integers(0, 256, raw.shape, dtype=np.uint8)
        channels = rng.random(3) < 0.6
        expected = out.copy()
        for c in np.flatnonzero(channels):
            m = raw[..., c] == 255
            expected[..., c][m] = np.maximum(out[..., c][m], ref[..., c][m])
        _fill_clipped(raw, out, ref, channels)
        np.testing.assert_array_equal(out, expected)


@pytest.mark.parametrize("name", ["color-pf", "local-motion-pf"])
def test_colour_trackers_keep_a_target_when_the_lamps_are_switched(name):
    """Colour vanish scenes whose every channel jumps times 1.3 at frame 20 (lamps switched on): with the jump read
    and undone in the bins (``light_jump``, the default of color-pf and local-motion-pf) the tracker keeps more of
    the target and raises its flag on it less often than without (docs/rules/sot_light_jump_rule.txt). Measured,
    seeds 0-2: color-pf mean IoU 0.469 against 0.393, false-lost 0.000 against 0.142; local-motion-pf 0.350 against
    0.182, 0.000 against 0.077."""
    lamps = np.full(3, 1.3, np.float32)
    assert pftrack.create_tracker(name).params.light_jump == 0.18
    ious, flags = {}, {}
    for lj in (0.18, 0.0):
        ious[lj], flags[lj] = [], []
        for seed in range(3):
            _, frames, truths = render_scene(vanish_scene(seed, gray=0.0))
            t = pftrack.create_tracker(name, seed=seed, light_jump=lj)
            t.init(frames[0], truths[0].boxes[0])
            for k in range(1, len(frames)):
                st = t.update(_cast(frames[k], lamps) if k >= 20 else frames[k])
                box = truths[k].boxes[0]
                if np.all(np.isfinite(box)):
                    v = iou(st.box, box)
                    ious[lj].append(v)
                    if v >= 0.5:
                        flags[lj].append(st.lost)
    assert np.mean(ious[0.18]) > np.mean(ious[0.0]) + 0.03, {k: np.mean(v) for k, v in ious.items()}
    assert np.mean(flags[0.18]) < np.mean(flags[0.0]), {k: np.mean(v) for k, v in flags.items()}
