#!/usr/bin/env python3
"""Offline high-precision reference values of the Bingham normalization constant.

Writes tests/data/normalization_d{d}.csv for d = 2..8 (and, with --extreme,
tests/data/normalization_extreme.csv; see tests/data/README.md).

Conventions (docs/design.md, § Conventions): F(Z) = ∫_{S^{d-1}} exp(xᵀ Z x) dx with the
SURFACE measure, Z = diag(z), z ascending, z_d = 0.  ω_i = ∂ log F/∂z_i = E[x_i²],
H_ij = ∂² log F/∂z_i∂z_j = E[x_i² x_j²] − ω_i ω_j.

Methods
  d = 2     closed form with the modified Bessel functions I0, I1, I2 (mpmath.besseli).
  d = 3, 4  the exact 1-D integrals of docs/design.md, § "d = 3, 4: one-dimensional Bessel
            integrals" (a coordinate times a circle, two circles), integrated for F,
            F·E[x_i²] and F·E[x_i²x_j²] at once with an adaptive composite Gauss–Legendre
            rule on geometrically graded panels at both ends of the interval (boundary
            layers of width ~1/|z|); Bessel functions in exponentially scaled form.
  d = 5..8  fixed-Talbot inversion of the Laplace transform of the (unnormalized) density of
            R = Σ λ_i y_i² (Kume & Wood 2005): F(Z) = 2 e^c π^{d/2} L⁻¹[Π(λ_i+s)^{-1/2}](1),
            λ_i = c − z_i; moments from the transforms of y_i² and y_i²y_j² weights,
            i.e. P(s)/(2(λ_i+s)) (= the Kume–Wood F_{d+2}-with-z_i-tripled identity) and
            P(s)/(4(λ_i+s)(λ_j+s)) (×3 if i = j).
Every data set is computed twice ("run A": 45 digits, "run B": 65 digits with a different
quadrature rule / panel grading / Talbot shift); the data (from run B) are written only if the
two runs agree to 1e-20 in every quantity: |Δ log F| (= relative error of F), relative log F,
relative ω_i, and H_ij relative to sqrt(H_ii H_jj) (some H_ij vanish to all digits, see
near_zero_H; those are written as 0).  Independent checks (asserted): brute-force
sphere quadrature (d = 3: 2-D, d = 4: 3-D, double precision), Talbot against the d = 2
closed form and the d = 3, 4 quadrature on every row, the Kume–Wood derivative identity
F_{d+2}(z_i tripled)/(2π) = F_d ω_i on every d = 3, 4 row, nested 2-D Bessel integrals for
d = 5, 6, mpmath.diff of log F, F(0) = |S^{d-1}|, Σω = 1, ΣH_ij = 0 (rows), permutation and
shift identities.

Usage: python3 scripts/reference_normalization.py [--quick] [--workers N]
       python3 scripts/reference_normalization.py --extreme [--quick]
       (only tests/data/normalization_extreme.csv: d = 2, 3, 4 at |z| = 1e10, 1e100, 1e300,
       log F and ω, checked against Talbot (1e10) or the factorized asymptote (≥ 1e100); ~25 s)
(full run: ~22 min wall with 2 workers on the 2-core dev VM while it was shared with builds;
~2500 s CPU in total.)
Requires only mpmath (pip install mpmath) and the standard library.

Files: this script (the grids, the rows computed in worker processes, the CSV output, the
command line), reference_normalization_methods.py (the numerical methods) and
reference_normalization_checks.py (the independent checks and the comparison of two runs).
"""

import argparse
import multiprocessing
import os
import random
import sys
import time

from mpmath import mp, mpf, libmp

from reference_normalization_checks import (
    _compare,
    check_identities,
    compare,
    run_extra_checks_wrapper,
    self_test_bessel,
)
from reference_normalization_methods import (
    RUN_A,
    RUN_B,
    besseli012e,
    closed_d2,
    compute,
    quad_d3,
    quad_d4,
    scale_of,
    talbot,
)

HERE = os.path.dirname(os.path.abspath(__file__))
OUTDIR = os.path.normpath(os.path.join(HERE, "..", "tests", "data"))

MAX_DISCREPANCY = mpf("1e-20")


# ----------------------------------------------------------------------------------------
# Grids
# ----------------------------------------------------------------------------------------

def r6(x):
    """Round to 6 significant digits (the result is the double nearest that decimal)."""
    return float("%.6g" % x)


def grid_d2():
    vals = {0.0, -1e-8, -0.5, -709.0, -710.0, -1428.0, -1e5, -1e6}
    for k in range(-64, 49):
        vals.add(-r6(10 ** (k / 8)))
    return [(v, 0.0) for v in sorted(vals)]


V = [0.0, -1e-6, -0.5, -1.0, -10.0, -100.0, -1e3, -1428.0, -1e4, -1e5, -5e5, -1e6]


def grid_d3(rng):
    pts = set()
    for i, a in enumerate(V):
        for b in V[i:]:
            pts.add(tuple(sorted((a, b))) + (0.0,))
    for _ in range(30):
        pts.add(tuple(sorted(-r6(10 ** rng.uniform(-6, 6)) for _ in range(2))) + (0.0,))
    pts |= {(-1e-9, -1e-9, 0.0), (-1e-9, -5e-10, 0.0), (-7.0, -7.0, 0.0), (-5e4, 0.0, 0.0),
            (-1e6, -1e-3, 0.0), (-1e6, -10.0, 0.0), (-2.0, -1.0, 0.0), (-200.0, -2.0, 0.0)}
    return sorted(pts)


def grid_d4(rng):
    pts = set()
    W = [0.0, -1e-6, -0.5, -10.0, -1e3, -1428.0, -1e5, -1e6]
    for i, a in enumerate(W):
        for j in range(i, len(W)):
            for k in range(j, len(W)):
                pts.add((W[k], W[j], W[i], 0.0))   # ascending
    pts = set(p for p in pts)
    for _ in range(25):
        pts.add(tuple(sorted(-r6(10 ** rng.uniform(-6, 6)) for _ in range(3))) + (0.0,))
    pts |= {(-1e6, -10.0, -1.0, 0.0), (-1e6, -1e6, -1e-3, 0.0), (-5e4, -5e4, 0.0, 0.0),
            (-7.0, -7.0, -7.0, 0.0), (-1e6, -1e6, -1e6, 0.0), (0.0, 0.0, 0.0, 0.0),
            (-1e-9, -1e-9, -1e-9, 0.0), (-3e-9, -2e-9, -1e-9, 0.0), (-1.0, -1.0, -1.0, 0.0),
            (-200.0, -200.0, -2.0, 0.0), (-500.0, -500.0, -500.0, 0.0), (-100.0, -100.0, -1.0, 0.0),
            (-1e4, -1e2, -1.0, 0.0), (-1e5, -1e3, -10.0, 0.0), (-1428.0, -710.0, -709.0, 0.0)}
    return sorted(pts)


def grid_high(d, rng):
    pts = set()
    pts.add(tuple([0.0] * d))
    pts.add(tuple([-1e-9] * (d - 1) + [0.0]))
    pts.add(tuple([-1.0] * (d - 1) + [0.0]))
    pts.add(tuple([-100.0] * (d - 1) + [0.0]))
    pts.add(tuple([-1e4] * (d - 1) + [0.0]))
    pts.add(tuple(sorted([-1e6] + [-1.0] * (d - 2)) + [0.0]))
    pts.add(tuple(sorted([-1e6] * (d - 2) + [-10.0]) + [0.0]))
    pts.add(tuple(sorted([-1e6, -1e4] + [-0.5] * (d - 3)) + [0.0]))
    pts.add(tuple(sorted([-1e5, -1e3] + [0.0] * (d - 3)) + [0.0]))
    while len(pts) < 40:
        kind = rng.random()
        if kind < 0.4:      # log-uniform magnitudes in [1e-3, 1e4]
            v = [-r6(10 ** rng.uniform(-3, 4)) for _ in range(d - 1)]
        elif kind < 0.7:    # uniform in [-1e4, 0] with ties
            base = [-r6(rng.uniform(0, 1e4)) for _ in range(max(1, (d - 1) // 2))]
            v = [rng.choice(base) for _ in range(d - 1)]
        else:               # a few small values and ties
            base = [-r6(10 ** rng.uniform(-2, 2)) for _ in range(2)]
            v = [rng.choice(base) for _ in range(d - 1)]
        pts.add(tuple(sorted(v)) + (0.0,))
    return sorted(pts)


# ----------------------------------------------------------------------------------------
# Row computations (run in worker processes)
# ----------------------------------------------------------------------------------------

def task_row(args):
    d, z = args
    t0 = time.time()
    A, evA = compute(d, z, RUN_A)
    B, evB = compute(d, z, RUN_B)
    extra = {}
    if d <= 4:
        # Talbot (independent of Bessel functions and quadrature) on every row
        with mp.workdps(RUN_A["dps"]):
            extra["talbot"] = talbot(z, RUN_A["dps"])
    if d in (3, 4):
        # Kume–Wood: F_{d+2}(z with z_i tripled) / (2π) = ∂F_d/∂z_i = F_d ω_i
        with mp.workdps(RUN_A["dps"]):
            kw = []
            for i in range(d):
                zz = list(z) + [z[i], z[i]]
                lf, _, _ = talbot(zz, RUN_A["dps"], want4=False)
                kw.append(lf - mp.log(2 * mp.pi))
            extra["kw"] = kw
    return d, z, A, B, extra, evA, evB, time.time() - t0


# ----------------------------------------------------------------------------------------
# Output: the values written to the CSV files
# ----------------------------------------------------------------------------------------

def near_zero_H(H, i, j):
    """|H_ij| below 1e-30 sqrt(H_ii H_jj): stored as 0 (the value is rounding noise of
    E[x_i²x_j²] - ω_iω_j; the true value is smaller than any stored digit)."""
    return abs(H[i][j]) < mpf(10) ** -30 * mp.sqrt(abs(H[i][i] * H[j][j]))


def fmt(x):
    return "%.17g" % libmp.to_float(mpf(x)._mpf_, rnd="n")


# ----------------------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="a few rows per d, no files written")
    ap.add_argument("--dims", default="2,3,4,5,6,7,8")
    ap.add_argument("--skip-extra", action="store_true")
    ap.add_argument("--extreme", action="store_true",
                    help="only the |z| = 1e10, 1e100, 1e300 rows (normalization_extreme.csv)")
    args = ap.parse_args()

    t_start = time.time()

    def log(msg):
        print("[%7.1fs] %s" % (time.time() - t_start, msg), flush=True)

    mp.dps = RUN_A["dps"]
    w = self_test_bessel()
    log("Bessel I0e/I1e/I2e (and I0-I1, 3I0-4I1+I2, I0-I2) vs mpmath.besseli: max error %s ulp(dps)" % mp.nstr(w, 2))
    if args.extreme:
        main_extreme(args, log)
        return

    rng = random.Random(20240607)
    dims = [int(x) for x in args.dims.split(",")]
    grids = {2: grid_d2(), 3: grid_d3(rng), 4: grid_d4(rng)}
    for d in (5, 6, 7, 8):
        grids[d] = grid_high(d, rng)
    if args.quick:
        for d in grids:
            g = grids[d]
            grids[d] = [g[0], g[len(g) // 3], g[-1]]
    tasks = [(d, z) for d in dims for z in grids[d]]
    # expensive first
    tasks.sort(key=lambda t: -{2: 0, 3: 2, 4: 3}.get(t[0], 1))
    results = {}
    with multiprocessing.Pool(args.workers) as pool:
        if not args.skip_extra:
            extra_async = pool.apply_async(run_extra_checks_wrapper)
        for i, r in enumerate(pool.imap_unordered(task_row, tasks, chunksize=1)):
            d, z, A, B, extra, evA, evB, dt = r
            results[(d, z)] = r
            if (i + 1) % 25 == 0 or i + 1 == len(tasks):
                log("%d/%d rows done" % (i + 1, len(tasks)))
        if not args.skip_extra:
            extra_lines, _ = extra_async.get()
            for line in extra_lines:
                log("[extra checks] " + line)

    mp.dps = RUN_A["dps"]
    ok = True
    summary = {}
    for d in dims:
        rows = [results[(d, z)] for z in grids[d]]
        disc = {}
        tal = {}
        kw = mpf(0)
        evs = []
        tsum = 0.0
        for (_, z, A, B, extra, evA, evB, dt) in rows:
            for k, v in compare(d, A, B).items():
                disc[k] = max(disc.get(k, mpf(0)), v)
            check_identities(d, z, A)
            check_identities(d, z, B)
            if "talbot" in extra:
                for k, v in compare(d, A, extra["talbot"]).items():
                    tal[k] = max(tal.get(k, mpf(0)), v)
            if "kw" in extra:
                for i in range(d):
                    kw = max(kw, abs(extra["kw"][i] - (A[0] + mp.log(A[1][i]))))
            evs.append((evA, evB))
            tsum += dt
        log("d=%d: %d rows, %.1f s CPU in rows" % (d, len(rows), tsum))
        log("  run A (dps %d) vs run B (dps %d): max |dlogF| %s, rel logF %s, rel omega %s, "
            "H (scaled by sqrt(HiiHjj)) %s, rel H (entries not near 0) %s"
            % (RUN_A["dps"], RUN_B["dps"], mp.nstr(disc["dlogF"], 2), mp.nstr(disc["rlogF"], 2),
               mp.nstr(disc["omega"], 2), mp.nstr(disc["H"], 2), mp.nstr(disc["Hrel"], 2)))
        if d in (3, 4):
            log("  quadrature nodes per row: run A %d..%d, run B %d..%d"
                % (min(e[0] for e in evs), max(e[0] for e in evs), min(e[1] for e in evs), max(e[1] for e in evs)))
        if tal:
            log("  Talbot (dps %d) vs run A: |dlogF| %s, rel omega %s, scaled H %s, rel H %s"
                % (RUN_A["dps"], mp.nstr(tal["dlogF"], 2), mp.nstr(tal["omega"], 2), mp.nstr(tal["H"], 2),
                   mp.nstr(tal["Hrel"], 2)))
            if max(tal["dlogF"], tal["omega"]) > mpf(10) ** -25 or tal["H"] > mpf(10) ** -20:
                ok = False
                log("  ERROR: Talbot disagrees")
        if d in (3, 4):
            log("  Kume-Wood log(F_%d(z_i tripled)/2pi) vs log(F_%d w_i): max |diff| %s" % (d + 2, d, mp.nstr(kw, 2)))
            if kw > mpf(10) ** -25:
                ok = False
        for k, v in disc.items():
            if v > MAX_DISCREPANCY:
                ok = False
                log("  ERROR: discrepancy %s = %s exceeds %s" % (k, mp.nstr(v, 3), MAX_DISCREPANCY))
        summary[d] = disc
    if not ok:
        log("REFUSING to write the data: checks failed")
        sys.exit(1)
    if args.quick:
        log("quick mode: no files written (%.1f s)" % (time.time() - t_start))
        return
    os.makedirs(OUTDIR, exist_ok=True)
    nzero = {}
    for d in dims:
        rows = [results[(d, z)] for z in grids[d]]
        path = os.path.join(OUTDIR, "normalization_d%d.csv" % d)
        header = (["d"] + ["z%d" % (i + 1) for i in range(d)] + ["logF"] + ["omega%d" % (i + 1) for i in range(d)]
                  + ["H%d%d" % (i + 1, j + 1) for i in range(d) for j in range(d)])
        with open(path, "w") as fh:
            fh.write(",".join(header) + "\n")
            for (_, z, A, B, extra, evA, evB, dt) in rows:
                logF, om, H = B          # the higher-precision run
                Hs = []
                for i in range(d):
                    for j in range(d):
                        if near_zero_H(H, i, j) and near_zero_H(A[2], i, j):
                            Hs.append("0")
                            nzero[d] = nzero.get(d, 0) + 1
                        else:
                            Hs.append(fmt(H[i][j]))
                vals = [str(d)] + [repr(float(v)) for v in z] + [fmt(logF)] + [fmt(o) for o in om] + Hs
                fh.write(",".join(vals) + "\n")
        log("wrote %s (%d rows; %d near-zero H entries written as 0)"
            % (os.path.relpath(path), len(rows), nzero.get(d, 0)))
    log("done in %.1f s" % (time.time() - t_start))


# ----------------------------------------------------------------------------------------
# --extreme: |z| = 1e10, 1e100, 1e300 for d = 2, 3, 4 (tests/data/normalization_extreme.csv)
# ----------------------------------------------------------------------------------------

def grid_extreme():
    """Rows with concentrations of magnitude M = 1e10, 1e100, 1e300 (z ascending, z_d = 0).

    Chosen so that the graded quadrature needs few panels: every row's integrand decays like
    e^{-|z|·u} away from the layers (see extreme_tops), except (-1e10, -1, -1, 0), whose right
    half is kept in full."""
    rows = []
    for M in (1e10, 1e100, 1e300):
        rows += [
            (2, (-M, 0.0)), (2, (-0.37 * M, 0.0)),
            (3, (-M, -M, 0.0)), (3, (-M, -0.5 * M, 0.0)), (3, (-M, -1e-3 * M, 0.0)),
            (3, (-M, -1.0, 0.0)), (3, (-M, 0.0, 0.0)),
            (4, (-M, -M, -M, 0.0)), (4, (-M, -0.1 * M, -0.01 * M, 0.0)),
            (4, (-M, -0.5 * M, 0.0, 0.0)), (4, (-M, -M, -1.0, 0.0)),
            (4, (-M, -0.3 * M, -2.5, 0.0)),
        ]
    rows.append((4, (-1e10, -1.0, -1.0, 0.0)))
    return rows


def extreme_tops(d, z, dps):
    """Where each half's grading may stop: beyond `top` the integrand is below e^{-K} times
    its peak, with K = (dps + 10) ln 10 + 2 ln(S + 1) + 50 (S = the largest |z_i - z_j|; the
    total is at least ~S^{-2} of the peak). d = 3 (variable t, factor e^{z1 t²}): left top
    √(K/|z1|); the right half (t ≥ 1/2, factor ≤ e^{z1/4}) needs no grading if |z1|/4 > K.
    d = 4 (variable u, factor e^{u z2}): left top K/|z2|; the right half (≤ e^{z2/2}) needs no
    grading if |z2|/2 > K. One panel [top, 1/2] still covers the rest."""
    K = (dps + 10) * mp.log(10) + 2 * mp.log(scale_of(z) + 1) + 50
    if d == 3:
        a = abs(mpf(z[0]))
        left = mp.sqrt(K / a) if a > 0 and K / a < mpf(1) / 16 else None
        right = mpf(0) if a / 4 > K else None
    else:
        a = abs(mpf(z[1]))
        left = K / a if a > 0 and K / a < mpf(1) / 4 else None
        right = mpf(0) if a / 2 > K else None
    return (left, right)


def compute_extreme(d, z, run):
    with mp.workdps(run["dps"]):
        if d == 2:
            # the closed form with the script's scaled Bessel functions (Hankel expansion at
            # large x): log F = log 2π + log(I0e(x)) + (z1/2 + x), x = -z1/2
            z1 = mpf(z[0])
            x = -z1 / 2
            i0, i1, i2 = besseli012e(x)
            logF = mp.log(2 * mp.pi) + mp.log(i0) + (z1 / 2 + x)   # (z1/2 + x = 0 exactly)
            with mp.workprec(mp.prec + 60):
                om = [(i0 - i1) / (2 * i0), (i0 + i1) / (2 * i0)]
            res, ev = (logF, om, None), 0
        elif d == 3:
            res, ev = quad_d3(z, run, want4=False, tops=extreme_tops(d, z, run["dps"]))
        else:
            res, ev = quad_d4(z, run, want4=False, tops=extreme_tops(d, z, run["dps"]))
        logF, om, _ = res
        return (+logF, [+o for o in om], None), ev


def factorized_asymptote(z, dps):
    """Independent check for rows whose entries are either huge (|z_i| ≥ 1e50) or moderate:
    the huge coordinates are Gaussian, F_d(z) = Π_huge √(π/|z_i|) · F_k(z_rest) with a relative
    correction O(max|z_rest| / min|z_huge|) ≤ 1e-40 here, and ω_i = 1/(2|z_i|) for the huge
    ones (F_1 = 2; F_2 by mpmath.besseli; F_3 by the quadrature at moderate z)."""
    with mp.workdps(dps):
        huge = [mpf(v) for v in z if abs(v) >= 1e50]
        rest = [v for v in z if abs(v) < 1e50]
        k = len(rest)
        if k == 1:
            lr, orest = mp.log(2), [mpf(1)]
        elif k == 2:
            lr, orest, _ = closed_d2(rest)
        else:
            (lr, orest, _), _ = quad_d3(rest, RUN_A, want4=False)
        logF = lr + sum(mp.log(mp.pi / abs(v)) / 2 for v in huge)
        om = []
        it = iter(orest)
        for v in z:
            om.append(1 / (2 * abs(mpf(v))) if abs(v) >= 1e50 else next(it))
        return logF, om, None


def task_extreme(args):
    d, z = args
    t0 = time.time()
    A, evA = compute_extreme(d, z, RUN_A)
    B, evB = compute_extreme(d, z, RUN_B)
    extra = {}
    M = max(abs(v) for v in z)
    if M <= 1e10:
        with mp.workdps(RUN_A["dps"]):
            extra["talbot"] = talbot(z, RUN_A["dps"], want4=False)
    else:
        extra["asymptote"] = factorized_asymptote(z, RUN_A["dps"])
    return d, z, A, B, extra, evA, evB, time.time() - t0


def main_extreme(args, log):
    tasks = grid_extreme()
    if args.quick:
        tasks = [tasks[0], tasks[7], tasks[-2]]
    results = {}
    with multiprocessing.Pool(args.workers) as pool:
        for r in pool.imap_unordered(task_extreme, tasks, chunksize=1):
            d, z, A, B, extra, evA, evB, dt = r
            results[(d, z)] = r
            log("d=%d z=%s: %.1f s, nodes A %d B %d" % (d, z, dt, evA, evB))
    ok = True
    worst = {}
    mp.dps = RUN_A["dps"]
    for (d, z) in tasks:
        _, _, A, B, extra, _, _, _ = results[(d, z)]
        with mp.workdps(RUN_B["dps"] + 20):
            disc = _compare(d, A, B)
            assert abs(mp.fsum(B[1]) - 1) < mpf(10) ** -35, ("sum omega", d, z)
            assert all(o > 0 for o in B[1])
            for key in ("talbot", "asymptote"):
                if key in extra:
                    c = _compare(d, A, extra[key])
                    worst[key] = max(worst.get(key, mpf(0)), c["dlogF"], c["omega"])
                    if max(c["dlogF"], c["omega"]) > mpf(10) ** -25:
                        ok = False
                        log("ERROR: %s disagrees at d=%d z=%s: %s" % (key, d, z, c))
        for k, v in disc.items():
            worst["AB " + k] = max(worst.get("AB " + k, mpf(0)), v)
            if v > MAX_DISCREPANCY:
                ok = False
                log("ERROR: run A vs B %s = %s at d=%d z=%s" % (k, mp.nstr(v, 3), d, z))
    for k, v in sorted(worst.items()):
        log("max %s: %s" % (k, mp.nstr(v, 2)))
    if not ok:
        log("REFUSING to write the data: checks failed")
        sys.exit(1)
    if args.quick:
        log("quick mode: no files written")
        return
    path = os.path.join(OUTDIR, "normalization_extreme.csv")
    with open(path, "w") as fh:
        fh.write("# d,z1..zd,logF,omega1..omegad (variable length: d = 2, 3, 4); written by\n"
                 "# scripts/reference_normalization.py --extreme (run B, 65 digits; see tests/data/README.md)\n")
        for (d, z) in tasks:
            logF, om, _ = results[(d, z)][3]
            vals = [str(d)] + [repr(float(v)) for v in z] + [fmt(logF)] + [fmt(o) for o in om]
            fh.write(",".join(vals) + "\n")
    log("wrote %s (%d rows)" % (os.path.relpath(path), len(tasks)))


if __name__ == "__main__":
    main()
