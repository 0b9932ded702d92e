"""The numerical methods of scripts/reference_normalization.py (its docstring, "Methods", says
which serves which d): the exponentially scaled Bessel functions I0, I1, I2 in high precision,
the adaptive composite Gauss–Legendre rule on graded panels, the circle and coordinate blocks of
the d = 3, 4 one-dimensional integrals, the d = 2 closed form, the fixed-Talbot Laplace inversion
for any d, and `compute`, one data set (log F, ω, H) by the method of its d at one run's
precision (RUN_A, RUN_B). Imported by reference_normalization.py and
reference_normalization_checks.py; requires only mpmath.
"""

from mpmath import mp, mpf, libmp

# The two runs.  dps: working decimal digits; n: Gauss–Legendre nodes per panel;
# ratio/offset: geometric panel grading; shift: added to the Talbot shift c.
RUN_A = dict(name="A", dps=45, n=32, ratio=2.0, offset=1.0, shift=0.0)
RUN_B = dict(name="B", dps=65, n=48, ratio=2.0, offset=0.7, shift=0.5)


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
# One data set (log F, ω, H) by the method of its d, at one run's precision
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
