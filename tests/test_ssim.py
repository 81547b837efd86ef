"""Book ch. 2: batched SSIM, the DSSIM gradient and ascent, ssim-pf / dssim / hybrid-ssim-pf."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.cues import ssim as S
from pftrack.cues import ssim_ascent as A
from pftrack.geometry import center_error
from pftrack.synth import camouflage_scene

from .conftest import cached_scene


def _pairs(seed=0, n=60, shape=(41, 31)):
    rng = np.random.default_rng(seed)
    t = cv2.GaussianBlur(rng.uniform(0, 255, shape), (0, 0), 1.0)
    p = np.clip(t[None] * rng.uniform(0.5, 1.2, (n, 1, 1)) + rng.normal(0, 25, (n,) + shape), 0, 255)
    return p, t


def test_batch_equals_the_reference_formula():
    p, t = _pairs()
    ref = np.array([S.ssim_reference(q, t) for q in p])
    assert np.max(np.abs(S.ssim_batch(p, t) - ref)) < 1e-6
    stack = np.ascontiguousarray(p.astype(np.float32).transpose(1, 2, 0))
    assert np.max(np.abs(S.ssim_stack(stack, t) - ref)) < 1e-6


def test_batch_equals_scikit_image_and_opencv_quality():
    p, t = _pairs(1)
    skm = pytest.importorskip("skimage.metrics")
    ref = [skm.structural_similarity(q, t, gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
                                     data_range=255) for q in p]
    assert np.max(np.abs(S.ssim_batch(p, t) - ref)) < 1e-6
    # OpenCV's quality module: whole map, REFLECT_101 borders
    q = [cv2.quality.QualitySSIM_compute(x.astype(np.float64), t.astype(np.float64))[0][0] for x in p]
    assert np.max(np.abs(S.ssim_batch(p, t, crop=False, border=cv2.BORDER_REFLECT_101) - q)) < 1e-6


def test_numpy_path_equals_compiled_path():
    from pftrack._numba import NUMBA_INSTALLED, set_numba_enabled

    if not NUMBA_INSTALLED:
        pytest.skip("numba not installed")
    p, t = _pairs(2)
    a = S.ssim_batch(p, t)
    prev = set_numba_enabled(False)
    try:
        b = S.ssim_batch(p, t)
    finally:
        set_numba_enabled(prev)
    assert np.max(np.abs(a - b)) < 1e-6


def test_global_ssim_closed_form_and_properties():
    rng = np.random.default_rng(3)
    j = rng.uniform(40, 200, (20, 30))
    a, b = 0.7, 12.0
    i = a * j + b
    mi, mj, vj = i.mean(), j.mean(), j.var(ddof=1)
    expected = (2 * mi * mj + S.C1) / (mi ** 2 + mj ** 2 + S.C1) * (2 * a * vj + S.C2) / ((1 + a * a) * vj + S.C2)
    assert A.ssim_global(i, j) == pytest.approx(expected, abs=1e-12)
    assert A.ssim_global(j, j) == pytest.approx(1.0, abs=1e-15)
    assert A.ssim_global(255 - j, j) < 0
    d = S.dissimilarity(np.array([1.0, 0.0, -1.0]))
    assert list(d) == [0.0, 0.5, 1.0]
    ll = S.log_likelihood_dmin(np.array([0.2, 0.1, 0.4]))
    assert ll.max() == pytest.approx(-1.0) and np.all(np.isfinite(S.log_likelihood_dmin(np.zeros(3))))


def _analytic_image(seed):
    rng = np.random.default_rng(seed)
    amp, kx, ky, ph = rng.uniform(20, 60, 6), rng.uniform(0.05, 0.2, 6), rng.uniform(0.05, 0.2, 6), rng.uniform(0, 6, 6)

    def f(x, y):
        return 128 + sum(amp[k] * np.sin(kx[k] * x + ky[k] * y + ph[k]) for k in range(6))

    def grad(x, y):
        c = [amp[k] * np.cos(kx[k] * x + ky[k] * y + ph[k]) for k in range(6)]
        return sum(c[k] * kx[k] for k in range(6)), sum(c[k] * ky[k] for k in range(6))

    return f, grad


def test_dssim_gradient_matches_finite_differences():
    """Eq. (39) with the corrected A3 = 2/(2 sigma_IJ + C2) against central differences of rho; the printed A3 is
    off."""
    f, grad = _analytic_image(1)
    u, v = S.patch_grid((30, 40))
    uu, vv = np.meshgrid(u, v)
    tmpl = f(80 + uu, 60 + vv)

    def rho(cx, cy):
        s = A.ssim_global(f(cx + uu, cy + vv), tmpl)
        return np.sign(s) * np.log(abs(s))

    rng = np.random.default_rng(2)
    worst_paper = 1.0
    for _ in range(20):
        cx, cy = 80 + rng.uniform(-6, 6), 60 + rng.uniform(-6, 6)
        gx, gy = grad(cx + uu, cy + vv)
        g = A.grad_rho(f(cx + uu, cy + vv), tmpl, gx, gy)
        gp = A.grad_rho(f(cx + uu, cy + vv), tmpl, gx, gy, a3_paper=True)
        e = 1e-4
        fd = np.array([(rho(cx + e, cy) - rho(cx - e, cy)) / (2 * e), (rho(cx, cy + e) - rho(cx, cy - e)) / (2 * e)])
        cos = g @ fd / np.linalg.norm(g) / np.linalg.norm(fd)
        assert cos > 0.9999 and abs(np.linalg.norm(g) / np.linalg.norm(fd) - 1) < 0.01
        worst_paper = min(worst_paper, np.linalg.norm(gp) / np.linalg.norm(fd))
    assert worst_paper < 0.9  # the printed constant gives a visibly wrong gradient


def test_dssim_ascent_converges_to_the_template_position():
    rng = np.random.default_rng(4)
    img = cv2.GaussianBlur(rng.uniform(0, 255, (120, 160)), (0, 0), 3).astype(np.float32)
    gx, gy = A.image_gradients(img)
    star = (80.0, 60.0)
    tmpl = S.sample_patches(img, np.array([[*star, 1.0]]), (30, 40))[0].astype(np.float64)
    hits = total = 0
    for dx in range(-4, 5):
        for dy in range(-4, 5):
            if dx == dy == 0:
                continue
            cx, cy, s, it = A.dssim_ascent(img, gx, gy, tmpl, (star[0] + dx, star[1] + dy))
            total += 1
            hits += (cx, cy) == star
            assert it <= max(abs(dx), abs(dy)) + 2
    assert hits / total >= 0.95
    flat = np.full((60, 80), 100, np.float32)
    z = np.zeros_like(flat)
    assert A.dssim_ascent(flat, z, z, np.full((10, 12), 90.0), (40, 30))[3] == 0  # no gradient: stops at once


def _track(name, spec, seed, **kw):
    scene = cached_scene(spec)
    frames, gt = scene.frames(), scene.groundtruth(0)
    t = pftrack.create_tracker(name, seed=seed, **kw)
    t.init(frames[0], tuple(gt[0]))
    boxes = [gt[0]] + [t.update(f).box for f in frames[1:]]
    return center_error(np.array(boxes), gt)


def test_camouflage_scene_is_tracked_by_structure_not_by_colour():
    """The target is a flipped patch of the background: ssim-pf follows it, colour cannot (ch02.md S1)."""
    ssim_err, colour_err = [], []
    for seed in range(3):
        spec = camouflage_scene(seed, n_frames=80)
        ssim_err.append(_track("ssim-pf", spec, seed).mean())
        colour_err.append(_track("color-pf", spec, seed).mean())
    assert max(ssim_err) < 3.0, ssim_err
    assert np.mean(ssim_err) * 5 < np.mean(colour_err), (ssim_err, colour_err)


@pytest.mark.parametrize("name", ["ssim-pf", "dssim", "hybrid-ssim-pf"])
def test_ssim_trackers_are_deterministic_and_follow_the_camouflaged_target(name):
    spec = camouflage_scene(7, n_frames=40)
    a = _track(name, spec, 3)
    b = _track(name, spec, 3)
    assert np.array_equal(a, b)
    assert a.mean() < 3.0


def test_hybrid_without_dssim_is_ssim_pf():
    """alpha = 0 and no DSSIM iterations: the hybrid's weights reduce to SSIM-PF's (same seed, same result)."""
    spec = camouflage_scene(2, n_frames=15)
    a = _track("hybrid-ssim-pf", spec, 1, alpha=0.0, max_iter=0, proposal="mixture_sample", n_particles=30)
    b = _track("ssim-pf", spec, 1, n_particles=30)
    assert np.array_equal(a, b)


def test_ssim_pf_rotation_state_and_grey_input():
    spec = camouflage_scene(4, n_frames=30)
    scene = cached_scene(spec)
    frames, gt = scene.frames(), scene.groundtruth(0)
    t = pftrack.create_tracker("ssim-pf", seed=0, rotation=True, n_particles=60)
    grey = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in frames]
    st = t.init(grey[0], tuple(gt[0]))
    for f in grey[1:]:
        st = t.update(f)
    assert st.particles.shape == (60, 4) and st.state_names[-1] == "angle"
    assert center_error(np.array([st.box]), gt[-1:])[0] < 5.0


@pytest.mark.parametrize("name", ["ssim-pf", "dssim", "hybrid-ssim-pf"])
def test_registered_and_usable_from_the_cli(tmp_path, name):
    from pftrack.cli import main
    from pftrack.io.sinks import read_track_csv
    from pftrack.synth import export_otb

    export_otb(camouflage_scene(1, n_frames=12), tmp_path / "seq")
    out = tmp_path / "t.csv"
    assert main(["track", str(tmp_path / "seq"), "--tracker", name, "--out", str(out), "--quiet"]) == 0
    rows = read_track_csv(out)
    assert rows.shape[0] == 12 and np.all(np.isfinite(rows[:, 1:5]))
    assert name in [s.name for s in pftrack.list_trackers()]


def test_region_ssim_and_sparse_gradients_agree_with_the_dense_ones():
    rng = np.random.default_rng(9)
    img = cv2.GaussianBlur(rng.uniform(0, 255, (120, 160)), (0, 0), 3).astype(np.float32)
    tmpl = S.sample_patches(img, np.array([[80.0, 60.0, 2.0]]), (15, 20))[0].astype(np.float64)
    assert A.region_ssim(img, tmpl, (80.0, 60.0), scale=2.0) == pytest.approx(1.0, abs=1e-9)
    patch = S.sample_patches(img, np.array([[83.0, 57.0, 2.0]]), (15, 20))[0]
    assert A.region_ssim(img, tmpl, (83.0, 57.0), scale=2.0) == pytest.approx(A.ssim_global(patch, tmpl), abs=1e-4)
    gx, gy = A.image_gradients(img)
    dense = A.dssim_ascent(img, gx, gy, tmpl, (84, 58), scale=2.0)
    sparse = A.dssim_ascent(img, None, None, tmpl, (84, 58), scale=2.0)
    assert dense[:2] == sparse[:2] == (80.0, 60.0)


def test_global_ssim_map_equals_the_batched_global_ssim_at_every_placement():
    from pftrack.cues.ssim import sample_stack, ssim_global_map, ssim_global_stack, top_peaks

    rng = np.random.default_rng(11)
    img = cv2.GaussianBlur(rng.uniform(0, 255, (40, 50)), (0, 0), 1.5).astype(np.float32)
    tpl = img[10:19, 20:33].copy()  # 9 x 13, an exact placement at top-left (20, 10)
    m = ssim_global_map(img, tpl)
    assert m.shape == (32, 38)
    ys, xs = np.mgrid[0:32:5, 0:38:6]
    st = np.column_stack([xs.ravel() + 13 / 2, ys.ravel() + 9 / 2, np.ones(xs.size)])
    ref = ssim_global_stack(sample_stack(img, st, (9, 13)), tpl)
    assert np.allclose(m[ys.ravel(), xs.ravel()], ref, atol=1e-4)
    assert m[10, 20] == pytest.approx(1.0, abs=1e-5) and np.unravel_index(np.argmax(m), m.shape) == (10, 20)
    peaks = top_peaks(m, 3, (4, 6))
    assert tuple(peaks[0]) == (10, 20)
    assert np.all(np.abs(peaks[1:] - peaks[0]).max(axis=1) > 0)
    assert all(abs(r - 10) > 4 or abs(c - 20) > 6 for r, c in peaks[1:])  # suppressed neighbourhood
    # reused buffers give the same map, also after a call of another size; in-place suppression the same peaks
    work: dict = {}
    for a, t in ((img, tpl), (img[:30], tpl[:7]), (img, tpl)):
        assert np.array_equal(ssim_global_map(a, t, work=work), ssim_global_map(a, t))
    assert np.array_equal(top_peaks(ssim_global_map(img, tpl, work=work), 3, (4, 6), inplace=True), peaks)
    from pftrack._numba import set_numba_enabled

    previous = set_numba_enabled(False)  # the NumPy path: the same map
    try:
        assert np.allclose(ssim_global_map(img, tpl), m, rtol=0, atol=1e-12)
    finally:
        set_numba_enabled(previous)


def test_region_samples_are_the_clamped_bilinear_image_on_the_scaled_grid():
    """The ascent's grid sampling (per-axis taps) equals a point-by-point bilinear interpolation with the
    coordinates clamped to the image, also for a region hanging over the border; with offsets +-1 it gives
    the central differences."""
    rng = np.random.default_rng(5)
    img = rng.uniform(0, 255, (23, 31)).astype(np.float32)
    tmpl = rng.uniform(0, 255, (7, 9))

    def bilinear(x, y):
        fx = np.clip(x - 0.5, 0, img.shape[1] - 1)
        fy = np.clip(y - 0.5, 0, img.shape[0] - 1)
        x0 = np.minimum(fx.astype(int), img.shape[1] - 2)
        y0 = np.minimum(fy.astype(int), img.shape[0] - 2)
        ax, ay = fx - x0, fy - y0
        i = img.astype(np.float64)
        return ((1 - ay) * ((1 - ax) * i[y0, x0] + ax * i[y0, x0 + 1])
                + ay * ((1 - ax) * i[y0 + 1, x0] + ax * i[y0 + 1, x0 + 1]))

    for cx, cy, s in ((15.3, 11.7, 1.0), (2.2, 20.9, 1.7), (29.5, 1.1, 0.6)):
        u, v = S.patch_grid(tmpl.shape)
        xx, yy = np.meshgrid(cx + s * u, cy + s * v)
        vals = np.empty(tmpl.size)
        ti, ta = np.empty((2, 2, 9), np.int64), np.empty((2, 9))
        sv = A._region_value(img, tmpl, cx, cy, s, S.C1, S.C2, vals, ti, ta)[0]
        assert np.allclose(vals, bilinear(xx, yy).ravel(), rtol=0, atol=1e-9)
        i, j = bilinear(xx, yy).ravel(), tmpl.ravel()
        ref = ((2 * i.mean() * j.mean() + S.C1) * (2 * np.cov(i, j)[0, 1] + S.C2)
               / ((i.mean() ** 2 + j.mean() ** 2 + S.C1) * (i.var(ddof=1) + j.var(ddof=1) + S.C2)))
        assert sv == pytest.approx(ref, abs=1e-9)
        e = np.empty((0, 0), np.float32)
        g = A._region_ssim_grad(img, e, e, tmpl, cx, cy, s, S.C1, S.C2, True)[1:]
        dx = 0.5 * (bilinear(xx + 1, yy) - bilinear(xx - 1, yy)).ravel()
        dy = 0.5 * (bilinear(xx, yy + 1) - bilinear(xx, yy - 1)).ravel()
        assert np.allclose(g, A.grad_rho(i, j, dx, dy), rtol=1e-9, atol=1e-12)
