//! d = 2: the closed form `F = 2π e^{(z1+z2)/2} I0((z2−z1)/2)` (JAIF App. B).
//!
//! With sorted `z1 ≤ z2 = 0` and `x = −z1/2 ≥ 0`: `F = 2π I0e(x)` where `I0e(x) = e^{−x} I0(x)`,
//! `ω1 = (I0e − I1e)/(2 I0e)` (the difference taken without cancellation), `ω2 = 1 − ω1`
//! computed as `(I0e + I1e)/(2 I0e)`.
//! Second derivatives: `∂²F/∂z1² = F·E[x1⁴]` with `E[cos⁴]` over the von Mises-type circle
//! density `= Q(x)/(8 I0e)`, `Q = e^{−x}(3I0 − 4I1 + I2)`; `E[x1²x2²] = (I0e − I2e)/(8 I0e) = I1e/(4x I0e)`;
//! `E[x2⁴] = (3I0e + 4I1e + I2e)/(8 I0e)`.

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
        // E[x1^4], E[x1^2 x2^2], E[x2^4] on the circle.
        let i2 = if x > 0.0 { i0 - 2.0 * i1 / x } else { 0.0 };
        let e11 = bessel_q(x) / (8.0 * i0);
        let e12 = if x > 0.0 { i1 / (4.0 * x * i0) } else { 0.125 };
        let e22 = (3.0 * i0 + 4.0 * i1 + i2) / (8.0 * i0);
        h[0] = e11 - w1 * w1;
        h[1] = e12 - w1 * w2;
        h[2] = h[1];
        h[3] = e22 - w2 * w2;
    }
    Ok(log_f)
}
