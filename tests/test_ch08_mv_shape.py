"""Object shapes for motion-vector groups from a selectively updated background (pftrack.multi.mv_shape)."""

from __future__ import annotations

import numpy as np
import pytest

from pftrack.multi import compressed as C
from pftrack.multi import mv_shape as S
from pftrack.multi.detectors import split_wide


def _group(box, shape_blocks):
    """A Group whose blocks are the 4x4 blocks of ``box`` (frame pixels)."""
    x, y, w, h = box
    m = np.zeros(shape_blocks, bool)
    m[int(y) // 4:int(np.ceil((y + h) / 4)), int(x) // 4:int(np.ceil((x + w) / 4))] = True
    return C.Group(tuple(float(v) for v in box), m, 0.0, 1.0, (4.0, 0.0), int(m.sum()))


def _scene(n=30, seed=0, size=(144, 192)):
    """A textured static background with a 12x40 object walking right by 4 px per frame from x=20, and a
    second one standing at x=170 from the first frame to frame 10, then walking away down."""
    rng = np.random.default_rng(seed)
    bg = rng.integers(40, 120, size).astype(np.uint8)
    person = rng.integers(170, 250, (40, 12)).astype(np.uint8)
    frames, boxes = [], []
    for t in range(n):
        f = bg.copy()
        x = 20 + 4 * t
        f[60:100, x:x + 12] = person
        y2 = 10 + max(0, t - 10) * 4
        f[y2:y2 + 40, 170:182] = person
        frames.append(f)
        boxes.append([(x, 60, 12, 40), (170, y2, 12, 40)])
    return frames, boxes


def test_split_wide_cuts_tall_wide_blobs_only():
    assert split_wide((0, 0, 20, 80), 0.4) == [(0.0, 0.0, 20.0, 80.0)]
    parts = split_wide((10, 5, 64, 80), 0.4)                    # two people side by side
    assert len(parts) == 2 and parts[1] == pytest.approx((42.0, 5.0, 32.0, 80.0))
    assert split_wide((0, 0, 200, 20), 0.4) == [(0.0, 0.0, 200.0, 20.0)]   # flat: a fragment, not split
    assert len(split_wide((0, 0, 400, 80), 0.4)) == 3            # at most three
    assert split_wide((0, 0, 64, 80), 0.0) == [(0.0, 0.0, 64.0, 80.0)]


def test_silhouette_boxes_one_box_per_component_touching_the_core():
    import cv2

    fg = np.zeros((40, 60), np.uint8)
    fg[5:30, 5:12] = 1          # person A
    fg[5:30, 16:23] = 1         # person B, a gap of 4 px
    fg[33:35, 40:42] = 1        # a speck touching nothing
    fg[12:14, 25:27] = 1        # a small fragment touching the core
    core = np.zeros_like(fg)
    core[10:20, 8:27] = 1
    _, lab, st, _ = cv2.connectedComponentsWithStats(fg, connectivity=8)
    boxes = S.silhouette_boxes(lab, st, core, scale=2, min_share=0.3)
    assert boxes == [(10.0, 10.0, 14.0, 50.0), (32.0, 10.0, 14.0, 50.0)]   # frame pixels, fragment dropped
    assert len(S.silhouette_boxes(lab, st, core, scale=2, min_share=0.0)) == 3
    assert S.silhouette_boxes(lab, st, np.zeros_like(fg), scale=2) == []
    assert S.union_box(boxes) == (10.0, 10.0, 36.0, 50.0)


def test_the_shaper_draws_walkers_tight_and_drops_the_ghost_of_a_first_frame_occupant():
    """Coarse groups (one block too wide on each side and too short, as 8x8/16x16 partitions are) become the
    objects' true boxes. The object standing in the first frame leaves: the background learns its place
    (running mean of the first frames away from moving blocks), so no ghost widens its box."""
    frames, truth = _scene()
    shaper = S.SilhouetteShaper(scale=2, alpha=0.01, tau=35.0, margin=0.5, split_aspect=0.4)
    errs = []
    for t, (f, tb) in enumerate(zip(frames, truth)):
        groups, moving = [], np.zeros((36, 48), bool)
        for (x, y, w, h) in tb:
            if t <= 10 and x == 170:       # standing still: no motion vectors, no group
                continue
            g = _group((x - 4, y + 6, w + 8, h - 14), moving.shape)
            moving |= g.mask
            groups.append(g)
        out = shaper(f, groups, moving)
        if t >= 22:                        # once the bootstrap mean has forgotten the standing object
            for g, (x, y, w, h) in zip(out, [b for b in tb]):
                errs.append(np.abs(np.array(g.box) - (x, y, w, h)).max())
                assert g.parts == [g.box]
    assert max(errs) <= 2.0


def test_the_detector_gives_one_box_per_silhouette():
    """Two walkers side by side in one motion-vector group, with a gap between them, are two detections."""
    rng = np.random.default_rng(1)
    bg = rng.integers(40, 120, (144, 192)).astype(np.uint8)
    a = rng.integers(170, 250, (40, 12)).astype(np.uint8)
    shaper = S.SilhouetteShaper(scale=2, alpha=0.01, tau=35.0, margin=0.5, split_aspect=0.4)
    for t in range(25):
        f = bg.copy()
        x = 20 + 3 * t
        f[60:100, x:x + 12] = a
        f[60:100, x + 20:x + 32] = a
        g = _group((x - 4, 64, 40, 28), (36, 48))
        out = shaper(f, [g], g.mask)
    assert sorted(out[0].parts) == [(float(x), 60.0, 12.0, 40.0), (float(x + 20), 60.0, 12.0, 40.0)]
    assert out[0].box == (float(x), 60.0, 32.0, 40.0)


def test_background_shape_is_the_default_and_blocks_keep_the_chapter_rule():
    assert C.CDParams().shape == "background"
    assert C.BlockAnalyser(C.CDParams(shape="blocks")).shaper is None
    assert C.BlockAnalyser(C.CDParams()).shaper is not None


def test_a_first_frame_occupant_is_forgotten_within_a_few_frames():
    """An object present only in the first frame leaves a ghost in a background initialised from that frame.
    The per-pixel mean of the first updates forgets it within a few frames, so a walker crossing its place ten
    frames later keeps its own box; a plain running average at rate alpha would keep the ghost for 1/alpha
    frames and widen the walker's box."""
    rng = np.random.default_rng(2)
    bg = rng.integers(40, 120, (144, 192)).astype(np.uint8)
    walker = rng.integers(170, 250, (40, 12)).astype(np.uint8)
    sitter = rng.integers(0, 20, (40, 20)).astype(np.uint8)
    shaper = S.SilhouetteShaper(scale=2, alpha=0.01, tau=35.0, margin=0.5, reach=2)
    for t in range(16):
        f = bg.copy()
        if t == 0:
            f[60:100, 64:84] = sitter
        x = 20 + 4 * t
        f[60:100, x:x + 12] = walker
        g = _group((x - 4, 66, 20, 26), (36, 48))
        (out,) = shaper(f, [g], g.mask)
        if t >= 10:                        # the walker is on the sitter's place (x 60..88)
            assert out.box == (float(x), 60.0, 12.0, 40.0)


def test_reduced_luma_is_the_block_mean():
    """The compiled block means equal OpenCV's area resize of the float image (exact for power-of-two scales),
    a partial block at the edge dropped."""
    import cv2

    from pftrack import _numba

    y = np.random.default_rng(6).integers(0, 256, (147, 195)).astype(np.uint8)
    ref = cv2.resize(y[:144, :192].astype(np.float32), (48, 36), interpolation=cv2.INTER_AREA)
    np.testing.assert_array_equal(S.reduce_luma(y, 4), ref)
    was = _numba.numba_enabled()
    _numba.set_numba_enabled(False)
    try:
        np.testing.assert_array_equal(S.reduce_luma(y, 4), ref)
    finally:
        _numba.set_numba_enabled(was)
    assert S.reduce_luma(y, 4)[2, 3] == pytest.approx(y[8:12, 12:16].mean())
