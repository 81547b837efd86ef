"""The structural (grey-patch NCC) cue and the fused loss test."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from pftrack._numba import NUMBA_INSTALLED, numba_enabled
from pftrack.cues.structure import (StructureCue, kernel_weights, ncc_reduced, ncc_scores, patch_shape, reduce_region,
                                    sample_boxes, standardize, weighted_templates)
from pftrack.filtering.loss import FusedLoss, LossDetector

def _texture(seed=0, shape=(120, 160)):
    rng = np.random.default_rng(seed)
    g = cv2.GaussianBlur(rng.uniform(0, 255, shape), (0, 0), 2.0)
    g = cv2.normalize(g, None, 0, 255, cv2.NORM_MINMAX)
    return np.repeat(g.astype(np.uint8)[..., None], 3, axis=2)


def test_patch_shape_keeps_aspect_and_size():
    ph, pw = patch_shape(40, 80, 256)
    assert ph * pw == pytest.approx(256, rel=0.1) and ph / pw == pytest.approx(2.0, rel=0.15)
    assert patch_shape(1, 1000, 16)[1] >= 4  # never degenerate


def test_ncc_is_one_on_the_template_and_invariant_to_gain_and_offset():
    rng = np.random.default_rng(1)
    t = rng.uniform(0, 255, (1, 64)).astype(np.float32)
    p = np.concatenate([t, 0.5 * t + 40, 1.7 * t - 30, rng.uniform(0, 255, (1, 64)).astype(np.float32)])
    r = ncc_scores(p, standardize(t))
    assert r[:3] == pytest.approx([1.0, 1.0, 1.0], abs=2e-3)
    assert abs(r[3]) < 0.5
    flat = ncc_scores(np.full((1, 64), 100.0, np.float32), standardize(t))
    assert flat[0] == pytest.approx(0.0, abs=1e-6)  # no structure, no evidence (no 0/0)


def test_weighted_ncc_ignores_what_the_kernel_gives_no_weight():
    rng = np.random.default_rng(3)
    w = kernel_weights((8, 8))
    assert w.mean() == pytest.approx(1.0) and w.reshape(8, 8)[0, 0] == 0.0  # the box's corners: background
    t = rng.uniform(0, 255, (1, 64)).astype(np.float32)
    p = t.copy()
    p[0, w == 0] = rng.uniform(0, 255, int((w == 0).sum()))  # change only the zero-weight pixels
    assert ncc_scores(p, standardize(t, weights=w), weights=w)[0] == pytest.approx(1.0, abs=1e-3)
    assert ncc_scores(p, standardize(t))[0] < 0.99  # the unweighted NCC sees the change


@pytest.mark.skipif(not NUMBA_INSTALLED, reason="numba not installed")
@pytest.mark.parametrize("kind", ["kernel", "uniform"])
def test_compiled_ncc_matches_the_remap_path(kind):
    from pftrack._numba import set_numba_enabled

    rng = np.random.default_rng(4)
    img = rng.integers(0, 255, (120, 160, 3), dtype=np.uint8)
    ell = np.column_stack([rng.uniform(-10, 170, 60), rng.uniform(-10, 130, 60), rng.uniform(3, 30, 60),
                           rng.uniform(3, 30, 60)])
    w = kernel_weights((12, 10), kind)
    red = reduce_region(img, (0, 0, 160, 120), 2)
    t = standardize(rng.uniform(0, 255, (2, 120)).astype(np.float32), weights=w)
    fast = ncc_reduced(red, ell, (12, 10), t, weights=w)
    prev = set_numba_enabled(False)
    try:
        ref = ncc_reduced(red, ell, (12, 10), t, weights=w)
    finally:
        set_numba_enabled(prev)
    # exact bilinear weights vs OpenCV's 1/32-pixel fixed-point interpolation
    assert np.max(np.abs(fast - ref)) < 0.02


@pytest.mark.skipif(not numba_enabled(), reason="a property of the compiled NCC")
def test_ncc_reads_8_bit_and_float_levels_alike():
    """The compiled NCC gives the same numbers from the 8-bit region and from its float64 copy (which it reads
    when the region is small next to the samples)."""
    from pftrack.cues.structure import Reduced

    rng = np.random.default_rng(5)
    img = rng.integers(0, 255, (120, 160, 3), dtype=np.uint8)
    red = reduce_region(img, (0, 0, 160, 120), 2)
    assert red.gray.dtype == np.uint8
    ell = np.column_stack([rng.uniform(0, 160, 40), rng.uniform(0, 120, 40), rng.uniform(3, 30, 40),
                           rng.uniform(3, 30, 40)])
    t = standardize(rng.uniform(0, 255, (2, 120)).astype(np.float32))
    small = ncc_reduced(red, ell, (12, 10), t)          # 40 x 120 samples: the float64 copy
    assert red.levels_for(40 * 120).dtype == np.float64
    big = Reduced(red.gray, red.x0, red.y0, red.k, red.frame_size)
    assert big.levels_for(10).dtype == np.uint8        # a region much larger than the samples: read as is
    # one box at a time: each region is large next to its 120 samples, so the 8-bit levels are read
    one = [ncc_reduced(Reduced(red.gray, red.x0, red.y0, red.k, red.frame_size), e[None], (12, 10), t)[0]
           for e in ell]
    assert np.array_equal(small, np.array(one))


@pytest.mark.skipif(not numba_enabled(), reason="a property of the compiled NCC")
@pytest.mark.parametrize("n_templates", [1, 2, 3])
@pytest.mark.parametrize("kind", ["kernel", "uniform"])
def test_ncc_of_a_batch_equals_one_box_at_a_time(n_templates, kind):
    """A batch of boxes scores bit for bit as each box alone, for one to three templates, with and without
    weights, also where boxes reach past the region's border."""
    from pftrack.cues.ncc_kernels import _ncc_boxes, _ncc_one
    from pftrack.cues.structure import _grid, weighted_templates

    rng = np.random.default_rng(11)
    img = rng.integers(0, 255, (90, 130, 3), dtype=np.uint8)
    red = reduce_region(img, (0, 0, 130, 90), 3)
    gray = red.gray.astype(np.float64)
    w = kernel_weights((12, 10), kind)
    tw, wts = weighted_templates(standardize(rng.uniform(0, 255, (n_templates, 120)).astype(np.float32), weights=w),
                                 None if kind == "uniform" else w)
    u, v = _grid((12, 10))
    for n in (1, 6, 7):
        ell = np.column_stack([rng.uniform(-15, 145, n), rng.uniform(-15, 105, n), rng.uniform(2, 40, n),
                               rng.uniform(2, 40, n)])
        out = np.empty(n)
        _ncc_boxes(gray, ell, float(red.x0), float(red.y0), float(red.k), u, v, tw, wts, 1.0, out)
        one = [_ncc_one(gray, e, float(red.x0), float(red.y0), float(red.k), u, v, tw, wts, 1.0, np.empty(n_templates))
               for e in ell]
        assert np.array_equal(out, np.array(one))


def _ncc_box_reference(gray, e, x0, y0, k, u, v, tmpl, wts, floor2):
    """The compiled NCC of one box written out in plain Python floats, one loop over the samples in the order
    the kernel sums them: each correlation and the best, for a bit-for-bit comparison."""
    h, w = gray.shape
    cx, cy, sx, sy = (e[0] - x0) / k - 0.5, (e[1] - y0) / k - 0.5, e[2] / k, e[3] / k

    def grid(c, s, t, n):
        p = min(max(c + t * s, 0.0), n - 1.0)
        i = min(int(p), max(n - 2, 0))
        return i, (p - i if n > 1 else 0.0)

    s1 = s2 = 0.0
    dots = [0.0] * tmpl.shape[0]
    kk = 0
    for a in range(v.size):
        ya, fy = grid(cy, sy, float(v[a]), h)
        yb = ya + (1 if h > 1 else 0)
        for b in range(u.size):
            xa, fx = grid(cx, sx, float(u[b]), w)
            xb = xa + (1 if w > 1 else 0)
            g00, g10 = float(gray[ya, xa]), float(gray[yb, xa])
            top = g00 + fx * (float(gray[ya, xb]) - g00)
            bot = g10 + fx * (float(gray[yb, xb]) - g10)
            val = top + fy * (bot - top)
            wv = val if wts.size == 0 else float(wts[kk]) * val
            s1 += wv
            s2 += wv * val
            for q in range(len(dots)):
                dots[q] += val * float(tmpl[q, kk])
            kk += 1
    n = u.size * v.size
    var = max(s2 - s1 * s1 / n, 0.0)
    norm = math.sqrt(var + floor2 * n)
    dots = [d / norm for d in dots]
    best = -math.inf
    for d in dots:
        if d > best:
            best = d
    return best, dots


@pytest.mark.skipif(not numba_enabled(), reason="a property of the compiled NCC")
@pytest.mark.parametrize("n_templates", [1, 2, 3])
@pytest.mark.parametrize("kind", ["kernel", "uniform"])
@pytest.mark.parametrize("region", [(40, 55), (1, 30), (25, 1), (1, 1)])
@pytest.mark.parametrize("dtype", [np.float64, np.uint8])
def test_compiled_ncc_equals_its_plain_transcription_bit_for_bit(n_templates, kind, region, dtype):
    """The compiled NCC (samples, sums, the best of the templates) gives the numbers of the formula summed in
    one loop over the samples, to the last bit: regions of one row or column, 8-bit and float levels, boxes
    past the border, a template of 0.0 correlation (ties), weights or none."""
    from pftrack.cues.ncc_kernels import _ncc_boxes, _ncc_one
    from pftrack.cues.structure import _grid

    rng = np.random.default_rng(5 + n_templates)
    gray = rng.integers(0, 256, region).astype(dtype)
    shape = (9, 7)
    u, v = _grid(shape)
    w = kernel_weights(shape, kind)
    raw = rng.normal(size=(n_templates, 63))
    if n_templates == 3:
        raw[1] = raw[0]  # two equal templates: equal correlations, the first kept
    tw, wts = weighted_templates(standardize(raw.astype(np.float32), weights=w), None if kind == "uniform" else w)
    x0, y0, k = 10.0, -4.0, 2.5
    ell = np.column_stack([rng.uniform(-20, 160, 40), rng.uniform(-30, 150, 40), rng.uniform(0.5, 60, 40),
                           rng.uniform(0.5, 60, 40)])
    out = np.empty(len(ell))
    _ncc_boxes(gray, ell, x0, y0, k, u, v, tw, wts, 0.7, out)
    for i, e in enumerate(ell):
        best, dots = _ncc_box_reference(gray, e, x0, y0, k, u, v, tw, wts, 0.7)
        got = np.empty(n_templates)
        one = _ncc_one(gray, e, x0, y0, k, u, v, tw, wts, 0.7, got)
        assert out[i] == best and one == best
        assert got.tolist() == dots


def test_sampled_box_equals_the_area_resized_crop():
    img = _texture()
    box = (40, 30, 64, 48)  # x, y, w, h: a 4x reduction to a 16x12 patch
    ell = np.array([[box[0] + box[2] / 2, box[1] + box[3] / 2, box[2] / 2, box[3] / 2]])
    got = sample_boxes(img, (0, 0, 160, 120), ell, (12, 16)).reshape(12, 16)
    crop = cv2.cvtColor(img[30:78, 40:104], cv2.COLOR_BGR2GRAY).astype(np.float32)
    ref = cv2.resize(crop, (16, 12), interpolation=cv2.INTER_AREA)
    # the reduced grid is not aligned with the box's edges, so equal up to a sub-pixel resampling
    assert np.mean(np.abs(got - ref)) < 8.0
    assert ncc_scores(got.reshape(1, -1), standardize(ref.reshape(1, -1)))[0] > 0.94  # 2 px off: 0.88


@pytest.mark.parametrize("k", [2, 3, 4, 5, 6, 7])
def test_compiled_block_means_equal_opencvs_area_resize(k):
    """Blocks of 3..7 px are summed by a compiled pass and rounded as OpenCV rounds them: the same numbers as its
    integer-factor area resize, on textured, flat and noisy frames at any offset (and OpenCV's own for k = 2 or
    a size that k does not divide)."""
    from pftrack.cues.reduced_region import block_means
    rng = np.random.default_rng(k)
    for trial in range(40):
        hgt, wid = int(rng.integers(k, 300)), int(rng.integers(k, 400))
        img = rng.integers(0, 256, (hgt, wid, 3), dtype=np.uint8)
        if trial % 3 == 1:
            img = cv2.GaussianBlur(img, (7, 7), 3)
        elif trial % 3 == 2:
            img[:] = rng.integers(0, 256)
        x0, y0 = int(rng.integers(0, wid // 2 + 1)), int(rng.integers(0, hgt // 2 + 1))
        w, h = (wid - x0) // k * k, (hgt - y0) // k * k
        if trial % 5 == 4:
            w = max(w - 1, 1)  # not a multiple of k: OpenCV's own path
        if w < k or h < k:
            continue
        ref = cv2.resize(img[y0:y0 + h, x0:x0 + w], (w // k, h // k), interpolation=cv2.INTER_AREA)
        assert np.array_equal(block_means(img, x0, y0, w, h, k), ref), (k, trial)


def test_a_frame_made_from_grey_is_reduced_on_its_one_channel_with_the_bgr_paths_numbers():
    """A BGR frame that ``as_bgr_uint8`` made from a grey image is reduced on that image: the same levels, block
    size and origin as the three-channel path, for every kind of block (1, 2, the compiled 3..7, the sampled 8+)."""
    from pftrack.frames import as_bgr_uint8, grey_origin
    rng = np.random.default_rng(7)
    for trial in range(60):
        hgt, wid = int(rng.integers(30, 300)), int(rng.integers(30, 400))
        grey = cv2.GaussianBlur(rng.integers(0, 256, (hgt, wid), dtype=np.uint8), (0, 0), float(rng.uniform(0.5, 3)))
        frame = as_bgr_uint8(grey)
        plain = frame.copy()  # the same pixels, no grey origin: the three-channel path
        assert grey_origin(frame) is not None and grey_origin(plain) is None
        k = int(rng.integers(1, 30))
        x0, y0 = int(rng.integers(0, wid // 2)), int(rng.integers(0, hgt // 2))
        roi = (x0, y0, int(rng.integers(x0 + 1, wid + 1)), int(rng.integers(y0 + 1, hgt + 1)))
        a, b = reduce_region(frame, roi, k), reduce_region(plain, roi, k)
        assert np.array_equal(a.gray, b.gray) and a.gray.dtype == b.gray.dtype, (trial, k, roi)
        assert (a.k, a.x0, a.y0, a.frame_size) == (b.k, b.x0, b.y0, b.frame_size)
        assert not np.shares_memory(a.gray, grey_origin(frame))


@pytest.mark.parametrize("k", [4, 8, 12, 16])
def test_large_block_reduction_is_close_to_the_block_means(k):
    """k >= 8 averages a spread subset of each block's pixels instead of all k x k (exact below)."""
    img = _texture(3, (480, 640))
    red = reduce_region(img, (0, 0, 640, 480), k)
    h, w = 480 // k, 640 // k
    grey = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY).astype(np.float64)
    exact = grey[:h * k, :w * k].reshape(h, k, w, k).mean(axis=(1, 3))
    assert red.gray.shape == exact.shape and red.k == k
    # the texture's features span ~5 px: block means of 16 px keep little contrast, a sampled mean a bit more
    assert np.mean(np.abs(red.gray - exact)) < 0.25 * np.std(exact) + 1.0
    assert np.corrcoef(red.gray.ravel(), exact.ravel())[0, 1] > 0.9


def test_the_frame_region_is_reused_for_the_estimate_and_at_the_frame_edge():
    img = _texture(4)
    cue = StructureCue(256)
    cue.init(img, np.array([80.0, 60.0, 15.0, 12.0]))
    calls = []
    import pftrack.cues.reduced_region as S  # where the cue's regions are reduced (reduced_for)

    orig = S.reduce_region
    S.reduce_region = lambda *a: calls.append(a[1]) or orig(*a)
    try:
        rng = np.random.default_rng(0)
        for cx in (80.0, 150.0):  # inside, and a target leaving across the right edge
            cue.new_frame()
            calls.clear()
            ell = np.column_stack([cx + rng.normal(0, 2, 50), 60 + rng.normal(0, 2, 50), np.full(50, 15.0),
                                   np.full(50, 12.0)])
            cue.scores(img, (0, 0, 160, 120), ell)
            cue.scores(img, (0, 0, 160, 120), ell.mean(axis=0, keepdims=True))   # the estimate
            cue.update(img, ell.mean(axis=0), 0.1)                                # its patch
            assert len(calls) == 1, (cx, calls)
    finally:
        S.reduce_region = orig


def test_structure_cue_peaks_at_the_target_and_keeps_its_anchor():
    img = _texture(2)
    cue = StructureCue(256)
    true = np.array([80.0, 60.0, 15.0, 12.0])
    cue.init(img, true)
    offs = np.array([[0, 0], [6, 0], [0, -6], [20, 15], [-30, 10]], dtype=float)
    ell = np.column_stack([true[:2] + offs, np.tile(true[2:], (len(offs), 1))])
    r = cue.scores(img, (0, 0, 160, 120), ell)
    assert int(np.argmax(r)) == 0 and r[0] == pytest.approx(1.0, abs=0.01)
    # a bad update (the reference blended fully into clutter) cannot erase the first frame's patch
    cue.update(img, ell[4], 1.0)
    assert cue.scores(img, (0, 0, 160, 120), ell[:1])[0] == pytest.approx(1.0, abs=0.01)


@pytest.mark.parametrize("weighting,anchor", [("kernel", True), ("uniform", True), ("kernel", False)])
def test_the_prepared_references_are_standardize_and_weighted_templates_to_the_bit(weighting, anchor):
    img = _texture(3)
    cue = StructureCue(256, anchor=anchor, weighting=weighting)
    cue.init(img, np.array([80.0, 60.0, 15.0, 12.0]))
    for centre in ((84.0, 57.0), (70.0, 66.0)):  # the running reference moves away from the anchor
        cue.update(img, np.array([*centre, 15.0, 12.0]), 0.3)
        run = standardize(cue._run[None, :], weights=cue.weights)
        refs = np.concatenate([run, cue._first_std]) if anchor else run
        tw, w = weighted_templates(refs, cue.weights)
        assert np.array_equal(cue._templates, refs)
        assert np.array_equal(cue._prepared[0], tw) and np.array_equal(cue._prepared[1], w)


def test_fused_loss_adds_likelihood_ratios_and_ignores_a_blind_cue():
    kw = dict(lost_frames=2, reacquire_margin=1.0)
    fused, single = FusedLoss(2, cue_clip=30.0, **kw), LossDetector(**kw)
    rng = np.random.default_rng(0)
    bg_colour = rng.uniform(0.2, 0.5, 200)
    bg_blind = np.r_[rng.uniform(0.9, 1.0, 180), np.ones(20)]  # as high on the background as on the target
    fused.set_background(np.column_stack([bg_colour, bg_blind]))
    single.set_background(bg_colour)
    for s in (0.9, 0.6, 0.55):
        assert fused.evaluate([s, 0.97]) == pytest.approx(single.evaluate(s), abs=1e-9)
    # two informative cues: the ratios add
    two = FusedLoss(2, cue_clip=30.0, **kw)
    two.set_background(np.column_stack([bg_colour, bg_colour]))
    assert two.evaluate([0.6, 0.6]) == pytest.approx(2 * single.evaluate(0.6))
    # a missing cue (NaN) gives no evidence; all missing is absence
    assert fused.evaluate([0.6, np.nan]) == pytest.approx(single.evaluate(0.6))
    assert fused.evaluate([np.nan, np.nan]) < -10
    # each cue's ratio is clipped before the sum: one extreme cue cannot outvote the other alone
    clipped = FusedLoss(2, cue_clip=3.0, **kw)
    clipped.set_background(np.column_stack([bg_colour, bg_colour]))
    assert clipped.evaluate([0.95, 0.3]) == pytest.approx(0.0, abs=1e-9)
    assert clipped.evaluate([0.95, 0.95]) == pytest.approx(6.0)


def test_fused_loss_hysteresis_and_reacquisition():
    det = FusedLoss(2, lost_frames=3, reacquire_margin=1.0)
    det.set_background(np.column_stack([np.linspace(0.2, 0.5, 50), np.linspace(0.4, 0.6, 50)]))
    assert det.step([0.95, 0.98]) == (False, pytest.approx(1.0, abs=1e-3))
    flags = [det.step([0.3, 0.5])[0] for _ in range(3)]
    assert flags == [False, False, True]
    assert not det.acquire([0.45, 0.55])  # background-like: stays lost
    assert det.acquire([0.95, 0.97]) and not det.lost


def test_fused_acquisition_vetoes_a_cue_far_below_its_history():
    """acquire_z: a look-alike whose shape matches (second cue at its history) and whose colour is far below the
    target's history, though far above this scene's background, passes the ratio test; with acquire_z it is
    refused, and the target itself is still taken."""
    def detector(z):
        det = FusedLoss(2, lost_frames=1, reacquire_margin=1.0, acquire_z=z)
        det.set_background(np.column_stack([np.linspace(0.05, 0.15, 50), np.linspace(0.7, 0.85, 50)]))
        for _ in range(40):
            det.step([0.97, 0.96])
        det.step([0.1, 0.7])  # lost
        assert det.lost
        return det

    look_alike, target = [0.6, 0.95], [0.96, 0.95]
    plain = detector(0.0)
    assert plain.evaluate(look_alike) > 1.0 and plain.acquire(look_alike)  # the colour ratio favours it
    strict = detector(4.0)
    assert not strict.acquire(look_alike) and strict.lost
    assert strict.acquire(target) and not strict.lost
    # a score within acquire_z spreads is not vetoed for that
    m = strict.members[0]
    assert strict.confident([m.mu_t - 3.0 * m.sd_t, 0.95], veto_z=4.0) == strict.confident(
        [m.mu_t - 3.0 * m.sd_t, 0.95])


def test_fused_acquisition_margin_is_separate_from_the_tracking_gate():
    """acquire_margin: ending a loss asks for a larger ratio than the tracking (model update) gate."""
    def detector(margin):
        det = FusedLoss(2, lost_frames=1, reacquire_margin=1.0, acquire_margin=margin)
        bg = np.linspace(0.2, 0.5, 50)
        det.set_background(np.column_stack([bg, bg]))
        for _ in range(20):
            det.step([0.95, 0.95])
        return det

    for margin, taken in ((None, True), (2.0, False)):
        det = detector(margin)
        det.step([0.1, 0.1])
        assert det.lost
        # a score whose fused ratio lies between the two margins (as acquire() sees it: one more frame unseen)
        for m in det.members:
            m.unseen += 1
        s = next([v, v] for v in np.linspace(0.5, 0.99, 2000) if 1.2 < det.evaluate([v, v]) < 1.8)
        for m in det.members:
            m.unseen -= 1
        assert det.acquire(s) is taken
        assert 1.0 < det.llr < 2.0


def test_a_box_unlike_the_targets_history_in_both_cues_counts_as_a_miss():
    """loss_history_z (photo-vanish-4106): an occluder of the target's colours that the background statistics never
    sampled scores far below the target's history in both cues yet far above the background's tail, so the fused
    ratio calls it the target; with history_miss_z the frame is a miss and the flag rises after lost_frames.  One cue
    far below its history (a turning face's structure) is not enough, nor one cue alone."""
    def detector(z):
        det = FusedLoss(2, lost_frames=3, reacquire_margin=1.0, cue_floor=2.0, history_miss_z=z)
        det.set_background(np.column_stack([np.linspace(0.05, 0.15, 50), np.linspace(0.3, 0.45, 50)]))
        for _ in range(40):
            det.step([0.97, 0.96])
        return det

    occluder = [0.6, 0.6]
    plain, strict = detector(0.0), detector(3.0)
    assert plain.evaluate(occluder) > 1.0  # each cue's ratio favours the occluder
    assert [plain.step(occluder)[0] for _ in range(3)] == [False, False, False]
    flags = [strict.step(occluder) for _ in range(3)]
    assert [f[0] for f in flags] == [False, False, True]
    assert all(score < 0.5 for _, score in flags) and strict.llr <= -1.0  # score and flag agree
    # one cue far below its history, the other at it: the fused ratio decides as before
    for s in ([0.6, 0.96], [0.97, 0.6], [0.6, np.nan]):
        a, b = detector(0.0), detector(3.0)
        assert [a.step(s) for _ in range(3)] == [b.step(s) for _ in range(3)]
    # the target itself is never a miss
    assert not strict.unlike_history(strict._vector([0.95, 0.95]))
