//! Vector observations, rotation noise and angular spread, each against an independent reference
//! written here or in `testkit` (never against the crate's own formulas): the rotation matrix
//! from the textbook quaternion formula, nalgebra's symmetric eigensolver, Monte Carlo integrals
//! over the crate's exact sampler and over Gaussian rotation vectors, and Gauss–Legendre
//! quadratures (nodes computed by Newton's method). The `q4` quaternion helpers are tested in
//! `tests/q4.rs`.

use bingham::filter::BinghamFilter;
use bingham::observation::{
    angular_spread, davenport_matrix, log_vmf_normalizer_s2, noise_from_angle_std,
    spread_from_omega, vector_observation,
};
use bingham::{Bingham, Error};
use nalgebra::{DMatrix, DVector, Matrix4};
use rand::rngs::StdRng;
use rand::SeedableRng;
use std::f64::consts::PI;
use testkit::{dist3, dot3, gauss_legendre, matvec, rot, Rng64};

// ---------------------------------------------------------------------------------------------
// Independent references

/// `rᵀ R(q) b`.
fn direct(q: &[f64; 4], b: &[f64; 3], r: &[f64; 3]) -> f64 {
    dot3(r, &matvec(&rot(q), b))
}

/// `∫_a^b f` by composite Gauss–Legendre (`panels` panels of `n` nodes).
fn integrate(f: impl Fn(f64) -> f64, a: f64, b: f64, panels: usize, n: usize) -> f64 {
    let (x, w) = gauss_legendre(n);
    let h = (b - a) / panels as f64;
    let mut total = 0.0;
    for p in 0..panels {
        let c = a + (p as f64 + 0.5) * h;
        let mut s = 0.0;
        for (xi, wi) in x.iter().zip(&w) {
            s += wi * f(c + 0.5 * h * xi);
        }
        total += 0.5 * h * s;
    }
    total
}

/// Mean and standard error of the mean.
fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// A state for the filter tests: `z = (−20, −10, −5, 0)`, a fixed random orientation of the axes.
fn test_state(seed: u64) -> Bingham {
    let m = Rng64(seed).orthogonal(4);
    Bingham::new(m, DVector::from_vec(vec![-20.0, -10.0, -5.0, 0.0])).unwrap()
}

fn precision(b: &Bingham) -> DMatrix<f64> {
    b.m() * DMatrix::from_diagonal(b.z()) * b.m().transpose()
}

fn max_abs(m: &DMatrix<f64>) -> f64 {
    m.iter().fold(0.0f64, |a, v| a.max(v.abs()))
}

fn is_invalid_argument<T: std::fmt::Debug>(r: Result<T, Error>) -> bool {
    matches!(r, Err(Error::InvalidArgument(_)))
}

fn is_invalid_dimension<T: std::fmt::Debug>(r: Result<T, Error>) -> bool {
    matches!(r, Err(Error::InvalidDimension(_)))
}

// ---------------------------------------------------------------------------------------------
// Davenport's matrix

#[test]
fn davenport_matrix_is_the_direct_evaluation() {
    let mut rng = Rng64(11);
    let mut worst = 0.0f64;
    let mut worst_eig = 0.0f64;
    for _ in 0..200 {
        let (b, r, q) = (
            rng.unit_array::<3>(),
            rng.unit_array::<3>(),
            rng.unit_array::<4>(),
        );
        let k = davenport_matrix(&b, &r);
        let mut qkq = 0.0;
        for i in 0..4 {
            for j in 0..4 {
                qkq += q[i] * k[i][j] * q[j];
                assert_eq!(k[i][j], k[j][i], "K symmetric");
            }
        }
        worst = worst.max((qkq - direct(&q, &b, &r)).abs());
        let trace = k[0][0] + k[1][1] + k[2][2] + k[3][3];
        assert!(trace.abs() < 1e-15, "trace {trace}");
        let km = Matrix4::from_fn(|i, j| k[i][j]);
        let mut ev: Vec<f64> = km.symmetric_eigen().eigenvalues.iter().copied().collect();
        ev.sort_by(|a, b| a.partial_cmp(b).unwrap());
        for (e, want) in ev.iter().zip([-1.0, -1.0, 1.0, 1.0]) {
            worst_eig = worst_eig.max((e - want).abs());
        }
    }
    println!("max |qᵀKq − rᵀR(q)b| = {worst:.2e}, max eigenvalue error {worst_eig:.2e}");
    assert!(worst < 1e-14, "{worst}");
    assert!(worst_eig < 1e-14, "{worst_eig}");
}

// ---------------------------------------------------------------------------------------------
// vector_observation

#[test]
fn vector_observation_is_the_vmf_likelihood() {
    let mut rng = Rng64(12);
    for kappa in [0.0, 0.3, 3.0, 100.0, 1e6] {
        for _ in 0..20 {
            let (b, r) = (rng.unit_array::<3>(), rng.unit_array::<3>());
            let obs = vector_observation(&b, &r, kappa).unwrap();
            assert_eq!(obs.dim(), 4);
            let z: Vec<f64> = obs.z().iter().copied().collect();
            let want = [-2.0 * kappa, -2.0 * kappa, 0.0, 0.0];
            for (a, w) in z.iter().zip(want) {
                assert!((a - w).abs() <= 1e-15 * kappa, "z = {z:?}, want {want:?}");
            }
            let m = obs.m();
            let orth = max_abs(&(m.transpose() * m - DMatrix::identity(4, 4)));
            assert!(orth < 1e-14, "MᵀM − I: {orth}");
            // The exponent is κ rᵀR(q)b up to the shift −κ.
            let p = precision(&obs);
            for _ in 0..10 {
                let q = rng.unit_array::<4>();
                let qv = DVector::from_column_slice(&q);
                let e = (qv.transpose() * &p * &qv)[(0, 0)];
                let want = kappa * direct(&q, &b, &r) - kappa;
                assert!(
                    (e - want).abs() <= 1e-13 * kappa.max(1.0),
                    "κ = {kappa}: exponent {e}, want {want}"
                );
            }
            // The last two columns rotate b onto r (for κ = 0 every direction is a mode).
            if kappa > 0.0 {
                for j in 2..4 {
                    let c = [m[(0, j)], m[(1, j)], m[(2, j)], m[(3, j)]];
                    let rb = matvec(&rot(&c), &b);
                    assert!(
                        dist3(&rb, &r) < 1e-13,
                        "column {j}: R b = {rb:?}, r = {r:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn vector_observation_rejects_bad_input() {
    let (b, r) = ([0.0, 0.0, 1.0], [0.6, 0.8, 0.0]);
    assert!(is_invalid_dimension(vector_observation(
        &[0.0, 1.0],
        &r,
        1.0
    )));
    assert!(is_invalid_dimension(vector_observation(
        &b,
        &[0.0, 0.0, 0.0, 1.0],
        1.0
    )));
    assert!(is_invalid_argument(vector_observation(
        &[f64::NAN, 0.0, 1.0],
        &r,
        1.0
    )));
    assert!(is_invalid_argument(vector_observation(
        &b,
        &[0.6, 0.8, f64::INFINITY],
        1.0
    )));
    assert!(is_invalid_argument(vector_observation(
        &[0.0, 0.0, 1.1],
        &r,
        1.0
    )));
    assert!(is_invalid_argument(vector_observation(
        &[0.0, 0.0, 0.0],
        &r,
        1.0
    )));
    for kappa in [-1.0, -1e-300, f64::NAN, f64::INFINITY] {
        assert!(
            is_invalid_argument(vector_observation(&b, &r, kappa)),
            "{kappa}"
        );
    }
    // b = ±r and b ⟂ r are fine (degenerate cross products).
    assert!(vector_observation(&b, &b, 5.0).is_ok());
    assert!(vector_observation(&b, &[0.0, 0.0, -1.0], 5.0).is_ok());
    assert!(vector_observation(&b, &[1.0, 0.0, 0.0], 5.0).is_ok());
}

// ---------------------------------------------------------------------------------------------
// BinghamFilter::update_vector and log_likelihood_vector

#[test]
fn update_vector_is_the_bayes_product() {
    let mut rng = Rng64(13);
    let mut worst = 0.0f64;
    for seed in 0..10 {
        let state = test_state(100 + seed);
        for kappa in [0.5, 3.0, 50.0] {
            let (b, r) = (rng.unit_array::<3>(), rng.unit_array::<3>());
            let mut f = BinghamFilter::from_bingham(&state).unwrap();
            f.update_vector(&b, &r, kappa).unwrap();
            let got = f.state();
            let want = state
                .multiply(&vector_observation(&b, &r, kappa).unwrap())
                .unwrap();
            let (pg, pw) = (precision(&got), precision(&want));
            let e = max_abs(&(&pg - &pw)) / max_abs(&pw);
            worst = worst.max(e);
            let (sg, sw) = (got.second_moment().unwrap(), want.second_moment().unwrap());
            let es = max_abs(&(&sg - &sw));
            assert!(es < 1e-10, "second moments differ by {es}");
        }
    }
    println!("update_vector vs multiply: max relative difference of M Z Mᵀ {worst:.2e}");
    assert!(worst < 1e-10, "{worst}");
}

#[test]
fn update_vector_refuses_bad_input_and_keeps_the_state() {
    let mut f2 = BinghamFilter::new(2, &[1.0, 0.0, 0.0, 1.0], &[-1.0, 0.0]).unwrap();
    let (b, r) = ([0.0, 0.0, 1.0], [0.6, 0.8, 0.0]);
    assert!(is_invalid_dimension(f2.update_vector(&b, &r, 1.0)));
    assert!(is_invalid_dimension(f2.log_likelihood_vector(&b, &r, 1.0)));
    let mut out = [0.0; 2];
    f2.angular_spread_into(&mut out).unwrap();

    let mut f = BinghamFilter::from_bingham(&test_state(7)).unwrap();
    f.update_vector(&b, &r, 2.0).unwrap();
    let snapshot = |f: &BinghamFilter| {
        let (mut m, mut z) = ([0.0; 16], [0.0; 4]);
        f.state_into(&mut m, &mut z).unwrap();
        let bits: Vec<u64> = m.iter().chain(z.iter()).map(|v| v.to_bits()).collect();
        bits
    };
    let before = snapshot(&f);
    let bad: Vec<(Vec<f64>, Vec<f64>, f64)> = vec![
        (vec![f64::NAN, 0.0, 1.0], r.to_vec(), 1.0),
        (b.to_vec(), vec![0.6, f64::NAN, 0.0], 1.0),
        (vec![0.0, 0.0, 2.0], r.to_vec(), 1.0),
        (b.to_vec(), vec![0.6, 0.6, 0.0], 1.0),
        (b.to_vec(), r.to_vec(), -1.0),
        (b.to_vec(), r.to_vec(), f64::NAN),
        (b.to_vec(), r.to_vec(), f64::INFINITY),
    ];
    for (bb, rr, k) in &bad {
        assert!(
            is_invalid_argument(f.update_vector(bb, rr, *k)),
            "{bb:?} {rr:?} {k}"
        );
        assert!(is_invalid_argument(f.log_likelihood_vector(bb, rr, *k)));
        assert_eq!(snapshot(&f), before, "state changed by a refused update");
    }
    assert!(is_invalid_dimension(f.update_vector(&[0.0, 1.0], &r, 1.0)));
    assert_eq!(snapshot(&f), before);
    // κ = 0 is an uninformative observation: the state stays (up to the eigensolver's rounding).
    let s0 = f.state();
    f.update_vector(&b, &r, 0.0).unwrap();
    let e = max_abs(&(precision(&f.state()) - precision(&s0)));
    assert!(e < 1e-12, "κ = 0 changed the state by {e}");
}

/// Predictive density of `b` by Monte Carlo over the state's samples, with its standard error.
fn predictive_mc(samples: &[DVector<f64>], b: &[f64; 3], r: &[f64; 3], kappa: f64) -> (f64, f64) {
    let c = kappa / (4.0 * PI * kappa.sinh());
    let vals: Vec<f64> = samples
        .iter()
        .map(|s| {
            let q = [s[0], s[1], s[2], s[3]];
            c * (kappa * direct(&q, b, r)).exp()
        })
        .collect();
    mean_se(&vals)
}

#[test]
fn log_likelihood_vector_against_monte_carlo() {
    let state = test_state(21);
    let f = BinghamFilter::from_bingham(&state).unwrap();
    let mut rng = StdRng::seed_from_u64(2024);
    let samples = state.sample(&mut rng, 200_000);
    let mut dir = Rng64(22);
    let kappa = 3.0;
    let r = [0.0, 0.0, 1.0];
    // The most likely direction (the mode maps b to r) and random ones.
    let mode = state.mode();
    let qm = [mode[0], mode[1], mode[2], mode[3]];
    let rm = rot(&qm);
    let b_mode = [rm[2][0], rm[2][1], rm[2][2]]; // R(q)ᵀ r
    let mut dirs = vec![b_mode];
    dirs.extend((0..5).map(|_| dir.unit_array::<3>()));
    for b in &dirs {
        let ll = f.log_likelihood_vector(b, &r, kappa).unwrap();
        let (p, se) = predictive_mc(&samples, b, &r, kappa);
        let dev = (ll.exp() - p) / se;
        println!(
            "b = {b:.3?}: exp(ll) = {:.6}, MC {p:.6} ± {se:.1e} ({dev:+.2} SE)",
            ll.exp()
        );
        assert!(dev.abs() < 4.0, "{dev} SE");
    }
}

#[test]
fn predictive_density_integrates_to_one() {
    let state = test_state(31);
    let f = BinghamFilter::from_bingham(&state).unwrap();
    let (x, w) = gauss_legendre(40);
    let nphi = 80;
    let r = [0.3, -0.4, (1.0f64 - 0.25).sqrt()];
    for kappa in [0.0, 1e-4, 3.0, 10.0] {
        let mut total = 0.0;
        for (ct, wt) in x.iter().zip(&w) {
            let st = (1.0 - ct * ct).sqrt();
            for k in 0..nphi {
                // The trapezoidal rule: spectrally accurate for the periodic φ.
                let phi = 2.0 * PI * k as f64 / nphi as f64;
                let b = [st * phi.cos(), st * phi.sin(), *ct];
                let ll = f.log_likelihood_vector(&b, &r, kappa).unwrap();
                total += wt * (2.0 * PI / nphi as f64) * ll.exp();
            }
        }
        println!("κ = {kappa}: ∫ p(b) db − 1 = {:.2e}", total - 1.0);
        assert!((total - 1.0).abs() < 1e-6, "κ = {kappa}: {total}");
    }
    // κ = 0: the direction is uniform whatever the state.
    let ll0 = f.log_likelihood_vector(&[1.0, 0.0, 0.0], &r, 0.0).unwrap();
    assert!((ll0 + (4.0 * PI).ln()).abs() < 1e-12, "{ll0}");
}

#[test]
fn vmf_normalizer() {
    // The density C(κ) exp(κ cos θ) integrates to one on S² (quadrature in cos θ).
    for kappa in [0.0, 1e-8, 1e-3, 0.5, 3.0, 30.0, 300.0] {
        let lc = log_vmf_normalizer_s2(kappa);
        let int = integrate(|t| 2.0 * PI * (lc + kappa * t).exp(), -1.0, 1.0, 40, 20);
        assert!((int - 1.0).abs() < 1e-13, "κ = {kappa}: {int}");
    }
    // Huge κ: log C = log κ − log 2π − κ (sinh κ ≈ e^κ/2), no overflow.
    for kappa in [800.0, 1e5, 1e300] {
        let lc = log_vmf_normalizer_s2(kappa);
        let want = kappa.ln() - (2.0 * PI).ln() - kappa;
        assert!(
            (lc - want).abs() <= 1e-15 * want.abs().max(1.0),
            "{kappa}: {lc}"
        );
    }
    assert_eq!(log_vmf_normalizer_s2(0.0), -(4.0 * PI).ln());
}

// ---------------------------------------------------------------------------------------------
// noise_from_angle_std

/// The second moment of `q = (cos(|v|/2), sin(|v|/2) v/|v|)`, `v ~ N(0, σ² I₃)`, by Monte
/// Carlo: per entry, the mean and its standard error.
fn rotation_noise_mc(sigma: f64, n: usize, seed: u64) -> [[(f64, f64); 4]; 4] {
    let mut rng = Rng64(seed);
    let mut sum = [[0.0; 4]; 4];
    let mut sum2 = [[0.0; 4]; 4];
    for _ in 0..n {
        let v = [
            sigma * rng.normal(),
            sigma * rng.normal(),
            sigma * rng.normal(),
        ];
        let th = dot3(&v, &v).sqrt();
        let s = (0.5 * th).sin() / th;
        let q = [(0.5 * th).cos(), s * v[0], s * v[1], s * v[2]];
        for i in 0..4 {
            for j in 0..4 {
                let x = q[i] * q[j];
                sum[i][j] += x;
                sum2[i][j] += x * x;
            }
        }
    }
    let nf = n as f64;
    let mut out = [[(0.0, 0.0); 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            let m = sum[i][j] / nf;
            let var = (sum2[i][j] / nf - m * m).max(0.0) * nf / (nf - 1.0);
            out[i][j] = (m, (var / nf).sqrt());
        }
    }
    out
}

/// `E[1 − cos|v|]`, `|v| = σ χ₃` (Maxwell), by quadrature of `2 sin²(σt/2)` against the χ₃
/// density `√(2/π) t² e^{−t²/2}` (no cancellation for small σ).
fn maxwell_one_minus_cos(sigma: f64) -> f64 {
    let c = (2.0 / PI).sqrt();
    integrate(
        |t| c * t * t * (-0.5 * t * t).exp() * 2.0 * (0.5 * sigma * t).sin().powi(2),
        0.0,
        40.0,
        200,
        16,
    )
}

/// `E[sin² φ]`, `φ ~ N(0, σ²)`, by quadrature.
fn gaussian_sin2(sigma: f64) -> f64 {
    let c = 1.0 / (2.0 * PI).sqrt();
    integrate(
        |t| c * (-0.5 * t * t).exp() * (sigma * t).sin().powi(2),
        -40.0,
        40.0,
        400,
        16,
    )
}

#[test]
fn rotation_noise_against_monte_carlo_d4() {
    for (k, sigma) in [0.01, 0.1, 0.5, 1.0].into_iter().enumerate() {
        let noise = noise_from_angle_std(4, sigma).unwrap();
        let s = noise.second_moment().unwrap();
        let mc = rotation_noise_mc(sigma, 400_000, 40 + k as u64);
        let mut worst = 0.0f64;
        for i in 0..4 {
            for j in 0..4 {
                let (m, se) = mc[i][j];
                // A floor for the exactly-zero-variance case (none here, but be safe).
                let dev = (s[(i, j)] - m).abs() / se.max(1e-300);
                worst = worst.max(dev);
                assert!(
                    dev < 4.0,
                    "σ = {sigma}: S[{i}][{j}] = {}, MC {m} ± {se}",
                    s[(i, j)]
                );
            }
        }
        println!("σ = {sigma}: max deviation from MC {worst:.2} SE");
    }
}

#[test]
fn rotation_noise_against_quadrature() {
    for sigma in [1e-4, 0.01, 0.1, 0.5, 1.0, 2.0, 5.0] {
        let noise = noise_from_angle_std(4, sigma).unwrap();
        let s = noise.second_moment().unwrap();
        let omc = maxwell_one_minus_cos(sigma);
        // S = diag(a, (1−a)/3 ×3), a = (1 + E cos)/2 = 1 − E[1 − cos]/2.
        let a = 1.0 - 0.5 * omc;
        let small = omc / 6.0;
        println!(
            "σ = {sigma}: |S00 − a| = {:.1e}, rel. error of S11 {:.1e}",
            (s[(0, 0)] - a).abs(),
            (s[(1, 1)] - small).abs() / small
        );
        assert!(
            (s[(0, 0)] - a).abs() < 1e-12,
            "σ = {sigma}: S00 {} vs {a}",
            s[(0, 0)]
        );
        for i in 1..4 {
            let rel = (s[(i, i)] - small).abs() / small;
            assert!(
                rel < 1e-12,
                "σ = {sigma}: S{i}{i} {} vs {small} (rel {rel})",
                s[(i, i)]
            );
            for j in 0..4 {
                if j != i {
                    assert!(s[(i, j)].abs() < 1e-12, "off-diagonal {}", s[(i, j)]);
                }
            }
        }
        // The closed form the docs state, (1 − σ²) e^{−σ²/2}, against the quadrature.
        let s2 = sigma * sigma;
        assert!(((1.0 - omc) - (1.0 - s2) * (-0.5 * s2).exp()).abs() < 1e-12);
        // The mode is the identity.
        let mode = noise.mode();
        assert!((mode[0].abs() - 1.0).abs() < 1e-12, "mode {mode:?}");
        assert!(mode.iter().skip(1).all(|v| v.abs() < 1e-6), "mode {mode:?}");
        // Three equal concentrations.
        let z = noise.z();
        assert_eq!(z[3], 0.0);
        assert!((z[0] - z[2]).abs() <= 1e-9 * z[0].abs(), "z = {z:?}");
    }
}

#[test]
fn rotation_noise_d2_against_quadrature() {
    for sigma in [1e-4, 0.01, 0.1, 0.5, 1.0, 3.0] {
        let noise = noise_from_angle_std(2, sigma).unwrap();
        let s = noise.second_moment().unwrap();
        let sin2 = gaussian_sin2(sigma);
        assert!((s[(0, 0)] - (1.0 - sin2)).abs() < 1e-12, "σ = {sigma}");
        let rel = (s[(1, 1)] - sin2).abs() / sin2;
        assert!(rel < 1e-9, "σ = {sigma}: {} vs {sin2}", s[(1, 1)]);
        assert!(s[(0, 1)].abs() < 1e-12);
        let mode = noise.mode();
        assert!((mode[0].abs() - 1.0).abs() < 1e-12, "mode {mode:?}");
    }
}

#[test]
fn rotation_noise_small_sigma_and_errors() {
    for sigma in [1e-3, 0.01] {
        let z4 = noise_from_angle_std(4, sigma).unwrap().z().clone();
        let want4 = -2.0 / (sigma * sigma);
        for i in 0..3 {
            assert!(
                (z4[i] / want4 - 1.0).abs() < 0.01,
                "d = 4 σ = {sigma}: {z4:?}"
            );
        }
        let z2 = noise_from_angle_std(2, sigma).unwrap().z().clone();
        let want2 = -0.5 / (sigma * sigma);
        assert!(
            (z2[0] / want2 - 1.0).abs() < 0.01,
            "d = 2 σ = {sigma}: {z2:?}"
        );
    }
    for sigma in [0.0, -0.1, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert!(
            is_invalid_argument(noise_from_angle_std(4, sigma)),
            "{sigma}"
        );
        assert!(
            is_invalid_argument(noise_from_angle_std(2, sigma)),
            "{sigma}"
        );
    }
    for d in [0, 1, 3, 5, 8] {
        assert!(
            is_invalid_dimension(noise_from_angle_std(d, 0.1)),
            "d = {d}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Angular spread

#[test]
fn angular_spread_d4_against_monte_carlo() {
    let m = Rng64(51).orthogonal(4);
    let b = Bingham::new(m, DVector::from_vec(vec![-30.0, -20.0, -10.0, 0.0])).unwrap();
    let spread = angular_spread(&b).unwrap();
    assert_eq!(spread.len(), 4);
    let sq: f64 = spread[..3].iter().map(|s| s * s).sum();
    assert!(
        (sq - spread[3] * spread[3]).abs() < 1e-14,
        "per-axis squares"
    );

    let mut rng = StdRng::seed_from_u64(52);
    let samples = b.sample(&mut rng, 200_000);
    let mode = b.mode();
    // (2 sin(θ/2))² = 4 (1 − (q·m)²), θ the rotation angle between sample and mode.
    let x2: Vec<f64> = samples
        .iter()
        .map(|q| 4.0 * (1.0 - q.dot(&mode).powi(2)))
        .collect();
    let (ms, se) = mean_se(&x2);
    let dev = (spread[3] * spread[3] - ms) / se;
    println!(
        "d = 4 spread total {:.3}°, MC RMS 2 sin(θ/2) {:.3}° ({dev:+.2} SE)",
        spread[3].to_degrees(),
        ms.sqrt().to_degrees()
    );
    assert!(dev.abs() < 4.0, "{dev}");
    // Per axis: E[(2 q·m_i)²] = spread[i]².
    for (i, s_i) in spread.iter().take(3).enumerate() {
        let col = b.m().column(i).into_owned();
        let v: Vec<f64> = samples.iter().map(|q| 4.0 * q.dot(&col).powi(2)).collect();
        let (mi, sei) = mean_se(&v);
        let dev = (s_i * s_i - mi) / sei;
        assert!(dev.abs() < 4.0, "axis {i}: {dev}");
    }
    // The filter reports the same.
    let f = BinghamFilter::from_bingham(&b).unwrap();
    let mut out = [0.0; 4];
    f.angular_spread_into(&mut out).unwrap();
    for i in 0..4 {
        assert!(
            (out[i] - spread[i]).abs() < 1e-12 * spread[i],
            "{out:?} vs {spread:?}"
        );
    }
    let mut wrong = [0.0; 3];
    assert!(is_invalid_dimension(f.angular_spread_into(&mut wrong)));
    // A small spread reads as the RMS angle (second order).
    let tight = Bingham::new(
        DMatrix::identity(4, 4),
        DVector::from_vec(vec![-2e4, -2e4, -2e4, 0.0]),
    )
    .unwrap();
    let t = angular_spread(&tight).unwrap()[3];
    // The vector part has variance 1/(2|z|) per axis and 2 sin(θ/2) = 2|v|: E = 4·3/(2|z|).
    let want = (3.0f64 * 4.0 / (2.0 * 2e4)).sqrt();
    assert!((t / want - 1.0).abs() < 1e-3, "{t} vs {want}");
}

#[test]
fn angular_spread_d2_against_monte_carlo() {
    let m = Rng64(61).orthogonal(2);
    let b = Bingham::new(m, DVector::from_vec(vec![-8.0, 0.0])).unwrap();
    let spread = angular_spread(&b).unwrap();
    assert_eq!(spread.len(), 2);
    assert!((spread[0] - spread[1]).abs() < 1e-15);
    let mut rng = StdRng::seed_from_u64(62);
    let samples = b.sample(&mut rng, 200_000);
    let mode = b.mode();
    let x2: Vec<f64> = samples.iter().map(|x| 1.0 - x.dot(&mode).powi(2)).collect();
    let (ms, se) = mean_se(&x2);
    let dev = (spread[1] * spread[1] - ms) / se;
    println!(
        "d = 2 spread {:.4} rad, MC RMS sin α {:.4} ({dev:+.2} SE)",
        spread[1],
        ms.sqrt()
    );
    assert!(dev.abs() < 4.0, "{dev}");
    // Errors and the uniform distribution.
    let b3 = Bingham::new(
        DMatrix::identity(3, 3),
        DVector::from_vec(vec![-1.0, -1.0, 0.0]),
    )
    .unwrap();
    assert!(is_invalid_dimension(angular_spread(&b3)));
    let mut out = [0.0; 4];
    spread_from_omega(&[0.25; 4], &mut out);
    assert!(
        (out[3] - 3f64.sqrt()).abs() < 1e-15,
        "uniform total {}",
        out[3]
    );
}
