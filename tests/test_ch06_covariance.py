"""Book ch. 6 §4: region covariance, SPD metrics and means, covariance search (ch06.md §5.1 tests 5-7)."""

import math

import numpy as np
import pytest
from scipy.linalg import expm, logm

from pftrack.cues import covariance as cv
from pftrack.cues import covariance_search as cs

from .conftest import grey_frames


def _spd(rng, d=9, n=None):
    shape = (d, d) if n is None else (n, d, d)
    A = rng.normal(size=shape)
    return A @ np.swapaxes(A, -1, -2) + 0.1 * np.eye(d)


def test_integral_covariance_equals_np_cov_on_random_windows_and_masks():
    rng = np.random.default_rng(0)
    frame = rng.integers(0, 256, (60, 80, 3), dtype=np.uint8)
    z = cv.covariance_features(frame, origin=(10, 20))
    mask = (rng.random((60, 80)) < 0.7).astype(np.float64)
    for weights in (None, mask):
        ic = cv.IntegralCovariance(z, weights, origin=(10, 20))
        for _ in range(50):
            x0, y0 = int(rng.integers(0, 60)), int(rng.integers(0, 40))
            x1, y1 = x0 + int(rng.integers(5, 80 - x0 + 1)), y0 + int(rng.integers(5, 60 - y0 + 1))
            C, W = ic.cov(np.array([[x0 + 10, y0 + 20, x1 + 10, y1 + 20]]))
            sub = z[y0:y1, x0:x1].reshape(-1, z.shape[-1])
            if weights is None:
                ref = np.cov(sub.T)
                assert W[0] == sub.shape[0]
            else:
                m = mask[y0:y1, x0:x1].ravel() > 0
                ref = np.cov(sub[m].T)
            np.testing.assert_allclose(C[0], ref, rtol=1e-8, atol=1e-8 * np.abs(ref).max())
            direct = cv.region_covariance(z[y0:y1, x0:x1], None if weights is None else mask[y0:y1, x0:x1])
            np.testing.assert_allclose(direct, ref, rtol=1e-8, atol=1e-8 * np.abs(ref).max())


@pytest.mark.parametrize("numba", [True, False])
def test_one_window_covariance_equals_the_integral_images(numba):
    """window_covariance (direct, one window) equals the integral-image covariance of the same level window,
    with and without soft weights, inside the frame and at its edge, compiled and in NumPy."""
    from pftrack._numba import set_numba_enabled

    rng = np.random.default_rng(4)
    frame = rng.integers(0, 256, (70, 90, 3), dtype=np.uint8)
    soft = rng.uniform(0.0, 1.0, (70, 90)).astype(np.float32)
    previous = set_numba_enabled(numba)
    try:
        for weights in (None, soft):
            lv = cs.Level(frame, 1, cs.derivative_scales(frame, kind="porikli9", gray=False), weights)
            for box in ((20.3, 15.2, 31.0, 24.6), (0.0, 50.0, 25.0, 20.0), (70.0, 0.0, 30.0, 30.0)):
                win = lv.to_level(box)
                ic = lv.integral(win, kind="porikli9", gray=False)
                C, _ = ic.cov(np.array([win]))
                ref = cv.standardize(C, np.array([[win[2] - win[0], win[3] - win[1]]]), lv.scales)[0]
                got = cs.window_covariance(lv, box, kind="porikli9", gray=False)
                np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())
    finally:
        set_numba_enabled(previous)


def test_features_coordinates_and_grey_channels():
    frame = np.zeros((5, 7, 3), np.uint8)
    z = cv.covariance_features(frame, origin=(3, 4), pitch=2)
    assert z.shape == (5, 7, 9)
    assert z[0, 0, 0] == 3 and z[0, 6, 0] == 15 and z[4, 0, 1] == 12
    assert cv.covariance_features(frame, gray=True).shape[-1] == 7
    assert cv.covariance_features(frame, kind="first_order").shape[-1] == 7
    assert cv.feature_names("first_order", gray=True) == ("x", "y", "I", "|Ix|", "|Iy|")


def test_le_distance_matches_scipy_logm_and_is_a_metric():
    rng = np.random.default_rng(1)
    C, D = _spd(rng), _spd(rng)
    ref = np.linalg.norm(logm(C).real - logm(D).real)
    d = cv.le_distance(cv.spd_log(C), cv.spd_log(D))
    assert d == pytest.approx(ref, rel=1e-9)
    assert cv.le_distance(cv.spd_log(C), cv.spd_log(C)) == pytest.approx(0.0, abs=1e-12)
    assert d == pytest.approx(cv.le_distance(cv.spd_log(D), cv.spd_log(C)), rel=1e-12)
    np.testing.assert_allclose(cv.spd_exp(cv.spd_log(C)), C, rtol=1e-9, atol=1e-9)
    A = rng.normal(size=(9, 9)) * 0.1
    A = A + A.T
    np.testing.assert_allclose(cv.spd_exp(A), expm(A), rtol=1e-9, atol=1e-12)


def test_le_distance_is_similarity_invariant():
    rng = np.random.default_rng(2)
    C, D = _spd(rng), _spd(rng)
    R, _ = np.linalg.qr(rng.normal(size=(9, 9)))
    s = 3.7
    d0 = cv.le_distance(cv.spd_log(C), cv.spd_log(D))
    d1 = cv.le_distance(cv.spd_log(s * R @ C @ R.T), cv.spd_log(s * R @ D @ R.T))
    assert d1 == pytest.approx(d0, abs=1e-10)


def test_le_mean_properties():
    rng = np.random.default_rng(3)
    C = _spd(rng)
    np.testing.assert_allclose(cv.le_mean(np.stack([C, np.linalg.inv(C)])), np.eye(9), atol=1e-10)
    d1, d2 = np.diag(rng.uniform(0.5, 3, 9)), np.diag(rng.uniform(0.5, 3, 9))
    np.testing.assert_allclose(cv.le_mean(np.stack([d1, d2])), np.sqrt(d1 @ d2), rtol=1e-10, atol=1e-12)
    # weights: a weight of 1 on one matrix gives that matrix
    np.testing.assert_allclose(cv.le_mean(np.stack([d1, d2]), np.array([1.0, 0.0])), d1, rtol=1e-10)


def test_airm_distance_invariances_and_eq29_orientation():
    rng = np.random.default_rng(4)
    C, D = _spd(rng), _spd(rng)
    A = rng.normal(size=(9, 9)) + 3 * np.eye(9)
    assert cv.airm_distance(A @ C @ A.T, A @ D @ A.T) == pytest.approx(cv.airm_distance(C, D), rel=1e-8)
    assert cv.airm_distance(C, 2 * C) == pytest.approx(3 * math.log(2), rel=1e-10)
    # the literal Eq. 29 (pencil (C1, C1)) would give distance 0 for any pair
    assert cv.airm_distance(C, D) > 0.1


def test_airm_mean_is_a_fixed_point_and_commuting_case():
    rng = np.random.default_rng(5)
    Cs = _spd(rng, n=5)
    M = cv.airm_mean(Cs, tol=1e-12, max_iter=500)
    lam, U = np.linalg.eigh(M)
    ih = (U / np.sqrt(lam)) @ U.T
    grad = sum(cv.spd_log(ih @ c @ ih) for c in Cs)
    assert np.linalg.norm(grad) < 1e-6
    d1, d2 = np.diag(rng.uniform(0.5, 3, 9)), np.diag(rng.uniform(0.5, 3, 9))
    np.testing.assert_allclose(cv.airm_mean(np.stack([d1, d2])), np.sqrt(d1 @ d2), rtol=1e-8)


def test_parity_with_pyriemann():
    pr = pytest.importorskip("pyriemann.utils.mean")
    dist = pytest.importorskip("pyriemann.utils.distance")
    rng = np.random.default_rng(6)
    Cs = _spd(rng, n=6)
    np.testing.assert_allclose(cv.le_mean(Cs), pr.mean_logeuclid(Cs), rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(cv.airm_mean(Cs, tol=1e-10), pr.mean_riemann(Cs, tol=1e-10), rtol=1e-6, atol=1e-8)
    assert cv.le_distance(cv.spd_log(Cs[0]), cv.spd_log(Cs[1])) == pytest.approx(
        dist.distance_logeuclid(Cs[0], Cs[1]), rel=1e-9)
    assert cv.airm_distance(Cs[0], Cs[1]) == pytest.approx(dist.distance_riemann(Cs[0], Cs[1]), rel=1e-9)


def _textured_frame(rng, h=480, w=640):
    import cv2

    noise = rng.integers(0, 256, (h // 8, w // 8, 3), dtype=np.uint8)
    bg = cv2.resize(noise, (w, h), interpolation=cv2.INTER_CUBIC)
    return cv2.GaussianBlur(bg, (0, 0), 2)


def test_derivative_scales_match_the_feature_image():
    rng = np.random.default_rng(10)
    frame = _textured_frame(rng, 120, 160)
    z = cv.covariance_features(frame)
    np.testing.assert_allclose(cs.derivative_scales(frame, kind="porikli9", gray=False),
                               cv.feature_scales(z), rtol=1e-5)


def _ramp_target(tw: int, th: int, period: float) -> np.ndarray:
    """A target of colour ramps across its width and height (a sub- or super-window has a different
    colour-coordinate covariance, so the scale is observable) and stripes of ``period`` rows the background lacks."""
    yy, xx = np.mgrid[0:th, 0:tw]
    target = np.zeros((th, tw, 3), np.uint8)
    target[..., 2] = (40 + 200 * xx / tw).astype(np.uint8)
    target[..., 1] = (40 + 200 * yy / th).astype(np.uint8)
    target[..., 0] = (60 + 60 * np.sin(yy / period)).astype(np.uint8)
    return target


@pytest.mark.parametrize("scale", [1.0, 1.1])
def test_global_search_finds_a_pasted_target(scale):
    import cv2

    rng = np.random.default_rng(7)
    frame0 = _textured_frame(rng)
    tw, th = 48, 96
    target = _ramp_target(tw, th, 3.0)
    frame0[100:100 + th, 200:200 + tw] = target
    lv0 = cs.Level.build(frame0, 1, kind="porikli9", gray=False)
    L = cv.SPDModel(cs.window_covariance(lv0, (200, 100, tw, th), kind="porikli9", gray=False))
    frame1 = _textured_frame(rng)
    sw, sh = int(round(tw * scale)), int(round(th * scale))
    frame1[300:300 + sh, 450:450 + sw] = cv2.resize(target, (sw, sh), interpolation=cv2.INTER_LINEAR)
    res = cs.search(frame1, L, (tw, th), kind="porikli9", gray=False)
    x, y, w, h = res.box
    assert abs(x - 450) <= 1 and abs(y - 300) <= 1
    assert w == pytest.approx(sw, abs=1) and h == pytest.approx(sh, abs=1)


def test_a_coarse_budget_bounds_the_windows_of_a_small_target_and_still_finds_it():
    """A small target leaves the coarse level at full resolution: ``coarse_budget`` decimates it further, with a
    fraction of the windows, and the refinement still lands on the target; 0 is the unbounded search."""
    rng = np.random.default_rng(11)
    frame0 = _textured_frame(rng, 240, 320)
    tw, th = 8, 24   # a thin target: its smaller side is the coarse level's 8 pixels at full resolution
    target = _ramp_target(tw, th, 2.0)
    frame0[60:60 + th, 100:100 + tw] = target
    lv0 = cs.Level.build(frame0, 1, kind="porikli9", gray=False)
    L = cv.SPDModel(cs.window_covariance(lv0, (100, 60, tw, th), kind="porikli9", gray=False))
    frame1 = _textured_frame(rng, 240, 320)
    frame1[150:150 + th, 220:220 + tw] = target
    full = cs.search(frame1, L, (tw, th), kind="porikli9", gray=False)
    fh, fw = frame1.shape[:2]
    bounded = cs.search(frame1, L, (tw, th), kind="porikli9", gray=False, coarse_budget=fw * fh // 4)  # halved
    for res in (full, bounded):
        x, y, _, _ = res.box
        assert abs(x - 220) <= 2 and abs(y - 150) <= 2, res.box
    assert bounded.n_windows < full.n_windows / 3
    same = cs.search(frame1, L, (tw, th), kind="porikli9", gray=False, coarse_budget=0)
    assert same.box == full.box and same.n_windows == full.n_windows


def test_particle_distances_rank_the_true_box_first():
    rng = np.random.default_rng(8)
    frame = _textured_frame(rng, 200, 200)
    frame[50:110, 60:90] = (30, 200, 30)
    frame[50:110, 75:90, 0] = 220
    lv = cs.Level.build(frame, 1, kind="porikli9", gray=False)
    L = cv.SPDModel(cs.window_covariance(lv, (60, 50, 30, 60), kind="porikli9", gray=False))
    boxes = np.array([[60, 50, 30, 60], [70, 55, 30, 60], [120, 100, 30, 60], [0, 0, 30, 60]], float)
    d = cs.particle_distances(lv, boxes, L, kind="porikli9", gray=False)
    assert np.argmin(d) == 0 and d[0] < 1e-6
    assert np.all(np.diff(d[:2]) > 0)


def test_spd_model_distances_match_the_pairwise_functions():
    rng = np.random.default_rng(9)
    M, Cs = _spd(rng), _spd(rng, n=4)
    le = cv.SPDModel(M, "le").distance(Cs)
    ai = cv.SPDModel(M, "airm").distance(Cs)
    for k in range(4):
        assert le[k] == pytest.approx(cv.le_distance(cv.spd_log(M), cv.spd_log(Cs[k])), rel=1e-10)
        assert ai[k] == pytest.approx(cv.airm_distance(M, Cs[k]), rel=1e-8)
    np.testing.assert_allclose(cv.SPDModel.from_log(cv.spd_log(M)).distance(Cs), le, rtol=1e-9)


def test_compiled_le_mean_equals_the_numpy_form():
    from pftrack import _numba

    rng = np.random.default_rng(5)
    A = rng.normal(size=(10, 9, 40))
    Cs = A @ A.transpose(0, 2, 1) / 40 + 1e-3 * np.eye(9)
    w = rng.random(10)
    got = cv.le_mean(Cs, w)
    ref = cv.spd_exp(np.tensordot(w / w.sum(), cv.spd_log(Cs), axes=1))
    np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-12)
    was = _numba.numba_enabled()
    _numba.set_numba_enabled(False)
    try:
        np.testing.assert_allclose(cv.le_mean(Cs, w), ref, rtol=1e-12, atol=1e-14)
    finally:
        _numba.set_numba_enabled(was)


def test_covariance_tracker_follows_a_grey_target_by_refining_around_the_last_box():
    """On grey input (one intensity channel) the coarse level's ranking missed the target on every frame of these
    scenes (AUC 0.02); refining around the last box as well keeps it (``refine_last``, the default)."""
    import pftrack
    from pftrack.eval.metrics import ope_scores
    from pftrack.synth import Scene, simple_scene

    for seed in (0, 2):
        sc = Scene(simple_scene(seed, n_frames=25))
        frames, gt = sc.frames(), sc.groundtruth(0)
        grey = grey_frames(frames)
        auc = {}
        for refine_last in (True, False):
            t = pftrack.create_tracker("covariance", refine_last=refine_last)
            t.init(grey[0], tuple(gt[0]))
            boxes = np.array([gt[0]] + [t.update(f).box for f in grey[1:]], float)
            auc[refine_last] = ope_scores(boxes, gt).auc
        assert auc[True] > 0.6 and auc[False] < 0.2, (seed, auc)


def test_a_zero_floor_of_the_distance_spread_is_refused():
    import pftrack
    from pftrack.errors import ParameterError

    with pytest.raises(ParameterError, match="threshold_floor"):
        pftrack.create_tracker("covariance", threshold_floor=0.0)
