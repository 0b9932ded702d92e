//! Step planning: the integrand's singularities nearest to the real `w` axis, the error they
//! predict for the trapezoidal rule, and the step at which that error is below the target.

use super::problem::Contour;
use std::f64::consts::PI;

/// Largest coarsest step of the production schedule.
pub(super) const H_COARSE: f64 = 0.5;
/// The step is chosen such that every singularity's predicted error term is below
/// `e^{−LN_TARGET}` (3e-17), below what the acceptance test [`TOL`](super::TOL) demands (so that
/// the test passes at the planned level).
const LN_TARGET: f64 = 38.0;

impl Contour {
    /// `Re φ(s)` at a real `s` in a gap between two `−λ_j` (one logarithm of a rescaled product).
    pub(super) fn re_phi_real(&self, s: f64) -> f64 {
        let (mut prod, mut acc) = (1.0f64, 0.0f64);
        for (&il, &n) in self.inv_lam.iter().zip(&self.count) {
            let f = (1.0 + s * il).abs();
            for _ in 0..n {
                prod *= f;
            }
            if !(1e-150..=1e150).contains(&prod) {
                acc += prod.ln();
                prod = 1.0;
            }
        }
        s - 0.5 * (acc + prod.ln())
    }

    /// The singularities of the integrand nearest to the real `w` axis, as `(a, ln C)`: strip
    /// half-width `a` (distance from the real axis) and the logarithm of the weight `C` of its
    /// error term `C·e^{−2πa/h}` in the trapezoidal rule, relative to the integrals.
    ///
    /// `w(s) = √(−φ(s))` is singular where `φ' = 0`. The zeros of `φ'` are real: `s = 0` and one
    /// saddle `s*` in each gap between consecutive `−λ_j` (`½ Σ m_j/(λ_j + s) = 1` is a secular
    /// equation). Approached from the upper half plane, `φ(s*) = −A − iπM/2` with `M` the number
    /// of `λ_j` (with multiplicity) right of `s*`, so the image is `w* = √(A + iπM/2)` with
    /// weight `e^{−A}`, times the size of the ω integrands' factor `λ_j/(λ_j + s)` of the two
    /// neighbours relative to its value at the mode (squared for the Hessian's integrands).
    /// The saddle `s = 0` itself has images on the other sheets of the logarithms, at
    /// `w*² = iπN`, `N` a multiple of the gcd of the multiplicities (winding once around `−λ_j`
    /// changes `φ` by `−iπm_j`): `a = √(πN/2)`, weight about 1 (here 2).
    pub(super) fn singularities(&self, hess: bool) -> Vec<(f64, f64)> {
        let g = self.lam.len();
        let power = if hess { 2.0 } else { 1.0 };
        let mut out = Vec::with_capacity(g);
        let gcd = self.count.iter().fold(0u32, |a, &b| {
            let (mut x, mut y) = (a, b);
            while y != 0 {
                (x, y) = (y, x % y);
            }
            x
        });
        out.push(((0.5 * PI * f64::from(gcd)).sqrt(), 2f64.ln()));
        let mut m_right = 0.0;
        // `lam` is descending: the gap between lam[k] (smaller) and lam[k − 1].
        for k in (1..g).rev() {
            m_right += self.mult[k];
            let (p, q) = (self.lam[k], self.lam[k - 1]);
            let (mp, mq) = (self.mult[k], self.mult[k - 1]);
            let delta = q - p;
            if delta <= 1e-13 * q {
                // A near-tie: its saddle lies far from the real w axis (`A → −∞`, `a ~ √|A|`).
                continue;
            }
            // s = −p − t, t ∈ (0, δ): ½ Σ m_j/(λ_j − p − t) = 1, increasing in t from −∞ to +∞;
            // Newton's method, bisection when a step leaves the bracket. Started at the
            // two-pole root; low accuracy suffices (A is stationary at the saddle).
            let mut t = mp * delta / (mp + mq);
            // Re φ is smallest at the saddle on the real gap: any point bounds A from below.
            if -self.re_phi_real(-p - t) > 2.0 * LN_TARGET + power * 40.0 {
                continue;
            }
            // Newton on G(t) = t(δ − t)·(the equation), free of the two nearest poles:
            // G = ½m_q t − ½m_p (δ − t) + t(δ − t) R(t), R the rest (other poles, and −1).
            let (mut lo, mut hi) = (0.0, delta);
            for _ in 0..100 {
                let (mut rest, mut drest) = (-1.0, 0.0);
                for (j, (&l, &m)) in self.lam.iter().zip(&self.mult).enumerate() {
                    if j != k && j + 1 != k {
                        let x = 1.0 / ((l - p) - t);
                        rest += 0.5 * m * x;
                        drest += 0.5 * m * x * x;
                    }
                }
                let u = t * (delta - t);
                let gt = 0.5 * mq * t - 0.5 * mp * (delta - t) + u * rest;
                let dg = 0.5 * (mp + mq) + (delta - 2.0 * t) * rest + u * drest;
                if gt > 0.0 {
                    hi = t;
                } else {
                    lo = t;
                }
                let mut tn = t - gt / dg;
                if !(tn > lo && tn < hi) {
                    tn = 0.5 * (lo + hi);
                }
                let done = (tn - t).abs() <= 1e-2 * tn.min(delta - tn);
                t = tn;
                if done {
                    break;
                }
            }
            let aa = -self.re_phi_real(-p - t);
            let c = (p / t).max(q / (delta - t)).clamp(1.0, 1e300);
            let half = 0.5 * PI * m_right;
            let rad = aa.hypot(half);
            let a = if aa > 0.0 {
                half / (2.0 * (0.5 * (rad + aa)).sqrt())
            } else {
                (0.5 * (rad - aa)).sqrt()
            };
            if a.is_finite() && aa.is_finite() {
                out.push((a, power * c.ln() - aa));
            }
        }
        out
    }
}

/// The predicted error of the level of step `h` whose integrals changed by `change` (relative)
/// from the level of step `2h`: each singularity's error term `C e^{−2πa/h}` is at most that
/// a-priori size, and at most `e^{−πa/h}` times its size at step `2h`, itself at most about
/// `change` (the error of the coarser level); the largest term.
pub(super) fn predicted_error(sing: &[(f64, f64)], h: f64, change: f64) -> f64 {
    sing.iter()
        .map(|&(a, lnw)| {
            let ratio = (-PI * a / h).exp();
            (ratio * change).min((lnw - 2.0 * PI * a / h).exp())
        })
        .fold(0.0, f64::max)
}

/// The step at which every singularity's error term `C e^{−2πa/h}` is below `e^{−LN_TARGET}`.
pub(super) fn planned_step(sing: &[(f64, f64)]) -> f64 {
    sing.iter()
        .map(|(a, lnw)| {
            let den = LN_TARGET + lnw;
            if den > 0.0 {
                2.0 * PI * a / den
            } else {
                f64::INFINITY
            }
        })
        .fold(H_COARSE, f64::min)
}
