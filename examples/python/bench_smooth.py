#!/usr/bin/env python3
"""Time per sample of the offline smoother (``bingham.smooth``) against VQF's offline variant
(``vqf.offlineVQF``) and the online AHRS (``bingham.Ahrs(Ts).update_batch``), on the same
samples in the same run: the nine BROAD trials at their native 286 Hz, default parameters. Each
round runs the three back to back on every trial, alternating which goes first; the figure is the
median over the rounds of the total time over the total samples (µs per sample): the wall time
(what a user waits; the smoother runs its backward pass on a second thread) and the CPU time
of the process (all its threads). NumPy's BLAS is held to one thread (``OPENBLAS_NUM_THREADS``
unless set), whose idle threads would otherwise spin on the second core.

    usage: python3 examples/python/bench_smooth.py [DATA_DIR] [--rounds N]
"""

import argparse
import glob
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import statistics
import time

import numpy as np

import broad


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data_dir", nargs="?")
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()
    import bingham
    import vqf
    trials = [broad.load_trial(p) for p in sorted(glob.glob(os.path.join(broad.data_dir(args.data_dir), "*.npz")))]
    n = sum(len(t["gyr"]) for t in trials)

    def smoother(t):
        bingham.smooth(t["gyr"], t["acc"], t["mag"], sample_time=t["Ts"])

    def offline_vqf(t):
        vqf.offlineVQF(t["gyr"], t["acc"], t["mag"], t["Ts"])

    def online(t):
        bingham.Ahrs(t["Ts"]).update_batch(t["gyr"], t["acc"], t["mag"])

    runs = {"smoother": smoother, "offlineVQF": offline_vqf, "online AHRS": online}
    times = {k: [] for k in runs}
    cpu = {k: [] for k in runs}
    for r in range(args.rounds):
        order = list(runs) if r % 2 == 0 else list(reversed(runs))
        for k in order:
            t0, c0 = time.perf_counter(), time.process_time()
            for t in trials:
                runs[k](t)
            times[k].append((time.perf_counter() - t0) / n * 1e6)
            cpu[k].append((time.process_time() - c0) / n * 1e6)
    print(f"{len(trials)} trials, {n} samples, {args.rounds} rounds; load average {os.getloadavg()[0]:.1f}")
    for k, v in times.items():
        print(f"{k:<12} median {statistics.median(v):.2f} us/sample  (rounds {min(v):.2f}-{max(v):.2f}); "
              f"CPU {statistics.median(cpu[k]):.2f} us/sample")
    print(f"ratio smoother/offlineVQF {statistics.median(times['smoother']) / statistics.median(times['offlineVQF']):.2f}")


if __name__ == "__main__":
    main()
