//! The third-order saddlepoint approximation of Kume & Wood (2005), any d. **APPROXIMATE.**
//!
//! This is [`Method::Saddlepoint`](super::Method::Saddlepoint): fast (O(d) per value, no
//! quadrature) but not exact: relative errors of `F` up to several percent — largest at moderate
//! concentration around one direction, roughly constant whenever a single direction dominates
//! (`R` is then nearly a Gamma(½) variable), smallest near the uniform distribution in higher
//! d; the ω have errors of the same size. Measured against the
//! exact method by `tests/saddlepoint.rs`; the figures are in `docs/accuracy.md`
//! (§ "Saddlepoint approximation"). Use [`Method::Exact`](super::Method::Exact) unless speed
//! matters more.
//!
//! # Formula (`docs/design.md`, § "Saddlepoint approximation")
//! With `λ_i = c − z_i > 0` and the cumulant generating function `K(t) = −½ Σ log(1 − t/λ_i)` of
//! `R = Σ y_i²/(2λ_i)`, `K⁽ʲ⁾(t) = ((j−1)!/2) Σ (λ_i − t)^{−j}`, the saddle point `t̂` solves
//! `K'(t̂) = 1`, and
//!
//! `F̂₁ = √2 · π^{(d−1)/2} · K''(t̂)^{−½} · Π (λ_i − t̂)^{−½} · e^{c − t̂}`,
//! `F̂₃ = F̂₁ · exp(ρ₄/8 − 5ρ₃²/24)`, `ρ_j = K⁽ʲ⁾(t̂)/K''(t̂)^{j/2}`.
//!
//! The approximation is exactly equivariant under shifts (`F̂(Z + aI) = e^a F̂(Z)`), so `c` is
//! chosen such that `t̂ = 0`, i.e. `½ Σ 1/(c − z_i) = 1` — the same shift as the exact method
//! uses (solved by Newton's method on a concave function, monotone from below; see
//! `contour::solve_shift`).
//!
//! # Derivatives
//! As in Gilitschenski et al. (2014), Cor. 2 (Kume & Wood 2007, surface measure):
//! `∂F/∂z_i = F_{d+2}(z_i three times)/(2π)`, `∂²F/∂z_i² = 3 F_{d+4}(z_i five times)/(4π²)`,
//! `∂²F/∂z_i∂z_j = F_{d+4}(z_i, z_j three times each)/(4π²)`, with every `F` replaced by its
//! saddlepoint approximation `F̂₃`. Hence `ω_i = F̂_{d+2}(…)/(2π F̂)` and the Hessian
//! `E[x_i² x_j²] − ω_i ω_j` are approximate too, and **`Σ ω_i` is not exactly 1** (it is off by
//! about the same relative amount as `F̂`). Tied values need no special care.

use super::contour::solve_shift;
use crate::error::{Error, Result};
use std::f64::consts::PI;

/// `log F̂₃` for the sorted `z` (ascending), where entry `extra[k].0` is repeated `extra[k].1`
/// additional times (the dimension is `z.len() + Σ extra[k].1`).
fn log_f_hat(z: &[f64], extra: &[(usize, f64)]) -> Result<f64> {
    let d = z.len();
    let zmax = z[d - 1];
    let mut zs = Vec::with_capacity(d);
    let mut mult = Vec::with_capacity(d);
    for &v in z {
        zs.push(v - zmax);
        mult.push(1.0);
    }
    for &(i, m) in extra {
        mult[i] += m;
    }
    let dim: f64 = mult.iter().sum();
    let c = solve_shift(&zs, &mult)?;
    let (mut k2, mut k3, mut k4, mut sum_log) = (0.0, 0.0, 0.0, 0.0);
    for (&v, &m) in zs.iter().zip(&mult) {
        let lam = c - v;
        let r = 1.0 / lam;
        let r2 = r * r;
        k2 += m * r2;
        k3 += m * r2 * r;
        k4 += m * r2 * r2;
        sum_log += m * lam.ln();
    }
    // K'' = ½ Σ λ^{-2}, K''' = Σ λ^{-3}, K'''' = 3 Σ λ^{-4} (at t̂ = 0).
    let k2 = 0.5 * k2;
    let k4 = 3.0 * k4;
    let rho3 = k3 / k2.powf(1.5);
    let rho4 = k4 / (k2 * k2);
    let t = rho4 / 8.0 - 5.0 * rho3 * rho3 / 24.0;
    let log_f = zmax + c + 0.5 * std::f64::consts::LN_2 + 0.5 * (dim - 1.0) * PI.ln()
        - 0.5 * k2.ln()
        - 0.5 * sum_log
        + t;
    if log_f.is_finite() {
        Ok(log_f)
    } else {
        Err(Error::Numerical(format!(
            "saddlepoint approximation is not finite for z = {z:?}"
        )))
    }
}

/// Sorted evaluation (see `sorted_eval` in the parent module): the saddlepoint approximation of `log F`, and its
/// gradient / Hessian through the Kume–Wood identities (approximate; `Σ ω ≠ 1` exactly).
pub(crate) fn log_f_sorted(
    z: &[f64],
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<f64> {
    let d = z.len();
    if d == 0 || z.iter().any(|v| !v.is_finite()) {
        return Err(Error::InvalidArgument(
            "z must be non-empty and finite".into(),
        ));
    }
    let log_f = log_f_hat(z, &[])?;
    let log_2pi = (2.0 * PI).ln();
    let mut omega = vec![0.0; d];
    if grad.is_some() || hess.is_some() {
        for (i, w) in omega.iter_mut().enumerate() {
            *w = (log_f_hat(z, &[(i, 2.0)])? - log_f - log_2pi).exp();
        }
    }
    if let Some(h) = hess {
        for i in 0..d {
            for j in i..d {
                let e = if i == j {
                    3.0 * (log_f_hat(z, &[(i, 4.0)])? - log_f - 2.0 * log_2pi).exp()
                } else {
                    (log_f_hat(z, &[(i, 2.0), (j, 2.0)])? - log_f - 2.0 * log_2pi).exp()
                };
                let v = e - omega[i] * omega[j];
                h[i * d + j] = v;
                h[j * d + i] = v;
            }
        }
    }
    if let Some(g) = grad {
        g.copy_from_slice(&omega);
    }
    Ok(log_f)
}
