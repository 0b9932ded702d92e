//! Points of the steepest-descent path: `φ` and its derivatives, the roots of `φ(s) = −w²` by
//! Halley's iteration, path following with Hermite predictors, and the accumulation of the
//! integrands at a node.

use super::complex::{clog1p, ArgProduct, Cx};
use super::problem::{Contour, Node};
use crate::error::{Error, Result};

/// Halley's step is accepted when `|δ|·κ ≤ HALLEY_ACCEPT` (κ: the relative sensitivity of `φ'`,
/// `φ''` and the `r_j` to a shift of `s`): the cubically converged point is then exact to
/// `~(|δ|κ)³ ≤ 1e-18` relative.
const HALLEY_ACCEPT: f64 = 1e-6;

impl Contour {
    /// `φ(s) = s − ½ Σ m_j log(1 + s/λ_j)` for `Im s > 0`, `φ'` and `φ''`, and
    /// `r_j = 1/(λ_j + s)` into `r`; also returns `max |r_j|` and `Σ m_j |r_j|²` (both within
    /// √2), which bound the relative changes of `r_j` and `φ'` under a shift of `s`.
    ///
    /// One logarithm: the sum of the logarithms is the logarithm of the product
    /// `P = Π (1 + s/λ_j)^{m_j}`, whose argument is tracked through the factors (each factor has
    /// argument in `(0, π)`, so the running product crosses the negative real axis exactly when
    /// its imaginary part turns from `≥ 0` to `< 0`). Near the saddle (`|P − 1| ≤ ½`, no
    /// crossing) `log1p(P − 1)` of the separately accumulated `P − 1` is used instead (relative
    /// accuracy for small `s`). `φ'(s) = 1 − ½ Σ m_j r_j` is evaluated as
    /// `(1 − ½ Σ m_j/λ_j) + (s/2) Σ m_j r_j/λ_j` (no cancellation near the saddle).
    pub(super) fn eval(&self, s: Cx, r: &mut [Cx]) -> ([Cx; 3], f64, f64) {
        let zero = Cx::new(0.0, 0.0);
        // Derivatives: r = 1/(λ + s) = (1/λ)·conj(f)/|f|² with f = 1 + s/λ.
        let (mut q, mut r2) = (zero, zero);
        let (mut sum2, mut rmax) = (0.0f64, 0.0f64);
        for (rj, ((&il, &m), &ml)) in r
            .iter_mut()
            .zip(self.inv_lam.iter().zip(&self.mult).zip(&self.mult_il))
        {
            let f = Cx::new(1.0 + s.re * il, s.im * il);
            let k = il / (f.re * f.re + f.im * f.im);
            let x = Cx::new(f.re * k, -f.im * k);
            *rj = x;
            q = q + x.scale(ml);
            r2 = r2 + (x * x).scale(m);
            sum2 += ml * k;
            rmax = rmax.max(x.norm1());
        }
        // The logarithm: tied groups (m_j ≥ 2) each by `m_j log1p(s/λ_j)`; the product over
        // the others, in two interleaved chains. For |s| ≤ 0.2: |P − 1| ≤ e^{2|s|} − 1 < ½ (as
        // ½ Σ m_j/λ_j ≈ 1) and the argument, at most 2|s|, is principal.
        let mut log = zero;
        if self.tied {
            for (&il, &m) in self.inv_lam.iter().zip(&self.mult) {
                if m > 1.0 {
                    log = log + clog1p(s.scale(il)).scale(m);
                }
            }
        }
        let pairs = self.single_il.chunks_exact(2);
        let rest = pairs.remainder();
        log = log
            + if s.norm1() <= 0.2 {
                // P − 1, accumulated as (1 + v)(1 + u) − 1 = v + u + vu.
                let (mut va, mut vb) = (zero, zero);
                for pair in pairs {
                    let (ua, ub) = (s.scale(pair[0]), s.scale(pair[1]));
                    va = va + ua + va * ua;
                    vb = vb + ub + vb * ub;
                }
                for &il in rest {
                    let u = s.scale(il);
                    va = va + u + va * u;
                }
                let v = va + vb + va * vb;
                Cx::new(
                    0.5 * (v.re * (2.0 + v.re) + v.im * v.im).ln_1p(),
                    v.im.atan2(1.0 + v.re),
                )
            } else {
                let (mut pa, mut pb) = (ArgProduct::ONE, ArgProduct::ONE);
                for pair in pairs {
                    pa.mul(Cx::new(1.0 + s.re * pair[0], s.im * pair[0]));
                    pb.mul(Cx::new(1.0 + s.re * pair[1], s.im * pair[1]));
                }
                for &il in rest {
                    pa.mul(Cx::new(1.0 + s.re * il, s.im * il));
                }
                pa.merge(pb).log()
            };
        let phi = s - log.scale(0.5);
        let dphi = Cx::new(self.om, 0.0) + (s * q).scale(0.5);
        ([phi, dphi, r2.scale(0.5)], rmax, sum2)
    }

    /// Halley's method for `φ(s) = −w²` in the open upper half plane, where the root is unique.
    /// Returns the root and `(φ', φ'', φ''')` there, with `r` holding `1/(λ_j + s)`.
    pub(super) fn solve(&self, w: f64, start: Cx, r: &mut [Cx]) -> Option<(Cx, [Cx; 3])> {
        let target = -w * w;
        let mut s = start;
        for _ in 0..50 {
            let (d, rmax, sum2) = self.eval(s, r);
            let id = d[1].recip();
            let newton = (d[0] - Cx::new(target, 0.0)) * id;
            // Halley's correction (cubic convergence) where it is small.
            let corr = (newton * d[2] * id).scale(0.5);
            let mut delta = if corr.norm1() <= 0.5 {
                newton * (Cx::new(1.0, 0.0) - corr).recip()
            } else {
                newton
            };
            if !delta.is_finite() {
                return None;
            }
            let size = delta.norm1();
            let inv = id.norm1();
            // |φ'''| ≤ Σ m|r|³ ≤ max|r| Σ m|r|².
            let kappa = (d[2].norm1() * inv)
                .max((rmax * sum2 * inv).sqrt())
                .max(rmax);
            if size * kappa <= HALLEY_ACCEPT && s.im - delta.im > 0.0 {
                // Converged: the last step's error is O(κ²δ³). r_j = 1/(λ_j + s), φ', φ'' and
                // φ''' at the new point.
                let s1 = s - delta;
                let zero = Cx::new(0.0, 0.0);
                let (mut q, mut r2, mut r3) = (zero, zero, zero);
                for ((rj, &ml), (&il, &m)) in r
                    .iter_mut()
                    .zip(&self.mult_il)
                    .zip(self.inv_lam.iter().zip(&self.mult))
                {
                    let f = Cx::new(1.0 + s1.re * il, s1.im * il);
                    let k = il / (f.re * f.re + f.im * f.im);
                    let x = Cx::new(f.re * k, -f.im * k);
                    *rj = x;
                    q = q + x.scale(ml);
                    let x2 = (x * x).scale(m);
                    r2 = r2 + x2;
                    r3 = r3 + x2 * x;
                }
                let dphi = Cx::new(self.om, 0.0) + (s1 * q).scale(0.5);
                return Some((s1, [dphi, r2.scale(0.5), r3.scale(-1.0)]));
            }
            let limit = 0.5 * (1.0 + s.norm1());
            if size > limit {
                delta = delta.scale(limit / size);
            }
            s = s - delta;
            if s.im <= 0.0 {
                // The root is unique in the upper half plane and φ(s̄) = conj φ(s): reflect.
                s.im = if s.im < 0.0 {
                    -s.im
                } else {
                    1e-3 * (1.0 + s.abs())
                };
            }
        }
        None
    }

    /// The path's derivatives at a solved point from `φ'(s) s' = −2w` and its derivatives
    /// (`d = (φ', φ'', φ''')` at `s`).
    pub(super) fn node(&self, w: f64, s: Cx, d: &[Cx; 3]) -> Result<Node> {
        let ip = d[0].recip();
        let ds = ip.scale(-2.0 * w);
        let dds = (Cx::new(-2.0, 0.0) - d[1] * ds * ds) * ip;
        let d3s = Cx::new(0.0, 0.0) - (d[2] * ds * ds * ds + (d[1] * ds * dds).scale(3.0)) * ip;
        if !(ds.is_finite() && dds.is_finite() && d3s.is_finite()) || ds.im <= 0.0 {
            return Err(Error::Numerical(format!(
                "steepest-descent path: bad tangent at w = {w}, s = ({}, {})",
                s.re, s.im
            )));
        }
        Ok(Node { w, s, ds, dds, d3s })
    }

    /// The saddle point `s = 0` at `w = 0` from the series `s = αw + βw² + γw³`:
    /// `α = i√(2/a)`, `β = b/(3a²)`, `γ = −(aβ²/2 + bα²β/2 + φ''''(0)α⁴/24)/(aα)`.
    pub(super) fn origin(&self) -> Node {
        let (a, b) = (self.a, self.b);
        let alpha = Cx::new(0.0, (2.0 / a).sqrt());
        let beta = b / (3.0 * a * a);
        // α² = −2/a, α⁴ = 4/a².
        let num = 0.5 * a * beta * beta - b * beta / a + self.c4 / (6.0 * a * a);
        let gamma = Cx::new(-num, 0.0) * (alpha.scale(a)).recip();
        Node {
            w: 0.0,
            s: Cx::new(0.0, 0.0),
            ds: alpha,
            dds: Cx::new(2.0 * beta, 0.0),
            d3s: gamma.scale(6.0),
        }
    }

    /// Follows the path from `from` to `w1`: Taylor predictor + Halley, halving on failure.
    pub(super) fn march(&self, from: &Node, w1: f64, depth: u32, r: &mut [Cx]) -> Result<Node> {
        let h = w1 - from.w;
        let pred = from.s
            + from.ds.scale(h)
            + from.dds.scale(0.5 * h * h)
            + from.d3s.scale(h * h * h / 6.0);
        if let Some((s, d)) = self.solve(w1, pred, r) {
            return self.node(w1, s, &d);
        }
        if depth == 0 {
            return Err(Error::NotConverged(format!(
                "steepest-descent path: Halley iteration failed near w = {w1}"
            )));
        }
        let mid = self.march(from, from.w + 0.5 * h, depth - 1, r)?;
        self.march(&mid, w1, depth - 1, r)
    }

    /// Adds `weight · e^{−w²} ·` the integrands at `node` to `sums` (`r_j = 1/(λ_j + s)` given,
    /// `δ_j = ½(r_j − 1/λ_j) = −½ s r_j/λ_j`, computed without cancellation):
    /// `[0, G)`: `½ Im(s' r_j)` (ω); with `hess` also `[G, 2G)`: `Im(s' δ_j)`;
    /// `[2G, 3G)`: `¼ Im(s' r_j²)` (`E[x⁴]/3`); `[3G, …)`: `Im(s' δ_j δ_k)`, `j ≤ k`, packed
    /// row by row.
    pub(super) fn accumulate(
        &self,
        node: &Node,
        weight: f64,
        r: &[Cx],
        dl: &mut [Cx],
        sums: &mut [f64],
        hess: bool,
    ) {
        let g = self.lam.len();
        let t = node.ds.scale(weight * (-node.w * node.w).exp());
        for (sj, &rj) in sums.iter_mut().zip(r.iter()) {
            *sj += 0.5 * (t.re * rj.im + t.im * rj.re);
        }
        if hess {
            let half_s = node.s.scale(-0.5);
            for ((dj, &rj), &il) in dl.iter_mut().zip(r.iter()).zip(&self.inv_lam) {
                *dj = (half_s * rj).scale(il);
            }
            for j in 0..g {
                let u = t * dl[j];
                sums[g + j] += u.im;
                sums[2 * g + j] += 0.25 * (t * r[j] * r[j]).im;
            }
            let mut idx = 3 * g;
            for j in 0..g {
                let u = t * dl[j];
                for dk in &dl[j..] {
                    sums[idx] += u.re * dk.im + u.im * dk.re;
                    idx += 1;
                }
            }
        }
    }
}
