//! The recursive Bingham filter (`bingham::filter`): agreement with the general (allocating)
//! core path, filter invariants, the log-likelihood against brute-force integration and Monte
//! Carlo, extreme concentrations, the failure contract (a failed call changes nothing), and the
//! JAIF Sec. 7 scenarios against the adapted Kalman filter.

mod filter_common;

use bingham::filter::{BinghamFilter, MAX_CONCENTRATION};
use bingham::quaternion::{compose, conjugate, left_matrix};
use bingham::{Bingham, Error};
use filter_common::*;
use nalgebra::{DMatrix, DVector};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::f64::consts::PI;
use testkit::scenarios::{normalized, scenario_2d, scenario_4d, Scenario};

fn random_rotation(rng: &mut StdRng, d: usize) -> DMatrix<f64> {
    let g = DMatrix::from_fn(d, d, |_, _| rng.gen::<f64>() - 0.5);
    g.qr().q()
}

fn random_unit(rng: &mut StdRng, d: usize) -> Vec<f64> {
    normalized(&(0..d).map(|_| rng.gen::<f64>() - 0.5).collect::<Vec<_>>())
}

fn row_major(m: &DMatrix<f64>) -> Vec<f64> {
    m.transpose().as_slice().to_vec()
}

/// Random concentrations `−10^u`, `u` uniform in `[lo, hi]`, plus a 0.
fn random_z(rng: &mut StdRng, d: usize, lo: f64, hi: f64) -> Vec<f64> {
    let mut z: Vec<f64> = (0..d - 1)
        .map(|_| -(10f64.powf(lo + (hi - lo) * rng.gen::<f64>())))
        .collect();
    z.push(0.0);
    z
}

fn state_of(f: &BinghamFilter) -> (Vec<f64>, Vec<f64>) {
    let d = f.dim();
    let mut m = vec![0.0; d * d];
    let mut z = vec![0.0; d];
    f.state_into(&mut m, &mut z).unwrap();
    (m, z)
}

fn bits(f: &BinghamFilter) -> Vec<u64> {
    let (m, z) = state_of(f);
    m.iter().chain(z.iter()).map(|v| v.to_bits()).collect()
}

/// `M Z Mᵀ` (row-major `m`): invariant under column signs and rotations within ties of `z`.
fn precision(d: usize, m: &[f64], z: &[f64]) -> DMatrix<f64> {
    let m = DMatrix::from_row_slice(d, d, m);
    &m * DMatrix::from_diagonal(&DVector::from_column_slice(z)) * m.transpose()
}

/// Asserts that the filter's state equals `b` to `tol` (relative to the largest |z|).
fn assert_state_close(f: &BinghamFilter, b: &Bingham, tol: f64, what: &str) {
    let d = f.dim();
    let (m, z) = state_of(f);
    let scale = b.z().amax().max(1.0);
    for (i, (&zi, &bi)) in z.iter().zip(b.z().iter()).enumerate() {
        // eigenvalues are accurate relative to the largest one
        let rel = (zi - bi).abs() / bi.abs().max(1e-2 * scale).max(1.0);
        assert!(rel <= tol, "{what}: z[{i}] = {zi} vs {bi} (rel {rel:e})");
    }
    let p = precision(d, &m, &z);
    let q = precision(d, &b.m_row_major(), b.z().as_slice());
    let err = (p - q).amax() / scale;
    assert!(err <= tol, "{what}: M Z Mᵀ differs by {err:e} (relative)");
    let mm = DMatrix::from_row_slice(d, d, &m);
    let orth = (mm.transpose() * &mm - DMatrix::identity(d, d)).amax();
    assert!(orth < 1e-14, "{what}: M not orthonormal ({orth:e})");
    for i in 0..d - 1 {
        assert!(z[i] <= z[i + 1], "{what}: z not ascending: {z:?}");
    }
    assert_eq!(z[d - 1], 0.0);
}

fn noise_bingham(d: usize, m: &[f64], z: &[f64]) -> Bingham {
    Bingham::from_row_major(d, m, z).unwrap()
}

/// The likelihood Bingham of the general path: `M_L = L(ẑ) D M_v`.
fn likelihood(d: usize, zhat: &[f64], mv: &[f64], zv: &[f64]) -> Bingham {
    let mut dm = DMatrix::from_row_slice(d, d, mv);
    for i in 1..d {
        dm.row_mut(i).neg_mut();
    }
    let zh = normalized(zhat);
    Bingham::new(left_matrix(&zh) * dm, DVector::from_column_slice(zv)).unwrap()
}

#[test]
fn new_rejects_other_dimensions() {
    for d in [0usize, 1, 3, 5, 8] {
        let m = vec![0.0; d * d];
        let z = vec![0.0; d];
        assert!(matches!(
            BinghamFilter::new(d, &m, &z),
            Err(Error::InvalidDimension(_))
        ));
    }
    let f = BinghamFilter::new(2, &[0.0, 1.0, 1.0, 0.0], &[3.0, 1.0]).unwrap();
    assert_eq!(f.dim(), 2);
    // sorted and shifted, the columns permuted along: the column (0, 1) has the larger z
    let (m, z) = state_of(&f);
    assert_eq!(z, vec![-2.0, 0.0]);
    assert_eq!(f.mode(), vec![0.0, 1.0]);
    assert_eq!(m, vec![1.0, 0.0, 0.0, 1.0]);
    let b = f.state();
    assert_eq!(b.z().as_slice(), &[-2.0, 0.0]);
    let g = BinghamFilter::from_bingham(&b).unwrap();
    assert_eq!(bits(&g), bits(&f));
}

/// Every predict, predict_rotation and update along simulated runs agrees with the general
/// (allocating) core operations applied to the same prior.
fn agrees_with_general_path(sc: &Scenario, runs: u64) {
    let d = sc.d;
    let wn = noise_bingham(d, &sc.mw, &sc.zw);
    let mut rng = StdRng::seed_from_u64(5);
    let mut worst_p: f64 = 0.0;
    for run in 0..runs {
        let (_, meas) = simulate(sc, run);
        let mut f = BinghamFilter::new(d, &sc.m0, &sc.z0).unwrap();
        for (k, z) in meas.iter().enumerate() {
            let prior = f.state();
            if k % 3 == 2 {
                let u = random_unit(&mut rng, d);
                f.predict_rotation(&u, &sc.mw, &sc.zw).unwrap();
                let expect = prior.rotate_right(&u).unwrap().compose(&wn).unwrap();
                assert_state_close(&f, &expect, 1e-12, "predict_rotation");
            } else {
                f.predict(&sc.mw, &sc.zw).unwrap();
                let expect = prior.compose(&wn).unwrap();
                assert_state_close(&f, &expect, 1e-12, "predict");
            }
            worst_p = worst_p.max(f.state().z().amax());
            let predicted = f.state();
            f.update(z, &sc.mv, &sc.zv).unwrap();
            let expect = predicted
                .multiply(&likelihood(d, z, &sc.mv, &sc.zv))
                .unwrap();
            assert_state_close(&f, &expect, 1e-13, "update");
        }
    }
    assert!(worst_p > 1.0);
}

#[test]
fn agrees_with_the_general_path_in_the_scenarios() {
    agrees_with_general_path(&scenario_2d(), 5);
    agrees_with_general_path(&scenario_4d(), 3);
}

#[test]
fn agrees_with_the_general_path_for_random_states_and_noises() {
    let mut rng = StdRng::seed_from_u64(17);
    for d in [2usize, 4] {
        for case in 0..60 {
            let (lo, hi) = [(-1.0, 1.0), (0.0, 3.0), (2.0, 6.0)][case % 3];
            let m0 = random_rotation(&mut rng, d);
            let z0 = random_z(&mut rng, d, lo, hi);
            let mw = random_rotation(&mut rng, d);
            let zw = random_z(&mut rng, d, 0.0, 4.0);
            let mv = random_rotation(&mut rng, d);
            let zv = random_z(&mut rng, d, -1.0, 4.0);
            let prior = Bingham::new(m0.clone(), DVector::from_vec(z0.clone())).unwrap();
            let mut f = BinghamFilter::new(d, &row_major(&m0), &z0).unwrap();
            let (mwr, mvr) = (row_major(&mw), row_major(&mv));
            f.predict(&mwr, &zw).unwrap();
            let expect = prior.compose(&noise_bingham(d, &mwr, &zw)).unwrap();
            assert_state_close(&f, &expect, 1e-12, "random predict");
            let zhat = random_unit(&mut rng, d);
            let predicted = f.state();
            f.update(&zhat, &mvr, &zv).unwrap();
            let expect = predicted
                .multiply(&likelihood(d, &zhat, &mvr, &zv))
                .unwrap();
            assert_state_close(&f, &expect, 1e-13, "random update");
        }
    }
}

#[test]
fn update_at_the_mode_with_aligned_noise_adds_concentrations() {
    let mut rng = StdRng::seed_from_u64(23);
    for d in [2usize, 4] {
        for _ in 0..20 {
            let m = random_rotation(&mut rng, d);
            let z = random_z(&mut rng, d, -1.0, 3.0);
            let mut f = BinghamFilter::new(d, &row_major(&m), &z).unwrap();
            let (m, z) = state_of(&f);
            let mode = f.mode();
            // M_v = D L(ẑ)ᵀ M: the likelihood's directions L(ẑ) D M_v are exactly M
            let mut mv = left_matrix(&mode).transpose() * DMatrix::from_row_slice(d, d, &m);
            for i in 1..d {
                mv.row_mut(i).neg_mut();
            }
            let zv = random_z(&mut rng, d, -1.0, 3.0);
            f.update(&mode, &row_major(&mv), &zv).unwrap();
            let (m2, z2) = state_of(&f);
            let mut expect: Vec<f64> = z.iter().zip(&zv).map(|(a, b)| a + b).collect();
            expect.sort_by(f64::total_cmp);
            for i in 0..d {
                assert!((z2[i] - expect[i]).abs() <= 1e-12 * expect[i].abs().max(1.0));
            }
            assert!(axial_error(&f.mode(), &mode) < 1e-12, "mode moved");
            let sum: Vec<f64> = z.iter().zip(&zv).map(|(a, b)| a + b).collect();
            let err = (precision(d, &m2, &z2) - precision(d, &m, &sum)).amax();
            assert!(err <= 1e-12 * expect[0].abs().max(1.0), "{err:e}");
        }
    }
}

#[test]
fn predict_with_identity_mode_noise_keeps_m_and_lowers_concentrations() {
    let mut rng = StdRng::seed_from_u64(29);
    for d in [2usize, 4] {
        for _ in 0..20 {
            let m = random_rotation(&mut rng, d);
            let z = random_z(&mut rng, d, -0.5, 3.0);
            let mut f = BinghamFilter::new(d, &row_major(&m), &z).unwrap();
            let (m0, z0) = state_of(&f);
            // identity mode; isotropic about it for d = 4 (for d = 2 any noise is)
            let mw = random_rotation(&mut rng, d);
            let mut mw = mw.clone();
            if d == 4 {
                let mut q = DMatrix::identity(4, 4);
                q.view_mut((1, 1), (3, 3))
                    .copy_from(&random_rotation(&mut rng, 3));
                mw = q;
            } else {
                mw.copy_from(&DMatrix::identity(2, 2));
            }
            // put the mode (e_1) last
            let mut mwr = DMatrix::zeros(d, d);
            for j in 0..d {
                mwr.set_column(j, &mw.column((j + 1) % d));
            }
            let c = -(10f64.powf(rng.gen::<f64>() * 3.0));
            let mut zw = vec![c; d];
            zw[d - 1] = 0.0;
            f.predict(&row_major(&mwr), &zw).unwrap();
            let (m1, z1) = state_of(&f);
            for i in 0..d - 1 {
                assert!(z1[i] > z0[i], "|z| not lowered: {z0:?} -> {z1:?}");
                assert!(z1[i] <= 0.0);
            }
            // same principal directions (up to sign) where the concentrations are distinct
            let m0 = DMatrix::from_row_slice(d, d, &m0);
            let m1 = DMatrix::from_row_slice(d, d, &m1);
            for j in 0..d {
                let gap = (0..d)
                    .filter(|&i| i != j)
                    .map(|i| (z0[i] - z0[j]).abs())
                    .fold(f64::INFINITY, f64::min);
                if gap > 1e-3 * z0[0].abs() {
                    let dot = m0.column(j).dot(&m1.column(j)).abs();
                    assert!(
                        (1.0 - dot) < 1e-12,
                        "column {j} moved: 1 - |dot| = {:e}",
                        1.0 - dot
                    );
                }
            }
        }
    }
}

/// `log p(ẑ)` by brute force for d = 2: `∫ f_state(x(θ)) f_v(x(θ)⁻¹ ⊕ ẑ) dθ` (trapezoid rule,
/// spectrally accurate for the periodic integrand).
fn brute_force_log_likelihood_2d(state: &Bingham, zhat: &[f64], noise: &Bingham) -> f64 {
    let n = 20000;
    let mut s = 0.0;
    for k in 0..n {
        let th = 2.0 * PI * k as f64 / n as f64;
        let x = [th.cos(), th.sin()];
        let v = compose(&conjugate(&x), zhat).unwrap();
        s += state.pdf(&x).unwrap() * noise.pdf(&v).unwrap();
    }
    (s * 2.0 * PI / n as f64).ln()
}

#[test]
fn log_likelihood_matches_brute_force_integration_d2() {
    let mut rng = StdRng::seed_from_u64(31);
    for case in 0..40 {
        let m = random_rotation(&mut rng, 2);
        let z = random_z(&mut rng, 2, -1.0, 2.5);
        let mv = random_rotation(&mut rng, 2);
        let zv = random_z(&mut rng, 2, -1.0, 2.5);
        let zhat = random_unit(&mut rng, 2);
        let f = BinghamFilter::new(2, &row_major(&m), &z).unwrap();
        let ll = f.log_likelihood(&zhat, &row_major(&mv), &zv).unwrap();
        let bf = brute_force_log_likelihood_2d(
            &f.state(),
            &zhat,
            &noise_bingham(2, &row_major(&mv), &zv),
        );
        assert!((ll - bf).abs() < 1e-10, "case {case}: {ll} vs {bf}");
        // a density of the measurement on the circle: antipodally symmetric
        let neg: Vec<f64> = zhat.iter().map(|v| -v).collect();
        let ll2 = f.log_likelihood(&neg, &row_major(&mv), &zv).unwrap();
        assert!((ll - ll2).abs() < 1e-12);
    }
    // it integrates to 1 over the measurement circle
    let f = BinghamFilter::new(2, &[1.0, 0.0, 0.0, 1.0], &[-3.0, 0.0]).unwrap();
    let n = 4000;
    let total: f64 = (0..n)
        .map(|k| {
            let th = 2.0 * PI * k as f64 / n as f64;
            f.log_likelihood(&[th.cos(), th.sin()], &[0.0, 1.0, 1.0, 0.0], &[-5.0, 0.0])
                .unwrap()
                .exp()
        })
        .sum::<f64>()
        * 2.0
        * PI
        / n as f64;
    assert!((total - 1.0).abs() < 1e-12, "∫ p(ẑ) dẑ = {total}");
}

#[test]
fn log_likelihood_matches_monte_carlo_d4() {
    let mut rng = StdRng::seed_from_u64(37);
    for _ in 0..6 {
        let m = random_rotation(&mut rng, 4);
        let z = random_z(&mut rng, 4, -0.5, 1.3);
        let mv = random_rotation(&mut rng, 4);
        let zv = random_z(&mut rng, 4, -0.5, 1.3);
        let zhat = random_unit(&mut rng, 4);
        let f = BinghamFilter::new(4, &row_major(&m), &z).unwrap();
        let ll = f.log_likelihood(&zhat, &row_major(&mv), &zv).unwrap();
        let noise = noise_bingham(4, &row_major(&mv), &zv);
        let log_fv = noise.log_normalization().unwrap();
        let pv = precision(4, &noise.m_row_major(), noise.z().as_slice());
        let n = 200_000;
        let vals: Vec<f64> = f
            .state()
            .sample(&mut rng, n)
            .iter()
            .map(|x| {
                let v = DVector::from_vec(compose(&conjugate(x.as_slice()), &zhat).unwrap());
                (v.dot(&(&pv * &v)) - log_fv).exp()
            })
            .collect();
        let mean = vals.iter().sum::<f64>() / n as f64;
        let var = vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let se = (var / n as f64).sqrt();
        assert!(
            (ll.exp() - mean).abs() < 5.0 * se,
            "p = {} vs Monte Carlo {mean} ± {se}",
            ll.exp()
        );
    }
}

#[test]
fn sharp_states_predict_and_update_stay_finite() {
    for d in [2usize, 4] {
        let eye: Vec<f64> = (0..d * d)
            .map(|k| if k / d == k % d { 1.0 } else { 0.0 })
            .collect();
        let sc = if d == 2 { scenario_2d() } else { scenario_4d() };
        for &zs in &[-1e8, -1e12, -1e15, -1e30, -1e200] {
            let mut z = vec![zs; d];
            z[d - 1] = 0.0;
            let mut f = BinghamFilter::new(d, &eye, &z).unwrap();
            // sharp noise as well: the capped state keeps the composed moment non-singular
            let mut zw = vec![zs; d];
            zw[d - 1] = 0.0;
            f.predict(&sc.mw, &zw).unwrap();
            let (m, z1) = state_of(&f);
            assert!(z1.iter().all(|v| v.is_finite()));
            assert!(z1[0] >= -1.01 * MAX_CONCENTRATION, "{z1:?}");
            let mm = DMatrix::from_row_slice(d, d, &m);
            assert!((mm.transpose() * &mm - DMatrix::identity(d, d)).amax() < 1e-14);
            // ordinary noise after it
            f.predict(&sc.mw, &sc.zw).unwrap();
            // repeated sharp updates at the truth
            let mut zv = vec![zs; d];
            zv[d - 1] = 0.0;
            let truth = f.mode();
            for _ in 0..200 {
                f.update(&truth, &sc.mv, &zv).unwrap();
                let (m, z) = state_of(&f);
                assert!(z.iter().all(|v| v.is_finite()), "{z:?}");
                let mm = DMatrix::from_row_slice(d, d, &m);
                assert!((mm.transpose() * &mm - DMatrix::identity(d, d)).amax() < 1e-14);
            }
            assert!(axial_error(&f.mode(), &truth) < 1e-9);
            f.predict(&sc.mw, &sc.zw).unwrap();
            f.predict(&sc.mw, &zw).unwrap();
            assert!(f
                .log_likelihood(&truth, &sc.mv, &sc.zv)
                .unwrap()
                .is_finite());
        }
        // overflow of the concentrations is reported, the state unchanged
        let mut z = vec![-1.5e308; d];
        z[d - 1] = 0.0;
        let mut f = BinghamFilter::new(d, &eye, &z).unwrap();
        let before = bits(&f);
        let mode = f.mode();
        assert!(matches!(
            f.update(&mode, &eye, &z),
            Err(Error::Numerical(_))
        ));
        assert_eq!(bits(&f), before);
    }
}

#[test]
fn failed_calls_change_nothing() {
    for sc in [scenario_2d(), scenario_4d()] {
        let d = sc.d;
        let mut f = BinghamFilter::new(d, &sc.m0, &sc.z0).unwrap();
        f.predict(&sc.mw, &sc.zw).unwrap();
        f.update(&sc.x0, &sc.mv, &sc.zv).unwrap();
        let before = bits(&f);
        let mut bad_m = sc.mw.clone();
        bad_m[0] += 1e-3;
        let mut nan_m = sc.mw.clone();
        nan_m[d] = f64::NAN;
        let mut inf_z = sc.zw.clone();
        inf_z[0] = f64::NEG_INFINITY;
        let short = &sc.zw[..d - 1];
        let long_m = [sc.mw.clone(), vec![0.0]].concat();
        let nonunit: Vec<f64> = sc.x0.iter().map(|v| v * (1.0 + 2e-3)).collect();
        let nan_x: Vec<f64> = sc.x0.iter().map(|_| f64::NAN).collect();
        let zero = vec![0.0; d];
        // finite, but z − max z overflows
        let mut span = vec![0.0; d];
        span[0] = f64::MAX;
        span[d - 1] = -f64::MAX;
        type Call<'a> = Box<dyn Fn(&mut BinghamFilter) -> bingham::Result<()> + 'a>;
        let calls: Vec<(&str, Call)> = vec![
            (
                "predict non-orthogonal",
                Box::new(|f| f.predict(&bad_m, &sc.zw)),
            ),
            ("predict NaN M", Box::new(|f| f.predict(&nan_m, &sc.zw))),
            ("predict Inf z", Box::new(|f| f.predict(&sc.mw, &inf_z))),
            ("predict short z", Box::new(|f| f.predict(&sc.mw, short))),
            ("predict long M", Box::new(|f| f.predict(&long_m, &sc.zw))),
            (
                "rotation non-unit",
                Box::new(|f| f.predict_rotation(&nonunit, &sc.mw, &sc.zw)),
            ),
            (
                "rotation NaN",
                Box::new(|f| f.predict_rotation(&nan_x, &sc.mw, &sc.zw)),
            ),
            (
                "rotation zero",
                Box::new(|f| f.predict_rotation(&zero, &sc.mw, &sc.zw)),
            ),
            (
                "rotation bad noise",
                Box::new(|f| f.predict_rotation(&sc.x0, &bad_m, &sc.zw)),
            ),
            (
                "update non-unit",
                Box::new(|f| f.update(&nonunit, &sc.mv, &sc.zv)),
            ),
            ("update NaN", Box::new(|f| f.update(&nan_x, &sc.mv, &sc.zv))),
            (
                "update short",
                Box::new(|f| f.update(&sc.x0[..d - 1], &sc.mv, &sc.zv)),
            ),
            (
                "update non-orthogonal",
                Box::new(|f| f.update(&sc.x0, &bad_m, &sc.zv)),
            ),
            (
                "update Inf z",
                Box::new(|f| f.update(&sc.x0, &sc.mv, &inf_z)),
            ),
            (
                "set_state non-orthogonal",
                Box::new(|f| f.set_state(&bad_m, &sc.z0)),
            ),
            ("set_state NaN", Box::new(|f| f.set_state(&nan_m, &sc.z0))),
            ("set_state short", Box::new(|f| f.set_state(&sc.m0, short))),
            ("set_state z span", Box::new(|f| f.set_state(&sc.m0, &span))),
            ("predict z span", Box::new(|f| f.predict(&sc.mw, &span))),
            (
                "update z span",
                Box::new(|f| f.update(&sc.x0, &sc.mv, &span)),
            ),
        ];
        for (what, call) in &calls {
            assert!(call(&mut f).is_err(), "{what} should fail");
            assert_eq!(bits(&f), before, "{what} changed the state");
        }
        assert!(matches!(
            BinghamFilter::new(d, &sc.m0, &span),
            Err(Error::InvalidArgument(_))
        ));
        assert!(f.log_likelihood(&nonunit, &sc.mv, &sc.zv).is_err());
        assert!(f.log_likelihood(&sc.x0, &bad_m, &sc.zv).is_err());
        let mut small = vec![0.0; d * d - 1];
        assert!(f.state_into(&mut small, &mut vec![0.0; d]).is_err());
        assert!(f.mode_into(&mut vec![0.0; d + 1]).is_err());
        // the filter still works, and as if nothing had happened
        let mut g = BinghamFilter::new(d, &sc.m0, &sc.z0).unwrap();
        g.predict(&sc.mw, &sc.zw).unwrap();
        g.update(&sc.x0, &sc.mv, &sc.zv).unwrap();
        f.predict(&sc.mw, &sc.zw).unwrap();
        g.predict(&sc.mw, &sc.zw).unwrap();
        assert_eq!(bits(&f), bits(&g));
    }
}

#[test]
fn noise_cache_follows_changing_noise_and_clones_are_independent() {
    let mut rng = StdRng::seed_from_u64(41);
    for d in [2usize, 4] {
        let m0 = row_major(&random_rotation(&mut rng, d));
        let z0 = random_z(&mut rng, d, 0.0, 2.0);
        let noises: Vec<(Vec<f64>, Vec<f64>)> = (0..3)
            .map(|_| {
                (
                    row_major(&random_rotation(&mut rng, d)),
                    random_z(&mut rng, d, 0.0, 3.0),
                )
            })
            .collect();
        let zhat = random_unit(&mut rng, d);
        let mut f = BinghamFilter::new(d, &m0, &z0).unwrap();
        for (k, (mw, zw)) in noises.iter().cycle().take(9).enumerate() {
            let prior = f.state();
            f.predict(mw, zw).unwrap();
            let expect = prior.compose(&noise_bingham(d, mw, zw)).unwrap();
            assert_state_close(&f, &expect, 1e-12, "changing process noise");
            let (mv, zv) = &noises[(k + 1) % 3];
            let predicted = f.state();
            let ll = f.log_likelihood(&zhat, mv, zv).unwrap();
            let g = f.clone();
            f.update(&zhat, mv, zv).unwrap();
            assert_eq!(ll, g.log_likelihood(&zhat, mv, zv).unwrap());
            let expect = predicted.multiply(&likelihood(d, &zhat, mv, zv)).unwrap();
            assert_state_close(&f, &expect, 1e-13, "changing measurement noise");
            assert_ne!(bits(&f), bits(&g), "the clone is independent");
        }
        // a clone evolves exactly like the original
        let mut g = f.clone();
        for (mw, zw) in &noises {
            f.predict(mw, zw).unwrap();
            g.predict(mw, zw).unwrap();
            f.update(&zhat, mw, zw).unwrap();
            g.update(&zhat, mw, zw).unwrap();
        }
        assert_eq!(bits(&f), bits(&g));
        // set_state resets to exactly the behaviour of a fresh filter
        f.set_state(&m0, &z0).unwrap();
        let mut h = BinghamFilter::new(d, &m0, &z0).unwrap();
        assert_eq!(bits(&f), bits(&h));
        f.predict(&noises[0].0, &noises[0].1).unwrap();
        h.predict(&noises[0].0, &noises[0].1).unwrap();
        assert_eq!(bits(&f), bits(&h));
    }
}

#[test]
fn exact_measurements_converge_to_the_truth() {
    let mut rng = StdRng::seed_from_u64(43);
    for sc in [scenario_2d(), scenario_4d()] {
        let truth = random_unit(&mut rng, sc.d);
        let mut f = BinghamFilter::new(sc.d, &sc.m0, &sc.z0).unwrap();
        // the error shrinks by a constant factor per step (about 0.9 for d = 2)
        for _ in 0..300 {
            f.predict(&sc.mw, &sc.zw).unwrap();
            f.update(&truth, &sc.mv, &sc.zv).unwrap();
        }
        assert!(axial_error(&truth, &f.mode()) < 1e-9);
    }
}

/// JAIF Fig. 4: over 100 Monte Carlo runs, the Bingham filter's mean RMSE is below the adapted
/// Kalman filter's, in both scenarios.
#[test]
fn scenarios_bingham_beats_kalman() {
    for sc in [scenario_2d(), scenario_4d()] {
        let kf = Kalman::new(&sc, 100_000);
        let runs = 100;
        let (mut sum_b, mut sum_k, mut wins) = (0.0, 0.0, 0);
        for run in 0..runs {
            let (truth, meas) = simulate(&sc, run);
            let rb = rmse(&run_bingham(&sc, &truth, &meas));
            let rk = rmse(&run_kalman(&kf, &truth, &meas));
            sum_b += rb;
            sum_k += rk;
            if rb < rk {
                wins += 1;
            }
        }
        let (mb, mk) = (sum_b / runs as f64, sum_k / runs as f64);
        println!(
            "d = {}: mean RMSE Bingham {mb:.4} rad, Kalman {mk:.4} rad; Bingham better in {wins} of {runs} runs",
            sc.d
        );
        assert!(mb < mk, "d = {}: Bingham {mb} vs Kalman {mk}", sc.d);
        assert!(wins > runs / 2);
    }
}

#[test]
fn filter_is_send_and_sync() {
    fn check<T: Send + Sync + Clone + std::fmt::Debug>() {}
    check::<BinghamFilter>();
}

/// `set_state` with what `state` returned reproduces the state bit for bit (the library's `M`
/// is orthonormal to a few ulps and is kept as it is), at every step of both scenarios.
#[test]
fn state_round_trip_is_bit_identical() {
    for sc in [scenario_2d(), scenario_4d()] {
        let (_, meas) = simulate(&sc, 0);
        let mut f = BinghamFilter::new(sc.d, &sc.m0, &sc.z0).unwrap();
        for y in meas.iter().take(30) {
            f.predict(&sc.mw, &sc.zw).unwrap();
            f.update(y, &sc.mv, &sc.zv).unwrap();
            let (m, z) = state_of(&f);
            let mut g = f.clone();
            g.set_state(&m, &z).unwrap();
            assert_eq!(bits(&g), bits(&f), "d = {}", sc.d);
        }
    }
}
