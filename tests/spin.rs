//! The second-order quaternion Bingham filter (`bingham::filter::SpinFilter`, Glover &
//! Kaelbling 2013, Sec. 4): one step against the same step written with the distribution
//! operations (composition, inversion by the conjugation, product), convergence to a noiseless
//! constant spin, the uniform orientation prior, prediction-only steps, the predictive density
//! against a Monte Carlo integral, and the failure contract.

use bingham::filter::{BinghamFilter, SpinFilter};
use bingham::quaternion::{compose, conjugate, q4};
use bingham::{Bingham, Error};
use nalgebra::{DMatrix, DVector};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

const I4: [f64; 16] = [
    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
];

/// `M` whose last column is `q` (the mode), from `left_matrix(q)` (orthogonal for unit `q`):
/// columns `q ∘ e_1, q ∘ e_2, q ∘ e_3, q` with concentrations `(z1, z2, z3, 0)` along them.
fn m_with_mode(q: &[f64; 4]) -> Vec<f64> {
    let l = bingham::quaternion::left_matrix(q);
    // columns of L(q) are q ∘ e_k; put q ∘ e_0 = q last
    let cols = [1usize, 2, 3, 0];
    let mut m = vec![0.0; 16];
    for (j, &c) in cols.iter().enumerate() {
        for i in 0..4 {
            m[i * 4 + j] = l[(i, c)];
        }
    }
    m
}

fn random_unit(rng: &mut StdRng) -> [f64; 4] {
    let v: Vec<f64> = (0..4).map(|_| rng.gen::<f64>() - 0.5).collect();
    let n = v.iter().map(|a| a * a).sum::<f64>().sqrt();
    [v[0] / n, v[1] / n, v[2] / n, v[3] / n]
}

fn random_rotation(rng: &mut StdRng) -> Vec<f64> {
    let g = DMatrix::from_fn(4, 4, |_, _| rng.gen::<f64>() - 0.5);
    g.qr().q().transpose().as_slice().to_vec()
}

fn angle(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    let d: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    2.0 * d.abs().min(1.0).acos()
}

fn precision(b: &Bingham) -> DMatrix<f64> {
    b.m() * DMatrix::from_diagonal(b.z()) * b.m().transpose()
}

fn assert_same(a: &Bingham, b: &Bingham, tol: f64, what: &str) {
    let (pa, pb) = (precision(a), precision(b));
    let scale = a.z().amax().max(1.0);
    let err = (&pa - &pb).amax() / scale;
    assert!(err < tol, "{what}: relative difference {err:e}\n{pa}\n{pb}");
}

/// The observation likelihood in `x` written out: `Bingham(x; Λo, V_o⁻¹ ∘ y)`.
fn likelihood(y: &[f64], m_o: &[f64], z_o: &[f64]) -> Bingham {
    let m = DMatrix::from_row_slice(4, 4, m_o);
    let mut ml = DMatrix::zeros(4, 4);
    for j in 0..4 {
        let v: Vec<f64> = m.column(j).iter().copied().collect();
        let c = compose(&conjugate(&v), y).unwrap();
        ml.set_column(j, &DVector::from_vec(c));
    }
    Bingham::new(ml, DVector::from_column_slice(z_o)).unwrap()
}

/// `Bingham(D M, Z)`: the distribution of `x⁻¹`.
fn inverse(b: &Bingham) -> Bingham {
    let mut m = b.m().clone();
    for mut row in m.row_iter_mut().skip(1) {
        row.neg_mut();
    }
    Bingham::new(m, b.z().clone()).unwrap()
}

#[test]
fn one_step_equals_the_distribution_operations() {
    let mut rng = StdRng::seed_from_u64(7);
    for case in 0..20 {
        let (m_x, m_v, m_w, m_o) = (
            random_rotation(&mut rng),
            random_rotation(&mut rng),
            random_rotation(&mut rng),
            random_rotation(&mut rng),
        );
        let z_x = [
            -30.0 - 100.0 * rng.gen::<f64>(),
            -20.0,
            -5.0 * rng.gen::<f64>(),
            0.0,
        ];
        let z_v = [-50.0, -10.0 - 20.0 * rng.gen::<f64>(), -3.0, 0.0];
        let z_w = [-400.0, -200.0, -100.0 * rng.gen::<f64>() - 1.0, 0.0];
        let z_o = [-40.0, -40.0, -10.0, 0.0];
        let u = random_unit(&mut rng);
        let y = random_unit(&mut rng);
        let bx = Bingham::from_row_major(4, &m_x, &z_x).unwrap();
        let bv = Bingham::from_row_major(4, &m_v, &z_v).unwrap();
        let bw = Bingham::from_row_major(4, &m_w, &z_w).unwrap();

        let mut f = SpinFilter::new(&m_x, &z_x, &m_v, &z_v).unwrap();
        let observe = case % 4 != 3;
        let yo = observe.then_some(&y[..]);
        f.step(Some(&u), &m_w, &z_w, yo, &m_o, &z_o).unwrap();

        let prior_x = bv.compose(&bx).unwrap();
        let (want_x, want_v_post) = if observe {
            let lik = likelihood(&y, &m_o, &z_o);
            let g = lik.compose(&inverse(&bx)).unwrap();
            (prior_x.multiply(&lik).unwrap(), bv.multiply(&g).unwrap())
        } else {
            (prior_x, bv.clone())
        };
        let want_v = bw.compose(&want_v_post.rotate_left(&u).unwrap()).unwrap();
        assert_same(&f.orientation(), &want_x, 1e-9, &format!("case {case}: x"));
        assert_same(&f.spin(), &want_v, 1e-9, &format!("case {case}: v"));
    }
}

/// A noiseless constant spin observed every step: the spin's mode converges to the true spin.
#[test]
fn constant_spin_converges() {
    let mut rng = StdRng::seed_from_u64(11);
    for trial in 0..6 {
        let axis = {
            let v: Vec<f64> = (0..3).map(|_| rng.gen::<f64>() - 0.5).collect();
            let n = v.iter().map(|a| a * a).sum::<f64>().sqrt();
            [v[0] / n, v[1] / n, v[2] / n]
        };
        let rate = 0.3 + 1.2 * rng.gen::<f64>(); // rad per step (17–86°)
        let spin = q4::from_rotation_vector(&[axis[0] * rate, axis[1] * rate, axis[2] * rate]);
        let mut x = random_unit(&mut rng);
        let uniform = [0.0; 4];
        // spin prior centred on the identity, broad (the paper's Λ = (−3, −3, −3))
        let mut f = SpinFilter::new(
            &I4,
            &uniform,
            &m_with_mode(&[1.0, 0.0, 0.0, 0.0]),
            &[-3.0, -3.0, -3.0, 0.0],
        )
        .unwrap();
        let z_w = [0.0, -400.0, -400.0, -400.0];
        let z_o = [0.0, -400.0, -400.0, -400.0];
        let mut errs = vec![];
        let mut x_err = 0.0;
        for _ in 0..300 {
            f.step(None, &I4, &z_w, Some(&x), &I4, &z_o).unwrap();
            errs.push(angle(&f.spin_mode(), &spin));
            x_err = angle(&f.orientation_mode(), &x);
            x = q4::mul(&spin, &x);
        }
        let last = *errs.last().unwrap();
        assert!(
            last < 1e-6,
            "trial {trial}: spin error after 300 steps {last:e} (after 20: {:e}, 50: {:e})",
            errs[19],
            errs[49]
        );
        assert!(x_err < 1e-6, "trial {trial}: orientation error {x_err:e}");
    }
}

#[test]
fn uniform_orientation_prior_learns_nothing_about_spin_from_one_observation() {
    let z_v = [-3.0, -3.0, -3.0, 0.0];
    let m_v = m_with_mode(&[1.0, 0.0, 0.0, 0.0]);
    let mut f = SpinFilter::new(&I4, &[0.0; 4], &m_v, &z_v).unwrap();
    let y = [0.5, 0.5, 0.5, 0.5];
    let z_w = [0.0, -1e12, -1e12, -1e12]; // (nearly) no process noise
    f.step(None, &I4, &z_w, Some(&y), &I4, &[0.0, -40.0, -40.0, -10.0])
        .unwrap();
    // the orientation's mode is the observation (up to sign); the spin prior is unchanged
    assert!(angle(&f.orientation_mode(), &y) < 1e-9);
    let before = Bingham::from_row_major(4, &m_v, &z_v).unwrap();
    assert_same(&f.spin(), &before, 1e-6, "spin after one observation");
}

#[test]
fn log_likelihood_is_the_world_frame_predictive_density_of_the_composed_prior() {
    let mut rng = StdRng::seed_from_u64(5);
    let (m_x, m_v, m_o) = (
        random_rotation(&mut rng),
        random_rotation(&mut rng),
        random_rotation(&mut rng),
    );
    let z_x = [-60.0, -25.0, -8.0, 0.0];
    let z_v = [-40.0, -30.0, -5.0, 0.0];
    let z_o = [-40.0, -40.0, -10.0, 0.0];
    let f = SpinFilter::new(&m_x, &z_x, &m_v, &z_v).unwrap();
    let prior = Bingham::from_row_major(4, &m_v, &z_v)
        .unwrap()
        .compose(&Bingham::from_row_major(4, &m_x, &z_x).unwrap())
        .unwrap();
    let g = BinghamFilter::new(4, &prior.m_row_major(), prior.z().as_slice()).unwrap();
    for _ in 0..5 {
        let y = random_unit(&mut rng);
        let a = f.log_likelihood(&y, &m_o, &z_o).unwrap();
        let b = g.log_likelihood_world(&y, &m_o, &z_o).unwrap();
        assert!((a - b).abs() < 1e-9 * (1.0 + b.abs()), "{a} vs {b}");
    }
}

#[test]
fn failures_change_nothing() {
    let mut f =
        SpinFilter::new(&I4, &[-5.0, -5.0, -5.0, 0.0], &I4, &[-3.0, -3.0, -3.0, 0.0]).unwrap();
    let z_w = [0.0, -400.0, -400.0, -400.0];
    f.step(
        None,
        &I4,
        &z_w,
        Some(&[1.0, 0.0, 0.0, 0.0]),
        &I4,
        &[0.0, -40.0, -40.0, -10.0],
    )
    .unwrap();
    let snapshot = |f: &SpinFilter| {
        let (mut a, mut b, mut c, mut d) =
            (vec![0.0; 16], vec![0.0; 4], vec![0.0; 16], vec![0.0; 4]);
        f.state_into(&mut a, &mut b, &mut c, &mut d).unwrap();
        [a, b, c, d]
            .concat()
            .iter()
            .map(|v| v.to_bits())
            .collect::<Vec<_>>()
    };
    let before = snapshot(&f);
    let bad_y = [1.0, 0.1, 0.0, 0.0];
    assert!(matches!(
        f.step(
            None,
            &I4,
            &z_w,
            Some(&bad_y),
            &I4,
            &[0.0, -40.0, -40.0, -10.0]
        ),
        Err(Error::InvalidArgument(_))
    ));
    assert!(f
        .step(Some(&[f64::NAN, 0.0, 0.0, 1.0]), &I4, &z_w, None, &[], &[])
        .is_err());
    assert!(f.step(None, &I4[..15], &z_w, None, &[], &[]).is_err());
    let mut skew = I4;
    skew[1] = 0.5;
    assert!(f
        .step(
            None,
            &I4,
            &z_w,
            Some(&[1.0, 0.0, 0.0, 0.0]),
            &skew,
            &[-1.0, -1.0, -1.0, 0.0]
        )
        .is_err());
    assert_eq!(snapshot(&f), before);
    // prediction only: the observation noise is ignored (may be empty)
    f.step(None, &I4, &z_w, None, &[], &[]).unwrap();
}
