"""The nonlinear steps' error control through Python (issue 21): the report, the tolerance and
the call budget, refusals that leave the filter unchanged, and a sampled update against an
importance-sampling reference computed here with NumPy."""

import numpy as np
import pytest

import bingham as bh


def orthogonal(rng, d):
    q, r = np.linalg.qr(rng.standard_normal((d, d)))
    return q * np.sign(np.diag(r))


RNG = np.random.default_rng(2121)
M4 = orthogonal(RNG, 4)
Z4 = np.array([-30.0, -12.0, -5.0, 0.0])
MW4 = np.eye(4)[:, [1, 2, 3, 0]]  # the mode (last column) is the identity quaternion
ZW4 = np.array([-500.0, -500.0, -500.0, 0.0])
A = np.eye(4) + 0.3 * RNG.standard_normal((4, 4))
C = RNG.standard_normal(4)
C /= np.linalg.norm(C)


def log_l(x):
    y = A @ x
    return 20.0 * (C @ y / np.linalg.norm(y)) ** 2


def test_defaults_are_the_documented_ones():
    assert bh.PREDICT_TOLERANCE == 5e-4 and bh.UPDATE_TOLERANCE == 2.5e-3


def test_a_rotation_costs_only_the_deterministic_points():
    u = np.array([np.cos(0.1), np.sin(0.1), 0.0, 0.0])
    with bh.Filter(M4, Z4) as f, bh.Filter(M4, Z4) as g:
        rep = f.predict_nonlinear(lambda x: bh.quat_multiply(x, u), MW4, ZW4)
        g.predict_rotation(u, MW4, ZW4)
        assert rep.method == "deterministic" and rep.calls == 19 and rep.samples == 0
        assert rep.error_estimate < 1e-12
        np.testing.assert_allclose(f.state()[1], g.state()[1], rtol=1e-9)


def test_a_nonlinear_prediction_is_sampled_to_the_tolerance():
    def a(x):
        y = A @ x
        return y / np.linalg.norm(y)

    with bh.Filter(M4, Z4) as f:
        rep = f.predict_nonlinear(a, MW4, ZW4, tolerance=1e-3)
        assert rep.method == "sampled" and rep.error_estimate <= 1e-3
        assert rep.calls > 19 and rep.samples >= 128 and 0 < rep.effective_share <= 1


def test_the_update_reports_and_meets_an_importance_sampling_reference():
    with bh.Filter(M4, Z4) as f:
        rep = f.update_nonlinear(log_l)
        assert rep.method == "sampled" and rep.error_estimate <= bh.UPDATE_TOLERANCE
        assert rep.mode_error_estimate <= 0.05 and rep.calls >= rep.samples
        got = bh.second_moment(*f.state())
    # The reference: 2·10⁵ prior samples weighted by the likelihood (vectorized log_l).
    xs = bh.sample(M4, Z4, 200_000, seed=11)
    ys = xs @ A.T
    lw = 20.0 * ((ys @ C) / np.linalg.norm(ys, axis=1)) ** 2
    w = np.exp(lw - lw.max())
    w /= w.sum()
    ref = (xs * w[:, None]).T @ xs
    se = np.sqrt(((np.einsum("ni,nj->nij", xs, xs) - ref) ** 2 * (w**2)[:, None, None]).sum(0))
    assert np.all(np.abs(got - ref) <= np.maximum(0.01, 3 * se)), (got - ref, se)


def test_a_small_budget_is_refused_and_changes_nothing():
    with bh.Filter(M4, Z4) as f:
        before = f.state()
        with pytest.raises(bh.BinghamError) as e:
            f.update_nonlinear(log_l, max_calls=100)
        assert e.value.status == bh.Status.ERR_NOT_CONVERGED
        assert "budget (100 calls" in e.value.message
        after = f.state()
        np.testing.assert_array_equal(after[0], before[0])
        np.testing.assert_array_equal(after[1], before[1])


@pytest.mark.parametrize("kw", [{"tolerance": -1.0}, {"tolerance": float("nan")}, {"mode_tolerance": 0.0}, {"max_calls": 0}])
def test_bad_options_are_refused_before_any_call(kw):
    calls = []

    def counted(x):
        calls.append(1)
        return log_l(x)

    with bh.Filter(M4, Z4) as f:
        with pytest.raises(bh.BinghamError) as e:
            f.update_nonlinear(counted, **kw)
        assert e.value.status == bh.Status.ERR_INVALID_ARGUMENT
        assert not calls
