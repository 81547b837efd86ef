import numpy as np
import pytest

from pftrack.filtering import (RESAMPLERS, ConstantVelocityScale, KalmanFilter, NCVRandomWalk, ParticleSet,
                               effective_sample_size, log_normalize)


@pytest.mark.parametrize("name", sorted(RESAMPLERS))
def test_resampler_is_unbiased(name):
    """The mean number of copies of each particle is proportional to its weight."""
    rng = np.random.default_rng(7)
    w = rng.random(20) ** 3
    w /= w.sum()
    n = w.size
    draws = 4000
    counts = np.zeros(n)
    for _ in range(draws):
        idx = RESAMPLERS[name](w, rng)
        assert idx.shape == (n,)
        assert idx.min() >= 0 and idx.max() < n
        counts += np.bincount(idx, minlength=n)
    mean_copies = counts / draws
    # standard error of a multinomial count is sqrt(N w (1-w) / draws) <= 0.04
    assert np.allclose(mean_copies, n * w, atol=0.12)


@pytest.mark.parametrize("name", sorted(RESAMPLERS))
def test_resampler_degenerate_weights(name):
    rng = np.random.default_rng(0)
    w = np.zeros(10)
    w[3] = 1.0
    assert (RESAMPLERS[name](w, rng) == 3).all()


@pytest.mark.parametrize("name", sorted(RESAMPLERS))
def test_resampler_uses_injected_rng(name):
    w = np.random.default_rng(1).random(50)
    w /= w.sum()
    a = RESAMPLERS[name](w, np.random.default_rng(5))
    b = RESAMPLERS[name](w, np.random.default_rng(5))
    assert (a == b).all()


def test_multinomial_binary_search_matches_paper():
    """Fig. 2 step 1: smallest j with c'(j) >= r."""
    from pftrack.filtering.resampling import _cumulative, _search

    c = _cumulative(np.array([0.1, 0.2, 0.3, 0.4]))
    assert _search(c, np.array([0.0, 0.1, 0.1000001, 0.3, 0.6, 0.99, 1.0])).tolist() == [0, 0, 1, 1, 2, 3, 3]


def test_compiled_multinomial_draws_the_indices_of_the_numpy_path():
    """The compiled multinomial resampler: the indices and the generator's state of the cumulative sums and the
    binary search, for weights with runs of zeros, unnormalised and near-degenerate ones; bad weights still raise."""
    from pftrack._numba import numba_enabled
    from pftrack.filtering import resampling

    if not numba_enabled():
        pytest.skip("Numba is off: the NumPy path is the only one")
    rng = np.random.default_rng(0)
    for trial in range(300):
        n = int(rng.integers(1, 300))
        w = rng.random(n) ** rng.uniform(0.5, 20.0)
        if trial % 3 == 0:
            w[rng.integers(0, n, n // 2)] = 0.0
        w[0] += 1e-300
        a_rng, b_rng = np.random.default_rng(trial), np.random.default_rng(trial)
        a = resampling.multinomial(w, a_rng)
        c = resampling._cumulative(w)
        b = resampling._search(c, b_rng.random(c.size))
        assert np.array_equal(a, b) and a.dtype == b.dtype
        assert a_rng.random() == b_rng.random()
    for bad in (np.zeros(4), np.array([1.0, np.nan]), np.array([np.inf, 1.0])):
        with pytest.raises(ValueError):
            resampling.multinomial(bad, rng)


def test_weighted_choice_draws_what_numpy_choice_draws():
    """The search's second layer draws with ``weighted_choice`` instead of ``Generator.choice(p=...)``: the same
    indices and the same generator state afterwards, on weights with zeros, a single mass and ties."""
    from pftrack.filtering.resampling import weighted_choice

    g = np.random.default_rng(3)
    cases = [np.array([1.0]), np.array([0.0, 1.0, 0.0]), np.full(7, 1.0 / 7)]
    for _ in range(200):
        r = g.normal(0.0, 5.0, int(g.integers(1, 400)))
        r[g.random(r.size) < 0.3] = -np.inf
        r[0] = 0.0
        w = np.exp(r - r.max())
        cases.append(w / w.sum())
    for i, p in enumerate(cases):
        m = 1 + i % 150
        a, b = np.random.default_rng(i), np.random.default_rng(i)
        want = a.choice(p.size, size=m, p=p)
        got = weighted_choice(p, m, b)
        assert got.dtype == want.dtype and np.array_equal(got, want)
        assert a.random() == b.random()


def test_log_normalize_extremes():
    lw, ok = log_normalize(np.array([-1e300, -1e300 + 1, -np.inf]))
    assert ok and np.isclose(np.exp(lw).sum(), 1.0) and np.all(np.isfinite(lw[:2]))
    lw, ok = log_normalize(np.array([-np.inf, -np.inf]))
    assert not ok and np.allclose(np.exp(lw), 0.5)
    lw, ok = log_normalize(np.array([np.nan, 0.0]))
    assert ok and np.allclose(np.exp(lw), [0.0, 1.0])


def test_particle_set_mean_and_ess():
    s = np.array([[0.0, 0.0], [10.0, 2.0]])
    ps = ParticleSet(s, np.log([0.25, 0.75]))
    assert ps.mean() == pytest.approx([7.5, 1.5])
    assert ps.ess() == pytest.approx(1 / (0.25 ** 2 + 0.75 ** 2))
    assert effective_sample_size(np.full(4, 0.25)) == pytest.approx(4.0)
    ps.resample(np.array([1, 1]))
    assert ps.states.tolist() == [[10.0, 2.0], [10.0, 2.0]]
    assert np.allclose(ps.weights, 0.5)


def test_constant_velocity_scale_transition():
    dyn = ConstantVelocityScale(max_scale_rate=0.5)
    s = np.array([[10.0, 20.0, 1.0, -2.0, 5.0, 8.0, 0.1]])
    dyn.transition(s)
    assert s[0].tolist() == pytest.approx([11.0, 18.0, 1.0, -2.0, 5.5, 8.8, 0.1])
    rng = np.random.default_rng(0)
    many = np.tile([0.0, 0, 0, 0, 10, 10, 0], (20000, 1))
    dyn.propagate(many, np.array([2.0, 2, 0.5, 0.5, 0, 0, 0]), rng)
    assert many[:, 0].std() == pytest.approx(2.0, rel=0.05)
    assert many[:, 2].std() == pytest.approx(0.5, rel=0.05)


def test_ncv_random_walk_size_bound():
    dyn = NCVRandomWalk(sigma_xy=1.0, max_size_change=0.15)
    rng = np.random.default_rng(0)
    s = np.tile([0.0, 0, 0, 0, 10, 20], (10000, 1))
    dyn.propagate(s, rng)
    assert np.all(np.abs(s[:, 4] / 10 - 1) <= 0.15 + 1e-12)
    assert np.all(np.abs(s[:, 5] / 20 - 1) <= 0.15 + 1e-12)
    # position moves by w/2 and velocity by w (same acceleration sample)
    assert np.allclose(s[:, 0], 0.5 * s[:, 2])


def test_kalman_tracks_constant_velocity():
    kf = KalmanFilter.constant_velocity_2d((0, 0), process_std=0.1, measurement_std=1.0)
    rng = np.random.default_rng(0)
    for t in range(1, 60):
        kf.predict()
        kf.update(np.array([2.0 * t, -1.0 * t]) + rng.normal(0, 1.0, 2))
    assert kf.x[2:] == pytest.approx([2.0, -1.0], abs=0.2)


@pytest.mark.parametrize("width", [0.0, 320.0])
def test_propagate_kernel_matches_reference(width):
    from pftrack._numba import NUMBA_INSTALLED, set_numba_enabled
    from pftrack.filtering.kernels import propagate_cv_scale

    if not NUMBA_INSTALLED:
        pytest.skip("numba not installed")
    rng = np.random.default_rng(3)
    base = np.column_stack([rng.uniform(-50, 400, 200), rng.uniform(-50, 300, 200), rng.normal(0, 3, (200, 2)),
                            rng.uniform(0.5, 60, (200, 2)), rng.normal(0, 0.2, 200)])
    noise = rng.standard_normal(base.shape)
    std = np.array([3.0, 3, 1, 1, 0.5, 0.5, 0.01])
    out = {}
    for flag in (True, False):
        prev = set_numba_enabled(flag)
        try:
            s = base.copy()
            roi = propagate_cv_scale(s, noise, std, damping=0.5, min_half_axis=2.0, max_half_axis=50.0,
                                     max_scale_rate=0.05, width=width, height=240.0)
            out[flag] = (s, roi)
        finally:
            set_numba_enabled(prev)
    assert np.allclose(out[True][0], out[False][0], rtol=0, atol=1e-12)
    assert np.allclose(out[True][1], out[False][1], rtol=0, atol=1e-12)
    s = out[True][0]
    assert s[:, 4:6].min() >= 2.0 and s[:, 4:6].max() <= 50.0 and np.abs(s[:, 6]).max() <= 0.05


def test_normalize_kernel_matches_reference():
    from pftrack._numba import NUMBA_INSTALLED, set_numba_enabled
    from pftrack.filtering.kernels import normalize_and_estimate

    if not NUMBA_INSTALLED:
        pytest.skip("numba not installed")
    rng = np.random.default_rng(4)
    states = rng.normal(0, 10, (50, 7))
    for ll in (rng.normal(-20, 5, 50), np.full(50, -np.inf), np.r_[np.full(49, -np.inf), -3.0],
               np.r_[np.nan, rng.normal(0, 1, 49)]):
        res = {}
        for flag in (True, False):
            prev = set_numba_enabled(flag)
            try:
                lw, w, m = np.empty(50), np.empty(50), np.empty(7)
                ok, ess = normalize_and_estimate(ll, states, lw, w, m)
                res[flag] = (ok, ess, lw, w, m)
            finally:
                set_numba_enabled(prev)
        a, b = res[True], res[False]
        assert a[0] == b[0] and a[1] == pytest.approx(b[1], rel=1e-12)
        assert np.allclose(a[3], b[3], atol=1e-15) and np.allclose(a[4], b[4], atol=1e-12)
        assert np.isclose(a[3].sum(), 1.0) and np.all(np.isfinite(a[3]))


def test_reappearance_log_prior_is_the_mixture_relative_to_uniform():
    from pftrack.filtering.dynamics import reappearance_log_prior

    pos = np.array([[50.0, 40.0], [53.0, 44.0], [300.0, 200.0]])
    area, sd, eps = 320.0 * 240.0, 5.0, 0.05
    raw = reappearance_log_prior(pos, (50.0, 40.0), sd, area, eps, cap=False)
    d2 = np.array([0.0, 25.0, 250.0 ** 2 + 160.0 ** 2]) / sd ** 2
    ref = np.log((1 - eps) * area * np.exp(-0.5 * d2) / (2 * np.pi * sd ** 2) + eps)
    np.testing.assert_allclose(raw, ref)
    assert raw[0] > 0 > raw[2] and raw[2] == pytest.approx(np.log(eps))  # far away: only the uniform part
    capped = reappearance_log_prior(pos, (50.0, 40.0), sd, area, eps)
    np.testing.assert_allclose(capped, np.minimum(raw, 0.0))
    # eps = 1: no preference anywhere
    np.testing.assert_allclose(reappearance_log_prior(pos, (50.0, 40.0), sd, area, 1.0, cap=False), 0.0, atol=1e-12)


def test_wide_proposal_widens_the_position_steps_of_a_random_share_only():
    from pftrack.filtering.dynamics import widen_position_noise

    noise = np.random.default_rng(1).standard_normal((20000, 7))
    before = noise.copy()
    widen_position_noise(noise, np.random.default_rng(2), 0.2, 3.0)
    changed = np.any(noise != before, axis=1)
    assert 0.18 < changed.mean() < 0.22  # about the share asked for, drawn at random
    np.testing.assert_array_equal(noise[changed][:, :2], 3.0 * before[changed][:, :2])  # x and y only, times 3
    np.testing.assert_array_equal(noise[:, 2:], before[:, 2:])
    np.testing.assert_array_equal(noise[~changed], before[~changed])
    # a step of 3.5 noise spreads: about 0.05 % of Gaussian steps reach it, a fifth of 24 % with the wide share
    far = np.abs(noise[:, 0]) > 3.5
    assert 0.03 < far.mean() < 0.06 and (np.abs(before[:, 0]) > 3.5).mean() < 0.002


def test_two_model_proposal_scales_a_random_share_of_the_steps_by_the_second_models_noise():
    from pftrack.filtering.dynamics import mix_noise

    noise = np.random.default_rng(1).standard_normal((20000, 7))
    before = noise.copy()
    factors = np.array([2 / 3, 2 / 3, 4.0, 4.0, 1.0, 1.0, 1.0])
    mix_noise(noise, np.random.default_rng(2), 0.3, factors)
    changed = np.any(noise != before, axis=1)
    assert 0.28 < changed.mean() < 0.32  # about the share asked for, drawn at random
    np.testing.assert_allclose(noise[changed], before[changed] * factors)  # every component by its own factor
    np.testing.assert_array_equal(noise[~changed], before[~changed])
    # the velocity steps' spread: sqrt(0.7 + 0.3 * 16) = 2.35 standard deviations of the first model
    assert 2.25 < noise[:, 2].std() < 2.45 and 0.9 < noise[:, 4].std() < 1.1


def test_two_model_proposal_off_draws_as_before_and_follows_a_turn_on():
    """Off, the same random stream gives the same samples. On, some samples' velocities follow a target that
    turned: after a reversal of 3 px a frame, more of the set moves the new way than with the first model alone."""
    states = np.zeros((2000, 7))
    states[:, 2] = 3.0  # moving right at 3 px a frame
    states[:, 4:6] = 10.0
    std = np.array([2.0, 2.0, 0.25, 0.25, 0.0, 0.0, 0.0])  # a slow velocity noise, as fusion-pf's
    plain, off, on = states.copy(), states.copy(), states.copy()
    ConstantVelocityScale().propagate(plain, std, np.random.default_rng(5))
    ConstantVelocityScale(mix_fraction=0.0, mix_factors=np.full(7, 4.0)).propagate(off, std, np.random.default_rng(5))
    np.testing.assert_array_equal(plain, off)
    factors = np.array([1.0, 1.0, 8.0, 8.0, 1.0, 1.0, 1.0])
    ConstantVelocityScale(mix_fraction=0.3, mix_factors=factors).propagate(on, std, np.random.default_rng(5))
    turned_plain = (plain[:, 2] < 0).mean()
    turned_on = (on[:, 2] < 0).mean()
    # velocity noise 0.25 cannot reverse 3 px a frame in one step; 2.0 does so for one sample in 15 (P(z < -1.5)),
    # so about 0.3 / 15 = 2 % of the set
    assert turned_plain < 0.001 and 0.012 < turned_on < 0.03


def test_color_pf_params_give_the_second_models_noise_over_the_first():
    import pftrack

    t = pftrack.create_tracker("fusion-pf", mix_fraction=0.3)  # fusion-pf's (0.3, 0.025) and the second (0.2, 0.1)
    np.testing.assert_allclose(t.dynamics.mix_factors, [2 / 3, 2 / 3, 4.0, 4.0, 1.0, 1.0, 1.0])
    assert pftrack.create_tracker("fusion-pf").dynamics.mix_factors is None


def test_wide_proposal_off_draws_as_before_and_on_spreads_the_set():
    states = np.zeros((400, 7))
    states[:, 4:6] = 10.0
    std = np.array([2.0, 2.0, 0.1, 0.1, 0.0, 0.0, 0.0])
    plain, off, on = states.copy(), states.copy(), states.copy()
    ConstantVelocityScale().propagate(plain, std, np.random.default_rng(5))
    ConstantVelocityScale(wide_fraction=0.0, wide_factor=3.0).propagate(off, std, np.random.default_rng(5))
    np.testing.assert_array_equal(plain, off)  # off: the same random stream, the same samples
    region = ConstantVelocityScale(wide_fraction=0.25, wide_factor=4.0).propagate(on, std, np.random.default_rng(5))
    assert np.abs(on[:, 0]).max() > 2 * np.abs(plain[:, 0]).max()
    assert region[0] <= on[:, 0].min() - 10.0 + 1e-9  # the quantised region reaches the wide samples' ellipses


def test_velocity_step_off_draws_as_before_and_on_keeps_the_step():
    """Off, the same samples as Eq. 9. At 1 each velocity is the sample's whole displacement (the second-order
    autoregressive model); at 0.25 a quarter of the way from Eq. 9's velocity to it. So after a step, a sample's
    velocity and its position noise are correlated: those that the noise moved right move right faster."""
    from pftrack.filtering.dynamics import step_velocity

    states = np.zeros((3000, 7))
    states[:, 2] = 3.0
    states[:, 4:6] = 10.0
    std = np.array([2.0, 2.0, 0.25, 0.25, 0.0, 0.0, 0.0])
    plain, off, full, part = states.copy(), states.copy(), states.copy(), states.copy()
    ConstantVelocityScale().propagate(plain, std, np.random.default_rng(5))
    ConstantVelocityScale(velocity_step=0.0).propagate(off, std, np.random.default_rng(5))
    np.testing.assert_array_equal(plain, off)
    ConstantVelocityScale(velocity_step=1.0).propagate(full, std, np.random.default_rng(5))
    ConstantVelocityScale(velocity_step=0.25).propagate(part, std, np.random.default_rng(5))
    np.testing.assert_array_equal(full[:, :2], plain[:, :2])  # the positions move as before
    np.testing.assert_allclose(full[:, 2:4], plain[:, :2] - states[:, :2])
    np.testing.assert_allclose(part[:, 2:4], 0.75 * plain[:, 2:4] + 0.25 * (plain[:, :2] - states[:, :2]))
    assert np.corrcoef(full[:, 0], full[:, 2])[0, 1] > 0.99
    assert abs(np.corrcoef(plain[:, 0], plain[:, 2])[0, 1]) < 0.1
    one = np.array([[5.0, 7.0, 1.0, -1.0, 3.0, 3.0, 0.0]])
    step_velocity(one, np.array([[2.0, 9.0]]), 0.5)
    np.testing.assert_allclose(one[0, 2:4], [0.5 * 1.0 + 0.5 * 3.0, 0.5 * -1.0 + 0.5 * -2.0])


def test_velocity_step_reaches_the_trackers_dynamics():
    import pftrack

    assert pftrack.create_tracker("fusion-pf", velocity_step=0.25).dynamics.velocity_step == 0.25
    assert pftrack.create_tracker("color-pf").dynamics.velocity_step == 0.0
