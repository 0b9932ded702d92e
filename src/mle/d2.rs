//! The d = 2 moment equation `ω_1([x, 0]) = r`, solved in closed-form steps ([`pair_solve`]):
//! the MLE's d = 2 case ([`newton_pair`]) and the pair problems of the d ≥ 3 cold start.

use super::solution::{NewtonStart, MLE_TOL};
use crate::error::{Error, Result};
use crate::normalization::d2::pair_moments;

/// [`newton`](super::newton::newton) for d = 2: `ω_1([z_1, 0]) = ω̂_1/(ω̂_1 + ω̂_2)` by
/// [`pair_solve`] to `MLE_TOL`, from the evaluated point in `z`, `grad`, `hess` or from
/// [`banerjee`]'s start. Writes the solution and its derivatives (this is the only evaluation
/// the Hessian of the solution needs in d = 2: [`pair_moments`] returns it with ω).
pub(super) fn newton_pair(
    target: &[f64],
    from: NewtonStart,
    z: &mut [f64],
    grad: &mut [f64],
    hess: &mut [f64],
) -> Result<usize> {
    let start = match from {
        NewtonStart::Evaluated => Some(PairPoint {
            x: z[0],
            w1: grad[0],
            w2: grad[1],
            h: hess[0],
        }),
        NewtonStart::Guess => None,
    };
    let (p, steps) = pair_solve(target[0], target[1], start, MLE_TOL);
    let steps = steps.ok_or_else(|| {
        let r = target[0] / (target[0] + target[1]);
        Error::NotConverged(format!(
            "MLE (d = 2): no convergence (relative residual {:e})",
            ((p.w1 - r) / r).abs()
        ))
    })?;
    z[0] = p.x;
    z[1] = 0.0;
    grad[0] = p.w1;
    grad[1] = p.w2;
    hess.copy_from_slice(&[p.h, -p.h, -p.h, p.h]);
    Ok(steps)
}

/// A point of the d = 2 moment equation: `z = [x, 0]` with `ω = (w1, w2)` and `h = ∂ω_1/∂z_1`.
#[derive(Debug, Clone, Copy)]
pub(super) struct PairPoint {
    pub(super) x: f64,
    pub(super) w1: f64,
    pub(super) w2: f64,
    pub(super) h: f64,
}

impl PairPoint {
    fn at(x: f64) -> PairPoint {
        let (w1, w2, h) = pair_moments(x);
        PairPoint { x, w1, w2, h }
    }
}

/// Most evaluations [`pair_solve`] makes (Newton needs two to four for 1e-13; each bisection
/// halves the bracket).
const PAIR_MAX_ITER: usize = 100;

/// `Φ(ω_1)`: the z_1 of Banerjee et al.'s approximation of the d = 2 moment equation's
/// solution, `κ ≈ ρ(2 − ρ²)/(1 − ρ²)` with `ρ = 1 − 2ω_1 = I1(κ)/I0(κ)` and `z_1 = −2κ`,
/// written in `ω_1` (`1 − ρ² = q = 4ω_1(1 − ω_1)`) so that it keeps its relative accuracy for
/// concentrated `ω_1`: `Φ = −2ρ(1 + q)/q`. Exact in both limits (`z_1 → 0` and `z_1 → −∞`) and
/// within 7 % between (measured: largest deviation 6.1 % of `z_1` at `ρ = 0.875`). The start of
/// [`pair_solve`].
fn banerjee(w: f64) -> f64 {
    let q = 4.0 * w * (1.0 - w);
    -2.0 * (1.0 - 2.0 * w) * (1.0 + q) / q
}

/// Solves `ω_1([x, 0]) = r = a/(a + b)` for `x ≤ 0` (`0 < a ≤ b`, i.e. `0 < r ≤ 1/2`) to
/// `|ω_1/r − 1| ≤ tol`, from `start`
/// (an evaluated point) or from `x = Φ(r)` ([`banerjee`], within 7 %). Newton's method on
/// `1/ω_1 − 1/r`, nearly linear in `x` (`1/ω_1 ≈ 2|x|` when concentrated): `Δ = ω_1²(1/ω_1 −
/// 1/r)/h = −ω_1 (ω_1/r − 1)/h`, `h = ∂ω_1/∂x`; where `h` has underflowed (|x| ≳ 1e154) its
/// asymptote `2ω_1²` is used. The root is kept in a bracket (`ω_1` increases with `x`): a step
/// that leaves it bisects instead (geometrically where the bracket spans orders of
/// magnitude), so the iteration converges from any start. Returns the last
/// point and the number of Newton steps, `None` if the bracket collapsed (or the steps ran out)
/// above the tolerance (beyond the rounding floor of `1e3·tol`).
pub(super) fn pair_solve(
    a: f64,
    b: f64,
    start: Option<PairPoint>,
    tol: f64,
) -> (PairPoint, Option<usize>) {
    // r and 1/r as two independent divisions (not one after the other)
    let (r, inv_r) = (a / (a + b), (a + b) / a);
    if r >= 0.5 {
        return (PairPoint::at(0.0), Some(0));
    }
    let mut p = match start {
        Some(p) if p.x <= 0.0 && p.x.is_finite() => p,
        _ => {
            let x = banerjee(r);
            PairPoint::at(if x.is_finite() { x.min(0.0) } else { -1.0 })
        }
    };
    // ω_1(lo) < r < ω_1(hi)
    let (mut lo, mut hi) = (f64::NEG_INFINITY, 0.0f64);
    let mut steps = 0;
    while steps < PAIR_MAX_ITER {
        let err = p.w1 * inv_r - 1.0;
        if err.abs() <= tol {
            return (p, Some(steps));
        }
        if err > 0.0 {
            hi = hi.min(p.x);
        } else {
            lo = lo.max(p.x);
        }
        // Δ = −ω_1·err/h; where h is not a normal number (it underflows for |x| ≳ 1e154) its
        // asymptote 2ω_1² gives Δ = −err/(2ω_1)
        let next = if p.h.is_normal() {
            p.x - p.w1 * err / p.h
        } else {
            p.x - err / (2.0 * p.w1)
        };
        let next = if next > lo && next < hi {
            next
        } else if lo.is_finite() {
            // bisection; geometric where the bracket spans orders of magnitude
            if hi < 0.0 && lo < 4.0 * hi {
                -(-lo).sqrt() * (-hi).sqrt()
            } else if hi == 0.0 && lo < -4.0 {
                -(-lo).sqrt()
            } else {
                0.5 * (lo + hi)
            }
        } else {
            // no lower end yet: twice as far out as the upper one (or −1 from 0)
            2.0 * hi.min(-0.5)
        };
        if next == p.x || next == lo || next == hi {
            break;
        }
        p = PairPoint::at(next);
        steps += 1;
    }
    let converged = (p.w1 * inv_r - 1.0).abs() <= 1e3 * tol;
    (p, converged.then_some(steps))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// d = 2 ([`pair_solve`]): the moment equation of `z = [x, 0]` solved back to `x` over the
    /// whole range (|x| from 1e-6 to 1e300), cold and from starts far on either side, to the
    /// tolerance in ω and to the matching accuracy in `x`.
    #[test]
    fn pair_solve_inverts_the_d2_moment_equation_everywhere() {
        let mut xs = vec![0.0];
        let mut e = -6.0;
        while e <= 300.0 {
            xs.push(-(10f64.powf(e)));
            e += 0.37;
        }
        for &x in &xs {
            let (w1, w2, h) = pair_moments(x);
            let inv_r = (w1 + w2) / w1;
            let starts = [
                None,
                Some(PairPoint::at(0.0)),
                Some(PairPoint::at(x * 0.5)),
                Some(PairPoint::at((x * 2.0).max(-f64::MAX))),
                Some(PairPoint::at(-1e300)),
                Some(PairPoint { x, w1, w2, h }),
            ];
            for start in starts {
                let (p, steps) = pair_solve(w1, w2, start, MLE_TOL);
                let steps = steps.unwrap_or_else(|| panic!("x = {x:e}, start {start:?}: {p:?}"));
                assert!(steps <= 60, "x = {x:e}: {steps} steps");
                assert!((p.w1 * inv_r - 1.0).abs() <= MLE_TOL, "x = {x:e}: {p:?}");
                // the tolerance in ω moves x by up to tol·ω_1/h (≈ tol·|x| when concentrated,
                // 4·tol near 0); where h underflows, ω_1 ≈ 1/(2|x|)
                let cond = if h > 0.0 { w1 / h } else { x.abs() };
                assert!(
                    (p.x - x).abs() <= 2.0 * MLE_TOL * cond + 1e-14 * x.abs(),
                    "x = {x:e}, start {start:?}: got {}",
                    p.x
                );
                let (w1p, w2p, hp) = pair_moments(p.x);
                assert_eq!((p.w1, p.w2, p.h), (w1p, w2p, hp));
            }
        }
        // r = 1/2 (ties) is z = 0
        assert_eq!(pair_solve(1.0, 1.0, None, MLE_TOL).0.x, 0.0);
    }
}
