"""Local-motion cue and local-motion-pf (Kristan et al.)."""

import math

import cv2
import numpy as np
import pytest

import pftrack
from pftrack._numba import NUMBA_INSTALLED
from pftrack.cues.motion import (FlowField, LocalMotionCue, local_motion, lucas_kanade_flow, min_eigenvalue,
                                 min_eigenvalue_reference, motion_likelihood, motion_log_likelihood,
                                 shi_tomasi_features, similarities)
from pftrack.eval.vot import run_vot
from pftrack.synth import crossing_scene, simple_scene

from .conftest import render_scene


def textured(rng, h=120, w=160):
    base = rng.integers(0, 256, (h // 4, w // 4), dtype=np.uint8)
    return cv2.GaussianBlur(cv2.resize(base, (w, h), interpolation=cv2.INTER_CUBIC), (0, 0), 1.0)


@pytest.mark.parametrize("shift", [(2.3, -1.4), (-0.6, 0.8), (4.0, 3.0)])
def test_flow_of_translated_texture_is_recovered(rng, shift):
    prev = textured(rng)
    M = np.float32([[1, 0, shift[0]], [0, 1, shift[1]]])
    cur = cv2.warpAffine(prev, M, (prev.shape[1], prev.shape[0]), flags=cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_REFLECT)
    pts = shi_tomasi_features(cur, (30, 30, 130, 90), max_features=200)
    assert len(pts) > 50
    flow = lucas_kanade_flow(prev, cur, pts, window=9, levels=2 if max(map(abs, shift)) > 3 else 1)
    assert flow.n > 0.8 * len(pts)
    assert np.median(flow.vx) == pytest.approx(shift[0], abs=0.1)
    assert np.median(flow.vy) == pytest.approx(shift[1], abs=0.1)


def test_shi_tomasi_map_equals_written_out_definition(rng):
    g = textured(rng)
    assert np.allclose(min_eigenvalue(g)[2:-2, 2:-2], min_eigenvalue_reference(g)[2:-2, 2:-2], rtol=1e-4, atol=1e-9)
    flat = np.full((40, 40), 128, np.uint8)
    assert len(shi_tomasi_features(flat, (0, 0, 40, 40))) == 0  # no texture, no feature


def test_similarities_follow_their_definitions():
    ref = np.array([2.0, 0.0])
    v = np.array([[2.0, 0.0], [0.0, 2.0], [-2.0, 0.0], [1.0, 0.0], [0.0, 0.0], [0.005, 0.0]])
    g_t, g_r = similarities(v, ref)
    assert g_t[:3] == pytest.approx([0.0, 0.5, 1.0])  # angle / pi
    assert g_r[:4] == pytest.approx([0.0, 0.0, 0.0, 1 / 3])  # |r_ref - r| / (r_ref + r)
    assert g_t[4] == 1.0 and g_r[4] == 1.0  # below the noise threshold: direction undefined
    assert g_t[5] == 1.0
    # both below the noise threshold: G_theta = 1, G_r = 0
    g_t, g_r = similarities(np.array([[0.001, 0.0]]), np.array([0.0, 0.004]))
    assert g_t[0] == 1.0 and g_r[0] == 0.0
    # an undefined region (no feature) gives G_theta = G_r = 1
    g_t, g_r = similarities(np.array([[2.0, 0.0]]), ref, defined=np.array([False]))
    assert g_t[0] == 1.0 and g_r[0] == 1.0
    p = motion_likelihood(np.array([0.0, 1.0]), np.array([0.0, 1.0]), sigma_theta=0.1, sigma_r=0.3, w_noise=0.01)
    assert p == pytest.approx([1.0, 0.99 * math.exp(-(10 + 1 / 0.3)) + 0.01])


def test_local_motion_is_the_kernel_weighted_mean():
    flow = FlowField(np.array([10.0, 12.0, 50.0]), np.array([10.0, 10.0, 10.0]), np.array([1.0, 3.0, 9.0]),
                     np.array([0.0, 0.0, 9.0]))
    v, defined = local_motion(flow, np.array([[10.0, 10.0, 4.0, 4.0], [100.0, 100.0, 5.0, 5.0]]), backend="numpy")
    w1, w2 = 1.0, (1 - 0.25) * 1.0  # (1 - u^2)(1 - v^2) at offsets 0 and 2 of half-axis 4
    assert v[0] == pytest.approx([(w1 * 1 + w2 * 3) / (w1 + w2), 0.0])
    assert defined.tolist() == [True, False] and v[1].tolist() == [0.0, 0.0]


@pytest.mark.skipif(not NUMBA_INSTALLED, reason="numba not installed")
def test_motion_kernels_match_reference(rng):
    flow = FlowField(rng.uniform(0, 100, 200), rng.uniform(0, 80, 200), rng.normal(0, 2, 200), rng.normal(0, 2, 200))
    ell = np.column_stack([rng.uniform(0, 100, 60), rng.uniform(0, 80, 60), rng.uniform(2, 30, 60),
                           rng.uniform(2, 30, 60)])
    a, da = local_motion(flow, ell, backend="numba")
    b, db = local_motion(flow, ell, backend="numpy")
    assert np.array_equal(da, db) and np.allclose(a, b, atol=1e-12)
    for ref in ([1.5, -0.5], [0.0, 0.0]):
        la = motion_log_likelihood(flow, ell, ref, backend="numba")
        lb = motion_log_likelihood(flow, ell, ref, backend="numpy")
        assert np.allclose(la, lb, atol=1e-12)


def test_reference_does_not_adapt_when_motions_disagree():
    cue = LocalMotionCue()
    ref = np.array([3.0, 0.0])
    # the tracker moves right, but the observed local motion goes left (an occluder): almost no change
    new = cue.adapt(ref, v_est=np.array([3.0, 0.0]), v_obs=np.array([-3.0, 0.5]))
    assert np.linalg.norm(new - ref) < 0.1
    # agreement: the reference follows the observation
    new = cue.adapt(ref, v_est=np.array([2.0, 1.0]), v_obs=np.array([2.0, 1.0]))
    assert new == pytest.approx([2.0, 1.0], abs=1e-6)


def run(name, spec, seed=0, **params):
    scene, frames, _ = render_scene(spec)
    gt = scene.groundtruth(0)
    tr = pftrack.create_tracker(name, seed=seed, **params)
    states = [tr.init(frames[0], gt[0])] + [tr.update(f) for f in frames[1:]]
    return gt, states, tr


def test_local_motion_pf_tracks_and_learns_the_reference_motion():
    gt, states, tr = run("local-motion-pf", simple_scene(2), seed=1)
    err = np.hypot(*(np.array([s.box for s in states])[:, :2] + np.array([s.box for s in states])[:, 2:] / 2
                     - gt[:, :2] - gt[:, 2:] / 2).T)
    assert err.mean() < 3.5  # measured 3.05 px once sprites were drawn without a dark outline (bound was 3.0)
    assert tr.v_ref is not None and np.all(np.isfinite(tr.v_ref))
    assert states[-1].particles.shape == (50, 6)


def test_motion_false_is_the_colour_reference_tracker():
    _, states, tr = run("local-motion-pf", simple_scene(2, n_frames=20), seed=1, motion=False)
    assert tr.v_ref is None and tr._prev_gray is None  # no flow is ever computed
    assert tr.state_names == ("x", "y", "vx", "vy", "hx", "hy")


def test_local_motion_halves_failures_on_identical_crossings():
    fails = {True: 0, False: 0}
    for seed in range(8):
        scene, frames, _ = render_scene(crossing_scene(seed))
        gt = scene.groundtruth(0)
        for motion in (True, False):
            tr = pftrack.create_tracker("local-motion-pf", seed=seed, motion=motion, sigma_xy=3.0)
            fails[motion] += run_vot(tr, frames, gt).failures
    assert fails[False] >= 3  # the scenes do fool the colour tracker
    assert fails[True] <= 0.5 * fails[False], fails


@pytest.mark.parametrize("pitch", [1, 3])
def test_lattice_eigenvalues_match_the_map(rng, pitch):
    from pftrack._numba import set_numba_enabled
    from pftrack.cues.motion import lattice_min_eigenvalues

    g = textured(rng)
    full = min_eigenvalue_reference(g)
    for flag in ([True, False] if NUMBA_INSTALLED else [False]):
        prev = set_numba_enabled(flag)
        try:
            xs, ys, lam = lattice_min_eigenvalues(g, (0, 5, 150, 100), pitch)
        finally:
            set_numba_enabled(prev)
        assert xs.min() >= 2 and ys.min() >= 5 and np.all(xs % pitch == 0) and np.all(ys % pitch == 0)
        assert np.allclose(lam, full[ys, xs], rtol=1e-4, atol=1e-9)


@pytest.mark.parametrize("motion", [True, False])
def test_local_motion_pf_searches_with_its_own_dynamics(motion):
    """search=true gives local-motion-pf color-pf's loss test and search; the search spreads the samples it keeps
    by the tracker's own one-step noise (Eq. 10), not color-pf's dynamics parameters, which it does not have."""
    from pftrack.synth import Scene, vanish_scene

    spec = vanish_scene(1, n_frames=70)
    pairs = [(f, tr.boxes[0]) for f, tr in Scene(spec)]
    t = pftrack.create_tracker("local-motion-pf", seed=0, search=True, motion=motion)
    assert t._position_step_std(20.0, 30.0) == 0.5 * t.params.sigma_xy
    t.init(pairs[0][0], pairs[0][1])
    lost = [t.update(f).lost for f, _ in pairs[1:]]
    assert any(lost)  # the target walked behind the occluder: the flag went up and the search ran
    c = pftrack.create_tracker("color-pf")
    assert c._position_step_std(20.0, 30.0) == max(c.params.position_noise * 25.0, c.params.min_noise_px)
