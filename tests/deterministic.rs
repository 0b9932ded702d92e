//! Deterministic samples: weights, unit points and the reproduced moments against the exact
//! moments from log F's gradient and Hessian (an independent evaluation: the moments are
//! recomputed here from `evaluate`, the points only enter through their coordinates).

use bingham::deterministic::{max_count, Reproduced, Scheme};
use bingham::normalization::evaluate;
use bingham::{Bingham, Method};

mod common;

/// A random orthogonal matrix (Gram-Schmidt of a deterministic pseudo-random matrix).
fn orthogonal(d: usize, seed: u64) -> Vec<f64> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut cols: Vec<Vec<f64>> = Vec::new();
    for _ in 0..d {
        let mut v: Vec<f64> = (0..d).map(|_| next()).collect();
        for c in &cols {
            let p: f64 = v.iter().zip(c).map(|(a, b)| a * b).sum();
            for (a, b) in v.iter_mut().zip(c) {
                *a -= p * b;
            }
        }
        let n = v.iter().map(|a| a * a).sum::<f64>().sqrt();
        cols.push(v.iter().map(|a| a / n).collect());
    }
    let mut m = vec![0.0; d * d];
    for r in 0..d {
        for c in 0..d {
            m[r * d + c] = cols[c][r];
        }
    }
    m
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
