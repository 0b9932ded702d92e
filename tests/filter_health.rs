//! The filter's health readout and likelihood gate (`BinghamFilter::surprise`,
//! `update_gated`): the surprise of measurements drawn from the model follows the χ² law with
//! d − 1 degrees of freedom that its documentation states (sampled states and noises, an
//! independent Monte Carlo of the model), a stream of quaternion fixes given in (x, y, z, w)
//! order is flagged at the documented threshold while the right order is not, and the gate
//! applies exactly `update` or nothing.

use bingham::filter::BinghamFilter;
use bingham::quaternion::compose;
use bingham::{Bingham, Error};
use nalgebra::{DMatrix, DVector};
use rand::rngs::StdRng;
use rand::SeedableRng;

/// χ²₃ and χ²₁ at 0.1 % (the thresholds the documentation quotes).
const CHI2_3_999: f64 = 16.27;
const CHI2_1_999: f64 = 10.83;

fn identity(d: usize) -> Vec<f64> {
    DMatrix::<f64>::identity(d, d).as_slice().to_vec()
}

/// A Bingham with mode `e_0` (the identity rotation) and the given concentrations on the
/// other axes (`M = I`, `z = (0, z1, …)`).
fn about_identity(z: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let d = z.len() + 1;
    let mut zz = vec![0.0];
    zz.extend_from_slice(z);
    (identity(d), zz)
}

fn sample(m: &[f64], z: &[f64], rng: &mut StdRng, n: usize) -> Vec<DVector<f64>> {
    let d = z.len();
    let b = Bingham::new(
        DMatrix::from_row_slice(d, d, m),
        DVector::from_column_slice(z),
    )
    .unwrap();
    b.sample(rng, n)
}

/// The surprise of `n` measurements `y = x ⊕ v` drawn from the model (x from the state, v from
/// the noise), with the state's mode turned to `mode`.
fn model_surprises(
    state_z: &[f64],
    noise_z: &[f64],
    mode: &[f64],
    n: usize,
    seed: u64,
) -> Vec<f64> {
    let d = mode.len();
    let mut rng = StdRng::seed_from_u64(seed);
    let (_, zs) = about_identity(state_z);
    // the state Bingham(L(mode) I, z): columns turned by the mode
    let lm = bingham::quaternion::left_matrix(mode);
    let ms: Vec<f64> = lm.transpose().as_slice().to_vec(); // row-major of L(mode)·I
    let f = BinghamFilter::new(d, &ms, &zs).unwrap();
    let (mv, zv) = about_identity(noise_z);
    let xs = sample(&ms, &zs, &mut rng, n);
    let vs = sample(&mv, &zv, &mut rng, n);
    xs.iter()
        .zip(&vs)
        .map(|(x, v)| {
            let y = compose(x.as_slice(), v.as_slice()).unwrap();
            f.surprise(&y, &mv, &zv).unwrap()
        })
        .collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn frac_above(v: &[f64], t: f64) -> f64 {
    v.iter().filter(|&&s| s > t).count() as f64 / v.len() as f64
}

#[test]
fn the_surprise_of_model_measurements_is_chi_square() {
    let n = 4000;
    let mode = [0.5f64.sqrt(), 0.5, 0.0, 0.5];
    let cases: [(&[f64], &[f64]); 3] = [
        (&[-400.0, -400.0, -400.0], &[-300.0, -300.0, -300.0]),
        // anisotropic state and noise (principal axes not aligned with each other's)
        (&[-2000.0, -300.0, -800.0], &[-200.0, -1500.0, -500.0]),
        (&[-5e4, -5e4, -5e4], &[-1e5, -2e4, -1e5]),
    ];
    for (k, (zs, zv)) in cases.iter().enumerate() {
        let s = model_surprises(zs, zv, &mode, n, 10 + k as u64);
        let (m, tail) = (mean(&s), frac_above(&s, CHI2_3_999));
        println!("d = 4 case {k}: mean {m:.3} (χ²₃: 3), P(s > 16.27) = {tail:.4} (0.001)");
        // the mean of χ²₃ is 3 with a standard error √(6/n) = 0.039
        assert!((m - 3.0).abs() < 0.2, "case {k}: mean {m}");
        assert!(tail < 0.004, "case {k}: tail {tail}");
        assert!(s.iter().all(|&x| x >= 0.0 && x.is_finite()));
    }
    let s = model_surprises(&[-500.0], &[-800.0], &[0.6, 0.8], n, 20);
    let (m, tail) = (mean(&s), frac_above(&s, CHI2_1_999));
    println!("d = 2: mean {m:.3} (χ²₁: 1), P(s > 10.83) = {tail:.4}");
    assert!((m - 1.0).abs() < 0.1, "d = 2 mean {m}");
    assert!(tail < 0.004, "d = 2 tail {tail}");
}

#[test]
fn a_broad_state_makes_nothing_surprising() {
    // uniform about the vertical (z-axis rotations: the heading) and sharp in tilt: a
    // measurement that differs only in heading scores little, one that differs in tilt a lot
    let (m, z) = about_identity(&[-2000.0, -2000.0, 0.0]);
    let f = BinghamFilter::new(4, &m, &z).unwrap();
    let (mv, zv) = about_identity(&[-800.0, -800.0, -800.0]);
    let yaw = [(0.5f64).cos(), 0.0, 0.0, (0.5f64).sin()];
    let tilt = [(0.25f64).cos(), (0.25f64).sin(), 0.0, 0.0];
    let s_yaw = f.surprise(&yaw, &mv, &zv).unwrap();
    let s_tilt = f.surprise(&tilt, &mv, &zv).unwrap();
    println!("yaw 57°: {s_yaw:.3}, tilt 29°: {s_tilt:.1}");
    assert!(s_yaw < 1.0, "{s_yaw}");
    // (0.5 rad)² over the variance 1/1000 + 1/400 rad²: 71
    assert!((s_tilt - 71.0).abs() < 8.0, "{s_tilt}");
}

/// A gyroscope-driven filter with orientation fixes every 10th step, as in a motion-capture or
/// camera fusion: the fixes in the right order stay below the threshold, fixes whose
/// components were read in (x, y, z, w) order are flagged.
#[test]
fn fixes_in_the_wrong_component_order_are_flagged() {
    let mut rng = StdRng::seed_from_u64(7);
    let dt = 0.01;
    let gyro_sd: f64 = 0.01; // rad/s per axis: the process noise
    let fix_sd: f64 = 1f64.to_radians();
    let noise_z = -1.0 / (2.0 * (gyro_sd * gyro_sd * dt) / 4.0 * 2.0);
    let (mw, zw) = about_identity(&[noise_z; 3]);
    let fix_z = -1.0 / (2.0 * fix_sd * fix_sd / 4.0);
    let (mv, zv) = about_identity(&[fix_z; 3]);
    let vs = sample(&mv, &zv, &mut rng, 10_000);
    let ws = sample(&mw, &zw, &mut rng, 10_000);
    let mut flagged = [0usize; 2];
    let mut count = 0usize;
    for (order, flags) in flagged.iter_mut().enumerate() {
        let mut truth = [0.9f64, 0.1, -0.3, 0.3];
        let n = truth.iter().map(|x| x * x).sum::<f64>().sqrt();
        truth.iter_mut().for_each(|x| *x /= n);
        // a wide start: the first fixes teach the orientation
        let (m0, z0) = about_identity(&[-1.0, -1.0, -1.0]);
        let mut f = BinghamFilter::new(4, &m0, &z0).unwrap();
        count = 0;
        for k in 0..3000 {
            let t = k as f64 * dt;
            let w = [0.8 * (0.7 * t).sin(), 0.5 * (0.3 * t).cos(), 0.6];
            let h = 0.5 * dt;
            let nw = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
            let s = (nw * h).sin() / nw;
            let u = [(nw * h).cos(), w[0] * s, w[1] * s, w[2] * s];
            // the truth turns by u and the process noise; the filter knows u
            truth = compose(&compose(&truth, &u).unwrap(), ws[k].as_slice())
                .unwrap()
                .try_into()
                .unwrap();
            f.predict_rotation(&u, &mw, &zw).unwrap();
            if k % 10 == 9 {
                let y: [f64; 4] = compose(&truth, vs[k].as_slice())
                    .unwrap()
                    .try_into()
                    .unwrap();
                // order 1: the components read as (x, y, z, w)
                let y = if order == 0 {
                    y
                } else {
                    [y[1], y[2], y[3], y[0]]
                };
                let g = f.update_gated(&y, &mv, &zv, f64::INFINITY).unwrap();
                assert!(g.accepted);
                if k > 200 {
                    count += 1;
                    *flags += usize::from(g.surprise > CHI2_3_999);
                }
            }
        }
    }
    let (right, wrong) = (
        flagged[0] as f64 / count as f64,
        flagged[1] as f64 / count as f64,
    );
    println!("flagged at s > 16.27: right order {right:.4}, (x, y, z, w) order {wrong:.4}");
    assert!(right < 0.01, "right order flagged {right}");
    assert!(wrong > 0.9, "wrong order flagged {wrong}");
}

#[test]
fn the_gate_applies_update_or_nothing() {
    let (m, z) = about_identity(&[-300.0, -300.0, -300.0]);
    let (mv, zv) = about_identity(&[-200.0, -200.0, -200.0]);
    let near = [0.999f64.sqrt(), 0.001f64.sqrt(), 0.0, 0.0];
    let far = [0.0, 1.0, 0.0, 0.0];
    let base = BinghamFilter::new(4, &m, &z).unwrap();

    let mut a = base.clone();
    let mut b = base.clone();
    let g = a.update_gated(&near, &mv, &zv, CHI2_3_999).unwrap();
    b.update(&near, &mv, &zv).unwrap();
    assert!(g.accepted);
    assert_eq!(g.surprise, base.surprise(&near, &mv, &zv).unwrap());
    assert_eq!(a.state(), b.state());

    let mut c = base.clone();
    let g = c.update_gated(&far, &mv, &zv, CHI2_3_999).unwrap();
    assert!(!g.accepted && g.surprise > 100.0, "{g:?}");
    assert_eq!(c.state(), base.state());

    for bad in [f64::NAN, -1.0] {
        let r = c.update_gated(&near, &mv, &zv, bad);
        assert!(matches!(r, Err(Error::InvalidArgument(_))), "{r:?}");
    }
    assert_eq!(c.state(), base.state());
}

/// The surprise is `2 (log p(ŷ) − log p(y))` clamped at 0: the same number as the difference of
/// the two predictive log densities `log_likelihood` gives (which carries the state's and the
/// noise's normalizers the surprise lets cancel), to rounding, over states and noises from
/// broad to concentrated and measurements near and far.
#[test]
fn the_surprise_is_twice_the_drop_of_the_predictive_log_density() {
    use rand::Rng;
    let mut rng = StdRng::seed_from_u64(41);
    let (mut checked, mut positive) = (0, 0);
    for case in 0..300 {
        let d = if case % 3 == 0 { 2 } else { 4 };
        let lz = |rng: &mut StdRng| -(10f64.powf(rng.gen_range(-1.0..4.0)));
        let mut zs: Vec<f64> = (0..d - 1).map(|_| lz(&mut rng)).collect();
        zs.sort_by(f64::total_cmp);
        zs.push(0.0);
        let zv_rest: Vec<f64> = (0..d - 1).map(|_| lz(&mut rng)).collect();
        // a random orthogonal M for the state (QR of a Gaussian matrix)
        let g = DMatrix::<f64>::from_fn(d, d, |_, _| rng.gen_range(-1.0..1.0));
        let q = g.qr().q();
        let ms: Vec<f64> = (0..d * d).map(|k| q[(k / d, k % d)]).collect();
        let f = BinghamFilter::new(d, &ms, &zs).unwrap();
        // the noise about the identity, so ŷ is the state's mode
        let (mv, zv) = about_identity(&zv_rest);
        let y_hat = f.mode();
        let mut y: Vec<f64> = y_hat.iter().map(|v| v + rng.gen_range(-0.3..0.3)).collect();
        let n = y.iter().map(|v| v * v).sum::<f64>().sqrt();
        y.iter_mut().for_each(|v| *v /= n);
        let s = f.surprise(&y, &mv, &zv).unwrap();
        let reference = (2.0
            * (f.log_likelihood(&y_hat, &mv, &zv).unwrap()
                - f.log_likelihood(&y, &mv, &zv).unwrap()))
        .max(0.0);
        let scale = 1.0 + reference.abs();
        assert!(
            (s - reference).abs() <= 1e-9 * scale,
            "case {case}: surprise {s} against {reference}"
        );
        checked += 1;
        positive += usize::from(reference > 0.1);
    }
    assert_eq!(checked, 300);
    assert!(positive > 200, "only {positive} measurements off the mode");
}
