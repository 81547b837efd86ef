"""Book ch. 3 §4.2: SEIR evolutionary resampling (ch03.md §5, test 6)."""

import numpy as np
import pytest

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


@pytest.mark.parametrize("name", ["color-pf", "fusion-pf", "local-motion-pf"])
def test_any_colour_particle_filter_takes_resampler_seir(name):
    """``resampler="seir"`` runs the loop inside the colour PFs: ESS per loop reported, reproducible with a
    seed, and the target followed on a simple synthetic scene."""
    import pftrack
    from pftrack.geometry import center_error
    from pftrack.synth import Scene, simple_scene

    scene = Scene(simple_scene(3, n_frames=30))
    frames, gt = scene.frames(), scene.groundtruth(0)

    def run(seed):
        t = pftrack.create_tracker(name, seed=seed, resampler="seir", n_particles=60)
        t.init(frames[0], tuple(gt[0]))
        return [t.update(f) for f in frames[1:]]

    a, b = run(1), run(1)
    assert [s.box for s in a] == [s.box for s in b]
    assert all(len(s.info["ess"]) == s.info["loops"] + 1 for s in a if "ess" in s.info)
    assert any(s.info.get("loops", 0) > 0 for s in a)
    err = center_error(np.array([s.box for s in a]), gt[1:])
    assert np.median(err) < 3.0
