//! Deterministic samples: weights, unit points and the reproduced moments against the exact
//! moments from log F's gradient and Hessian (an independent evaluation: the moments are
//! recomputed here from `evaluate`, the points only enter through their coordinates).

use bingham::deterministic::{max_count, DeterministicSamples, Reproduced, Scheme};
use bingham::normalization::evaluate;
use bingham::{Bingham, Method};
use testkit::{xorshift_uniform, Rng64};

mod filter_common;

/// A Haar-random orthogonal matrix (row-major) from the shared test generator.
fn orthogonal(d: usize, seed: u64) -> Vec<f64> {
    let q = Rng64(seed).orthogonal(d);
    (0..d * d).map(|k| q[(k / d, k % d)]).collect()
}

/// Max relative errors of the second moment and of the principal fourth moments
/// `E[y_i² y_j²]` of the point set against the exact ones.
fn moment_errors(b: &Bingham, scheme: Scheme) -> (f64, f64, Reproduced, usize) {
    let d = b.dim();
    let s = b.deterministic_samples(scheme).unwrap();
    assert_eq!(s.points.len(), s.count() * d);
    assert!(s.count() <= max_count(d, scheme));
    let sum: f64 = s.weights.iter().sum();
    assert!((sum - 1.0).abs() < 1e-14, "weights sum to {sum}");
    assert!(s.weights.iter().all(|&w| w >= 0.0 && w.is_finite()));
    let ev = evaluate(b.z().as_slice(), Method::Exact, true).unwrap();
    let m = b.m();
    // principal coordinates of each point
    let mut e2 = vec![0.0; d * d];
    let mut e4 = vec![0.0; d * d];
    for (k, x) in s.points.chunks(d).enumerate() {
        let n: f64 = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!((n - 1.0).abs() < 1e-14);
        let y: Vec<f64> = (0..d)
            .map(|i| (0..d).map(|r| m[(r, i)] * x[r]).sum())
            .collect();
        for i in 0..d {
            for j in 0..d {
                e2[i * d + j] += s.weights[k] * y[i] * y[j];
                e4[i * d + j] += s.weights[k] * y[i] * y[i] * y[j] * y[j];
            }
        }
    }
    let mut err2: f64 = 0.0;
    let mut err4: f64 = 0.0;
    for i in 0..d {
        for j in 0..d {
            let want2 = if i == j { ev.grad[i] } else { 0.0 };
            err2 = err2.max((e2[i * d + j] - want2).abs() / ev.grad[i].max(ev.grad[j]));
            let want4 = ev.hess[i * d + j] + ev.grad[i] * ev.grad[j];
            err4 = err4.max((e4[i * d + j] - want4).abs() / want4);
        }
    }
    (err2, err4, s.reproduced, s.count())
}

#[test]
fn moments_scheme_reproduces_second_and_fourth_moments() {
    let cases: &[&[f64]] = &[
        &[-3.0, 0.0],
        &[-1e6, 0.0],
        &[0.0, 0.0],
        &[-20.0, -5.0, 0.0],
        &[-1e4, -1e3, -1e2, 0.0],
        &[-17.0, -17.0, -17.0, 0.0],
        &[-5.0, -1.0, -0.1, 0.0],
        &[-1.0, -1.0, -1.0, 0.0],
        &[0.0, 0.0, 0.0, 0.0],
        &[-1e6, -1e5, -1e3, 0.0],
        &[-100.0, -50.0, -10.0, 0.0],
        // Girdles (two sharp axes and a broad one): the three-center variant.
        &[-143.46, -143.45, -2.0, 0.0],
        &[-200.0, -200.0, -2.0, 0.0],
        &[-1e6, -1e6, -1.0, 0.0],
        &[-1e4, -400.0, -0.5, 0.0],
        &[-1e6, -10.0, -1.0, 0.0],
        &[-6.7e4, -6.3e3, -2.9, 0.0],
    ];
    for (n, z) in cases.iter().enumerate() {
        let d = z.len();
        let b = Bingham::from_row_major(d, &orthogonal(d, n as u64 + 1), z).unwrap();
        let (e2, e4, rep, count) = moment_errors(&b, Scheme::Moments);
        println!("z = {z:?}: {count} points, second {e2:.1e}, fourth {e4:.1e}, {rep:?}");
        assert_eq!(rep, Reproduced::FourthMoments, "z = {z:?}");
        assert_eq!(count, 2 * d * d - 4 * d + 3);
        assert!(e2 < 1e-12, "z = {z:?}: second moment error {e2:e}");
        assert!(e4 < 1e-10, "z = {z:?}: fourth moment error {e4:e}");
    }
}

/// Where no positive set of either shape exists, the TAC 2016 points with λ = 1/2, and the
/// scheme says so.
#[test]
fn moments_scheme_falls_back_with_second_moment_only() {
    for (n, z) in [[-25.57, -6.78, -0.0169, 0.0], [-2.79e6, -12.5, -0.145, 0.0]]
        .iter()
        .enumerate()
    {
        let b = Bingham::from_row_major(4, &orthogonal(4, 90 + n as u64), z).unwrap();
        let (e2, e4, rep, count) = moment_errors(&b, Scheme::Moments);
        println!("fallback z = {z:?}: {count} points, second {e2:.1e}, fourth {e4:.1e}");
        assert_eq!(rep, Reproduced::SecondMoment);
        assert_eq!(count, 7);
        assert!(e2 < 1e-12);
        let tac = b
            .deterministic_samples(Scheme::Tac2016 { lambda: 0.5 })
            .unwrap();
        let ours = b.deterministic_samples(Scheme::Moments).unwrap();
        assert_eq!(
            tac,
            DeterministicSamples {
                reproduced: Reproduced::SecondMoment,
                ..ours
            }
        );
    }
}

/// The TAC 2016 scheme: 2d − 1 points, exact second moment, fourth moments not reproduced;
/// the mode's weight is λ ω_{d−1}.
#[test]
fn tac2016_reproduces_the_second_moment() {
    for (n, z) in [
        vec![-3.0, 0.0],
        vec![-20.0, -5.0, 0.0],
        vec![-40.0, -25.0, -12.0, 0.0],
    ]
    .iter()
    .enumerate()
    {
        let d = z.len();
        let b = Bingham::from_row_major(d, &orthogonal(d, 60 + n as u64), z).unwrap();
        for lambda in [0.0, 0.5, 1.0] {
            let (e2, e4, rep, count) = moment_errors(&b, Scheme::Tac2016 { lambda });
            assert_eq!(rep, Reproduced::SecondMoment);
            assert_eq!(count, 2 * d - 1);
            assert!(e2 < 1e-12, "{e2:e}");
            assert!(
                e4 > 1e-3,
                "TAC 2016 does not reproduce the fourth moments: {e4:e}"
            );
            let s = b.deterministic_samples(Scheme::Tac2016 { lambda }).unwrap();
            let w = b.omega().unwrap();
            assert!((s.weights[0] - lambda * w[d - 1]).abs() < 1e-15);
        }
    }
    let b = Bingham::from_row_major(2, &orthogonal(2, 1), &[-3.0, 0.0]).unwrap();
    for lambda in [-0.1, 1.1, f64::NAN] {
        assert!(b.deterministic_samples(Scheme::Tac2016 { lambda }).is_err());
    }
}

/// Over random z (|z_i| log-uniform in [0.1, 1e7]): how often each d needs the fallback, and
/// every moment-matched set reproduces its moments.
#[test]
fn moments_scheme_coverage_over_random_z() {
    let mut uniform = xorshift_uniform(0x5eed);
    for d in [2usize, 3, 4] {
        let n = 2000;
        let mut fallback = 0;
        let mut worst: f64 = 0.0;
        for k in 0..n {
            let mut z: Vec<f64> = (0..d)
                .map(|_| -(10f64).powf(-1.0 + 8.0 * uniform()))
                .collect();
            z[d - 1] = 0.0;
            let b = Bingham::from_row_major(d, &orthogonal(d, 1000 + k as u64), &z).unwrap();
            let (e2, e4, rep, _) = moment_errors(&b, Scheme::Moments);
            assert!(e2 < 1e-11, "z = {z:?}: {e2:e}");
            match rep {
                Reproduced::FourthMoments => worst = worst.max(e4),
                Reproduced::SecondMoment => fallback += 1,
            }
        }
        let share = fallback as f64 / n as f64;
        println!(
            "d = {d}: fallback for {:.2} % of {n} random z; fourth moments to {worst:.1e}",
            100.0 * share
        );
        assert!(worst < 1e-9);
        if d < 4 {
            assert_eq!(fallback, 0);
        } else {
            assert!(share < 0.06, "{share}");
        }
    }
}

/// Every predicted and updated state of 5 runs of the JAIF d = 4 scenario (the predictions are
/// girdles, z ≈ (−150, −150, −2, 0)) gets a fourth-moment set.
#[test]
fn jaif_states_get_fourth_moment_sets() {
    use bingham::filter::BinghamFilter;
    let sc = testkit::scenarios::scenario_4d();
    let (mut fallback, mut total) = (0, 0);
    let mut check = |f: &BinghamFilter| {
        let s = f.state().deterministic_samples(Scheme::Moments).unwrap();
        if s.reproduced != Reproduced::FourthMoments {
            fallback += 1;
        }
        total += 1;
    };
    for run in 0..5 {
        let meas = filter_common::simulate(&sc, run).1;
        let mut f = BinghamFilter::new(4, &sc.m0, &sc.z0).unwrap();
        for y in &meas {
            f.predict(&sc.mw, &sc.zw).unwrap();
            check(&f);
            f.update(y, &sc.mv, &sc.zv).unwrap();
            check(&f);
        }
    }
    println!("JAIF d = 4 states: {fallback} of {total} need the fallback");
    assert_eq!(fallback, 0);
}
