"""Compiled replacements of NumPy steps in the tracking loop give NumPy's numbers to the last bit."""

import numpy as np
import pytest

from pftrack._numba import NUMBA_INSTALLED, np_sum, set_numba_enabled
from pftrack.cues.color import blend_model
from pftrack.cues.contrast import blend_counts
from pftrack.cues.histogram_cue import ColorFeatures

pytestmark = pytest.mark.skipif(not NUMBA_INSTALLED, reason="numba not installed")


def both_paths(fn):
    """``fn()`` with the compiled kernels, then with the NumPy reference path."""
    compiled = fn()
    previous = set_numba_enabled(False)
    try:
        reference = fn()
    finally:
        set_numba_enabled(previous)
    return compiled, reference


def test_np_sum_is_numpys_pairwise_sum(rng):
    for n in [*range(1, 260), 511, 512, 513, 1000, 4096, 9000, 65536]:
        x = rng.random(n) * 10.0 ** rng.uniform(-6, 6, n)
        assert np_sum(x) == x.sum(), n
    # a sequential sum differs from NumPy's on such data: the test can tell the two apart
    x = rng.random(512) * 10.0 ** rng.uniform(-6, 6, 512)
    seq = 0.0
    for v in x:
        seq += v
    assert seq != x.sum()


def test_contrast_count_blend_matches_numpy(rng):
    for trial in range(20):
        obj_ref, sur_ref = rng.random(512) * 50, rng.random(512) * 80
        obj = rng.integers(0, 30, 512).astype(np.float64) * (rng.random(512) < 0.3)
        sur = rng.integers(0, 30, 512).astype(np.float64) * (rng.random(512) < (0.0 if trial == 3 else 0.5))
        if trial == 5:
            obj[:] = 0.0  # nothing to learn
        a, b = both_paths(lambda: blend_counts(obj_ref, obj, sur_ref, sur, 0.02))
        if trial == 5:
            assert a is None and b is None
            continue
        for x, y in zip(a, b):
            assert x.dtype == y.dtype == np.float64 and np.array_equal(x, y)


def test_model_blend_matches_numpy(rng):
    q = rng.random(512) ** 4
    q /= q.sum()
    for alpha in (0.0, 0.02, 0.1, 1.0):
        p = rng.random(512) ** 3
        p /= p.sum()
        (qa, sa), (qb, sb) = both_paths(lambda: blend_model(q, p, alpha))
        assert np.array_equal(qa, qb) and np.array_equal(sa, sb)
    (qa, _), (qb, _) = both_paths(lambda: blend_model(np.zeros(8), np.zeros(8), 0.5))
    assert np.array_equal(qa, np.full(8, 1 / 8)) and np.array_equal(qb, qa)


def test_lattice_coordinates_match_numpy(rng):
    feats = ColorFeatures(np.zeros((10, 10), np.uint16), 17, 9, 3)
    ell = np.column_stack([rng.uniform(0, 300, 50), rng.uniform(0, 200, 50), rng.uniform(1, 60, 50),
                           rng.uniform(1, 60, 50)])
    (ea, xa, ya), (eb, xb, yb) = both_paths(lambda: feats.to_lattice(ell))
    assert np.array_equal(ea, eb) and (xa, ya) == (xb, yb) == (0, 0)


def test_grey_block_means_are_opencvs_area_resize(rng):
    import cv2

    from pftrack.cues.illumination import block_means_gray

    for trial in range(40):
        h, w = (int(v) for v in rng.integers(16, 400, 2))
        k = int(rng.integers(2, 40))
        if w < k or h < k:
            continue
        g = rng.integers(0, 256, (h, w)).astype(np.uint8)
        if trial % 2:  # few levels: many sums exactly half-way between two means
            g = (g // 64 * 64 + 8).astype(np.uint8)
        sw, sh = w // k, h // k
        ref = cv2.resize(g[:sh * k, :sw * k], (sw, sh), interpolation=cv2.INTER_AREA).astype(np.float32)
        compiled, numpy_path = both_paths(lambda: block_means_gray(g, k))
        assert compiled.dtype == np.float32 and np.array_equal(compiled, ref), (h, w, k)
        assert np.array_equal(numpy_path, ref)


def test_quotient_levels_are_opencvs_saturating_multiply(rng):
    import cv2

    from pftrack.cues.illumination import _scale_levels

    for trial in range(10):
        g = rng.integers(0, 256, (37, 53)).astype(np.uint8)
        gain = rng.uniform(0.0, 4.0, g.shape).astype(np.float32)
        if trial % 2:  # products exactly half-way between two levels, both ways of the tie, and saturation
            gain = np.where(g % 2 == 1, np.float32(0.5), np.float32(1.5)).astype(np.float32)
            gain[0] = 300.0
        ref = np.empty_like(g)
        cv2.multiply(g, gain, dst=ref, dtype=cv2.CV_8U)
        assert np.array_equal(_scale_levels(g, gain, np.empty_like(g)), ref)


def test_quotient_image_is_the_same_with_and_without_the_compiled_kernels(rng):
    from pftrack.cues.illumination import QuotientImage

    for shape in [(240, 320), (97, 131), (20, 17)]:
        g = rng.integers(0, 256, shape).astype(np.uint8)
        compiled, numpy_path = both_paths(lambda: QuotientImage(0.1, bgr=False)(g).copy())
        assert np.array_equal(compiled, numpy_path), shape


def test_equalisation_table_counts_as_numpy_does(rng):
    import cv2

    from pftrack.cues.intensity import equalization_lut

    for shape in [(240, 320, 3), (61, 83), (5, 7, 3)]:
        f = rng.integers(0, 256, shape).astype(np.uint8)
        sub = f[::4, ::4] if f.ndim == 2 else cv2.cvtColor(np.ascontiguousarray(f[::4, ::4]), cv2.COLOR_BGR2GRAY)
        hist = np.bincount(sub.ravel(), minlength=256).astype(np.float64)
        cdf = np.cumsum(hist)
        expected = np.clip(np.round((cdf - 0.5 * hist) / cdf[-1] * 255.0), 0, 255).astype(np.uint8)
        assert np.array_equal(equalization_lut(f), expected), shape


def test_compiled_equalisation_table_is_the_numpy_paths(rng):
    import cv2

    from pftrack.cues.intensity import equalization_lut

    for trial in range(300):
        h, w = (int(v) for v in rng.integers(1, 200, 2))
        kind = trial % 4
        if kind == 0:
            g = rng.integers(0, 256, (h, w)).astype(np.uint8)
        elif kind == 1:  # one level: the middle of the table
            g = np.full((h, w), int(rng.integers(0, 256)), np.uint8)
        elif kind == 2:  # a narrow range: many ties at the table's halves
            g = rng.integers(0, int(rng.integers(1, 8)), (h, w)).astype(np.uint8)
        else:
            g = rng.normal(128, rng.uniform(1, 60), (h, w)).clip(0, 255).astype(np.uint8)
        if trial % 5 == 0:
            g = g[:, ::2]  # a strided view
        stride = int(rng.integers(1, 9))
        bgr = cv2.cvtColor(np.ascontiguousarray(g), cv2.COLOR_GRAY2BGR)
        compiled, reference = both_paths(lambda: (equalization_lut(bgr, stride=stride, gray=g),
                                                  equalization_lut(np.ascontiguousarray(g), stride=stride)))
        assert np.array_equal(compiled[0], reference[0]) and np.array_equal(compiled[1], reference[1]), trial


def test_compiled_grey_features_are_the_opencv_paths_numbers(rng):
    """quantize_gray: the compiled lattice levels and gradients (pitch >= 3) and the compiled binning give the bins of
    the OpenCV and NumPy path, over frames of three layouts, regions reaching past the frame, pitches and thresholds."""
    from pftrack.cues.gray_kernels import exact_gray_available
    from pftrack.cues.intensity import equalization_lut, quantize_gray

    if not exact_gray_available():
        pytest.skip("this OpenCV's grey conversion differs from the fixed-point formula: its own path is used")
    for trial in range(300):
        h, w = (int(v) for v in rng.integers(5, 160, 2))
        shape = [(h, w, 3), (h, w), (h, w, 1)][trial % 3]
        frame = rng.integers(0, 256, shape).astype(np.uint8)
        if trial % 4 == 0:  # a grey frame with JPEG-like channel differences
            base = rng.integers(0, 256, (h, w, 1))
            frame = np.clip(base + rng.integers(-2, 3, (h, w, 3)), 0, 255).astype(np.uint8)
        pitch = int(rng.integers(1, 12))
        x0, y0 = int(rng.integers(0, w)) // pitch * pitch, int(rng.integers(0, h)) // pitch * pitch
        roi = (x0, y0, int(rng.integers(x0 + 1, w + 10)), int(rng.integers(y0 + 1, h + 10)))
        lut = equalization_lut(frame) if trial % 2 else np.arange(256, dtype=np.uint8)
        kw = dict(n_intensity=int(rng.choice([8, 16])), n_orientation=int(rng.choice([4, 8])),
                  gradient_threshold=float(rng.choice([40.0, 10.3, 0.0])))
        compiled, reference = both_paths(lambda: quantize_gray(frame, roi, pitch, lut, **kw).copy())
        assert np.array_equal(compiled, reference), (shape, roi, pitch, kw)


def test_a_frame_made_from_grey_gives_the_three_channel_paths_grey_features_and_quotient(rng):
    """quantize_gray and the self-quotient image read the grey image a BGR frame was made from (as_bgr_uint8): the
    same bins and levels as on a plain copy of the frame, which takes the three-channel paths, at every pitch."""
    from pftrack.cues.illumination import QuotientImage
    from pftrack.cues.intensity import equalization_lut, quantize_gray
    from pftrack.frames import as_bgr_uint8, grey_origin

    for trial in range(120):
        h, w = (int(v) for v in rng.integers(5, 160, 2))
        frame = as_bgr_uint8(rng.integers(0, 256, (h, w)).astype(np.uint8))
        plain = frame.copy()
        assert grey_origin(frame) is not None and grey_origin(plain) is None
        pitch = int(rng.integers(1, 12))
        x0, y0 = int(rng.integers(0, w)) // pitch * pitch, int(rng.integers(0, h)) // pitch * pitch
        roi = (x0, y0, int(rng.integers(x0 + 1, w + 10)), int(rng.integers(y0 + 1, h + 10)))
        lut = equalization_lut(plain) if trial % 2 else np.arange(256, dtype=np.uint8)
        kw = dict(n_intensity=16, n_orientation=8, gradient_threshold=float(rng.choice([40.0, 10.3, 0.0])))
        assert np.array_equal(quantize_gray(frame, roi, pitch, lut, **kw), quantize_gray(plain, roi, pitch, lut, **kw))
        if trial % 10 == 0:
            assert np.array_equal(QuotientImage(0.1, bgr=False)(frame), QuotientImage(0.1, bgr=False)(plain))


def test_the_grey_conversion_formula_is_opencvs_for_every_colour():
    import cv2

    from pftrack.cues import gray_kernels as gk

    if not gk.exact_gray_available():
        pytest.skip("this OpenCV's grey conversion differs from the fixed-point formula: its own path is used")
    v = np.arange(1 << 24, dtype=np.uint32)
    img = np.stack([(v >> 16) & 255, (v >> 8) & 255, v & 255], -1).astype(np.uint8).reshape(4096, 4096, 3)
    b, g, r = (img[..., c].astype(np.int32) for c in range(3))
    mine = (gk._CB * b + gk._CG * g + gk._CR * r + (1 << (gk._SHIFT - 1))) >> gk._SHIFT
    assert np.array_equal(mine, cv2.cvtColor(img, cv2.COLOR_BGR2GRAY))


def test_mean_shift_sums_are_the_numpy_steps(rng):
    """The compiled mean-shift step visits ellipse_pixels' pixels and sums them as NumPy does (to the last bit)."""
    from pftrack.cues.meanshift_step import shift_sums

    for trial in range(200):
        h, w = (int(v) for v in rng.integers(1, 120, 2))
        bins = rng.integers(0, 64, (h, w)).astype(np.uint16)
        ratio = rng.random(64) * 3.0 * (rng.random(64) < 0.8)
        x0, y0 = (int(v) for v in rng.integers(0, 50, 2))
        ell = (x0 + rng.uniform(-20, w + 20), y0 + rng.uniform(-20, h + 20), rng.uniform(0.3, 70), rng.uniform(0.3, 70))
        compiled, reference = both_paths(lambda: shift_sums(bins, x0, y0, ell, ratio))
        assert compiled == reference, (trial, compiled, reference)
        if compiled[0] > 200:
            assert compiled[1] > 0
