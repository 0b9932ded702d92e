#!/usr/bin/env python3
"""The AHRS's time per sample against VQF's, on the same samples, at 50 Hz, 100 Hz, 286 Hz and
1 kHz (issue 35): the ratio table of ``make bench-compare``.

    usage: python3 examples/python/bench_compare.py [DATA_DIR] [--repeats N] [--rates 50,100,286,1000]
                                                    [--sim-runs K] [--sim-duration SECONDS]
                                                    [--kernel portable|avx2|avx512] [--json OUT.json]

Both filters run through their batch calls on the same arrays: ``bingham.Ahrs(Ts).update_batch(gyr,
acc, mag)`` (the C ABI's ``bingham_ahrs_update_batch_health`` through ctypes, quaternions only)
and ``vqf.VQF(Ts).updateBatch(gyr, acc, mag)`` (VQF's C++ batch call through its Python
binding), each with its default parameters for the rate, a fresh filter per recording (created
outside the timing).

Samples, two sources at every rate:

* **BROAD**: the nine shared trials (DATA_DIR, default $BROAD_DIR, else ``../shared/data/broad``
  relative to the repository root; see ``examples/python/broad.py``), 285.714 Hz native ("286 Hz");
  100 Hz and 50 Hz by decimation: each output sample is the mean of the input over its own
  sample period (the integral of the piecewise-constant input, differenced; for the gyroscope
  the mean rate over the period, what a gyroscope sampled at that rate reports). Not at 1 kHz
  (the recordings hold nothing above 286 Hz).
* **simulated**: ``examples/python/imu_sim.py`` (``--sim-runs`` runs of ``--sim-duration`` s, seeds
  0, 1, …; smooth 3-axis motion up to 3 rad/s, a gyroscope bias of 0.2°/s per axis, the default
  noise scaled with the rate), sampled at each rate.

Timing: ``--repeats`` rounds; each round runs every recording of every rate and source with both
filters, back to back, alternating which filter goes first, so a change of the machine's load
touches both alike. Per round and (rate, source): the total time over its recordings divided by
their samples (µs per sample); the table shows the median over the rounds and the ratio of the
medians (Bingham ÷ VQF: below 1 the AHRS is faster). The header names the CPU (``model name``
of /proc/cpuinfo), the d = 3, 4 kernel path the library runs (``BINGHAM_KERNEL`` if it names a
path the CPU has, else the fastest one the CPU flags allow: the library's own rule, see
``docs/speed.md``) and the load average before and after. Below the table, per source, the
cost of a sample without its correction and of a correction (from ``b = p + c/k`` at the two
lowest rates, ``k`` samples per 50-ms correction), and what a correction may cost for the AHRS
to match VQF at each rate, ``(VQF − p)·k`` (``docs/speed.md``, "the floor at 50 and 100 Hz").
Figures belong in
``docs/speed.md`` (row ``bench-compare``) with the CPU, the path and the load.
"""

import argparse
import glob
import json
import math
import os
import platform
import statistics
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)

BROAD_RATE = 1.0 / 0.0035  # 285.714… Hz
RATES = {"50": 50.0, "100": 100.0, "286": BROAD_RATE, "1000": 1000.0}
SIM_BIAS = tuple(math.radians(v) for v in (0.2, -0.2, 0.2))


# ---- the machine ------------------------------------------------------------------------------


def cpu_model():
    """``model name`` (x86) or ``CPU part``/``Model`` (aarch64) of /proc/cpuinfo, with the
    family/model numbers where present."""
    info = {}
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if ":" in line:
                    k, v = line.split(":", 1)
                    info.setdefault(k.strip(), v.strip())
    except OSError:
        return platform.processor() or platform.machine()
    name = info.get("model name") or info.get("Model") or info.get("Hardware") or platform.machine()
    extra = []
    if "cpu family" in info:
        extra.append(f"family {info['cpu family']}, model {info.get('model', '?')}")
    if "CPU part" in info:
        extra.append(f"CPU part {info['CPU part']}")
    return f"{name} ({'; '.join(extra)})" if extra else name


def cpu_flags():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("flags"):
                    return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return set()


def kernel_path():
    """The d = 3, 4 kernel path the library picks (``src/normalization/quadrature/kernel_path.rs``):
    the one ``BINGHAM_KERNEL`` names if the CPU has it, else the fastest available."""
    flags = cpu_flags() if platform.machine() in ("x86_64", "AMD64") else set()
    available = ["portable"]
    if {"avx2", "fma"} <= flags:
        available.append("avx2")
        if {"avx512f", "avx512vl", "avx512dq"} <= flags:
            available.append("avx512")
    asked = os.environ.get("BINGHAM_KERNEL", "").strip().lower()
    if asked in available:
        return asked, f"BINGHAM_KERNEL={asked}"
    why = "the fastest available" if not asked else f"BINGHAM_KERNEL={asked!r} not available: the fastest"
    return available[-1], why


def vqf_version(vqf):
    try:
        from importlib.metadata import version

        return version("vqf")
    except Exception:  # noqa: BLE001 -- the version is only printed
        return getattr(vqf, "__version__", "?")


# ---- the samples ------------------------------------------------------------------------------


def decimate(x, fs_in, fs_out):
    """Each output row is the mean of the input over its own period (1/fs_out): the input taken
    as constant over each of its periods (sample k covering (t_{k−1}, t_k]), integrated,
    interpolated at the output times and differenced. Works for any ratio of rates."""
    n = x.shape[0]
    t_in = np.arange(n) / fs_in
    cum = np.vstack([np.zeros((1, x.shape[1])), np.cumsum(x[1:], axis=0) / fs_in])
    m = int(math.floor((n - 1) * fs_out / fs_in))
    t_out = np.arange(m + 1) / fs_out
    integral = np.column_stack([np.interp(t_out, t_in, cum[:, j]) for j in range(x.shape[1])])
    return np.ascontiguousarray(np.diff(integral, axis=0) * fs_out)


def broad_recordings(data_dir, fs):
    """The nine BROAD trials at the rate fs (native or decimated): list of (name, gyr, acc, mag)."""
    from broad import load_trial  # noqa: E402 -- the reader of examples/python/broad.py

    out = []
    for path in sorted(glob.glob(os.path.join(data_dir, "*.npz"))):
        trial = load_trial(path)
        name = os.path.basename(path)[:2]
        if abs(fs - trial["fs"]) < 1e-6 * fs:
            out.append((name, trial["gyr"], trial["acc"], trial["mag"]))
        else:
            out.append((name,) + tuple(decimate(trial[k], trial["fs"], fs)
                                       for k in ("gyr", "acc", "mag")))
    return out


def sim_recordings(fs, runs, duration):
    from imu_sim import simulate  # noqa: E402

    out = []
    for seed in range(runs):
        sim = simulate(fs=fs, duration=duration, seed=seed, gyro_bias=SIM_BIAS)
        out.append((f"sim{seed}", sim["gyr"], sim["acc"], sim["mag"]))
    return out


# ---- timing -----------------------------------------------------------------------------------


def time_bingham(bingham, ts, gyr, acc, mag):
    ahrs = bingham.Ahrs(ts)
    t0 = time.perf_counter()
    q = ahrs.update_batch(gyr, acc, mag)
    seconds = time.perf_counter() - t0
    if not np.all(np.isfinite(q)):
        raise RuntimeError("the Bingham AHRS returned a non-finite quaternion")
    return seconds


def time_vqf(vqf, ts, gyr, acc, mag):
    f = vqf.VQF(ts)
    t0 = time.perf_counter()
    out = f.updateBatch(gyr, acc, mag)
    seconds = time.perf_counter() - t0
    if not np.all(np.isfinite(out["quat9D"])):
        raise RuntimeError("VQF returned a non-finite quaternion")
    return seconds


# The AHRS corrects once every CORRECTION_PERIOD seconds (src/ahrs/lowpass.rs), i.e. every
# round(CORRECTION_PERIOD·fs) samples (half away from zero, as the library rounds).
CORRECTION_PERIOD = 0.05


def samples_per_correction(fs):
    return max(1, math.floor(CORRECTION_PERIOD * fs + 0.5))


def correction_budget(rows):
    """Per source with two rates: the cost of a sample without its correction `p` and of a
    correction `c` (µs), from `b = p + c/k` at the two lowest rates (`k` samples per
    correction), and what a correction may cost for the AHRS to match VQF at each rate,
    `(v − p)·k` (docs/speed.md, "the floor at 50 and 100 Hz")."""
    out = {}
    for source in sorted({r["source"] for r in rows}):
        rs = sorted((r for r in rows if r["source"] == source), key=lambda r: r["rate"])
        if len(rs) < 2:
            continue
        (b1, k1), (b2, k2) = [(r["bingham_us"], samples_per_correction(r["rate"])) for r in rs[:2]]
        if k1 == k2:
            continue
        c = (b1 - b2) / (1.0 / k1 - 1.0 / k2)
        p = b1 - c / k1
        out[source] = {"sample_us": p, "correction_us": c, "from": [rs[0]["rate"], rs[1]["rate"]],
                       "budget_us": [[r["rate"], (r["vqf_us"] - p) * samples_per_correction(r["rate"])]
                                     for r in rs]}
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data_dir", nargs="?", default=None)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--rates", default="50,100,286,1000")
    ap.add_argument("--sim-runs", type=int, default=3)
    ap.add_argument("--sim-duration", type=float, default=60.0)
    ap.add_argument("--kernel", choices=("portable", "avx2", "avx512"),
                    help="set BINGHAM_KERNEL for this run (before the library is loaded)")
    ap.add_argument("--json", help="write every round's figures to this file")
    args = ap.parse_args(argv)
    if args.kernel:
        os.environ["BINGHAM_KERNEL"] = args.kernel

    try:
        import bingham
    except ImportError as e:
        sys.exit(f"cannot import the bingham package ({e}): `make venv`, or pip install ./python")
    try:
        import vqf
    except ImportError as e:
        sys.exit(f"cannot import vqf ({e}): pip install vqf (`make deps` installs it)")

    data_dir = args.data_dir or os.environ.get("BROAD_DIR") or os.path.join(
        REPO, "..", "shared", "data", "broad")
    have_broad = bool(glob.glob(os.path.join(data_dir, "*.npz")))
    rates = [r.strip() for r in args.rates.split(",") if r.strip()]
    for r in rates:
        if r not in RATES:
            sys.exit(f"unknown rate {r!r}: one of {', '.join(RATES)}")

    # every recording, loaded once: {(rate, source): [(name, gyr, acc, mag), …]}
    sets = {}
    for r in rates:
        fs = RATES[r]
        if have_broad and r != "1000":
            sets[(r, "BROAD")] = broad_recordings(data_dir, fs)
        sets[(r, "simulated")] = sim_recordings(fs, args.sim_runs, args.sim_duration)

    path, why = kernel_path()
    load_before = os.getloadavg()
    print(f"CPU: {cpu_model()}, {os.cpu_count()} logical CPUs")
    print(f"kernel path (d = 3, 4): {path} ({why})")
    print(f"bingham {bingham.__version__} ({bingham.library_path()}); vqf {vqf_version(vqf)}")
    if not have_broad:
        print(f"BROAD not found in {data_dir}: simulated samples only")
    print(f"load average before: {load_before[0]:.2f} {load_before[1]:.2f} {load_before[2]:.2f}; "
          f"{args.repeats} rounds, interleaved")

    # rounds[key] = list of (bingham s/sample, vqf s/sample), one per round
    rounds = {key: [] for key in sets}
    for k in range(args.repeats):
        for key, recs in sets.items():
            fs = RATES[key[0]]
            tb = tv = 0.0
            n = 0
            for i, (_, gyr, acc, mag) in enumerate(recs):
                if (k + i) % 2 == 0:
                    tb += time_bingham(bingham, 1.0 / fs, gyr, acc, mag)
                    tv += time_vqf(vqf, 1.0 / fs, gyr, acc, mag)
                else:
                    tv += time_vqf(vqf, 1.0 / fs, gyr, acc, mag)
                    tb += time_bingham(bingham, 1.0 / fs, gyr, acc, mag)
                n += gyr.shape[0]
            rounds[key].append((tb / n, tv / n))
        print(f"  round {k + 1}/{args.repeats} done", file=sys.stderr)
    load_after = os.getloadavg()

    print()
    print(f"{'rate':>8}  {'source':<22} {'samples':>8}  {'Bingham µs':>10}  {'VQF µs':>8}  "
          f"{'ratio':>6}  {'ratio range':>13}")
    rows = []
    for key, recs in sets.items():
        r, source = key
        b = statistics.median(x[0] for x in rounds[key]) * 1e6
        v = statistics.median(x[1] for x in rounds[key]) * 1e6
        ratios = [x[0] / x[1] for x in rounds[key]]
        n = sum(rec[1].shape[0] for rec in recs)
        label = f"{source} ({len(recs)})" + (", decimated" if source == "BROAD" and r in ("50", "100")
                                            else "")
        rate = f"{RATES[r]:.0f} Hz" if r != "286" else "286 Hz"
        print(f"{rate:>8}  {label:<22} {n:>8}  {b:>10.3f}  {v:>8.3f}  {b / v:>5.2f}×  "
              f"{min(ratios):>5.2f}–{max(ratios):.2f}×")
        rows.append({"rate": RATES[r], "source": source, "recordings": len(recs), "samples": n,
                     "bingham_us": b, "vqf_us": v, "ratio": b / v,
                     "rounds": [[x[0] * 1e6, x[1] * 1e6] for x in rounds[key]]})
    print()
    print(f"µs per sample, median of {args.repeats} rounds; ratio = Bingham / VQF (below 1: "
          f"the AHRS is faster); ratio range over the rounds")
    budget = correction_budget(rows)
    for source, d in budget.items():
        rates_s = ", ".join(f"{fs:.0f} Hz {b:.2f} µs" for fs, b in d["budget_us"])
        print(f"{source}: a sample without its correction {d['sample_us']:.2f} µs, a correction "
              f"{d['correction_us']:.2f} µs (from the {d['from'][0]:.0f} and {d['from'][1]:.0f} Hz "
              f"rows); what a correction may cost for 1.0×: {rates_s}")
    print(f"load average after: {load_after[0]:.2f} {load_after[1]:.2f} {load_after[2]:.2f}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"cpu": cpu_model(), "kernel_path": path, "kernel_path_why": why,
                       "load_before": load_before, "load_after": load_after,
                       "repeats": args.repeats, "rows": rows,
                       "correction_budget": budget}, f, indent=1)
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
