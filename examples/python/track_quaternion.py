#!/usr/bin/env python3
"""Orientation tracking with unit quaternions: the JAIF 2014 Sec. 7.2 scenario through the ctypes
binding (``bingham.Filter``), against the Kalman filter adapted as in JAIF Sec. 7.

    usage: python3 examples/python/track_quaternion.py [runs]

Quaternions are scalar first ``(w, x, y, z)``; ``q`` and ``-q`` are the same rotation. The truth
performs a random walk ``x[k] = x[k-1] ⊕ w[k-1]`` (Hamilton product) and is measured as
``z[k] = x[k] ⊕ v[k]``:

* initial estimate  M0 = I, z0 = (-1, -1, -1, 0)  (mode (0, 0, 0, 1))
* system noise      Mw = anti-diagonal ones, zw = (-200, -200, -2, 0)  (mode (1, 0, 0, 0))
* measurement noise Mv = anti-diagonal ones, zv = (-500, -500, -500, 0)
* true initial state (0, 1, 0, 0); 100 steps per run.

The noise comes from the library's exact sampler with the seeds of ``examples/c/
quaternion_tracking.c`` (run r: 1000 + 2r and 1001 + 2r), so both print the same numbers. The
Kalman filter runs on the quaternion as a vector in R^4 (identity models, Gaussians fitted to
one mode of each Bingham density by Monte Carlo, measurement mirrored to the prediction's
hemisphere, estimate normalized after each update). Error per step: ``min(angle, pi - angle)``
between truth and estimate in R^4; per run the RMSE over the steps.

Needs the ``bingham`` Python package: ``pip install ./python`` from the repository root (``make
demo`` installs it into a virtual environment and runs this program with it).
"""

import math
import sys
import time

import numpy as np

try:
    import bingham as bh
except ImportError as e:
    sys.exit(f"{e}: install the bingham package first, `pip install ./python` from the repository root")

STEPS = 100
FIT_SAMPLES = 100_000

ANTI = np.fliplr(np.eye(4))
M0, Z0 = np.eye(4), np.array([-1.0, -1.0, -1.0, 0.0])
MW, ZW = ANTI, np.array([-200.0, -200.0, -2.0, 0.0])
MV, ZV = ANTI, np.array([-500.0, -500.0, -500.0, 0.0])
X0 = np.array([0.0, 1.0, 0.0, 0.0])


def qmul(a, b):
    """Hamilton product, scalar first, normalized."""
    r = np.array(
        [
            a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
            a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
            a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
            a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
        ]
    )
    return r / np.linalg.norm(r)


def axial_error(a, b):
    c = abs(a @ b) / (np.linalg.norm(a) * np.linalg.norm(b))
    return math.acos(min(1.0, c))


def gaussian_fit(m, z, seed):
    """Mode and C = E[(s x - mu)(s x - mu)^T], s = sign(mu^T x), by Monte Carlo."""
    mu = bh.mode(m, z)
    x = bh.sample(m, z, FIT_SAMPLES, seed=seed)
    s = np.where(x @ mu < 0, -1.0, 1.0)
    e = s[:, None] * x - mu
    return mu, e.T @ e / FIT_SAMPLES


class Kalman:
    def __init__(self, x0, p0, q, r, mu_w):
        self.x, self.p, self.q, self.r, self.mu_w = x0.copy(), p0.copy(), q, r, mu_w

    def predict(self):
        self.x = qmul(self.x, self.mu_w)  # the identity here
        self.p = self.p + self.q

    def update(self, z):
        if z @ self.x < 0:  # mirror the measurement
            z = -z
        s = self.p + self.r
        k = np.linalg.solve(s, self.p).T  # P S^-1 (P, S symmetric)
        self.x = self.x + k @ (z - self.x)
        p = self.p - k @ self.p
        self.p = 0.5 * (p + p.T)
        self.x /= np.linalg.norm(self.x)


def main(argv):
    runs = int(argv[1]) if len(argv) > 1 else 100
    mu0, c0 = gaussian_fit(M0, Z0, 7)
    mu_w, cw = gaussian_fit(MW, ZW, 8)
    _, cv = gaussian_fit(MV, ZV, 9)
    print(f"Quaternion tracking (d = 4) via the Python binding, Bingham vs Kalman filter: {runs} runs of {STEPS} steps")
    rmse_b, rmse_k, seconds = [], [], 0.0
    for r in range(runs):
        w = bh.sample(MW, ZW, STEPS, seed=1000 + 2 * r)
        v = bh.sample(MV, ZV, STEPS, seed=1001 + 2 * r)
        x = X0
        truth, meas = [], []
        for k in range(STEPS):
            x = qmul(x, w[k])
            truth.append(x)
            meas.append(qmul(x, v[k]))
        eb, ek = [], []
        kf = Kalman(mu0, c0, cw, cv, mu_w)
        with bh.Filter(M0, Z0) as f:
            for xk, zk in zip(truth, meas):
                t0 = time.perf_counter()
                f.predict(MW, ZW)
                f.update(zk, MV, ZV)
                seconds += time.perf_counter() - t0
                eb.append(axial_error(xk, f.mode()))
                kf.predict()
                kf.update(zk)
                ek.append(axial_error(xk, kf.x))
        rmse_b.append(math.sqrt(np.mean(np.square(eb))))
        rmse_k.append(math.sqrt(np.mean(np.square(ek))))
    rmse_b, rmse_k = np.array(rmse_b), np.array(rmse_k)
    wins = int(np.sum(rmse_b < rmse_k))
    print(f"  mean RMSE  Bingham filter {rmse_b.mean():.4f} rad ({math.degrees(rmse_b.mean()):.2f} deg)")
    print(f"             Kalman filter  {rmse_k.mean():.4f} rad ({math.degrees(rmse_k.mean()):.2f} deg)")
    print(f"  Bingham filter better in {wins} of {runs} runs ({100 * wins // runs} %)")
    print(f"  {1e6 * seconds / (runs * STEPS):.1f} us per step (predict + update, including the ctypes and NumPy call overhead)")
    return 0 if rmse_b.mean() < rmse_k.mean() else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
