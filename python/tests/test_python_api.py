"""The Python layer's own rules (issue 23): AhrsParams only in valid forms, Ahrs never modifying
the caller's parameters and refusing a sample_time that is a rate, Ahrs.from_rate, errors named
by the Python function, and the quaternion helpers against independent references (rotation
matrices by Rodrigues' formula, the BROAD example's metric, SciPy when installed)."""

import copy
import ctypes
import math
import os
import pickle
import re
import sys

import numpy as np
import pytest

import bingham as bh
from bingham._library import _SIGNATURES
from bingham.errors import _PYTHON_NAMES

HERE = os.path.dirname(os.path.abspath(__file__))
# broad.py is an example program (examples/python/), not part of the package
sys.path.insert(0, os.path.join(HERE, "..", "..", "examples", "python"))
import broad  # noqa: E402

DT = 0.01


def still(n=200):
    """n samples at rest, level, facing north (sensor = world ENU)."""
    return np.zeros((n, 3)), np.tile([0.0, 0.0, 9.81], (n, 1)), np.tile([0.0, 20.0, -40.0], (n, 1))


# ---- AhrsParams --------------------------------------------------------------------------------


def test_params_keywords_start_from_the_defaults():
    d = bh.AhrsParams.default(DT)
    assert d.as_dict() == bh.AhrsParams(sample_time=DT).as_dict()
    assert d.gyro_noise > 0 and d.sample_time == DT
    p = bh.AhrsParams(sample_time=DT, acc_noise=0.8, bias_std=0.02)
    want = dict(d.as_dict(), acc_noise=0.8, bias_std=0.02)
    assert p.as_dict() == want
    # the defaults depend on the sample time, and keywords follow it
    assert bh.AhrsParams(sample_time=0.002).as_dict() == bh.AhrsParams.default(0.002).as_dict()
    assert "acc_noise=0.8" in repr(p)


@pytest.mark.parametrize(
    "args, kwargs",
    [((0.01,), {}), ((), {}), ((), {"acc_noise": 0.8}), ((0.01,), {"acc_noise": 0.8})],
)
def test_params_invalid_forms_point_to_the_valid_ones(args, kwargs):
    with pytest.raises(TypeError) as e:
        bh.AhrsParams(*args, **kwargs)
    msg = str(e.value)
    assert "AhrsParams.default(sample_time)" in msg and "AhrsParams(sample_time=" in msg, msg


def test_params_unknown_field_lists_the_valid_ones():
    with pytest.raises(TypeError) as e:
        bh.AhrsParams(sample_time=DT, acc_nosie=0.8)
    msg = str(e.value)
    assert "'acc_nosie'" in msg
    for name, *_ in bh.AhrsParams._fields_:
        assert name in msg
    with pytest.raises(TypeError) as e:
        bh.Ahrs(DT, acc_nosie=0.8)
    assert "'acc_nosie'" in str(e.value) and "acc_noise" in str(e.value)


def test_params_refused_sample_time_is_a_library_error():
    with pytest.raises(bh.BinghamError) as e:
        bh.AhrsParams(sample_time=0.0)
    assert e.value.status == bh.Status.ERR_INVALID_ARGUMENT and "sample_time" in e.value.message


def test_params_copies_are_independent():
    p = bh.AhrsParams(sample_time=DT, acc_noise=0.8)
    for q in (p.copy(), copy.copy(p), copy.deepcopy(p), pickle.loads(pickle.dumps(p)),
              bh.AhrsParams.from_buffer_copy(p)):
        assert type(q) is bh.AhrsParams and q is not p
        assert q.as_dict() == p.as_dict()
        q.acc_noise = 0.5
        assert p.acc_noise == 0.8
    assert ctypes.sizeof(bh.AhrsParams) == 8 * len(bh.AhrsParams._fields_)


# ---- Ahrs ----------------------------------------------------------------------------------------


def test_ahrs_never_modifies_the_callers_params():
    p = bh.AhrsParams.default(DT)
    before = p.as_dict()
    a = bh.Ahrs(DT, params=p, acc_noise=0.9, mag_latency=0.0)
    assert p.as_dict() == before
    assert a.params is not p
    assert a.params.as_dict() == dict(before, acc_noise=0.9, mag_latency=0.0)
    p.acc_noise = 2.0  # changing the caller's object later changes nothing either
    assert a.params.acc_noise == 0.9
    # the overrides are in effect: the same as building the parameters with them
    b = bh.Ahrs(DT, params=bh.AhrsParams(sample_time=DT, acc_noise=0.9, mag_latency=0.0))
    gyr, acc, mag = still()
    gyr[:, 2] = 0.3
    acc[50:, 0] = 2.0
    assert np.array_equal(a.update_batch(gyr, acc, mag), b.update_batch(gyr, acc, mag))


def test_ahrs_sample_time_must_match_params():
    p = bh.AhrsParams.default(DT)
    with pytest.raises(ValueError) as e:
        bh.Ahrs(0.02, params=p)
    msg = str(e.value)
    assert "sample_time = 0.02" in msg and "params.sample_time = 0.01" in msg, msg
    bh.Ahrs(p.sample_time, params=p).close()
    with pytest.raises(TypeError):
        bh.Ahrs(DT, params=p.as_dict())  # not an AhrsParams


def test_ahrs_from_rate():
    a = bh.Ahrs.from_rate(100)
    assert a.params.sample_time == 1.0 / 100
    assert a.params.as_dict() == bh.AhrsParams.default(0.01).as_dict()
    b = bh.Ahrs.from_rate(250.0, acc_noise=0.7)
    assert b.params.sample_time == 1.0 / 250 and b.params.acc_noise == 0.7
    gyr, acc, mag = still()
    assert np.array_equal(a.update_batch(gyr, acc, mag), bh.Ahrs(0.01).update_batch(gyr, acc, mag))
    assert bh.Ahrs.from_rate(1).params.sample_time == 1.0
    for bad in (0, -100, math.nan, math.inf, -math.inf, 0.5):
        with pytest.raises(ValueError):
            bh.Ahrs.from_rate(bad)
        with pytest.raises(ValueError):
            bh.AhrsParams.from_rate(bad)
    # AhrsParams.from_rate (bingham_ahrs_params_from_rate): the defaults for the period 1/hz
    assert bh.AhrsParams.from_rate(100).as_dict() == bh.AhrsParams.default(0.01).as_dict()
    assert bh.AhrsParams.from_rate(400).sample_time == 0.0025
    with pytest.raises(bh.BinghamError) as e:  # above 1e6 Hz: the library's bound
        bh.AhrsParams.from_rate(2e6)
    assert str(e.value).startswith("AhrsParams.from_rate"), str(e.value)


def test_ahrs_refuses_a_rate_passed_as_sample_time():
    for hz in (100, 1000.0, 1.5):
        with pytest.raises(ValueError) as e:
            bh.Ahrs(hz)
        msg = str(e.value)
        assert f"sample_time = {hz:g} s" in msg and "did you pass a rate in Hz?" in msg, msg
        assert f"use Ahrs.from_rate({hz:g})" in msg, msg
    bh.Ahrs(1.0).close()  # the bound itself is accepted
    # the parameters are refused the same way (the library's bound, BINGHAM_AHRS_MAX_SAMPLE_TIME)
    for make in (lambda: bh.AhrsParams.default(2.0), lambda: bh.AhrsParams(sample_time=2.0)):
        with pytest.raises(ValueError) as e:
            make()
        msg = str(e.value)
        assert msg.startswith("AhrsParams: sample_time = 2 s: did you pass a rate in Hz?"), msg
        assert "use Ahrs.from_rate(2)" in msg, msg
    # a structure changed by hand is refused by the AHRS
    p = bh.AhrsParams.default(DT)
    p.sample_time = 2.0
    with pytest.raises(ValueError, match="did you pass a rate in Hz"):
        bh.Ahrs(2.0, params=p)
    # ... and by the library, when the Python check is bypassed
    lib = bh._library.lib()
    h = ctypes.c_void_p()
    assert lib.bingham_ahrs_new(ctypes.byref(p), ctypes.byref(h)) == bh.Status.ERR_INVALID_ARGUMENT
    assert "did you pass a rate in Hz?" in bh.last_error_message()
    # non-finite and non-positive values remain the library's to refuse
    for bad in (0.0, -0.01, math.nan, math.inf):
        with pytest.raises(bh.BinghamError):
            bh.Ahrs(bad)


# ---- errors named by the Python function -----------------------------------------------------


def _resolve(dotted):
    obj = bh
    for part in dotted.split("."):
        obj = getattr(obj, part)
    return obj


def test_every_called_c_function_has_a_python_name():
    called = set()
    pkg = os.path.dirname(os.path.abspath(bh.__file__))
    for name in os.listdir(pkg):
        if name.endswith(".py"):
            with open(os.path.join(pkg, name), encoding="utf-8") as f:
                called |= set(re.findall(r"lib\(\)\.(bingham_\w+)", f.read()))
    utilities = {"bingham_version", "bingham_status_str", "bingham_last_error_message",
                 "bingham_filter_free", "bingham_ahrs_free", "bingham_spin_filter_free"}
    assert called - utilities <= set(_PYTHON_NAMES), sorted(called - utilities - set(_PYTHON_NAMES))
    for c_name, py_name in _PYTHON_NAMES.items():
        assert c_name in _SIGNATURES, c_name
        assert callable(_resolve(py_name)), py_name


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: bh.log_normalization_constant([np.nan, 0.0, 0.0]), "log_normalization_constant"),
        (lambda: bh.noise_from_angle_std(3, 0.1), "noise_from_angle_std"),
        (lambda: bh.Filter(np.eye(4), [-1.0, -1.0, -1.0, np.nan]), "Filter"),
        (lambda: bh.Filter(np.eye(4), [-1.0, -1.0, -1.0, 0.0]).update_nonlinear(lambda x: math.nan),
         "Filter.update_nonlinear"),
        (lambda: bh.Ahrs(DT, acc_noise=-1.0), "Ahrs"),
        (lambda: bh.Ahrs(DT).update([1e12, 0.0, 0.0], [0.0, 0.0, 9.81]), "Ahrs.update"),
        (lambda: bh.Ahrs(DT).update([0.0, 0.0, 0.0], [0.0, 0.0, 9.81], dt=-1.0), "Ahrs.update"),
        (lambda: bh.Ahrs(DT).update_batch(np.full((2, 3), np.nan), np.zeros((2, 3))), "Ahrs.update_batch"),
        (lambda: bh.Ahrs(DT).update_batch(np.zeros((2, 3)), np.tile([0.0, 0.0, 9.81], (2, 1)), time=[1.0, 1.0]),
         "Ahrs.update_batch"),
        (lambda: bh.AhrsParams.default(-1.0), "AhrsParams.default"),
    ],
)
def test_error_text_leads_with_the_python_name(call, name):
    with pytest.raises(bh.BinghamError) as e:
        call()
    text = str(e.value)
    assert text.startswith(f"{name}: {e.value.status_name} ("), text
    assert "bingham_" not in text, text
    assert e.value.function == name
    # .message stays the library's, naming the C function
    assert e.value.message.startswith("bingham_"), e.value.message
    assert e.value.message.split(":")[0] not in text


# ---- quaternions -----------------------------------------------------------------------------------


def rodrigues(q):
    """R(q) from the axis and angle of a unit quaternion (Rodrigues' formula), (..., 3, 3)."""
    q = np.asarray(q, dtype=float)
    v = q[..., 1:]
    s = np.linalg.norm(v, axis=-1)
    angle = 2.0 * np.arctan2(s, q[..., 0])
    axis = v / np.where(s > 0, s, 1.0)[..., None]
    k = np.zeros(q.shape[:-1] + (3, 3))
    k[..., 0, 1], k[..., 0, 2], k[..., 1, 2] = -axis[..., 2], axis[..., 1], -axis[..., 0]
    k = k - np.swapaxes(k, -1, -2)
    sin, cos = np.sin(angle)[..., None, None], np.cos(angle)[..., None, None]
    return np.eye(3) + sin * k + (1.0 - cos) * (k @ k)


def random_quats(rng, *shape):
    q = rng.normal(size=shape + (4,))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def axis_angle(axis, angle):
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * axis])


def test_quat_multiply_composes_rotations():
    rng = np.random.default_rng(23)
    a, b = random_quats(rng, 200), random_quats(rng, 200)
    ab = bh.quat_multiply(a, b)
    assert ab.shape == (200, 4) and ab.dtype == np.float64
    np.testing.assert_allclose(np.linalg.norm(ab, axis=-1), 1.0, atol=1e-14)
    np.testing.assert_allclose(rodrigues(ab), rodrigues(a) @ rodrigues(b), atol=1e-12)
    # the basis: i j = k, j i = -k, i i = -1; the identity
    i, j, k = np.eye(4)[1], np.eye(4)[2], np.eye(4)[3]
    np.testing.assert_array_equal(bh.quat_multiply(i, j), k)
    np.testing.assert_array_equal(bh.quat_multiply(j, i), -k)
    np.testing.assert_array_equal(bh.quat_multiply(i, i), [-1.0, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(bh.quat_multiply([1, 0, 0, 0], a[0]), a[0])
    # broadcasting over leading axes, lists accepted
    c = bh.quat_multiply(a[:3, None, :], b[:5])
    assert c.shape == (3, 5, 4)
    np.testing.assert_allclose(c[2, 4], bh.quat_multiply(list(a[2]), list(b[4])), rtol=0, atol=0)
    assert bh.quat_multiply(a[0], b).shape == (200, 4)
    for bad in ([1.0, 0.0, 0.0], 1.0, np.zeros((2, 3))):
        with pytest.raises(ValueError):
            bh.quat_multiply(bad, a[0])


def test_quat_conjugate_is_the_inverse():
    rng = np.random.default_rng(5)
    q = random_quats(rng, 50)
    qc = bh.quat_conjugate(q)
    np.testing.assert_array_equal(qc[:, 0], q[:, 0])
    np.testing.assert_array_equal(qc[:, 1:], -q[:, 1:])
    np.testing.assert_allclose(rodrigues(qc), np.swapaxes(rodrigues(q), -1, -2), atol=1e-12)
    np.testing.assert_allclose(bh.quat_multiply(q, qc), np.tile([1.0, 0, 0, 0], (50, 1)), atol=1e-15)
    q2 = 3.0 * q[0]  # not unit: q q* = |q|^2
    np.testing.assert_allclose(bh.quat_multiply(q2, bh.quat_conjugate(q2)), [9.0, 0, 0, 0], atol=1e-14)


def test_orientation_error_is_broads():
    rng = np.random.default_rng(7)
    truth = random_quats(rng, 500)
    small = random_quats(rng, 500) * [1.0, 0.2, 0.2, 0.2]  # errors of all sizes, near and far
    est = bh.quat_multiply(small / np.linalg.norm(small, axis=-1, keepdims=True), truth)
    est[::3] = random_quats(rng, len(est[::3]))
    est[::2] *= -1.0  # the sign does not matter
    truth[1::5] *= 1.0 + 1e-9  # nor a not-quite-unit truth
    err = bh.orientation_error(est, truth)
    ref = broad.errors(est, truth)
    assert isinstance(err, bh.OrientationError)
    for name in ("total", "heading", "inclination"):
        np.testing.assert_allclose(getattr(err, name), ref[name], rtol=0, atol=1e-12, err_msg=name)
    one = bh.orientation_error(est[4], truth[4])
    assert all(type(v) is float for v in one)
    np.testing.assert_allclose(one, [ref["total"][4], ref["heading"][4], ref["inclination"][4]], atol=1e-12)
    total, heading, inclination = err  # a tuple
    assert np.all(heading <= total + 1e-12) and np.all(inclination <= total + 1e-12)
    assert np.all((0 <= total) & (total <= math.pi))


def test_orientation_error_separates_heading_and_inclination():
    rng = np.random.default_rng(11)
    for truth in random_quats(rng, 20):
        for angle in (0.01, 0.5, 2.0, 3.1):
            yaw = bh.quat_multiply(axis_angle([0, 0, 1], angle), truth)  # about the world's up
            t, h, i = bh.orientation_error(yaw, truth)
            assert t == pytest.approx(angle, abs=1e-7) and h == pytest.approx(angle, abs=1e-7)
            assert i == pytest.approx(0.0, abs=1e-7)
            horizontal = [math.cos(angle), math.sin(angle), 0.0]
            tilt = bh.quat_multiply(axis_angle(horizontal, angle), truth)
            t, h, i = bh.orientation_error(tilt, truth)
            assert t == pytest.approx(angle, abs=1e-7) and i == pytest.approx(angle, abs=1e-7)
            assert h == pytest.approx(0.0, abs=1e-7)
    nan = bh.orientation_error([1.0, 0, 0, 0], [np.nan, 0, 0, 0])
    assert all(math.isnan(v) for v in nan)


def test_orientation_error_of_the_ahrs_at_rest():
    # level, facing north: the sensor frame is the world's ENU, q = identity
    a = bh.Ahrs.from_rate(100)
    q = a.update_batch(*still(300))
    err = bh.orientation_error(q[-1], [1.0, 0.0, 0.0, 0.0])
    assert err.total < math.radians(1.0)
    # turned 90° about the vertical: the sensor's x axis points north, ENU's y
    yaw = axis_angle([0, 0, 1], math.pi / 2)
    r = rodrigues(yaw)
    gyr, acc, mag = still(300)
    b = bh.Ahrs.from_rate(100)
    q = b.update_batch(gyr, acc @ r, mag @ r)  # sensor readings: R^T v_world
    err = bh.orientation_error(q[-1], yaw)
    assert err.total < math.radians(1.0) and err.heading < math.radians(1.0)


def test_scipy_order_conversions():
    np.testing.assert_array_equal(bh.to_scipy([1.0, 2.0, 3.0, 4.0]), [2.0, 3.0, 4.0, 1.0])
    np.testing.assert_array_equal(bh.from_scipy([2.0, 3.0, 4.0, 1.0]), [1.0, 2.0, 3.0, 4.0])
    rng = np.random.default_rng(3)
    q = random_quats(rng, 4, 6)
    assert bh.to_scipy(q).shape == (4, 6, 4)
    np.testing.assert_array_equal(bh.from_scipy(bh.to_scipy(q)), q)
    np.testing.assert_array_equal(bh.to_scipy(q)[..., 3], q[..., 0])
    with pytest.raises(ValueError):
        bh.to_scipy([1.0, 0.0, 0.0])
    with pytest.raises(ValueError):
        bh.from_scipy(np.zeros((3, 5)))


def test_scipy_rotation_agrees():
    transform = pytest.importorskip("scipy.spatial.transform")
    rng = np.random.default_rng(13)
    q = random_quats(rng, 100)
    r = transform.Rotation.from_quat(bh.to_scipy(q))
    np.testing.assert_allclose(r.as_matrix(), rodrigues(q), atol=1e-12)
    back = bh.from_scipy(r.as_quat())
    np.testing.assert_allclose(np.abs(np.sum(back * q, axis=-1)), 1.0, atol=1e-12)  # ±q
    np.testing.assert_allclose(r.magnitude(), bh.orientation_error(q, [1.0, 0, 0, 0]).total, atol=1e-9)
    try:
        direct = transform.Rotation.from_quat(q, scalar_first=True)  # SciPy >= 1.14
    except TypeError:
        return
    np.testing.assert_allclose(direct.as_matrix(), rodrigues(q), atol=1e-12)


def test_quaternions_read_with_few_decimals_are_normalized_and_gross_errors_refused():
    """BINGHAM_UNIT_TOL = 1e-3 (issue 23): a fix rounded to 4 decimals is accepted (normalized);
    one 1 % off unit length is refused with "normalize it first"."""
    rng = np.random.default_rng(5)
    m = np.eye(4)[:, [1, 2, 3, 0]]
    z = np.array([-100.0, -100.0, -100.0, 0.0])
    for _ in range(200):
        q = rng.standard_normal(4)
        q /= np.linalg.norm(q)
        with bh.Filter(m, z) as f, bh.Filter(m, z) as g:
            f.update(np.round(q, 4), m, z)
            g.update(q, m, z)
            # the rounding moves the fix by at most ~1e-4: the posteriors agree to that
            assert abs(abs(f.mode() @ g.mode()) - 1) < 1e-6
    with bh.Filter(m, z) as f:
        with pytest.raises(bh.BinghamError) as e:
            f.update(1.01 * q, m, z)
        assert e.value.status == bh.Status.ERR_INVALID_ARGUMENT
        assert "normalize it first" in e.value.message
