//! Exponentially scaled modified Bessel functions of the first kind.
//!
//! `i0e(x) = e^{-|x|} I0(x)`, `i1e(x) = e^{-|x|} I1(x)`, the difference
//! `e^{-x} (I0(x) - I1(x))` computed without cancellation, and
//! `Q(x) = e^{-x} (3 I0(x) - 4 I1(x) + I2(x))` (for Hessians). [`i01e`] returns the first three
//! at once; the quadrature rules of the normalization constant evaluate the same fits at several
//! nodes at once (the crate-internal `lanes`).
//!
//! Contract: within 1 ulp of the correctly rounded value on `[0, 128)`, within a few ulp beyond
//! (measured against the 50-digit `tests/data/bessel_reference.csv`, `tests/special.rs`; figures
//! in `docs/accuracy.md`, § "Bessel functions"); finite for every finite argument. Method: 96
//! double-double-anchored polynomial pieces on `[0, 128)` (coefficients fitted from scratch by
//! `scripts/bessel_reference.py` into the generated `tables`), the asymptotic series beyond, the
//! differences fitted directly (no cancellation); the derivation is in `docs/design.md`
//! (§ "Bessel functions"). The crate-internal `lanes` evaluates the same fits for several
//! arguments at once (SIMD) for the quadrature; its results equal these functions' (bit for bit
//! without fused multiply-adds). Speed: `docs/speed.md` (`benches/special.rs`).

pub(crate) mod lanes;
mod pieces;
mod tables;

use pieces::{piece_index, Lanes, NT};
use tables::{
    ASY_D_HI, ASY_D_LO, ASY_I0_HI, ASY_I0_LO, ASY_Q_HI, ASY_Q_LO, ASY_Q_TAIL, ASY_TAIL, PIECES,
    Q_PIECES, X_ASY,
};

#[inline(always)]
fn madd(a: Lanes, b: Lanes, t: f64) -> Lanes {
    [a[0] + b[0] * t, a[1] + b[1] * t]
}

/// `Σ q[k] t^k` (degree 9) in both lanes by Estrin's scheme: depth 4 instead of Horner's 9.
#[inline(always)]
fn estrin2(q: &[Lanes; NT], t: f64) -> Lanes {
    let t2 = t * t;
    let t4 = t2 * t2;
    let t8 = t4 * t4;
    let a0 = madd(q[0], q[1], t);
    let a1 = madd(q[2], q[3], t);
    let a2 = madd(q[4], q[5], t);
    let a3 = madd(q[6], q[7], t);
    let a4 = madd(q[8], q[9], t);
    let b0 = madd(a0, a1, t2);
    let b1 = madd(a2, a3, t2);
    madd(madd(b0, b1, t4), a4, t8)
}

/// `Σ q[k] t^k` (degree 9) by Estrin's scheme.
#[inline(always)]
fn estrin(q: &[f64; NT], t: f64) -> f64 {
    let t2 = t * t;
    let t4 = t2 * t2;
    let t8 = t4 * t4;
    let a0 = q[0] + q[1] * t;
    let a1 = q[2] + q[3] * t;
    let a2 = q[4] + q[5] * t;
    let a3 = q[6] + q[7] * t;
    let a4 = q[8] + q[9] * t;
    let b0 = a0 + a1 * t2;
    let b1 = a2 + a3 * t2;
    (b0 + b1 * t4) + a4 * t8
}

/// `(i0e, i1e, i0e − i1e)` for `x ≥ 0` (or NaN).
#[inline(always)]
fn i01e_nonneg(x: f64) -> (f64, f64, f64) {
    if x < X_ASY {
        let j = piece_index(x);
        let p = &PIECES[j];
        let t = x - p.c;
        let g = estrin2(&p.q, t);
        let r = madd(p.lo, g, t);
        // First piece: lane 0 holds e^{-x} I1(x) / x.
        let m = if j == 0 { x } else { 1.0 };
        let (i1, d) = ((p.hi[0] + r[0]) * m, p.hi[1] + r[1]);
        (i1 + d, i1, d)
    } else {
        // Also reached by NaN, which propagates.
        let s = 1.0 / x;
        let u = s.sqrt();
        // sqrt(x)·i0e = ASY_I0 + a,  x^{3/2}·d = b,  sqrt(x)·i1e = ASY_I0 + a − s·b.
        let g = estrin2(&ASY_TAIL, s);
        let a = ASY_I0_LO + s * g[0];
        let b = ASY_D_HI + (ASY_D_LO + s * g[1]);
        let sb = s * b;
        (u * (ASY_I0_HI + a), u * (ASY_I0_HI + (a - sb)), u * sb)
    }
}

/// `e^{-|x|} I0(x)`, the exponentially scaled modified Bessel function of order 0 (even in `x`).
///
/// `i0e(0) = 1`, `i0e(±∞) = 0`; within 1 ulp of the correctly rounded value (measured, see the
/// module documentation).
#[inline]
#[must_use]
pub fn i0e(x: f64) -> f64 {
    i01e_nonneg(x.abs()).0
}

/// `e^{-|x|} I1(x)`, the exponentially scaled modified Bessel function of order 1 (odd in `x`).
///
/// `i1e(0) = 0`, `i1e(±∞) = ±0`; within 2 ulp (measured), also for tiny `|x|`, where
/// `i1e(x) ≈ x/2`.
#[inline]
#[must_use]
pub fn i1e(x: f64) -> f64 {
    i01e_nonneg(x.abs()).1.copysign(x)
}

/// `e^{-x} (I0(x) − I1(x))` for `x ≥ 0`, computed without cancellation (negative `x` is taken as `|x|`).
///
/// For large `x` this is `≈ (2πx)^{-1/2} / (2x)`, a small fraction of `i0e(x)`; it is fitted and
/// expanded directly, so its relative error stays below 4e-16 (measured) for all `x` — a plain
/// `i0e(x) - i1e(x)` would lose `log10(2x)` digits. `i0e_minus_i1e(0) = 1`.
#[inline]
#[must_use]
pub fn i0e_minus_i1e(x: f64) -> f64 {
    i01e_nonneg(x.abs()).2
}

/// `(i0e(x), i1e(x), i0e_minus_i1e(x))` at once, sharing all work; meant for `x ≥ 0`.
///
/// The three values are bit-for-bit those of [`i0e`], [`i1e`] and [`i0e_minus_i1e`]; for negative
/// `x` that means `i0e(|x|)`, `−i1e(|x|)` and `i0e_minus_i1e(|x|)`. A table lookup and one
/// two-lane degree-9 polynomial for `x < 128`; one division, one square root and one two-lane
/// series beyond.
#[inline]
#[must_use]
pub fn i01e(x: f64) -> (f64, f64, f64) {
    let (i0, i1, d) = i01e_nonneg(x.abs());
    (i0, i1.copysign(x), d)
}

/// `(k·i0e(x), k·i1e(x), k·(i0e − i1e)(x), k·x·(i0e − i1e)(x))` for `x ≥ 0` and a scale `k > 0`,
/// without intermediate underflow: for `x ≥ 128` the factor `k·x^{−1/2}` is formed first, so
/// with `k ≈ √x` every output is O(1) except `k·(i0e − i1e) ≈ 1/(2x)` (representable for all
/// finite `x`). The normalization constant's scaled quadrature and the d = 2 closed form use it
/// for arguments up to the largest double, where `i0e − i1e ≈ x^{−3/2}/5` underflows.
/// For `x < 128` the results are those of [`i01e`] times `k`.
#[inline(always)]
pub(crate) fn i01e_times(x: f64, k: f64) -> (f64, f64, f64, f64) {
    if x < X_ASY {
        let (i0, i1, d) = i01e_nonneg(x);
        let kd = k * d;
        (k * i0, k * i1, kd, kd * x)
    } else {
        let s = 1.0 / x;
        let ku = k * s.sqrt();
        let g = estrin2(&ASY_TAIL, s);
        let a = ASY_I0_LO + s * g[0];
        let b = ASY_D_HI + (ASY_D_LO + s * g[1]);
        let sb = s * b;
        (
            ku * (ASY_I0_HI + a),
            ku * (ASY_I0_HI + (a - sb)),
            ku * sb,
            ku * b,
        )
    }
}

/// `(k·Q(x), k·x²·Q(x))` (see [`bessel_q`]) for `x ≥ 0` and a scale `k > 0`, formed like
/// [`i01e_times`] so that `k·x²·Q ≈ 0.6·k/√x` never underflows when it is representable.
#[inline(always)]
pub(crate) fn bessel_q_times(x: f64, k: f64) -> (f64, f64) {
    if x < X_ASY {
        let kq = k * bessel_q(x);
        (kq, kq * x * x)
    } else {
        let s = 1.0 / x;
        let ku = k * s.sqrt();
        let b = ASY_Q_HI + (ASY_Q_LO + s * estrin(&ASY_Q_TAIL, s));
        let kub = ku * b;
        (kub * s * s, kub)
    }
}

/// The largest power of two `≤ x` for `x ≥ 1` finite (an exact scale factor).
#[inline(always)]
pub(crate) fn pow2_floor(x: f64) -> f64 {
    f64::from_bits(x.to_bits() & 0xfff0_0000_0000_0000)
}

/// `Q(x) = e^{-x} (3 I0(x) − 4 I1(x) + I2(x))` for `x ≥ 0` (negative `x` is taken as `|x|`).
///
/// Equals `4 (i0e − i1e) − 2 i1e / x`. `Q(0) = 3`, and `Q(x) ≈ (3/2) (2πx)^{-1/2} x^{-2}` for
/// large `x`, i.e. `O(x^{-2})` relative to `i0e`: the formula above would lose `log10(x)` digits, so
/// `Q` is fitted and expanded directly (no cancellation); relative error below 4e-16 (measured).
#[inline]
#[must_use]
pub fn bessel_q(x: f64) -> f64 {
    let x = x.abs();
    if x < X_ASY {
        let j = piece_index(x);
        let p = &Q_PIECES[j];
        let t = x - PIECES[j].c;
        p.hi + (p.lo + t * estrin(&p.q, t))
    } else {
        let s = 1.0 / x;
        let b = ASY_Q_HI + (ASY_Q_LO + s * estrin(&ASY_Q_TAIL, s));
        b / ((x * x) * x.sqrt())
    }
}
