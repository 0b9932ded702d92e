#!/usr/bin/env python3
"""Orientation tracking with nonlinear models: a nonlinear rate law for the prediction and a
camera (pinhole projection) for the measurement, through ``Filter.predict_nonlinear`` and
``Filter.update_nonlinear``.

    usage: python3 examples/python/nonlinear.py [steps] [seed]

The body (orientation q, a unit quaternion, scalar first, body → world) sits at a known position
in front of a fixed pinhole camera (the world frame is the camera frame: x right, y down, z
along the optical axis). Its dynamics is nonlinear in q: it spins about its own x axis and that
axis is pulled towards the world's "up" (−y) with a rate that grows with the misalignment, like
a self-righting buoy,

    ω(q) = GAIN · (b × R(q)ᵀ up) + SPIN · b        (body frame, rad/s; b = body x axis)
    q[k+1] = q[k] ⊗ exp(ω(q[k]) DT) ⊗ w[k],        w ~ isotropic, SIGMA_W rad per √s,

and the camera sees three markers fixed on the body at offsets ``MARKERS`` (metres, body frame):
pixel ``π(P + R(q) b_i)`` with ``π(X, Y, Z) = F (X/Z, Y/Z) + C`` and Gaussian pixel noise of
SIGMA_PX px. The measurement is a nonlinear function of q (the projection divides by the depth),
so there is no Bingham likelihood to multiply: the filter gets the log-likelihood of the pixel
residuals as a Python function. Both functions satisfy the sign contract (R(−q) = R(q)).

The filter starts 25° off with a 30° spread. Printed: the rotation angle between estimate and
truth, and the filter's own total angular spread (≈ RMS angle), every 25 steps (every 10 with
BINGHAM_VERBOSE=1 in the environment); then the RMS
error after the first second against the spread, and the same run with the camera only (a
random-walk prediction that ignores the rate law, with its process noise widened to cover it).

Needs the ``bingham`` Python package: ``pip install ./python`` from the repository root (``make
venv`` installs it into ``target/venv``).
"""

import math
import os
import sys

import numpy as np

try:
    import bingham as bh
except ImportError as e:
    sys.exit(f"{e}: install the bingham package first, `pip install ./python` from the repository root")

DT = 0.05  # s
GAIN = 1.5  # 1/s
SPIN = 0.8  # rad/s about the body x axis
SIGMA_W = 0.05  # rad/√s process noise
B = np.array([1.0, 0.0, 0.0])  # the body axis that rights itself
UP = np.array([0.0, -1.0, 0.0])  # world "up" in the camera frame (y points down)

F_PX, C_PX = 600.0, np.array([320.0, 240.0])  # focal length and principal point, pixels
P = np.array([0.1, -0.05, 1.5])  # the body's position in front of the camera, metres
MARKERS = 0.25 * np.eye(3)  # marker offsets (rows), metres, body frame
SIGMA_PX = 1.5  # pixel noise (standard deviation per coordinate)


def qmul(a, b):
    """Hamilton product, scalar first."""
    return np.array(
        [
            a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
            a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
            a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
            a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
        ]
    )


def expq(v):
    """The unit quaternion of the rotation vector v (radians)."""
    a = float(np.linalg.norm(v))
    if a < 1e-12:
        return np.array([1.0, *(0.5 * np.asarray(v))]) / math.sqrt(1 + 0.25 * a * a)
    return np.array([math.cos(a / 2), *(math.sin(a / 2) / a * np.asarray(v))])


def rotmat(q):
    """R(q), body → world."""
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def rate_law(q):
    """One step of the nonlinear dynamics without noise: q ⊗ exp(ω(q) DT), a unit quaternion."""
    omega = GAIN * np.cross(B, rotmat(q).T @ UP) + SPIN * B
    out = qmul(q, expq(omega * DT))
    return out / np.linalg.norm(out)


def project(q):
    """The markers' pixels (3×2) for orientation q; depths below 5 cm are clamped (a marker at or
    behind the camera is then simply very unlikely, not an error)."""
    c = P + MARKERS @ rotmat(q).T
    depth = np.maximum(c[:, 2], 0.05)
    return F_PX * c[:, :2] / depth[:, None] + C_PX


def camera_log_likelihood(pixels):
    """log L(q) of measured marker pixels (3×2), up to a constant."""

    def log_l(q):
        r = project(q) - pixels
        return -0.5 * float(np.sum(r * r)) / SIGMA_PX**2

    return log_l


def angle(a, b):
    """The rotation angle between two unit quaternions (q and −q are the same rotation), radians."""
    return 2 * math.acos(min(1.0, abs(float(a @ b))))


def run(steps, seed, use_rate_law, verbose):
    rng = np.random.default_rng(seed)
    m_w, z_w = bh.noise_from_angle_std(4, SIGMA_W * math.sqrt(DT))
    # the truth's process noise: the same Bingham noise, from the library's exact sampler
    w = bh.sample(m_w, z_w, steps, seed=seed)
    truth = expq([0.4, -0.3, 1.0])
    start_error = expq(math.radians(25.0) * np.array([0.6, 0.0, 0.8]))
    m0, z0 = bh.noise_from_angle_std(4, math.radians(30.0))
    m0 = np.stack([qmul(qmul(truth, start_error), e) for e in m0.T], axis=1)  # mode: 25° off
    # ignoring the rate law, the prediction needs more noise: up to (GAIN + SPIN) rad/s of unmodelled motion
    m_wf, z_wf = (m_w, z_w) if use_rate_law else bh.noise_from_angle_std(4, (GAIN + SPIN) * DT)
    errors, spreads = [], []
    every = 10 if os.environ.get("BINGHAM_VERBOSE", "0") not in ("", "0") else 25  # steps per printed row
    with bh.Filter(m0, z0) as f:
        for k in range(steps):
            truth = qmul(rate_law(truth), w[k])
            if use_rate_law:
                f.predict_nonlinear(rate_law, m_wf, z_wf)
            else:
                f.predict(m_wf, z_wf)
            pixels = project(truth) + SIGMA_PX * rng.normal(size=(3, 2))
            f.update_nonlinear(camera_log_likelihood(pixels))
            errors.append(angle(f.mode(), truth))
            spreads.append(f.angular_spread()[-1])
            if verbose and (k % every == every - 1 or k == 0):
                print(
                    f"  {(k + 1) * DT:4.2f} s  error {math.degrees(errors[-1]):5.2f}°  "
                    f"spread {math.degrees(spreads[-1]):5.2f}°"
                )
    return np.array(errors), np.array(spreads)


def main():
    steps = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 7
    print(f"Nonlinear models as Python functions (rate law, pinhole camera): {steps} steps of {DT} s, seed {seed}")
    print("  time    error = rotation angle estimate-truth, spread = the filter's total angular spread")
    errors, spreads = run(steps, seed, use_rate_law=True, verbose=True)
    errors_rw, spreads_rw = run(steps, seed, use_rate_law=False, verbose=False)
    settle = int(round(1.0 / DT))
    rms = lambda a: math.degrees(math.sqrt(np.mean(a[settle:] ** 2)))  # noqa: E731
    print(f"  after the first second: RMS error {rms(errors):.2f}°, RMS spread {rms(spreads):.2f}°")
    print(
        f"  camera only (random-walk prediction): RMS error {rms(errors_rw):.2f}°, "
        f"RMS spread {rms(spreads_rw):.2f}°"
    )


if __name__ == "__main__":
    main()
