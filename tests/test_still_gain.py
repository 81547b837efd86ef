"""``color_normalize="still"``: the frame's gain against the first frame measured on the same pixels of a still view
(``pftrack.cues.still_gain``), undone in the colour quantisation."""

from __future__ import annotations

import numpy as np
import pytest

import pftrack
from pftrack.cues.histogram_cue import ColorCue
from pftrack.cues.still_gain import HIGH, HIST_BINS, LOW, SPAN, CastUndo, pair_bins, reference_lattice, still_gain
from pftrack.eval.metrics import per_frame_iou
from pftrack.synth.varied import varied_scene

from .conftest import cached_scene


def _scene(seed=0, shape=(240, 320)):
    rng = np.random.default_rng(seed)
    small = rng.integers(30, 200, (shape[0] // 8, shape[1] // 8, 3)).astype(np.float32)
    import cv2

    return cv2.resize(small, (shape[1], shape[0]), interpolation=cv2.INTER_LINEAR)


def _u8(x):
    return np.clip(np.rint(x), 0, 255).astype(np.uint8)


def test_gain_of_a_still_view_is_found_per_channel_and_a_moved_view_gives_none():
    rng = np.random.default_rng(1)
    base = _scene(1)
    ref = reference_lattice(_u8(base))
    assert np.array_equal(still_gain(ref, _u8(base)), np.ones(3))  # no change: exactly 1
    lit = _u8(base * np.array([1.5, 1.2, 0.7]) + rng.normal(0, 2, base.shape))
    np.testing.assert_allclose(still_gain(ref, lit), [1.5, 1.2, 0.7], rtol=0.012)
    walker = base.copy()
    walker[40:160, 60:140] = 250 - walker[40:160, 60:140]  # a target over about 12 % of the view
    np.testing.assert_allclose(still_gain(ref, _u8(walker * 1.3)), 1.3, rtol=0.012)
    assert still_gain(ref, _u8(np.roll(base, 9, axis=1))) is None  # a pan: the log-ratios spread
    assert still_gain(ref, _u8(base[:200])) is None  # another size
    assert still_gain(ref, _u8(base)[..., 0]) is None  # not BGR


def test_the_pair_table_gives_every_pair_of_levels_the_bin_of_its_log_ratio():
    """The kernels look a pair of levels up in ``pair_bins``: the bin is the one the log-ratio's formula gives, and
    -1 for a level that is dark or clipped."""
    table = pair_bins()
    log = np.log(np.maximum(np.arange(256, dtype=np.float64), 1.0))
    scale = HIST_BINS / (2.0 * SPAN)
    for a in range(256):
        for b in (0, LOW, LOW + 1, 100, 128, HIGH - 1, HIGH, 255, a):
            inside = LOW < a < HIGH and LOW < b < HIGH
            want = int((log[b] - log[a] + SPAN) * scale) if inside else -1
            assert table[a, b] == want, (a, b)
    assert table[100, 100] == HIST_BINS // 2  # no change: the middle bin


def test_the_gain_read_from_the_jump_reader_s_lattice_is_the_frame_s():
    """The colour cue reads the still gain from the lattice the jump reader copied (contiguous, stride 1): the same
    gains as from the frame, and the same tables frame after frame."""
    rng = np.random.default_rng(3)
    base = _scene(3)
    ref = reference_lattice(_u8(base))
    jumps = CastUndo(0.2)
    for k, g in enumerate(([1.0, 1.0, 1.0], [1.3, 1.1, 0.8], [1.3, 1.1, 0.8], [0.7, 0.7, 0.7])):
        frame = _u8(base * np.array(g) + rng.normal(0, 2, base.shape))
        jumps.read(frame)
        a, b = still_gain(ref, frame), still_gain(ref, jumps.reader.lattice, stride=1)
        assert a is not None and np.array_equal(a, b), k
    cues = [ColorCue(color_space="rgb", normalize="still", cast_jump=c) for c in (0.2, 0.0)]
    frames = [_u8(base * s + rng.normal(0, 2, base.shape)) for s in (1.0, 1.0, 1.4, 1.4, 0.9)]
    for cue in cues:
        cue.adapt_to(frames[0])
    for f in frames[1:]:
        for cue in cues:
            cue.new_frame(f)
        assert np.array_equal(cues[0].lut, cues[1].lut)


def test_cue_quantises_a_brightened_still_frame_as_the_first_one():
    base = _u8(_scene(2) * 0.6)
    bright = _u8(base.astype(np.float32) * 1.8)
    plain, still = ColorCue("rgb"), ColorCue("rgb", normalize="still")
    for cue in (plain, still):
        cue.adapt_to(base)
        cue.new_frame(base)
    roi = (0, 0, 320, 240)
    first = plain.prepare(base, roi).bins.copy()
    assert still.lut is still._base_lut  # no change on the first frame: the table of shifts
    still.new_frame(bright)
    plain.new_frame(bright)
    assert np.mean(still.prepare(bright, roi).bins == first) > 0.9
    assert np.mean(plain.prepare(bright, roi).bins == first) < 0.3
    still.new_frame(_u8(np.roll(bright, 11, axis=0)))  # the view moves: the last gain is held
    np.testing.assert_allclose(still._still_gain, 1.8, rtol=0.02)
    with pytest.raises(ValueError):
        ColorCue("rgb", normalize="sometimes")


def _ramp_run(seed: int, normalize: str) -> float:
    """Mean IoU of color-pf on a varied colour scene whose exposure rises from 0.5 to 1 over 25 frames."""
    spec = varied_scene(seed, n_frames=50, gray=0.0, illumination=0.0, distractors=(1, 2))
    frames, truth = [], []
    for t, (img, tr) in enumerate(cached_scene(spec)):
        frames.append(_u8(img.astype(np.float32) * (0.5 + 0.5 * min(1.0, t / 25))))
        truth.append(tr.boxes[0])
    tracker = pftrack.create_tracker("color-pf", seed=0, color_normalize=normalize)
    tracker.init(frames[0], tuple(truth[0]))
    boxes = [truth[0]] + [tracker.update(f).box for f in frames[1:]]
    return float(np.nanmean(per_frame_iou(np.array(boxes), np.array(truth))))


def test_an_exposure_that_settles_is_tracked_better_with_the_still_gain():
    plain = [_ramp_run(s, "none") for s in range(5)]
    still = [_ramp_run(s, "still") for s in range(5)]
    assert np.mean(still) > np.mean(plain) + 0.05, (plain, still)


@pytest.mark.parametrize("seed", [326, 418])
def test_fusion_pf_default_reacquires_a_target_whose_light_drifted_while_hidden_without_the_relit_score(seed):
    """The vanish scenes of ``relit_colour``'s test (a global light drift while the target is hidden): the still
    view's gain, fusion-pf's default, undoes the drift in the colour bins, so the target is re-acquired even
    without the relit colour score."""
    from pftrack.synth import vanish_scene

    from .conftest import lost_flag_run

    assert pftrack.create_tracker("fusion-pf").params.color_normalize == "still"
    run = lost_flag_run(vanish_scene(seed), "fusion-pf", seed, relit_colour=False)
    assert run.reappearances == 1 and run.reacquired == 1
