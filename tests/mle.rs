//! MLE round trips: for Z across the supported range (ties included) and a random rotation M,
//! the MLE of S(M, Z) returns Z and reproduces S.

use bingham::{mle_from_samples, mle_from_second_moment, Bingham};
use nalgebra::{DMatrix, DVector};
use testkit::{rel, Rng64};

fn round_trip(m: DMatrix<f64>, z: &[f64]) -> (f64, f64) {
    let d = z.len();
    let b = Bingham::new(m, DVector::from_column_slice(z)).unwrap();
    let s = b.second_moment().unwrap();
    let fit = mle_from_second_moment(&s).unwrap_or_else(|e| panic!("z = {z:?}: {e}"));
    let mut ez = 0.0f64;
    for i in 0..d {
        let (a, t) = (fit.z()[i], b.z()[i]);
        let err = if t.abs() < 1.0 {
            (a - t).abs()
        } else {
            rel(a, t, 0.0)
        };
        ez = ez.max(err);
    }
    let s2 = fit.second_moment().unwrap();
    let es = (&s2 - &s).amax();
    assert!(
        ez <= 1e-9,
        "z = {z:?}: fitted {:?} (err {ez:e})",
        fit.z().as_slice()
    );
    assert!(es <= 1e-9, "z = {z:?}: second moment differs by {es:e}");
    (ez, es)
}

#[test]
fn round_trip_across_the_range() {
    let mut rng = Rng64(2024);
    let mags = [0.0, 1e-6, 0.3, 1.0, 7.0, 50.0, 1e3, 1428.0, 1e4, 1e5, 1e6];
    let (mut wz, mut ws, mut count) = (0.0f64, 0.0f64, 0);
    for d in [2usize, 3, 4] {
        for _ in 0..150 {
            let mut z: Vec<f64> = (0..d - 1)
                .map(|_| {
                    if rng.uniform() < 0.5 {
                        -mags[(rng.uniform() * mags.len() as f64) as usize]
                    } else {
                        -(10f64).powf(-3.0 + 9.0 * rng.uniform())
                    }
                })
                .collect();
            if rng.uniform() < 0.25 && d > 2 {
                z[1] = z[0]; // ties
            }
            z.push(0.0);
            let m = rng.orthogonal(d);
            let (a, b) = round_trip(m, &z);
            wz = wz.max(a);
            ws = ws.max(b);
            count += 1;
        }
    }
    println!("{count} round trips: max z error {wz:e}, max S error {ws:e}");
}

#[test]
fn named_cases() {
    let mut rng = Rng64(5);
    for z in [
        vec![0.0, 0.0],
        vec![0.0, 0.0, 0.0, 0.0],
        vec![-1e6, -10.0, -1.0, 0.0],
        vec![-5e4, -5e4, 0.0, 0.0],
        vec![-1e6, -1e6, -1e6, 0.0],
        vec![-7.0, -7.0, -7.0, 0.0],
        vec![-1e-9, -1e-9, 0.0],
        vec![-1e6, 0.0],
        vec![-200.0, -200.0, -2.0, 0.0],
    ] {
        let d = z.len();
        round_trip(rng.orthogonal(d), &z);
    }
}

#[test]
fn tiny_omega_gives_huge_concentration() {
    // ω_i down to 1e-7 must give z_i near −5e6
    let w = [1e-7, 2e-7, 1e-3];
    let last = 1.0 - w.iter().sum::<f64>();
    let s = DMatrix::from_diagonal(&DVector::from_vec(vec![w[0], w[1], w[2], last]));
    let fit = mle_from_second_moment(&s).unwrap();
    let om = fit.omega().unwrap();
    for i in 0..3 {
        assert!(rel(om[i], w[i], 0.0) < 1e-12, "{} vs {}", om[i], w[i]);
    }
    assert!(fit.z()[0] < -4.9e6 && fit.z()[0] > -5.1e6, "{}", fit.z()[0]);
}

#[test]
fn near_uniform_gives_near_zero() {
    let s = DMatrix::<f64>::identity(3, 3) * (1.0 / 3.0);
    let fit = mle_from_second_moment(&s).unwrap();
    assert!(fit.z().amax() < 1e-12, "{:?}", fit.z());
    let mut s = DMatrix::<f64>::identity(4, 4) * 0.25;
    s[(0, 0)] += 1e-9;
    s[(3, 3)] -= 1e-9;
    let fit = mle_from_second_moment(&s).unwrap();
    assert!(fit.z().amax() < 1e-6, "{:?}", fit.z());
}

#[test]
fn singular_or_bad_moments_are_errors() {
    let s = DMatrix::from_diagonal(&DVector::from_vec(vec![0.0, 0.5, 0.5]));
    assert!(mle_from_second_moment(&s).is_err());
    let s = DMatrix::from_diagonal(&DVector::from_vec(vec![-0.1, 0.5, 0.6]));
    assert!(mle_from_second_moment(&s).is_err());
    let mut s = DMatrix::<f64>::identity(3, 3);
    s[(0, 1)] = f64::NAN;
    assert!(mle_from_second_moment(&s).is_err());
    let mut s = DMatrix::<f64>::identity(3, 3);
    s[(0, 1)] = 0.3;
    assert!(mle_from_second_moment(&s).is_err(), "asymmetric");
    assert!(mle_from_second_moment(&DMatrix::zeros(3, 3)).is_err());
    assert!(mle_from_second_moment(&DMatrix::identity(1, 1)).is_err());
}

#[test]
fn from_samples_weighted_equals_moment() {
    let mut rng = Rng64(99);
    let d = 3;
    let n = 50;
    let mut x = Vec::new();
    let mut w = Vec::new();
    let mut s = DMatrix::zeros(d, d);
    for _ in 0..n {
        let v = DVector::from_fn(d, |_, _| rng.normal()).normalize();
        let wk = rng.uniform() + 0.1;
        s += &v * v.transpose() * wk;
        x.extend_from_slice(v.as_slice());
        w.push(wk);
    }
    let a = mle_from_samples(d, &x, Some(&w)).unwrap();
    let b = mle_from_second_moment(&s).unwrap();
    for i in 0..d {
        assert!(rel(a.z()[i], b.z()[i], 1.0) < 1e-12);
    }
    // unweighted equals all-ones weights
    let ones = vec![1.0; n];
    let a1 = mle_from_samples(d, &x, None).unwrap();
    let a2 = mle_from_samples(d, &x, Some(&ones)).unwrap();
    assert_eq!(a1.z(), a2.z());
    // errors
    assert!(mle_from_samples(d, &x[..x.len() - 1], None).is_err());
    let mut bad = x.clone();
    bad[0] *= 2.0;
    assert!(mle_from_samples(d, &bad, None).is_err(), "non-unit");
    let mut wneg = w.clone();
    wneg[3] = -1.0;
    assert!(mle_from_samples(d, &x, Some(&wneg)).is_err());
    assert!(mle_from_samples(d, &x, Some(&w[..3])).is_err());
}
