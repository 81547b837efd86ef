import numpy as np
import pytest

from pftrack._numba import NUMBA_INSTALLED
from pftrack.cues.color import (bhattacharyya_coefficient, bhattacharyya_distance, ellipse_histograms, ellipse_rho,
                                kernel_weights, reachable_roi)
from pftrack.cues.histogram_cue import ColorCue
from pftrack.cues.quantize import make_lut, quantize


def reference_histogram(frame_bins, ellipse, n_bins, kernel="nummiaro", parts=1):
    """One-ellipse reference written straight from Eqs. 2-4 (loops over pixels); with ``parts=2`` the rows below the
    centre (dy > 0) count in bins ``n_bins .. 2 n_bins - 1``, normalised together with the rows above."""
    cx, cy, hx, hy = ellipse
    a2 = hx * hx + hy * hy
    h = np.zeros(n_bins * parts)
    H, W = frame_bins.shape
    for j in range(H):
        for i in range(W):
            dx, dy = i + 0.5 - cx, j + 0.5 - cy
            if (dx / hx) ** 2 + (dy / hy) ** 2 <= 1.0:
                k = 1 - (dx * dx + dy * dy) / a2 if kernel == "nummiaro" else 1 - ((dx / hx) ** 2 + (dy / hy) ** 2)
                if k > 0:
                    h[frame_bins[j, i] + (n_bins if parts == 2 and dy > 0 else 0)] += k
    return h / h.sum()


@pytest.fixture
def image(rng):
    return rng.integers(0, 256, (60, 80, 3), dtype=np.uint8)


def test_histogram_sums_to_one(image):
    cue = ColorCue()
    feats = cue.prepare_frame(image)
    ell = np.array([[40.0, 30.0, 10.0, 15.0], [5.0, 5.0, 8.0, 8.0], [79.0, 59.0, 20.0, 6.0]])
    hist, tot = cue.histograms(feats, ell)
    assert hist.shape == (3, 512)
    assert np.allclose(hist.sum(axis=1), 1.0)
    assert np.all(tot > 0)


def test_bhattacharyya_identity_and_symmetry(rng):
    p = rng.random(512)
    p /= p.sum()
    q = rng.random(512)
    q /= q.sum()
    assert bhattacharyya_coefficient(p, p) == pytest.approx(1.0)
    assert bhattacharyya_coefficient(p, q) == pytest.approx(bhattacharyya_coefficient(q, p))
    assert bhattacharyya_distance(p, p) == pytest.approx(0.0, abs=1e-7)
    disjoint = np.zeros(512)
    disjoint[0] = 1
    other = np.zeros(512)
    other[1] = 1
    assert bhattacharyya_coefficient(disjoint, other) == 0.0
    assert bhattacharyya_distance(disjoint, other) == pytest.approx(1.0)


def test_kernel_weights_match_eq2():
    """k(r) = 1 - r^2 with r = ||d|| / a, a = sqrt(Hx^2 + Hy^2); zero outside the ellipse."""
    hx, hy = 6.0, 8.0
    a = np.hypot(hx, hy)
    d = np.array([[0.0, 0.0], [3.0, 4.0], [6.0, 0.0], [0.0, 8.0], [6.0, 8.0]])
    w = kernel_weights(d, hx, hy)
    expected = [1.0, 1 - 25 / a ** 2, 1 - 36 / a ** 2, 1 - 64 / a ** 2, 0.0]
    assert w == pytest.approx(expected)


@pytest.mark.parametrize("kernel", ["nummiaro", "epanechnikov"])
@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_batch_equals_single_reference(image, kernel, backend, rng):
    if backend == "numba" and not NUMBA_INSTALLED:
        pytest.skip("numba not installed")
    lut = make_lut("rgb", (8, 8, 8))
    bins = quantize(image, lut)
    ell = np.column_stack([rng.uniform(0, 80, 25), rng.uniform(0, 60, 25), rng.uniform(2, 20, 25),
                           rng.uniform(2, 20, 25)])
    hist, _ = ellipse_histograms(bins, 0, 0, ell, 512, kernel=kernel, backend=backend)
    for n in range(len(ell)):
        assert hist[n] == pytest.approx(reference_histogram(bins, ell[n], 512, kernel), abs=1e-12)


@pytest.mark.skipif(not NUMBA_INSTALLED, reason="numba not installed")
def test_numba_and_numpy_paths_identical(rng):
    img = rng.integers(0, 256, (120, 160, 3), dtype=np.uint8)
    cue = ColorCue()
    feats = cue.prepare(img, (20, 10, 150, 110))
    ell = np.column_stack([rng.uniform(10, 160, 200), rng.uniform(0, 120, 200), rng.uniform(1, 40, 200),
                           rng.uniform(1, 40, 200)])
    a, ta = ellipse_histograms(feats.bins, feats.x0, feats.y0, ell, 512, backend="numba")
    b, tb = ellipse_histograms(feats.bins, feats.x0, feats.y0, ell, 512, backend="numpy")
    # same pixels and weights; only the order of the floating-point sums differs
    assert np.array_equal(ta > 0, tb > 0) and np.array_equal(a > 0, b > 0)
    assert np.allclose(a, b, rtol=0, atol=1e-12) and np.allclose(ta, tb, rtol=1e-12, atol=0)


@pytest.mark.parametrize("bins", [(8, 8, 8), (16, 4, 2), (6, 6, 6)])
def test_region_quantisation_by_shifts_equals_the_table(rng, bins):
    """Power-of-two RGB bins are quantised by shifts on the frame's rows: the same bins as the table lookup,
    for any region (and the table itself when the bins are not powers of two)."""
    from pftrack.cues.quantize import quantize_region, shift_form
    lut = make_lut("rgb", bins)
    shifts = shift_form(lut)
    assert (shifts is None) == (bins == (6, 6, 6))
    img = rng.integers(0, 256, (70, 90, 3), dtype=np.uint8)
    for x0, y0, x1, y1 in [(0, 0, 90, 70), (13, 7, 61, 52), (89, 69, 90, 70), (5, 60, 90, 70)]:
        expected = quantize(np.ascontiguousarray(img[y0:y1, x0:x1]), lut)
        out = np.empty((y1 - y0, x1 - x0), np.uint16)
        assert np.array_equal(quantize_region(img, x0, y0, x1, y1, lut, out, shifts), expected)
    cue = ColorCue(bins=bins)
    feats = cue.prepare(img, (13, 7, 61, 52))
    assert np.array_equal(feats.bins, quantize(np.ascontiguousarray(img[7:52, 13:61]), lut))


@pytest.mark.skipif(not NUMBA_INSTALLED, reason="numba not installed")
def test_compiled_rows_take_exactly_the_pixels_inside_on_the_pixel_grid(rng):
    """Ellipses whose ends fall on pixel centres (centres and half-axes on the half-pixel grid, the rows' spans
    then end exactly at a centre) and random ones: the compiled path's analytic row spans, with its exact
    fallback near pixel centres, select exactly the pixels of the exact test (one bin per pixel)."""
    h, w = 60, 80
    bins = np.arange(h * w, dtype=np.int64).reshape(h, w)
    snapped = np.column_stack([rng.integers(0, 160, 300) / 2.0, rng.integers(0, 120, 300) / 2.0,
                               rng.integers(1, 60, 300) / 2.0, rng.integers(1, 60, 300) / 2.0])
    snapped[:100, 3] = snapped[:100, 2]  # circles: rows whose span ends at a centre in both directions
    free = np.column_stack([rng.uniform(0, 80, 200), rng.uniform(0, 60, 200), rng.uniform(0.3, 30, 200),
                            rng.uniform(0.3, 30, 200)])
    ell = np.concatenate([snapped, free])
    a, _ = ellipse_histograms(bins, 0, 0, ell, h * w, backend="numba")
    b, _ = ellipse_histograms(bins, 0, 0, ell, h * w, backend="numpy")
    assert np.array_equal(a > 0, b > 0)
    assert np.allclose(a, b, rtol=0, atol=1e-12)


@pytest.mark.parametrize("kernel", ["nummiaro", "epanechnikov"])
@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_fused_rho_equals_histogram_then_bhattacharyya(rng, kernel, backend):
    if backend == "numba" and not NUMBA_INSTALLED:
        pytest.skip("numba not installed")
    img = rng.integers(0, 256, (90, 120, 3), dtype=np.uint8)
    cue = ColorCue(kernel=kernel)
    feats = cue.prepare(img, (5, 5, 110, 85))
    ell = np.column_stack([rng.uniform(0, 120, 300), rng.uniform(0, 90, 300), rng.uniform(0.5, 30, 300),
                           rng.uniform(0.5, 30, 300)])
    q = rng.random(512) ** 4
    q /= q.sum()
    hist, tot = ellipse_histograms(feats.bins, feats.x0, feats.y0, ell, 512, kernel=kernel, backend="numpy")
    expected = np.where(tot > 0, bhattacharyya_coefficient(hist, q), 0.0)
    rho, tot2 = ellipse_rho(feats.bins, feats.x0, feats.y0, ell, np.sqrt(q), kernel=kernel, backend=backend)
    assert np.allclose(rho, expected, rtol=0, atol=1e-12)
    assert np.allclose(tot2, tot, rtol=1e-12, atol=1e-12)


def test_roi_offset_gives_same_histogram(image):
    cue = ColorCue()
    ell = np.array([[40.0, 30.0, 10.0, 12.0]])
    full, _ = cue.histograms(cue.prepare_frame(image), ell, reuse=False)
    roi = reachable_roi(ell, 80, 60)
    part, _ = cue.histograms(cue.prepare(image, roi), ell, reuse=False)
    assert np.allclose(full, part)


def test_ellipse_outside_image_is_empty(image):
    cue = ColorCue()
    hist, tot = cue.histograms(cue.prepare_frame(image), np.array([[500.0, 500.0, 5.0, 5.0]]))
    assert tot[0] == 0 and hist.sum() == 0


def test_rgb_and_hsv_bin_layout():
    px = np.array([[[255, 0, 0], [0, 0, 255], [0, 255, 0]]], dtype=np.uint8)  # BGR: blue, red, green
    b = quantize(px, make_lut("rgb", (8, 8, 8)))
    assert b.tolist() == [[7, 7 * 64, 7 * 8]]
    cue = ColorCue("hsv")
    assert cue.n_bins == 8 * 8 * 4
    f = cue.prepare(px, (0, 0, 3, 1))
    assert f.bins.max() < cue.n_bins


@pytest.mark.parametrize("pitch", [2, 3])
@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_lattice_sampling_matches_reference(rng, pitch, backend):
    from pftrack._numba import set_numba_enabled

    if backend == "numba" and not NUMBA_INSTALLED:
        pytest.skip("numba not installed")
    img = rng.integers(0, 256, (60, 80, 3), dtype=np.uint8)
    lut = make_lut("rgb", (8, 8, 8))
    cue = ColorCue()
    prev = set_numba_enabled(backend == "numba")
    try:
        feats = cue.prepare(img, (3, 7, 80, 60), pitch)
        ell = np.column_stack([rng.uniform(0, 80, 20), rng.uniform(0, 60, 20), rng.uniform(3, 25, 20),
                               rng.uniform(3, 25, 20)])
        hist, _ = cue.histograms(feats, ell, reuse=False)
    finally:
        set_numba_enabled(prev)
    assert feats.x0 % pitch == 0 and feats.y0 % pitch == 0
    full = quantize(img, lut)
    for n in range(len(ell)):
        cx, cy, hx, hy = ell[n]
        a2 = hx * hx + hy * hy
        ref = np.zeros(512)
        for j in range(feats.y0, 60, pitch):
            for i in range(feats.x0, 80, pitch):
                dx, dy = i + 0.5 - cx, j + 0.5 - cy
                if (dx / hx) ** 2 + (dy / hy) ** 2 <= 1.0:
                    ref[full[j, i]] += 1 - (dx * dx + dy * dy) / a2
        if ref.sum() > 0:
            assert hist[n] == pytest.approx(ref / ref.sum(), abs=1e-9)
        else:
            assert hist[n].sum() == 0


def test_max_pixels_picks_a_lattice():
    cue = ColorCue(max_pixels=1000)
    assert cue.step_for(np.array([[0, 0, 10.0, 10.0]])) == 1
    assert cue.step_for(np.array([[0, 0, 50.0, 50.0]])) == 3  # 7854 px -> pitch 3 (~873 samples)
    assert ColorCue().step_for(np.array([[0, 0, 500.0, 500.0]])) == 1


def test_prepare_with_a_mapped_table_undoes_a_gain_without_touching_the_frame_features():
    from pftrack.cues.intensity import channel_levels, gain_maps

    rng = np.random.default_rng(3)
    img = rng.integers(20, 160, (60, 80, 3)).astype(np.uint8)
    lit = (img.astype(np.float32) * np.array([1.5, 1.0, 0.75], np.float32)).round().clip(0, 255).astype(np.uint8)
    cue = ColorCue("rgb")
    roi = (10, 10, 70, 50)
    ref = cue.prepare(img, roi).bins.copy()
    frame_feats = cue.prepare(lit, roi)          # the frame's features live in the cue's shared buffer
    held = frame_feats.bins.copy()
    identity = cue.prepare(img, roi, lut=cue.mapped_lut(np.tile(np.arange(256), (3, 1))))
    assert np.array_equal(identity.bins, ref)
    relit = cue.prepare(lit, roi, lut=cue.mapped_lut(gain_maps(channel_levels(img), channel_levels(lit))))
    assert np.mean(relit.bins == ref) > 0.9 > np.mean(held == ref)
    assert np.array_equal(frame_feats.bins, held)  # a mapped table quantises into its own array
    with pytest.raises(ValueError):
        ColorCue("gray").prepare(img, roi, lut=cue.lut)


@pytest.mark.skipif(not NUMBA_INSTALLED, reason="numba not installed")
@pytest.mark.parametrize("n, shape", [(100, (70, 90)), (6, (300, 400))])
def test_fused_rho_with_a_bin_count_not_a_multiple_of_eight(rng, n, shape):
    """The compiled sum visits only the bins that can be non-zero: those of the region (many ellipses over a
    small region) or the groups of 8 bins each ellipse touched (a few ellipses in a large one); the last
    group is partial here (153 bins, the grey features' 17 x 9)."""
    bins = rng.integers(0, 153, shape).astype(np.uint16)
    bins[:, :30] = 152  # the last, partial group carries much of the mass
    ell = np.column_stack([rng.uniform(0, 90, n), rng.uniform(0, 70, n), rng.uniform(0.5, 25, n),
                           rng.uniform(0.5, 25, n)])
    q = rng.random(153) ** 3
    q /= q.sum()
    hist, tot = ellipse_histograms(bins, 0, 0, ell, 153, backend="numpy")
    expected = np.where(tot > 0, bhattacharyya_coefficient(hist, q), 0.0)
    rho, tot2 = ellipse_rho(bins, 0, 0, ell, np.sqrt(q), backend="numba")
    assert np.allclose(rho, expected, rtol=0, atol=1e-12)
    assert np.allclose(tot2, tot, rtol=1e-12, atol=1e-12)


def test_channel_levels_are_the_medians_of_the_lattice():
    """The 8-bit path (each channel's histogram) gives np.median's numbers, for odd and even counts, colour and
    grey frames."""
    from pftrack.cues.intensity import channel_levels

    rng = np.random.default_rng(3)
    for t in range(60):
        h, w = (int(v) for v in rng.integers(1, 90, 2))
        img = (rng.integers(0, 256, (h, w, 3), dtype=np.uint8) if t % 2
               else np.minimum(rng.poisson(rng.uniform(0, 60), (h, w, 3)), 255).astype(np.uint8))
        stride = int(rng.integers(1, 12))
        ref = np.maximum(np.median(img[::stride, ::stride].reshape(-1, 3), axis=0), 1.0)
        assert np.array_equal(channel_levels(img, stride=stride), ref)
    grey = rng.integers(0, 256, (40, 50), dtype=np.uint8)
    assert np.array_equal(channel_levels(grey, stride=3), np.maximum(np.median(grey[::3, ::3].reshape(-1, 1), axis=0),
                                                                     1.0))
    # the compiled lattice on a view (a block of the frame, as light_levels' blocks are) and on 4 channels
    img = rng.integers(0, 256, (61, 83, 4), dtype=np.uint8)
    for view in (img[5:40, 7:70], img[::-1, ::2]):
        ref = np.maximum(np.median(view[::4, ::4].reshape(-1, 4), axis=0), 1.0)
        assert np.array_equal(channel_levels(view, stride=4), ref)



@pytest.mark.parametrize("kernel", ["nummiaro", "epanechnikov"])
@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_two_part_histograms_follow_the_rows_of_each_ellipse(image, kernel, backend, rng):
    """parts=2: each ellipse's rows above its own centre fill the first half of the bins, the rows below the
    second; as the loops of the reference, on both paths, and the fused rho (dense and sparse bin scans) is the
    Bhattacharyya coefficient of those histograms."""
    if backend == "numba" and not NUMBA_INSTALLED:
        pytest.skip("numba not installed")
    bins = quantize(image, make_lut("rgb", (8, 8, 8)))
    ell = np.column_stack([rng.uniform(0, 80, 25), rng.uniform(0, 60, 25), rng.uniform(2, 20, 25),
                           rng.uniform(2, 20, 25)])
    ell[0] = (40.5, 30.5, 6.0, 6.0)  # a centre on a pixel centre: its row (dy = 0) is in the upper part
    hist, tot = ellipse_histograms(bins, 0, 0, ell, 1024, kernel=kernel, backend=backend, parts=2)
    for n in range(len(ell)):
        assert hist[n] == pytest.approx(reference_histogram(bins, ell[n], 512, kernel, parts=2), abs=1e-12)
    inside = (ell[:, 0] - ell[:, 2] >= 0) & (ell[:, 0] + ell[:, 2] <= 80) & (ell[:, 1] - ell[:, 3] >= 0) & (
        ell[:, 1] + ell[:, 3] <= 60)
    upper = hist[inside, :512].sum(axis=1)
    assert inside.sum() >= 3 and np.all((upper > 0.3) & (upper < 0.7))  # the symmetric kernel: about half each
    q = rng.random(1024) ** 4
    q /= q.sum()
    expected = np.where(tot > 0, bhattacharyya_coefficient(hist, q), 0.0)
    for few in (False, True):  # all the ellipses (the region's bins scanned) or one (the touched groups)
        sel = ell[:1] if few else ell
        rho, _ = ellipse_rho(bins, 0, 0, sel, np.sqrt(q), kernel=kernel, backend=backend, parts=2)
        assert np.allclose(rho, expected[:len(sel)], rtol=0, atol=1e-12)
    one, _ = ellipse_histograms(bins, 0, 0, ell, 512, kernel=kernel, backend=backend)
    assert np.allclose(hist[:, :512] + hist[:, 512:], one, rtol=0, atol=1e-12)  # the parts add up to the whole


def test_two_parts_need_an_even_number_of_bins(image):
    bins = quantize(image, make_lut("rgb", (8, 8, 8)))
    with pytest.raises(ValueError, match="parts"):
        ellipse_histograms(bins, 0, 0, np.array([[40.0, 30.0, 5.0, 5.0]]), 511, parts=2)
    with pytest.raises(ValueError, match="parts"):
        ellipse_rho(bins, 0, 0, np.array([[40.0, 30.0, 5.0, 5.0]]), np.ones(1024), parts=3)
