//! [`Bingham::sample`]: exact rejection sampling (Kent, Ganeiber & Mardia 2013) with an angular
//! central Gaussian envelope; needs no normalization constant.
//!
//! With `A = −M Z Mᵀ` (eigenvalues `λ_i = −z_i ≥ 0`) the target is `f*(x) = exp(−xᵀAx)`, the
//! envelope `g*(x) = (xᵀΩx)^{−d/2}` with `Ω = I + 2A/b`, where `b` solves
//! `Σ 1/(b + 2λ_i) = 1`; `f* ≤ M* g*` with `M* = exp(−(d−b)/2) (d/b)^{d/2}`.

use nalgebra::DVector;
use rand::Rng;

use crate::distribution::Bingham;

impl Bingham {
    /// Draws `n` independent samples (unit vectors) by exact rejection sampling from an angular
    /// central Gaussian envelope (Kent, Ganeiber & Mardia 2013). Deterministic for a seeded `rng`.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R, n: usize) -> Vec<DVector<f64>> {
        Sampler::new(self).sample(rng, n)
    }
}

/// A prepared sampler for one distribution.
struct Sampler<'a> {
    dist: &'a Bingham,
    lambda: Vec<f64>,
    /// standard deviations of the envelope's Gaussian in the eigenbasis: (1 + 2λ/b)^{−1/2}
    sd: Vec<f64>,
    b: f64,
    log_m: f64,
}

impl<'a> Sampler<'a> {
    fn new(dist: &'a Bingham) -> Self {
        let d = dist.dim();
        // λ is capped at 1e300: beyond about 9e307, 2λ/b overflows (b ≥ 1), the envelope's sd
        // becomes 0 and (1 + 2λ/b)·c² = ∞·0 = NaN fails every acceptance test, so the loop never
        // ended. The cap changes nothing visible: a spread of 1/√(2λ) ≤ 1e-150 around the mode
        // rounds to the mode itself.
        let lambda: Vec<f64> = dist.z().iter().map(|z| (-z).clamp(0.0, 1e300)).collect();
        // Solve h(b) = Σ 1/(b + 2λ_i) − 1 = 0 on (0, d]: h is decreasing; h(d) ≤ 0, h(0+) = +∞
        // (λ_d = 0). Bisection then Newton polish, in log b for robustness.
        let h = |b: f64| lambda.iter().map(|l| 1.0 / (b + 2.0 * l)).sum::<f64>() - 1.0;
        let (mut lo, mut hi) = (f64::MIN_POSITIVE, d as f64);
        for _ in 0..200 {
            let mid = (lo * hi).sqrt().max(0.5 * (lo + hi) * 1e-300);
            let mid = if mid <= lo || mid >= hi {
                0.5 * (lo + hi)
            } else {
                mid
            };
            if h(mid) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi - lo <= 1e-15 * hi {
                break;
            }
        }
        let b = 0.5 * (lo + hi);
        let dd = d as f64;
        let log_m = -(dd - b) / 2.0 + 0.5 * dd * (dd / b).ln();
        let sd = lambda
            .iter()
            .map(|l| (1.0 + 2.0 * l / b).sqrt().recip())
            .collect();
        Sampler {
            dist,
            lambda,
            sd,
            b,
            log_m,
        }
    }

    /// One sample in the eigen-coordinates `c = Mᵀx`.
    fn draw_coords<R: Rng + ?Sized>(&self, rng: &mut R, c: &mut [f64]) {
        loop {
            let mut norm2 = 0.0;
            for (i, ci) in c.iter_mut().enumerate() {
                *ci = standard_normal(rng) * self.sd[i];
                norm2 += *ci * *ci;
            }
            if norm2 == 0.0 || !norm2.is_finite() {
                continue;
            }
            let inv = norm2.sqrt().recip();
            let mut xax = 0.0;
            let mut xox = 0.0;
            for (i, ci) in c.iter_mut().enumerate() {
                *ci *= inv;
                let c2 = *ci * *ci;
                xax += self.lambda[i] * c2;
                xox += (1.0 + 2.0 * self.lambda[i] / self.b) * c2;
            }
            let log_ratio = -xax + 0.5 * c.len() as f64 * xox.ln() - self.log_m;
            let u: f64 = rng.gen::<f64>();
            if u.ln() < log_ratio {
                return;
            }
        }
    }

    fn sample<R: Rng + ?Sized>(&self, rng: &mut R, n: usize) -> Vec<DVector<f64>> {
        let d = self.dist.dim();
        let mut c = vec![0.0; d];
        (0..n)
            .map(|_| {
                self.draw_coords(rng, &mut c);
                self.dist.m() * DVector::from_column_slice(&c)
            })
            .collect()
    }
}

/// A standard normal variate by the Box–Muller transform (one of the pair is used).
fn standard_normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    let u1: f64 = 1.0 - rng.gen::<f64>(); // (0, 1]
    let u2: f64 = rng.gen::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}
