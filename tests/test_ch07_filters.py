"""Book ch. 7 §1.2 and §1.4: RLS AR(p) predictors and the fuzzy gain controller (ch07.md §5.1)."""

import numpy as np
import pytest

from pftrack.filtering.fuzzy import FuzzyGain
from pftrack.filtering.rls import RLSAR, JointRLSAR, regressors, rls_batch, stabilise


def _ar2(n=120, seed=0):
    rng = np.random.default_rng(seed)
    x = np.zeros(n)
    x[:2] = rng.normal(size=2)
    for k in range(2, n):
        x[k] = 1.6 * x[k - 1] - 0.8 * x[k - 2] + 0.1 * rng.normal()
    return x


def test_regressors_rows():
    c, t = regressors(np.arange(5.0), 2)
    np.testing.assert_array_equal(c, [[1, 0], [2, 1], [3, 2]])
    np.testing.assert_array_equal(t, [2, 3, 4])
    c, t = regressors(np.array([[1.0, 10], [2, 20], [3, 30]]), 2)  # interleaved channels (Eq. 27)
    np.testing.assert_array_equal(c, [[2, 20, 1, 10]])
    np.testing.assert_array_equal(t, [[3, 30]])


def test_rls_recursion_equals_batch_solution():
    x = _ar2()
    f = RLSAR(1, ridge=0.0, forgetting=0.99)
    for n, v in enumerate(x):
        f.push([v])
        if n >= 6:
            ref = rls_batch(x[:n + 1], forgetting=0.99)
            np.testing.assert_allclose(f.coef[0], ref, rtol=1e-8)
    np.testing.assert_allclose(f.coef[0], [1.6, -0.8], atol=0.15)  # the generating model


def test_exact_ar2_signal_is_predicted_exactly():
    w = 2 * np.pi / 40
    s = 3 * np.sin(w * np.arange(120))
    f = RLSAR(1, ridge=1e-9)
    worst = 0.0
    for v in s:
        if f.ready:
            worst = max(worst, abs(f.predict()[0] - v))
        f.push([v])
    assert worst < 1e-5
    np.testing.assert_allclose(f.coef[0], [2 * np.cos(w), -1.0], atol=1e-4)


@pytest.mark.parametrize("prior,ridge", [("zero", 1e-6), ("mean", 10.0), ("hold", 1.0)])
def test_constant_velocity_is_not_singular(prior, ridge):
    f = RLSAR(3, ridge=ridge, prior=prior)
    for _ in range(20):
        f.push([3.0, -1.5, 0.0])
    np.testing.assert_allclose(f.predict(), [3.0, -1.5, 0.0], atol=1e-6)


def test_prediction_uses_the_previous_coefficients():
    x = _ar2(40, seed=3)
    f = RLSAR(1, ridge=0.0)
    for v in x[:30]:
        f.push([v])
    expected = f.coef[0] @ [x[29], x[28]]  # c_{N+1}^T a_N, not a_{N+1}
    assert f.predict()[0] == pytest.approx(expected)


def test_sliding_window_refit():
    x = _ar2(60, seed=1)
    f = RLSAR(1, ridge=0.0, window=10)
    for v in x:
        f.push([v])
    np.testing.assert_allclose(f.coef[0], rls_batch(x[-10:], forgetting=0.99), rtol=1e-8)


def test_joint_rls_equals_two_batch_fits_on_the_shared_regressor():
    rng = np.random.default_rng(2)
    xs = np.cumsum(rng.normal(size=(60, 2)), 0) * 0.1 + rng.normal(size=(60, 2))
    j = JointRLSAR(2, ridge=0.0)
    for n, v in enumerate(xs):
        j.push(v)
        if n >= 6:
            ref = rls_batch(xs[:n + 1])
            np.testing.assert_allclose(j.coef, ref, rtol=1e-8, atol=1e-10)
            for ch in range(2):  # each column is its own weighted least-squares fit (Eq. 28)
                np.testing.assert_allclose(ref[:, ch], rls_batch(xs[:n + 1], ridge=0.0)[:, ch])


def test_joint_rls_with_identical_channels_does_not_raise():
    j = JointRLSAR(2)
    for _ in range(15):
        j.push([2.0, 2.0])
    np.testing.assert_allclose(j.predict(), [2.0, 2.0], atol=1e-5)


def test_stabilise_pulls_roots_into_the_unit_circle():
    bad = np.array([[-1.0, 2.0], [2.5, -1.2], [0.5, 0.5]])  # roots 1 & -2; complex |r| > 1; stable
    st = stabilise(bad)
    for row in st:
        assert np.all(np.abs(np.roots([1.0, -row[0], -row[1]])) <= 1 + 1e-9)
    np.testing.assert_array_equal(st[2], bad[2])
    st3 = stabilise(np.array([[0.0, 0.0, 1.5]]))  # p = 3 through the root path
    assert np.all(np.abs(np.roots(np.concatenate([[1.0], -st3[0]]))) <= 1 + 1e-9)


# ch07.md §1.4 worked values
WORKED = [((0.0, 1), 1.0), ((0.4, 1), 0.75), ((0.3, 1), 0.8409), ((1.0, 1), 0.5), ((-1.0, 0), 1.0),
          ((0.0, 0), 0.5), ((-0.3, 0), 0.6591), ((-0.4, 0), 0.75)]


@pytest.mark.parametrize("arg,k", WORKED)
def test_fuzzy_controller_worked_values(arg, k):
    assert float(FuzzyGain().from_normalised(*arg)) == pytest.approx(k, abs=1e-4)


def test_fuzzy_controller_range_monotonicity_and_partition():
    f = FuzzyGain()
    e = np.linspace(-3, 3, 601)
    for qv in (0, 1):
        k = f.from_normalised(e, qv)
        assert k.min() >= 0.5 - 1e-12 and k.max() <= 1.0 + 1e-12
    on = (e >= 0) & (e <= 1)
    assert np.all(np.diff(f.from_normalised(e[on], 1)) <= 1e-12)
    # with the filter in use a falling error (exit, NB) raises k: k falls from 1 at e = -1 to 0.5 at e = 0
    # (ch07.md §5.1 says "non-decreasing" here, which its own worked values (-1, 0) -> 1, (0, 0) -> 0.5 contradict)
    neg = (e >= -1) & (e <= 0)
    assert np.all(np.diff(f.from_normalised(e[neg], 0)) <= 1e-12)
    mu = f.memberships(e)
    np.testing.assert_allclose(mu["NB"] + mu["M"] + mu["PB"], 1.0)


def test_fuzzy_normalisation_and_other_defuzzifiers():
    f = FuzzyGain()
    # delta eps of 1.2 px at |v| = 3 px/frame is e = 0.4; the speed floor keeps e finite when stopped
    assert float(f(1.2, 3.0, 1)) == pytest.approx(0.75)
    assert float(f(0.1, 0.0, 1)) == pytest.approx(float(f.from_normalised(0.2, 1)))
    px = FuzzyGain(units="px", breakpoints=(0.5, 1.5))
    assert float(px(1.0, 100.0, 1)) == pytest.approx(0.75)
    for d in ("coa", "mom", "ca"):
        g = FuzzyGain(defuzz=d)
        assert float(g.from_normalised(0.0, 1)) == pytest.approx(1.0, abs=1e-3)
        assert float(g.from_normalised(0.0, 0)) == pytest.approx(0.5, abs=1e-3)
    # centroid of the union by direct integration
    u = np.linspace(0.25, 1.25, 20001)
    agg = np.maximum(np.minimum(np.clip(1 - np.abs(u - 0.5) / 0.25, 0, None), 0.5),
                     np.minimum(np.clip(1 - np.abs(u - 1.0) / 0.25, 0, None), 0.5))
    centroid = (agg * u).sum() / agg.sum()
    assert float(FuzzyGain(defuzz="coa").from_normalised(0.4, 1)) == pytest.approx(centroid, abs=1e-3)
    with pytest.raises(ValueError):
        FuzzyGain(defuzz="bisector")
