//! d = 3 and d = 4: the normalization constant as an exact 1-D integral of Bessel functions.
//!
//! Split the coordinates into two groups whose squared norms are `u` and `1 − u`
//! (`docs/design.md`, § "d = 3, 4: one-dimensional Bessel integrals"). With `z` sorted
//! ascending and `z_d = 0`:
//!
//! * d = 4: two circles, `(z1, z2)` of radius² `u` and `(z3, z4)` of radius² `1 − u`:
//!   `F = 2π² ∫₀¹ A(u) B(1−u) du`, `A(r) = e^{r z2} I0e(r (z2−z1)/2)`, `B(r) = I0e(r (z4−z3)/2)`.
//! * d = 3: the single coordinate `x1` (`x1² = u`) and the circle `(z2, z3)`:
//!   `F = 2π ∫₀¹ A(u) B(1−u) du`, `A(r) = r^{−1/2} e^{r z1}`, `B(r) = I0e(r (z3−z2)/2)`.
//!
//! Moments come from the same integrals (the circle moments `E[x_lo²] = r (I0e − I1e)/2`, …, in
//! `docs/design.md`); every integrand is positive, so `ω_i = E[x_i²]` carries no cancellation.
//!
//! Contract: for every finite sorted `z` with `z_d = 0`, `log F` and every `ω_i` to near machine
//! precision (down to `ω_i ≈ 1/(2|z_i|)` at |z| = 1e300); the Hessian less accurately (a
//! covariance of nearly independent coordinates cancels digits; it only steers the MLE). How: the halves `u ∈ [0, ½]`, `[½, 1]` in `√u`, `√(1−u)`, graded 20-point
//! Gauss–Legendre panels (`LAYOUT`, in `rule`), power-of-two scalings per group and half
//! (`Scaling`, in `groups`), the kernel (`kernel`) compiled per CPU path (`simd`, the crate's
//! only `unsafe` outside the FFI), the path chosen at run time (`Path`, in `kernel_path`).
//! Derivation and numerics: `docs/design.md` (§ "Numerical notes": d = 3, 4 quadrature, kernel
//! paths, range); measured accuracy `docs/accuracy.md`, speed `docs/speed.md`.

use crate::error::Result;

mod groups;
mod kernel;
mod kernel_path;
mod rule;
mod simd;

use groups::{d_factors, Group};
use kernel::half_setup;
pub use kernel_path::{Path, KERNEL_ENV};
use rule::{padded, Layout, Rule, LAYOUT, RULE};
use simd::half_on;

/// `log F`, `ω` and (with `fourth`) the Hessian in sorted order, and the node count.
struct Integral {
    log_f: f64,
    omega: [f64; 4],
    hess: [f64; 16],
    nodes: usize,
}

#[allow(clippy::too_many_arguments)]
fn integrate_counted(
    path: Path,
    rule: &Rule,
    lay: &Layout,
    log_c: f64,
    g1: Group,
    g2: Group,
    d: usize,
    fourth: bool,
) -> Integral {
    let left = half_setup(lay, &g1, &g2, true);
    let (sc1, sc2) = (left.sc1, left.sc2);
    let mut sums = half_on(path, rule, &g1, &g2, true, fourth, &left);
    let dl = d_factors(&g1, &sc1, &sc2);
    // The far half u ∈ [½, 1]: A(u) decreases and B(1−u) ≤ 1, so its integral is at most
    // A(½)/2 (times the moment factors, ≤ 1). Skip it when that bound is negligible against
    // F and against every moment integral (all in the left half's scaled units:
    // f_true = f/(C1 C2), m_true = m/(C1 C2 D)).
    let at_half = g1.eval_far(&sc1, 0.5, std::f64::consts::FRAC_1_SQRT_2);
    let bound = 0.5 * at_half.g * sc2.c;
    let smallest = sums.m[..d]
        .iter()
        .zip(dl.iter())
        .fold(sums.f, |acc, (&m, &dk)| acc.min(m / dk));
    if bound > 1e-18 * smallest {
        let setup = half_setup(lay, &g1, &g2, false);
        let right = half_on(path, rule, &g1, &g2, false, fourth, &setup);
        let (rc1, rc2) = (setup.sc1, setup.sc2);
        let dr = d_factors(&g1, &rc1, &rc2);
        // right-half sums in the left half's units (modest ratios: this half only runs
        // when group 1's rate is below a few thousand)
        let cf = (sc1.c / rc1.c) * (sc2.c / rc2.c);
        let mut ratio = [0.0; 4];
        for ((r, l), rr) in ratio.iter_mut().zip(&dl).zip(&dr).take(d) {
            *r = cf * (l / rr);
        }
        sums.nodes += right.nodes;
        sums.f += cf * right.f;
        for ((s, r), m) in sums.m.iter_mut().zip(&ratio).zip(&right.m).take(d) {
            *s += r * m;
        }
        if fourth {
            for (i, (row, rrow)) in sums.q.iter_mut().zip(&right.q).enumerate().take(d) {
                for j in i..d {
                    row[j] += (ratio[i] * (dl[j] / dr[j])) * rrow[j];
                }
            }
        }
    }
    // f / (C1 C2) by exact power-of-two divisions; its logarithm directly while it is a
    // normal double, else log f minus the scale's exponent times ln 2
    let f_true = sums.f / sc1.c / sc2.c;
    let log_f = if f_true >= f64::MIN_POSITIVE {
        log_c + f_true.ln()
    } else {
        let exponent = |v: f64| ((v.to_bits() >> 52) as i64 - 1023) as f64;
        log_c + sums.f.ln() - (exponent(sc1.c) + exponent(sc2.c)) * std::f64::consts::LN_2
    };
    let mut out = Integral {
        log_f,
        omega: [0.0; 4],
        hess: [0.0; 16],
        nodes: sums.nodes,
    };
    for ((w, m), dk) in out.omega.iter_mut().zip(&sums.m).zip(&dl).take(d) {
        *w = m / sums.f / dk;
    }
    if fourth {
        let (omega, h) = (&out.omega, &mut out.hess);
        // Cov(x_i², x_j²) for i, j < d; the last row and column from Σ_i ∂ω_i/∂z_j = 0,
        // which avoids the cancellation E[x_d⁴] − ω_d² when x_d² ≈ 1.
        for i in 0..d - 1 {
            for j in i..d - 1 {
                let v = sums.q[i][j] / sums.f / dl[i] / dl[j] - omega[i] * omega[j];
                h[i * d + j] = v;
                h[j * d + i] = v;
            }
        }
        let mut last_sum = 0.0;
        for i in 0..d - 1 {
            let s: f64 = (0..d - 1).map(|j| h[i * d + j]).sum();
            h[i * d + d - 1] = -s;
            h[(d - 1) * d + i] = -s;
            last_sum += s;
        }
        h[d * d - 1] = last_sum;
    }
    out
}

/// Evaluates with the given rule, layout and kernel; writes the outputs in sorted order.
fn integrate(
    path: Path,
    rule: &Rule,
    lay: &Layout,
    z: &[f64],
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<(f64, usize)> {
    let d = z.len();
    let (log_c, g1, g2) = groups(z);
    let out = integrate_counted(path, rule, lay, log_c, g1, g2, d, hess.is_some());
    if let Some(g) = grad {
        g.copy_from_slice(&out.omega[..d]);
    }
    if let Some(h) = hess {
        h.copy_from_slice(&out.hess[..d * d]);
    }
    Ok((out.log_f, out.nodes))
}

/// `log c` and the two groups of sorted `z` (d = 3 or 4), `F = c ∫ A B` (module documentation).
fn groups(z: &[f64]) -> (f64, Group, Group) {
    /// ln(2π) and ln(2π²), as `f64::ln` rounds them
    const LN_2PI: f64 = 1.8378770664093453;
    const LN_2PI2: f64 = 2.9826069522587457;
    if z.len() == 3 {
        (
            LN_2PI,
            Group::Single { z: z[0] },
            Group::Circle {
                zhi: z[2],
                beta: 0.5 * (z[2] - z[1]),
            },
        )
    } else {
        (
            LN_2PI2,
            Group::Circle {
                zhi: z[1],
                beta: 0.5 * (z[1] - z[0]),
            },
            Group::Circle {
                zhi: z[3],
                beta: 0.5 * (z[3] - z[2]),
            },
        )
    }
}

/// The same integral with a much finer rule (Gauss–Legendre 30 on a layout ~4× denser,
/// truncation at e^{−80}): the convergence check used by the tests. Sorted `z`; writes `ω`
/// and, if given, the Hessian (sorted order).
#[doc(hidden)]
pub fn log_f_sorted_fine(z: &[f64], grad: &mut [f64], hess: Option<&mut [f64]>) -> Result<f64> {
    static R30: ([f64; 32], [f64; 32]) = padded::<30, 32>();
    let fine = Layout {
        first: 0.25,
        rho: 1.6,
        w_max: 0.08,
        trunc: 80.0,
        kappa: 0.5,
        grow: 1.0,
    };
    let rule = Rule {
        x: &R30.0,
        w: &R30.1,
        n: 30,
    };
    integrate(Path::detected(), &rule, &fine, z, Some(grad), hess).map(|r| r.0)
}

/// Evaluation with a chosen Gauss–Legendre order and layout `[first, rho, w_max, trunc, kappa,
/// grow]` (`grow` optional, default 1) for tuning experiments; returns `log F` and the node count.
#[doc(hidden)]
pub fn log_f_sorted_tuned(
    z: &[f64],
    grad: &mut [f64],
    hess: Option<&mut [f64]>,
    n: usize,
    lay: &[f64],
) -> Result<(f64, usize)> {
    let lay = Layout {
        first: lay[0],
        rho: lay[1],
        w_max: lay[2],
        trunc: lay[3],
        kappa: lay[4],
        grow: lay.get(5).copied().unwrap_or(1.0),
    };
    macro_rules! go {
        ($n:literal, $p:literal) => {{
            static R: ([f64; $p], [f64; $p]) = padded::<$n, $p>();
            let rule = Rule {
                x: &R.0,
                w: &R.1,
                n: $n,
            };
            integrate(Path::detected(), &rule, &lay, z, Some(grad), hess)
        }};
    }
    match n {
        6 => go!(6, 8),
        8 => go!(8, 8),
        10 => go!(10, 16),
        12 => go!(12, 16),
        14 => go!(14, 16),
        16 => go!(16, 16),
        18 => go!(18, 24),
        24 => go!(24, 24),
        32 => go!(32, 32),
        _ => go!(20, 24),
    }
}

/// d = 3 or 4 with a chosen kernel (see [`Path`]); sorted `z`, outputs in sorted order.
pub(crate) fn log_f_sorted_on(
    path: Path,
    z: &[f64],
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<f64> {
    integrate(path, &RULE, &LAYOUT, z, grad, hess).map(|r| r.0)
}
