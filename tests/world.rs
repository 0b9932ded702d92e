//! World-frame steps of the first-order filter (`predict_world`, `update_world`,
//! `log_likelihood_world`; Glover & Kaelbling 2013): the second moment after a prediction
//! against the composition written out with quaternion products, the update against
//! `Bingham::multiply` with the likelihood written out, the predictive density against a Monte
//! Carlo integral, the d = 2 and isotropic cases against the body-frame steps, and the failure
//! contract.

use bingham::filter::BinghamFilter;
use bingham::quaternion::{compose, conjugate, left_matrix};
use bingham::{Bingham, Error};
use nalgebra::{DMatrix, DVector};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

fn random_rotation(rng: &mut StdRng, d: usize) -> Vec<f64> {
    let g = DMatrix::from_fn(d, d, |_, _| rng.gen::<f64>() - 0.5);
    g.qr().q().transpose().as_slice().to_vec()
}

fn random_unit(rng: &mut StdRng, d: usize) -> Vec<f64> {
    let v: Vec<f64> = (0..d).map(|_| rng.gen::<f64>() - 0.5).collect();
    let n = v.iter().map(|a| a * a).sum::<f64>().sqrt();
    v.iter().map(|a| a / n).collect()
}

fn state(f: &BinghamFilter) -> Bingham {
    f.state()
}

fn precision(b: &Bingham) -> DMatrix<f64> {
    b.m() * DMatrix::from_diagonal(b.z()) * b.m().transpose()
}

/// `E[(w ∘ y)(w ∘ y)ᵀ]` for independent `w`, `y` with second moments `b`, `a`: `w ∘ y = L(w) y`
/// and `L(w) = Σ_a w_a L(e_a)`, so the moment is `Σ_ab B_ab L(e_a) A L(e_b)ᵀ`.
fn left_composition(b: &DMatrix<f64>, a: &DMatrix<f64>) -> DMatrix<f64> {
    let d = a.nrows();
    let basis: Vec<DMatrix<f64>> = (0..d)
        .map(|k| {
            let mut e = vec![0.0; d];
            e[k] = 1.0;
            left_matrix(&e)
        })
        .collect();
    let mut c = DMatrix::zeros(d, d);
    for i in 0..d {
        for j in 0..d {
            c += b[(i, j)] * &basis[i] * a * basis[j].transpose();
        }
    }
    c
}

#[test]
fn predict_world_second_moment_is_the_left_composition() {
    let mut rng = StdRng::seed_from_u64(3);
    for d in [2usize, 4] {
        for case in 0..10 {
            let m = random_rotation(&mut rng, d);
            let m_w = random_rotation(&mut rng, d);
            let mut z: Vec<f64> = (0..d).map(|_| -200.0 * rng.gen::<f64>()).collect();
            z[0] = 0.0;
            let mut z_w: Vec<f64> = (0..d).map(|_| -400.0 * rng.gen::<f64>() - 1.0).collect();
            z_w[case % d] = 0.0;
            let u = random_unit(&mut rng, d);
            let mut f = BinghamFilter::new(d, &m, &z).unwrap();
            let a = state(&f).second_moment().unwrap();
            let b = Bingham::from_row_major(d, &m_w, &z_w)
                .unwrap()
                .second_moment()
                .unwrap();
            let lu = left_matrix(&u);
            let want = left_composition(&b, &(&lu * &a * lu.transpose()));
            f.predict_world(Some(&u), &m_w, &z_w).unwrap();
            let got = state(&f).second_moment().unwrap();
            let err = (&got - &want).amax();
            assert!(err < 1e-10, "d = {d}, case {case}: moment error {err:e}");
        }
    }
}

/// Monte Carlo: the sample second moment of `w ∘ u ∘ x` with anisotropic noise (the paper's
/// Λ's) against the state after `predict_world`, within 5 standard errors per entry; and the
/// body-frame prediction differs from it (the frames matter for anisotropic noise).
#[test]
fn predict_world_against_sampled_compositions() {
    let mut rng = StdRng::seed_from_u64(9);
    let m = random_rotation(&mut rng, 4);
    let z = [-80.0, -30.0, -5.0, 0.0];
    let id: Vec<f64> = DMatrix::<f64>::identity(4, 4).as_slice().to_vec();
    for z_w in [[0.0, -10.0, -10.0, -1.0], [0.0, -400.0, -400.0, -10.0]] {
        let u = random_unit(&mut rng, 4);
        let mut f = BinghamFilter::new(4, &m, &z).unwrap();
        let mut g = f.clone();
        f.predict_world(Some(&u), &id, &z_w).unwrap();
        g.predict_rotation(&u, &id, &z_w).unwrap();
        let bx = Bingham::from_row_major(4, &m, &z).unwrap();
        let bw = Bingham::from_row_major(4, &id, &z_w).unwrap();
        let n = 200_000;
        let xs = bx.sample(&mut rng, n);
        let ws = bw.sample(&mut rng, n);
        let (mut s1, mut s2) = (DMatrix::zeros(4, 4), DMatrix::zeros(4, 4));
        for (x, w) in xs.iter().zip(&ws) {
            let y = compose(w.as_slice(), &compose(&u, x.as_slice()).unwrap()).unwrap();
            let y = DVector::from_vec(y);
            let o = &y * y.transpose();
            s2 += o.component_mul(&o);
            s1 += o;
        }
        let mean = &s1 / n as f64;
        let var = &s2 / n as f64 - mean.component_mul(&mean);
        let got = state(&f).second_moment().unwrap();
        let body = state(&g).second_moment().unwrap();
        let mut worst: f64 = 0.0;
        let mut body_worst: f64 = 0.0;
        for k in 0..16 {
            let se = (var[k] / n as f64).sqrt().max(1e-12);
            worst = worst.max((got[k] - mean[k]).abs() / se);
            body_worst = body_worst.max((body[k] - mean[k]).abs() / se);
        }
        assert!(worst < 5.0, "z_w = {z_w:?}: {worst:.1} SE from the samples");
        assert!(
            body_worst > 20.0,
            "z_w = {z_w:?}: the body frame is only {body_worst:.1} SE off"
        );
    }
}

#[test]
fn world_equals_body_for_d2_and_for_isotropic_noise_without_control() {
    let mut rng = StdRng::seed_from_u64(4);
    let m2 = random_rotation(&mut rng, 2);
    let (mut f, mut g) = (
        BinghamFilter::new(2, &m2, &[-30.0, 0.0]).unwrap(),
        BinghamFilter::new(2, &m2, &[-30.0, 0.0]).unwrap(),
    );
    let u = random_unit(&mut rng, 2);
    let mw = random_rotation(&mut rng, 2);
    f.predict_world(Some(&u), &mw, &[-50.0, 0.0]).unwrap();
    g.predict_rotation(&u, &mw, &[-50.0, 0.0]).unwrap();
    let y = random_unit(&mut rng, 2);
    f.update_world(&y, &mw, &[-20.0, 0.0]).unwrap();
    g.update(&y, &mw, &[-20.0, 0.0]).unwrap();
    let e = (precision(&state(&f)) - precision(&state(&g))).amax();
    assert!(e < 1e-9, "d = 2: {e:e}");

    let m4 = random_rotation(&mut rng, 4);
    let id: Vec<f64> = DMatrix::<f64>::identity(4, 4).as_slice().to_vec();
    let z_iso = [0.0, -200.0, -200.0, -200.0];
    let (mut f, mut g) = (
        BinghamFilter::new(4, &m4, &[-60.0, -20.0, -3.0, 0.0]).unwrap(),
        BinghamFilter::new(4, &m4, &[-60.0, -20.0, -3.0, 0.0]).unwrap(),
    );
    f.predict_world(None, &id, &z_iso).unwrap();
    g.predict(&id, &z_iso).unwrap();
    let e = (precision(&state(&f)) - precision(&state(&g))).amax();
    assert!(e < 1e-8 * 200.0, "isotropic d = 4: {e:e}");
}

/// `update_world` is `multiply` with `Bingham(x; Λo, V_o⁻¹ ∘ y)`, and `log_likelihood_world` is
/// `log ∫ f(x) f_v(y ∘ x⁻¹) dx`, checked by Monte Carlo over the state.
#[test]
fn update_world_is_the_product_with_the_written_out_likelihood() {
    let mut rng = StdRng::seed_from_u64(21);
    for case in 0..10 {
        let m = random_rotation(&mut rng, 4);
        let z = [-100.0 * rng.gen::<f64>(), -20.0, -2.0, 0.0];
        let m_v = random_rotation(&mut rng, 4);
        let z_v = [-40.0, -40.0, -10.0, 0.0];
        let y = random_unit(&mut rng, 4);
        let mut f = BinghamFilter::new(4, &m, &z).unwrap();
        let prior = state(&f);
        let ll = f.log_likelihood_world(&y, &m_v, &z_v).unwrap();
        f.update_world(&y, &m_v, &z_v).unwrap();

        let mv = DMatrix::from_row_slice(4, 4, &m_v);
        let mut ml = DMatrix::zeros(4, 4);
        for j in 0..4 {
            let v: Vec<f64> = mv.column(j).iter().copied().collect();
            ml.set_column(j, &DVector::from_vec(compose(&conjugate(&v), &y).unwrap()));
        }
        let lik = Bingham::new(ml, DVector::from_column_slice(&z_v)).unwrap();
        let want = prior.multiply(&lik).unwrap();
        let e = (precision(&state(&f)) - precision(&want)).amax() / 100.0;
        assert!(e < 1e-10, "case {case}: {e:e}");

        if case < 3 {
            let noise = Bingham::from_row_major(4, &m_v, &z_v).unwrap();
            let lf = noise.log_normalization().unwrap();
            let n = 400_000;
            let xs = prior.sample(&mut rng, n);
            let (mut s, mut s2) = (0.0, 0.0);
            for x in &xs {
                let r = compose(&y, &conjugate(x.as_slice())).unwrap();
                let p = (noise.log_pdf(&r).unwrap()).exp();
                s += p;
                s2 += p * p;
            }
            let mean = s / n as f64;
            let se = ((s2 / n as f64 - mean * mean) / n as f64).sqrt();
            let want_ll = mean.ln();
            let tol = 4.0 * se / mean;
            assert!(
                (ll - want_ll).abs() < tol,
                "case {case}: {ll} vs MC {want_ll} ± {tol} (log F_v {lf})"
            );
        }
    }
}

#[test]
fn world_steps_refuse_bad_input_and_change_nothing() {
    let id: Vec<f64> = DMatrix::<f64>::identity(4, 4).as_slice().to_vec();
    let mut f = BinghamFilter::new(4, &id, &[-5.0, -5.0, -5.0, 0.0]).unwrap();
    let before = state(&f);
    let z = [0.0, -10.0, -10.0, -1.0];
    assert!(matches!(
        f.predict_world(Some(&[1.0, 0.5, 0.0, 0.0]), &id, &z),
        Err(Error::InvalidArgument(_))
    ));
    assert!(f.predict_world(None, &id[..12], &z).is_err());
    assert!(f.update_world(&[f64::NAN, 0.0, 0.0, 1.0], &id, &z).is_err());
    assert!(f.update_world(&[1.0, 0.0, 0.0], &id, &z).is_err());
    assert!(f
        .log_likelihood_world(&[2.0, 0.0, 0.0, 0.0], &id, &z)
        .is_err());
    assert_eq!(precision(&state(&f)), precision(&before));
}
