"""Nonlinear models through the ctypes binding: deterministic samples, ``Filter.predict_nonlinear``
and ``Filter.update_nonlinear`` with Python callables (issue 12).

References are independent of the points under test: the library's second moment and the
Hessian of log F (``E[y_i² y_j²] = H_ij + ω_i ω_j`` in the principal coordinates), the linear
``predict`` and the exact Bayes product ``multiply``, and a NumPy Monte Carlo simulation with
its own standard error.
"""

import math

import numpy as np
import pytest

import bingham as bh


def random_orthogonal(d, seed):
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(d, d)))
    return q * np.sign(np.diag(r))


def qmul(p, q):
    """Hamilton product, scalar first; p, q of shape (4,) or (n, 4)."""
    p, q = np.asarray(p, dtype=float), np.asarray(q, dtype=float)
    w1, x1, y1, z1 = np.moveaxis(p, -1, 0)
    w2, x2, y2, z2 = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ],
        axis=-1,
    )


def rotmat(q):
    """R(q) (sensor → world) for unit q of shape (4,) or (n, 4): shape (3, 3) or (n, 3, 3)."""
    w, x, y, z = np.moveaxis(np.asarray(q, dtype=float), -1, 0)
    r = np.stack(
        [
            1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
            2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
            2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
        ],
        axis=-1,
    )
    return r.reshape(r.shape[:-1] + (3, 3))


def expq(v):
    """The unit quaternion of rotation vector(s) v (shape (3,) or (n, 3))."""
    v = np.asarray(v, dtype=float)
    a = np.linalg.norm(v, axis=-1, keepdims=True)
    s = np.where(a > 1e-12, np.sin(a / 2) / np.where(a > 0, a, 1.0), 0.5)
    return np.concatenate([np.cos(a / 2), s * v], axis=-1)


# The nonlinear rate law of the Monte Carlo test: the body axis B turns towards the world's up
# axis with a rate that grows with the misalignment (ω is quadratic in q, so a(-q) = -a(q)).
B_AXIS = np.array([1.0, 0.0, 0.0])
UP = np.array([0.0, 0.0, 1.0])
GAIN, DT = 6.0, 0.1


def rate_law(q):
    """One step q' = q ⊗ exp(ω(q) DT), ω(q) = GAIN · B × R(q)ᵀ up (body frame); q: (4,) or (n, 4)."""
    up_body = np.einsum("...ji,j->...i", rotmat(q), UP)
    omega = GAIN * np.cross(B_AXIS, up_body)
    out = qmul(q, expq(omega * DT))
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


def fourth_moment_tensor(y, w):
    return np.einsum("n,na,nb,nc,nd->abcd", w, y, y, y, y)


def fourth_moment_reference(z):
    """E[y_a y_b y_c y_d] of Bingham(I, z) from the Hessian: non-zero only where the indices pair up."""
    _, omega, h = bh.log_normalization_hessian(z)
    e4 = h + np.outer(omega, omega)  # E[y_i² y_j²]
    d = len(z)
    t = np.zeros((d,) * 4)
    for i in range(d):
        for j in range(d):
            t[i, i, j, j] = t[i, j, i, j] = t[i, j, j, i] = e4[i, j]
    return t


DISTRIBUTIONS = [
    (2, [-3.0, 0.0]),
    (2, [-2000.0, 0.0]),
    (3, [-5.0, 0.0, -2.0]),
    (3, [-300.0, -40.0, 0.0]),
    (4, [-1.0, -1.0, -1.0, 0.0]),
    (4, [-200.0, -200.0, -20.0, 0.0]),
    (4, [-50.0, -8.0, 0.0, -20.0]),
    (4, [-1e4, -1e3, -1e2, 0.0]),
]


@pytest.mark.parametrize("d,z", DISTRIBUTIONS)
def test_moments_scheme_reproduces_second_and_fourth_moments(d, z):
    m = random_orthogonal(d, 17 + d)
    z = np.array(z)
    x, w, reproduced = bh.deterministic_samples(m, z, "moments")
    assert reproduced == 4
    assert x.shape == (2 * d * d - 4 * d + 3, d) and w.shape == (x.shape[0],)
    assert np.all(w > 0) and abs(w.sum() - 1.0) < 1e-14
    np.testing.assert_allclose(np.linalg.norm(x, axis=1), 1.0, atol=1e-14)
    mode = m[:, np.argmax(z)]
    assert np.all(x @ mode > 0), "every point in the mode's hemisphere"
    np.testing.assert_allclose((x * w[:, None]).T @ x, bh.second_moment(m, z), rtol=0, atol=1e-12)
    y = x @ m  # principal coordinates y = Mᵀ x, in the order of the input z
    np.testing.assert_allclose(fourth_moment_tensor(y, w), fourth_moment_reference(z), rtol=0, atol=1e-10)


@pytest.mark.parametrize("d,z", DISTRIBUTIONS)
def test_tac2016_reproduces_the_second_moment_only(d, z):
    m = random_orthogonal(d, 5 + d)
    z = np.array(z)
    for lam in (0.0, 0.5, 1.0):
        x, w, reproduced = bh.deterministic_samples(m, z, "tac2016", lam)
        assert reproduced == 2
        assert x.shape == (2 * d - 1, d)
        assert np.all(w >= 0) and abs(w.sum() - 1.0) < 1e-14
        np.testing.assert_allclose(np.linalg.norm(x, axis=1), 1.0, atol=1e-14)
        np.testing.assert_allclose((x * w[:, None]).T @ x, bh.second_moment(m, z), rtol=0, atol=1e-12)
    # ... and not the fourth moments (E[y_i⁴] = ω_i² / w_i): off by far more than rounding
    x, w, _ = bh.deterministic_samples(m, z, "tac2016", 0.5)
    err = np.abs(fourth_moment_tensor(x @ m, w) - fourth_moment_reference(z)).max()
    _, omega = bh.log_normalization_constant(z)
    assert err > 0.1 * np.sort(omega)[-2] ** 2, err
    # the mode (the first point) gets the weight lam · ω_mode
    for lam in (0.0, 0.3, 1.0):
        x, w, _ = bh.deterministic_samples(m, z, "tac2016", lam)
        np.testing.assert_allclose(x[0], m[:, np.argmax(z)] * np.sign(x[0] @ m[:, np.argmax(z)]), atol=1e-15)
        assert abs(w[0] - lam * omega.max()) < 1e-14, (lam, w[0], omega.max())


@pytest.mark.parametrize("z", [[-25.57, -6.78, -0.0169, 0.0], [-2.79e6, -12.5, -0.145, 0.0]])
def test_moments_scheme_falls_back_where_no_positive_set_exists(z):
    m = random_orthogonal(4, 3)
    z = np.array(z)  # a very broad axis next to a moderately sharp one
    x, w, reproduced = bh.deterministic_samples(m, z, "moments", lam=0.9)  # lam is ignored
    assert reproduced == 2 and x.shape == (7, 4)
    xt, wt, _ = bh.deterministic_samples(m, z, "tac2016", 0.5)
    np.testing.assert_array_equal(x, xt)
    np.testing.assert_array_equal(w, wt)
    np.testing.assert_allclose((x * w[:, None]).T @ x, bh.second_moment(m, z), rtol=0, atol=1e-12)


@pytest.mark.parametrize("z", [[-1e4, -400.0, -0.5, 0.0], [-200.0, -200.0, -2.0, 0.0]])
def test_moments_scheme_girdles_reproduce_the_fourth_moments(z):
    m = random_orthogonal(4, 3)
    z = np.array(z)  # two sharp axes, one broad: a "girdle" (three centers on the broad circle)
    x, w, reproduced = bh.deterministic_samples(m, z, "moments")
    assert reproduced == 4 and x.shape == (19, 4) and np.all(w >= 0)
    np.testing.assert_allclose((x * w[:, None]).T @ x, bh.second_moment(m, z), rtol=0, atol=1e-12)
    np.testing.assert_allclose(fourth_moment_tensor(x @ m, w), fourth_moment_reference(z), rtol=0, atol=1e-10)


def test_deterministic_samples_errors():
    m, z = np.eye(4), np.array([-3.0, -2.0, -1.0, 0.0])
    with pytest.raises(ValueError):
        bh.deterministic_samples(m, z, "unscented")
    with pytest.raises(ValueError):
        bh.deterministic_samples(np.eye(3), z)
    for lam in (-0.1, 1.5, math.nan):
        with pytest.raises(bh.BinghamError) as e:
            bh.deterministic_samples(m, z, "tac2016", lam)
        assert e.value.status == bh.Status.ERR_INVALID_ARGUMENT
        assert "lambda" in e.value.message
    with pytest.raises(bh.BinghamError) as e:
        bh.deterministic_samples(np.eye(65), np.zeros(65))
    assert e.value.status == bh.Status.ERR_INVALID_DIMENSION


# ---- the filter -----------------------------------------------------------------------------

M4 = random_orthogonal(4, 42)
Z4 = np.array([-120.0, -60.0, -25.0, 0.0])
MW4, ZW4 = bh.noise_from_angle_std(4, 0.05)
M2 = np.array([[math.cos(0.4), -math.sin(0.4)], [math.sin(0.4), math.cos(0.4)]])
Z2 = np.array([-30.0, 0.0])
MW2, ZW2 = np.array([[0.0, 1.0], [1.0, 0.0]]), np.array([-400.0, 0.0])


def same_distribution(a, b, rtol):
    """(m, z) pairs equal: z relative, principal axes up to sign."""
    (ma, za), (mb, zb) = a, b
    np.testing.assert_allclose(za, zb, rtol=rtol, atol=0)
    np.testing.assert_allclose(np.abs(np.sum(ma * mb, axis=0)), 1.0, atol=1e-9)


@pytest.mark.parametrize("m,z,mw,zw", [(M4, Z4, MW4, ZW4), (M2, Z2, MW2, ZW2)])
def test_identity_predict_nonlinear_equals_predict(m, z, mw, zw):
    calls = []

    def identity(x):
        calls.append(x)
        return x

    with bh.Filter(m, z) as f, bh.Filter(m, z) as g:
        for _ in range(3):
            calls.clear()
            f.predict(mw, zw)
            g.predict_nonlinear(identity, mw, zw)
            same_distribution(g.state(), f.state(), rtol=1e-9)
            d = len(z)
            assert len(calls) == 2 * d * d - 4 * d + 3
            assert all(isinstance(x, np.ndarray) and x.shape == (d,) for x in calls)


def test_predict_nonlinear_with_a_known_rotation_equals_predict_rotation():
    u = expq([0.3, -0.2, 0.5])
    with bh.Filter(M4, Z4) as f, bh.Filter(M4, Z4) as g:
        f.predict_rotation(u, MW4, ZW4)
        g.predict_nonlinear(lambda x: qmul(x, u), MW4, ZW4)
        same_distribution(g.state(), f.state(), rtol=1e-9)
        # sign flips of the callback's output change nothing
        with bh.Filter(M4, Z4) as h:
            flip = iter(range(1000))
            h.predict_nonlinear(lambda x: qmul(x, u) * (-1) ** next(flip), MW4, ZW4)
            same_distribution(h.state(), f.state(), rtol=1e-9)


def failing_calls(d):
    """(name, callable, expected cause type or None) for the transition."""

    def raise_on_third():
        n = iter(range(100))

        def fn(x):
            if next(n) == 2:
                raise ValueError("boom")
            return x

        return fn

    return [
        ("raises", raise_on_third(), ValueError),
        ("nan", lambda x: np.full(d, math.nan), None),
        ("inf", lambda x: np.r_[math.inf, x[1:]], None),
        ("short", lambda x: x[:-1], ValueError),
        ("2-d", lambda x: x.reshape(1, d), ValueError),
        ("not unit", lambda x: 1.01 * x, None),
        ("zero", lambda x: np.zeros(d), None),
        ("not numeric", lambda x: ["a"] * d, ValueError),
        ("None", lambda x: None, ValueError),
    ]


@pytest.mark.parametrize("m,z,mw,zw", [(M4, Z4, MW4, ZW4), (M2, Z2, MW2, ZW2)])
def test_a_failing_transition_leaves_the_filter_unchanged(m, z, mw, zw):
    d = len(z)
    with bh.Filter(m, z) as f:
        f.predict(mw, zw)  # a warm start that must survive too
        before = f.state()
        for name, fn, cause in failing_calls(d):
            with pytest.raises(bh.BinghamError) as e:
                f.predict_nonlinear(fn, mw, zw)
            assert e.value.status == bh.Status.ERR_CALLBACK == 7, name
            assert e.value.message.startswith("bingham_filter_predict_nonlinear"), (name, e.value.message)
            if cause is None:
                assert e.value.__cause__ is None, name
            else:
                assert isinstance(e.value.__cause__, cause), name
            after = f.state()
            np.testing.assert_array_equal(after[0], before[0], err_msg=name)
            np.testing.assert_array_equal(after[1], before[1], err_msg=name)
        # and it still works, with the same result as a fresh copy
        with bh.Filter(*before) as g:
            f.predict_nonlinear(lambda x: x, mw, zw)
            g.predict_nonlinear(lambda x: x, mw, zw)
            same_distribution(f.state(), g.state(), rtol=1e-9)


def test_the_callers_exception_is_the_cause():
    class Custom(Exception):
        pass

    def fn(x):
        raise Custom("from the model")

    with bh.Filter(M4, Z4) as f:
        with pytest.raises(bh.BinghamError) as e:
            f.predict_nonlinear(fn, MW4, ZW4)
        assert type(e.value.__cause__) is Custom and str(e.value.__cause__) == "from the model"
        with pytest.raises(bh.BinghamError) as e:
            f.update_nonlinear(fn)
        assert type(e.value.__cause__) is Custom


def test_keyboard_interrupt_is_not_turned_into_a_status():
    def fn(x):
        raise KeyboardInterrupt

    with bh.Filter(M4, Z4) as f:
        before = f.state()
        with pytest.raises(KeyboardInterrupt):
            f.predict_nonlinear(fn, MW4, ZW4)
        with pytest.raises(KeyboardInterrupt):
            f.update_nonlinear(fn)
        np.testing.assert_array_equal(f.state()[1], before[1])
        f.predict(MW4, ZW4)  # still usable


def test_a_callback_may_not_use_its_filter():
    with bh.Filter(M4, Z4) as f:
        with pytest.raises(bh.BinghamError) as e:
            f.predict_nonlinear(lambda x: f.mode(), MW4, ZW4)
        assert isinstance(e.value.__cause__, ValueError)
        with pytest.raises(bh.BinghamError) as e:
            f.update_nonlinear(lambda x: f.close())
        assert isinstance(e.value.__cause__, ValueError)
        f.mode()  # not closed, usable
        # other filters are fine
        with bh.Filter(M4, Z4) as g:
            f.update_nonlinear(lambda x: float(g.log_likelihood(x, MW4, ZW4)))


def test_a_failing_log_likelihood_leaves_the_filter_unchanged():
    cases = [
        ("raises", lambda x: 1 / 0, ZeroDivisionError),
        ("nan", lambda x: math.nan, None),
        ("+inf", lambda x: math.inf, None),
        ("-inf", lambda x: -math.inf, None),
        ("not a number", lambda x: "x", ValueError),
        ("None", lambda x: None, TypeError),
    ]
    for m, z in ((M4, Z4), (M2, Z2)):
        with bh.Filter(m, z) as f:
            before = f.state()
            for name, fn, cause in cases:
                with pytest.raises(bh.BinghamError) as e:
                    f.update_nonlinear(fn)
                assert e.value.status == bh.Status.ERR_CALLBACK, name
                assert e.value.message.startswith("bingham_filter_update_nonlinear"), (name, e.value.message)
                if cause is None:
                    assert e.value.__cause__ is None, name
                else:
                    assert isinstance(e.value.__cause__, cause), name
                np.testing.assert_array_equal(f.state()[0], before[0], err_msg=name)
                np.testing.assert_array_equal(f.state()[1], before[1], err_msg=name)
            # failing only after a first round over the samples (a sharp, non-Bingham likelihood
            # takes several): the first call of the second round
            calls = iter(range(10**6))
            u = m[:, 0]
            fail_at = 2 * len(z) ** 2 - 4 * len(z) + 3

            def late(x):
                if next(calls) == fail_at:
                    raise RuntimeError("late")
                return -2000.0 * math.sqrt(max(0.0, 1.0 - float(x @ u) ** 2))

            with pytest.raises(bh.BinghamError) as e:
                f.update_nonlinear(late)
            assert isinstance(e.value.__cause__, RuntimeError)
            assert next(calls) == fail_at + 1, "no call after the failure"
            np.testing.assert_array_equal(f.state()[1], before[1])


# (name, prior z, likelihood z, bounds on the posterior's z (relative) and mode (rad)). A
# Bingham log-likelihood is a quadratic form, which the update's fitted exponent represents
# exactly: measured z errors 2e-14, 3e-12, 9e-11 and mode errors below 1e-14 rad.
BAYES_CASES = [
    ("likelihood as broad as the prior", Z4, np.array([-100.0, -50.0, -20.0, 0.0]), 1e-8, 1e-10),
    ("likelihood spread ~1/10 of the prior's", Z4, np.array([-1e4, -6e3, -2.5e3, 0.0]), 1e-8, 1e-10),
    ("likelihood spread ~1/100 of the prior's", Z4, np.array([-1e6, -6e5, -2.5e5, 0.0]), 1e-8, 1e-10),
]


@pytest.mark.parametrize("name,z0,zl,ztol,mode_tol", BAYES_CASES)
def test_update_nonlinear_with_a_bingham_likelihood_is_close_to_multiply(name, z0, zl, ztol, mode_tol):
    # the likelihood's mode 0.1 rad from the prior's, so the update moves the estimate
    ml = rotmat_4(expq([0.06, -0.05, 0.06])) @ M4 @ random_orthogonal_mode_fixed(7)
    p = ml @ np.diag(zl) @ ml.T
    m_ref, z_ref = bh.multiply(M4, z0, ml, zl)
    calls = []

    def log_l(x):
        calls.append(x)
        return float(x @ p @ x)

    with bh.Filter(M4, z0) as f:
        f.update_nonlinear(log_l)
        m, z = f.state()
    zerr = np.max(np.abs(z[:-1] / z_ref[:-1] - 1))
    merr = mode_angle(m[:, -1], m_ref[:, -1])
    print(f"{name}: z relative error {zerr:.2e}, mode error {merr:.2e} rad, {len(calls)} calls")
    assert zerr < ztol, (name, z, z_ref)
    assert merr < mode_tol, name


def mode_angle(a, b):
    """The angle between two axes (a ~ -a), accurate for small angles."""
    d1, d2 = np.linalg.norm(a - b), np.linalg.norm(a + b)
    return 2 * math.atan2(min(d1, d2), max(d1, d2))


def rotmat_4(u):
    """The 4×4 matrix of x ↦ u ⊕ x."""
    return np.stack([qmul(u, e) for e in np.eye(4)], axis=1)


def random_orthogonal_mode_fixed(seed):
    """An orthogonal matrix that keeps the last axis: mixes the principal axes 0..2 only."""
    r = np.eye(4)
    r[:3, :3] = random_orthogonal(3, seed)
    return r


def test_monte_carlo_nonlinear_prediction():
    """The nonlinear rate law on a concentrated d = 4 state: the predicted second moment against
    2·10⁵ samples pushed through the same law and composed with sampled noise."""
    n = 200_000
    m0 = rotmat_4(expq([0.2, 0.5, -0.3])) @ random_orthogonal(4, 11)
    m0 = np.linalg.qr(m0)[0]
    z0 = np.array([-400.0, -150.0, -60.0, 0.0])  # angular spreads about 0.05..0.13 rad
    mw, zw = bh.noise_from_angle_std(4, 0.02)
    x = bh.sample(m0, z0, n, seed=2024)
    w = bh.sample(mw, zw, n, seed=2025)
    y = qmul(rate_law(x), w)
    prod = y[:, :, None] * y[:, None, :]
    s_mc = prod.mean(axis=0)
    se = prod.std(axis=0) / math.sqrt(n)
    with bh.Filter(m0, z0) as f:
        f.predict_nonlinear(rate_law, mw, zw)
        s = bh.second_moment(*f.state())
    with bh.Filter(m0, z0) as g:  # the linear model (rate law ignored) is far off: the test can tell
        g.predict(mw, zw)
        s_lin = bh.second_moment(*g.state())
    err = np.abs(s - s_mc) / se
    print(f"max |S - S_mc| / SE = {err.max():.2f}, linear model: {(np.abs(s_lin - s_mc) / se).max():.0f}")
    assert err.max() < 5.0  # measured 1.24
    assert (np.abs(s_lin - s_mc) / se).max() > 100  # measured 2698

    # the same by hand from the deterministic samples: propagate, refit, compose with the noise
    def by_hand(scheme, lam):
        x, w, _ = bh.deterministic_samples(m0, z0, scheme, lam)
        y = rate_law(x)
        return bh.second_moment(*bh.compose(*bh.mle((y * w[:, None]).T @ y), mw, zw))

    np.testing.assert_allclose(by_hand("moments", 0.5), s, rtol=0, atol=1e-10)
    for lam in (0.5, 1.0):
        print(f"TAC 2016 points, lambda {lam}: max |S - S_mc| / SE = "
              f"{(np.abs(by_hand('tac2016', lam) - s_mc) / se).max():.2f}")
