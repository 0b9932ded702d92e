"""The AHRS with its own time steps, timestamps and missing samples through the Python binding:
``Ahrs.update(..., dt=...)`` (``bingham_ahrs_update_dt``), ``Ahrs.update_batch(..., time=...)``
(``bingham_ahrs_update_batch_timed``), :meth:`Ahrs.orientation_covariance` and the health
readout's ``gyr_missing_time``, ``acc_missing_time``, ``mag_missing_time``.

- ``update(dt=sample_time)`` is ``update()`` bit for bit (NaN rows in every channel included);
  a bad ``dt`` raises with the AHRS unchanged (a twin fed the same afterwards stays equal);
  ``dt`` is used (a steady turn of 0.3 rad/s turns the estimate by 0.15 rad in 0.5 s);
- ``update_batch(time=uniform)`` is ``update_batch()`` bit for bit (quaternions, spreads, health
  scores, final state); with jitter and dropped samples a batch split anywhere is one call; the
  first timestamp's step is from the previous timed batch's last one (``update(dt=...)`` with the
  difference), ``sample_time`` after an untimed update;
- a timestamp not after the previous one (or NaN/Inf, or a step above 10 s) raises naming
  "sample k", the samples before it kept in the AHRS state (equal to a reference fed only them),
  and the last timestamp kept is t[k-1];
- ``orientation_covariance()``: the identity before the first sample; symmetric, positive
  semi-definite, its trace ``angular_spread()[3]**2`` (1e-12 relative) after every sample; in the
  world frame (a tilted sensor without magnetometer: the unknown heading about world z);
- the missing times: 0 at the start, the magnetometer's counted from the first sample when none
  is given, grown by the step per missing row (``sample_time``, ``dt``, the timestamps'
  differences), 0 again after a usable sample.
"""

import math

import numpy as np
import pytest

import bingham as bh

DT = 0.01


def stream(n, gaps=False, start=0):
    """n samples of a turn about the vertical (0.3 rad/s) with a swinging rate about x, gravity and
    a northern field; with ``gaps`` NaN rows: the gyroscope every 13th sample, the accelerometer
    every 17th (never the first), the magnetometer every 5th."""
    k = np.arange(start, start + n)
    yaw = 0.3 * DT * k
    gyr = np.column_stack([0.001 + 0.5 * np.sin(0.05 * k), np.full(n, -0.002), np.full(n, 0.3)])
    acc = np.tile([0.0, 0.0, 9.81], (n, 1))
    mag = np.column_stack([20.0 * np.sin(yaw), 20.0 * np.cos(yaw), np.full(n, -40.0)])
    if gaps:
        gyr[k % 13 == 5] = np.nan
        acc[(k % 17 == 3) & (k > 0)] = np.nan
        mag[k % 5 == 2] = np.nan
    return gyr, acc, mag


def snapshot(a):
    m, z = a.state()
    h = a.health()
    return [a.quaternion(), m, z, a.gyro_bias(), a.gyro_bias_covariance(), a.angular_spread(),
            a.orientation_covariance(), np.array([getattr(h, f) for f, _ in h._fields_], dtype=float)]


def same(s, t):
    return all(np.array_equal(x, y) for x, y in zip(s, t))


# ---- update(dt=...) ---------------------------------------------------------------------------


def test_update_dt_sample_time_is_update_bit_for_bit():
    gyr, acc, mag = stream(300, gaps=True)
    a, b = bh.Ahrs(DT), bh.Ahrs(DT)
    for k in range(300):
        m = None if k % 3 == 1 else mag[k]
        a.update(gyr[k], acc[k], m, dt=DT)
        b.update(gyr[k], acc[k], m)
        assert same(snapshot(a), snapshot(b)), k


def test_a_bad_dt_raises_and_changes_nothing():
    gyr, acc, mag = stream(201)
    a, twin = bh.Ahrs(DT), bh.Ahrs(DT)
    a.update_batch(gyr[:200], acc[:200], mag[:200])
    twin.update_batch(gyr[:200], acc[:200], mag[:200])
    before = snapshot(a)
    for bad in (0.0, -0.0, -0.01, math.nan, math.inf, -math.inf, 1e-7, 10.000001, 1e300):
        with pytest.raises(bh.BinghamError) as e:
            a.update(gyr[200], acc[200], mag[200], dt=bad)
        assert e.value.status == bh.Status.ERR_INVALID_ARGUMENT and "dt" in e.value.message
        assert same(before, snapshot(a))
    # the hidden state too: a twin that never saw the refused calls evolves identically
    a.update(gyr[200], acc[200], mag[200], dt=0.013)
    twin.update(gyr[200], acc[200], mag[200], dt=0.013)
    assert same(snapshot(a), snapshot(twin))
    # the bounds themselves are accepted
    for ok in (1e-6, 10.0):
        c = bh.Ahrs(DT)
        c.update_batch(gyr[:200], acc[:200], mag[:200])
        c.update(gyr[200], acc[200], mag[200], dt=ok)
        assert np.all(np.isfinite(c.quaternion())) and np.all(np.isfinite(c.orientation_covariance()))
    # before the first sample too
    f = bh.Ahrs(DT)
    with pytest.raises(bh.BinghamError):
        f.update(gyr[0], acc[0], mag[0], dt=math.nan)
    assert np.array_equal(f.quaternion(), [1.0, 0.0, 0.0, 0.0])
    assert np.array_equal(f.orientation_covariance(), np.eye(3))


def test_dt_is_used():
    # a steady turn of 0.3 rad/s about z (the last rate the AHRS saw), no accelerometer or
    # magnetometer sample: 0.15 rad in 0.5 s, 0.003 rad in sample_time
    k = np.arange(300)
    yaw = 0.3 * DT * k
    gyr = np.tile([0.001, -0.002, 0.3], (300, 1))
    acc = np.tile([0.0, 0.0, 9.81], (300, 1))
    mag = np.column_stack([20.0 * np.sin(yaw), 20.0 * np.cos(yaw), np.full(300, -40.0)])
    turns = []
    for dt in (0.5, DT):
        a = bh.Ahrs(DT)
        a.update_batch(gyr, acc, mag)
        q0 = a.quaternion()
        a.update(gyr[-1], [np.nan] * 3, None, dt=dt)
        turns.append(2 * math.acos(min(1.0, abs(float(np.dot(q0, a.quaternion()))))))
    assert abs(turns[0] - 0.15) <= 0.003 and abs(turns[1] - 0.003) <= 1e-4, turns


# ---- update_batch(time=...) ---------------------------------------------------------------------


def test_timed_batch_with_uniform_timestamps_is_the_untimed_batch():
    n = 400
    gyr, acc, mag = stream(n, gaps=True)
    t = 12345.678 + DT * np.arange(n)  # any origin; the differences carry rounding
    for m in (mag, None):
        a, b = bh.Ahrs(DT), bh.Ahrs(DT)
        qa, sa, ha = a.update_batch(gyr, acc, m, spread=True, health=True, time=t)
        qb, sb, hb = b.update_batch(gyr, acc, m, spread=True, health=True)
        assert np.array_equal(qa, qb) and np.array_equal(sa, sb) and np.array_equal(ha, hb)
        assert same(snapshot(a), snapshot(b))
        assert np.all(np.isfinite(qa)) and np.all(np.isfinite(sa))
    # the quaternions alone
    a, b = bh.Ahrs(DT), bh.Ahrs(DT)
    assert np.array_equal(a.update_batch(gyr, acc, mag, time=t), b.update_batch(gyr, acc, mag))


def jittered_times(n, start=3.0):
    k = np.arange(n)
    steps = DT * (1.0 + 0.3 * np.sin(1.7 * k)) + np.where(k % 37 == 36, 3 * DT, 0.0)
    return start + np.cumsum(steps)


def test_a_split_timed_batch_is_one_call():
    n = 300
    gyr, acc, mag = stream(n, gaps=True)
    t = jittered_times(n)
    a, b = bh.Ahrs(DT), bh.Ahrs(DT)
    qa, sa, ha = a.update_batch(gyr, acc, mag, spread=True, health=True, time=t)
    pieces = []
    for lo, hi in ((0, 1), (1, 1), (1, 50), (50, 51), (51, 200), (200, n)):
        pieces.append(b.update_batch(gyr[lo:hi], acc[lo:hi], mag[lo:hi], spread=True, health=True,
                                     time=t[lo:hi]))
    assert np.array_equal(qa, np.concatenate([p[0] for p in pieces]))
    assert np.array_equal(sa, np.concatenate([p[1] for p in pieces]))
    assert np.array_equal(ha, np.concatenate([p[2] for p in pieces]))
    assert same(snapshot(a), snapshot(b))
    # the steps are used: not the untimed batch's result
    assert not np.array_equal(qa, bh.Ahrs(DT).update_batch(gyr, acc, mag))


def test_the_first_timestamps_step():
    n = 100
    gyr, acc, mag = stream(n + 3)
    t = jittered_times(n)
    a, b = bh.Ahrs(DT), bh.Ahrs(DT)
    a.update_batch(gyr[:n], acc[:n], mag[:n], time=t)
    b.update_batch(gyr[:n], acc[:n], mag[:n], time=t)
    # from the previous timed batch's last timestamp
    tn = t[-1] + 0.037
    a.update_batch(gyr[n:n + 1], acc[n:n + 1], mag[n:n + 1], time=[tn])
    b.update(gyr[n], acc[n], mag[n], dt=tn - t[-1])
    assert same(snapshot(a), snapshot(b))
    # after an untimed update: sample_time, whatever the timestamp (even one before the last)
    a.update(gyr[n + 1], acc[n + 1], mag[n + 1])
    b.update(gyr[n + 1], acc[n + 1], mag[n + 1])
    a.update_batch(gyr[n + 2:n + 3], acc[n + 2:n + 3], mag[n + 2:n + 3], time=[1.0])
    b.update(gyr[n + 2], acc[n + 2], mag[n + 2])
    assert same(snapshot(a), snapshot(b))


@pytest.mark.parametrize("kind", ["equal", "before", "nan", "inf", "step above 10 s"])
def test_a_bad_timestamp_raises_naming_the_sample_and_keeps_the_earlier_samples(kind):
    gyr, acc, mag = stream(10, gaps=True)
    t = 100.0 + DT * np.arange(10)
    bad = {"equal": t[4], "before": t[4] - 0.005, "nan": math.nan, "inf": math.inf,
           "step above 10 s": t[4] + 10.5}[kind]
    tt = t.copy()
    tt[5] = bad
    a = bh.Ahrs(DT)
    with pytest.raises(bh.BinghamError) as e:
        a.update_batch(gyr, acc, mag, spread=True, health=True, time=tt)
    assert e.value.status == bh.Status.ERR_INVALID_ARGUMENT
    assert "sample 5" in e.value.message, e.value.message
    # samples 0..4 were processed: the state of a reference fed only them
    ref = bh.Ahrs(DT)
    ref.update_batch(gyr[:5], acc[:5], mag[:5], time=t[:5])
    assert same(snapshot(a), snapshot(ref))
    # the last timestamp kept is t[4]: both continue identically from t[5]
    qa = a.update_batch(gyr[5:], acc[5:], mag[5:], time=t[5:])
    qr = ref.update_batch(gyr[5:], acc[5:], mag[5:], time=t[5:])
    assert np.array_equal(qa, qr) and same(snapshot(a), snapshot(ref))


def test_nan_gyroscope_rows_never_stop_a_timed_batch():
    gyr, acc, mag = stream(50)
    gyr[10:20] = np.nan
    t = jittered_times(50)
    a, b = bh.Ahrs(DT), bh.Ahrs(DT)
    q = a.update_batch(gyr, acc, mag, time=t)
    for k in range(50):
        b.update_batch(gyr[k:k + 1], acc[k:k + 1], mag[k:k + 1], time=t[k:k + 1])
        assert np.array_equal(q[k], b.quaternion())
    assert np.all(np.isfinite(q)) and same(snapshot(a), snapshot(b))


# ---- orientation_covariance() --------------------------------------------------------------------


def check_covariance(a):
    c = a.orientation_covariance()
    assert c.shape == (3, 3) and c.dtype == np.float64 and np.all(np.isfinite(c))
    tr = np.trace(c)
    np.testing.assert_allclose(c, c.T, rtol=0, atol=1e-15 * tr)
    assert np.linalg.eigvalsh(c).min() >= -1e-14 * tr
    s2 = a.angular_spread()[3] ** 2
    assert abs(tr - s2) <= 1e-12 * s2, (tr, s2)
    return c


def test_orientation_covariance_symmetric_psd_with_the_squared_spread_as_trace():
    a = bh.Ahrs(DT)
    assert np.array_equal(a.orientation_covariance(), np.eye(3))  # uniform before the first sample
    check_covariance(a)
    gyr, acc, mag = stream(400, gaps=True)
    for k in range(400):
        a.update(gyr[k], acc[k], mag[k])
        check_covariance(a)  # between corrections too (the pending process noise included)
    assert np.trace(a.orientation_covariance()) < 0.01
    a.close()
    with pytest.raises(ValueError):
        a.orientation_covariance()


def test_orientation_covariance_is_in_the_world_frame():
    # a sensor tilted 60 degrees about x, without magnetometer: the unknown heading is the
    # variance about world z (up), not about the sensor's z axis (0, sin 60, cos 60) in the world
    th = math.radians(60.0)
    acc = [0.0, 9.81 * math.sin(th), 9.81 * math.cos(th)]
    a = bh.Ahrs(DT)
    for _ in range(500):
        a.update([0.0, 0.0, 0.0], acc)
    w, v = np.linalg.eigh(check_covariance(a))
    assert w[2] > 1e3 * w[1]
    assert abs(abs(v[2, 2]) - 1.0) < 1e-6, v[:, 2]


# ---- the health readout's missing times ----------------------------------------------------------


def missing(a):
    h = a.health()
    return np.array([h.gyr_missing_time, h.acc_missing_time, h.mag_missing_time])


def test_missing_times():
    gyr, acc, mag = stream(200)
    nan3 = [np.nan] * 3
    a = bh.Ahrs(DT)
    assert np.array_equal(missing(a), [0.0, 0.0, 0.0])
    # without a magnetometer: its missing time counts from the first sample
    a.update(gyr[0], acc[0], None)
    assert np.array_equal(missing(a), [0.0, 0.0, 0.0])
    for k in range(1, 101):
        a.update(gyr[k], acc[k], None)
    np.testing.assert_allclose(missing(a), [0.0, 0.0, 1.0], rtol=0, atol=1e-12)
    a.update(gyr[101], acc[101], mag[101])
    assert np.array_equal(missing(a), [0.0, 0.0, 0.0])
    # per missing row, the sensor's time grows by sample_time; a usable sample resets it
    for col, arr in enumerate((gyr, acc, mag)):
        for r in range(1, 4):
            row = [x.copy() for x in (gyr[101 + r], acc[101 + r], mag[101 + r])]
            row[col][:] = np.nan
            a.update(*row)
            want = np.zeros(3)
            want[col] = DT * r
            np.testing.assert_allclose(missing(a), want, rtol=0, atol=1e-15)
        a.update(gyr[110], acc[110], mag[110])
        assert np.array_equal(missing(a), [0.0, 0.0, 0.0])
    # free fall is no accelerometer sample
    a.update(gyr[111], [0.0, 0.3, 1.0], mag[111])
    np.testing.assert_allclose(missing(a), [0.0, DT, 0.0], rtol=0, atol=1e-15)
    # with dt: the step is added
    a.update(nan3, acc[112], mag[112], dt=0.05)
    np.testing.assert_allclose(missing(a), [0.05, 0.0, 0.0], rtol=0, atol=1e-15)
    a.update(nan3, nan3, mag[113], dt=0.03)
    np.testing.assert_allclose(missing(a), [0.08, 0.03, 0.0], rtol=0, atol=1e-15)
    a.update(gyr[114], acc[114], mag[114])
    assert np.array_equal(missing(a), [0.0, 0.0, 0.0])
    # a timed batch: the timestamps' differences over the missing rows
    t = np.array([50.0, 50.02, 50.05, 50.25])
    g = gyr[120:124].copy()
    g[1:] = np.nan
    a.update_batch(g, acc[120:124], mag[120:124], time=t)
    np.testing.assert_allclose(missing(a), [0.25, 0.0, 0.0], rtol=0, atol=1e-12)
    a.update_batch(gyr[124:125], acc[124:125], mag[124:125], time=[50.26])
    assert np.array_equal(missing(a), [0.0, 0.0, 0.0])
