//! d = 2: the closed form `F = 2π e^{(z1+z2)/2} I0((z2−z1)/2)` (JAIF App. B).
//!
//! With sorted `z1 ≤ z2 = 0` and `x = −z1/2 ≥ 0`: `F = 2π I0e(x)` where `I0e(x) = e^{−x} I0(x)`,
//! `ω1 = (I0e − I1e)/(2 I0e)` (the difference taken without cancellation), `ω2 = 1 − ω1`
//! computed as `(I0e + I1e)/(2 I0e)`.
//! Second derivatives: `∂²F/∂z1² = F·E[x1⁴]` with `E[x1⁴] = Q(x)/(8 I0e)`,
//! `Q = e^{−x}(3I0 − 4I1 + I2)` (evaluated without cancellation); the rest of the Hessian of
//! `log F` follows from `ω1 + ω2 = 1`.
//!
//! Range: for `x ≥ 128` every Bessel value is taken times the exact factor `k = 2^⌊e/2⌋`
//! (`e` the binary exponent of `x`, so `k ≈ √x`; [`crate::special::i01e_times`]), which keeps
//! `I0e − I1e ≈ x^{−3/2}/5` and `Q ≈ x^{−5/2}` from underflowing; `ω1 ≈ 1/(4x)` keeps its
//! relative accuracy for every finite `z1`, and `H` until it drops below the smallest double
//! (`|z1| ≳ 1e154`). Below 128 nothing underflows and `k = 1`. The outputs are ratios of values
//! scaled by the same power of two, so they do not depend on `k`.

use crate::error::Result;
use crate::special::{bessel_q_times, i01e_times};

/// `(i0e, ω1, ω2, E[x1⁴])` at `x = −z1/2 ≥ 0`, every value formed from Bessel functions
/// scaled by `k ≈ √x` (an exact power of two; 1 below 128), so that nothing underflows for any
/// finite `x`: `i0e ≈ (2πx)^{−1/2}` and `ω1 ≈ 1/(4x)` are representable down to the smallest
/// `x^{−1}`, but `i0e − i1e ≈ x^{−3/2}/5` is not.
#[inline(always)]
fn scaled(x: f64, fourth: bool) -> (f64, f64, f64, f64) {
    let k = if x < 128.0 { 1.0 } else { pow2_floor_sqrt(x) };
    let (ki0, ki1, kdm, _) = i01e_times(x, k);
    // one division (the ratios are within an ulp of the divided ones; the MLE evaluates this
    // several times in a row, so it is on the filter step's critical path)
    let half_inv = 0.5 / ki0;
    let w1 = kdm * half_inv;
    let w2 = (ki0 + ki1) * half_inv;
    let e11 = if fourth {
        bessel_q_times(x, k).0 * (0.25 * half_inv)
    } else {
        0.0
    };
    (ki0 / k, w1, w2, e11)
}

/// A power of two within a factor 2 of `√x` for `x ≥ 1` finite: `2^⌊e/2⌋`, `e` the exponent of
/// `x` (bit operations only; any such power of two serves as the exact scale factor `k`).
#[inline(always)]
fn pow2_floor_sqrt(x: f64) -> f64 {
    let e = (x.to_bits() >> 52) as i64 - 1023;
    f64::from_bits(((e / 2 + 1023) as u64) << 52)
}

/// Sorted evaluation (see `sorted_eval` in the parent module): `z = [z1, 0]`, `z1 ≤ 0`.
pub(crate) fn log_f_sorted(
    z: &[f64],
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<f64> {
    let x = -0.5 * z[0];
    let (i0, w1, w2, e11) = scaled(x, hess.is_some());
    let log_f = (2.0 * std::f64::consts::PI).ln() + i0.ln();
    if let Some(g) = grad {
        g[0] = w1;
        g[1] = w2;
    }
    if let Some(h) = hess {
        // H11 = E[x1⁴] − ω1² (no cancellation: E[x1⁴] ≈ 3ω1² when concentrated); since
        // ω1 + ω2 = 1 the other entries follow: H12 = H21 = −H11, H22 = H11 (computing
        // E[x2⁴] − ω2² directly would cancel catastrophically when x2² ≈ 1).
        let h11 = e11 - w1 * w1;
        h[0] = h11;
        h[1] = -h11;
        h[2] = -h11;
        h[3] = h11;
    }
    Ok(log_f)
}

/// `(ω1, ω2, ∂ω1/∂z1)` of `z = [z1, 0]`, `z1 ≤ 0`, with `∂ω1/∂z1 = Var(x1²)` (the same
/// formulas as [`log_f_sorted`], without its output slices and without `log F`: the d = 2
/// moment equation and the MLE's start solve many such problems).
#[inline]
pub(crate) fn pair_moments(z1: f64) -> (f64, f64, f64) {
    let (_, w1, w2, e11) = scaled(-0.5 * z1, true);
    (w1, w2, e11 - w1 * w1)
}
