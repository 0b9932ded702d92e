#!/usr/bin/env python3
"""The simulated-IMU suite (issue 20): the Bingham AHRS, VQF and Madgwick on the same simulated
samples with known truth (``imu_sim.py``), one scenario per effect.

    usage: python3 examples/python/ahrs_suite.py [--only NAME,...] [--group G,...] [--quick]
                                                 [--json OUT.json] [--seed N] [--seeds K] [--list]

Filters (each with its defaults, causal, on the same samples):

* Bingham: ``bingham.Ahrs(Ts).update_batch(gyr, acc, mag, spread=True)``, then ``gyro_bias()``;
* VQF: ``broad.run_vqf`` (``vqf.VQF(Ts).updateBatch``, ``quat9D``); its bias estimate (the
  ``bias`` output of ``updateBatch``, rad/s) from a second, identical VQF run;
* Smoother: ``bingham.smooth(gyr, acc, mag, sample_time=Ts, time=t, full=True)``, the offline
  smoother over the whole trial (not causal), its spread and its smoothed bias at the last sample;
* offlineVQF: ``vqf.offlineVQF(gyr, acc, mag, Ts)`` (VQF's offline variant), ``quat9D`` and its
  ``bias`` output at the last sample; it gets the samples as VQF does;
* Madgwick: ``broad.run_madgwick`` (``ahrs`` package, gain 0.12, earth frame turned to ENU); it
  has no bias estimate.

Lost samples and timestamps (the ``timing`` and ``lost`` scenarios): Bingham gets the NaN rows
as they are and the timestamps (``update_batch(..., time=t)``). The peers get their best
equivalent (:func:`peer_trial`): a NaN row becomes [0 0 0], which VQF and Madgwick both skip
(that sensor's correction is left out of the sample; a NaN would spoil their state for good);
VQF, whose period is fixed, gets the gyroscope scaled by Δt_k/Ts (its integration then turns by
exactly exp(gyr_k·Δt_k)); Madgwick is run sample by sample with its ``dt`` argument.

Metric: BROAD's (``broad.errors``: total, heading, inclination error) against the simulator's
truth; per scenario and filter the RMS over the samples from the settling time on (10 s unless
the scenario says otherwise) to the end. Bias error: |b̂ − b| / |b| in % at the last sample
(t = 60 s in the full suite), where the filter offers an estimate. Bingham only: RMS error /
RMS predicted spread over the same samples (1 = calibrated, > 1 = overconfident), and, pooled
over all scenarios, the Spearman rank correlation of the RMS total error with the RMS spread in
consecutive 5-s segments (from the settling time on; the median of the per-scenario
correlations is also given). Time: wall time of each filter's batch run per sample.

Scenarios (full suite; every one 60 s (the ``reject`` group 75 s), seed 20, 2 s initial rest,
|ω| up to 3 rad/s, gyro bias 0.2 °/s per axis with signs (+, −, +) unless named otherwise;
sensors as ``imu_sim``'s defaults:
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

Issue 34's scenarios (item 7: what the mechanisms need; ``--group issue34`` runs them alone),
each a physical choice, the base scenario (bias 0.2 °/s, 2 s rest) plus one effect:

* ``lever`` group: the IMU mounted at r from the rotation centre, r = 0.1 and 0.3 m along the
  body direction (0.6, −0.48, 0.64) (``lever0.1``, ``lever0.3``: a sensor on a limb or a
  handheld device; the accelerometer feels ω̇×r + ω×(ω×r), up to a few m/s² at 3 rad/s);
  ``lever0.2_spin4``: 0.2 m during spinning at 4 rad/s (+ motion up to 1 rad/s), a steady
  centripetal acceleration of about 3 m/s² (a sensor off the axis of a rotating body);
* ``acc`` group: an uncalibrated accelerometer, ``acc_offset`` (0.15, −0.10, 0.20) m/s² per axis,
  ``acc_scale`` (+1.5, −1.0, +2.0) % per axis, ``acc_offset_scale`` both (typical MEMS
  turn-on offsets and sensitivity tolerances; an offset of 0.15 m/s² is a 0.9° tilt at rest
  that no filter can see without motion);
* ``field`` group: ``field_volume``: the rotation centre wanders slowly through a volume
  (±1.5 m horizontally, ±0.3 m vertically, periods of 30–200 s) in which the local field is
  turned from the reference by a smooth function of position, up to 6° (about 1–6° over the
  run; correlated over tens of seconds, as measured in indoor motion-capture volumes);
  ``field_offset``: the local field turned by a constant 1.5° about the vertical (a heading
  offset no IMU can observe: every filter's heading is 1.5° off at best);
* ``reject`` group (75 s each): spinning about the world vertical at 110 or 180 °/s
  (``reject110``, ``reject180``; from 4 s to 70 s, half-cosine ramps of 2 s, with a wobble up to
  0.5 rad/s) with a 30 µT magnet fixed to the sensor from 20 s to 65 s (45 s): the measured
  field's norm swings at the spin rate, so a filter rejects the magnetometer or averages the
  disturbance out over the rotation. The magnet comes after every filter has its field
  reference (VQF accepts its first reference after about 10–12 s of these runs; before it, VQF
  applies the field at half gain whatever it is); ``reject180_gscale`` adds a gyroscope scale
  error of 0.2 % per axis (0.36 °/s of heading drift at 180 °/s while the field is rejected);
  ``reject180_nomag`` is the same spin without the magnet (the reference). Their bias error is
  at 75 s, the end of the run;
* ``timing`` group: ``drop1``, ``drop5``: 1 % and 5 % of the samples (packets: all sensors)
  dropped at random, the rest with their timestamps; ``jitter10``: the sampling instants
  jittered uniformly by ±10 % of the period, with their timestamps (the gyroscope integrating
  over the true interval);
* ``lost`` group: ``lost_mag20``: the magnetometer's rows NaN from 25 s to 45 s;
  ``lost_accmag10``: the accelerometer's and magnetometer's rows NaN from 30 s to 40 s;
* ``start`` group: ``start_flip180``: for the first 0.5 s (at rest) the local field is turned
  180° about the vertical (same norm and dip), then it is the reference field: every filter
  initializes its heading from its first samples, so each starts 180° wrong in heading, from
  the same samples. This is the start that is fair to all three: each gets the same wrong
  evidence through its own initialization, where a forced state would need each filter's own
  way in (Bingham's ``set_state`` with some confidence, Madgwick's ``q0``, VQF's internal
  ``state`` with its fast initial heading gain ``kMagInit``), each with its own choices.
  Besides the RMS errors the suite prints, per filter, the time from which the total error
  stays within 5° (``within_5deg_after_s`` in the JSON, kept for every scenario).

``--quick`` runs every scenario for 25 s (events at 12.5 s instead of 30 s; every event time
and window scaled by 25/60) as a smoke test. ``--group G,...`` runs the scenarios of these
groups (``bias``, ``rate``, ``spin``, ``latency``, ``magnet``, ``bursts``, ``lever``, ``acc``,
``field``, ``reject``, ``timing``, ``lost``, ``start``; ``issue34`` for the last seven) or
name prefixes; ``--list`` shows each scenario's group.
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

FILTERS = ("bingham", "smoother", "vqf", "vqf_offline", "madgwick")
LABELS = {"bingham": "Bingham", "smoother": "Smoother", "vqf": "VQF",
          "vqf_offline": "offlineVQF", "madgwick": "Madgwick"}
SHORT = {"bingham": "Bing", "smoother": "Smth", "vqf": "VQF", "vqf_offline": "oVQF",
         "madgwick": "Madg"}
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
    return out + mechanism_scenarios()


# issue 34's scenarios (item 7): each a physical choice, documented in the module docstring
LEVER_DIR = np.array([0.6, -0.48, 0.64])  # a unit vector, body frame
ACC_OFFSET = (0.15, -0.10, 0.20)  # m/s², per axis
ACC_SCALE = (0.015, -0.010, 0.020)  # per axis
GYRO_SCALE = (0.002, -0.002, 0.002)  # per axis
VOLUME = dict(pos_amp=(1.5, 1.5, 0.3), field_var=6.0 * DEG)
REJECTION = dict(duration=75.0, omega_max=0.5, yaw_spin_time=(4.0, 70.0), yaw_spin_ramp=2.0,
                 attach_time=20.0, attach_end=65.0, attach_field=30.0)


def mechanism_scenarios():
    """Issue 34's scenarios, after the suite's first ones (the same table format)."""
    out = []
    for r in (0.1, 0.3):
        out.append((f"lever{r:g}", f"IMU {r:g} m from the rotation centre",
                    dict(lever_arm=tuple(r * LEVER_DIR)), SETTLE))
    out.append(("lever0.2_spin4", "IMU 0.2 m from the centre, spinning at 4 rad/s",
                dict(lever_arm=tuple(0.2 * LEVER_DIR), spin_rate=4.0, omega_max=1.0), SETTLE))
    out.append(("acc_offset", "accelerometer offset (0.15, -0.10, 0.20) m/s^2",
                dict(acc_offset=ACC_OFFSET), SETTLE))
    out.append(("acc_scale", "accelerometer scale error (+1.5, -1.0, +2.0) %",
                dict(acc_scale=ACC_SCALE), SETTLE))
    out.append(("acc_offset_scale", "accelerometer offset and scale error together",
                dict(acc_offset=ACC_OFFSET, acc_scale=ACC_SCALE), SETTLE))
    out.append(("field_volume", "moving in a 3 m volume, local field turned by up to 6 deg",
                dict(VOLUME), SETTLE))
    out.append(("field_offset", "local field turned 1.5 deg in heading, constant (unobservable)",
                dict(field_offset=(0.0, 0.0, 1.5 * DEG)), SETTLE))
    for w in (110, 180):
        out.append((f"reject{w}", f"spinning {w} deg/s about the vertical, 30 uT "
                    "body-fixed magnet for 45 s", dict(REJECTION, yaw_spin=w * DEG), SETTLE))
    out.append(("reject180_gscale", "as reject180, gyro scale error 0.2 %",
                dict(REJECTION, yaw_spin=180 * DEG, gyro_scale=GYRO_SCALE), SETTLE))
    out.append(("reject180_nomag", "as reject180 without the magnet",
                dict(REJECTION, yaw_spin=180 * DEG, attach_time=None, attach_end=None), SETTLE))
    for d in (1, 5):
        out.append((f"drop{d}", f"{d} % of the samples dropped, timestamps given",
                    dict(drop_rate=d / 100.0), SETTLE))
    out.append(("jitter10", "sampling instants jittered +-10 % of the period, timestamps given",
                dict(time_jitter=0.1), SETTLE))
    out.append(("lost_mag20", "magnetometer rows NaN from 25 s to 45 s",
                dict(mag_lost=(25.0, 45.0)), SETTLE))
    out.append(("lost_accmag10", "accelerometer and magnetometer rows NaN from 30 s to 40 s",
                dict(acc_lost=(30.0, 40.0), mag_lost=(30.0, 40.0)), SETTLE))
    out.append(("start_flip180", "field reversed in heading for the first 0.5 s (a start 180 "
                "deg wrong)", dict(mag_flip_until=0.5), SETTLE))
    return out


def config_for(overrides, seed, quick):
    kw = dict(BASE, seed=seed, **overrides)
    if quick:
        scale = QUICK_DURATION / kw["duration"]
        kw["duration"] = QUICK_DURATION
        for k in ("pass_time", "attach_time", "attach_end"):
            if kw.get(k) is not None:
                kw[k] *= scale
        for k in ("yaw_spin_time", "acc_lost", "mag_lost"):  # event windows
            if kw.get(k) is not None:
                kw[k] = tuple(scale * x for x in kw[k])
    return imu_sim.SimConfig(**kw)


# ---- the filters ------------------------------------------------------------------------------


def run_bingham(trial):
    """(quaternions n×4, spread n (rad), bias estimate at the end (3, rad/s), seconds)."""
    import bingham
    f = bingham.Ahrs(trial["Ts"])
    t0 = time.perf_counter()
    q, spread = f.update_batch(trial["gyr"], trial["acc"], trial["mag"], spread=True,
                               time=trial.get("time"))
    seconds = time.perf_counter() - t0
    return np.asarray(q, dtype=float), np.asarray(spread, dtype=float), f.gyro_bias(), seconds


def run_smoother(trial):
    """The offline smoother (``bingham.smooth``, the whole trial): (quaternions n×4, spread n
    (rad), the smoothed bias at the last sample (3, rad/s), seconds)."""
    import bingham
    t0 = time.perf_counter()
    r = bingham.smooth(trial["gyr"], trial["acc"], trial["mag"], sample_time=trial["Ts"],
                       time=trial.get("time"), full=True)
    seconds = time.perf_counter() - t0
    return np.asarray(r.quat, dtype=float), np.asarray(r.spread, dtype=float), r.bias[-1], seconds


def vqf_bias(trial):
    """VQF's gyro bias estimate after the last sample (rad/s): ``broad.run_vqf`` returns only the
    quaternions, so this is a second run of the same filter on the same samples."""
    import vqf
    out = vqf.VQF(trial["Ts"]).updateBatch(trial["gyr"], trial["acc"], trial["mag"])
    return np.asarray(out["bias"][-1], dtype=float)


def peer_trial(trial):
    """The samples as VQF and Madgwick can take them. Both skip a sensor's correction on a
    sample of [0 0 0] (VQF's ``updateAcc``/``updateMag`` ignore it; the ``ahrs`` package's
    Madgwick integrates the gyroscope alone), while a NaN row spoils their state for good: a
    lost sample (NaN row) becomes a zero row, "skip". Neither takes timestamps (VQF's period
    is fixed at construction): with ``time``, VQF is given the gyroscope scaled by
    Δt_k / Ts, so that its fixed-step integration turns by exactly exp(gyr_k·Δt_k) (the
    corrections keep their nominal time constants), and Madgwick is run sample by sample with
    its ``dt`` argument (:func:`run_madgwick_timed`)."""
    out = dict(trial)
    for k in ("acc", "mag"):
        if np.isnan(trial[k]).any():
            out[k] = np.ascontiguousarray(np.nan_to_num(trial[k], nan=0.0))
    return out


def run_madgwick_timed(trial):
    """``broad.run_madgwick`` with a time step per sample (the ``ahrs`` package's
    ``updateMARG(..., dt=...)``), started as its batch mode is (``ecompass`` of the first
    sample)."""
    import ahrs
    from ahrs.common.orientation import ecompass
    t0 = time.perf_counter()
    f = ahrs.filters.Madgwick(frequency=trial["fs"], gain=0.12)
    gyr, acc, mag, t = trial["gyr"], trial["acc"], trial["mag"], trial["time"]
    q = np.zeros((len(t), 4))
    q[0] = ecompass(acc[0], mag[0], frame="NED", representation="quaternion")
    for k in range(1, len(t)):
        q[k] = f.updateMARG(q[k - 1], gyr[k], acc[k], mag[k], dt=t[k] - t[k - 1])
    seconds = time.perf_counter() - t0
    return broad.qmul(broad.NED_TO_ENU, q), seconds


def run_filter(name, trial):
    """(q, spread or None, bias estimate or None, seconds)."""
    if name == "bingham":
        return run_bingham(trial)
    if name == "smoother":
        return run_smoother(trial)
    trial = peer_trial(trial)
    timed = trial.get("time") is not None
    if name == "vqf_offline":
        import vqf
        if timed:
            dt = np.diff(trial["time"], prepend=trial["time"][0] - trial["Ts"])
            gyr = trial["gyr"] * (dt / trial["Ts"])[:, None]
            trial = dict(trial, gyr=np.ascontiguousarray(gyr))
        t0 = time.perf_counter()
        out = vqf.offlineVQF(trial["gyr"], trial["acc"], trial["mag"], trial["Ts"])
        seconds = time.perf_counter() - t0
        return (np.asarray(out["quat9D"], dtype=float), None,
                np.asarray(out["bias"][-1], dtype=float), seconds)
    if name == "vqf":
        if timed:
            dt = np.diff(trial["time"], prepend=trial["time"][0] - trial["Ts"])
            gyr = trial["gyr"] * (dt / trial["Ts"])[:, None]
            trial = dict(trial, gyr=np.ascontiguousarray(gyr))
        q, _, seconds = broad.run_vqf(trial)
        return np.asarray(q, dtype=float), None, vqf_bias(trial), seconds
    if timed:
        q, seconds = run_madgwick_timed(trial)
    else:
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


def settle_time(err, t, tol):
    """The time from which the error stays within ``tol`` to the end (0 if it always is; the
    last sample's time if it ends above)."""
    bad = np.nonzero(~(err <= tol))[0]
    if not len(bad):
        return 0.0
    return float(t[min(bad[-1] + 1, len(t) - 1)])


# ---- one scenario -----------------------------------------------------------------------------


def group_of(name):
    """The scenario family (table blocks): bias, rate, spin, latency, magnet, bursts."""
    for g in ("bias", "rate", "spin4_latency", "spin", "latency", "magnet", "bursts", "lever",
              "acc_", "field", "reject", "drop", "jitter", "lost", "start"):
        if name.startswith(g):
            return {"spin4_latency": "latency", "acc_": "acc", "drop": "timing",
                    "jitter": "timing"}.get(g, g)
    return name


# the groups of issue 34's scenarios (``--group issue34`` runs them all)
MECHANISM_GROUPS = ("lever", "acc", "field", "reject", "timing", "lost", "start")


def select_groups(todo, spec):
    """The scenarios of ``todo`` whose group (or name prefix) is in the comma-separated
    ``spec``; ``issue34`` stands for every group of :data:`MECHANISM_GROUPS`. (selected, the
    unknown entries)."""
    wanted = [g.strip() for g in spec.split(",") if g.strip()]
    expanded = []
    for g in wanted:
        expanded += list(MECHANISM_GROUPS) if g == "issue34" else [g]
    pick = [s for s in todo if any(group_of(s[0]) == g or s[0].startswith(g) for g in expanded)]
    unknown = [g for g in expanded
               if not any(group_of(s[0]) == g or s[0].startswith(g) for s in todo)]
    return pick, unknown


def evaluate(name, desc, overrides, settle, filters, seed, quick):
    cfg = config_for(overrides, seed, quick)
    t0 = time.perf_counter()
    sim = imu_sim.simulate(cfg)
    sim_seconds = time.perf_counter() - t0
    trial = {k: sim[k] for k in ("gyr", "acc", "mag", "fs", "Ts")}
    trial["time"] = sim["t"] if sim["timed"] else None
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
        r["within_5deg_after_s"] = settle_time(err["total"], sim["t"], 5.0 * DEG)
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
            if f == "bingham":
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
    bias_f = [f for f in filters if f in ("bingham", "smoother", "vqf", "vqf_offline")]
    w = 6 * len(filters) + len(filters) - 1
    head1 = f"{'':<18}" + "".join(f" | {title:^{w}}" for _, title in groups)
    head2 = f"{'scenario':<18}" + "".join(" | " + " ".join(f"{SHORT[f]:>6}" for f in filters)
                                          for _ in groups)
    if bias_f:
        wb = 6 * len(bias_f) + len(bias_f) - 1
        head1 += f" | {'bias err %':^{wb}}"
        head2 += " | " + " ".join(f"{SHORT[f]:>6}" for f in bias_f)
    ours = [f for f in ("bingham", "smoother") if f in filters]
    for f in ours:
        head1 += f" | {SHORT[f]:>5}"
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
        for f in ours:
            line += " | " + fmt(fr.get(f, {}).get("error_spread_ratio"), "{:5.2f}", 5)
        print(line)
    print()


def print_settling(results, filters):
    """For the ``start`` group (a start 180° wrong): per filter the time from which its total
    error stays within 5°."""
    rows = [(n, r) for n, r in results.items() if r["group"] == "start"]
    if not rows:
        return
    print("time from which the total error stays within 5 deg (s)")
    print(f"{'scenario':<18} | " + " ".join(f"{SHORT[f]:>6}" for f in filters))
    for name, res in rows:
        print(f"{name:<18} | " + " ".join(
            fmt(res["filters"].get(f, {}).get("within_5deg_after_s"), "{:6.1f}") for f in filters))
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
    ap.add_argument("--group", metavar="G,...",
                    help="only the scenarios of these groups or name prefixes (e.g. lever,timing; "
                         "issue34: " + ",".join(MECHANISM_GROUPS) + "); see --list")
    ap.add_argument("--list", action="store_true", help="list the scenarios and exit")
    args = ap.parse_args(argv)

    todo = scenarios()
    if args.group:
        todo, unknown = select_groups(todo, args.group)
        if unknown:
            print(f"unknown group(s): {', '.join(unknown)} (see --list)")
            return 2
    if args.list:
        for name, desc, _, settle in todo:
            print(f"{name:<24} {group_of(name):<10} {desc} (settling {settle:g} s)")
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
    print_settling(results, filters)
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
