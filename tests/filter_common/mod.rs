//! The evaluation scenarios of JAIF Sec. 7 with the library (shared by `tests/filter.rs`,
//! `tests/filter_alloc.rs` and `tests/deterministic.rs`): simulation of the truth and the
//! measurements with the library's exact sampler, the Bingham filter, and the Kalman filter adapted
//! as in JAIF Sec. 7. The scenarios themselves and the simulation loop are in
//! `testkit::scenarios` (also used by `benches/filter.rs`).
//!
//! The noise draws are the same as those of `examples/c/*_tracking.c`: per Monte Carlo run `r`,
//! `bingham_sample(d, Mw, Zw, seed_w(r), STEPS, …)` and `bingham_sample(d, Mv, Zv, seed_v(r), …)`
//! (`Bingham::sample` with `StdRng::seed_from_u64`, which is what `bingham_sample` does).
#![allow(dead_code)]

use bingham::filter::BinghamFilter;
use bingham::quaternion::compose;
use bingham::Bingham;
use nalgebra::{DMatrix, DVector};
use rand::rngs::StdRng;
use rand::SeedableRng;
use testkit::scenarios::{simulate_with, Scenario};

/// `n` samples of `Bingham(m, z)` as `bingham_sample(d, m, z, seed, n, …)` draws them.
pub fn draw(d: usize, m: &[f64], z: &[f64], seed: u64, n: usize) -> Vec<Vec<f64>> {
    let b = Bingham::new(
        DMatrix::from_row_slice(d, d, m),
        DVector::from_column_slice(z),
    )
    .unwrap();
    let mut rng = StdRng::seed_from_u64(seed);
    b.sample(&mut rng, n)
        .into_iter()
        .map(|v| v.as_slice().to_vec())
        .collect()
}

/// One run: the true states `x_1..x_STEPS` and measurements `z_k = x_k ⊕ v_k`, where
/// `x_k = x_{k−1} ⊕ w_{k−1}`.
pub fn simulate(sc: &Scenario, run: u64) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    simulate_with(
        sc,
        run,
        |m, z, seed, n| draw(sc.d, m, z, seed, n),
        |x, y| compose(x, y).unwrap(),
    )
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The axial angular error `min(∠(a, b), π − ∠(a, b))` (JAIF eq. 67–68).
pub fn axial_error(a: &[f64], b: &[f64]) -> f64 {
    // 2 atan2(|â − s b̂|, |â + s b̂|) with s = sign(a·b): accurate for tiny angles, where
    // acos(a·b) has a floor of √ε ≈ 1.5e-8.
    let (na, nb) = (dot(a, a).sqrt(), dot(b, b).sqrt());
    let s = if dot(a, b) < 0.0 { -1.0 } else { 1.0 };
    let (mut diff, mut sum) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        let (u, v) = (x / na, s * y / nb);
        diff += (u - v) * (u - v);
        sum += (u + v) * (u + v);
    }
    2.0 * diff.sqrt().atan2(sum.sqrt())
}

pub fn rmse(errors: &[f64]) -> f64 {
    (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt()
}

/// Runs the Bingham filter on one simulated run; returns the errors per step.
pub fn run_bingham(sc: &Scenario, truth: &[Vec<f64>], meas: &[Vec<f64>]) -> Vec<f64> {
    let mut f = BinghamFilter::new(sc.d, &sc.m0, &sc.z0).unwrap();
    let mut errors = Vec::with_capacity(truth.len());
    for (x, z) in truth.iter().zip(meas) {
        f.predict(&sc.mw, &sc.zw).unwrap();
        f.update(z, &sc.mv, &sc.zv).unwrap();
        errors.push(axial_error(x, &f.mode()));
    }
    errors
}

/// The Gaussian fitted to one mode of a Bingham distribution (JAIF eq. 57; for d = 4
/// "analogously"): `C = E[(s x − μ)(s x − μ)ᵀ]` with `μ` the mode and `s = sign(μᵀx)`; returns
/// (μ, C row-major). As in `examples/c/*_tracking.c`: for d = 2 by the midpoint rule with 20000
/// nodes over the half circle around the mode (eq. 57), for d = 4 by Monte Carlo with `n`
/// samples drawn with `seed`.
pub fn gaussian_fit(d: usize, m: &[f64], z: &[f64], n: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let b = Bingham::new(
        DMatrix::from_row_slice(d, d, m),
        DVector::from_column_slice(z),
    )
    .unwrap();
    let mu = b.mode().as_slice().to_vec();
    let mut c = vec![0.0; d * d];
    if d == 2 {
        let nodes = 20000;
        let alpha = mu[1].atan2(mu[0]);
        let mut mass = 0.0;
        for i in 0..nodes {
            let phi = alpha - std::f64::consts::FRAC_PI_2
                + std::f64::consts::PI * (i as f64 + 0.5) / nodes as f64;
            let x = [phi.cos(), phi.sin()];
            let p = b.pdf(&x).unwrap();
            let e = [x[0] - mu[0], x[1] - mu[1]];
            mass += p;
            c[0] += p * e[0] * e[0];
            c[1] += p * e[0] * e[1];
            c[3] += p * e[1] * e[1];
        }
        c[0] /= mass;
        c[1] /= mass;
        c[3] /= mass;
        c[2] = c[1];
        return (mu, c);
    }
    for x in draw(d, m, z, seed, n) {
        let s = if dot(&mu, &x) < 0.0 { -1.0 } else { 1.0 };
        let e: Vec<f64> = (0..d).map(|i| s * x[i] - mu[i]).collect();
        for i in 0..d {
            for j in 0..d {
                c[i * d + j] += e[i] * e[j] / n as f64;
            }
        }
    }
    (mu, c)
}

/// The Kalman filter adapted as in JAIF Sec. 7: state vector in R^d with identity system and
/// measurement models, noise covariances from [`gaussian_fit`], the measurement mirrored
/// (`ẑ ← −ẑ`) when it is more than 90° from the prediction, the estimate normalized after each
/// update.
pub struct Kalman {
    pub d: usize,
    pub x: DVector<f64>,
    pub p: DMatrix<f64>,
    pub q: DMatrix<f64>,
    pub r: DMatrix<f64>,
    /// The noise modes (the identity in the scenarios): `x ← x ⊕ μ_w`, `ẑ ≈ x ⊕ μ_v`.
    pub mu_w: Vec<f64>,
}

impl Kalman {
    pub fn new(sc: &Scenario, n: usize) -> Kalman {
        let d = sc.d;
        let (x0, p0) = gaussian_fit(d, &sc.m0, &sc.z0, n, 7);
        let (mu_w, q) = gaussian_fit(d, &sc.mw, &sc.zw, n, 8);
        let (_, r) = gaussian_fit(d, &sc.mv, &sc.zv, n, 9);
        Kalman {
            d,
            x: DVector::from_vec(x0),
            p: DMatrix::from_row_slice(d, d, &p0),
            q: DMatrix::from_row_slice(d, d, &q),
            r: DMatrix::from_row_slice(d, d, &r),
            mu_w,
        }
    }

    pub fn predict(&mut self) {
        self.x = DVector::from_vec(compose(self.x.as_slice(), &self.mu_w).unwrap());
        self.p = &self.p + &self.q;
    }

    pub fn update(&mut self, z: &[f64]) {
        let mut zv = DVector::from_column_slice(z);
        if zv.dot(&self.x) < 0.0 {
            zv = -zv;
        }
        let s = &self.p + &self.r;
        let k = &self.p * s.try_inverse().unwrap();
        self.x = &self.x + &k * (zv - &self.x);
        self.p = (DMatrix::identity(self.d, self.d) - &k) * &self.p;
        self.p = (&self.p + self.p.transpose()) * 0.5;
        let n = self.x.norm();
        self.x /= n;
    }
}

/// Runs a fresh copy of `kf` on one simulated run; returns the errors per step.
pub fn run_kalman(kf: &Kalman, truth: &[Vec<f64>], meas: &[Vec<f64>]) -> Vec<f64> {
    let mut k = Kalman {
        d: kf.d,
        x: kf.x.clone(),
        p: kf.p.clone(),
        q: kf.q.clone(),
        r: kf.r.clone(),
        mu_w: kf.mu_w.clone(),
    };
    let mut errors = Vec::with_capacity(truth.len());
    for (x, z) in truth.iter().zip(meas) {
        k.predict();
        k.update(z);
        errors.push(axial_error(x, k.x.as_slice()));
    }
    errors
}
