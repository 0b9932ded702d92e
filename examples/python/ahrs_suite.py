#!/usr/bin/env python3
"""The simulated-IMU suite (issue 20): the Bingham AHRS, VQF and Madgwick on the same simulated
samples with known truth (``imu_sim.py``), one scenario per effect.

    usage: python3 examples/python/ahrs_suite.py [--only NAME,...] [--quick] [--json OUT.json]
                                                 [--seed N] [--seeds K] [--list]

Filters (each with its defaults, causal, on the same samples):

* Bingham: ``bingham.Ahrs(Ts).update_batch(gyr, acc, mag, spread=True)``, then ``gyro_bias()``;
* VQF: ``broad.run_vqf`` (``vqf.VQF(Ts).updateBatch``, ``quat9D``); its bias estimate (the
  ``bias`` output of ``updateBatch``, rad/s) from a second, identical VQF run;
* Madgwick: ``broad.run_madgwick`` (``ahrs`` package, gain 0.12, earth frame turned to ENU); it
  has no bias estimate.

Metric: BROAD's (``broad.errors``: total, heading, inclination error) against the simulator's
truth; per scenario and filter the RMS over the samples from the settling time on (10 s unless
the scenario says otherwise) to the end. Bias error: |b̂ − b| / |b| in % at the last sample
(t = 60 s in the full suite), where the filter offers an estimate. Bingham only: RMS error /
RMS predicted spread over the same samples (1 = calibrated, > 1 = overconfident), and, pooled
over all scenarios, the Spearman rank correlation of the RMS total error with the RMS spread in
consecutive 5-s segments (from the settling time on; the median of the per-scenario
correlations is also given). Time: wall time of each filter's batch run per sample.

Scenarios (full suite; every one 60 s, seed 20, 2 s initial rest, |ω| up to 3 rad/s, gyro bias
0.2 °/s per axis with signs (+, −, +) unless named otherwise; sensors as ``imu_sim``'s defaults:
gyro noise 0.005 rad/s, accelerometer 0.05 m/s², magnetometer 0.5 µT per sample at 100 Hz,
50 µT field with 60° dip):

* ``bias{B}_rest{R}``: gyro bias B = 0.2, 0.5, 1 °/s per axis, R = 0, 2, 10 s of initial rest;
* ``rate{F}``: bias 0.5 °/s, 2 s rest, at F = 100, 286 and 1000 Hz (the same motion; noise of
  constant density, so the same angle random walk: per-sample noise ×√(F/100));
  ``rate1000_lownoise``: the same at 1000 Hz with the per-sample noise of 100 Hz (√10 lower
  density), to tell the sample rate from the noise level;
* ``spin{W}``: sustained spinning at W = 2, 4, 7 rad/s about a slowly wandering axis, on top of
  motion up to 1 rad/s;
* ``latency{L}``: the magnetometer lags by L = 0, 5, 10, 20 ms (``latency0`` is the same run as
  ``bias0.2_rest2``); ``spin4_latency{L}``: the same lags, L = 5, 10, 20 ms, during spinning at
  4 rad/s (``spin4`` is L = 0), where a lag turns the field steadily rather than back and forth;
* ``magnet_pass``: a magnet passing by (dipole, 40 µT at closest approach at 30 s, time scale 1 s);
* ``magnet_attached``: a magnet attached from 30 s on (20 µT constant in the sensor frame);
* ``bursts``: linear-acceleration bursts (0.3 per second, 2–8 m/s² peaks, 0.3–1.5 s each).

``--quick`` runs every scenario for 25 s (events at 12.5 s instead of 30 s) as a smoke test.
``--seeds K`` (K > 1) also runs the nine bias scenarios with the seeds N+1 … N+K−1 and prints, per
scenario, each filter's total error averaged over the K seeds and on how many seeds Bingham's is
at or below VQF's: one seed is one noise realization and one motion, and the filters' ranking
on the bias scenarios turns on a few hundredths of a degree.
The suite is a measuring stick: the scenario parameters are physical choices, not tuned to any
filter. Needs the ``bingham`` package (``pip install ./python``, or ``BINGHAM_LIB`` and
``PYTHONPATH=python``) and, for the peers, ``pip install vqf ahrs``.
"""

import argparse
import dataclasses
import json
import math
import os
import platform
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import broad  # noqa: E402  (the BROAD comparison: metric and peer runners)
import imu_sim  # noqa: E402

FILTERS = ("bingham", "vqf", "madgwick")
LABELS = {"bingham": "Bingham", "vqf": "VQF", "madgwick": "Madgwick"}
SHORT = {"bingham": "Bing", "vqf": "VQF", "madgwick": "Madg"}
METRICS = ("total", "heading", "inclination")
SEED = 20
SETTLE = 10.0
SEGMENT = 5.0
DURATION = 60.0
QUICK_DURATION = 25.0
DEG = math.pi / 180.0
BIAS_SIGNS = np.array([1.0, -1.0, 1.0])


def _bias(deg_per_s):
    return tuple(deg_per_s * DEG * BIAS_SIGNS)


BASE = dict(fs=100.0, duration=DURATION, omega_max=3.0, rest=2.0, gyro_bias=_bias(0.2))


def scenarios():
    """[(name, description, overrides of BASE, settling time s)] in table order."""
    out = []
    for b in (0.2, 0.5, 1.0):
        for r in (0, 2, 10):
            out.append((f"bias{b:g}_rest{r}", f"gyro bias {b:g} deg/s per axis, {r} s rest",
                        dict(gyro_bias=_bias(b), rest=float(r)), SETTLE))
    for f in (100, 286, 1000):
        out.append((f"rate{f}", f"bias 0.5 deg/s, 2 s rest, {f} Hz",
                    dict(gyro_bias=_bias(0.5), fs=float(f)), SETTLE))
    out.append(("rate1000_lownoise", "as rate1000, per-sample noise as at 100 Hz",
                dict(gyro_bias=_bias(0.5), fs=1000.0, noise_ref_rate=None), SETTLE))
    for w in (2, 4, 7):
        out.append((f"spin{w}", f"spinning at {w} rad/s (+ motion up to 1 rad/s)",
                    dict(spin_rate=float(w), omega_max=1.0), SETTLE))
    for lat in (0, 5, 10, 20):
        out.append((f"latency{lat}", f"magnetometer latency {lat} ms",
                    dict(mag_latency=lat * 1e-3), SETTLE))
    for lat in (5, 10, 20):
        out.append((f"spin4_latency{lat}", f"spinning at 4 rad/s, magnetometer latency {lat} ms",
                    dict(spin_rate=4.0, omega_max=1.0, mag_latency=lat * 1e-3), SETTLE))
    out.append(("magnet_pass", "magnet passing by at 30 s (40 uT peak)",
                dict(pass_time=30.0), SETTLE))
    out.append(("magnet_attached", "magnet attached from 30 s on (20 uT)",
                dict(attach_time=30.0), SETTLE))
    out.append(("bursts", "linear-acceleration bursts (0.3/s, 2-8 m/s^2)",
                dict(burst_rate=0.3), SETTLE))
    return out


def config_for(overrides, seed, quick):
    kw = dict(BASE, seed=seed, **overrides)
    if quick:
        scale = QUICK_DURATION / kw["duration"]
        kw["duration"] = QUICK_DURATION
        for k in ("pass_time", "attach_time"):
            if kw.get(k) is not None:
                kw[k] *= scale
    return imu_sim.SimConfig(**kw)


# ---- the filters ------------------------------------------------------------------------------


def run_bingham(trial):
    """(quaternions n×4, spread n (rad), bias estimate at the end (3, rad/s), seconds)."""
    import bingham
    f = bingham.Ahrs(trial["Ts"])
    t0 = time.perf_counter()
    q, spread = f.update_batch(trial["gyr"], trial["acc"], trial["mag"], spread=True)
    seconds = time.perf_counter() - t0
    return np.asarray(q, dtype=float), np.asarray(spread, dtype=float), f.gyro_bias(), seconds


def vqf_bias(trial):
    """VQF's gyro bias estimate after the last sample (rad/s): ``broad.run_vqf`` returns only the
    quaternions, so this is a second run of the same filter on the same samples."""
    import vqf
    out = vqf.VQF(trial["Ts"]).updateBatch(trial["gyr"], trial["acc"], trial["mag"])
    return np.asarray(out["bias"][-1], dtype=float)


def run_filter(name, trial):
    """(q, spread or None, bias estimate or None, seconds)."""
    if name == "bingham":
        return run_bingham(trial)
    if name == "vqf":
        q, _, seconds = broad.run_vqf(trial)
        return np.asarray(q, dtype=float), None, vqf_bias(trial), seconds
    q, _, seconds = broad.run_madgwick(trial)
    return np.asarray(q, dtype=float), None, None, seconds


def available_filters():
    """(filters to run, {filter: why skipped}), from broad's check of the packages."""
    run, skipped = broad.available_filters(False)
    return [f for f in FILTERS if f in run], {f: w for f, w in skipped.items() if f in FILTERS}


# ---- statistics -------------------------------------------------------------------------------


def rank(x):
    """Ranks 0 … n−1 of x, ties given their mean rank."""
    x = np.asarray(x, dtype=float)
    order = np.argsort(x, kind="mergesort")
    r = np.empty(len(x))
    r[order] = np.arange(len(x))
    _, inv, counts = np.unique(x, return_inverse=True, return_counts=True)
    return (np.bincount(inv, weights=r) / counts)[inv]


def spearman(x, y):
    if len(x) < 3:
        return float("nan")
    rx, ry = rank(x), rank(y)
    rx, ry = rx - rx.mean(), ry - ry.mean()
    den = math.sqrt(float(np.sum(rx * rx) * np.sum(ry * ry)))
    return float(np.sum(rx * ry) / den) if den > 0 else float("nan")


def segments(err, spread, fs, start):
    """RMS error and RMS spread (degrees) in consecutive SEGMENT-second pieces from ``start``."""
    m = int(round(SEGMENT * fs))
    k = (len(err) - start) // m
    e = err[start:start + k * m].reshape(k, m)
    s = spread[start:start + k * m].reshape(k, m)
    return (np.degrees(np.sqrt(np.mean(e * e, axis=1))),
            np.degrees(np.sqrt(np.mean(s * s, axis=1))))


# ---- one scenario -----------------------------------------------------------------------------


def group_of(name):
    """The scenario family (table blocks): bias, rate, spin, latency, magnet, bursts."""
    for g in ("bias", "rate", "spin4_latency", "spin", "latency", "magnet", "bursts"):
        if name.startswith(g):
            return "latency" if g == "spin4_latency" else g
    return name


def evaluate(name, desc, overrides, settle, filters, seed, quick):
    cfg = config_for(overrides, seed, quick)
    t0 = time.perf_counter()
    sim = imu_sim.simulate(cfg)
    sim_seconds = time.perf_counter() - t0
    trial = {k: sim[k] for k in ("gyr", "acc", "mag", "fs", "Ts")}
    truth_q, truth_b = sim["truth"]["quat"], sim["truth"]["bias"]
    n = len(truth_q)
    start = int(np.searchsorted(sim["t"], settle - 1e-9))
    res = {"description": desc, "group": group_of(name), "fs": sim["fs"],
           "duration": cfg.duration, "samples": n, "settle_s": settle,
           "samples_evaluated": n - start, "seed": seed, "overrides": dict(overrides),
           "config": dataclasses.asdict(cfg), "true_bias_rad_s": truth_b.tolist(),
           "simulation_s": sim_seconds, "filters": {}, "errors": {}}
    segs = None
    for f in filters:
        try:
            q, spread, bias, seconds = run_filter(f, trial)
        except Exception as e:  # noqa: BLE001 -- one failing filter must not stop the others
            res["errors"][f] = f"{type(e).__name__}: {e}"
            continue
        err = broad.errors(q, truth_q)
        r = {m: math.degrees(broad.rms(err[m][start:])) for m in METRICS}
        r["us_per_sample"] = seconds / n * 1e6
        if bias is not None:
            d = np.linalg.norm(bias - truth_b)
            r["bias_estimate_rad_s"] = bias.tolist()
            r["bias_error_deg_s"] = math.degrees(d)
            nb = np.linalg.norm(truth_b)
            r["bias_error_pct"] = 100.0 * d / nb if nb > 0 else None
        if spread is not None:
            r["rms_spread_deg"] = math.degrees(broad.rms(spread[start:]))
            r["error_spread_ratio"] = broad.rms(err["total"][start:]) / broad.rms(spread[start:])
            se, ss = segments(err["total"], spread, sim["fs"], start)
            r["segment_rms_error_deg"] = se.tolist()
            r["segment_rms_spread_deg"] = ss.tolist()
            r["segment_spearman"] = spearman(se, ss)
            segs = (se, ss)
        res["filters"][f] = r
    if not res["errors"]:
        del res["errors"]
    return res, segs


# ---- output -----------------------------------------------------------------------------------


def fmt(v, spec="{:6.2f}", width=6):
    return f"{'--':>{width}}" if v is None or (isinstance(v, float) and math.isnan(v)) \
        else spec.format(v)


def print_table(results, filters):
    groups = [("total", "total RMSE (deg)"), ("heading", "heading RMSE"),
              ("inclination", "inclination RMSE")]
    bias_f = [f for f in filters if f in ("bingham", "vqf")]
    w = 6 * len(filters) + len(filters) - 1
    head1 = f"{'':<18}" + "".join(f" | {title:^{w}}" for _, title in groups)
    head2 = f"{'scenario':<18}" + "".join(" | " + " ".join(f"{SHORT[f]:>6}" for f in filters)
                                          for _ in groups)
    if bias_f:
        wb = 6 * len(bias_f) + len(bias_f) - 1
        head1 += f" | {'bias err %':^{wb}}"
        head2 += " | " + " ".join(f"{SHORT[f]:>6}" for f in bias_f)
    if "bingham" in filters:
        head1 += " | Bing"
        head2 += " | e/spr"
    print(head1)
    print(head2)
    print("-" * len(head2))
    group = None
    for name, res in results.items():
        if group is not None and res["group"] != group:
            print()
        group = res["group"]
        fr = res["filters"]
        line = f"{name:<18}"
        for m, _ in groups:
            line += " | " + " ".join(fmt(fr.get(f, {}).get(m)) for f in filters)
        if bias_f:
            line += " | " + " ".join(fmt(fr.get(f, {}).get("bias_error_pct"), "{:6.1f}")
                                     for f in bias_f)
        if "bingham" in filters:
            line += " | " + fmt(fr.get("bingham", {}).get("error_spread_ratio"), "{:5.2f}", 5)
        print(line)
    print()


def over_seeds(todo, filters, seed, k, quick, first):
    """The bias scenarios of ``todo`` with the seeds ``seed`` … ``seed + k − 1`` (``first`` holds
    the runs with ``seed``): per scenario and filter the total error of every seed, their mean,
    and how many seeds have Bingham's at or below VQF's; printed as a table."""
    out = {}
    for name, desc, overrides, settle in todo:
        if group_of(name) != "bias":
            continue
        per = {f: [first[name]["filters"][f]["total"]] for f in filters
               if f in first[name]["filters"]}
        for s in range(seed + 1, seed + k):
            res, _ = evaluate(name, desc, overrides, settle, filters, s, quick)
            for f in per:
                per[f].append(res["filters"][f]["total"] if f in res["filters"] else math.nan)
        row = {f: {"totals": v, "mean": float(np.mean(v))} for f, v in per.items()}
        if "bingham" in per and "vqf" in per:
            row["bingham_at_or_below_vqf"] = int(sum(
                b <= v for b, v in zip(per["bingham"], per["vqf"])))
        out[name] = row
    if out:
        print(f"bias scenarios over {k} seeds ({seed}…{seed + k - 1}): total RMSE (deg), mean "
              "over the seeds" + ("; seeds with Bingham <= VQF" if "vqf" in filters else ""))
        print(f"{'scenario':<18} | " + " ".join(f"{SHORT[f]:>6}" for f in filters))
        for name, row in out.items():
            line = f"{name:<18} | " + " ".join(fmt(row.get(f, {}).get("mean")) for f in filters)
            if "bingham_at_or_below_vqf" in row:
                line += f" | {row['bingham_at_or_below_vqf']}/{k}"
            print(line)
        print()
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", help="comma-separated scenario names (default: all; see --list)")
    ap.add_argument("--quick", action="store_true",
                    help=f"{QUICK_DURATION:g}-s versions of the scenarios (smoke test)")
    ap.add_argument("--json", metavar="OUT.json", help="write all numbers as JSON")
    ap.add_argument("--seed", type=int, default=SEED, help=f"simulation seed (default {SEED})")
    ap.add_argument("--seeds", type=int, default=1, metavar="K",
                    help="also run the bias scenarios with K-1 more seeds (default 1: none)")
    ap.add_argument("--list", action="store_true", help="list the scenarios and exit")
    args = ap.parse_args(argv)

    todo = scenarios()
    if args.list:
        for name, desc, _, settle in todo:
            print(f"{name:<18} {desc} (settling {settle:g} s)")
        return 0
    if args.only:
        wanted = [s.strip() for s in args.only.split(",") if s.strip()]
        unknown = [w for w in wanted if w not in {s[0] for s in todo}]
        if unknown:
            print(f"unknown scenario(s): {', '.join(unknown)} (see --list)")
            return 2
        todo = [s for s in todo if s[0] in wanted]

    filters, skipped = available_filters()
    print("Simulated-IMU suite (examples/python/imu_sim.py): known truth, every filter on the "
          "same samples")
    for f, why in skipped.items():
        print(f"note: {LABELS[f]} skipped ({why})")
    if not filters:
        print("nothing to run")
        return 0
    dur = QUICK_DURATION if args.quick else DURATION
    print(f"filters: {', '.join(LABELS[f] for f in filters)}; seed {args.seed}; "
          f"{len(todo)} scenario(s) of {dur:g} s{' (--quick)' if args.quick else ''}; "
          f"errors are RMS from the settling time ({SETTLE:g} s) to the end; bias error at the "
          f"end (t = {dur:g} s)\n")

    t0 = time.perf_counter()
    results, seg_e, seg_s = {}, [], []
    for name, desc, overrides, settle in todo:
        res, segs = evaluate(name, desc, overrides, settle, filters, args.seed, args.quick)
        results[name] = res
        for f, msg in res.get("errors", {}).items():
            print(f"note: {LABELS[f]} failed on {name}: {msg}")
        if segs is not None:
            seg_e.append(segs[0])
            seg_s.append(segs[1])
    wall = time.perf_counter() - t0

    print_table(results, filters)
    summary = {"wall_seconds": wall}
    if "bingham" in filters:
        print("Bing e/spr: RMS of Bingham's total error / RMS of its predicted spread "
              "(1 = calibrated, > 1 = overconfident)")
    if seg_e:
        pooled = spearman(np.concatenate(seg_e), np.concatenate(seg_s))
        per = [r["filters"]["bingham"]["segment_spearman"] for r in results.values()
               if "bingham" in r["filters"]]
        per = [p for p in per if not math.isnan(p)]
        med = float(np.median(per)) if per else float("nan")
        summary.update(spearman_pooled=pooled, spearman_median_per_scenario=med,
                       segments=int(sum(len(e) for e in seg_e)))
        print(f"Bingham, {SEGMENT:g}-s segment RMS error vs RMS spread: Spearman {pooled:+.2f} "
              f"pooled over {summary['segments']} segments; median per scenario {med:+.2f}")
    if args.seeds > 1:
        summary["seeds"] = over_seeds(todo, filters, args.seed, args.seeds, args.quick, results)
    times = {}
    for f in filters:
        n = sum(r["samples"] for r in results.values() if f in r["filters"])
        s = sum(r["filters"][f]["us_per_sample"] * r["samples"] for r in results.values()
                if f in r["filters"])
        if n:
            times[f] = s / n
    summary["us_per_sample"] = times
    print("time per sample: " + ", ".join(f"{LABELS[f]} {v:.2f} us" for f, v in times.items()))
    print(f"wall time {wall:.1f} s")
    if args.json:
        doc = {"suite": "examples/python/ahrs_suite.py", "quick": args.quick, "seed": args.seed,
               "filters": filters, "skipped": skipped, "settle_s": SETTLE,
               "segment_s": SEGMENT, "metric_unit": "deg", "bias_error_unit": "percent of |b|",
               "time_unit": "us_per_sample", "python": platform.python_version(),
               "scenarios": results, "summary": summary}
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(doc, fh, indent=1)
        print(f"json: {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
