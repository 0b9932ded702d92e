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
"""

import argparse
import math
import multiprocessing
import os
import random
import sys
import time

from mpmath import mp, mpf, libmp

HERE = os.path.dirname(os.path.abspath(__file__))
OUTDIR = os.path.normpath(os.path.join(HERE, "..", "tests", "data"))

# The two runs.  dps: working decimal digits; n: Gauss–Legendre nodes per panel;
# ratio/offset: geometric panel grading; shift: added to the Talbot shift c.
RUN_A = dict(name="A", dps=45, n=32, ratio=2.0, offset=1.0, shift=0.0)
RUN_B = dict(name="B", dps=65, n=48, ratio=2.0, offset=0.7, shift=0.5)
MAX_DISCREPANCY = mpf("1e-20")


# ----------------------------------------------------------------------------------------
# Bessel functions I0, I1, I2, exponentially scaled, at the current precision + 60 bits
# ----------------------------------------------------------------------------------------

def besseli012e(x):
    """(I0(x), I1(x), I2(x)) * exp(-x) for mpf x >= 0, accurate to ~mp.prec + 50 bits.

    Power series in fixed point for small x; the (convergent up to its least term, which is
    ~e^{-2x}) Hankel expansion for x > (wp + 20) ln2 / 2.  Checked against mpmath.besseli
    in self_test_bessel().  The guard bits keep combinations like 3I0 - 4I1 + I2
    (~1/x² relative at large x) accurate.
    """
    # 2 log2(x) more bits for large x: the combinations I0 - I1 (~I0/(2x)) and 3I0 - 4I1 + I2
    # (~I0/x²) are formed by subtraction and must keep mp.prec + 60 bits (x up to 1e308 for
    # the --extreme rows).
    wp = mp.prec + 60 + (2 * int(mp.log(mpf(x), 2)) if x > 1 else 0)
    with mp.workprec(wp):
        x = mpf(x)
        if x == 0:
            return mpf(1), mpf(0), mpf(0)
        if x > (wp + 20) * 0.34657359 + 5:
            one = 1 << wp
            xinv8 = libmp.to_fixed((1 / (8 * x))._mpf_, wp)
            res = []
            for nu in (0, 1, 2):
                c = 4 * nu * nu
                t = one
                s = one
                k = 1
                while True:
                    t = ((t * ((2 * k - 1) ** 2 - c) * xinv8) >> wp) // k
                    s += t
                    if abs(t) < 4:
                        break
                    k += 1
                    if k > 4 * wp:
                        raise RuntimeError("Hankel expansion did not converge")
                res.append(s)
            f = mpf(2) ** (-wp) / mp.sqrt(2 * mp.pi * x)
            return res[0] * f, res[1] * f, res[2] * f
        X = libmp.to_fixed(x._mpf_, wp)
        Q = (X * X) >> (wp + 2)          # x²/4
        t = 1 << wp
        s0 = s1 = s2 = 0
        k = 0
        while t:
            s0 += t
            s1 += t // (k + 1)
            s2 += t // ((k + 1) * (k + 2))
            k += 1
            t = ((t * Q) >> wp) // (k * k)
        sc = mp.exp(-x) * mpf(2) ** (-wp)
        return s0 * sc, (x / 2) * s1 * sc, (x * x / 4) * s2 * sc


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
# Adaptive composite Gauss–Legendre for vector-valued integrands on [0, 1]
# ----------------------------------------------------------------------------------------

_GL_CACHE = {}


def gauss_legendre(n):
    """Nodes and weights on [-1, 1] at the current precision (Newton on P_n)."""
    key = (n, mp.prec)
    if key in _GL_CACHE:
        return _GL_CACHE[key]
    with mp.workprec(mp.prec + 20):
        xs, ws = [], []
        for i in range(1, n // 2 + 1):
            x = mp.cos(mp.pi * (i - mpf(1) / 4) / (n + mpf(1) / 2))
            for _ in range(100):
                p0, p1 = mpf(1), x
                for k in range(2, n + 1):
                    p0, p1 = p1, ((2 * k - 1) * x * p1 - (k - 1) * p0) / k
                dp = n * (x * p1 - p0) / (x * x - 1)
                dx = p1 / dp
                x -= dx
                if abs(dx) < mpf(2) ** (-mp.prec - 10):
                    break
            p0, p1 = mpf(1), x
            for k in range(2, n + 1):
                p0, p1 = p1, ((2 * k - 1) * x * p1 - (k - 1) * p0) / k
            dp = n * (x * p1 - p0) / (x * x - 1)
            w = 2 / ((1 - x * x) * dp * dp)
            xs += [x, -x]
            ws += [w, w]
        if n % 2:
            p0, p1 = mpf(1), mpf(0)
            for k in range(2, n + 1):
                p0, p1 = p1, ((2 * k - 1) * 0 * p1 - (k - 1) * p0) / k
            dp = n * (0 * p1 - p0) / (0 - 1)
            xs.append(mpf(0))
            ws.append(2 / (dp * dp))
    res = ([+x for x in xs], [+w for w in ws])
    _GL_CACHE[key] = res
    return res


class Integrator:
    """∫_0^1 f(u, 1-u) du for a vector-valued f with positive components.

    f receives both u and 1-u (each computed without cancellation: panels in [1/2, 1] are
    mirrored copies of panels in [0, 1/2]).  Breakpoints: 0, eps·ratio^k ... 1/2 from each end
    (eps_left/eps_right ~ the boundary-layer widths).  Each panel is accepted when its n-point
    Gauss–Legendre value and the sum over its two halves agree to tol relative to the current
    total of every component; otherwise it is bisected.
    """

    def __init__(self, n, ratio, tol, max_depth=40):
        self.n = n
        self.ratio = ratio
        self.tol = tol
        self.max_depth = max_depth
        self.evals = 0

    def _gl(self, f, a, b, side):
        xs, ws = gauss_legendre(self.n)
        h = (b - a) / 2
        m = (a + b) / 2
        acc = None
        for x, w in zip(xs, ws):
            v = m + h * x
            vals = f(v, 1 - v) if side == 0 else f(1 - v, v)
            if acc is None:
                acc = [w * y for y in vals]
            else:
                for i, y in enumerate(vals):
                    acc[i] += w * y
        self.evals += len(xs)
        return [h * y for y in acc]

    @staticmethod
    def _grade(eps, ratio, top=None):
        """Breakpoints 0, eps, eps·ratio, … up to 1/2; with `top` (< 1/2) the grading stops
        at `top` and one panel [top, 1/2] follows (for the --extreme rows: beyond `top` the
        integrand is below e^{-K} of the total, see extreme_tops)."""
        half = mpf(1) / 2
        stop = half / 1.5 if top is None else min(mpf(top), half / 1.5)
        bps = [mpf(0)]
        p = mpf(eps)
        while p < stop:
            bps.append(p)
            p *= ratio
        if top is not None and stop < half / 1.5:
            bps.append(stop)
        bps.append(half)
        return bps

    def integrate(self, f, eps_left, eps_right, adaptive=True, tops=(None, None)):
        panels = []
        for side, eps in ((0, eps_left), (1, eps_right)):
            bps = self._grade(eps, self.ratio, tops[side])
            for a, b in zip(bps[:-1], bps[1:]):
                panels.append((a, b, side))
        ests = [self._gl(f, a, b, s) for (a, b, s) in panels]
        total = [sum(col) for col in zip(*ests)]
        if not adaptive:
            return total
        for t in total:
            if not t > 0:
                raise RuntimeError("non-positive component total")
        result = [mpf(0)] * len(total)
        stack = [(a, b, s, e, 0) for (a, b, s), e in zip(panels, ests)]
        while stack:
            a, b, s, est, depth = stack.pop()
            m = (a + b) / 2
            left = self._gl(f, a, m, s)
            right = self._gl(f, m, b, s)
            both = [x + y for x, y in zip(left, right)]
            err = max(abs(x - y) / t for x, y, t in zip(both, est, total))
            if err <= self.tol:
                result = [r + x for r, x in zip(result, both)]
            else:
                if depth >= self.max_depth:
                    raise RuntimeError("quadrature did not converge on [%s, %s]" % (a, b))
                stack.append((a, m, s, left, depth + 1))
                stack.append((m, b, s, right, depth + 1))
        return result


# ----------------------------------------------------------------------------------------
# Blocks: a single coordinate x = ±t, or a circle (x_a, x_b) = sqrt(r)(cos φ, sin φ)
# ----------------------------------------------------------------------------------------

def circle_block(r, za, zb):
    """Integrals over a circle of radius² r of exp(za x_a² + zb x_b²) times 1, x², x⁴, x_a²x_b²,
    divided by 2π.  Returns (m0, {i: m2}, {(i,j): m4}) with i in {0 (=a), 1 (=b)}.

    With x_a = √r cos φ, x_b = √r sin φ and A = r(zb - za)/2:
      exp(za x_a² + zb x_b²) = exp(r(za+zb)/2) exp(-A cos 2φ),
      (1/2π)∫ exp(-A cos2φ) {1, cos2φ, cos4φ} dφ = {I0, -I1, I2}(A)  (I_n even/odd in A), so
      x_a² → r(I0 - I1)/2, x_b² → r(I0 + I1)/2, x_a⁴ → r²(3I0 - 4I1 + I2)/8,
      x_b⁴ → r²(3I0 + 4I1 + I2)/8, x_a²x_b² → r²(I0 - I2)/8   (times exp(r(za+zb)/2)).
    Scaled: exp(r(za+zb)/2) I_n(|A|) = exp(r max(za,zb)) I_n e(|A|).
    """
    prec = mp.prec
    i0, i1, i2 = besseli012e(abs(r * (zb - za) / 2))
    with mp.workprec(prec + 60):    # the differences lose up to ~2 log2(A) bits
        A = r * (zb - za) / 2
        if A < 0:               # za > zb: the roles of a and b swap (I1 is odd)
            i1 = -i1
        d01m = i0 - i1
        d01p = i0 + i1
        q4m = 3 * i0 - 4 * i1 + i2
        q4p = 3 * i0 + 4 * i1 + i2
        d02 = i0 - i2
    e = mp.exp(r * max(za, zb))
    m0 = e * i0
    m2 = {0: e * r * d01m / 2, 1: e * r * d01p / 2}
    r2e = e * r * r / 8
    m4 = {(0, 0): r2e * q4m, (1, 1): r2e * q4p, (0, 1): r2e * d02}
    return m0, m2, m4


def combine_blocks(blocks, d, want4=True):
    """blocks: list of (coords, m0, m2, m4) → vector [F, F2_1..F2_d, F4_ij (i<=j)]."""
    m0s = [b[1] for b in blocks]
    total0 = mpf(1)
    for m in m0s:
        total0 *= m
    F2 = [None] * d
    owner = {}
    for bi, (coords, m0, m2, m4) in enumerate(blocks):
        rest = mpf(1)
        for bj, m in enumerate(m0s):
            if bj != bi:
                rest *= m
        for k, c in enumerate(coords):
            F2[c] = m2[k] * rest
            owner[c] = (bi, k)
    out = [total0] + F2
    if want4:
        for i in range(d):
            for j in range(i, d):
                bi, ki = owner[i]
                bj, kj = owner[j]
                if bi == bj:
                    rest = mpf(1)
                    for bk, m in enumerate(m0s):
                        if bk != bi:
                            rest *= m
                    key = (min(ki, kj), max(ki, kj))
                    out.append(blocks[bi][3][key] * rest)
                else:
                    rest = mpf(1)
                    for bk, m in enumerate(m0s):
                        if bk != bi and bk != bj:
                            rest *= m
                    out.append(blocks[bi][2][ki] * blocks[bj][2][kj] * rest)
    return out


def finish(d, vec, logC, want4=True):
    """From [F/C, F2/C, F4/C] to (log F, ω, H) (H full d×d list of lists, or None)."""
    F0 = vec[0]
    logF = logC + mp.log(F0)
    om = [v / F0 for v in vec[1:1 + d]]
    H = None
    if want4:
        H = [[None] * d for _ in range(d)]
        idx = 1 + d
        for i in range(d):
            for j in range(i, d):
                h = vec[idx] / F0 - om[i] * om[j]
                H[i][j] = H[j][i] = h
                idx += 1
    return logF, om, H


def scale_of(z):
    zs = [mpf(v) for v in z]
    return max([abs(a - b) for a in zs for b in zs] + [mpf(1)])


def quad_d3(z, run, want4=True, adaptive=True, tol=None, tops=(None, None)):
    """F = 2π ∫_{-1}^{1} exp(z1 t²) · [circle of radius² 1-t² in (x2, x3)] dt (even in t)."""
    z1, z2, z3 = (mpf(v) for v in z)
    S = scale_of(z)
    big = max(abs(z1 - max(z2, z3)), mpf(1))

    def f(t, s):                       # s = 1 - t, computed without cancellation
        r = s * (1 + t)                # = 1 - t²
        g = mp.exp(z1 * t * t)
        m0, m2, m4 = circle_block(r, z2, z3)
        t2 = t * t
        blocks = [([0], g, {0: g * t2}, {(0, 0): g * t2 * t2}), ([1, 2], m0, m2, m4)]
        return combine_blocks(blocks, 3, want4)

    integ = Integrator(run["n"], run["ratio"], tol if tol is not None else mpf(10) ** (3 - run["dps"]))
    eps0 = run["offset"] / (4 * mp.sqrt(big))
    eps1 = run["offset"] / (8 * S)
    vec = integ.integrate(f, min(eps0, mpf(1) / 8), min(eps1, mpf(1) / 8), adaptive, tops)
    return finish(3, vec, mp.log(4 * mp.pi), want4), integ.evals


def quad_d4(z, run, want4=True, adaptive=True, tol=None, tops=(None, None)):
    """F = 2π² ∫_0^1 [circle radius² u in (x1,x2)] · [circle radius² 1-u in (x3,x4)] du."""
    z1, z2, z3, z4 = (mpf(v) for v in z)
    S = scale_of(z)

    def f(u, w):
        a = circle_block(u, z1, z2)
        b = circle_block(w, z3, z4)
        blocks = [([0, 1],) + a, ([2, 3],) + b]
        return combine_blocks(blocks, 4, want4)

    integ = Integrator(run["n"], run["ratio"], tol if tol is not None else mpf(10) ** (3 - run["dps"]))
    eps = min(run["offset"] / (4 * S), mpf(1) / 8)
    vec = integ.integrate(f, eps, eps, adaptive, tops)
    return finish(4, vec, mp.log(2 * mp.pi ** 2), want4), integ.evals


def closed_d2(z):
    """F = 2π e^{(z1+z2)/2} I0((z2-z1)/2), moments from the circle factors (mpmath.besseli)."""
    z1, z2 = (mpf(v) for v in z)
    A = (z2 - z1) / 2
    sgn = 1 if A >= 0 else -1
    a = abs(A)
    i0, i1, i2 = mp.besseli(0, a), mp.besseli(1, a) * sgn, mp.besseli(2, a)
    logF = mp.log(2 * mp.pi) + (z1 + z2) / 2 + mp.log(i0)
    om = [(i0 - i1) / (2 * i0), (i0 + i1) / (2 * i0)]
    e4 = [[(3 * i0 - 4 * i1 + i2) / (8 * i0), (i0 - i2) / (8 * i0)],
          [(i0 - i2) / (8 * i0), (3 * i0 + 4 * i1 + i2) / (8 * i0)]]
    H = [[e4[i][j] - om[i] * om[j] for j in range(2)] for i in range(2)]
    return logF, om, H


# ----------------------------------------------------------------------------------------
# Laplace inversion (fixed Talbot, Abate & Valkó 2004), any d
# ----------------------------------------------------------------------------------------

def saddle_shift(z):
    """c > max z with ½ Σ 1/(c - z_i) = 1 (so E[R] = 1), as a double (any c > max z is exact)."""
    zf = [float(v) for v in z]
    zm = max(zf)
    gaps = [zm - v for v in zf]
    lo, hi = 0.25, len(zf) / 2.0            # δ = c - zm in [1/2, d/2];  g(δ) decreasing
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        g = 0.5 * sum(1.0 / (mid + v) for v in gaps)
        if g > 1:
            lo = mid
        else:
            hi = mid
    return zm + hi


def talbot(z, dps, shift=0.0, want4=True):
    """(log F, ω, H) by fixed-Talbot inversion at t = 1 of
       G0(s) = Π (λ_i + s)^{-1/2},  G2_i = G0/(2(λ_i+s)),  G4_ij = G0/(4(λ_i+s)(λ_j+s)) (×3, i=j),
    F = 2 e^c π^{d/2} g0(1), F ω_i = 2 e^c π^{d/2} g2_i(1), F E[x_i²x_j²] = 2 e^c π^{d/2} g4_ij(1).
    (∫_{R^d} y_i² e^{-yᵀ(Λ+s)y} dy = π^{d/2} Π(λ+s)^{-1/2}/(2(λ_i+s)), y = √R x.)"""
    d = len(z)
    c = saddle_shift(z) + shift
    dps_goal = int(1.72 * dps)
    M = int(1.38 * dps_goal)
    with mp.workdps(dps_goal + 10):
        lam = [mpf(c) - mpf(v) for v in z]
        r = mpf(2) * M / 5
        n4 = d * (d + 1) // 2 if want4 else 0
        acc = [mp.mpc(0)] * (1 + d + n4)
        for k in range(M):
            if k == 0:
                s = mp.mpc(r)
                fac = mp.mpc(mpf(1) / 2)
            else:
                th = k * mp.pi / M
                cot = mp.cot(th)
                s = r * th * mp.mpc(cot, 1)
                fac = mp.mpc(1, th + (th * cot - 1) * cot)
            ls = [lm + s for lm in lam]
            base = mp.exp(s - sum(mp.log(v) for v in ls) / 2) * fac
            inv = [1 / v for v in ls]
            vals = [base] + [base * q / 2 for q in inv]
            if want4:
                for i in range(d):
                    for j in range(i, d):
                        vals.append(base * inv[i] * inv[j] * (3 if i == j else 1) / 4)
            acc = [a + v for a, v in zip(acc, vals)]
        vec = [a.real * r / M for a in acc]
        logC = mp.log(2) + mpf(c) + mp.log(mp.pi) * d / 2
        logF, om, H = finish(d, vec, logC, want4)
    return +logF, [+o for o in om], ([[+h for h in row] for row in H] if H else None)


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

def compute(d, z, run):
    with mp.workdps(run["dps"]):
        if d == 2:
            res, ev = closed_d2(z), 0
        elif d == 3:
            res, ev = quad_d3(z, run)
        elif d == 4:
            res, ev = quad_d4(z, run)
        else:
            res, ev = talbot(z, run["dps"], run["shift"]), 0
        logF, om, H = res
        return (+logF, [+o for o in om], [[+h for h in row] for row in H]), ev


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


def near_zero_H(H, i, j):
    """|H_ij| below 1e-30 sqrt(H_ii H_jj): stored as 0 (the value is rounding noise of
    E[x_i²x_j²] - ω_iω_j; the true value is smaller than any stored digit)."""
    return abs(H[i][j]) < mpf(10) ** -30 * mp.sqrt(abs(H[i][i] * H[j][j]))


def fmt(x):
    return "%.17g" % libmp.to_float(mpf(x)._mpf_, rnd="n")


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


def run_extra_checks_wrapper():
    lines = []
    worst = run_extra_checks(lines.append)
    return lines, {k: str(v) for k, v in worst.items()}


if __name__ == "__main__":
    main()
