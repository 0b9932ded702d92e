//! Exact `F(Z)`, ω and the Hessian of `log F` for any d: Laplace inversion along the
//! steepest-descent contour (used by the dispatcher for d ≥ 5; correct for every d ≥ 1).
//!
//! With `λ_i = c − z_i`, `F(Z) = e^c · 2π^{d/2} · Π λ_i^{−1/2} · f_R(1)`, where `f_R` is the
//! density of `Σ y_i²/(2λ_i)` (Kume & Wood 2005); `f_R(1)` is the Laplace inversion integral of
//! `e^{φ(s)}`, `φ(s) = s − ½ Σ log(1 + s/λ_i)`, taken along the steepest-descent path through
//! the real saddle (the shift `c` puts it at `s = 0`) and parametrized by `φ(s(w)) = −w²`:
//! `f_R(1) = (1/π) ∫_0^∞ e^{−w²} y'(w) dw`. The trapezoidal rule in `w` converges geometrically;
//! its step is planned from the integrand's known singularities and refined until the predicted
//! error is below 1e-16. ω and the Hessian are the same integrals with the factors
//! `½/(λ_i + s)` and their products (differentiation under the integral).
//!
//! The parts: `complex` (the complex arithmetic and the argument-tracking product), `problem`
//! (the shifted problem and a point of its contour), `path` (solving `φ(s) = −w²` point by point
//! along the path), `steps` (the singularities and the step they allow) and this module (the
//! nested rule, the acceptance test and the results).
//! Contract: finite results for every finite sorted `z` with `z[d−1] = 0`, `F` and every `ω_i`
//! to near machine precision, or `Error::NotConverged` beyond 7169 nodes (never observed).
//! The derivation, the error bound and the cost are in `docs/design.md` (§ "The contour method
//! (any d)"); the measured accuracy in `docs/accuracy.md`, the speed in `docs/speed.md`.

mod complex;
mod path;
mod problem;
mod steps;
#[cfg(test)]
mod tests;

use crate::error::{Error, Result};
use complex::Cx;
use problem::{Contour, Node};
use std::f64::consts::{LN_2, PI};
use steps::{planned_step, predicted_error, H_COARSE};

/// End of the integration range in `w` (production schedule): the tail beyond is below
/// `e^{−42.25} < 5e-19` relative (module docs).
const W_END: f64 = 6.5;
/// The fixed schedule (convergence studies): `h₀ = 0.5` on `[0, 7]`, 14 coarsest steps.
const FIXED_N0: usize = 14;
/// Hard limit on the number of nodes (the finest level of the fixed schedule, `h = 2⁻¹⁰`).
const MAX_NODES: usize = 7169;
/// Accept a level when the predicted error of the integrals of `F` and ω ([`predicted_error`],
/// from their largest relative change `Δ` from the previous level) is at most this.
const TOL: f64 = 1e-16;
/// Accept the Hessian's integrals when their change is at most this (relative to the natural
/// scales), or when their predicted error is at most [`HESS_PREDICTED_TOL`]. For large d and
/// concentrations (d = 64, `|z| ~ 1e6`) their level-to-level change stalls at a rounding floor
/// of 2e-13..1e-12 (thousands of nodes summed) while `F` and ω have converged to 1e-15.
const HESS_TOL: f64 = 1e-11;
/// See [`HESS_TOL`].
const HESS_PREDICTED_TOL: f64 = 1e-15;
/// Maximal recursion depth of the step subdivision in path following.
const MAX_DEPTH: u32 = 12;

/// Neumaier's compensated summation.
#[derive(Default)]
struct Neumaier {
    sum: f64,
    comp: f64,
}

impl Neumaier {
    fn add(&mut self, x: f64) {
        let t = self.sum + x;
        if self.sum.abs() >= x.abs() {
            self.comp += (self.sum - t) + x;
        } else {
            self.comp += (x - t) + self.sum;
        }
        self.sum = t;
    }

    fn sum(&self) -> f64 {
        self.sum + self.comp
    }
}

/// Solves `½ Σ m_j/(c − z_j) = 1` for `c > 0`, where `z` is ascending with last entry
/// `0 = max z` and `m_j ≥ 1` are multiplicities (`Σ m_j` is the dimension).
///
/// `G(c) = 2/Σ m_j/(c − z_j) − 1` is a harmonic mean of linear functions minus one, hence
/// concave and increasing; Newton's method started at `c₀ = m_last/2` (where `G ≤ 0`) climbs
/// monotonically to the root. The root lies in `[m_last/2, (Σ m_j)/2]`.
pub(crate) fn solve_shift(z: &[f64], mult: &[f64]) -> Result<f64> {
    let mut c = 0.5 * mult[mult.len() - 1];
    for _ in 0..200 {
        let (mut s1, mut s2) = (0.0, 0.0);
        for (&zj, &m) in z.iter().zip(mult) {
            let r = 1.0 / (c - zj);
            s1 += m * r;
            s2 += m * r * r;
        }
        let g = 2.0 / s1 - 1.0;
        let step = -g * s1 * s1 / (2.0 * s2);
        if step.is_nan() || step <= 4.0 * f64::EPSILON * c {
            if c.is_finite() && c > 0.0 {
                return Ok(c);
            }
            break;
        }
        c += step;
    }
    Err(Error::NotConverged("shift to the saddle point".into()))
}

/// Everything the general method computes (sorted order, as the input).
#[derive(Debug, Clone)]
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) struct GeneralEval {
    /// `log F(z)`.
    pub log_f: f64,
    /// `ω_i = ∂ log F/∂z_i` (empty unless requested).
    pub grad: Vec<f64>,
    /// `∂² log F/∂z_i∂z_j`, row-major (empty unless requested).
    pub hess: Vec<f64>,
    /// Number of contour points used.
    pub nodes: usize,
    /// The relative change of the integrals of `F` and ω at each refinement level.
    pub changes: Vec<f64>,
    /// The predicted error at each refinement level.
    pub estimates: Vec<f64>,
}

/// Scales against which the change of each integral is measured: its own size, but for the
/// Hessian's auxiliary integrals (`δ` terms, which may be near zero by cancellation inside the
/// integral) at least 1e-3 of their natural size (`ω`-integral/`λ`, and products thereof).
fn natural_scales(first: &[f64], inv_lam: &[f64], hess: bool) -> Vec<f64> {
    let g = inv_lam.len();
    let mut scale = vec![0.0; first.len()];
    if hess {
        let total: f64 = first[..g].iter().map(|v| v.abs()).sum();
        let nat: Vec<f64> = (0..g).map(|j| first[j].abs() * inv_lam[j]).collect();
        for j in 0..g {
            scale[g + j] = 1e-3 * nat[j];
        }
        let mut idx = 3 * g;
        for j in 0..g {
            for k in j..g {
                scale[idx] = 1e-3 * nat[j] * nat[k] / total;
                idx += 1;
            }
        }
    }
    scale
}

/// Largest change between two levels, relative to each integral's size (at least `scale`, and
/// at least 1e-250: values that small only need absolute accuracy).
fn max_change(cur: &[f64], prev: &[f64], scale: &[f64]) -> f64 {
    cur.iter()
        .zip(prev)
        .zip(scale)
        .map(|((c1, c0), s)| (c1 - c0).abs() / c1.abs().max(*s).max(1e-250))
        .fold(0.0, f64::max)
}

/// The quadrature schedule.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Rule {
    /// Accept a level when the predicted error of the integrals of `F` and ω is at most this
    /// (`0`: never before `max_level`).
    pub tol: f64,
    /// `true`: the production schedule (coarsest step planned from the singularities, range
    /// `[0, 6.5]`); `false`: the fixed schedule `h = 2⁻¹, 2⁻², …` on `[0, 7]`.
    pub planned: bool,
    /// Finest level (step `h₀/2^level`).
    pub max_level: usize,
    /// Return the finest level's values even if `tol` was not met (for convergence studies).
    pub accept_at_max: bool,
}

/// The production schedule.
pub(crate) const RULE: Rule = Rule {
    tol: TOL,
    planned: true,
    max_level: 12,
    accept_at_max: false,
};

/// Evaluates `log F` and optionally ω and the Hessian for sorted (ascending), finite `z` of any
/// length `d ≥ 1` (the internal limit is only memory; the public one is `MAX_DIM`).
pub(crate) fn evaluate_sorted(z: &[f64], want_grad: bool, want_hess: bool) -> Result<GeneralEval> {
    evaluate_with(z, want_grad, want_hess, RULE)
}

/// [`evaluate_sorted`] with an explicit quadrature schedule.
pub(crate) fn evaluate_with(
    z: &[f64],
    want_grad: bool,
    want_hess: bool,
    rule: Rule,
) -> Result<GeneralEval> {
    let d = z.len();
    if d == 0 {
        return Err(Error::InvalidDimension("empty z".into()));
    }
    if z.iter().any(|v| !v.is_finite()) || z.windows(2).any(|p| p[0] > p[1]) {
        return Err(Error::InvalidArgument(
            "z must be finite and ascending".into(),
        ));
    }
    let zmax = z[d - 1];
    // Groups of equal values (ties), relative to the maximum.
    let mut zg: Vec<f64> = Vec::with_capacity(d);
    let mut mult: Vec<f64> = Vec::with_capacity(d);
    let mut group_of = Vec::with_capacity(d);
    for (i, &v) in z.iter().enumerate() {
        if i > 0 && v == z[i - 1] {
            *mult.last_mut().expect("nonempty") += 1.0;
        } else {
            zg.push(v - zmax);
            mult.push(1.0);
        }
        group_of.push(zg.len() - 1);
    }
    let g = zg.len();
    let c = solve_shift(&zg, &mult)?;
    let lam: Vec<f64> = zg.iter().map(|&v| c - v).collect();
    let inv_lam: Vec<f64> = lam.iter().map(|&l| 1.0 / l).collect();
    let moment = |k: i32| -> f64 {
        inv_lam
            .iter()
            .zip(&mult)
            .map(|(il, m)| m * il.powi(k))
            .sum::<f64>()
    };
    let kappa = 0.5 * moment(1);
    let ct = Contour {
        count: mult.iter().map(|&m| m as u32).collect(),
        tied: mult.iter().any(|&m| m > 1.0),
        single_il: inv_lam
            .iter()
            .zip(&mult)
            .filter(|(_, &m)| m == 1.0)
            .map(|(&il, _)| il)
            .collect(),
        mult_il: mult.iter().zip(&inv_lam).map(|(m, il)| m * il).collect(),
        om: 1.0 - kappa,
        a: 0.5 * moment(2),
        b: -moment(3),
        c4: 3.0 * moment(4),
        lam,
        inv_lam,
        mult,
    };

    let hess = want_hess;
    let nint = g + if hess { 3 * g + g * (g + 1) / 2 } else { 0 };
    let mut sums = vec![0.0; nint];
    let mut r: Vec<Cx> = ct.inv_lam.iter().map(|&il| Cx::new(il, 0.0)).collect();
    let mut dl = vec![Cx::new(0.0, 0.0); g];

    // The schedule: the coarsest step h₀ = h/2^L ≤ 0.5 for the planned step h.
    let sing = ct.singularities(hess);
    let (n0, mut h) = if rule.planned {
        let step = planned_step(&sing).max(W_END / MAX_NODES as f64);
        let mut h0 = step;
        while 2.0 * h0 <= H_COARSE {
            h0 *= 2.0;
        }
        let n0 = (W_END / h0).ceil() as usize;
        (n0, W_END / n0 as f64)
    } else {
        (FIXED_N0, H_COARSE)
    };

    // Level 0: march out from the saddle point.
    let mut nodes: Vec<Node> = Vec::with_capacity(n0 + 1);
    nodes.push(ct.origin());
    ct.accumulate(&nodes[0], 0.5, &r, &mut dl, &mut sums, hess);
    for k in 1..=n0 {
        let next = ct.march(&nodes[k - 1], h * k as f64, MAX_DEPTH, &mut r)?;
        ct.accumulate(&next, 1.0, &r, &mut dl, &mut sums, hess);
        nodes.push(next);
    }
    let mut prev: Vec<f64> = sums.iter().map(|v| v * h).collect();
    let scale = natural_scales(&prev, &ct.inv_lam, hess);
    let mut change = f64::INFINITY;
    let mut hess_change = 0.0;
    let mut changes = Vec::new();
    let mut estimates = Vec::new();
    let mut result: Option<Vec<f64>> = None;
    if rule.max_level == 0 && rule.accept_at_max {
        result = Some(prev.clone());
    }
    let mut refined: Vec<Node> = Vec::new();
    for level in 1..=rule.max_level {
        if 2 * nodes.len() - 1 > MAX_NODES {
            break;
        }
        h *= 0.5;
        refined.clear();
        refined.reserve(2 * nodes.len() - 1);
        for pair in nodes.windows(2) {
            let (l, rt) = (&pair[0], &pair[1]);
            let wm = 0.5 * (l.w + rt.w);
            let step = rt.w - l.w;
            // Septic Hermite predictor from both neighbours (s and three derivatives each).
            let pred = (l.s + rt.s).scale(0.5)
                + (l.ds - rt.ds).scale(11.0 * step / 64.0)
                + (l.dds + rt.dds).scale(3.0 * step * step / 128.0)
                + (l.d3s - rt.d3s).scale(step * step * step / 768.0);
            let mid = match ct.solve(wm, pred, &mut r) {
                Some((s, dv)) => ct.node(wm, s, &dv)?,
                None => ct.march(l, wm, MAX_DEPTH, &mut r)?,
            };
            ct.accumulate(&mid, 1.0, &r, &mut dl, &mut sums, hess);
            refined.push(*l);
            refined.push(mid);
        }
        refined.push(*nodes.last().expect("nonempty"));
        std::mem::swap(&mut nodes, &mut refined);
        let cur: Vec<f64> = sums.iter().map(|v| v * h).collect();
        change = max_change(&cur[..g], &prev[..g], &scale[..g]);
        hess_change = max_change(&cur[g..], &prev[g..], &scale[g..]);
        let estimate = predicted_error(&sing, h, change);
        changes.push(change);
        estimates.push(estimate);
        let converged = rule.tol > 0.0
            && estimate <= rule.tol
            && (hess_change <= HESS_TOL
                || predicted_error(&sing, h, hess_change) <= HESS_PREDICTED_TOL);
        if converged || (rule.accept_at_max && level == rule.max_level) {
            result = Some(cur);
            break;
        }
        prev = cur;
    }
    let t = result.ok_or_else(|| {
        Error::NotConverged(format!(
            "contour quadrature: relative change {change:e} (Hessian integrals {hess_change:e}) \
             after {} nodes",
            nodes.len()
        ))
    })?;

    // I = ∫₀^∞ e^{−w²} y'(w) dw = Σ_j m_j T_j  (so that Σ ω = 1 up to rounding).
    let total: f64 = t[..g].iter().zip(&ct.mult).map(|(tj, m)| m * tj).sum();
    if !(total > 0.0 && total.is_finite()) {
        return Err(Error::Numerical("contour integral is not positive".into()));
    }
    // log F = z_max + c + log 2 + (d/2) log π − ½ Σ m_j log λ_j + log I − log π, summed with
    // compensation (the terms reach hundreds for large d and |z|).
    let mut acc = Neumaier::default();
    for (l, m) in ct.lam.iter().zip(&ct.mult) {
        acc.add(-0.5 * m * l.ln());
    }
    acc.add(zmax);
    acc.add(c);
    acc.add(LN_2);
    acc.add(0.5 * (d as f64 - 2.0) * PI.ln());
    acc.add(total.ln());
    let log_f = acc.sum();
    if !log_f.is_finite() {
        return Err(Error::Numerical("log F is not finite".into()));
    }
    let grad = if want_grad || want_hess {
        group_of.iter().map(|&j| t[j] / total).collect()
    } else {
        Vec::new()
    };
    let mut hmat = Vec::new();
    if want_hess {
        hmat = vec![0.0; d * d];
        // ε_j = L(δ_j) = ω_j − 1/(2λ_j); for a ≠ b, Cov(x_a², x_b²) = E[x_a² x_b²] − ω_a ω_b
        // = L(δ_j δ_k) − ε_j ε_k (L the normalized contour functional, real-linear with
        // L(1) = 1): no cancellation between the ~ω_a ω_b-sized terms of the direct form.
        let eps: Vec<f64> = (0..g).map(|j| t[g + j] / total).collect();
        let mut offs = vec![0usize; g];
        let mut o = 3 * g;
        for (j, off) in offs.iter_mut().enumerate() {
            *off = o;
            o += g - j;
        }
        for i in 0..d {
            for k in 0..d {
                let (gi, gk) = (group_of[i], group_of[k]);
                hmat[i * d + k] = if i == k {
                    3.0 * t[2 * g + gi] / total - grad[i] * grad[i]
                } else {
                    let (j0, j1) = if gi <= gk { (gi, gk) } else { (gk, gi) };
                    t[offs[j0] + (j1 - j0)] / total - eps[gi] * eps[gk]
                };
            }
        }
        // The mode's variance from the zero row sum (Σ_k ∂ω_i/∂z_k = 0): E[x_d⁴] − ω_d² cancels
        // when the mode carries almost all the mass.
        let l = d - 1;
        let s: f64 = (0..l).map(|i| hmat[i * d + l]).sum();
        hmat[l * d + l] = -s;
        if hmat.iter().any(|v| !v.is_finite()) {
            return Err(Error::Numerical("Hessian is not finite".into()));
        }
    }
    Ok(GeneralEval {
        log_f,
        grad: if want_grad { grad } else { Vec::new() },
        hess: hmat,
        nodes: nodes.len(),
        changes,
        estimates,
    })
}

/// Sorted evaluation (see `sorted_eval` in the parent module).
pub(crate) fn log_f_sorted(
    z: &[f64],
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<f64> {
    let ev = evaluate_sorted(z, grad.is_some(), hess.is_some())?;
    if let Some(gr) = grad {
        gr.copy_from_slice(&ev.grad);
    }
    if let Some(hs) = hess {
        hs.copy_from_slice(&ev.hess);
    }
    Ok(ev.log_f)
}
