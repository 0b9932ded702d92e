#!/usr/bin/env python3
"""A deterministic IMU simulator with known truth (gyroscope, accelerometer, magnetometer), for
measuring orientation filters (AHRS) on the same samples. NumPy only.

    from imu_sim import SimConfig, simulate
    sim = simulate(SimConfig(fs=100.0, duration=60.0, gyro_bias=(0.0035, -0.0035, 0.0035)))
    sim["gyr"], sim["acc"], sim["mag"]            # n×3 samples at t_k = k / fs, k = 0 … n−1
    sim["truth"]["quat"], sim["truth"]["bias"]    # n×4 orientation, the 3-vector gyro bias

Conventions: quaternions (w, x, y, z), scalar first, Hamilton product; the orientation q maps
the sensor (body) frame to the world frame, which is ENU (x east, y north, z up); R(q) is its
rotation matrix, so a world vector v reads R(q)ᵀ·v in the sensor frame. Units: s, rad, rad/s,
m/s², µT. Every random draw comes from ``numpy.random.SeedSequence(seed)`` split into
independent streams (motion, initial orientation, bursts, passing magnet, attached magnet, the
noise of each sensor; then, appended so that the earlier ones are unchanged: position, field,
timing jitter, drops), so switching one model on or off leaves the others' draws unchanged, and
the motion does not depend on the sample rate: the same ``seed`` at 100 Hz and at 1 kHz is the
same trajectory sampled differently (with its own noise realization).

Models and defaults (the fields of :class:`SimConfig`):

* **Angular velocity** ω(t) (body frame) = e(t)·(ω_base(t) + ω_spin(t)):
  - ω_base: per axis a sum of ``n_tones`` (5) sinusoids with frequencies uniform in
    ``omega_band`` (0.1–1.5 Hz), amplitudes uniform in [0.5, 1] and random phases, scaled so
    that max |ω_base| over [0, duration] (on a fixed 5 ms grid) is ``omega_max`` (3 rad/s). The
    axes change continuously; the spectrum ends at 1.5 Hz (band-limited, smooth).
  - ω_spin (``spin_rate``, default 0 = off): sustained spinning, ``spin_rate``·â(t) with â(t)
    the unit vector of a0 + ``spin_wander`` (0.5) × a sum of 3 sinusoids per axis of 0.01–0.05 Hz
    (a0 a random unit vector): an axis that wanders slowly (tens of degrees per minute) in the
    body frame. |ω| then reaches up to ``spin_rate`` + ``omega_max``.
  - e(t), the initial rest (``rest``, default 0 s): with rest > 0, e = 0 (the sensor is still)
    until ``rest``, then rises as a half cosine over ``ramp`` (1 s) to 1; with rest = 0, e ≡ 1
    (the motion is already under way at t = 0, also before it).
  ``omega_fn`` (a callable t[n] → n×3) replaces this model altogether (used by the tests).
  - a spin about the *world* vertical (``yaw_spin``, rad/s, default 0 = off): the orientation is
    q(t) = exp(ẑ·θ(t)) ⊗ q_b(t), q_b the body-rate motion above and θ̇ = W(t) = ``yaw_spin``
    rising by a half cosine over ``yaw_spin_ramp`` (2 s) from ``yaw_spin_time[0]`` and falling
    the same way from ``yaw_spin_time[1]`` (θ in closed form); the body rate is then
    ω = ω_b + R(q_b)ᵀ·ẑ·W (a turntable or a person turning on the spot, wobbling by ω_b).
* **Position** (``pos_amp``, m per world axis, default 0 = the rotation centre stays put): the
  rotation centre wanders through a volume, per axis a sum of ``pos_tones`` (3) sinusoids of
  frequencies uniform in ``pos_band`` (0.005–0.03 Hz: periods of 30–200 s, a slow walk about a
  motion-capture volume), amplitudes uniform in [0.5, 1], random phases, scaled so that
  max |p_i| over the run is ``pos_amp[i]``. Its acceleration p̈ (closed form) is part of the
  linear acceleration a(t) the accelerometer sees (at most a few cm/s² with these bands).
* **Orientation** (truth): q(0) has a uniform random heading and a tilt uniform in
  [0, ``tilt_max``] (20°) about a random horizontal axis (``q0`` overrides it); q(t) integrates
  q̇ = ½ q ⊗ (0, ω) on a fine grid (step ≤ ``fine_step`` = 1 ms, an integer fraction of the
  sample time) with the 4th-order Magnus step of two Gauss–Legendre nodes,
  θ = h/2·(ω₁ + ω₂) + √3/12·h²·(ω₁ × ω₂), q ← q ⊗ exp(θ) (local error O(h⁵); the step
  increments are composed by a parallel prefix product). Orientations between grid points
  (the magnetometer latency) are slerped.
* **Gyroscope**: gyr_k = (1 + s)∘ω̄_k + b + n, where ω̄_k is the mean body rate over (t_{k−1}, t_k]:
  exactly the rotation vector of q(t_{k−1})⁻¹ ⊗ q(t_k) divided by Ts, so that a filter that turns
  its estimate by exp(gyr_k·Ts) on sample k (VQF, Madgwick, the Bingham AHRS) reproduces the truth
  from noise-free, bias-free samples; it differs from the instantaneous ω(t_k − Ts/2) by
  O(Ts²) (``truth["omega"]`` holds the instantaneous ω(t_k)). b = ``gyro_bias`` (constant
  3-vector, rad/s, default 0); s = ``gyro_scale`` (per-axis scale error, default 0; a 0.2 %
  error turns 180 °/s into a 0.36 °/s drift); n white Gaussian, ``gyro_noise`` (0.005 rad/s)
  per axis.
* **Accelerometer**: the specific force in the body frame,
  acc_k = (1 + s_a)∘(R(q(t_k))ᵀ·(a(t_k) + (0, 0, g)) + ω̇×r + ω×(ω×r)) + o + n, with
  g = ``gravity`` (9.81 m/s², so +g up at rest), a(t) the linear acceleration of the rotation
  centre (world frame: bursts + p̈), n white, ``acc_noise`` (0.05 m/s²) per axis, and:
  - r = ``lever_arm`` (m, body frame, default 0): the accelerometer sits at r from the centre
    of rotation, so it also feels the tangential ω̇×r and centripetal ω×(ω×r) accelerations
    (ω, ω̇ the body rate and its derivative at t_k; ω̇ of the analytic base motion by a central
    difference of 0.1 ms, the spin about the vertical in closed form); truth ``acc_lever``;
  - o = ``acc_offset`` (m/s², per axis, default 0) and s_a = ``acc_scale`` (per-axis scale
    error, default 0): an uncalibrated accelerometer (typical MEMS: 0.1–0.2 m/s², 1–2 %).
  The burst model for a(t): bursts
  arrive as a Poisson process of rate ``burst_rate`` (per second, default 0 = none) from
  ``rest`` on; each has a duration uniform in ``burst_dur`` (0.3–1.5 s), a peak magnitude uniform
  in ``burst_amp`` (2–8 m/s²), a uniformly random world direction u, and the profile
  a(t) = A·u·sin(2πs)·sin²(πs)/c (s = (t − t₀)/duration ∈ [0, 1], c normalizing the peak to A):
  a push and a brake, so the velocity returns to zero after each burst.
* **Magnetometer**: mag_k = R(q(t_k − L))ᵀ·(m_loc(t_k − L) + d_pass(t_k − L)) + d_att(t_k − L)
  + n, µT:
  - m_E, the Earth field (the reference that defines north): magnitude ``mag_field`` (50 µT),
    dip ``mag_dip`` (60°, downward, north in +y): m_E = |m|·(0, cos dip, −sin dip);
  - m_loc = R(exp(δ))·m_E, the local field: the reference turned by the rotation vector
    δ = ``field_offset`` (constant, rad, default 0: a local offset no IMU can observe) + δ_v(p),
    a smooth function of the position p(t) (``field_var`` > 0, default 0 = off): per component a
    sum of ``field_modes`` (4) plane waves c·sin(k·p + φ), k of random direction and wavelength
    uniform in ``field_wavelength`` (3–8 m), c normal, scaled so that max |δ_v| along the run's
    trajectory is ``field_var`` (as steel in floors and walls bends the field of an indoor
    motion-capture volume by a few degrees; with the default position bands the offset is
    correlated over tens of seconds). Its norm is unchanged, its dip and heading move. Truth
    ``field_rotation`` (δ at each sample);
  - ``mag_flip_until`` (s, default None): before it, m_loc is turned 180° about the vertical (the
    same norm and dip, heading reversed): a filter that initializes its heading from its first
    samples starts 180° wrong;
  - L = ``mag_latency`` (s, default 0): the magnetometer sample k shows the field at t_k − L,
    the orientation there slerped between fine-grid points (latency also delays the
    disturbances: the whole channel lags);
  - d_pass, a magnet passing by (``pass_time`` t_c, default None = off): a point dipole of
    random fixed world direction m̂ moving on a straight line (random direction û, closest
    approach along a random n̂ ⊥ û) past the sensor; with s = (t − t_c)/``pass_tau`` the distance
    is r₀·√(1 + s²) and d_pass = K·(3(m̂·r̂)r̂ − m̂)/(1 + s²)^{3/2} (:func:`dipole_field`), K set so
    that |d_pass(t_c)| = ``pass_peak`` (40 µT). It rises and falls over a few ``pass_tau`` (1 s):
    its magnitude is at most 2K/(1 + s²)^{3/2} (below 1 % of the peak for |s| > 5.8);
  - d_att, a magnet attached to the sensor (``attach_time``, default None = off): a constant
    body-frame field of magnitude ``attach_field`` (20 µT) and random direction from
    ``attach_time`` on, switched on by a half cosine over ``attach_ramp`` (0.5 s), and off the
    same way from ``attach_end`` (default None: never);
  - n white, ``mag_noise`` (0.5 µT) per axis.
* **Noise levels** are per-sample standard deviations at ``noise_ref_rate`` (100 Hz); at another
  rate f they are scaled by √(f / noise_ref_rate) — a constant noise density, so the same
  sensor sampled faster has the same angle random walk (``noise_ref_rate=None``: no scaling).
* **The stream** (defaults: every sample, at t_k = k·Ts):
  - ``time_jitter`` J (fraction of Ts, < 0.5): the sampling instants are t_k = (k + J·u_k)·Ts,
    u_k uniform in [−1, 1] (u_0 = 0); every sensor samples at t_k (orientations off the fine
    grid by one more Magnus step from the grid point below) and the gyroscope's sample is the
    mean rate over the true interval (t_{k−1}, t_k]; the result's ``t`` holds the t_k, which a
    filter gets as timestamps;
  - ``drop_rate`` (fraction): each sample (all sensors together: a lost packet) is dropped
    independently with this probability (never the first); the sample after a drop still
    integrates only its own period (the dropped interval's turn is not in any sample);
  - ``acc_lost``, ``mag_lost`` ((start, end) s, default None): that sensor's rows are NaN for
    start ≤ t < end (a sensor that stops; the other sensors go on).
  ``sim["timed"]`` is True when the times are not k·Ts (jitter or drops).

Truth (``sim["truth"]``): ``quat`` (n×4, w ≥ 0), ``bias`` (3), ``omega`` (instantaneous ω(t_k)),
``gyr_clean`` (ω̄_k, before the scale error), ``lin_acc`` (a(t_k), world), ``quat_mag``
(q(t_k − L)), ``mag_earth`` (3), ``mag_pass`` (d_pass(t_k − L), world), ``mag_attached``
(d_att(t_k − L), body), ``acc_lever`` (ω̇×r + ω×(ω×r), body), ``position`` (p(t_k), world),
``field_rotation`` (δ(t_k − L)).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Callable, Optional, Tuple

import numpy as np

__all__ = ["SimConfig", "simulate", "motion", "dipole_field", "qmul", "qconj", "qexp", "qlog",
           "qrotate_inv", "quat_to_matrix", "slerp"]

DEG = math.pi / 180.0


@dataclasses.dataclass
class SimConfig:
    """Every model parameter of :func:`simulate` (see the module docstring); units s, rad, rad/s,
    m/s², µT."""

    fs: float = 100.0
    duration: float = 60.0
    seed: int = 0
    # motion
    omega_max: float = 3.0
    omega_band: Tuple[float, float] = (0.1, 1.5)
    n_tones: int = 5
    spin_rate: float = 0.0
    spin_wander: float = 0.5
    spin_band: Tuple[float, float] = (0.01, 0.05)
    rest: float = 0.0
    ramp: float = 1.0
    tilt_max: float = 20.0 * DEG
    yaw_spin: float = 0.0
    yaw_spin_time: Tuple[float, float] = (0.0, math.inf)
    yaw_spin_ramp: float = 2.0
    pos_amp: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    pos_band: Tuple[float, float] = (0.005, 0.03)
    pos_tones: int = 3
    omega_fn: Optional[Callable[[np.ndarray], np.ndarray]] = None
    q0: Optional[Tuple[float, float, float, float]] = None
    fine_step: float = 1e-3
    # gyroscope
    gyro_bias: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    gyro_noise: float = 0.005
    gyro_scale: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    # accelerometer
    gravity: float = 9.81
    acc_noise: float = 0.05
    burst_rate: float = 0.0
    burst_amp: Tuple[float, float] = (2.0, 8.0)
    burst_dur: Tuple[float, float] = (0.3, 1.5)
    lever_arm: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    acc_offset: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    acc_scale: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    # magnetometer
    mag_field: float = 50.0
    mag_dip: float = 60.0 * DEG
    mag_noise: float = 0.5
    mag_latency: float = 0.0
    pass_time: Optional[float] = None
    pass_peak: float = 40.0
    pass_tau: float = 1.0
    attach_time: Optional[float] = None
    attach_field: float = 20.0
    attach_ramp: float = 0.5
    attach_end: Optional[float] = None
    field_offset: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    field_var: float = 0.0
    field_wavelength: Tuple[float, float] = (3.0, 8.0)
    field_modes: int = 4
    mag_flip_until: Optional[float] = None
    # the stream: timestamps and lost samples
    time_jitter: float = 0.0
    drop_rate: float = 0.0
    acc_lost: Optional[Tuple[float, float]] = None
    mag_lost: Optional[Tuple[float, float]] = None
    # noise scaling with the sample rate
    noise_ref_rate: Optional[float] = 100.0


# ---- quaternions (…×4 arrays, scalar first) ---------------------------------------------------


def qmul(a, b):
    """Hamilton product a ⊗ b."""
    w1, x1, y1, z1 = np.moveaxis(np.asarray(a, dtype=float), -1, 0)
    w2, x2, y2, z2 = np.moveaxis(np.asarray(b, dtype=float), -1, 0)
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
                     w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                     w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], axis=-1)


def qconj(q):
    return np.asarray(q, dtype=float) * np.array([1.0, -1.0, -1.0, -1.0])


def qexp(theta):
    """The unit quaternion of the rotation vector θ (…×3): (cos |θ|/2, sin(|θ|/2)·θ/|θ|)."""
    theta = np.asarray(theta, dtype=float)
    a = np.linalg.norm(theta, axis=-1, keepdims=True)
    # sin(a/2)/a = 0.5·sinc(a/(2π)) with numpy's normalized sinc: exact at a = 0
    return np.concatenate([np.cos(a / 2.0), theta * (0.5 * np.sinc(a / (2.0 * np.pi)))], axis=-1)


def qlog(q):
    """The rotation vector (…×3) of the unit quaternion q (the shorter rotation, angle ≤ π)."""
    q = np.asarray(q, dtype=float)
    q = np.where(q[..., :1] < 0.0, -q, q)
    w, v = q[..., 0], q[..., 1:]
    s = np.linalg.norm(v, axis=-1)
    small = s < 1e-8  # there w ≈ 1: 2·atan2(s, w)/s = (2/w)(1 − s²/(3w²) + …)
    ww = np.where(small, w, 1.0)
    f = np.where(small, 2.0 / ww * (1.0 - s * s / (3.0 * ww * ww)),
                 2.0 * np.arctan2(s, w) / np.where(small, 1.0, s))
    return v * f[..., None]


def quat_to_matrix(q):
    """R(q) (…×3×3), the rotation of q: world = R·body."""
    w, x, y, z = np.moveaxis(np.asarray(q, dtype=float), -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
    ], axis=-2)


def qrotate_inv(q, v):
    """R(q)ᵀ·v: a world vector v (…×3 or 3) in the body frame of q (…×4)."""
    v = np.broadcast_to(v, np.shape(q)[:-1] + (3,))
    return np.einsum("...ji,...j->...i", quat_to_matrix(q), v)


def slerp(qa, qb, u):
    """Spherical interpolation qa ⊗ exp(u·log(qa⁻¹ ⊗ qb)), u ∈ [0, 1] (…)."""
    d = qlog(qmul(qconj(qa), qb))
    return qmul(qa, qexp(d * np.asarray(u, dtype=float)[..., None]))


def _prefix_product(dq):
    """P[i] = dq[0] ⊗ dq[1] ⊗ … ⊗ dq[i] (Hillis–Steele scan: log2(n) vectorized passes)."""
    p = np.array(dq, dtype=float)
    d = 1
    while d < len(p):
        p[d:] = qmul(p[:-d], p[d:])
        d *= 2
    return p / np.linalg.norm(p, axis=-1, keepdims=True)


def dipole_field(moment, r):
    """The field of a point dipole ``moment`` (…×3) at the displacement ``r`` (…×3), in units of
    µ0/4π: (3(m·r̂)r̂ − m)/|r|³."""
    r = np.asarray(r, dtype=float)
    m = np.asarray(moment, dtype=float)
    d = np.linalg.norm(r, axis=-1, keepdims=True)
    rh = r / d
    return (3.0 * np.sum(m * rh, axis=-1, keepdims=True) * rh - m) / d ** 3


# ---- the models -------------------------------------------------------------------------------


def _streams(seed):
    # new streams are appended: SeedSequence.spawn's children do not depend on how many are
    # spawned, so the earlier streams (and every run that uses only them) stay bit-identical
    names = ("motion", "orientation", "bursts", "pass", "attach", "gyr", "acc", "mag",
             "position", "field", "timing", "drops")
    return dict(zip(names, (np.random.default_rng(s)
                            for s in np.random.SeedSequence(seed).spawn(len(names)))))


def _unit(rng, n=None):
    v = rng.normal(size=(3,) if n is None else (n, 3))
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _tones(rng, n_tones, band, amp=(0.5, 1.0)):
    """(frequencies, amplitudes, phases), each 3×n_tones."""
    f = rng.uniform(band[0], band[1], size=(3, n_tones))
    a = rng.uniform(amp[0], amp[1], size=(3, n_tones))
    ph = rng.uniform(0.0, 2.0 * np.pi, size=(3, n_tones))
    return f, a, ph


def _eval_tones(tones, t):
    f, a, ph = tones
    t = np.asarray(t, dtype=float)[..., None, None]
    return np.sum(a * np.sin(2.0 * np.pi * f * t + ph), axis=-1)


def _envelope(cfg, t):
    t = np.asarray(t, dtype=float)
    if cfg.rest <= 0.0:
        return np.ones_like(t)
    s = np.clip((t - cfg.rest) / max(cfg.ramp, 1e-12), 0.0, 1.0)
    return 0.5 * (1.0 - np.cos(np.pi * s))


def motion(cfg: SimConfig) -> Callable[[np.ndarray], np.ndarray]:
    """The body rate ω(t) (n×3, rad/s) of the configuration: a function of time only (no
    dependence on the sample rate)."""
    if cfg.omega_fn is not None:
        return lambda t: np.asarray(cfg.omega_fn(np.asarray(t, dtype=float)), dtype=float)
    rng = _streams(cfg.seed)["motion"]
    base = _tones(rng, cfg.n_tones, cfg.omega_band)
    spin = _tones(rng, 3, cfg.spin_band)
    a0 = _unit(rng)
    grid = np.arange(0.0, max(cfg.duration, 0.005) + 1e-9, 0.005)
    peak = np.max(np.linalg.norm(_eval_tones(base, grid), axis=-1))
    scale = cfg.omega_max / peak if peak > 0 else 0.0

    def omega(t):
        t = np.asarray(t, dtype=float)
        w = scale * _eval_tones(base, t)
        if cfg.spin_rate:
            ax = a0 + cfg.spin_wander * _eval_tones(spin, t)
            w = w + cfg.spin_rate * ax / np.linalg.norm(ax, axis=-1, keepdims=True)
        return w * _envelope(cfg, t)[..., None]

    return omega


def _initial_orientation(cfg):
    if cfg.q0 is not None:
        q = np.asarray(cfg.q0, dtype=float)
        return q / np.linalg.norm(q)
    rng = _streams(cfg.seed)["orientation"]
    heading = rng.uniform(0.0, 2.0 * np.pi)
    tilt = rng.uniform(0.0, cfg.tilt_max)
    phi = rng.uniform(0.0, 2.0 * np.pi)
    return qmul(qexp([0.0, 0.0, heading]), qexp(tilt * np.array([np.cos(phi), np.sin(phi), 0.0])))


def _bursts(cfg, t):
    """Linear acceleration a(t) (n×3, world) of the burst model."""
    out = np.zeros(np.shape(t) + (3,))
    if cfg.burst_rate <= 0.0:
        return out
    rng = _streams(cfg.seed)["bursts"]
    s = np.linspace(0.0, 1.0, 2001)
    c = np.max(np.abs(np.sin(2 * np.pi * s) * np.sin(np.pi * s) ** 2))
    t0 = cfg.rest
    while True:
        t0 += rng.exponential(1.0 / cfg.burst_rate)
        if t0 >= cfg.duration:
            break
        dur = rng.uniform(*cfg.burst_dur)
        amp = rng.uniform(*cfg.burst_amp)
        u = _unit(rng)
        s = (t - t0) / dur
        inside = (s >= 0.0) & (s <= 1.0)
        prof = np.where(inside, np.sin(2 * np.pi * s) * np.sin(np.pi * s) ** 2, 0.0) / c
        out += amp * prof[..., None] * u
    return out


def _magnet_pass(cfg, t):
    """d_pass(t) (n×3, world, µT)."""
    out = np.zeros(np.shape(t) + (3,))
    if cfg.pass_time is None:
        return out
    rng = _streams(cfg.seed)["pass"]
    m = _unit(rng)
    u = _unit(rng)
    n = _unit(rng)
    n = n - np.dot(n, u) * u
    n /= np.linalg.norm(n)
    k = cfg.pass_peak / np.linalg.norm(dipole_field(m, n))
    s = (np.asarray(t, dtype=float) - cfg.pass_time) / cfg.pass_tau
    return k * dipole_field(m, n + s[..., None] * u)


def _magnet_attached(cfg, t):
    """d_att(t) (n×3, body, µT)."""
    out = np.zeros(np.shape(t) + (3,))
    if cfg.attach_time is None:
        return out
    d = cfg.attach_field * _unit(_streams(cfg.seed)["attach"])
    s = np.clip((np.asarray(t, dtype=float) - cfg.attach_time) / max(cfg.attach_ramp, 1e-12), 0, 1)
    on = 0.5 * (1.0 - np.cos(np.pi * s))
    if cfg.attach_end is not None:  # removed again: a half cosine down over attach_ramp
        s = np.clip((np.asarray(t, dtype=float) - cfg.attach_end) / max(cfg.attach_ramp, 1e-12),
                    0, 1)
        on = on * 0.5 * (1.0 + np.cos(np.pi * s))
    return on[..., None] * d


def _rise(s, r):
    """(∫ ramp, ramp, ramp') at s of the half-cosine ramp 0 → 1 over [0, r] (1 after)."""
    s = np.asarray(s, dtype=float)
    u = np.clip(s / r, 0.0, 1.0)
    integral = np.where(s <= 0.0, 0.0, np.where(s < r, 0.5 * (s - r / np.pi * np.sin(np.pi * u)),
                                                 s - 0.5 * r))
    inside = (s > 0.0) & (s < r)
    return (integral, 0.5 * (1.0 - np.cos(np.pi * u)),
            np.where(inside, 0.5 * np.pi / r * np.sin(np.pi * u), 0.0))


def _yaw(cfg, t):
    """(θ, W, Ẇ) (n each) of the spin about the world vertical: W(t) = ``yaw_spin``·e(t), e
    rising by a half cosine over ``yaw_spin_ramp`` from ``yaw_spin_time[0]`` and falling the
    same way from ``yaw_spin_time[1]``; θ(t) = ∫₀ᵗ W (closed form)."""
    t0, t1 = cfg.yaw_spin_time
    r = max(cfg.yaw_spin_ramp, 1e-9)
    a, b = _rise(np.asarray(t, dtype=float) - t0, r), _rise(np.asarray(t, dtype=float) - t1, r)
    a0, b0 = _rise(-t0, r)[0], _rise(-t1, r)[0]  # θ(0) = 0
    w = cfg.yaw_spin
    return w * ((a[0] - a0) - (b[0] - b0)), w * (a[1] - b[1]), w * (a[2] - b[2])


def _yaw_quat(theta):
    z = np.zeros(np.shape(theta) + (3,))
    z[..., 2] = theta
    return qexp(z)


def _position(cfg, t):
    """(p, p̈) (n×3 each, world, m and m/s²): the sensor's slow wander through a volume, per
    axis a sum of ``pos_tones`` sinusoids of ``pos_band`` with amplitudes uniform in [0.5, 1]
    and random phases, scaled so that max |p_i| over [0, duration] is ``pos_amp[i]``."""
    t = np.asarray(t, dtype=float)
    amp = np.asarray(cfg.pos_amp, dtype=float)
    if not np.any(amp):
        return np.zeros(t.shape + (3,)), np.zeros(t.shape + (3,))
    f, a, ph = _tones(_streams(cfg.seed)["position"], cfg.pos_tones, cfg.pos_band)
    grid = np.arange(0.0, max(cfg.duration, 0.05) + 1e-9, 0.05)
    peak = np.max(np.abs(_eval_tones((f, a, ph), grid)), axis=0)
    k = amp / np.where(peak > 0, peak, 1.0)
    p = k * _eval_tones((f, a, ph), t)
    acc = -k * _eval_tones((f, a * (2.0 * np.pi * f) ** 2, ph), t)
    return p, acc


def _field_rotation(cfg, p):
    """The rotation vector δ(p) (n×3, rad) by which the local field is turned from the reference
    at the position p: per component a sum of ``field_modes`` plane waves c·sin(k·p + φ) (k of
    random direction, wavelength uniform in ``field_wavelength``, c normal), scaled so that
    max |δ| over the run's trajectory (a 0.05-s grid) is ``field_var``; plus the constant
    ``field_offset``."""
    out = np.broadcast_to(np.asarray(cfg.field_offset, dtype=float), np.shape(p)).copy()
    if cfg.field_var <= 0.0:
        return out
    rng = _streams(cfg.seed)["field"]
    m = cfg.field_modes
    kdir = _unit(rng, m)
    lam = rng.uniform(cfg.field_wavelength[0], cfg.field_wavelength[1], size=m)
    kvec = kdir * (2.0 * np.pi / lam)[:, None]
    c = rng.normal(size=(m, 3))
    ph = rng.uniform(0.0, 2.0 * np.pi, size=m)

    def raw(q):
        return np.sin(np.asarray(q) @ kvec.T + ph) @ c

    grid = _position(cfg, np.arange(0.0, max(cfg.duration, 0.05) + 1e-9, 0.05))[0]
    peak = np.max(np.linalg.norm(raw(grid), axis=-1))
    return out + (cfg.field_var / peak if peak > 0 else 0.0) * raw(p)


def _window(t, w):
    """t in [w[0], w[1]) (all False for w None)."""
    t = np.asarray(t, dtype=float)
    return np.zeros(t.shape, dtype=bool) if w is None else (t >= w[0]) & (t < w[1])


def simulate(cfg: Optional[SimConfig] = None, **overrides) -> dict:
    """Samples and truth of one run (see the module docstring). ``overrides`` replace fields of
    ``cfg`` (or of the defaults). Returns a dict: fs, Ts, t (n: the samples' times), gyr, acc,
    mag (n×3), timed (True when the times are not k·Ts: jitter or drops; pass ``t`` to a
    filter as timestamps), truth (dict), config (the SimConfig)."""
    cfg = dataclasses.replace(cfg or SimConfig(), **overrides)
    fs = float(cfg.fs)
    ts = 1.0 / fs
    n = int(round(cfg.duration * fs))
    if n < 2:
        raise ValueError("duration too short for the sample rate")
    lat = float(cfg.mag_latency)
    if lat < 0:
        raise ValueError("mag_latency must be ≥ 0")
    if not 0.0 <= cfg.time_jitter < 0.5:
        raise ValueError("time_jitter must be in [0, 0.5)")
    if not 0.0 <= cfg.drop_rate < 1.0:
        raise ValueError("drop_rate must be in [0, 1)")
    jitter = cfg.time_jitter > 0.0
    sub = max(1, int(math.ceil(ts / cfg.fine_step - 1e-9)))  # fine steps per sample
    h = ts / sub
    pre = sub * (1 + int(math.ceil(lat / ts - 1e-9)))  # fine steps before t = 0
    extra = sub if jitter else 0  # fine steps after the last nominal sample time
    tj = (np.arange(pre + (n - 1) * sub + 1 + extra) - pre) * h  # the fine grid

    omega = motion(cfg)
    c = math.sqrt(3.0) / 6.0
    w1 = omega(tj[:-1] + (0.5 - c) * h)
    w2 = omega(tj[:-1] + (0.5 + c) * h)
    theta = 0.5 * h * (w1 + w2) + (math.sqrt(3.0) / 12.0) * h * h * np.cross(w1, w2)
    cum = _prefix_product(np.concatenate([[[1.0, 0.0, 0.0, 0.0]], qexp(theta)]))
    # anchor: q(0) = q_init, q(t) = q_init ⊗ P(0)⁻¹ ⊗ P(t)
    qgrid = qmul(qmul(_initial_orientation(cfg), qconj(cum[pre])), cum)
    qgrid /= np.linalg.norm(qgrid, axis=-1, keepdims=True)
    qbase = qgrid  # the body-rate motion alone (without the spin about the world vertical)
    yaw = cfg.yaw_spin != 0.0
    rng = _streams(cfg.seed)

    def base_at(times):
        """The body-rate motion's orientation at arbitrary times: one Magnus step (of the
        fine grid's order) from the grid point at or below each time."""
        j = np.clip(np.floor((times - tj[0]) / h + 1e-9).astype(int), 0, len(tj) - 2)
        d = (times - tj[j])[:, None]
        v1 = omega(tj[j] + (0.5 - c) * d[:, 0])
        v2 = omega(tj[j] + (0.5 + c) * d[:, 0])
        th = 0.5 * d * (v1 + v2) + (math.sqrt(3.0) / 12.0) * d * d * np.cross(v1, v2)
        out = qmul(qbase[j], qexp(th))
        return out / np.linalg.norm(out, axis=-1, keepdims=True)

    def with_yaw(qb, times):
        if not yaw:
            return qb
        out = qmul(_yaw_quat(_yaw(cfg, times)[0]), qb)
        return out / np.linalg.norm(out, axis=-1, keepdims=True)

    if jitter:
        # the sampling instants jitter: t_k = (k + J·u_k)·Ts, u_k uniform in [−1, 1] (u_0 = 0);
        # every sensor samples at t_k, and the gyroscope's sample is the mean rate over
        # (t_{k−1}, t_k] (t_{−1} = −Ts)
        u = rng["timing"].uniform(-1.0, 1.0, size=n)
        u[0] = 0.0
        t = (np.arange(n) + cfg.time_jitter * u) * ts
        t_prev = np.concatenate([[-ts], t[:-1]])
        qb = base_at(t)
        q = with_yaw(qb, t)
        gyr_clean = qlog(qmul(qconj(with_yaw(base_at(t_prev), t_prev)), q)) / (t - t_prev)[:, None]
        q_mag = q if lat == 0.0 else with_yaw(base_at(t - lat), t - lat)
    else:
        if yaw:
            qgrid = with_yaw(qbase, tj)
        idx = pre + sub * np.arange(n)
        t = np.arange(n) * ts
        q = qgrid[idx]
        qb = qbase[idx]
        gyr_clean = qlog(qmul(qconj(qgrid[idx - sub]), q)) / ts

        # orientation at t_k − L: slerp between the fine-grid points around it
        pos = idx - lat / h
        lo = np.clip(np.floor(pos + 1e-9).astype(int), 0, len(tj) - 2)
        frac = np.clip(pos - lo, 0.0, 1.0)
        q_mag = slerp(qgrid[lo], qgrid[lo + 1], frac)
        q_mag /= np.linalg.norm(q_mag, axis=-1, keepdims=True)

    # the body rate (truth) and, for the lever arm, its derivative
    w_body = omega(t)
    if yaw:
        _, yw, ywd = _yaw(cfg, t)
        up = qrotate_inv(qb, np.array([0.0, 0.0, 1.0]))  # the world vertical in the base frame
        w_base = w_body
        w_body = w_base + up * yw[:, None]
    lever = np.asarray(cfg.lever_arm, dtype=float).reshape(3)
    acc_lever = np.zeros((n, 3))
    if np.any(lever):
        dt_fd = 1e-4  # ω̇ of the (smooth, analytic) base motion by a central difference
        w_dot = (omega(t + dt_fd) - omega(t - dt_fd)) / (2.0 * dt_fd)
        if yaw:
            w_dot = w_dot - np.cross(w_base, up * yw[:, None]) + up * ywd[:, None]
        acc_lever = np.cross(w_dot, lever) + np.cross(w_body, np.cross(w_body, lever))

    lin_acc = _bursts(cfg, t)
    position, p_dd = _position(cfg, t)
    if np.any(cfg.pos_amp):
        lin_acc = lin_acc + p_dd
    f_world = lin_acc + np.array([0.0, 0.0, cfg.gravity])
    m_earth = cfg.mag_field * np.array([0.0, math.cos(cfg.mag_dip), -math.sin(cfg.mag_dip)])
    t_mag = t - lat
    d_pass = _magnet_pass(cfg, t_mag)
    d_att = _magnet_attached(cfg, t_mag)
    m_local = m_earth
    field_rot = np.zeros((n, 3))
    if cfg.field_var > 0.0 or np.any(cfg.field_offset):
        field_rot = _field_rotation(cfg, _position(cfg, t_mag)[0])
        m_local = np.einsum("nij,j->ni", quat_to_matrix(qexp(field_rot)), m_earth)
    if cfg.mag_flip_until is not None:
        flip = (t_mag < cfg.mag_flip_until)[:, None] * np.array([1.0, 1.0, 0.0])
        m_local = np.broadcast_to(m_local, (n, 3)) * (1.0 - 2.0 * flip)

    scale = 1.0 if cfg.noise_ref_rate is None else math.sqrt(fs / cfg.noise_ref_rate)
    bias = np.asarray(cfg.gyro_bias, dtype=float).reshape(3)
    gyr_true = gyr_clean
    if np.any(cfg.gyro_scale):
        gyr_true = gyr_clean * (1.0 + np.asarray(cfg.gyro_scale, dtype=float))
    gyr = gyr_true + bias + cfg.gyro_noise * scale * rng["gyr"].normal(size=(n, 3))
    f_body = qrotate_inv(q, f_world)
    if np.any(lever):
        f_body = f_body + acc_lever
    if np.any(cfg.acc_scale):
        f_body = f_body * (1.0 + np.asarray(cfg.acc_scale, dtype=float))
    if np.any(cfg.acc_offset):
        f_body = f_body + np.asarray(cfg.acc_offset, dtype=float)
    acc = f_body + cfg.acc_noise * scale * rng["acc"].normal(size=(n, 3))
    mag = (qrotate_inv(q_mag, m_local + d_pass) + d_att
           + cfg.mag_noise * scale * rng["mag"].normal(size=(n, 3)))
    acc[_window(t, cfg.acc_lost)] = np.nan
    mag[_window(t, cfg.mag_lost)] = np.nan

    sign = np.where(q[:, :1] < 0.0, -1.0, 1.0)
    truth = {"quat": q * sign, "bias": bias, "omega": w_body, "gyr_clean": gyr_clean,
             "lin_acc": lin_acc, "quat_mag": q_mag, "mag_earth": m_earth, "mag_pass": d_pass,
             "mag_attached": d_att, "acc_lever": acc_lever, "position": position,
             "field_rotation": field_rot}
    if cfg.drop_rate > 0.0:
        keep = rng["drops"].random(n) >= cfg.drop_rate
        keep[0] = True
        t, gyr, acc, mag = t[keep], gyr[keep], acc[keep], mag[keep]
        per_sample = ("quat", "omega", "gyr_clean", "lin_acc", "quat_mag", "mag_pass",
                      "mag_attached", "acc_lever", "position", "field_rotation")
        truth = {k: (v[keep] if k in per_sample else v) for k, v in truth.items()}
    return {"fs": fs, "Ts": ts, "t": t, "timed": bool(jitter or cfg.drop_rate > 0.0),
            "gyr": np.ascontiguousarray(gyr), "acc": np.ascontiguousarray(acc),
            "mag": np.ascontiguousarray(mag), "truth": truth, "config": cfg}


if __name__ == "__main__":
    import time

    t0 = time.perf_counter()
    sim = simulate(SimConfig(gyro_bias=(0.01, 0.01, 0.01), rest=2.0))
    print(f"{len(sim['t'])} samples in {time.perf_counter() - t0:.3f} s; "
          f"max |ω| {np.max(np.linalg.norm(sim['truth']['omega'], axis=1)):.2f} rad/s")
