#!/usr/bin/env python3
"""High-precision reference for `src/special/` (`mod.rs`, `tables.rs`) (exponentially scaled modified Bessel functions).

Two jobs, both with mpmath at 50 significant digits (Python 3.11; `pip install mpmath` if missing):

  python3 scripts/bessel_reference.py
      Writes tests/data/bessel_reference.csv: columns x, i0e, i1e, i0e_minus_i1e, bessel_q where
      i0e = e^-x I0(x), i1e = e^-x I1(x), i0e_minus_i1e = e^-x (I0(x) - I1(x)),
      bessel_q = e^-x (3 I0(x) - 4 I1(x) + I2(x)).
      x is printed with repr (the exact double); every value is the double nearest to the 50-digit
      value, printed with 17 significant digits (round-trips exactly).  The grid is dense on
      [0, 140) (steps 1/512 below 8, 1/64 up to 50, 1/16 beyond, plus 2000 pseudo-random points),
      log-spaced from 50 up to 1e7, and brackets every breakpoint of the approximations (every
      piece boundary and the start of the asymptotic series at 128, by the neighbouring doubles
      and by a relative 1e-12).

  python3 scripts/bessel_reference.py --write-tables src/special/tables.rs
      Writes the coefficient tables, the whole file src/special/tables.rs (marked @generated), and prints the truncation error of every piece (evaluated in high precision
      with the coefficients rounded to doubles) to stderr.

Approximation scheme (fitted here from scratch, no third-party coefficient sets):
  * 0 <= x < 128 is cut into 96 pieces: width 1/4 on [0, 8), then 16 pieces per octave on [8, 128).
    On a piece with midpoint c each of f = i1e, i0e - i1e and bessel_q is written
    f(c + t) = f(c) + t g(t): f(c) is stored as a double-double (hi, lo) and the divided difference g
    is interpolated at NT = 10 Chebyshev points (degree 9), then expanded into monomials in t.  On
    the first piece [0, 1/4) the function fitted in place of i1e is i1e(x) / x, so that
    i1e = x * (...) keeps full relative accuracy as x -> 0.
  * x >= 128: the asymptotic series e^-x I_nu(x) ~ (2 pi x)^-1/2 sum_k (-1)^k a_k(nu) x^-k,
    a_k(nu) = prod_{j=1..k} (4 nu^2 - (2j - 1)^2) / (k! 8^k), with the coefficients of I0 - I1 and of
    3 I0 - 4 I1 + I2 combined exactly (rational arithmetic) before rounding, so the differences are
    computed without cancellation.  9, 10 and 11 terms keep the truncation error at x = 128 below
    1e-17 relative (i0e, i0e - i1e, Q).
The truncation errors (coefficients rounded to doubles, evaluated exactly) are printed to stderr and
recorded in the generated block: about 2e-17 relative, i.e. well below half an ulp.
"""

import math
import sys
from fractions import Fraction
from pathlib import Path

try:
    import mpmath as mp
except ImportError:  # pragma: no cover
    sys.exit("mpmath is required: pip install mpmath")

mp.mp.dps = 50

ROOT = Path(__file__).resolve().parent.parent
CSV_PATH = ROOT / "tests" / "data" / "bessel_reference.csv"

# Number of coefficients of the divided-difference polynomial g (degree NT - 1; f has degree NT).
# The Rust side defines the same NT in src/special/pieces.rs (the tables are typed with it).
NT = 10
# Pieces: width 1 / PIECES_PER_UNIT on [0, 8), PIECES_PER_OCTAVE per octave on [8, X_ASY).
PIECES_PER_UNIT = 4
PIECES_PER_OCTAVE = 16
# Start of the asymptotic series.
X_ASY = 128.0
# Number of asymptotic terms (k = 0 .. N - 1) for e^-x I0, for the difference and for Q.
N_I0 = 9
N_D = 11
N_Q = 13


# ---------------------------------------------------------------- functions (mpmath)
def _scaled(nu, x):
    return mp.besseli(nu, x) * mp.exp(-x)


def f_i0e(x):
    return _scaled(0, mp.mpf(x))


def f_i1e(x):
    return _scaled(1, mp.mpf(x))


def f_d(x):
    x = mp.mpf(x)
    return (mp.besseli(0, x) - mp.besseli(1, x)) * mp.exp(-x)


def f_q(x):
    x = mp.mpf(x)
    return (3 * mp.besseli(0, x) - 4 * mp.besseli(1, x) + mp.besseli(2, x)) * mp.exp(-x)


# ---------------------------------------------------------------- piecewise fits
def pieces():
    """(a, b, c): the pieces of [0, X_ASY) and their midpoints (src/special/pieces.rs: `piece_index`)."""
    out = []
    for k in range(8 * PIECES_PER_UNIT):  # [0, 8)
        a, b = k / PIECES_PER_UNIT, (k + 1) / PIECES_PER_UNIT
        out.append((a, b, (a + b) / 2))
    e = 3
    while 2.0**e < X_ASY:  # [8, X_ASY), by octaves
        for m in range(PIECES_PER_OCTAVE):
            a = 2.0**e * (1 + m / PIECES_PER_OCTAVE)
            b = 2.0**e * (1 + (m + 1) / PIECES_PER_OCTAVE)
            out.append((a, b, (a + b) / 2))
        e += 1
    return out


def cheb_monomial(g, lo, hi, n):
    """Interpolate g at n Chebyshev points of [lo, hi]; return the monomial coefficients in t."""
    lo, hi = mp.mpf(lo), mp.mpf(hi)
    mid, h = (lo + hi) / 2, (hi - lo) / 2
    th = [mp.pi * (k + mp.mpf(1) / 2) / n for k in range(n)]
    gs = [g(mid + h * mp.cos(t)) for t in th]
    a = [sum(gs[k] * mp.cos(j * th[k]) for k in range(n)) * 2 / n for j in range(n)]
    a[0] /= 2
    cheb = [[mp.mpf(1)], [mp.mpf(0), mp.mpf(1)]]
    for k in range(2, n):
        p = [mp.mpf(0)] + [2 * c for c in cheb[k - 1]]
        for i, c in enumerate(cheb[k - 2]):
            p[i] -= c
        cheb.append(p)
    cy = [mp.mpf(0)] * n  # monomials in y = (t - mid) / h
    for k in range(n):
        for i, c in enumerate(cheb[k]):
            cy[i] += a[k] * c
    ct = [mp.mpf(0)] * n
    for i in range(n):
        for j in range(i + 1):
            ct[j] += cy[i] * mp.binomial(i, j) * (-mid) ** (i - j) / h**i
    return ct


def split(v):
    hi = float(v)
    return hi, float(v - hi)


def fit_piece(f, a, b, c):
    fc = f(c)
    dc = mp.diff(f, mp.mpf(c)) if c != 0 else None

    def g(t):
        return (f(c + t) - fc) / t if abs(t) > mp.mpf(10) ** -30 else dc

    coeffs = cheb_monomial(g, a - c, b - c, NT)
    hi, lo = split(fc)
    return hi, lo, [float(v) for v in coeffs]


def f_i1e_over_x(x):
    x = mp.mpf(x)
    return f_i1e(x) / x if x != 0 else mp.mpf(1) / 2


def eval_piece(hi, lo, q, t):
    t = mp.mpf(t)
    s = mp.mpf(0)
    for v in reversed(q):
        s = s * t + v
    return mp.mpf(hi) + mp.mpf(lo) + t * s


# ---------------------------------------------------------------- asymptotic series
def a_k(k, nu):
    p = Fraction(1)
    for j in range(1, k + 1):
        p *= 4 * nu * nu - (2 * j - 1) ** 2
    return p / (math.factorial(k) * 8**k)


def series(comb, n):
    """Signed coefficients (-1)^k comb(k) / sqrt(2 pi), k = 0 .. n - 1, in high precision."""
    r = 1 / mp.sqrt(2 * mp.pi)
    out = []
    for k in range(n):
        v = comb(k) * (-1) ** k
        out.append(mp.mpf(v.numerator) / v.denominator * r)
    return out


def asy_coefficients():
    c0 = series(lambda k: a_k(k, 0), N_I0)
    cd = series(lambda k: a_k(k, 0) - a_k(k, 1), N_D)
    cq = series(lambda k: 3 * a_k(k, 0) - 4 * a_k(k, 1) + a_k(k, 2), N_Q)
    assert cd[0] == 0 and cq[0] == 0 and cq[1] == 0
    return c0, cd[1:], cq[2:]


def check_asy(c0, cd, cq, xs):
    """Max relative error of the series (coefficients rounded as stored) at the points xs."""
    worst = [0, 0, 0]
    for x in xs:
        x = mp.mpf(x)
        s = 1 / x
        u = mp.sqrt(s)
        p0 = mp.fsum(mp.mpf(float(v)) * s**k for k, v in enumerate(c0[1:], 1)) + c0[0]
        pd = mp.fsum(mp.mpf(float(v)) * s**k for k, v in enumerate(cd[1:], 1)) + cd[0]
        pq = mp.fsum(mp.mpf(float(v)) * s**k for k, v in enumerate(cq[1:], 1)) + cq[0]
        errs = [u * p0 / f_i0e(x) - 1, u * s * pd / f_d(x) - 1, u * s * s * pq / f_q(x) - 1]
        worst = [max(w, abs(e)) for w, e in zip(worst, errs)]
    return worst


# ---------------------------------------------------------------- Rust source generation
def rust_f64(v):
    r = repr(float(v))
    if "e" not in r and "." not in r and "inf" not in r and "nan" not in r:
        r += ".0"
    return r


def poly_literal(hi, lo, q, indent):
    pad = " " * indent
    lines = [f"Poly {{ hi: {rust_f64(hi)}, lo: {rust_f64(lo)}, q: ["]
    for i in range(0, len(q), 3):
        lines.append(pad + "    " + " ".join(rust_f64(v) + "," for v in q[i:i + 3]))
    lines.append(pad + "] },")
    return lines


def max_rel_error(f, hi, lo, q, a, b, c):
    m = 0
    for k in range(101):
        x = mp.mpf(a) + (b - a) * mp.mpf(k) / 100
        m = max(m, abs(eval_piece(hi, lo, q, x - c) / f(x) - 1))
    return m


def generate():
    out = [
        "// Truncation errors (coefficients rounded to doubles, evaluated exactly):",
    ]
    body = [f"#[rustfmt::skip]", f"static PIECES: [Piece; {len(pieces())}] = ["]
    qbody = []
    worst = {"i1e": 0, "d": 0, "q": 0}
    for j, (a, b, c) in enumerate(pieces()):
        fits = {}
        for name, f in (("i1e", f_i1e), ("d", f_d), ("q", f_q)):
            if name == "i1e" and j == 0:
                # First piece: i1e = x * G(x - 1/4), G = i1e / x (full relative accuracy at 0).
                f = f_i1e_over_x
            fit = fit_piece(f, a, b, c)
            m = max_rel_error(f, *fit, a, b, c)
            fits[name] = fit
            worst[name] = max(worst[name], m)
            print(f"piece [{a}, {b}) {name}: max truncation {float(m):.2e}", file=sys.stderr)
        body.append(f"    // [{a}, {b})")
        (h1, l1, q1), (hd, ld, qd) = fits["i1e"], fits["d"]
        body.append("    Piece {")
        body.append(f"        c: {rust_f64(c)},")
        body.append(f"        hi: [{rust_f64(h1)}, {rust_f64(hd)}],")
        body.append(f"        lo: [{rust_f64(l1)}, {rust_f64(ld)}],")
        body.append("        q: [")
        body += [f"            [{rust_f64(u)}, {rust_f64(v)}]," for u, v in zip(q1, qd)]
        body.append("        ],")
        body.append("    },")
        qbody += ["    " + l if i == 0 else l for i, l in enumerate(poly_literal(*fits["q"], 4))]
    body.append("];")
    out.append(f"// pieces of [0, {X_ASY:g}): " + ", ".join(f"{k} {float(v):.1e}" for k, v in worst.items()))
    print(f"worst truncation over the pieces: { {k: f'{float(v):.2e}' for k, v in worst.items()} }", file=sys.stderr)

    c0, cd, cq = asy_coefficients()
    xs = [X_ASY, X_ASY * (1 + 1e-9), 1.25 * X_ASY, 1.6 * X_ASY, 1e3, 1e5]
    w = check_asy(c0, cd, cq, xs)
    out.append(f"// asymptotic series, x >= {X_ASY}: i0e {float(w[0]):.1e}, d {float(w[1]):.1e}, q {float(w[2]):.1e}")
    print(f"asymptotic series max truncation for x >= {X_ASY}: i0e {float(w[0]):.2e}, "
          f"i0e-i1e {float(w[1]):.2e}, Q {float(w[2]):.2e}", file=sys.stderr)
    out += [
        "",
        "/// Start of the asymptotic series.",
        f"const X_ASY: f64 = {rust_f64(X_ASY)};",
        "",
        "/// Per piece of `[0, X_ASY)`, lanes `[e^{-x} I1(x) (/ x on the first piece), e^{-x} (I0(x) - I1(x))]`.",
    ]
    out += body
    out += [
        "",
        "/// Per piece of `[0, X_ASY)`: `e^{-x} (3 I0(x) - 4 I1(x) + I2(x))`, expanded at `PIECES[j].c`.",
        "#[rustfmt::skip]",
        f"static Q_PIECES: [Poly; {len(pieces())}] = [",
    ]
    out += qbody
    out.append("];")

    def hl(name, v, doc):
        hi, lo = split(v)
        return [f"/// {doc}", f"const {name}_HI: f64 = {rust_f64(hi)};", f"const {name}_LO: f64 = {rust_f64(lo)};"]

    def arr(name, vals, doc):
        lines = [f"/// {d}" for d in doc.split("\n")] + ["#[rustfmt::skip]", f"const {name}: [f64; NT] = ["]
        assert len(vals) == NT
        for i in range(0, len(vals), 3):
            lines.append("    " + " ".join(rust_f64(v) + "," for v in vals[i:i + 3]))
        lines.append("];")
        return lines

    out.append("")
    out += hl("ASY_I0", c0[0], "`1/sqrt(2 pi)`: leading coefficient of `sqrt(x) e^{-x} I0(x)`.")
    out += hl("ASY_D", cd[0], "`1/(2 sqrt(2 pi))`: leading coefficient of `x^{3/2} e^{-x} (I0 - I1)`.")
    t0, td = c0[1:], cd[1:]
    n = NT  # zero-padded to the length the Estrin evaluation in src/special/mod.rs expects
    assert max(len(t0), len(td), len(cq) - 1) <= NT
    t0 = t0 + [0] * (n - len(t0))
    td = td + [0] * (n - len(td))
    out += [
        "/// Tails of the series in `s = 1/x`, zero-padded: row `k - 1` (k = 1, 2, ...) holds",
        "/// `(-1)^k a_k(0) / sqrt(2 pi)` (series of `sqrt(x) e^{-x} I0(x)`, coefficient of `s^k`) and",
        "/// `(-1)^(k+1) (a_(k+1)(0) - a_(k+1)(1)) / sqrt(2 pi)` (series of `x^{3/2} e^{-x} (I0 - I1)`,",
        "/// coefficient of `s^k`).",
        "#[rustfmt::skip]",
        "const ASY_TAIL: [[f64; 2]; NT] = [",
    ]
    out += [f"    [{rust_f64(u)}, {rust_f64(v)}]," for u, v in zip(t0, td)]
    out.append("];")
    out += hl("ASY_Q", cq[0], "`3/(2 sqrt(2 pi))`: leading coefficient of `x^{5/2} Q(x)`.")
    out += arr("ASY_Q_TAIL", cq[1:] + [0] * (NT - len(cq) + 1),
               "`(-1)^k (3 a_k(0) - 4 a_k(1) + a_k(2)) / sqrt(2 pi)`, k = 3, 4, ...: coefficient of\n"
               "`s^(k-2)` in `x^{5/2} Q(x)` (zero-padded).")
    return "\n".join(out) + "\n"


def tables_file(block):
    """The whole of src/special/tables.rs around a generated block (items visible to `special`)."""
    lines = []
    for line in block.splitlines():
        if line.startswith(("const ", "static ")):
            line = "pub(super) " + line
        lines.append(line)
    head = [
        "// @generated by scripts/bessel_reference.py --write-tables src/special/tables.rs;",
        "// do not edit by hand.",
        "//! Coefficient tables of the Bessel fits in `special` (see that module's documentation).",
        "",
        "use super::pieces::{Piece, Poly, NT};",
        "",
    ]
    return "\n".join(head + lines).rstrip("\n") + "\n"


def write_tables(path):
    Path(path).write_text(tables_file(generate()))


# ---------------------------------------------------------------- reference CSV
def grid():
    xs = set()
    xs.update(k / 512 for k in range(0, 512 * 8))  # dense on [0, 8) (32 pieces) ...
    xs.update(k / 64 for k in range(64 * 8, 64 * 50 + 1))  # ... on [8, 50] ...
    xs.update(k / 16 for k in range(16 * 50, 16 * 140))  # ... and on [50, 140)
    state = 12345  # deterministic pseudo-random points on [0, 140)
    for _ in range(2000):
        state = (6364136223846793005 * state + 1442695040888963407) % 2**64
        xs.add((state >> 11) / 2**53 * 140.0)
    n = 600  # log-spaced on [50, 1e7]
    xs.update(50.0 * (2e5) ** (i / (n - 1)) for i in range(n))
    xs.update([1e-300, 1e-100, 1e-20, 1e-10, 1e-5, 1e-3, 0.1, 1e7])
    breaks = sorted({b for _, b, _ in pieces()} | {X_ASY, 7.75, 500.0, 1000.0})
    for b in breaks:
        xs.update([b, math.nextafter(b, 0.0), math.nextafter(b, math.inf), b * (1 - 1e-12), b * (1 + 1e-12)])
    return sorted(v for v in xs if v <= 1e7)


def write_csv():
    CSV_PATH.parent.mkdir(parents=True, exist_ok=True)
    rows = ["x,i0e,i1e,i0e_minus_i1e,bessel_q"]
    for x in grid():
        vals = [f_i0e(x), f_i1e(x), f_d(x), f_q(x)]
        rows.append(",".join([repr(x)] + ["%.17g" % float(v) for v in vals]))
    CSV_PATH.write_text("\n".join(rows) + "\n")
    print(f"wrote {len(rows) - 1} points to {CSV_PATH}", file=sys.stderr)


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--write-tables":
        write_tables(sys.argv[2])
    elif len(sys.argv) == 1:
        write_csv()
    else:
        sys.exit(__doc__)
