//! The second-order EKF of `tests/glover_spin.rs` ("EKF-2" there): LaViola's (2003) quaternion
//! EKF, discrete time, as Glover & Kaelbling adapted it. State `(x, v)` in R⁸ (orientation and
//! spin), `x ← v x`, `v ← v` with Gaussian noise on `v`, measurement `h(x) = x/|x|`; the noise
//! covariances are matched to the test's Bingham noises by sampling (`EkfNoise`), and a dark
//! frame is handled in one of three ways (`Dark`). The method and its variants are described in
//! the documentation of `tests/glover_spin.rs`.
//!
//! Not a submodule of `glover_common` and not shared: `tests/glover_spin.rs` includes this file
//! with `#[path]`, and it uses that test's observation model (`Obs`, `FLIP`, `Y_DARK`), noise
//! concentrations and seed from the including crate's root.

use crate::ball::{Obs, FLIP, IDENTITY, SEED, Y_DARK, Z_DARK, Z_DETECT, Z_PROCESS, Z_SPIN_PRIOR};
use crate::glover_common::{dot, lmat, m_with_mode, mul, normalized, rmat, to_q, I4, Q};
use bingham::Bingham;
use nalgebra::{Matrix4, SMatrix, SVector, Vector4};
use rand::rngs::StdRng;
use rand::SeedableRng;

type M8 = SMatrix<f64, 8, 8>;
type V8 = SVector<f64, 8>;
type M48 = SMatrix<f64, 4, 8>;

/// Gaussian noise covariances (in R⁴, about the mean of the hemisphere `q₀ ≥ 0`) matched to the
/// Bingham noises by sampling, and the spin prior's.
pub struct EkfNoise {
    process: Matrix4<f64>,
    detect: Matrix4<f64>,
    dark: Matrix4<f64>,
    dark_gaussian: Matrix4<f64>,
    spin_prior: Matrix4<f64>,
    spin_prior_mean: Q,
}

/// Mean and covariance of samples of `b` flipped to the hemisphere `q₀ ≥ 0`.
fn hemisphere_moments(b: &Bingham, rng: &mut StdRng, n: usize) -> (Vector4<f64>, Matrix4<f64>) {
    let xs: Vec<Vector4<f64>> = b
        .sample(rng, n)
        .iter()
        .map(|s| {
            let v = Vector4::new(s[0], s[1], s[2], s[3]);
            if v[0] < 0.0 {
                -v
            } else {
                v
            }
        })
        .collect();
    let mean = xs.iter().fold(Vector4::zeros(), |a, x| a + x) / n as f64;
    let cov = xs.iter().fold(Matrix4::zeros(), |a, x| {
        a + (x - mean) * (x - mean).transpose()
    }) / (n - 1) as f64;
    (mean, cov)
}

impl EkfNoise {
    pub fn new() -> EkfNoise {
        let mut rng = StdRng::seed_from_u64(SEED + 77);
        let b = |z: &[f64; 4]| Bingham::from_row_major(4, &I4, z).unwrap();
        let (_, process) = hemisphere_moments(&b(&Z_PROCESS), &mut rng, 20_000);
        let (_, detect) = hemisphere_moments(&b(&Z_DETECT), &mut rng, 20_000);
        let prior = Bingham::from_row_major(4, &m_with_mode(&IDENTITY), &Z_SPIN_PRIOR).unwrap();
        let (mean, spin_prior) = hemisphere_moments(&prior, &mut rng, 20_000);
        // the dark observation: the tilt variance of Bingham(0, −3.6, −3.6, 0) about the two image
        // axes; along the circle (k) the nearest point is used, so no information (variance 1)
        let s = b(&Z_DARK).second_moment().unwrap();
        let dark = Matrix4::from_diagonal(&Vector4::new(1e-4, s[(1, 1)], s[(2, 2)], 1.0));
        let (_, dark_gaussian) = hemisphere_moments(&b(&Z_DARK), &mut rng, 20_000);
        EkfNoise {
            process,
            detect,
            dark,
            dark_gaussian,
            spin_prior,
            spin_prior_mean: normalized(&to_q(&mean)),
        }
    }
}

/// What the EKF makes of a dark frame.
#[derive(Clone, Copy, PartialEq)]
pub enum Dark {
    /// the nearest point of the dark observation's circle, with the tilt variance
    Nearest,
    /// skipped
    Skip,
    /// `y_dark` with the Gaussian matched to `Bingham(0, −3.6, −3.6, 0)` (sampled)
    Gaussian,
}

pub struct Ekf2 {
    s: V8,
    p: M8,
    on: bool,
    dark: Dark,
    /// of a detection's interpretations the likelier (else the one reported)
    choose: bool,
}

impl Ekf2 {
    pub fn new(dark: Dark, choose: bool, n: &EkfNoise) -> Ekf2 {
        let mut p = M8::zeros();
        p.fixed_view_mut::<4, 4>(4, 4).copy_from(&n.spin_prior);
        let mut s = V8::zeros();
        s[0] = 1.0;
        s[4] = 1.0;
        Ekf2 {
            s,
            p,
            on: false,
            dark,
            choose,
        }
    }

    fn x(&self) -> Q {
        [self.s[0], self.s[1], self.s[2], self.s[3]]
    }

    pub fn v(&self) -> Q {
        [self.s[4], self.s[5], self.s[6], self.s[7]]
    }

    fn set(&mut self, x: &Q, v: &Q) {
        self.s.fixed_rows_mut::<4>(0).copy_from_slice(x);
        self.s.fixed_rows_mut::<4>(4).copy_from_slice(v);
    }

    fn renormalize(&mut self) {
        self.set(&normalized(&self.x()), &normalized(&self.v()));
    }

    fn predict(&mut self, n: &EkfNoise) {
        let (x, v) = (self.x(), self.v());
        let xn = mul(&v, &x);
        let mut f = M8::identity();
        f.fixed_view_mut::<4, 4>(0, 0).copy_from(&lmat(&v));
        f.fixed_view_mut::<4, 4>(0, 4).copy_from(&rmat(&x));
        let mut q = M8::identity() * 1e-8;
        let rv = rmat(&v);
        q.fixed_view_mut::<4, 4>(4, 4)
            .copy_from(&(rv * n.process * rv.transpose()));
        self.p = f * self.p * f.transpose() + q;
        self.set(&normalized(&xn), &normalized(&v));
    }

    /// The innovation, its covariance, the measurement Jacobian and noise for observing
    /// `y` (sign-aligned with the state) with the noise covariance `sigma` (noise frame).
    fn innovation(
        &self,
        y: &Q,
        sigma: &Matrix4<f64>,
    ) -> (Vector4<f64>, Matrix4<f64>, M48, Matrix4<f64>) {
        let x = self.x();
        let xv = Vector4::from_column_slice(&x);
        let sign = if dot(y, &x) < 0.0 { -1.0 } else { 1.0 };
        let r = Vector4::from_column_slice(y) * sign - xv;
        let mut h = M48::zeros();
        h.fixed_view_mut::<4, 4>(0, 0)
            .copy_from(&(Matrix4::identity() - xv * xv.transpose()));
        let rx = rmat(&x);
        let noise = rx * sigma * rx.transpose();
        let s = h * self.p * h.transpose() + noise;
        (r, s, h, noise)
    }

    fn mahalanobis(&self, y: &Q, sigma: &Matrix4<f64>) -> f64 {
        let (r, s, _, _) = self.innovation(y, sigma);
        let si = s.try_inverse().expect("innovation covariance");
        (r.transpose() * si * r)[(0, 0)]
    }

    fn update(&mut self, y: &Q, sigma: &Matrix4<f64>) {
        let (r, s, h, noise) = self.innovation(y, sigma);
        let si = s.try_inverse().expect("innovation covariance");
        let k = self.p * h.transpose() * si;
        let ikh = M8::identity() - k * h;
        self.s += k * r;
        self.p = ikh * self.p * ikh.transpose() + k * noise * k.transpose();
        self.p = 0.5 * (self.p + self.p.transpose());
        self.renormalize();
    }

    pub fn frame(&mut self, obs: &Obs, n: &EkfNoise) {
        if self.on {
            self.predict(n);
        }
        match obs {
            Obs::Logo(y) if !self.on => {
                let r = rmat(y);
                self.p
                    .fixed_view_mut::<4, 4>(0, 0)
                    .copy_from(&(r * n.detect * r.transpose()));
                self.set(y, &n.spin_prior_mean);
                self.on = true;
            }
            Obs::Logo(y) => {
                let y2 = mul(y, &FLIP);
                let pick = if !self.choose
                    || self.mahalanobis(y, &n.detect) <= self.mahalanobis(&y2, &n.detect)
                {
                    *y
                } else {
                    y2
                };
                self.update(&pick, &n.detect);
            }
            Obs::Dark if self.on && self.dark == Dark::Gaussian => {
                self.update(&Y_DARK, &n.dark_gaussian);
            }
            Obs::Dark if self.on && self.dark == Dark::Nearest => {
                // the nearest point of the circle {R_z(α) ∘ y_dark}
                let x = self.x();
                let a = Y_DARK;
                let b = mul(&[0.0, 0.0, 0.0, 1.0], &Y_DARK);
                let (ca, cb) = (dot(&a, &x), dot(&b, &x));
                let p = normalized(&[
                    ca * a[0] + cb * b[0],
                    ca * a[1] + cb * b[1],
                    ca * a[2] + cb * b[2],
                    ca * a[3] + cb * b[3],
                ]);
                self.update(&p, &n.dark);
            }
            Obs::Dark => {}
        }
    }

    /// The type whose mean spin is nearest in the Mahalanobis distance of the spin's Gaussian
    /// (in the tangent space at the estimate; the type's sign aligned).
    pub fn classify(&self, means: &[Q]) -> usize {
        let v = self.v();
        let vv = Vector4::from_column_slice(&v);
        let proj = Matrix4::identity() - vv * vv.transpose();
        let pv = self.p.fixed_view::<4, 4>(4, 4).into_owned();
        let pt = proj * pv * proj + vv * vv.transpose();
        let pi = pt.try_inverse().expect("spin covariance");
        let mut best = (f64::INFINITY, 0);
        for (k, m) in means.iter().enumerate() {
            let sign = if dot(m, &v) < 0.0 { -1.0 } else { 1.0 };
            let r = proj * (Vector4::from_column_slice(m) * sign - vv);
            let d = (r.transpose() * pi * r)[(0, 0)];
            if d < best.0 {
                best = (d, k);
            }
        }
        best.1
    }
}
