#!/usr/bin/env python3
"""Orientation accuracy on real IMU data: the Bingham AHRS (``bingham.Ahrs``) against VQF, Madgwick
and Mahony on nine trials of BROAD, with BROAD's own error metric.

    usage: python3 examples/python/broad.py [DATA_DIR] [--plot FILE.svg] [--trial NN]
                                            [--only NN,NN] [--no-peers] [--json OUT.json] [--jobs N]
                                            [--mag-latency SECONDS|estimate]

Data: BROAD, the Berlin Robust Orientation Estimation Assessment Dataset: D. Laidig, M. Caruso,
A. Cereatti, T. Seel, "BROAD - A Benchmark for Robust Inertial Orientation Estimation", Data 6(7):72,
2021, doi:10.3390/data6070072, licensed under CC BY 4.0 (nine trials converted to .npz; see the
README.md in the data directory). DATA_DIR defaults to $BROAD_DIR, else ``../shared/data/broad``
relative to the repository root.

Each trial ``NN_name.npz`` holds gyr (rad/s), acc (m/s²), mag (µT), opt_quat (truth, (w, x, y, z),
sensor -> ENU) and movement. Every filter runs over the whole trial with one parameter set for all
trials, causally except the two offline ones (Smoother, offlineVQF):

* Bingham: ``bingham.Ahrs(Ts).update_batch(gyr, acc, mag, spread=True)`` with its default
  (tuned) parameters; also gives the predicted total angular standard deviation ("spread") and,
  after the last sample, its online estimate of the magnetometer's latency (printed per trial).
  ``--mag-latency SECONDS`` sets ``mag_latency`` (default: the library's, which compensates
  the AHRS's online estimate of the latency); ``--mag-latency estimate`` runs each trial
  twice and sets it to the first run's final estimate (a per-trial calibration from the whole
  trial, not causal; the time is that of the second run);
* Smoother: ``bingham.smooth(gyr, acc, mag, sample_time=Ts)``, the offline smoother (the whole
  trial, forward and backward; not causal) with the same defaults, and its predicted spread;
* VQF: ``vqf.VQF(Ts)`` default parameters, online 9-D output ``quat9D`` (C++ batch call);
* offlineVQF: ``vqf.offlineVQF(gyr, acc, mag, Ts)`` default parameters, 9-D output ``quat9D``
  (VQF's own offline variant: forward–backward filtering of its bias and low-pass states);
* Madgwick: ``ahrs.filters.Madgwick(gyr, acc, mag, frequency, gain=0.12)`` (the class's own batch
  loop and initial quaternion), earth frame turned to ENU by ``(1/√2, 0, 0, 1/√2) ⊗ q``;
* Mahony: ``ahrs.filters.Mahony(..., k_P=0.74, k_I=0.0012)`` (already ENU).

Metric (BROAD's): ``e = q̂ ⊗ q⁻¹`` normalized; total error ``2·acos(|e_w|)``, heading error
``2·atan(|e_z / e_w|)``, inclination error ``2·acos(√(e_w² + e_z²))``; per trial the RMSE in degrees
over the samples where ``movement`` is true (and the truth is not NaN: the optical system loses
the marker for a few samples in trials 30 and 34); per group the mean of the trials' RMSEs.
Time: wall time of the batch run divided by the number of samples (µs per sample). Calibration of
the Bingham AHRS: RMS of its actual total error ÷ RMS of its predicted spread, over the same
samples (1 = honest, > 1 = overconfident).

``--plot FILE.svg`` draws the total error over time of one trial (``--trial``, default 07) for
every filter (hand-written SVG, no plotting library needed); ``--json OUT.json`` writes all the
numbers. Peers whose package is missing are skipped with a note (``pip install vqf ahrs``).
Needs the ``bingham`` Python package: ``pip install ./python`` from the repository root (``make
broad`` installs it into a virtual environment and runs this program with it).
"""

import argparse
import glob
import json
import math
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))

ATTRIBUTION = ("BROAD (Laidig, Caruso, Cereatti, Seel, Data 6(7):72, 2021, "
               "doi:10.3390/data6070072), CC BY 4.0")
FILTERS = ("bingham", "smoother", "vqf", "vqf_offline", "madgwick", "mahony")
OURS = ("bingham", "smoother")
LABELS = {"bingham": "Bingham", "smoother": "Smoother", "vqf": "VQF", "vqf_offline": "offlineVQF",
          "madgwick": "Madgwick", "mahony": "Mahony"}
COLORS = {"bingham": "#d62728", "smoother": "#ff7f0e", "vqf": "#1f77b4", "vqf_offline": "#17becf",
          "madgwick": "#2ca02c", "mahony": "#9467bd"}
METRICS = ("total", "heading", "inclination")
NED_TO_ENU = np.array([math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)])


# ---- quaternions and the metric ---------------------------------------------------------------


def qmul(a, b):
    """Hamilton product of (…, 4) arrays, scalar first."""
    w1, x1, y1, z1 = np.moveaxis(np.asarray(a), -1, 0)
    w2, x2, y2, z2 = np.moveaxis(np.asarray(b), -1, 0)
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
                     w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                     w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], axis=-1)


def errors(q_est, q_true):
    """Total, heading and inclination error (radians) per sample; NaN where the truth is NaN."""
    e = qmul(q_est, q_true * np.array([1.0, -1.0, -1.0, -1.0]))
    e = e / np.linalg.norm(e, axis=1, keepdims=True)
    w, z = np.abs(e[:, 0]), np.abs(e[:, 3])
    total = 2.0 * np.arccos(np.clip(w, 0.0, 1.0))
    heading = 2.0 * np.arctan2(z, w)
    inclination = 2.0 * np.arccos(np.clip(np.sqrt(w * w + z * z), 0.0, 1.0))
    return {"total": total, "heading": heading, "inclination": inclination}


def rms(x):
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else float("nan")


# ---- the filters ------------------------------------------------------------------------------


def _bingham():
    """The ``bingham`` module if it has ``Ahrs``, else a string saying why not."""
    try:
        import bingham
    except Exception as e:  # noqa: BLE001 -- any failure only skips our filter
        return f"cannot import the bingham package ({e}): pip install ./python"
    if not hasattr(bingham, "Ahrs"):
        return "the installed bingham package has no Ahrs yet"
    return bingham


def run_bingham(trial, mag_latency=None):
    """The Bingham AHRS on one trial: (quaternions N×4, predicted spread N in rad, seconds,
    {"mag_latency": the latency compensated (s), "mag_latency_estimate": the AHRS's online
    estimate after the last sample (s, or None)}). ``mag_latency``: None (the default
    parameters: the online estimate compensated), seconds, or ``"estimate"``:
    a first run with the defaults, then the timed run with ``mag_latency`` = the first run's
    final estimate (a per-trial calibration from the whole trial, not causal)."""
    import bingham
    if mag_latency == "estimate":
        first = bingham.Ahrs(trial["Ts"])
        first.update_batch(trial["gyr"], trial["acc"], trial["mag"])
        mag_latency = first.mag_latency_estimate() or 0.0
    overrides = {} if mag_latency is None else {"mag_latency": float(mag_latency)}
    ahrs_filter = bingham.Ahrs(trial["Ts"], **overrides)
    t0 = time.perf_counter()
    q, spread = ahrs_filter.update_batch(trial["gyr"], trial["acc"], trial["mag"], spread=True)
    seconds = time.perf_counter() - t0
    readout = {"mag_latency": ahrs_filter.params.mag_latency,
               "mag_latency_estimate": ahrs_filter.mag_latency_estimate()}
    return np.asarray(q, dtype=np.float64), np.asarray(spread, dtype=np.float64), seconds, readout


def run_ours(trial):
    """The Bingham AHRS with its defaults on one trial: (quaternions N×4, predicted spread N in
    rad, seconds)."""
    return run_bingham(trial)[:3]


def run_smoother(trial):
    """The Bingham offline smoother with its defaults on one trial: (quaternions N×4, predicted
    spread N in rad, seconds)."""
    import bingham
    t0 = time.perf_counter()
    q, spread = bingham.smooth(trial["gyr"], trial["acc"], trial["mag"], sample_time=trial["Ts"])
    return q, spread, time.perf_counter() - t0


def run_vqf_offline(trial):
    import vqf
    t0 = time.perf_counter()
    out = vqf.offlineVQF(trial["gyr"], trial["acc"], trial["mag"], trial["Ts"])
    return out["quat9D"], None, time.perf_counter() - t0


def run_vqf(trial):
    import vqf
    t0 = time.perf_counter()
    out = vqf.VQF(trial["Ts"]).updateBatch(trial["gyr"], trial["acc"], trial["mag"])
    return out["quat9D"], None, time.perf_counter() - t0


def run_madgwick(trial):
    import ahrs
    t0 = time.perf_counter()
    q = ahrs.filters.Madgwick(gyr=trial["gyr"], acc=trial["acc"], mag=trial["mag"],
                              frequency=trial["fs"], gain=0.12).Q
    dt = time.perf_counter() - t0
    return qmul(NED_TO_ENU, q), None, dt


def run_mahony(trial):
    import ahrs
    t0 = time.perf_counter()
    q = ahrs.filters.Mahony(gyr=trial["gyr"], acc=trial["acc"], mag=trial["mag"],
                            frequency=trial["fs"], k_P=0.74, k_I=0.0012).Q
    return q, None, time.perf_counter() - t0


RUNNERS = {"bingham": run_ours, "smoother": run_smoother, "vqf": run_vqf,
           "vqf_offline": run_vqf_offline, "madgwick": run_madgwick, "mahony": run_mahony}


def available_filters(no_peers):
    """(filters to run, {filter: why skipped})."""
    run, skipped = [], {}
    b = _bingham()
    if isinstance(b, str):
        skipped["bingham"] = skipped["smoother"] = b
    else:
        run.append("bingham")
        if hasattr(b, "smooth"):
            run.append("smoother")
        else:
            skipped["smoother"] = "the installed bingham package has no smooth yet"
    if no_peers:
        for f in FILTERS:
            if f not in OURS:
                skipped[f] = "--no-peers"
        return run, skipped
    for f, module in (("vqf", "vqf"), ("vqf_offline", "vqf"), ("madgwick", "ahrs"),
                      ("mahony", "ahrs")):
        try:
            __import__(module)
            run.append(f)
        except ImportError:
            skipped[f] = f"Python package '{module}' missing: pip install {module}"
    return run, skipped


# ---- one trial --------------------------------------------------------------------------------


def load_trial(path):
    d = np.load(path)
    fs = float(d["sampling_rate"])
    trial = {k: np.ascontiguousarray(d[k], dtype=np.float64) for k in ("gyr", "acc", "mag")}
    trial.update(fs=fs, Ts=1.0 / fs, truth=np.asarray(d["opt_quat"], dtype=np.float64),
                 movement=np.asarray(d["movement"], dtype=bool))
    return trial


def evaluate(job):
    """Runs the filters on one trial; returns (results, total-error series for the plot or None).
    ``job``: (path, filters, keep_series[, mag_latency of the Bingham AHRS, see run_bingham])."""
    path, filters, keep_series = job[:3]
    mag_latency = job[3] if len(job) > 3 else None
    trial = load_trial(path)
    n = len(trial["gyr"])
    sel = trial["movement"] & ~np.isnan(trial["truth"][:, 0])
    res = {"samples": n, "samples_evaluated": int(sel.sum()), "filters": {}, "errors": {}}
    series = {} if keep_series else None
    for f in filters:
        readout = {}
        try:
            if f == "bingham":
                q, spread, seconds, readout = run_bingham(trial, mag_latency)
            else:
                q, spread, seconds = RUNNERS[f](trial)
        except Exception as e:  # noqa: BLE001 -- one failing filter must not stop the others
            res["errors"][f] = f"{type(e).__name__}: {e}"
            continue
        err = errors(q, trial["truth"])
        r = {m: math.degrees(rms(err[m][sel])) for m in METRICS}
        r.update(readout)
        r["us_per_sample"] = seconds / n * 1e6
        if spread is not None:
            r["calibration_ratio"] = rms(err["total"][sel]) / rms(spread[sel])
        res["filters"][f] = r
        if keep_series:
            series[f] = np.degrees(err["total"])
    if keep_series:
        series["_movement"] = trial["movement"]
        series["_fs"] = trial["fs"]
    return res, series


# ---- SVG plot ---------------------------------------------------------------------------------


def write_svg(path, title, series, filters):
    """Total error (degrees) over time as polylines, one per filter, with axes and legend."""
    W, H, L, R, T, B = 900, 420, 60, 130, 30, 45
    fs, mv = series["_fs"], series["_movement"]
    n = len(mv)
    dur = n / fs
    peak = max((np.nanmax(series[f][mv]) for f in filters if np.any(mv)), default=1.0)
    ymax = max(1.0, float(np.ceil(peak / 5.0) * 5.0))
    x = lambda t: L + (W - L - R) * t / dur  # noqa: E731
    y = lambda v: T + (H - T - B) * (1.0 - min(v, ymax) / ymax)  # noqa: E731
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" '
           f'font-family="sans-serif" font-size="12">',
           f'<rect width="{W}" height="{H}" fill="white"/>',
           f'<text x="{L}" y="18" font-size="14">{title}</text>']
    edges = np.flatnonzero(np.diff(np.r_[0, (~mv).astype(int), 0]))  # rest spans: not scored
    for a, b in zip(edges[::2], edges[1::2]):
        out.append(f'<rect x="{x(a / fs):.1f}" y="{T}" width="{x(b / fs) - x(a / fs):.1f}" '
                   f'height="{H - T - B}" fill="#eeeeee"/>')
    nice = lambda span: next(s for s in (1, 2, 5, 10, 20, 30, 60, 120, 300, 1e9)  # noqa: E731
                             if span / s <= 8)
    for v in np.arange(0.0, ymax + 1e-9, nice(ymax)):  # axes with ticks and grid
        out.append(f'<line x1="{L}" x2="{W - R}" y1="{y(v):.1f}" y2="{y(v):.1f}" stroke="#ddd"/>'
                   f'<text x="{L - 6}" y="{y(v) + 4:.1f}" text-anchor="end">{v:g}</text>')
    for t in np.arange(0.0, dur, nice(dur)):
        out.append(f'<text x="{x(t):.1f}" y="{H - B + 16}" text-anchor="middle">{t:g}</text>')
    out.append(f'<rect x="{L}" y="{T}" width="{W - L - R}" height="{H - T - B}" fill="none" '
               f'stroke="black"/><text x="{(L + W - R) / 2}" y="{H - 8}" text-anchor="middle">'
               f'time (s); grey: rest, not scored</text><text x="16" y="{(T + H - B) / 2}" '
               f'transform="rotate(-90 16 {(T + H - B) / 2})" text-anchor="middle">'
               f'total error (deg)</text>')
    step = max(1, n // 3000)
    for i, f in enumerate(filters):  # legend
        ly = T + 10 + 18 * i
        out.append(f'<line x1="{W - R + 10}" x2="{W - R + 30}" y1="{ly}" y2="{ly}" '
                   f'stroke="{COLORS[f]}" stroke-width="2"/>'
                   f'<text x="{W - R + 36}" y="{ly + 4}">{LABELS[f]}</text>')
    for f in reversed(filters):  # the first filter (ours) drawn last, on top
        e = series[f]
        runs, pts = [], []
        for k in range(0, n, step):  # NaN truth breaks the line
            if np.isnan(e[k]):
                if len(pts) > 1:
                    runs.append(pts)
                pts = []
            else:
                pts.append(f"{x(k / fs):.1f},{y(e[k]):.1f}")
        if len(pts) > 1:
            runs.append(pts)
        for p in runs:
            out.append(f'<polyline fill="none" stroke="{COLORS[f]}" stroke-width="1" '
                       f'points="{" ".join(p)}"/>')
    out.append("</svg>")
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("\n".join(out) + "\n")


# ---- main -------------------------------------------------------------------------------------


def data_dir(arg):
    if arg is None:
        arg = os.environ.get("BROAD_DIR") or os.path.join(REPO, "..", "shared", "data", "broad")
    if not os.path.isabs(arg) and not os.path.isdir(arg):
        arg = os.path.join(REPO, arg)  # relative to the repository root as a fallback
    return os.path.normpath(arg)


def group_means(trials, filters):
    """{group: {"trials": [...], "filters": {f: {metric: mean over the group's trials}}}}."""
    names = []
    for t in trials.values():
        names += [g for g in t["groups"] if g not in names]
    out = {}
    for g in names:
        members = [k for k, t in trials.items() if g in t["groups"]]
        fm = {}
        for f in filters:
            rows = [trials[k]["filters"][f] for k in members if f in trials[k]["filters"]]
            if len(rows) == len(members):
                keys = [m for m in rows[0]
                        if all(isinstance(r.get(m), (int, float)) for r in rows)]
                fm[f] = {m: float(np.mean([r[m] for r in rows])) for m in keys}
        out[g] = {"trials": members, "filters": fm}
    return out


def print_table(title, rows, filters, metric, extra=(), fmt="{:8.2f}"):
    """``extra``: further columns, each (heading, filter, key)."""
    extra = [extra] if extra and isinstance(extra[0], str) else list(extra or ())
    head = f"{title:<42}" + "".join(f"{LABELS[f]:>12}" for f in filters)
    for e in extra:
        head += f"{e[0]:>14}"
    print(head)
    print("-" * len(head))
    for name, fdict in rows:
        if name is None:
            print("-" * len(head))
            continue
        line = f"{name[:42]:<42}"
        for f in filters:
            v = fdict.get(f, {}).get(metric)
            line += f"{'':>4}" + (fmt.format(v) if v is not None else f"{'--':>8}")
        for e in extra:
            v = fdict.get(e[1], {}).get(e[2])
            line += f"{'':>6}" + (fmt.format(v) if v is not None else f"{'--':>8}")
        print(line)
    print()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("data_dir", nargs="?", help="directory of the BROAD trials (*.npz)")
    ap.add_argument("--plot", metavar="FILE.svg", help="SVG of one trial's total error over time")
    ap.add_argument("--trial", default="07", help="trial number to plot (default 07)")
    ap.add_argument("--only", help="comma-separated trial numbers to evaluate (default: all)")
    ap.add_argument("--no-peers", action="store_true", help="run the Bingham AHRS only")
    ap.add_argument("--json", metavar="OUT.json", help="write all numbers as JSON")
    ap.add_argument("--jobs", type=int, default=0,
                    help="worker processes over trials (default: CPU count with peers, else 1)")
    ap.add_argument("--mag-latency", default=None, metavar="SECONDS|estimate",
                    help="the Bingham AHRS's mag_latency: seconds (default: the library's, "
                         "-1 = its online estimate compensated), or 'estimate': "
                         "per trial the AHRS's own final estimate from a first run")
    args = ap.parse_args(argv)
    mag_latency = (args.mag_latency if args.mag_latency in (None, "estimate")
                   else float(args.mag_latency))

    ddir = data_dir(args.data_dir)
    paths = sorted(glob.glob(os.path.join(ddir, "*.npz")))
    if args.only:
        wanted = [s.strip() for s in args.only.split(",") if s.strip()]
        paths = [p for p in paths if any(os.path.basename(p).startswith(w) for w in wanted)]
    print(f"BROAD evaluation on data from {ATTRIBUTION}")
    print(f"data: {ddir} ({len(paths)} trials)")
    if not paths:
        print("no trial files (*.npz) found: give DATA_DIR or set BROAD_DIR")
        return 0
    info = {}
    if os.path.exists(os.path.join(ddir, "trials.json")):
        with open(os.path.join(ddir, "trials.json"), encoding="utf-8") as fh:
            info = json.load(fh).get("trials", {})

    filters, skipped = available_filters(args.no_peers)
    for f, why in skipped.items():
        print(f"note: {LABELS[f]} skipped ({why})")
    if not filters:
        print("nothing to run")
        return 0

    names = [os.path.splitext(os.path.basename(p))[0] for p in paths]
    plot_name = next((n for n in names if n.startswith(args.trial)), None) if args.plot else None
    if args.plot and plot_name is None:
        print(f"note: trial {args.trial} not among the evaluated trials, no plot")
    jobs = [(p, filters, n == plot_name, mag_latency) for p, n in zip(paths, names)]
    nproc = args.jobs or (min(os.cpu_count() or 1, len(paths)) if len(filters) > 1 or
                          "bingham" not in filters else 1)
    print(f"filters: {', '.join(LABELS[f] for f in filters)}; {nproc} worker process(es)\n")
    t0 = time.perf_counter()
    if nproc > 1:
        import multiprocessing
        with multiprocessing.Pool(nproc) as pool:
            outs = pool.map(evaluate, jobs, chunksize=1)
    else:
        outs = [evaluate(j) for j in jobs]
    wall = time.perf_counter() - t0

    trials, plot_series = {}, None
    for name, (res, series) in zip(names, outs):
        res["groups"] = info.get(name, {}).get("groups", ["all_trials"])
        if "all_trials" not in res["groups"]:
            res["groups"] = ["all_trials"] + res["groups"]
        trials[name] = res
        for f, msg in res["errors"].items():
            print(f"note: {LABELS[f]} failed on {name}: {msg}")
        if series is not None:
            plot_series = series
    groups = group_means(trials, filters)
    # printed: the two top-level groups, then all trials (finer groups are in the JSON)
    shown = [g for g in ("undisturbed", "disturbed") if g in groups] + ["all_trials"]

    def rows(label_of_group):
        r = [(k, trials[k]["filters"]) for k in trials] + [(None, None)]
        return r + [(label_of_group(g), groups[g]["filters"]) for g in shown]

    glabel = lambda g: f"mean {g.replace('_', ' ')} ({len(groups[g]['trials'])})"  # noqa: E731
    for metric in METRICS:
        extra = [(f"{LABELS[f]} cal", f, "calibration_ratio") for f in OURS
                 if metric == "total" and f in filters]
        print_table(f"{metric} RMSE (deg)", rows(glabel), filters, metric, extra)
    print_table("time (us per sample)", rows(glabel), filters, "us_per_sample")
    if "bingham" in filters:
        print("Bingham cal, Smoother cal: RMS of the actual total error / RMS of the predicted "
              "spread (1 = calibrated, > 1 = overconfident)")
        setting = args.mag_latency or "default (-1: the online estimate compensated)"
        print(f"Bingham mag_latency: {setting}; its online estimate of the magnetometer "
              "latency after the last sample (ms):")
        print("  " + ", ".join(
            f"{k[:2]} {1e3 * est:.1f}" if est is not None else f"{k[:2]} --"
            for k, est in ((k, t["filters"].get("bingham", {}).get("mag_latency_estimate"))
                           for k, t in trials.items())))
    print(f"wall time {wall:.1f} s")

    if args.plot and plot_series is not None:
        drawn = [f for f in filters if f in plot_series]
        write_svg(args.plot, f"BROAD trial {plot_name}: total orientation error", plot_series,
                  drawn)
        print(f"plot: {args.plot}")
    if args.json:
        for t in trials.values():
            if not t["errors"]:
                del t["errors"]
        doc = {"dataset": ATTRIBUTION, "data_dir": ddir, "filters": filters, "skipped": skipped,
               "metric_unit": "deg", "time_unit": "us_per_sample", "trials": trials,
               "groups": groups, "mean": groups["all_trials"]["filters"], "wall_seconds": wall}
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(doc, fh, indent=1)
        print(f"json: {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
