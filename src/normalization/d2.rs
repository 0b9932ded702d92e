//! d = 2: the closed form `F = 2π e^{(z1+z2)/2} I0((z2−z1)/2)` (JAIF App. B).
//!
//! With sorted `z1 ≤ z2 = 0` and `x = −z1/2 ≥ 0`: `F = 2π I0e(x)` where `I0e(x) = e^{−x} I0(x)`,
//! `ω1 = (I0e − I1e)/(2 I0e)` (the difference taken without cancellation), `ω2 = 1 − ω1`
//! computed as `(I0e + I1e)/(2 I0e)`.
//! Second derivatives: `∂²F/∂z1² = F·E[x1⁴]` with `E[x1⁴] = Q(x)/(8 I0e)`,
//! `Q = e^{−x}(3I0 − 4I1 + I2)` (evaluated without cancellation); the rest of the Hessian of
//! `log F` follows from `ω1 + ω2 = 1`.

use crate::error::Result;
use crate::special::{bessel_q, i01e};

/// Sorted evaluation (see `SortedEval`): `z = [z1, 0]`, `z1 ≤ 0`.
pub(crate) fn log_f_sorted(
    z: &[f64],
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<f64> {
    let x = -0.5 * z[0];
    let (i0, i1, dm) = i01e(x);
    let log_f = (2.0 * std::f64::consts::PI).ln() + i0.ln();
    let w1 = dm / (2.0 * i0);
    let w2 = (i0 + i1) / (2.0 * i0);
    if let Some(g) = grad {
        g[0] = w1;
        g[1] = w2;
    }
    if let Some(h) = hess {
        // H11 = E[x1⁴] − ω1² (no cancellation: E[x1⁴] ≈ 3ω1² when concentrated); since
        // ω1 + ω2 = 1 the other entries follow: H12 = H21 = −H11, H22 = H11 (computing
        // E[x2⁴] − ω2² directly would cancel catastrophically when x2² ≈ 1).
        let e11 = bessel_q(x) / (8.0 * i0);
        let h11 = e11 - w1 * w1;
        h[0] = h11;
        h[1] = -h11;
        h[2] = -h11;
        h[3] = h11;
    }
    Ok(log_f)
}

/// `ω1` and `∂ω1/∂z1 = Var(x1²)` of `z = [z1, 0]`, `z1 ≤ 0` (the same formulas as
/// [`log_f_sorted`], without its output slices; the MLE's start solves many d = 2 problems).
#[inline]
pub(crate) fn omega1_with_slope(z1: f64) -> (f64, f64) {
    let x = -0.5 * z1;
    let (i0, _, dm) = i01e(x);
    let w1 = dm / (2.0 * i0);
    (w1, bessel_q(x) / (8.0 * i0) - w1 * w1)
}
