//! The smoother's product step against importance sampling, and its result on two threads
//! against one.

use nalgebra::{Matrix3, Vector3};

use super::fusion::fuse;
use super::handoff::handoff_index;
use super::passes::CHUNK;
use super::threads::{run, PARALLEL_PRODUCT};
use super::types::{Fusion, SmoothInput, SmoothOptions};
use crate::ahrs::{AhrsParams, LATENCY_ESTIMATE};
use crate::quaternion::q4;

/// A small deterministic generator (SplitMix64) and normal deviates (Box–Muller).
struct Rng(u64);
impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let u = self.uniform().max(1e-300);
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * self.uniform()).cos()
    }
}

/// The product step against importance sampling: orientations drawn from the forward
/// density (`exp(φ/2) ⊗ q_f`, `φ ~ N(0, C_f)` in the world frame), weighted by the backward
/// density (`exp(−½ δᵀ C_b⁻¹ δ)`, `δ` the rotation vector from `q_b`); the weighted mean
/// rotation vector about `q_f` and its covariance against `fuse`, to three standard errors
/// of the weighted means (the variance's to a relative 5 %).
#[test]
fn the_product_step_matches_importance_sampling() {
    let mut rng = Rng(42);
    let qf = q4::from_rotation_vector(&[0.3, -1.1, 2.0]);
    let cf = Matrix3::new(4e-4, 1e-4, 0.0, 1e-4, 3e-4, -5e-5, 0.0, -5e-5, 9e-4);
    let cb = Matrix3::new(6e-4, -2e-4, 1e-4, -2e-4, 8e-4, 0.0, 1e-4, 0.0, 2e-4);
    let d_true = Vector3::new(0.02, -0.015, 0.03);
    let qb = q4::mul(
        &q4::from_rotation_vector(&[d_true.x, d_true.y, d_true.z]),
        &qf,
    );
    let d = q4::to_rotation_vector(&q4::mul(&qb, &q4::conj(&qf)));
    let (shift, cs) = fuse(&cf, &cb, &Vector3::new(d[0], d[1], d[2])).unwrap();
    let lf = cf.cholesky().unwrap().l();
    let cb_inv = cb.try_inverse().unwrap();
    let n = 400_000;
    let (mut sw, mut sw2) = (0.0, 0.0);
    let mut m1 = Vector3::zeros();
    let mut m2 = Matrix3::zeros();
    let mut samples = Vec::with_capacity(n);
    for _ in 0..n {
        let phi = lf * Vector3::new(rng.normal(), rng.normal(), rng.normal());
        let q = q4::mul(&q4::from_rotation_vector(&[phi.x, phi.y, phi.z]), &qf);
        let e = q4::to_rotation_vector(&q4::mul(&q, &q4::conj(&qb)));
        let e = Vector3::new(e[0], e[1], e[2]);
        let w = (-0.5 * (e.transpose() * cb_inv * e)[0]).exp();
        sw += w;
        sw2 += w * w;
        m1 += w * phi;
        samples.push((w, phi));
    }
    let mean = m1 / sw;
    for (w, phi) in &samples {
        let r = phi - mean;
        m2 += *w * r * r.transpose();
    }
    let cov = m2 / sw;
    // the effective sample size sets the weighted mean's standard error
    let ess = sw * sw / sw2;
    for i in 0..3 {
        let se = (cov[(i, i)] / ess).sqrt();
        assert!(
            (mean[i] - shift[i]).abs() < 3.0 * se,
            "axis {i}: sampled {} vs fused {} (se {se})",
            mean[i],
            shift[i]
        );
        assert!(
            (cov[(i, i)] / cs[(i, i)] - 1.0).abs() < 0.05,
            "axis {i}: sampled variance {} vs fused {}",
            cov[(i, i)],
            cs[(i, i)]
        );
    }
}

/// The passes on two threads give the result of one thread bit for bit (the handoff and
/// the product at each sample are functions of the recording alone), with the bias and the
/// exact product, on a recording long enough for both to be concurrent (the product formed
/// chunk by chunk as the backward pass goes), and on one without a magnetometer (the passes
/// in turn, the product's halves on two threads).
#[test]
fn two_threads_give_the_result_of_one() {
    let mut rng = Rng(7);
    let dt = 0.01;
    let n = 9000; // 90 s: the handoff after 30 s, 60 s concurrent
    let mut gyr = Vec::with_capacity(n);
    let mut acc = Vec::with_capacity(n);
    let mut mag = Vec::with_capacity(n);
    let mut q = [1.0, 0.0, 0.0, 0.0];
    for k in 0..n {
        let t = k as f64 * dt;
        let w = [
            0.5 * (0.7 * t).sin(),
            0.4 * (0.3 * t).cos(),
            0.6 * (0.2 * t).sin(),
        ];
        q = q4::mul(&q, &q4::from_rotation_vector(&w.map(|x| x * dt)));
        let r = q4::to_matrix(&q);
        // the world's gravity reaction (up) and field (north, down) in the sensor frame
        let body = |v: [f64; 3]| -> [f64; 3] {
            std::array::from_fn(|i| r[0][i] * v[0] + r[1][i] * v[1] + r[2][i] * v[2])
        };
        let a = body([0.0, 0.0, 9.81]);
        let m = body([0.0, 20.0, -40.0]);
        gyr.push(std::array::from_fn(|i| w[i] + 0.01 + 0.002 * rng.normal()));
        acc.push(std::array::from_fn(|i| a[i] + 0.05 * rng.normal()));
        mag.push(std::array::from_fn(|i| m[i] + 0.3 * rng.normal()));
    }
    let input = SmoothInput {
        time: None,
        gyr: &gyr,
        acc: &acc,
        mag: Some(&mag),
    };
    // a fixed latency: the handoff at HANDOFF_TIME; the estimate: when it exists
    for (latency, fusion) in [
        (0.0, Fusion::Tangent),
        (0.0, Fusion::Bingham),
        (LATENCY_ESTIMATE, Fusion::Tangent),
    ] {
        let mut params = AhrsParams::new(dt);
        params.mag_latency = latency;
        let options = SmoothOptions {
            fusion,
            ..SmoothOptions::default()
        };
        let at = handoff_index(n, dt, true);
        assert!(at + 1 < n && at > 0, "{at}");
        assert_threads_agree(&params, &options, &input);
    }
    // without the magnetometer the passes run in turn, and over PARALLEL_PRODUCT samples
    // the product's two halves (of the backward pass's chunks) on two threads
    let long = 3 * n;
    let (gyr2, acc2): (Vec<_>, Vec<_>) = (0..long).map(|k| (gyr[k % n], acc[k % n])).unzip();
    let input = SmoothInput {
        time: None,
        gyr: &gyr2,
        acc: &acc2,
        mag: None,
    };
    let params = AhrsParams::new(dt);
    let options = SmoothOptions::default();
    assert!(long > PARALLEL_PRODUCT + CHUNK);
    assert_threads_agree(&params, &options, &input);
}

/// The smoother with one thread and with two: every smoothed state and bias bit for bit.
fn assert_threads_agree(params: &AhrsParams, options: &SmoothOptions, input: &SmoothInput<'_>) {
    let (f1, b1, k1) = run(params, options, input, true, false).unwrap();
    let (f2, b2, k2) = run(params, options, input, true, true).unwrap();
    let (b1, b2) = (b1.unwrap(), b2.unwrap());
    assert_eq!(k1, k2);
    assert_eq!((f1.len(), b1.len()), (input.gyr.len(), input.gyr.len()));
    for k in 0..input.gyr.len() {
        assert_eq!(f1[k].q, f2[k].q, "sample {k}");
        assert_eq!(f1[k].c, f2[k].c, "sample {k}");
        assert_eq!(b1[k].b, b2[k].b, "sample {k}");
        assert_eq!(b1[k].p, b2[k].p, "sample {k}");
    }
}
