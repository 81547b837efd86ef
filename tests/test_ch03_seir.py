"""Book ch. 3 §4.2: SEIR evolutionary resampling (ch03.md §5, test 6)."""

import numpy as np

from pftrack.filtering.particles import effective_sample_size, weights_from_log
from pftrack.filtering.seir import seir


def _ll(x):
    return -0.5 * np.sum((x - 50.0) ** 2, axis=1) / 4.0  # N(x; (50, 50), 2^2 I)


def test_seir_reaches_the_target_ess_on_the_toy_problem():
    reached, err_sir, err_seir = [], [], []
    for seed in range(200):
        rng = np.random.default_rng(seed)
        x = rng.normal(40.0, 5.0, (300, 2))
        ll = _ll(x)
        w = weights_from_log(ll)
        assert effective_sample_size(w) < 0.1 * 300  # a degenerate weight set
        xs, lls, info = seir(x, ll, _ll, rng, mutation_std=2.5)
        assert info.loops <= 10 and len(info.ess) == info.loops + 1
        reached.append(info.ess[-1] >= 240)
        ws = weights_from_log(lls)
        err_sir.append(np.hypot(*((w[:, None] * x).sum(0) - 50)))
        err_seir.append(np.hypot(*((ws[:, None] * xs).sum(0) - 50)))
    assert np.mean(reached) >= 0.95
    assert np.median(err_seir) < np.median(err_sir)


def test_seir_is_reproducible_and_stops_when_the_ess_is_high():
    x = np.random.default_rng(0).normal(40.0, 5.0, (100, 2))
    a = seir(x, _ll(x), _ll, np.random.default_rng(7), mutation_std=2.0)
    b = seir(x, _ll(x), _ll, np.random.default_rng(7), mutation_std=2.0)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    flat = np.zeros(100)  # equal weights: ESS = N, no loop
    xs, _lls, info = seir(x, flat, _ll, np.random.default_rng(1))
    assert info.loops == 0 and len(info.ess) == 1 and abs(info.ess[0] - 100.0) < 1e-9
    np.testing.assert_array_equal(xs, x)
    _, _, capped = seir(x, _ll(x), _ll, np.random.default_rng(2), n_target=101, max_loops=3)
    assert capped.loops == 3  # an unreachable target stops at T_max
