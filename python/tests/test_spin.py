"""Glover & Kaelbling's models through the Python binding (issue 22): ``Filter.predict_world``,
``update_world``, ``log_likelihood_world`` and ``SpinFilter``, against independent references:

* the world-frame update equals :func:`multiply` with the likelihood written out here (directions
  ``conj(m_i) ∘ y``), the prediction with a control equals ``compose(w, rotate_left(x, u))``, and
  the predictive density equals ``F(A + P) / (F(Z_x) F(Z_v))`` from the normalization constants
  (``A``, ``P`` the exponents of state and likelihood);
* one ``SpinFilter.step`` equals the same step composed from the package's distribution
  functions (compose, multiply, rotate_left; the inverse of ``x`` by conjugation), with and
  without control and observation; its predictive density equals the first-order filter's for
  the composed prior ``compose(spin, orientation)``;
* a noiseless constant spin is found (spin mode within 1e-6 rad after 300 steps);
* errors raise :class:`BinghamError` named by the Python method (or ``ValueError`` for shapes)
  and leave the state unchanged; ``clone`` is independent, ``close`` idempotent.
"""

import math

import numpy as np
import pytest

import bingham as bh

EYE = np.eye(4)
# the paper's kind of anisotropic noise, mode at the identity (the last column of M)
ANTI = np.fliplr(np.eye(4))


def random_orthogonal(rng):
    q, r = np.linalg.qr(rng.normal(size=(4, 4)))
    return q * np.sign(np.diag(r))


def random_unit(rng):
    v = rng.normal(size=4)
    return v / np.linalg.norm(v)


def axis_angle(axis, angle):
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    return np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * a])


def angle(a, b):
    return 2 * math.acos(min(1.0, abs(float(np.dot(a, b)))))


def precision(m, z):
    return m @ np.diag(z) @ m.T


def assert_same(a, b, tol, what):
    pa, pb = precision(*a), precision(*b)
    err = np.abs(pa - pb).max() / max(1.0, np.abs(a[1]).max())
    assert err < tol, f"{what}: relative difference {err:.3g}"


def likelihood(y, m_o, z_o):
    """The likelihood of ``y = o ∘ x``, o ~ Bingham(m_o, z_o), as a Bingham density of x."""
    cols = [bh.quat_multiply(bh.quat_conjugate(m_o[:, j]), y) for j in range(4)]
    return np.stack(cols, axis=1), np.asarray(z_o, dtype=float)


def inverse(m, z):
    """The distribution of ``x⁻¹`` (the conjugate): rows 1–3 of M negated."""
    return np.diag([1.0, -1.0, -1.0, -1.0]) @ m, z


def snapshot(f):
    return [a.copy() for a in f.state()]


def same_state(a, b):
    return all(np.array_equal(x, y) for x, y in zip(a, b))


# ---- the first-order filter's world-frame steps ------------------------------------------------


def test_world_update_is_the_product_with_the_written_out_likelihood():
    rng = np.random.default_rng(3)
    for _ in range(10):
        m, z = random_orthogonal(rng), np.array([-60.0, -25.0, -8.0, 0.0])
        m_v, z_v = random_orthogonal(rng), np.array([-40.0, -40.0, -10.0, 0.0])
        y = random_unit(rng)
        f = bh.Filter(m, z)
        f.update_world(y, m_v, z_v)
        assert_same(f.state(), bh.multiply(m, z, *likelihood(y, m_v, z_v)), 1e-12, "update_world")


def test_world_prediction_is_the_composition_with_the_rotated_state():
    rng = np.random.default_rng(4)
    for _ in range(10):
        m, z = random_orthogonal(rng), np.array([-60.0, -25.0, -8.0, 0.0])
        m_w, z_w = random_orthogonal(rng), np.array([-400.0, -200.0, -50.0, 0.0])
        u = random_unit(rng)
        f = bh.Filter(m, z)
        f.predict_world(m_w, z_w, u=u)
        want = bh.compose(m_w, z_w, *bh.rotate_left(m, z, u))
        assert_same(f.state(), want, 1e-9, "predict_world")
        # no control is the identity
        g, h = bh.Filter(m, z), bh.Filter(m, z)
        g.predict_world(m_w, z_w)
        h.predict_world(m_w, z_w, u=[1.0, 0.0, 0.0, 0.0])
        assert same_state(g.state(), h.state())
        # the world frame is not the body frame for an anisotropic noise
        b = bh.Filter(m, z)
        b.predict_rotation(u, m_w, z_w)
        assert np.abs(precision(*b.state()) - precision(*f.state())).max() > 1e-3


def test_world_log_likelihood_from_normalization_constants():
    rng = np.random.default_rng(5)
    for _ in range(10):
        m, z = random_orthogonal(rng), np.array([-30.0, -12.0, -3.0, 0.0])
        m_v, z_v = random_orthogonal(rng), np.array([-40.0, -40.0, -10.0, 0.0])
        y = random_unit(rng)
        f = bh.Filter(m, z)
        # ∫ exp(xᵀ(A + P)x) dx / (F(Z) F(Z_v)): both densities are Bingham in x
        c = precision(m, z) + precision(*likelihood(y, m_v, z_v))
        want = (
            bh.log_normalization_constant(np.linalg.eigvalsh(c))[0]
            - bh.log_normalization_constant(z)[0]
            - bh.log_normalization_constant(z_v)[0]
        )
        assert f.log_likelihood_world(y, m_v, z_v) == pytest.approx(want, rel=1e-10, abs=1e-10)
        assert f.log_likelihood_world(-y, m_v, z_v) == pytest.approx(want, rel=1e-10, abs=1e-10)


def test_world_steps_d2_equal_the_body_frame_ones():
    m, z = np.eye(2), np.array([-1.0, 0.0])
    w = (np.fliplr(np.eye(2)), np.array([-50.0, 0.0]))
    u, y = [math.cos(0.3), math.sin(0.3)], [math.cos(0.35), math.sin(0.35)]
    f, g = bh.Filter(m, z), bh.Filter(m, z)
    f.predict_world(*w, u=u)
    g.predict_rotation(u, *w)
    f.update_world(y, *w)
    g.update(y, *w)
    assert_same(f.state(), g.state(), 1e-12, "d = 2")
    assert f.log_likelihood_world(y, *w) == pytest.approx(g.log_likelihood(y, *w), rel=1e-12)


def test_world_errors_name_the_method_and_change_nothing():
    f = bh.Filter(EYE, [-5.0, -5.0, -5.0, 0.0])
    w = (ANTI, np.array([-400.0, -200.0, -50.0, 0.0]))
    f.predict_world(*w)
    before = snapshot(f)
    for call, name in [
        (lambda: f.predict_world(*w, u=[1.0, 0.1, 0.0, 0.0]), "Filter.predict_world"),
        (lambda: f.update_world([np.nan, 0.0, 0.0, 1.0], *w), "Filter.update_world"),
        (lambda: f.log_likelihood_world([2.0, 0.0, 0.0, 0.0], *w), "Filter.log_likelihood_world"),
    ]:
        with pytest.raises(bh.BinghamError) as e:
            call()
        assert str(e.value).startswith(f"{name}: "), str(e.value)
        assert e.value.status == bh.Status.ERR_INVALID_ARGUMENT
        assert same_state(snapshot(f), before)
    with pytest.raises(ValueError):
        f.update_world([1.0, 0.0], *w)
    with pytest.raises(ValueError):
        f.predict_world(*w, u=[1.0, 0.0, 0.0])
    assert same_state(snapshot(f), before)


# ---- the spin filter -----------------------------------------------------------------------------


@pytest.mark.parametrize("case", range(12))
def test_step_equals_the_distribution_operations(case):
    rng = np.random.default_rng(100 + case)
    m_x, m_v, m_w, m_o = (random_orthogonal(rng) for _ in range(4))
    z_x = np.array([-30.0 - 100.0 * rng.random(), -20.0, -5.0 * rng.random(), 0.0])
    z_v = np.array([-50.0, -10.0 - 20.0 * rng.random(), -3.0, 0.0])
    z_w = np.array([-400.0, -200.0, -1.0 - 100.0 * rng.random(), 0.0])
    z_o = np.array([-40.0, -40.0, -10.0, 0.0])
    u = random_unit(rng) if case % 3 != 0 else None
    y = random_unit(rng)
    observe = case % 4 != 3

    f = bh.SpinFilter(m_x, z_x, m_v, z_v)
    if observe:
        f.step(m_w, z_w, y, m_o, z_o, u=u)
    else:
        f.step(m_w, z_w, u=u)

    # x ← (B_v ∘ B_x) · L;  v ← W ∘ u ∘ (B_v · (L ∘ B_x⁻¹))
    want_x = bh.compose(m_v, z_v, m_x, z_x)
    want_v = (m_v, z_v)
    if observe:
        lik = likelihood(y, m_o, z_o)
        want_x = bh.multiply(*want_x, *lik)
        want_v = bh.multiply(m_v, z_v, *bh.compose(*lik, *inverse(m_x, z_x)))
    if u is not None:
        want_v = bh.rotate_left(*want_v, u)
    want_v = bh.compose(m_w, z_w, *want_v)
    assert_same(f.orientation(), want_x, 1e-9, f"case {case}: orientation")
    assert_same(f.spin(), want_v, 1e-9, f"case {case}: spin")
    m_xs, z_xs, m_vs, z_vs = f.state()
    assert same_state([m_xs, z_xs], f.orientation()) and same_state([m_vs, z_vs], f.spin())
    assert np.array_equal(f.orientation_mode(), bh.mode(*f.orientation()))
    assert np.array_equal(f.spin_mode(), bh.mode(*f.spin()))
    xs, vs = f.angular_spread()
    assert np.array_equal(xs, bh.angular_spread(*f.orientation()))
    assert np.array_equal(vs, bh.angular_spread(*f.spin()))


def test_log_likelihood_is_the_world_frame_density_of_the_composed_prior():
    rng = np.random.default_rng(8)
    m_x, m_v, m_o = (random_orthogonal(rng) for _ in range(3))
    z_x, z_v = np.array([-60.0, -25.0, -8.0, 0.0]), np.array([-40.0, -30.0, -5.0, 0.0])
    z_o = np.array([-40.0, -40.0, -10.0, 0.0])
    f = bh.SpinFilter(m_x, z_x, m_v, z_v)
    g = bh.Filter(*bh.compose(m_v, z_v, m_x, z_x))
    before = snapshot(f)
    for _ in range(5):
        y = random_unit(rng)
        assert f.log_likelihood(y, m_o, z_o) == pytest.approx(g.log_likelihood_world(y, m_o, z_o), rel=1e-9)
    assert same_state(snapshot(f), before)


def test_constant_spin_converges():
    rng = np.random.default_rng(11)
    for trial in range(3):
        spin = axis_angle(rng.normal(size=3), 0.3 + 1.2 * rng.random())  # 17–86° per step
        x = random_unit(rng)
        # uniform orientation prior, broad spin prior at the identity (the paper's (−3)³)
        f = bh.SpinFilter(EYE, np.zeros(4), EYE, [0.0, -3.0, -3.0, -3.0])
        sharp = [0.0, -400.0, -400.0, -400.0]
        errs = []
        for _ in range(300):
            f.step(EYE, sharp, x, EYE, sharp)
            errs.append(angle(f.spin_mode(), spin))
            x_err = angle(f.orientation_mode(), x)
            x = bh.quat_multiply(spin, x)
        assert errs[-1] < 1e-6, f"trial {trial}: spin error {errs[-1]:.3g} (after 20: {errs[19]:.3g})"
        assert x_err < 1e-6
        # the spin is composed with the process noise last: between its spread and twice that
        noise_spread = bh.angular_spread(EYE, sharp)[3]
        assert noise_spread < f.angular_spread()[1][3] < 2 * noise_spread


def test_prediction_only_steps_propagate_the_spin():
    spin = axis_angle([0.0, 0.0, 1.0], 0.5)
    x0 = axis_angle([1.0, 0.0, 0.0], 0.2)
    sharp = [0.0, -1e6, -1e6, -1e6]
    # a sharp state at (x0, spin): without observations, x follows the spin
    mv = np.stack([bh.quat_multiply(spin, e) for e in EYE], axis=1)  # columns spin ∘ e_i, mode spin
    mx = np.stack([bh.quat_multiply(x0, e) for e in EYE], axis=1)
    f = bh.SpinFilter(mx, sharp, mv, sharp)
    x = x0
    for _ in range(5):
        f.step(EYE, sharp)
        x = bh.quat_multiply(spin, x)
    assert angle(f.orientation_mode(), x) < 1e-4
    assert angle(f.spin_mode(), spin) < 1e-4
    # the observation noise is ignored without an observation
    f.step(EYE, sharp, None, np.full((4, 4), np.nan), None)


def test_errors_name_the_method_and_change_nothing():
    f = bh.SpinFilter(EYE, [-5.0, -5.0, -5.0, 0.0], EYE, [0.0, -3.0, -3.0, -3.0])
    w = (EYE, [0.0, -400.0, -400.0, -400.0])
    o = (ANTI, [-40.0, -40.0, -10.0, 0.0])
    f.step(*w, [1.0, 0.0, 0.0, 0.0], *o)
    before = snapshot(f)
    skew = EYE.copy()
    skew[0, 1] = 0.5
    for call, name, status in [
        (lambda: f.step(*w, [1.0, 0.1, 0.0, 0.0], *o), "SpinFilter.step", bh.Status.ERR_INVALID_ARGUMENT),
        (lambda: f.step(*w, u=[np.nan, 0.0, 0.0, 1.0]), "SpinFilter.step", bh.Status.ERR_INVALID_ARGUMENT),
        (lambda: f.step(skew, w[1]), "SpinFilter.step", bh.Status.ERR_INVALID_ARGUMENT),
        (lambda: f.log_likelihood([2.0, 0.0, 0.0, 0.0], *o), "SpinFilter.log_likelihood",
         bh.Status.ERR_INVALID_ARGUMENT),
        (lambda: f.set_state(EYE, [0.0, 0.0, 0.0, np.inf], EYE, w[1]), "SpinFilter.set_state",
         bh.Status.ERR_INVALID_ARGUMENT),
    ]:
        with pytest.raises(bh.BinghamError) as e:
            call()
        assert str(e.value).startswith(f"{name}: "), str(e.value)
        assert "bingham_" not in str(e.value)
        assert e.value.function == name and e.value.status == status
        assert same_state(snapshot(f), before)
    with pytest.raises(bh.BinghamError) as e:
        bh.SpinFilter(EYE, [0.0, 0.0, 0.0, np.nan], EYE, w[1])
    assert str(e.value).startswith("SpinFilter: ")
    # shapes are checked before the library is called
    for call in (
        lambda: f.step(*w, [1.0, 0.0, 0.0], *o),
        lambda: f.step(np.eye(3), [0.0, -1.0, -1.0]),
        lambda: f.step(*w, [1.0, 0.0, 0.0, 0.0]),  # an observation without its noise
        lambda: f.log_likelihood([1.0, 0.0, 0.0, 0.0], np.eye(2), [0.0, -1.0]),
        lambda: bh.SpinFilter(np.eye(2), [0.0, 0.0], EYE, w[1]),
    ):
        with pytest.raises(ValueError):
            call()
    assert same_state(snapshot(f), before)


def test_clone_set_state_and_close():
    w = (EYE, [0.0, -400.0, -400.0, -400.0])
    with bh.SpinFilter(EYE, np.zeros(4), EYE, [0.0, -3.0, -3.0, -3.0]) as f:
        f.step(*w, axis_angle([0, 1, 0], 0.3), ANTI, [-40.0, -40.0, -10.0, 0.0])
        before = snapshot(f)
        g = f.clone()
        assert same_state(snapshot(g), before)
        g.step(*w)
        assert same_state(snapshot(f), before) and not same_state(snapshot(g), before)
        g.set_state(*before)
        assert same_state(snapshot(g), before)
        g.close()
        g.close()
        with pytest.raises(ValueError, match="closed"):
            g.step(*w)
    with pytest.raises(ValueError, match="closed"):
        f.spin_mode()
