//! Lane-wise versions of the special functions: several arguments evaluated at once by the same
//! sequence of operations, written as plain Rust over fixed-size arrays so that the compiler
//! turns every step into SIMD instructions (the d = 3, 4 normalization-constant quadrature
//! evaluates its nodes this way, see `normalization::quad`).
//!
//! Every function here is `#[inline(always)]` and free of branches that differ between lanes:
//! the piece of a Bessel fit is found per lane and its coefficients gathered, both the piece
//! polynomial and the asymptotic series are evaluated when a batch holds arguments of both
//! kinds, and the result is selected per lane. A lane's result therefore depends on its own
//! argument only (never on the other lanes), and is the same on every call.
//!
//! The instruction set is chosen by the caller: the kernels are instantiated inside functions
//! compiled with `#[target_feature(enable = ...)]` (AVX2 + FMA, AVX-512) and in a plain one.
//! [`Arith`] selects between `a·b + c` rounded twice ([`Plain`], every target) and the fused
//! multiply-add ([`Fused`], only inside functions compiled with FMA enabled, where it is one
//! instruction; elsewhere it would be a slow library call).

use super::pieces::{piece_index, Piece, Poly, NT};
use super::tables::{
    ASY_D_HI, ASY_D_LO, ASY_I0_HI, ASY_I0_LO, ASY_Q_HI, ASY_Q_LO, ASY_Q_TAIL, ASY_TAIL, PIECES,
    Q_PIECES, X_ASY,
};
use std::ops::{Add, Mul, Sub};

/// `L` doubles processed together (one SIMD register for `L = 4` with AVX2, `L = 8` with
/// AVX-512).
#[derive(Clone, Copy, Debug)]
pub(crate) struct F<const L: usize>(pub [f64; L]);

/// A per-lane condition.
pub(crate) type Mask<const L: usize> = [bool; L];

impl<const L: usize> F<L> {
    /// Every lane `v`.
    #[inline(always)]
    pub fn splat(v: f64) -> Self {
        F([v; L])
    }

    /// `f` applied to every lane.
    #[inline(always)]
    pub fn map(self, f: impl Fn(f64) -> f64) -> Self {
        let mut o = self.0;
        for v in o.iter_mut() {
            *v = f(*v);
        }
        F(o)
    }

    /// `f` applied lane by lane to `self` and `o`.
    #[inline(always)]
    pub fn zip(self, o: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        let mut r = self.0;
        for (v, w) in r.iter_mut().zip(o.0) {
            *v = f(*v, w);
        }
        F(r)
    }

    /// Lane-wise square root.
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        self.map(f64::sqrt)
    }

    /// Lane-wise `1/self`.
    #[inline(always)]
    pub fn recip(self) -> Self {
        self.map(|v| 1.0 / v)
    }

    /// Lane-wise `self < v`.
    #[inline(always)]
    pub fn lt(self, v: f64) -> Mask<L> {
        let mut m = [false; L];
        for (b, x) in m.iter_mut().zip(self.0) {
            *b = x < v;
        }
        m
    }

    /// Lane-wise `if m { a } else { b }`.
    #[inline(always)]
    pub fn select(m: Mask<L>, a: Self, b: Self) -> Self {
        let mut r = b.0;
        for ((v, c), x) in r.iter_mut().zip(m).zip(a.0) {
            *v = if c { x } else { *v };
        }
        F(r)
    }

    /// The sum of the lanes, added in lane order (the same order on every call).
    #[inline(always)]
    pub fn sum(self) -> f64 {
        self.0.iter().fold(0.0, |s, v| s + v)
    }
}

impl<const L: usize> Add for F<L> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self.zip(o, |a, b| a + b)
    }
}

impl<const L: usize> Sub for F<L> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self.zip(o, |a, b| a - b)
    }
}

impl<const L: usize> Mul for F<L> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self.zip(o, |a, b| a * b)
    }
}

impl<const L: usize> Add<f64> for F<L> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: f64) -> Self {
        self.map(|a| a + o)
    }
}

impl<const L: usize> Mul<f64> for F<L> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: f64) -> Self {
        self.map(|a| a * o)
    }
}

/// How `a·b + c` is evaluated.
pub(crate) trait Arith: Copy {
    /// `a·b + c`, lane-wise.
    fn madd<const L: usize>(a: F<L>, b: F<L>, c: F<L>) -> F<L>;
}

/// `a·b + c` with two roundings (every target).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Plain;

/// `a·b + c` fused (one rounding): only for code compiled with the FMA instructions enabled
/// (the x86-64 kernels; other targets build only the portable one).
#[derive(Clone, Copy, Debug)]
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
pub(crate) struct Fused;

impl Arith for Plain {
    #[inline(always)]
    fn madd<const L: usize>(a: F<L>, b: F<L>, c: F<L>) -> F<L> {
        let mut r = c.0;
        for ((v, x), y) in r.iter_mut().zip(a.0).zip(b.0) {
            *v += x * y;
        }
        F(r)
    }
}

impl Arith for Fused {
    #[inline(always)]
    fn madd<const L: usize>(a: F<L>, b: F<L>, c: F<L>) -> F<L> {
        let mut r = c.0;
        for ((v, x), y) in r.iter_mut().zip(a.0).zip(b.0) {
            *v = x.mul_add(y, *v);
        }
        F(r)
    }
}

/// `1.5·2^52`: adding it rounds a double of magnitude below `2^51` to an integer, which then
/// sits in the low mantissa bits.
const SHIFTER: f64 = 6755399441055744.0;

/// `2^n` for integer-valued `n ∈ [−1022, 1023]` given as `n + SHIFTER` (exact bit arithmetic).
#[inline(always)]
fn pow2_shifted<const L: usize>(ns: F<L>) -> F<L> {
    ns.map(|v| f64::from_bits((v.to_bits().wrapping_add(1023)) << 52))
}

/// Coefficients `1/k!`, k = 2..=13, of the Taylor series of `e^r`.
const EXP_TAYLOR: [f64; 12] = [
    1.0 / 2.0,
    1.0 / 6.0,
    1.0 / 24.0,
    1.0 / 120.0,
    1.0 / 720.0,
    1.0 / 5040.0,
    1.0 / 40320.0,
    1.0 / 362880.0,
    1.0 / 3628800.0,
    1.0 / 39916800.0,
    1.0 / 479001600.0,
    1.0 / 6227020800.0,
];

/// Lane-wise `e^x` for `x ≤ 0` (including `−∞`: 0), within 1 ulp, subnormal results rounded
/// once. Larger `x` up to 709 is also handled (not used by the quadrature).
///
/// `x = n ln 2 + r` with `|r| ≤ ln2/2` (`n ln 2` in two parts, the first exact), `e^r` by its
/// Taylor series to degree 13 (truncation below 5e-18 relative) as `1 + (r + r²·P(r))`, then
/// times `2^{n₁}·2^{n₂}` with `n₁ + n₂ = n`, each factor a normal number, so a subnormal result is
/// rounded once. Branch-free; no table.
#[inline(always)]
pub(crate) fn exp<A: Arith, const L: usize>(x: F<L>) -> F<L> {
    const LOG2E: f64 = std::f64::consts::LOG2_E;
    // ln 2 = LN2_HI + LN2_LO, LN2_HI with 21 trailing zero bits (n·LN2_HI exact for |n| < 2^21)
    const LN2_HI: f64 = 0.693_147_180_369_123_8;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    // below −746 the result is 0 (e^−746 < half the smallest subnormal); −∞ and NaN-free
    let x = x.map(|v| if v < -746.0 { -746.0 } else { v.min(709.0) });
    let ns = A::madd(x, F::splat(LOG2E), F::splat(SHIFTER));
    let n = ns + (-SHIFTER);
    // x − n·LN2_HI is exact; the second part fused where available (one rounding)
    let r = A::madd(n, F::splat(-LN2_LO), A::madd(n, F::splat(-LN2_HI), x));
    let r2 = r * r;
    let r4 = r2 * r2;
    let c = |k: usize| F::splat(EXP_TAYLOR[k]);
    // Σ_{k=0}^{11} EXP_TAYLOR[k] r^k by Estrin's scheme
    let a0 = A::madd(c(1), r, c(0));
    let a1 = A::madd(c(3), r, c(2));
    let a2 = A::madd(c(5), r, c(4));
    let a3 = A::madd(c(7), r, c(6));
    let a4 = A::madd(c(9), r, c(8));
    let a5 = A::madd(c(11), r, c(10));
    let b0 = A::madd(a1, r2, a0);
    let b1 = A::madd(a3, r2, a2);
    let b2 = A::madd(a5, r2, a4);
    let p = A::madd(A::madd(b2, r4, b1), r4, b0);
    let e = A::madd(r2, p, r) + 1.0;
    // n = n1 + n2, n1 = round(n/2): both in [−538, 512]
    let n1s = n * 0.5 + SHIFTER;
    let n1 = n1s + (-SHIFTER);
    let n2s = (n - n1) + SHIFTER;
    e * pow2_shifted(n1s) * pow2_shifted(n2s)
}

/// `Σ_{k<N} q(k) t^k` (`N` = 10, 9 or 8: degree 9, 8 or 7) by Estrin's scheme, lane-wise;
/// `q(k)` yields the coefficients of `t^k` (per lane), each fetched where it is first needed.
/// For degree-9 coefficients whose last `10 − N` are zero, `N` < 10 gives the same values (the
/// zero terms add exact zeros there) without those operations.
#[inline(always)]
fn estrin<A: Arith, const L: usize, const N: usize>(q: impl Fn(usize) -> F<L>, t: F<L>) -> F<L> {
    const { assert!(N >= 8 && N <= 10) };
    let t2 = t * t;
    let t4 = t2 * t2;
    let a0 = A::madd(q(1), t, q(0));
    let a1 = A::madd(q(3), t, q(2));
    let a2 = A::madd(q(5), t, q(4));
    let a3 = A::madd(q(7), t, q(6));
    let b0 = A::madd(a1, t2, a0);
    let b1 = A::madd(a3, t2, a2);
    let low = A::madd(b1, t4, b0);
    match N {
        8 => low,
        9 => A::madd(q(8), t4 * t4, low),
        _ => A::madd(A::madd(q(9), t, q(8)), t4 * t4, low),
    }
}

/// The piece polynomials of `[0, X_ASY)` for lanes whose pieces are `j` at offsets `t = x − c`:
/// `(e^{-x} I1(x), e^{-x} (I0(x) − I1(x)))`, lane 0 being `e^{-x} I1(x) / x` on the first piece.
///
/// The two functions' coefficients sit next to each other in [`PIECES`], so they are evaluated
/// on interleaved pairs (`L2 = 2L` values: lane `l`'s pair at `2l`, `2l + 1`): each coefficient
/// of a lane is one 16-byte load instead of two scattered ones.
#[inline(always)]
fn piece_pairs<A: Arith, const L: usize, const L2: usize>(j: &[usize; L], t: F<L>) -> (F<L>, F<L>) {
    const { assert!(L2 == 2 * L) };
    let mut tt = [0.0; L2];
    for (l, &tl) in t.0.iter().enumerate() {
        tt[2 * l] = tl;
        tt[2 * l + 1] = tl;
    }
    let tt = F(tt);
    // the pairs `$field` of every lane's piece
    macro_rules! pairs {
        (|$p:ident| $field:expr) => {{
            let mut v = [0.0; L2];
            for (l, &jl) in j.iter().enumerate() {
                let $p = &PIECES[jl];
                let pair: [f64; 2] = $field;
                v[2 * l] = pair[0];
                v[2 * l + 1] = pair[1];
            }
            F(v)
        }};
    }
    let g = estrin::<A, L2, 10>(|i| pairs!(|p| p.q[i]), tt);
    let f = pairs!(|p| p.hi) + A::madd(g, tt, pairs!(|p| p.lo));
    // Taken apart only now. The barrier keeps the optimizer from rewriting the evaluation into
    // one lane per node, which gathers every coefficient by single 8-byte loads (measurably
    // slower for the whole quadrature: docs/speed.md, row `lanes-barrier`); it does not change
    // any value.
    let f = std::hint::black_box(f);
    let mut i1 = [0.0; L];
    let mut d = [0.0; L];
    for l in 0..L {
        i1[l] = f.0[2 * l];
        d[l] = f.0[2 * l + 1];
    }
    (F(i1), F(d))
}

/// Per piece of `[0, X_ASY)`, the coefficients of the three fitted functions side by side:
/// slots `[e^{-x} I1(x) (/ x on the first piece), e^{-x} (I0(x) − I1(x)), Q(x), 0]` (from
/// [`PIECES`] and [`Q_PIECES`], assembled at compile time).
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct Piece3 {
    q: [[f64; 4]; NT],
    hi: [f64; 4],
    lo: [f64; 4],
}

/// [`PIECES`] and [`Q_PIECES`] merged into [`Piece3`] records.
const fn merge_pieces(p: &[Piece; 96], q: &[Poly; 96]) -> [Piece3; 96] {
    let mut out = [Piece3 {
        q: [[0.0; 4]; NT],
        hi: [0.0; 4],
        lo: [0.0; 4],
    }; 96];
    let mut j = 0;
    while j < 96 {
        let mut k = 0;
        while k < NT {
            out[j].q[k] = [p[j].q[k][0], p[j].q[k][1], q[j].q[k], 0.0];
            k += 1;
        }
        out[j].hi = [p[j].hi[0], p[j].hi[1], q[j].hi, 0.0];
        out[j].lo = [p[j].lo[0], p[j].lo[1], q[j].lo, 0.0];
        j += 1;
    }
    out
}

/// The merged piece table (the Hessian's kernels need all three functions at every node).
static PIECES3: [Piece3; 96] = merge_pieces(&PIECES, &Q_PIECES);

/// As [`piece_pairs`], and `Q(x)` too: the three functions evaluated on interleaved quadruples
/// (`L4 = 4L` values, lane `l`'s at `4l..4l + 4`, the fourth slot unused) from [`PIECES3`],
/// each coefficient of a lane one aligned 32-byte load.
#[inline(always)]
fn piece_quads<A: Arith, const L: usize, const L4: usize>(
    j: &[usize; L],
    t: F<L>,
) -> (F<L>, F<L>, F<L>) {
    const { assert!(L4 == 4 * L) };
    let mut tt = [0.0; L4];
    for (l, &tl) in t.0.iter().enumerate() {
        tt[4 * l..4 * l + 4].fill(tl);
    }
    let tt = F(tt);
    // the quadruples `$field` of every lane's piece
    macro_rules! quads {
        (|$p:ident| $field:expr) => {{
            let mut v = [0.0; L4];
            for (l, &jl) in j.iter().enumerate() {
                let $p = &PIECES3[jl];
                let quad: [f64; 4] = $field;
                v[4 * l..4 * l + 4].copy_from_slice(&quad);
            }
            F(v)
        }};
    }
    let g = estrin::<A, L4, 10>(|i| quads!(|p| p.q[i]), tt);
    let f = quads!(|p| p.hi) + A::madd(g, tt, quads!(|p| p.lo));
    // as in `piece_pairs`: evaluated in this layout, then taken apart
    let f = std::hint::black_box(f);
    let mut i1 = [0.0; L];
    let mut d = [0.0; L];
    let mut q = [0.0; L];
    for l in 0..L {
        i1[l] = f.0[4 * l];
        d[l] = f.0[4 * l + 1];
        q[l] = f.0[4 * l + 2];
    }
    (F(i1), F(d), F(q))
}

/// [`piece_pairs`] (with `FOURTH` [`piece_quads`]) when every lane is on piece `j`: the same
/// operations lane by lane, so the same results, with each coefficient loaded once.
#[inline(always)]
fn piece_shared<A: Arith, const L: usize, const FOURTH: bool>(
    j: usize,
    t: F<L>,
) -> (F<L>, F<L>, F<L>) {
    let p = &PIECES[j];
    let g1 = estrin::<A, L, 10>(|i| F::splat(p.q[i][0]), t);
    let gd = estrin::<A, L, 10>(|i| F::splat(p.q[i][1]), t);
    let f1 = A::madd(g1, t, F::splat(p.lo[0])) + p.hi[0];
    let d = A::madd(gd, t, F::splat(p.lo[1])) + p.hi[1];
    let q = if FOURTH {
        let pq = &Q_PIECES[j];
        let gq = estrin::<A, L, 10>(|i| F::splat(pq.q[i]), t);
        A::madd(gq, t, F::splat(pq.lo)) + pq.hi
    } else {
        F::splat(0.0)
    };
    (f1, d, q)
}

/// Scaled Bessel values at a batch of arguments (see [`bessel`]).
#[derive(Clone, Copy)]
pub(crate) struct Bessel<const L: usize> {
    /// `k·i0e(x)`
    pub i0: F<L>,
    /// `k·i1e(x)`
    pub i1: F<L>,
    /// `k·(i0e − i1e)(x)`
    pub dm: F<L>,
    /// `k·x·(i0e − i1e)(x)`
    pub xdm: F<L>,
    /// `k·i1e(x)/x` (`k/2` at `x = 0`); only with `FOURTH`
    pub i1x: F<L>,
    /// `k·Q(x)`; only with `FOURTH`
    pub q: F<L>,
    /// `k·x²·Q(x)`; only with `FOURTH`
    pub x2q: F<L>,
}

/// What the caller knows about a batch's arguments (see [`Span::of`]): it lets [`bessel`] skip
/// the per-lane piece search and the selection between the two methods. A hint never changes a
/// result: each lane's value is the one [`Span::Mixed`] gives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Span {
    /// Every lane in piece `j` of `[0, X_ASY)`.
    Piece(usize),
    /// Every lane at or beyond `X_ASY`.
    Asymptotic,
    /// Nothing known.
    Mixed,
}

impl Span {
    /// The span of every argument in `[lo, hi]` (`0 ≤ lo ≤ hi`, or NaN: `Mixed`). The piece index
    /// does not decrease with `x`, so one piece at both ends is one piece throughout.
    #[inline(always)]
    pub fn of(lo: f64, hi: f64) -> Span {
        if lo >= X_ASY {
            Span::Asymptotic
        } else if hi < X_ASY && piece_index(lo) == piece_index(hi) {
            Span::Piece(piece_index(lo))
        } else {
            Span::Mixed
        }
    }
}

/// The asymptotic series for every lane (`x ≥ X_ASY`): the values of [`bessel`] there.
#[inline(always)]
fn bessel_asymptotic<A: Arith, const L: usize, const FOURTH: bool>(
    x: F<L>,
    k: F<L>,
    out: &mut Bessel<L>,
) {
    let s = x.recip();
    let ku = k * s.sqrt();
    // the I0 tail has 8 coefficients, the I0 − I1 tail 9 (zero-padded to NT)
    const { assert!(ASY_TAIL[8][0] == 0.0 && ASY_TAIL[9][0] == 0.0 && ASY_TAIL[9][1] == 0.0) };
    let ga = estrin::<A, L, 8>(|i| F::splat(ASY_TAIL[i][0]), s);
    let gb = estrin::<A, L, 9>(|i| F::splat(ASY_TAIL[i][1]), s);
    let a = A::madd(s, ga, F::splat(ASY_I0_LO));
    let b = A::madd(s, gb, F::splat(ASY_D_LO)) + ASY_D_HI;
    let sb = s * b;
    out.i0 = ku * (a + ASY_I0_HI);
    out.i1 = ku * ((a - sb) + ASY_I0_HI);
    out.dm = ku * sb;
    out.xdm = ku * b;
    if FOURTH {
        out.i1x = out.i1 * s;
        let bq = A::madd(
            s,
            estrin::<A, L, 10>(|i| F::splat(ASY_Q_TAIL[i]), s),
            F::splat(ASY_Q_LO),
        ) + ASY_Q_HI;
        let kub = ku * bq;
        out.q = kub * s * s;
        out.x2q = kub;
    }
}

/// The lane-wise [`super::i01e_times`] (and with `FOURTH` [`super::bessel_q_times`] and
/// `k·i1e(x)/x`) for `x ≥ 0`, `k > 0`: the same fits and series, evaluated for all lanes at
/// once. Lanes below `X_ASY` take the piece polynomials (coefficients gathered by piece),
/// the others the asymptotic series; a part that no lane needs is skipped. `span` is what the
/// caller knows about the arguments ([`Span::Mixed`] if nothing); a lane's result does not
/// depend on it.
#[inline(always)]
pub(crate) fn bessel<
    A: Arith,
    const L: usize,
    const L2: usize,
    const L4: usize,
    const FOURTH: bool,
>(
    x: F<L>,
    k: F<L>,
    span: Span,
) -> Bessel<L> {
    let zero = F::splat(0.0);
    let mut out = Bessel {
        i0: zero,
        i1: zero,
        dm: zero,
        xdm: zero,
        i1x: zero,
        q: zero,
        x2q: zero,
    };
    match span {
        Span::Asymptotic => {
            bessel_asymptotic::<A, L, FOURTH>(x, k, &mut out);
            return out;
        }
        Span::Piece(j) => {
            // as below for a batch on one piece, without the per-lane search and selection
            let t = x - F::splat(PIECES[j].c);
            let (f1, d, qfit) = piece_shared::<A, L, FOURTH>(j, t);
            let i1 = if j == 0 { f1 * x } else { f1 };
            let i0 = i1 + d;
            let kd = k * d;
            out.i0 = k * i0;
            out.i1 = k * i1;
            out.dm = kd;
            out.xdm = kd * x;
            if FOURTH {
                out.i1x = if j == 0 { k * f1 } else { k * i1 * x.recip() };
                let qv = k * qfit;
                out.q = qv;
                out.x2q = qv * x * x;
            }
            return out;
        }
        Span::Mixed => {}
    }
    let small = x.lt(X_ASY);
    let any_small = small.iter().any(|&b| b);
    let any_large = small.iter().any(|&b| !b);
    if any_large {
        bessel_asymptotic::<A, L, FOURTH>(x, k, &mut out);
    }
    if any_small {
        // piece index per lane (`pieces::piece_index`), clamped so that lanes beyond X_ASY
        // (whose result is discarded) index a valid piece
        let mut j = [0usize; L];
        for (jl, xl) in j.iter_mut().zip(x.0) {
            *jl = piece_index(xl).min(PIECES.len() - 1);
        }
        // coefficient `$field` of each lane's piece of `$table`
        macro_rules! gather {
            ($table:ident, |$p:ident| $field:expr) => {{
                let mut v = [0.0; L];
                for (vl, &jl) in v.iter_mut().zip(&j) {
                    let $p = &$table[jl];
                    *vl = $field;
                }
                F(v)
            }};
        }
        let c = gather!(PIECES, |p| p.c);
        let t = x - c;
        let (f1, d, qfit) = if j.iter().all(|&jl| jl == j[0]) {
            // one piece for the whole batch (common for the far group, whose argument moves
            // slowly): its coefficients are loaded once for all lanes
            piece_shared::<A, L, FOURTH>(j[0], t)
        } else if FOURTH {
            piece_quads::<A, L, L4>(&j, t)
        } else {
            let (f1, d) = piece_pairs::<A, L, L2>(&j, t);
            (f1, d, zero)
        };
        // first piece: lane 0 holds e^{-x} I1(x) / x
        let mut first = [false; L];
        for (b, &jl) in first.iter_mut().zip(&j) {
            *b = jl == 0;
        }
        let i1 = F::select(first, f1 * x, f1);
        let i0 = i1 + d;
        let kd = k * d;
        out.i0 = F::select(small, k * i0, out.i0);
        out.i1 = F::select(small, k * i1, out.i1);
        out.dm = F::select(small, kd, out.dm);
        out.xdm = F::select(small, kd * x, out.xdm);
        if FOURTH {
            // k·i1e/x: from the first piece's fit directly (exact limit k/2 at x = 0)
            let s = x.recip();
            let i1x = F::select(first, k * f1, k * i1 * s);
            out.i1x = F::select(small, i1x, out.i1x);
            let qv = k * qfit;
            out.q = F::select(small, qv, out.q);
            out.x2q = F::select(small, qv * x * x, out.x2q);
        }
    }
    out
}

#[cfg(test)]
mod tests;
