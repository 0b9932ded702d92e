#!/usr/bin/env python3
"""The AHRS's magnetometer latency (issue 20) on the simulated IMU of the AHRS suite, with known
truth: the online estimate (``Ahrs.mag_latency_estimate``) and the compensation (``mag_latency``).

    usage: python3 examples/python/ahrs_latency.py [--seeds N]

1. The suite's latency scenarios (``latency{0,5,10,20}``: the base motion up to 3 rad/s;
   ``spin4``, ``spin4_latency{5,10,20}``: 4 rad/s about a wandering axis plus motion up to
   1 rad/s; 100 Hz, 60 s, seed 20): the estimate after 60 s, and the RMS total / heading error
   from 10 s on with ``mag_latency`` = 0, = the true latency, = the estimate of a first run.
2. The scatter of the estimate over seeds 0 … N−1 (default 8) for ``spin4_latency10`` and
   ``latency10`` at 100, 286 and 1000 Hz (noise of constant density: per-sample noise ×√(f/100)).

Needs the ``bingham`` package (``pip install ./python``, or ``BINGHAM_LIB`` and
``PYTHONPATH=python``) and NumPy; docs/accuracy/ahrs.md ("Sensor latency") quotes its output.
"""

import argparse
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import ahrs_suite  # noqa: E402
import broad  # noqa: E402
import imu_sim  # noqa: E402

SCENARIOS = {name: overrides for name, _, overrides, _ in ahrs_suite.scenarios()}
TABLE = ("latency0", "latency5", "latency10", "latency20",
         "spin4", "spin4_latency5", "spin4_latency10", "spin4_latency20")


def run(sim, mag_latency=0.0):
    """(the AHRS after the run, RMS total and heading error in degrees from 10 s on)."""
    import bingham
    a = bingham.Ahrs(sim["Ts"], mag_latency=mag_latency)
    q = a.update_batch(sim["gyr"], sim["acc"], sim["mag"])
    err = broad.errors(q, sim["truth"]["quat"])
    sel = sim["t"] >= ahrs_suite.SETTLE
    return a, [math.degrees(broad.rms(err[m][sel])) for m in ("total", "heading")]


def simulate(name, seed=ahrs_suite.SEED, fs=None):
    overrides = dict(SCENARIOS[name])
    if fs is not None:
        overrides["fs"] = fs
    return imu_sim.simulate(ahrs_suite.config_for(overrides, seed, False))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=8, help="seeds for the scatter (default 8)")
    args = ap.parse_args(argv)

    print("scenario            latency  estimate | total / heading RMSE (deg): "
          "uncompensated | true latency | estimate")
    for name in TABLE:
        sim = simulate(name)
        latency = SCENARIOS[name].get("mag_latency", 0.0)
        a, plain = run(sim)
        est = a.mag_latency_estimate()
        _, true = run(sim, latency)
        _, comp = run(sim, est or 0.0)
        est_ms = f"{1e3 * est:6.2f}" if est is not None else "    --"
        print(f"{name:<18} {1e3 * latency:5.1f} ms {est_ms} ms | {plain[0]:.2f} / {plain[1]:.2f}"
              f" | {true[0]:.2f} / {true[1]:.2f} | {comp[0]:.2f} / {comp[1]:.2f}")
    print()
    print(f"estimate - truth (ms) over seeds 0..{args.seeds - 1}, 10 ms latency:")
    for fs in (100.0, 286.0, 1000.0):
        for name in ("spin4_latency10", "latency10"):
            errs = []
            for seed in range(args.seeds):
                a, _ = run(simulate(name, seed, fs))
                est = a.mag_latency_estimate()
                errs.append(float("nan") if est is None else 1e3 * est - 10.0)
            e = np.array(errs)
            print(f"  {name:<16} {fs:6.0f} Hz: mean {np.nanmean(e):+.2f}, sd {np.nanstd(e):.2f},"
                  f" max |err| {np.nanmax(np.abs(e)):.2f}, no estimate {int(np.isnan(e).sum())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
