"""The AHRS per sensor channel through the Python binding: the gyroscope bias's uncertainty
(``bias_std``, ``gyro_scale_noise``, :meth:`Ahrs.gyro_bias_covariance`) and NaN as "no sample"
of any sensor (the gyroscope's a gap the AHRS carries the orientation through; only a gyroscope
turning by more than 1e6 rad in a sample is refused)."""

import math

import numpy as np
import pytest

import bingham as bh

DT = 0.01


def stream(n):
    """n samples of a slow turn about the vertical (0.3 rad/s) with gravity and a northern field;
    the gyroscope reads the rate plus a small bias (0.001, -0.002, 0)."""
    t = np.arange(n) * DT
    yaw = 0.3 * t
    gyr = np.tile([0.001, -0.002, 0.3], (n, 1))
    acc = np.tile([0.0, 0.0, 9.81], (n, 1))
    mag = np.column_stack([20.0 * np.sin(yaw), 20.0 * np.cos(yaw), np.full(n, -40.0)])
    return gyr, acc, mag


def snapshot(a):
    m, z = a.state()
    return [a.quaternion(), m, z, a.gyro_bias(), a.gyro_bias_covariance(), a.angular_spread()]


def same(s, t):
    return all(np.array_equal(x, y) for x, y in zip(s, t))


def test_new_parameters_defaults_and_validation():
    p = bh.AhrsParams.default(DT)
    assert abs(p.bias_std - math.radians(0.5)) <= 1e-15
    assert math.isfinite(p.gyro_scale_noise) and p.gyro_scale_noise >= 0.0
    for field, bad in (("bias_std", (math.nan, -1.0, 0.0, math.inf)),
                       ("gyro_scale_noise", (math.nan, -1.0, math.inf)),
                       ("gyro_scale_std", (math.nan, -1e-3, 0.06, math.inf))):
        for v in bad:
            with pytest.raises(bh.BinghamError) as e:
                bh.Ahrs(DT, **{field: v})
            assert e.value.status == bh.Status.ERR_INVALID_ARGUMENT
            assert field in e.value.message
    bh.Ahrs(DT, gyro_scale_noise=0.0).close()
    bh.Ahrs(DT, gyro_scale_std=0.0).close()
    bh.Ahrs(DT, gyro_scale_std=0.05).close()


def test_gyro_bias_covariance_starts_at_bias_std_and_shrinks():
    for std in (None, 0.02):
        a = bh.Ahrs(DT) if std is None else bh.Ahrs(DT, bias_std=std)
        c = a.gyro_bias_covariance()
        assert c.shape == (3, 3) and c.dtype == np.float64
        assert np.array_equal(c, np.eye(3) * a.params.bias_std ** 2)
    a = bh.Ahrs(DT)
    gyr, acc, mag = stream(3000)
    a.update_batch(gyr, acc, mag)
    c = a.gyro_bias_covariance()
    var0 = a.params.bias_std ** 2
    assert np.all(np.isfinite(c))
    np.testing.assert_allclose(c, c.T, rtol=0, atol=1e-12 * var0)
    assert np.all(np.diag(c) > 0) and np.all(np.diag(c) < var0)
    assert np.all(np.linalg.eigvalsh(c) >= -1e-12 * var0)
    a.close()
    with pytest.raises(ValueError):
        a.gyro_bias_covariance()


def test_nan_in_any_sensor_is_no_sample_a_gyroscope_turning_too_far_is_refused():
    a = bh.Ahrs(DT)
    gyr, acc, mag = stream(300)
    a.update_batch(gyr[:200], acc[:200], mag[:200])
    # a NaN (or Inf) gyroscope entry: a gap, accepted; the same as a row of NaN, bit for bit;
    # gyr_missing_time counts it (one sample_time), the other sensors' stay 0
    b = bh.Ahrs(DT)
    b.update_batch(gyr[:200], acc[:200], mag[:200])
    for bad in (np.nan, np.inf, -np.inf):
        c, d = bh.Ahrs(DT), bh.Ahrs(DT)
        c.update_batch(gyr[:200], acc[:200], mag[:200])
        d.update_batch(gyr[:200], acc[:200], mag[:200])
        c.update([0.0, bad, 0.3], acc[200], mag[200])
        d.update([np.nan] * 3, acc[200], mag[200])
        assert same(snapshot(c), snapshot(d))
        h = c.health()
        assert (h.gyr_missing_time, h.acc_missing_time, h.mag_missing_time) == (DT, 0.0, 0.0)
    # a finite gyroscope turning by more than 1e6 rad in the sample: refused, the AHRS unchanged
    before = snapshot(a)
    with pytest.raises(bh.BinghamError) as e:
        a.update([0.0, 2e8, 0.3], acc[200], mag[200])
    assert e.value.status == bh.Status.ERR_INVALID_ARGUMENT and "gyroscope" in e.value.message
    assert same(before, snapshot(a))
    # a NaN field is the same as no magnetometer, bit for bit
    a.update(gyr[200], acc[200], [np.nan, 0.0, 0.0])
    b.update(gyr[200], acc[200], None)
    assert same(snapshot(a), snapshot(b))
    # a NaN accelerometer sample is accepted, the gyroscope still turns the estimate
    q = a.quaternion()
    a.update(gyr[201], [np.inf, 0.0, 9.81], mag[201])
    assert np.all(np.isfinite(a.quaternion())) and not np.array_equal(q, a.quaternion())


def test_batch_with_nan_rows_equals_single_updates():
    gyr, acc, mag = stream(60)
    acc[10:20] = np.nan  # an accelerometer gap
    mag[1::4] = np.nan  # a magnetometer at a quarter of the rate
    a, b = bh.Ahrs(DT), bh.Ahrs(DT)
    q, s = a.update_batch(gyr, acc, mag, spread=True)
    for k in range(60):
        b.update(gyr[k], acc[k], mag[k])
        assert np.array_equal(q[k], b.quaternion())
        assert s[k] == b.angular_spread()[3]
    assert same(snapshot(a), snapshot(b))
    # NaN gyroscope rows (gaps) do not stop the batch: equal to single updates
    g2 = gyr.copy()
    g2[7, 0] = np.nan
    g2[30:34] = np.nan
    c, d = bh.Ahrs(DT), bh.Ahrs(DT)
    q2 = c.update_batch(g2, acc, mag)
    for k in range(60):
        d.update(g2[k], acc[k], mag[k])
        assert np.array_equal(q2[k], d.quaternion())
    assert same(snapshot(c), snapshot(d))
    # a gyroscope row turning by more than 1e6 rad stops the batch there, naming the sample
    g3 = g2.copy()
    g3[41, 2] = 1e12
    c = bh.Ahrs(DT)
    with pytest.raises(bh.BinghamError) as e:
        c.update_batch(g3, acc, mag)
    assert "sample 41" in e.value.message
    d = bh.Ahrs(DT)
    d.update_batch(g3[:41], acc[:41], mag[:41])
    assert same(snapshot(c), snapshot(d))
    # the very first sample needs an accelerometer
    acc0 = acc.copy()
    acc0[0] = np.nan
    f = bh.Ahrs(DT)
    with pytest.raises(bh.BinghamError) as e:
        f.update_batch(gyr, acc0, mag)
    assert "sample 0" in e.value.message
