"""The IMU simulator of the AHRS suite (examples/python/imu_sim.py) against independent checks:
closed-form motion, the kinematics by finite differences, the physics of each sensor model.

Nothing here runs an orientation filter: the simulator is the measuring stick of the AHRS
suite (examples/python/ahrs_suite.py), so it is checked on its own.
"""

import math
import os
import sys

import numpy as np
import pytest

# imu_sim.py is an example program (examples/python/), not part of the package
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples", "python"))
import imu_sim as sim_mod  # noqa: E402
from imu_sim import SimConfig, qconj, qexp, qmul, qrotate_inv, simulate  # noqa: E402

QUIET = dict(gyro_noise=0.0, acc_noise=0.0, mag_noise=0.0)


def angle(a, b):
    """Angle (rad) of the rotation between unit quaternions (accurate near 0)."""
    return np.linalg.norm(sim_mod.qlog(qmul(qconj(a), b)), axis=-1)


# a precession with a closed form: q(t) = exp(ẑ·α·t) ⊗ B ⊗ exp(ẑ·γ·t), whose body rate is
# ω(t) = R(B ⊗ exp(ẑγt))ᵀ·(0, 0, α) + (0, 0, γ)
ALPHA, GAMMA = 1.3, -2.1
B = qexp([0.7, 0.2, 0.0])


def precession_q(t):
    t = np.asarray(t, dtype=float)[..., None]
    z = np.array([0.0, 0.0, 1.0])
    return qmul(qmul(qexp(z * ALPHA * t), B), qexp(z * GAMMA * t))


def precession_omega(t):
    c = qexp(np.array([0.0, 0.0, GAMMA]) * np.asarray(t, dtype=float)[..., None])
    return qrotate_inv(qmul(B, c), np.array([0.0, 0.0, ALPHA])) + np.array([0.0, 0.0, GAMMA])


@pytest.mark.parametrize("fs", [50.0, 100.0, 1000.0])
def test_orientation_matches_a_closed_form_motion(fs):
    s = simulate(SimConfig(fs=fs, duration=30.0, omega_fn=precession_omega, q0=tuple(B), **QUIET))
    assert np.max(angle(s["truth"]["quat"], precession_q(s["t"]))) < 1e-10


def test_orientation_integration_converges_at_fourth_order():
    kw = dict(duration=20.0, seed=3, spin_rate=5.0, **QUIET)
    ref = simulate(SimConfig(fine_step=2.5e-4, **kw))["truth"]["quat"]
    e10 = np.max(angle(simulate(SimConfig(fine_step=0.01, **kw))["truth"]["quat"], ref))
    e5 = np.max(angle(simulate(SimConfig(fine_step=0.005, **kw))["truth"]["quat"], ref))
    assert e10 < 1e-6
    assert 10.0 < e10 / e5 < 25.0  # 2⁴ = 16


def test_kinematics_by_finite_differences():
    # q̇ = ½ q ⊗ (0, ω): central differences of the truth against the motion's own ω(t)
    s = simulate(SimConfig(fs=1000.0, duration=10.0, seed=5, spin_rate=3.0, **QUIET))
    q, ts = s["truth"]["quat"], s["Ts"]
    # the truth has w ≥ 0; undo its sign flips for a continuous path
    flips = np.concatenate([[0], np.cumsum(np.sum(q[1:] * q[:-1], axis=1) < 0)])
    q = q * np.where(flips % 2 == 1, -1.0, 1.0)[:, None]
    dq = (q[2:] - q[:-2]) / (2.0 * ts)
    w = np.concatenate([np.zeros((len(q) - 2, 1)), s["truth"]["omega"][1:-1]], axis=1)
    expect = 0.5 * qmul(q[1:-1], w)
    assert np.max(np.abs(dq - expect)) < 5e-5  # O(Ts²) of central differences (measured 8e-6)


def test_same_motion_at_every_sample_rate():
    a = simulate(SimConfig(fs=100.0, duration=20.0, seed=7))
    b = simulate(SimConfig(fs=1000.0, duration=20.0, seed=7))
    c = simulate(SimConfig(fs=250.0, duration=20.0, seed=7))
    assert np.max(angle(a["truth"]["quat"], b["truth"]["quat"][::10])) < 1e-10
    assert np.max(angle(c["truth"]["quat"][::5], b["truth"]["quat"][::20])) < 1e-10


def test_gyro_integrated_back_reproduces_the_truth():
    bias = (0.01, -0.02, 0.005)
    s = simulate(SimConfig(duration=30.0, rest=2.0, gyro_bias=bias, gyro_noise=0.0))
    q = s["truth"]["quat"][0]
    out = [q]
    for g in s["gyr"][1:]:
        q = qmul(q, qexp((g - np.array(bias)) * s["Ts"]))
        out.append(q)
    assert np.max(angle(np.array(out), s["truth"]["quat"])) < 1e-10


def test_gyro_is_the_mean_rate_over_the_preceding_interval():
    # against the instantaneous rate at the interval's midpoint: the difference is O(Ts²)
    diffs = []
    for fs in (100.0, 200.0):
        s = simulate(SimConfig(fs=fs, duration=20.0, seed=2, **QUIET))
        omega = sim_mod.motion(s["config"])
        d = s["gyr"][1:] - omega(s["t"][1:] - s["Ts"] / 2.0)
        diffs.append(np.max(np.abs(d)))
    assert diffs[0] < 2e-3
    assert 3.0 < diffs[0] / diffs[1] < 5.0


def test_gyro_bias_and_noise_statistics():
    bias = np.array([0.004, -0.009, 0.002])
    for fs, scale in ((100.0, 1.0), (400.0, 2.0)):
        s = simulate(SimConfig(fs=fs, duration=60.0, gyro_bias=tuple(bias)))
        r = s["gyr"] - s["truth"]["gyr_clean"]
        n = len(r)
        sigma = 0.005 * scale  # noise of constant density: ×√(fs/100)
        assert np.all(np.abs(r.mean(axis=0) - bias) < 5.0 * sigma / math.sqrt(n))
        assert np.all(np.abs(r.std(axis=0) / sigma - 1.0) < 0.05)
    s = simulate(SimConfig(fs=400.0, duration=10.0, noise_ref_rate=None))
    assert abs(np.std(s["gyr"] - s["truth"]["gyr_clean"]) / 0.005 - 1.0) < 0.05


def test_motion_limits_and_rest():
    s = simulate(SimConfig(duration=30.0, rest=5.0, omega_max=2.5, gyro_bias=(0.01, 0.0, 0.0),
                           **QUIET))
    w = np.linalg.norm(s["truth"]["omega"], axis=1)
    assert np.max(w) <= 2.5 + 1e-9 and np.max(w) > 2.0
    still = s["t"] < 5.0
    assert np.all(w[still] == 0.0)
    assert np.max(angle(s["truth"]["quat"][still], s["truth"]["quat"][:1])) < 1e-14
    assert np.allclose(s["gyr"][still][1:], [0.01, 0.0, 0.0], atol=1e-14, rtol=0)
    spin = simulate(SimConfig(duration=30.0, spin_rate=6.0, omega_max=0.0, **QUIET))
    assert np.allclose(np.linalg.norm(spin["truth"]["omega"], axis=1), 6.0)


def test_accelerometer_at_rest_is_gravity_in_the_body_frame():
    s = simulate(SimConfig(duration=10.0, rest=4.0, **QUIET))
    q = s["truth"]["quat"]
    still = s["t"] < 4.0
    # R(q)ᵀ·(0, 0, g), with R built independently of the simulator's helper
    w, x, y, z = q.T
    expect = 9.81 * np.stack([2 * (x * z - w * y), 2 * (y * z + w * x),
                              1 - 2 * (x * x + y * y)], axis=1)
    assert np.max(np.abs(s["acc"] - expect)) < 1e-12  # no linear acceleration by default
    assert np.allclose(np.linalg.norm(s["acc"][still], axis=1), 9.81, atol=1e-12, rtol=0)


def test_linear_acceleration_bursts():
    s = simulate(SimConfig(duration=60.0, burst_rate=0.5, **QUIET))
    a = s["truth"]["lin_acc"]
    mag = np.linalg.norm(a, axis=1)
    assert np.max(mag) <= 8.0 + 1e-9 and np.mean(mag > 0.5) > 0.05
    grav = qrotate_inv(s["truth"]["quat"], np.array([0.0, 0.0, 9.81]))
    assert np.max(np.abs(s["acc"] - grav - qrotate_inv(s["truth"]["quat"], a))) < 1e-12
    # every burst is a push and a brake: the velocity returns to zero between bursts (fine grid)
    cfg = s["config"]
    t = np.arange(0.0, 50.0, 1e-4)
    v = np.cumsum(sim_mod._bursts(cfg, t), axis=0) * 1e-4
    quiet = np.linalg.norm(sim_mod._bursts(cfg, t), axis=1) == 0.0
    assert np.max(np.linalg.norm(v[quiet], axis=1)) < 1e-3
    # the bursts do not change the motion or the other sensors
    plain = simulate(SimConfig(duration=60.0, **QUIET))
    assert np.array_equal(plain["gyr"], s["gyr"]) and np.array_equal(plain["mag"], s["mag"])


def test_magnetometer_is_the_earth_field_in_the_body_frame():
    s = simulate(SimConfig(duration=20.0, **QUIET))
    assert np.allclose(np.linalg.norm(s["mag"], axis=1), 50.0, atol=1e-10, rtol=0)
    # with gravity (no linear acceleration): the angle between the field and "up" is 90° + dip
    cosang = np.sum(s["mag"] * s["acc"], axis=1) / (50.0 * 9.81)
    assert np.allclose(np.degrees(np.arccos(cosang)), 150.0, atol=1e-8)
    # the horizontal part points north: the field in the world frame via the truth
    world = np.einsum("nij,nj->ni", sim_mod.quat_to_matrix(s["truth"]["quat"]), s["mag"])
    assert np.allclose(world, [0.0, 25.0, -50.0 * math.sin(math.radians(60.0))], atol=1e-10)


def test_magnetometer_latency_shows_the_earlier_field():
    plain = simulate(SimConfig(duration=20.0, **QUIET))
    late = simulate(SimConfig(duration=20.0, mag_latency=0.02, **QUIET))  # two samples
    assert np.max(np.abs(late["mag"][2:] - plain["mag"][:-2])) < 1e-10
    # the other sensors are unchanged (to rounding: the fine grid starts earlier)
    assert np.allclose(late["gyr"], plain["gyr"], atol=1e-12, rtol=0)
    assert np.allclose(late["acc"], plain["acc"], atol=1e-12, rtol=0)
    # between grid points (slerp): 7.5 ms against the undelayed run at 400 Hz, t_k − 7.5 ms
    odd = simulate(SimConfig(duration=20.0, mag_latency=0.0075, **QUIET))
    fast = simulate(SimConfig(fs=400.0, duration=20.0, **QUIET))
    k = np.arange(1, len(odd["t"]))
    assert np.max(np.abs(odd["mag"][k] - fast["mag"][4 * k - 3])) < 1e-3  # µT of 50


def test_dipole_field():
    m = np.array([0.3, -1.0, 0.4])
    r = np.array([0.5, 0.2, -0.9])
    b1, b2 = sim_mod.dipole_field(m, r), sim_mod.dipole_field(m, 2.0 * r)
    assert np.allclose(b2, b1 / 8.0, rtol=1e-14, atol=0)  # falls off as 1/r³
    along = sim_mod.dipole_field(m, m)  # on the axis: 2m/|r|³; across: −m/|r|³
    assert np.allclose(along, 2.0 * m / np.linalg.norm(m) ** 3)
    side = np.cross(m, [1.0, 0.0, 0.0])
    assert np.allclose(sim_mod.dipole_field(m, side), -m / np.linalg.norm(side) ** 3)


def test_magnet_passing_by_rises_and_falls():
    s = simulate(SimConfig(duration=40.0, pass_time=20.0, pass_peak=40.0, pass_tau=1.0, **QUIET))
    d = s["truth"]["mag_pass"]
    mag = np.linalg.norm(d, axis=1)
    t = s["t"]
    assert abs(mag[np.argmin(np.abs(t - 20.0))] - 40.0) < 1e-9
    assert abs(t[np.argmax(mag)] - 20.0) < 1.0
    # |B| = K·|3(m̂·r̂)r̂ − m̂|/(1 + s²)^{3/2} with peak/2 ≤ K ≤ peak: at most 2·peak/(1 + s²)^{3/2}
    bound = 2.0 * 40.0 / (1.0 + (t - 20.0) ** 2) ** 1.5
    assert np.all(mag <= bound + 1e-9)
    assert np.all(mag[np.abs(t - 20.0) > 6.0] < 0.4)  # below 1 % of the peak
    plain = simulate(SimConfig(duration=40.0, **QUIET))
    assert np.max(np.abs(s["mag"] - plain["mag"] - qrotate_inv(s["truth"]["quat"], d))) < 1e-10


def test_magnet_attached_is_constant_in_the_body_frame():
    s = simulate(SimConfig(duration=20.0, attach_time=8.0, attach_field=20.0, **QUIET))
    plain = simulate(SimConfig(duration=20.0, **QUIET))
    d = s["mag"] - plain["mag"]
    t = s["t"]
    assert np.all(d[t < 8.0] == 0.0)
    after = d[t >= 8.5]
    assert np.allclose(after, after[0], atol=1e-10, rtol=0)
    assert abs(np.linalg.norm(after[0]) - 20.0) < 1e-10


def test_deterministic_and_seeded():
    a = simulate(SimConfig(duration=5.0, seed=11, gyro_bias=(0.01, 0.0, 0.0)))
    b = simulate(SimConfig(duration=5.0, seed=11, gyro_bias=(0.01, 0.0, 0.0)))
    c = simulate(SimConfig(duration=5.0, seed=12, gyro_bias=(0.01, 0.0, 0.0)))
    for k in ("gyr", "acc", "mag"):
        assert np.array_equal(a[k], b[k])
        assert not np.array_equal(a[k], c[k])
    assert np.array_equal(a["truth"]["quat"], b["truth"]["quat"])


# ---- issue 34's models: lever arm, position and local field, calibration errors, the stream ----

LEVER = np.array([0.12, -0.2, 0.05])


def second_difference_in_body(s, p_world):
    """The acceleration of a world trajectory p (n×3) by central second differences, in the
    body frame of the truth (samples 1 … n−2)."""
    ts = s["Ts"]
    pdd = (p_world[2:] - 2.0 * p_world[1:-1] + p_world[:-2]) / ts ** 2
    return qrotate_inv(s["truth"]["quat"][1:-1], pdd)


@pytest.mark.parametrize("spin", [False, True])
def test_lever_arm_matches_the_offset_points_acceleration(spin):
    # the accelerometer at r from the rotation centre: its position is R(q)·r (the centre
    # fixed), whose second difference, seen in the body frame, must be the simulator's
    # ω̇×r + ω×(ω×r) (computed from the body rate, not from the orientation)
    extra = dict(yaw_spin=2.5, yaw_spin_time=(3.0, 15.0), omega_max=1.0) if spin else {}
    s = simulate(SimConfig(fs=1000.0, duration=20.0, seed=4, lever_arm=tuple(LEVER), **QUIET,
                           **extra))
    p = np.einsum("nij,j->ni", sim_mod.quat_to_matrix(s["truth"]["quat"]), LEVER)
    lever = s["truth"]["acc_lever"]
    assert np.max(np.linalg.norm(lever, axis=1)) > 1.0  # a real effect (m/s²)
    assert np.max(np.abs(second_difference_in_body(s, p) - lever[1:-1])) < 5e-4  # O(Ts²)
    # it is what the accelerometer adds, and nothing else changes
    plain = simulate(SimConfig(fs=1000.0, duration=20.0, seed=4, **QUIET, **extra))
    assert np.max(np.abs(s["acc"] - plain["acc"] - lever)) < 1e-12
    assert np.array_equal(s["gyr"], plain["gyr"]) and np.array_equal(s["mag"], plain["mag"])


def test_spin_about_the_world_vertical():
    w = math.radians(150.0)
    s = simulate(SimConfig(duration=30.0, seed=3, yaw_spin=w, yaw_spin_time=(5.0, 25.0),
                           omega_max=0.0, **QUIET))
    t, rate = s["t"], np.linalg.norm(s["truth"]["omega"], axis=1)
    assert np.allclose(rate[(t > 7.0) & (t < 25.0)], w, rtol=0, atol=1e-12)
    assert np.all(rate[(t < 5.0) | (t > 27.0)] < 1e-12)
    # the body's vertical stays put in the world (the spin is about the world vertical)
    up = qrotate_inv(s["truth"]["quat"], np.array([0.0, 0.0, 1.0]))
    assert np.max(np.abs(up - up[0])) < 1e-9
    # the gyroscope integrated back reproduces the truth (ramps included)
    q = s["truth"]["quat"][0]
    out = [q]
    for g in s["gyr"][1:]:
        q = qmul(q, qexp(g * s["Ts"]))
        out.append(q)
    assert np.max(angle(np.array(out), s["truth"]["quat"])) < 1e-10


def test_position_and_its_acceleration():
    s = simulate(SimConfig(fs=200.0, duration=60.0, seed=6, pos_amp=(1.5, 1.0, 0.3), **QUIET))
    p = s["truth"]["position"]
    assert np.allclose(np.max(np.abs(p), axis=0), [1.5, 1.0, 0.3], rtol=1e-3)
    # p̈ (closed form, in lin_acc) against second differences of p
    pdd = (p[2:] - 2.0 * p[1:-1] + p[:-2]) / s["Ts"] ** 2
    assert np.max(np.abs(pdd - s["truth"]["lin_acc"][1:-1])) < 1e-6
    plain = simulate(SimConfig(fs=200.0, duration=60.0, seed=6, **QUIET))
    assert np.max(np.abs(s["acc"] - plain["acc"]
                         - qrotate_inv(s["truth"]["quat"], s["truth"]["lin_acc"]))) < 1e-12
    assert np.array_equal(s["gyr"], plain["gyr"]) and np.array_equal(s["mag"], plain["mag"])


def test_local_field_offsets():
    m_e = 50.0 * np.array([0.0, math.cos(math.radians(60.0)), -math.sin(math.radians(60.0))])
    # a constant offset turns the world field, nothing else
    off = (0.0, 0.0, math.radians(1.5))
    s = simulate(SimConfig(duration=20.0, field_offset=off, **QUIET))
    world = np.einsum("nij,nj->ni", sim_mod.quat_to_matrix(s["truth"]["quat"]), s["mag"])
    c, sn = math.cos(off[2]), math.sin(off[2])
    assert np.allclose(world, [c * m_e[0] - sn * m_e[1], sn * m_e[0] + c * m_e[1], m_e[2]],
                       atol=1e-10, rtol=0)
    # over the volume: up to field_var, the norm kept, smooth along the slow trajectory
    s = simulate(SimConfig(duration=60.0, seed=8, pos_amp=(1.5, 1.5, 0.3),
                           field_var=math.radians(6.0), **QUIET))
    d = np.linalg.norm(s["truth"]["field_rotation"], axis=1)
    assert abs(np.max(d) - math.radians(6.0)) < math.radians(0.05)
    assert np.allclose(np.linalg.norm(s["mag"], axis=1), 50.0, atol=1e-10, rtol=0)
    assert np.max(np.abs(np.diff(d))) < math.radians(0.01)  # per 10 ms
    world = np.einsum("nij,nj->ni", sim_mod.quat_to_matrix(s["truth"]["quat"]), s["mag"])
    expect = np.einsum("nij,j->ni", sim_mod.quat_to_matrix(qexp(s["truth"]["field_rotation"])),
                       m_e)
    assert np.allclose(world, expect, atol=1e-10, rtol=0)


def test_reversed_start_field():
    s = simulate(SimConfig(duration=5.0, mag_flip_until=0.5, **QUIET))
    plain = simulate(SimConfig(duration=5.0, **QUIET))
    world = np.einsum("nij,nj->ni", sim_mod.quat_to_matrix(s["truth"]["quat"]), s["mag"])
    early = s["t"] < 0.5
    assert np.allclose(world[early], [0.0, -25.0, -50.0 * math.sin(math.radians(60.0))],
                       atol=1e-10)
    assert np.array_equal(s["mag"][~early], plain["mag"][~early])


def test_calibration_errors():
    kw = dict(duration=20.0, seed=2)
    plain = simulate(SimConfig(**kw))
    off, sc = np.array([0.15, -0.1, 0.2]), np.array([0.015, -0.01, 0.02])
    gs = np.array([2e-3, 0.0, -1e-3])
    s = simulate(SimConfig(acc_offset=tuple(off), acc_scale=tuple(sc), gyro_scale=tuple(gs), **kw))
    noise = plain["acc"] - qrotate_inv(plain["truth"]["quat"], np.array([0.0, 0.0, 9.81]))
    assert np.allclose(s["acc"], (plain["acc"] - noise) * (1.0 + sc) + off + noise, atol=1e-12)
    assert np.allclose(s["gyr"] - plain["gyr"], plain["truth"]["gyr_clean"] * gs, atol=1e-15)
    assert np.array_equal(s["mag"], plain["mag"])


def test_jittered_sampling_instants():
    # the precession's closed form at the jittered times: the truth off the fine grid
    s = simulate(SimConfig(fs=100.0, duration=30.0, time_jitter=0.1, omega_fn=precession_omega,
                           q0=tuple(B), **QUIET))
    t, ts = s["t"], s["Ts"]
    assert s["timed"] and t[0] == 0.0
    dev = t - np.arange(len(t)) * ts
    assert np.max(np.abs(dev)) <= 0.1 * ts + 1e-15 and np.max(np.abs(dev)) > 0.09 * ts
    assert np.max(angle(s["truth"]["quat"], precession_q(t))) < 1e-10
    # the gyroscope is the mean rate over the true interval: integrated with the timestamps'
    # steps, it reproduces the truth
    s = simulate(SimConfig(duration=20.0, seed=3, time_jitter=0.1, yaw_spin=2.0,
                           yaw_spin_time=(2.0, 10.0), **QUIET))
    t = s["t"]
    q = s["truth"]["quat"][0]
    out = [q]
    for k in range(1, len(t)):
        q = qmul(q, qexp(s["gyr"][k] * (t[k] - t[k - 1])))
        out.append(q)
    assert np.max(angle(np.array(out), s["truth"]["quat"])) < 1e-10


def test_dropped_and_lost_samples():
    kw = dict(duration=60.0, seed=3)
    full = simulate(SimConfig(**kw))
    s = simulate(SimConfig(drop_rate=0.05, **kw))
    assert s["timed"] and not full["timed"]
    keep = np.searchsorted(full["t"], s["t"])
    assert np.array_equal(full["t"][keep], s["t"])
    assert abs(1.0 - len(keep) / len(full["t"]) - 0.05) < 0.01
    for k in ("gyr", "acc", "mag"):  # the same samples, less the dropped ones
        assert np.array_equal(full[k][keep], s[k])
    assert np.array_equal(full["truth"]["quat"][keep], s["truth"]["quat"])
    lost = simulate(SimConfig(acc_lost=(30.0, 40.0), mag_lost=(25.0, 45.0), **kw))
    t = lost["t"]
    a_gone, m_gone = (t >= 30.0) & (t < 40.0), (t >= 25.0) & (t < 45.0)
    assert np.all(np.isnan(lost["acc"][a_gone])) and np.all(np.isnan(lost["mag"][m_gone]))
    assert np.array_equal(lost["acc"][~a_gone], full["acc"][~a_gone])
    assert np.array_equal(lost["mag"][~m_gone], full["mag"][~m_gone])
    assert np.array_equal(lost["gyr"], full["gyr"])


def test_attached_magnet_removed_again():
    s = simulate(SimConfig(duration=20.0, attach_time=5.0, attach_end=12.0, **QUIET))
    d = s["truth"]["mag_attached"]
    t = s["t"]
    assert np.allclose(np.linalg.norm(d[(t > 5.5) & (t < 12.0)], axis=1), 20.0)
    assert np.all(d[(t < 5.0) | (t >= 12.5)] == 0.0)
