"""The independent checks of scripts/reference_normalization.py: the scaled Bessel functions
against mpmath.besseli (self_test_bessel), brute-force sphere quadrature in double precision
(d = 3, 4), nested 2-D Bessel integrals (d = 5, 6), the comparison of two results (compare:
|Δ log F|, relative log F, ω and H), the identities every row must satisfy (check_identities),
and the extra checks run beside the rows (run_extra_checks: brute force, nested integrals,
permutation and shift identities, mpmath.diff of log F).
"""

import math

from mpmath import mp, mpf

from reference_normalization_methods import (
    RUN_A,
    RUN_B,
    Integrator,
    besseli012e,
    circle_block,
    compute,
    finish,
    gauss_legendre,
    quad_d3,
    quad_d4,
    talbot,
)


def self_test_bessel():
    worst = mpf(0)
    for dps in (RUN_A["dps"], RUN_B["dps"]):
        with mp.workdps(dps):
            for xs in ["1e-9", "1e-3", "0.5", "1", "3", "10", "30", "60", "70", "80", "90",
                       "100", "110", "150", "1e3", "1e4", "5e5", "1e6", "1.7e6"]:
                x = mpf(xs)
                a = besseli012e(x)
                with mp.extradps(30):
                    b = [mp.besseli(n, x) * mp.exp(-x) for n in (0, 1, 2)]
                    errs = [abs(a[i] / b[i] - 1) for i in range(3)]
                    errs.append(abs((a[0] - a[1]) / (b[0] - b[1]) - 1))
                    errs.append(abs((3 * a[0] - 4 * a[1] + a[2]) / (3 * b[0] - 4 * b[1] + b[2]) - 1))
                    errs.append(abs((a[0] - a[2]) / (b[0] - b[2]) - 1))
                e = max(errs) * mpf(10) ** dps
                worst = max(worst, e)
    assert worst < 1e-3, worst
    return worst


# ----------------------------------------------------------------------------------------
# Independent brute-force sphere quadrature (double precision)
# ----------------------------------------------------------------------------------------

def gl_double(n, a, b):
    with mp.workdps(30):
        xs, ws = gauss_legendre(n)
        h = (mpf(b) - a) / 2
        m = (mpf(b) + a) / 2
        return [float(m + h * x) for x in xs], [float(h * w) for w in ws]


def moments_from_sums(d, S0, S2, S4):
    logF = math.log(S0)
    om = [v / S0 for v in S2]
    H = [[S4[i][j] / S0 - om[i] * om[j] for j in range(d)] for i in range(d)]
    return logF, om, H


def brute_d3(z, nth=160, nph=160):
    """x = (sinθ cosφ, sinθ sinφ, cosθ), dA = sinθ dθ dφ: Gauss–Legendre in θ, trapezoid in φ
    (the pole is x3 here, x1 in the 1-D form)."""
    z1, z2, z3 = z
    ths, wts = gl_double(nth, 0.0, math.pi)
    cs = [(math.cos(2 * math.pi * k / nph) ** 2, math.sin(2 * math.pi * k / nph) ** 2) for k in range(nph)]
    wph = 2 * math.pi / nph
    S0 = []
    S2 = [[] for _ in range(3)]
    S4 = [[[] for _ in range(3)] for _ in range(3)]
    for th, wt in zip(ths, wts):
        st2, ct2 = math.sin(th) ** 2, math.cos(th) ** 2
        w0 = wt * math.sin(th) * wph
        s0 = 0.0
        acc2 = [0.0] * 3
        acc4 = [[0.0] * 3 for _ in range(3)]
        for c2, s2 in cs:
            x = (st2 * c2, st2 * s2, ct2)
            e = math.exp(z1 * x[0] + z2 * x[1] + z3 * x[2])
            s0 += e
            for i in range(3):
                acc2[i] += e * x[i]
                for j in range(i, 3):
                    acc4[i][j] += e * x[i] * x[j]
        S0.append(w0 * s0)
        for i in range(3):
            S2[i].append(w0 * acc2[i])
            for j in range(i, 3):
                S4[i][j].append(w0 * acc4[i][j])
    s0 = math.fsum(S0)
    s2 = [math.fsum(v) for v in S2]
    s4 = [[0.0] * 3 for _ in range(3)]
    for i in range(3):
        for j in range(i, 3):
            s4[i][j] = s4[j][i] = math.fsum(S4[i][j])
    return moments_from_sums(3, s0, s2, s4)


def brute_d4(z, nps=64, nth=64, nph=64):
    """x = (cosψ, sinψ cosθ, sinψ sinθ cosφ, sinψ sinθ sinφ), dA = sin²ψ sinθ dψ dθ dφ."""
    z1, z2, z3, z4 = z
    pss, wps = gl_double(nps, 0.0, math.pi)
    ths, wts = gl_double(nth, 0.0, math.pi)
    cs = [(math.cos(2 * math.pi * k / nph) ** 2, math.sin(2 * math.pi * k / nph) ** 2) for k in range(nph)]
    wph = 2 * math.pi / nph
    S0 = []
    S2 = [[] for _ in range(4)]
    S4 = [[[] for _ in range(4)] for _ in range(4)]
    for ps, wp_ in zip(pss, wps):
        sp2, cp2 = math.sin(ps) ** 2, math.cos(ps) ** 2
        for th, wt in zip(ths, wts):
            st2, ct2 = math.sin(th) ** 2, math.cos(th) ** 2
            w0 = wp_ * wt * sp2 * math.sin(th) * wph
            a, b, q = cp2, sp2 * ct2, sp2 * st2
            base = z1 * a + z2 * b
            s0 = 0.0
            acc2 = [0.0] * 4
            acc4 = [[0.0] * 4 for _ in range(4)]
            for c2, s2 in cs:
                x = (a, b, q * c2, q * s2)
                e = math.exp(base + z3 * x[2] + z4 * x[3])
                s0 += e
                for i in range(4):
                    acc2[i] += e * x[i]
                    for j in range(i, 4):
                        acc4[i][j] += e * x[i] * x[j]
            S0.append(w0 * s0)
            for i in range(4):
                S2[i].append(w0 * acc2[i])
                for j in range(i, 4):
                    S4[i][j].append(w0 * acc4[i][j])
    s0 = math.fsum(S0)
    s2 = [math.fsum(v) for v in S2]
    s4 = [[0.0] * 4 for _ in range(4)]
    for i in range(4):
        for j in range(i, 4):
            s4[i][j] = s4[j][i] = math.fsum(S4[i][j])
    return moments_from_sums(4, s0, s2, s4)


# ----------------------------------------------------------------------------------------
# Nested 2-D Bessel integrals for d = 5, 6 (independent of the Laplace inversion)
# ----------------------------------------------------------------------------------------

def nested_d5(z, n=30):
    """F_5 = 2 ∫_0^1 (1-t²) e^{z1 t²} F_4((1-t²)(z2..z5)) dt  (x1 = t, then S³ of radius² 1-t²);
    E[x1²] ↔ t², E[x_j²] ↔ (1-t²) ω^{(4)}_j.  Fixed rules (moderate z only)."""
    run = dict(n=n, ratio=2.0, offset=1.0, dps=mp.dps)
    zs = [mpf(v) for v in z]

    def f(t, s):
        rho = s * (1 + t)
        (lf4, om4, _), _ = quad_d4([rho * v for v in zs[1:]], run, want4=False, adaptive=False)
        g = 2 * rho * mp.exp(zs[0] * t * t + lf4)
        return [g, g * t * t] + [g * rho * o for o in om4]

    integ = Integrator(n, 2.0, None)
    vec = integ.integrate(f, mpf(1) / 4, mpf(1) / 4, adaptive=False)
    return finish(5, vec, mpf(0), want4=False)


def nested_d6(z, n=30):
    """F_6 = π ∫_0^1 (1-r) C_{12}(r) F_4((1-r)(z3..z6)) dr, C_{12}(r) = e^{r(z1+z2)/2} I0(r(z2-z1)/2)
    (three circles of radii² r, r2, 1-r-r2)."""
    run = dict(n=n, ratio=2.0, offset=1.0, dps=mp.dps)
    zs = [mpf(v) for v in z]

    def f(r, rho):
        (lf4, om4, _), _ = quad_d4([rho * v for v in zs[2:]], run, want4=False, adaptive=False)
        m0, m2, _ = circle_block(r, zs[0], zs[1])
        g = mp.pi * rho * mp.exp(lf4)
        return [g * m0, g * m2[0], g * m2[1]] + [g * m0 * rho * o for o in om4]

    integ = Integrator(n, 2.0, None)
    vec = integ.integrate(f, mpf(1) / 4, mpf(1) / 4, adaptive=False)
    return finish(6, vec, mpf(0), want4=False)


def rel(a, b):
    a, b = mpf(a), mpf(b)
    m = max(abs(a), abs(b))
    return mpf(0) if m == 0 else abs(a - b) / m


def compare(d, X, Y):
    """max discrepancies: |ΔlogF| (= relative error of F), relative in log F, ω, H."""
    with mp.workdps(RUN_B["dps"] + 20):
        return _compare(d, X, Y)


def _compare(d, X, Y):
    (lx, ox, hx), (ly, oy, hy) = X, Y
    out = {"dlogF": abs(lx - ly), "rlogF": rel(lx, ly),
           "omega": max(rel(a, b) for a, b in zip(ox, oy))}
    if hx is not None and hy is not None:
        # H_ij relative to sqrt(H_ii H_jj) (Cauchy–Schwarz scale of a covariance): some
        # off-diagonal entries vanish to leading order (e.g. z1 = z2 on one circle, where
        # E[x1²x2²] - ω1ω2 is exponentially small), so a plain relative error is meaningless.
        out["H"] = max(abs(hx[i][j] - hy[i][j]) / mp.sqrt(abs(hx[i][i] * hx[j][j]))
                       for i in range(d) for j in range(d))
        # plain relative error over the entries that are not near-zero
        out["Hrel"] = max(rel(hx[i][j], hy[i][j]) for i in range(d) for j in range(d)
                          if abs(hx[i][j]) > mpf(10) ** -6 * mp.sqrt(abs(hx[i][i] * hx[j][j])))
    return out


# ----------------------------------------------------------------------------------------
# Checks that run in the main process
# ----------------------------------------------------------------------------------------

def check_identities(d, z, res):
    logF, om, H = res
    with mp.workdps(RUN_A["dps"]):
        s = abs(mp.fsum(om) - 1)
        assert s < mpf(10) ** -35, ("sum omega", d, z, s)
        for i in range(d):
            rs = abs(mp.fsum(H[i])) / max(abs(h) for h in H[i])
            assert rs < mpf(10) ** -20, ("row sum H", d, z, rs)
        for o in om:
            assert o > 0
        if all(v == 0 for v in z):
            exact = mp.log(2 * mp.pi ** (mpf(d) / 2) / mp.gamma(mpf(d) / 2))
            assert abs(logF - exact) < mpf(10) ** -35, ("F(0)", d)
            for o in om:
                assert abs(o - mpf(1) / d) < mpf(10) ** -35
            for i in range(d):
                for j in range(d):
                    e4 = mpf(3 if i == j else 1) / (d * (d + 2))
                    assert abs(H[i][j] - (e4 - mpf(1) / d ** 2)) < mpf(10) ** -35


def run_extra_checks(log):
    """Brute force, nested integrals, permutation/shift identities, mpmath.diff."""
    worst = {}

    def note(key, v):
        worst[key] = max(worst.get(key, mpf(0)), mpf(v))

    mp.dps = RUN_A["dps"]
    # brute force d = 3 (double precision) vs the 1-D form at 45 digits
    for z in [(-50.0, -20.0, 0.0), (-10.0, -1.0, 0.0), (-3.0, -3.0, 0.0), (-0.5, -1e-6, 0.0),
              (-30.0, 0.0, 0.0), (-1.0, -1.0, 0.0)]:
        (q, _) = quad_d3(z, RUN_A)
        b = brute_d3(z)
        c = compare(3, q, b)
        for k, v in c.items():
            note("brute3_" + k, v)
        assert c["dlogF"] < 1e-12 and c["omega"] < 1e-12 and c["H"] < 1e-12, (z, c)
    log("brute-force d=3 (2-D, 160x160, double): " + fmtw(worst, "brute3_"))
    for z in [(-20.0, -5.0, -1.0, 0.0), (-10.0, -10.0, -2.0, 0.0), (-1.0, -0.5, -0.5, 0.0),
              (-15.0, -3.0, -3.0, 0.0)]:
        (q, _) = quad_d4(z, RUN_A)
        b = brute_d4(z)
        c = compare(4, q, b)
        for k, v in c.items():
            note("brute4_" + k, v)
        assert c["dlogF"] < 1e-12 and c["omega"] < 1e-12 and c["H"] < 1e-12, (z, c)
    log("brute-force d=4 (3-D, 64^3, double): " + fmtw(worst, "brute4_"))

    # permutation invariance of the quadrature (a different coordinate / circle pairing)
    for z in [(-1e6, -10.0, 0.0), (-1e4, -1e4, 0.0), (-3.5, -1.0, 0.0), (-1e5, -0.5, 0.0)]:
        (q, _) = quad_d3(z, RUN_A)
        for perm in [(1, 0, 2), (2, 1, 0), (0, 2, 1)]:
            zp = [z[p] for p in perm]
            (qp, _) = quad_d3(zp, RUN_A)
            lp, op, hp = qp
            inv = [perm.index(i) for i in range(3)]
            back = (lp, [op[inv[i]] for i in range(3)], [[hp[inv[i]][inv[j]] for j in range(3)] for i in range(3)])
            c = compare(3, q, back)
            for k, v in c.items():
                note("perm_" + k, v)
    for z in [(-1e6, -10.0, -1.0, 0.0), (-5e4, -5e4, 0.0, 0.0), (-7.0, -3.0, -1.0, 0.0), (-1e5, -1e3, -1e3, 0.0)]:
        (q, _) = quad_d4(z, RUN_A)
        for perm in [(0, 2, 1, 3), (0, 3, 1, 2), (3, 2, 1, 0)]:
            zp = [z[p] for p in perm]
            (qp, _) = quad_d4(zp, RUN_A)
            lp, op, hp = qp
            inv = [perm.index(i) for i in range(4)]
            back = (lp, [op[inv[i]] for i in range(4)], [[hp[inv[i]][inv[j]] for j in range(4)] for i in range(4)])
            c = compare(4, q, back)
            for k, v in c.items():
                note("perm_" + k, v)
    log("permutation invariance (d=3, 4 quadrature with permuted z): " + fmtw(worst, "perm_"))
    assert all(worst[k] < mpf(10) ** -30 for k in worst if k.startswith("perm_"))

    # shift: F(Z + aI) = e^a F(Z)
    for d, z in [(3, (-1e6, -10.0, 0.0)), (3, (-2.0, -1.0, 0.0)), (4, (-1e5, -10.0, -1.0, 0.0)), (2, (-1428.0, 0.0)),
                 (6, (-1e4, -100.0, -100.0, -5.0, -1.0, 0.0))]:
        for a in (-3.25, 2.5):
            za = [v + a for v in z]
            (r0, _) = compute(d, z, RUN_A)
            (r1, _) = compute(d, za, RUN_A)
            c = compare(d, (r0[0] + a, r0[1], r0[2]), r1)
            for k, v in c.items():
                note("shift_" + k, v)
    log("shift identity F(Z+aI) = e^a F(Z): " + fmtw(worst, "shift_"))
    assert all(worst[k] < mpf(10) ** -30 for k in worst if k.startswith("shift_"))

    # mpmath.diff of log F (d = 2 closed form, d = 5..8 Talbot) against ω
    for d, z in [(2, (-3.0, 0.0)), (5, (-100.0, -10.0, -3.0, -1.0, 0.0)), (6, (-50.0, -50.0, -5.0, -1.0, -1.0, 0.0)),
                 (7, (-1e3, -100.0, -10.0, -10.0, -1.0, -0.1, 0.0)), (8, (-20.0, -10.0, -5.0, -4.0, -3.0, -2.0, -1.0, 0.0))]:
        (r0, _) = compute(d, z, RUN_A)
        for i in range(d):
            def lf(x, i=i):
                zz = list(z)
                zz[i] = x
                return compute(d, zz, RUN_A)[0][0] if d == 2 else talbot(zz, RUN_A["dps"] + 20, want4=False)[0]
            with mp.workdps(RUN_A["dps"]):
                g = mp.diff(lf, mpf(z[i]), h=mpf(10) ** -12)
            note("diff_omega", rel(g, r0[1][i]))
    log("mpmath.diff(log F) vs omega: " + fmtw(worst, "diff_"))
    assert worst["diff_omega"] < mpf(10) ** -20

    # nested 2-D Bessel integrals, d = 5 and 6, vs Talbot
    with mp.workdps(30):
        for z in [(-5.0, -3.0, -2.0, -1.0, 0.0), (-4.0, -4.0, -0.5, -0.5, 0.0), (-2.0, -1.0, -1.0, -1.0, 0.0),
                  (0.0, 0.0, 0.0, 0.0, 0.0)]:
            n = nested_d5(z)
            t = talbot(z, 30, want4=False)
            c = compare(5, n, t)
            for k, v in c.items():
                note("nested5_" + k, v)
        for z in [(-5.0, -3.0, -2.0, -1.5, -1.0, 0.0), (-4.0, -4.0, -4.0, -0.5, -0.5, 0.0),
                  (-3.0, -0.25, -1.0, -2.0, -0.5, 0.0)]:
            n = nested_d6(z)
            t = talbot(z, 30, want4=False)
            c = compare(6, n, t)
            for k, v in c.items():
                note("nested6_" + k, v)
    log("nested 2-D Bessel integrals vs Talbot, d=5: " + fmtw(worst, "nested5_") +
        "; d=6: " + fmtw(worst, "nested6_"))
    assert all(worst[k] < mpf(10) ** -25 for k in worst if k.startswith("nested"))
    return worst


def fmtw(worst, prefix):
    return ", ".join("%s %s" % (k[len(prefix):], mp.nstr(v, 2)) for k, v in sorted(worst.items()) if k.startswith(prefix))


def run_extra_checks_wrapper():
    lines = []
    worst = run_extra_checks(lines.append)
    return lines, {k: str(v) for k, v in worst.items()}
