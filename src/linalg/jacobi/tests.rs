//! Tests of the Jacobi eigendecomposition against the definition and independent solvers.

use super::*;

use testkit::xorshift;

/// Random orthogonal n×n matrix.
fn orthogonal(n: usize, r: &mut impl FnMut() -> f64) -> DMatrix<f64> {
    DMatrix::from_fn(n, n, |_, _| r()).qr().q()
}

/// `Q·diag(λ)·Qᵀ`, symmetrised.
fn rotated(lambda: &[f64], r: &mut impl FnMut() -> f64) -> DMatrix<f64> {
    let n = lambda.len();
    let q = orthogonal(n, r);
    let a = &q * DMatrix::from_diagonal(&DVector::from_column_slice(lambda)) * q.transpose();
    (&a + a.transpose()) * 0.5
}

/// The signature of `jacobi_in_place` and `jacobi_general`.
type Solver = fn(usize, &mut [f64], &mut [f64], &mut [f64], &mut [f64]);

/// Eigenvalues (sorted) and eigenvectors (unsorted columns) by `solver`.
fn solve(a: &DMatrix<f64>, solver: Solver) -> (Vec<f64>, DVector<f64>, DMatrix<f64>) {
    let n = a.nrows();
    let mut m: Vec<f64> = a.transpose().as_slice().to_vec();
    let (mut v, mut d, mut w) = (vec![0.0; n * n], vec![0.0; n], vec![0.0; 2 * n]);
    solver(n, &mut m, &mut v, &mut d, &mut w);
    let mut sorted = d.clone();
    sorted.sort_by(f64::total_cmp);
    (
        sorted,
        DVector::from_vec(d),
        DMatrix::from_row_slice(n, n, &v),
    )
}

/// Largest |VΛVᵀ − A|_ij / √(|a_ii·a_jj|) (the componentwise backward error that gives
/// graded matrices relative accuracy) and largest |VᵀV − I|.
fn graded_residual(a: &DMatrix<f64>, d: &DVector<f64>, v: &DMatrix<f64>) -> (f64, f64) {
    let n = a.nrows();
    let rec = v * DMatrix::from_diagonal(d) * v.transpose();
    let mut worst: f64 = 0.0;
    for i in 0..n {
        for j in 0..n {
            let scale = (a[(i, i)].abs() * a[(j, j)].abs()).sqrt();
            worst = worst.max((rec[(i, j)] - a[(i, j)]).abs() / scale);
        }
    }
    let ortho = (v.transpose() * v - DMatrix::identity(n, n)).amax();
    (worst, ortho)
}

/// Double-double numbers (about 106 bits) for an independent reference.
#[derive(Clone, Copy, Debug)]
struct Dd(f64, f64);

impl Dd {
    fn two_sum(a: f64, b: f64) -> Dd {
        let s = a + b;
        let bb = s - a;
        Dd(s, (a - (s - bb)) + (b - bb))
    }
    fn norm(self) -> Dd {
        let s = self.0 + self.1;
        Dd(s, self.1 - (s - self.0))
    }
    fn add(self, o: Dd) -> Dd {
        let s = Dd::two_sum(self.0, o.0);
        let t = Dd::two_sum(self.1, o.1);
        let s = Dd(s.0, s.1 + t.0).norm();
        Dd(s.0, s.1 + t.1).norm()
    }
    fn neg(self) -> Dd {
        Dd(-self.0, -self.1)
    }
    fn sub(self, o: Dd) -> Dd {
        self.add(o.neg())
    }
    fn mul(self, o: Dd) -> Dd {
        let p = self.0 * o.0;
        let e = self.0.mul_add(o.0, -p);
        Dd(p, e + (self.0 * o.1 + self.1 * o.0)).norm()
    }
    fn div(self, o: Dd) -> Dd {
        let q1 = self.0 / o.0;
        let r = self.sub(o.mul(Dd(q1, 0.0)));
        let q2 = r.0 / o.0;
        let r = r.sub(o.mul(Dd(q2, 0.0)));
        let q3 = r.0 / o.0;
        Dd(q1, q2).norm().add(Dd(q3, 0.0))
    }
    fn sqrt(self) -> Dd {
        if self.0 <= 0.0 {
            return Dd(0.0, 0.0);
        }
        let s = Dd(self.0.sqrt(), 0.0);
        s.add(self.sub(s.mul(s)).div(s.add(s)))
    }
    fn abs(self) -> Dd {
        if self.0 < 0.0 {
            self.neg()
        } else {
            self
        }
    }
}

/// Eigenvalues (sorted) of `a` by cyclic Jacobi in double-double arithmetic (rotations
/// as in `jacobi_general`, so graded matrices get relative accuracy ~1e-31).
fn reference_eigenvalues(a: &DMatrix<f64>) -> Vec<f64> {
    let n = a.nrows();
    let mut m: Vec<Vec<Dd>> = (0..n)
        .map(|i| (0..n).map(|j| Dd(a[(i, j)], 0.0)).collect())
        .collect();
    let one = Dd(1.0, 0.0);
    for _ in 0..60 {
        let mut done = true;
        for p in 0..n {
            for q in p + 1..n {
                let apq = m[p][q];
                let scale = (m[p][p].0 * m[q][q].0).abs().sqrt();
                if apq.0 == 0.0 || apq.0.abs() <= 1e-40 * scale {
                    continue;
                }
                done = false;
                let theta = m[q][q].sub(m[p][p]).div(apq.add(apq));
                let t = one.div(theta.abs().add(one.add(theta.mul(theta)).sqrt()));
                let t = if theta.0 < 0.0 { t.neg() } else { t };
                let c = one.div(one.add(t.mul(t)).sqrt());
                let s = t.mul(c);
                let ta = t.mul(apq);
                m[p][p] = m[p][p].sub(ta);
                m[q][q] = m[q][q].add(ta);
                m[p][q] = Dd(0.0, 0.0);
                m[q][p] = Dd(0.0, 0.0);
                for j in 0..n {
                    if j != p && j != q {
                        let (g, h) = (m[j][p], m[j][q]);
                        let gp = c.mul(g).sub(s.mul(h));
                        let hp = s.mul(g).add(c.mul(h));
                        m[j][p] = gp;
                        m[p][j] = gp;
                        m[j][q] = hp;
                        m[q][j] = hp;
                    }
                }
            }
        }
        if done {
            break;
        }
    }
    let mut d: Vec<f64> = (0..n).map(|i| m[i][i].0).collect();
    d.sort_by(f64::total_cmp);
    d
}

#[test]
fn reconstructs_close_eigenvalues() {
    let mut worst: f64 = 0.0;
    let mut ortho: f64 = 0.0;
    let mut r = xorshift(88172645463325252);
    for n in [2usize, 3, 4, 7] {
        for _ in 0..300 {
            let g = DMatrix::from_fn(n, n, |_, _| r());
            let q = g.qr().q();
            let w = DVector::from_fn(n, |i, _| {
                0.5 + 1e-3 * i as f64 + if i == 0 { -0.499 } else { 0.0 }
            });
            let a = &q * DMatrix::from_diagonal(&w) * q.transpose();
            let a = (&a + a.transpose()) * 0.5;
            let (vals, vecs) = jacobi_eigen(&a);
            let rec = &vecs * DMatrix::from_diagonal(&vals) * vecs.transpose();
            worst = worst.max((rec - &a).amax());
            ortho = ortho.max((vecs.transpose() * &vecs - DMatrix::identity(n, n)).amax());
        }
    }
    assert!(worst < 1e-15, "reconstruction {worst:e}");
    assert!(ortho < 4e-15, "orthogonality {ortho:e}");
}

/// n = 2 (closed form) against the general path over 600 decades of scale and 24 of
/// off-diagonal size: the same eigenpairs, eigenvalues within 2 ulps of ‖A‖, eigenvectors
/// within 2 ulps (the same rotation, formed by a shorter chain).
#[test]
fn two_by_two_agrees_with_the_general_path() {
    let mut r = xorshift(3);
    let mut cases = vec![
        [1.0, 0.0, 2.0],
        [1.0, 1e-300, 1.0],
        [2.0, 3.0, 2.0],
        [-1e12, 5.0, 0.0],
        [0.0, -0.0, -0.0],
        [1e300, 1e-300, -1e300],
        [5e-324, 5e-324, 0.0],
        [3.0, -2.0, 3.0],
    ];
    for _ in 0..2000 {
        let s = 10f64.powf(600.0 * r() - 300.0);
        let t = 10f64.powf(24.0 * r() - 12.0);
        cases.push([s * r(), s * t * r(), s * r()]);
    }
    for [a, b, c] in cases {
        let (mut v, mut d, mut w) = ([0.0; 4], [0.0; 2], [0.0; 4]);
        jacobi_in_place(2, &mut [a, b, b, c], &mut v, &mut d, &mut w);
        let (mut v2, mut d2) = ([0.0; 4], [0.0; 2]);
        jacobi_general(2, &mut [a, b, b, c], &mut v2, &mut d2, &mut w);
        // the same eigenpairs: sorted, eigenvectors up to sign (for a zero gap either
        // rotation by ±45° is the decomposition)
        let norm = a.abs().max(b.abs()).max(c.abs());
        let pairs = |v: [f64; 4], d: [f64; 2]| {
            let mut p = [(d[0], [v[0], v[2]]), (d[1], [v[1], v[3]])];
            p.sort_by(|x, y| x.0.total_cmp(&y.0));
            p
        };
        // (subnormal entries carry fewer bits: there the two chains may differ in the
        // eigenvectors by the entries' own relative precision, so only the eigenvalues are
        // compared, to a few subnormal steps)
        let subnormal = [a, b, c].iter().any(|x| *x != 0.0 && !x.is_normal());
        for ((l, x), (l2, x2)) in pairs(v, d).into_iter().zip(pairs(v2, d2)) {
            assert!(
                (l - l2).abs() <= 2.0 * f64::EPSILON * norm + 4.0 * 5e-324,
                "{a} {b} {c}: {d:?} {d2:?}"
            );
            if subnormal {
                continue;
            }
            let sign = if x[0] * x2[0] + x[1] * x2[1] < 0.0 {
                -1.0
            } else {
                1.0
            };
            for k in 0..2 {
                assert!(
                    (x[k] - sign * x2[k]).abs() <= 2.0 * f64::EPSILON,
                    "{a} {b} {c}: {v:?} {v2:?}"
                );
            }
        }
    }
}

/// Rotated spectra with eigenvalues from 1e-12 to 1e12 relative (the filter's precisions
/// and second moments): the eigenvalues agree with the extended-precision reference to a few
/// ulps of ‖A‖ (all a rotated matrix determines), as the general path does.
#[test]
fn wide_range_matches_reference() {
    let mut r = xorshift(11);
    for n in [2usize, 3, 4] {
        let (mut worst, mut worst_general, mut worst_rec, mut worst_ortho) =
            (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for k in 0..600 {
            let lambda: Vec<f64> = (0..n)
                .map(|i| match k % 3 {
                    // Bingham-like: 0, −1, −1e6, −1e12 (spread by random exponents)
                    0 if i == n - 1 => 0.0,
                    0 => -(10f64.powf(24.0 * (r() + 0.5))),
                    // second moment: positive, spread up to 1e24
                    1 => 10f64.powf(24.0 * (r() + 0.5)),
                    // indefinite
                    _ => 10f64.powf(24.0 * (r() + 0.5)) * r().signum(),
                })
                .collect();
            let a = rotated(&lambda, &mut r);
            let norm = a.norm();
            let reference = reference_eigenvalues(&a);
            let (fast, d, v) = solve(&a, jacobi_in_place);
            let (general, _, _) = solve(&a, jacobi_general);
            for i in 0..n {
                worst = worst.max((fast[i] - reference[i]).abs() / norm);
                worst_general = worst_general.max((general[i] - reference[i]).abs() / norm);
            }
            let rec = &v * DMatrix::from_diagonal(&d) * v.transpose();
            worst_rec = worst_rec.max((rec - &a).amax() / norm);
            worst_ortho = worst_ortho.max((v.transpose() * &v - DMatrix::identity(n, n)).amax());
        }
        let eps = f64::EPSILON;
        // measured: eigenvalues ≤ 1.2 eps (general path ≤ 1.6), reconstruction ≤ 2.8 eps,
        // orthogonality ≤ 3 eps
        assert!(
            worst < 3.0 * eps,
            "n = {n}: eigenvalues {:.2} eps",
            worst / eps
        );
        assert!(
            worst_general < 3.0 * eps,
            "n = {n}: general {:.2} eps",
            worst_general / eps
        );
        assert!(
            worst_rec < 5.0 * eps,
            "n = {n}: rec {:.2} eps",
            worst_rec / eps
        );
        assert!(
            worst_ortho < 6.0 * eps,
            "n = {n}: ortho {:.2} eps",
            worst_ortho / eps
        );
    }
}

/// Graded matrices `A = ±D·H·D` (H well conditioned with unit diagonal, definite or
/// indefinite; D from 1e-6 to 1e6 in random order: eigenvalues from 1e-12 to 1e12
/// relative): every eigenvalue to a few ulps *relative* against the extended-precision
/// reference, and a componentwise backward error of a few ulps of √(|a_ii·a_jj|).
#[test]
fn graded_matrices_keep_relative_accuracy() {
    let mut r = xorshift(29);
    for n in [2usize, 3, 4] {
        let (mut worst, mut worst_general, mut worst_res, mut worst_ortho) =
            (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for k in 0..900 {
            // H: unit diagonal; definite (eigenvalues in [0.5, 2] before the scaling) or,
            // every third, indefinite (diagonal ±1, off-diagonals below 0.3)
            let h = if k % 3 == 2 {
                DMatrix::from_fn(n, n, |i, j| match (i, j) {
                    _ if i == j => [1.0, -1.0][i % 2],
                    _ => 0.0,
                })
            } else {
                let lambda: Vec<f64> = (0..n).map(|_| 1.25 + 1.5 * r()).collect();
                let h = rotated(&lambda, &mut r);
                DMatrix::from_fn(n, n, |i, j| h[(i, j)] / (h[(i, i)] * h[(j, j)]).sqrt())
            };
            let mut off = DMatrix::from_fn(n, n, |_, _| 0.6 * r());
            off = (&off + off.transpose()) * 0.5;
            let sign = if k % 3 == 1 { -1.0 } else { 1.0 };
            let dg: Vec<f64> = (0..n).map(|_| 10f64.powf(12.0 * r())).collect();
            let a = DMatrix::from_fn(n, n, |i, j| {
                let hij = if k % 3 == 2 && i != j {
                    off[(i, j)]
                } else {
                    h[(i, j)]
                };
                sign * dg[i] * hij * dg[j]
            });
            let reference = reference_eigenvalues(&a);
            let (fast, d, v) = solve(&a, jacobi_in_place);
            let (general, _, _) = solve(&a, jacobi_general);
            for i in 0..n {
                let rel = |x: f64| (x - reference[i]).abs() / reference[i].abs();
                worst = worst.max(rel(fast[i]));
                worst_general = worst_general.max(rel(general[i]));
            }
            let (res, ortho) = graded_residual(&a, &d, &v);
            worst_res = worst_res.max(res);
            worst_ortho = worst_ortho.max(ortho);
        }
        let eps = f64::EPSILON;
        // measured: relative ≤ 1.5 eps (general path ≤ 1.9), residual ≤ 2.9 eps,
        // orthogonality ≤ 2.5 eps
        assert!(
            worst < 4.0 * eps,
            "n = {n}: relative {:.2} eps",
            worst / eps
        );
        assert!(
            worst_general < 4.0 * eps,
            "n = {n}: general {:.2} eps",
            worst_general / eps
        );
        assert!(
            worst_res < 6.0 * eps,
            "n = {n}: residual {:.2} eps",
            worst_res / eps
        );
        assert!(
            worst_ortho < 6.0 * eps,
            "n = {n}: ortho {:.2} eps",
            worst_ortho / eps
        );
    }
}

/// Diagonal and block-diagonal inputs, repeated eigenvalues, signed zeros.
#[test]
fn special_structures() {
    for n in [2usize, 3, 4] {
        // diagonal (with ±0): returned as is, V = I exactly
        let diag = [3.0, -0.0, 0.0, -2.5];
        let a = DMatrix::from_fn(n, n, |i, j| if i == j { diag[i] } else { 0.0 });
        let (_, d, v) = solve(&a, jacobi_in_place);
        for i in 0..n {
            // (−0 comes back as +0: d = b + z, as on the general path)
            assert_eq!(d[i], diag[i]);
        }
        assert_eq!(v, DMatrix::identity(n, n));
        // all zeros, both signs
        for z in [0.0, -0.0] {
            let (_, d, v) = solve(&DMatrix::from_element(n, n, z), jacobi_in_place);
            assert!(d.iter().all(|x| *x == 0.0));
            assert_eq!(v, DMatrix::identity(n, n));
        }
    }
    // block diagonal: the uncoupled rows and columns stay exact
    let a = DMatrix::from_row_slice(
        4,
        4,
        &[
            2.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.5, 0.0, 0.0, 0.5, 3.0, 0.0, 0.0, 0.0, 0.0, -7.0,
        ],
    );
    let (_, d, v) = solve(&a, jacobi_in_place);
    assert_eq!((d[0], d[3]), (2.0, -7.0));
    for i in 0..4 {
        for j in [0, 3] {
            assert_eq!(v[(i, j)], if i == j { 1.0 } else { 0.0 });
            assert_eq!(v[(j, i)], if i == j { 1.0 } else { 0.0 });
        }
    }
    // repeated eigenvalues
    let mut r = xorshift(7);
    let eps = f64::EPSILON;
    for n in [2usize, 3, 4] {
        for lambda in [
            vec![1.0; 4],
            vec![1.0, 1.0, 1.0, 2.0],
            vec![-1.0, 3.0, -1.0, 3.0],
            vec![0.0, 0.0, -1e6, -1e6],
        ] {
            for _ in 0..50 {
                let a = rotated(&lambda[..n], &mut r);
                let (sorted, d, v) = solve(&a, jacobi_in_place);
                let reference = reference_eigenvalues(&a);
                let norm = a.norm();
                for i in 0..n {
                    assert!((sorted[i] - reference[i]).abs() <= 2.0 * eps * norm);
                }
                let rec = &v * DMatrix::from_diagonal(&d) * v.transpose();
                assert!((rec - &a).amax() <= 4.0 * eps * norm);
                assert!((v.transpose() * &v - DMatrix::identity(n, n)).amax() <= 6.0 * eps);
            }
        }
    }
}

/// Scales from the subnormals to 1e307 and mixed magnitudes: finite output, the same
/// relative accuracy; scaling by a power of two (away from the range limits) scales the
/// result exactly. NaN input terminates.
#[test]
fn extreme_scales() {
    let mut r = xorshift(17);
    let eps = f64::EPSILON;
    for n in [2usize, 3, 4] {
        for _ in 0..200 {
            let g = DMatrix::from_fn(n, n, |_, _| r());
            let base = (&g + g.transpose()) * 0.5;
            let (unit, _, _) = solve(&base, jacobi_in_place);
            for k in [
                -1070, -1040, -1000, -600, -480, -300, 0, 300, 480, 600, 1000, 1020,
            ] {
                let scale = 2f64.powi(k);
                let a = &base * scale;
                let (sorted, d, v) = solve(&a, jacobi_in_place);
                assert!(d.iter().chain(v.iter()).all(|x| x.is_finite()), "2^{k}");
                // (a.norm() would under- or overflow)
                let norm = base.norm() * scale;
                let rec = &v * DMatrix::from_diagonal(&d) * v.transpose();
                let ortho = (v.transpose() * &v - DMatrix::identity(n, n)).amax();
                assert!(ortho <= 6.0 * eps, "2^{k}: {ortho:e}");
                if k > -1000 {
                    assert!((rec - &a).amax() <= 5.0 * eps * norm, "2^{k}");
                }
                if (-900..=900).contains(&k) {
                    for i in 0..n {
                        let x = sorted[i] / scale;
                        assert!(
                            (x - unit[i]).abs() <= 4.0 * eps * base.norm(),
                            "2^{k}: {x:e} vs {:e} (n = {n}, {i})",
                            unit[i]
                        );
                    }
                }
            }
        }
        // mixed magnitudes: diagonal 1e300 / 1e-300, off-diagonals from 1e-320 to 1e150
        for _ in 0..200 {
            let a = DMatrix::from_fn(n, n, |i, j| {
                let (i, j) = (i.min(j), i.max(j));
                let e = [300.0, -300.0, 150.0, -320.0][(i + 2 * j) % 4];
                10f64.powf(e + r()) * (r() + 0.01)
            });
            let a = DMatrix::from_fn(n, n, |i, j| a[(i.min(j), i.max(j))]);
            let (_, d, v) = solve(&a, jacobi_in_place);
            assert!(d.iter().chain(v.iter()).all(|x| x.is_finite()));
            let rec = &v * DMatrix::from_diagonal(&d) * v.transpose();
            assert!((rec - &a).amax() <= 5.0 * eps * a.amax() * n as f64);
            assert!((v.transpose() * &v - DMatrix::identity(n, n)).amax() <= 6.0 * eps);
        }
        // the largest norm of the documented range
        let a = DMatrix::from_fn(
            n,
            n,
            |i, j| if i == j { 0.3 } else { -0.2 } * 2f64.powi(1020),
        );
        let (_, d, v) = solve(&a, jacobi_in_place);
        assert!(d.iter().chain(v.iter()).all(|x| x.is_finite()));
        // NaN: terminates (callers check for finite output)
        let mut a = DMatrix::from_element(n, n, 1.0);
        a[(0, n - 1)] = f64::NAN;
        let (_, d, _) = solve(&a, jacobi_in_place);
        assert!(d.iter().any(|x| x.is_nan()));
    }
}

/// Nearly diagonal inputs (the iteration ends in the first-order step at once), graded and
/// with close diagonals, against the extended-precision reference; repeated runs give
/// bit-identical output.
#[test]
fn nearly_diagonal_and_deterministic() {
    let mut r = xorshift(41);
    let eps = f64::EPSILON;
    for n in [3usize, 4] {
        for k in 0..400 {
            let dg: Vec<f64> = (0..n)
                .map(|i| match k % 4 {
                    0 => 10f64.powf(12.0 * r()),
                    1 => 1.0 + 1e-6 * i as f64 + 1e-9 * r(),
                    2 => -(10f64.powf(6.0 * r())),
                    _ => r(),
                })
                .collect();
            let off = 10f64.powf(-9.0 - 6.0 * (r() + 0.5));
            let a = DMatrix::from_fn(n, n, |i, j| {
                if i == j {
                    dg[i]
                } else {
                    let (i, j) = (i.min(j), i.max(j));
                    off * (dg[i] * dg[j]).abs().sqrt() * ((i * 7 + j * 3) as f64 * 0.37).sin()
                }
            });
            let reference = reference_eigenvalues(&a);
            let (sorted, d, v) = solve(&a, jacobi_in_place);
            for i in 0..n {
                let rel = (sorted[i] - reference[i]).abs() / reference[i].abs();
                assert!(rel <= 2.0 * eps, "k = {k}: {:.2} eps", rel / eps);
            }
            let (res, ortho) = graded_residual(&a, &d, &v);
            assert!(res <= 4.0 * eps && ortho <= 4.0 * eps, "k = {k}");
            let (sorted2, d2, v2) = solve(&a, jacobi_in_place);
            assert_eq!(sorted, sorted2);
            assert_eq!((d, v), (d2, v2));
        }
    }
}

/// The regimes of `rotation` and Numerical Recipes' formulas against the exact rotation
/// (double-double), and the shortcut for tiny angles against the series (bit for bit).
#[test]
fn rotation_regimes() {
    let mut r = xorshift(5);
    let one = Dd(1.0, 0.0);
    let ulps = |x: f64, y: Dd| (Dd(x, 0.0).sub(y)).0.abs() / (f64::EPSILON * y.0.abs());
    let (mut worst, mut worst_nr) = ([0.0f64; 3], [0.0f64; 3]);
    for k in 0..100_000 {
        let apq = r() * 10f64.powf(40.0 * r());
        let x = match k % 3 {
            0 => 10f64.powf(-30.0 * (r() + 0.5)),
            1 => 10f64.powf(-3.0 * (r() + 0.5)),
            _ => 10f64.powf(8.0 * r()),
        } * r().signum();
        let h = apq / x;
        // exact: θ = h/(2apq), t = sign(θ)/(|θ| + √(1 + θ²)), c = 1/√(1 + t²)
        let a = Dd(apq, 0.0);
        let theta = Dd(h, 0.0).div(a.add(a));
        let t = one.div(theta.abs().add(one.add(theta.mul(theta)).sqrt()));
        let t = if theta.0 < 0.0 { t.neg() } else { t };
        let c = one.div(one.add(t.mul(t)).sqrt());
        let exact = [t.mul(a), t.mul(c), t.mul(c).div(one.add(c))];
        let (ta, s, tau) = rotation(apq, h);
        let (t0, s0, tau0) = rotation_nr(apq, h);
        for (i, (got, nr)) in [(ta, t0 * apq), (s, s0), (tau, tau0)]
            .into_iter()
            .enumerate()
        {
            worst[i] = worst[i].max(ulps(got, exact[i]));
            worst_nr[i] = worst_nr[i].max(ulps(nr, exact[i]));
        }
        if apq.abs() <= TINY_X * h.abs() {
            let (ta1, s1, tau1) = rotation_series(apq, h);
            assert_eq!((ta.to_bits(), s.to_bits()), (ta1.to_bits(), s1.to_bits()));
            assert_eq!(tau.to_bits(), tau1.to_bits());
        }
    }
    // measured: ≤ 1.9 ulps (Numerical Recipes' formulas: ≤ 2.2)
    assert!(worst.iter().all(|w| *w <= 2.5), "{worst:?}");
}

/// The warm start of `sym_eigen_in_basis` on matrices like the filter's correction: the second
/// moment of a concentrated state (`M diag(ω) Mᵀ`, ω of concentrations −1e3 … −1e5, the
/// first two nearly equal as the AHRS's tilt axes) moved by a small noise, decomposed in the
/// basis `M` (a Jacobi eigenbasis, orthonormal to a few ulps). Eigenvalues against the
/// double-double reference (as for the cold path on the same matrices) and relative to the
/// cold ones; the mode against nalgebra's `SymmetricEigen` (the only eigenvector separated
/// enough for its accuracy), every eigenpair by its residual, the conventions of `sym_eigen`;
/// a basis that is not orthonormal enough is declined.
#[test]
fn warm_start_in_a_nearly_diagonalizing_basis() {
    use crate::linalg::{
        in_basis, orthogonality_error, sym_eigen, sym_eigen_in_basis, warm_basis, Square,
    };
    use nalgebra::Const;
    let mut r = xorshift(43);
    let eps = f64::EPSILON;
    let (mut worst_warm, mut worst_cold, mut worst_vec) = (0.0f64, 0.0f64, 0.0f64);
    let mut worst_ortho = 0.0f64;
    let mut worst_wc = 0.0f64;
    let (mut worst_mode, mut worst_res) = (0.0f64, 0.0f64);
    let mut worst_rec = 0.0f64;
    let mut cases = 0;
    for k in 0..300 {
        let g = Square::<Const<4>>::from_fn(|_, _| r());
        let (m, _) = sym_eigen(&(g + g.transpose())).unwrap();
        if !warm_basis(&m) {
            continue;
        }
        cases += 1;
        // ω ≈ 1/(2|z|) for the three concentrations, the rest on the mode
        let z1 = 10f64.powf(3.0 + 2.0 * (r() + 0.5));
        let z3 = 10f64.powf(3.0 + 2.0 * (r() + 0.5));
        let mut w = [
            0.5 / z1,
            0.5 / (z1 * (1.0 + 1e-3 * (r() + 0.5))),
            0.5 / z3,
            0.0,
        ];
        w[3] = 1.0 - w[0] - w[1] - w[2];
        // the noise: C = G A Gᵀ with G = I + E, |E| ~ 1e-3 (the AHRS's off-diagonals in the
        // basis M are 1e-4 … 1 of the eigenvalue gaps)
        let e = Square::<Const<4>>::from_fn(|_, _| 2e-3 * r());
        let gm = Square::<Const<4>>::identity() + e;
        let a = m * Square::<Const<4>>::from_diagonal(&w.into()) * m.transpose();
        let c0 = gm * a * gm.transpose();
        let c = (c0 + c0.transpose()) * 0.5;
        let reference = reference_eigenvalues(&DMatrix::from_column_slice(4, 4, c.as_slice()));
        let (vc, lc) = sym_eigen(&c).unwrap();
        let (vw, lw) = sym_eigen_in_basis(&in_basis(&c, &m), &m).unwrap();
        for i in 0..4 {
            worst_warm = worst_warm.max((lw[i] - reference[i]).abs());
            worst_cold = worst_cold.max((lc[i] - reference[i]).abs());
            worst_wc = worst_wc.max((lw[i] - lc[i]).abs() / lc[i]);
            assert!(i == 0 || lw[i - 1] <= lw[i], "k = {k}: ascending");
            let col = vw.column(i);
            let big = col
                .iter()
                .fold(0.0f64, |a, &x| if x.abs() > a.abs() { x } else { a });
            assert!(big > 0.0, "k = {k}: sign");
        }
        worst_ortho = worst_ortho.max(orthogonality_error(&vw));
        let rec = vw * Square::<Const<4>>::from_diagonal(&lw) * vw.transpose();
        worst_rec = worst_rec.max((rec - c).amax());
        // the mode (separated by ~1 = ‖C‖) against nalgebra's QR-based solver (accurate to
        // ~ε/gap, which is enough only there), up to sign
        let na = nalgebra::SymmetricEigen::new(DMatrix::from_column_slice(4, 4, c.as_slice()));
        let top = na.eigenvalues.imax();
        let (x, y) = (vw.column(3), na.eigenvectors.column(top));
        let s = if x.dot(&y) < 0.0 { -1.0 } else { 1.0 };
        worst_mode = worst_mode.max((0..4).map(|r| (x[r] - s * y[r]).abs()).fold(0.0, f64::max));
        // every eigenpair by its definition (‖C v − λ v‖), and against the cold path scaled by
        // the eigenvalue's gap (eigenvectors are determined to ~ε/gap)
        for i in 0..4 {
            let x = vw.column(i);
            worst_res = worst_res.max((c * x - x * lw[i]).amax());
            let gap = (0..4)
                .filter(|&j| j != i)
                .map(|j| (lw[j] - lw[i]).abs())
                .fold(f64::INFINITY, f64::min);
            worst_vec = worst_vec.max((x - vc.column(i)).amax() * gap);
        }
    }
    // measured: every eigenvalue within 3 ulps of ‖C‖ = 1 (cold: 1), the small ones (ω down to
    // 5e-6) within 8.5e-12 relative (cold: 1.8e-11) and 1.8e-11 of the cold ones; eigenvectors
    // orthonormal within 4 ulps, reconstruction 4.5 ulps (cold 2.5), residuals 2.5 ulps, the
    // mode within 4 ulps of nalgebra's, the other vectors within 2 ulps/gap of the cold ones
    assert!(cases >= 250, "{cases} bases accepted");
    assert!(
        worst_warm <= 4.0 * eps && worst_cold <= 4.0 * eps,
        "{worst_warm:e} {worst_cold:e}"
    );
    assert!(worst_wc <= 4e-11, "warm vs cold {worst_wc:e}");
    assert!(
        worst_ortho <= 6.0 * eps && worst_rec <= 6.0 * eps,
        "{worst_ortho:e} {worst_rec:e}"
    );
    assert!(
        worst_res <= 4.0 * eps && worst_mode <= 8.0 * eps,
        "{worst_res:e} {worst_mode:e}"
    );
    assert!(worst_vec <= 4.0 * eps, "{worst_vec:e}");
    // a basis that has drifted from orthonormality is declined (the caller decomposes cold)
    let (m, _) = sym_eigen(&Square::<Const<4>>::from_fn(|i, j| (i + j) as f64)).unwrap();
    assert!(warm_basis(&m));
    assert!(!warm_basis(&(m * (1.0 + 4.0 * eps))));
    assert!(!warm_basis(&(m * f64::NAN)));
}
