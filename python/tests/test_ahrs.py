"""Tests of the vector-observation functions and the AHRS through the Python binding, against
independent references written here (rotation matrices from quaternions, Monte Carlo)."""

import numpy as np
import pytest

import bingham as bh


def rot(q):
    """R(q) for a unit quaternion (w, x, y, z): v_world = R v_sensor."""
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def unit(v):
    return v / np.linalg.norm(v)


def test_vector_observation_is_the_vmf_likelihood():
    rng = np.random.default_rng(1)
    for _ in range(20):
        b, r = unit(rng.normal(size=3)), unit(rng.normal(size=3))
        kappa = rng.uniform(0.1, 50)
        m, z = bh.vector_observation(b, r, kappa)
        np.testing.assert_allclose(z, [-2 * kappa, -2 * kappa, 0, 0], rtol=1e-14)
        a = m @ np.diag(z) @ m.T
        for _ in range(10):
            q = unit(rng.normal(size=4))
            # exponent with the normalization shift: κ rᵀR(q)b − κ
            assert q @ a @ q == pytest.approx(kappa * r @ rot(q) @ b - kappa, abs=1e-11 * kappa)


def test_filter_update_vector_equals_multiply_and_refuses_bad_input():
    rng = np.random.default_rng(2)
    m0, _ = np.linalg.qr(rng.normal(size=(4, 4)))
    z0 = np.array([-30.0, -10.0, -3.0, 0.0])
    b, r = unit(rng.normal(size=3)), unit(rng.normal(size=3))
    f = bh.Filter(m0, z0)
    f.update_vector(b, r, 7.0)
    ml, zl = bh.vector_observation(b, r, 7.0)
    mp, zp = bh.multiply(m0, z0, ml, zl)
    m, z = f.state()
    np.testing.assert_allclose(m @ np.diag(z) @ m.T, mp @ np.diag(zp) @ mp.T, atol=1e-10)
    before = f.state()
    for args in ((b * 2, r, 1.0), (b, r, -1.0), (b, r, float("nan"))):
        with pytest.raises(bh.BinghamError) as e:
            f.update_vector(*args)
        assert e.value.status == bh.Status.ERR_INVALID_ARGUMENT
    after = f.state()
    assert np.array_equal(before[0], after[0]) and np.array_equal(before[1], after[1])
    f2 = bh.Filter(np.eye(2), [-1.0, 0.0])
    with pytest.raises(bh.BinghamError) as e:
        f2.update_vector(b, r, 1.0)
    assert e.value.status == bh.Status.ERR_INVALID_DIMENSION


def test_noise_from_angle_std_second_moment_monte_carlo():
    rng = np.random.default_rng(3)
    sigma = 0.3
    v = rng.normal(scale=sigma, size=(400000, 3))
    th = np.linalg.norm(v, axis=1)
    q = np.column_stack([np.cos(th / 2), np.sin(th / 2)[:, None] * v / th[:, None]])
    s_mc = q.T @ q / len(q)
    m, z = bh.noise_from_angle_std(4, sigma)
    s = bh.second_moment(m, z)
    np.testing.assert_allclose(s, s_mc, atol=5e-4)
    assert abs(m[0, 3]) == pytest.approx(1.0)


def test_angular_spread_is_rms_of_two_sin_half_angle():
    m, z = bh.noise_from_angle_std(4, 0.2)
    x = bh.sample(m, z, 200000, seed=5)
    mode = m[:, 3]
    c = np.clip(np.abs(x @ mode), 0, 1)
    rms = np.sqrt(np.mean(4 * (1 - c * c)))  # (2 sin(θ/2))² = 4 (1 − cos²(θ/2))
    spread = bh.angular_spread(m, z)
    assert spread[3] == pytest.approx(rms, rel=0.01)
    assert spread[3] ** 2 == pytest.approx(np.sum(spread[:3] ** 2), rel=1e-12)


def test_ahrs_tracks_a_simulated_rotation():
    dt = 0.01
    n = 3000
    a = bh.Ahrs(dt)
    t = np.arange(n) * dt
    w_body = np.column_stack([0.5 * np.sin(0.7 * t), 0.4 * np.cos(0.5 * t), 0.3 * np.ones(n)])
    w_body[:200] = 0.0
    q = np.array([1.0, 0.0, 0.0, 0.0])
    field = np.array([0.0, 20.0, -40.0])
    gyr, acc, mag, truth = [], [], [], []
    for k in range(n):
        r = rot(q)
        gyr.append(w_body[k])
        acc.append(r.T @ np.array([0, 0, 9.81]))
        mag.append(r.T @ field)
        truth.append(q.copy())
        ang = np.linalg.norm(w_body[k]) * dt
        if ang > 0:
            ax = w_body[k] / np.linalg.norm(w_body[k])
            dq = np.concatenate([[np.cos(ang / 2)], np.sin(ang / 2) * ax])
            w0, x0, y0, z0 = q
            w1, x1, y1, z1 = dq
            q = unit(np.array([w0 * w1 - x0 * x1 - y0 * y1 - z0 * z1,
                               w0 * x1 + x0 * w1 + y0 * z1 - z0 * y1,
                               w0 * y1 - x0 * z1 + y0 * w1 + z0 * x1,
                               w0 * z1 + x0 * y1 - y0 * x1 + z0 * w1]))
    est, spread = a.update_batch(np.array(gyr), np.array(acc), np.array(mag), spread=True)
    err = 2 * np.arccos(np.clip(np.abs(np.sum(est * np.array(truth), axis=1)), 0, 1))
    assert np.degrees(np.sqrt(np.mean(err[500:] ** 2))) < 2.0
    assert np.all(np.isfinite(spread)) and np.all(spread > 0)


def test_ahrs_refuses_a_gyroscope_turning_too_far_and_batch_names_it():
    a = bh.Ahrs(0.01)
    a.update([0, 0, 0], [0, 0, 9.81], [0, 20, -40])
    q0, s0, b0 = a.quaternion(), a.state(), a.gyro_bias()
    # finite, but 1e12 rad/s turns by 1e10 rad in 0.01 s: not a rate
    with pytest.raises(bh.BinghamError) as e:
        a.update([1e12, 0, 0], [0, 0, 9.81], None)
    assert e.value.status == bh.Status.ERR_INVALID_ARGUMENT and "gyroscope" in e.value.message
    assert np.array_equal(q0, a.quaternion()) and np.array_equal(b0, a.gyro_bias())
    assert np.array_equal(s0[0], a.state()[0])
    gyr = np.zeros((10, 3))
    acc = np.tile([0, 0, 9.81], (10, 1))
    gyr[3, 1] = np.inf  # a gyroscope gap: processed (NaN/Inf is "no sample": test_ahrs_channels.py)
    gyr[6, 2] = -1e12
    with pytest.raises(bh.BinghamError) as e:
        a.update_batch(gyr, acc)
    assert "sample 6" in e.value.message
    with pytest.raises(TypeError):
        bh.Ahrs(0.01, no_such_parameter=1.0)
    with pytest.raises(bh.BinghamError):
        bh.Ahrs(0.0)


def _reversing_spin(s_z, seconds=70.0, dt=0.01):
    """An upright sensor: 10 s at rest, then turning about the vertical at 1 rad/s, the
    direction reversed every 5 s, its gyroscope reading (1 + s_z) times the rate about z."""
    t = np.arange(int(round(seconds / dt))) * dt
    w = np.where(t < 10.0, 0.0, np.where(((t - 10.0) // 5.0) % 2 == 0, 1.0, -1.0))
    yaw = np.concatenate([[0.0], np.cumsum(w * dt)[:-1]])
    dip = np.radians(60.0)
    gyr = np.c_[np.zeros_like(t), np.zeros_like(t), (1.0 + s_z) * w]
    acc = np.tile([0.0, 0.0, 9.81], (len(t), 1))
    mag = 50.0 * np.c_[np.cos(dip) * np.sin(yaw), np.cos(dip) * np.cos(yaw),
                       -np.sin(dip) * np.ones_like(t)]
    return gyr, acc, mag


def test_gyro_scale_is_learned_from_reversing_rotation():
    # zero at creation; the drift s_z·ω flips with the rate, which no bias explains: the
    # estimate about z moves toward the truth, the unexcited axes stay at 0; with
    # gyro_scale_std = 0 it is not estimated
    assert np.array_equal(bh.Ahrs(0.01).gyro_scale(), np.zeros(3))
    gyr, acc, mag = _reversing_spin(0.01)
    a = bh.Ahrs(0.01, gyro_scale_std=0.01)
    a.update_batch(gyr, acc, mag)
    s = a.gyro_scale()
    assert s.shape == (3,)
    assert abs(s[2] - 0.01) < 0.005 and abs(s[0]) < 1e-3 and abs(s[1]) < 1e-3, s
    off = bh.Ahrs(0.01, gyro_scale_std=0.0)
    off.update_batch(gyr, acc, mag)
    assert np.array_equal(off.gyro_scale(), np.zeros(3))
