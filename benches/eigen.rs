//! Symmetric eigendecompositions of the sizes the filter needs (criterion): `jacobi_in_place`
//! for n = 4 and n = 2 (specialised code) and the general-n Jacobi path at n = 4 for comparison.
//! Target (median): ≤ 0.3 µs per 4×4 decomposition.
//!
//! The matrices are those of a d = 4 (and d = 2) filter step, `Q·diag(λ)·Qᵀ` with random
//! orthogonal `Q` (fixed seed): "precision" a Bingham parameter matrix (λ = (z₁, z₂, z₃, 0),
//! z negative with spreads 1..1e6), "precision sum" the sum of two of them (the Bayes update),
//! "moment" a second moment (λ positive, summing to 1, spreads 1..1e6). Each iteration
//! decomposes the whole set of [`N`] matrices (copying each into the scratch first) and reports
//! elements per second; divide the median time by [`N`] for one decomposition. Two more sets,
//! "exponent, warm" and "moment, warm", are what the AHRS's correction hands Jacobi: the
//! matrix in the state's previous eigenbasis, nearly diagonal ([`warm_sets`]).

use bingham::internals as linalg;

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nalgebra::{DMatrix, DVector};

/// Matrices per set.
const N: usize = 256;

/// Deterministic uniform numbers in [0, 1).
struct Uniform(u64);

impl Uniform {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal (Box–Muller).
    fn normal(&mut self) -> f64 {
        let u = 1.0 - self.next();
        let v = self.next();
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }

    /// Random orthogonal n×n matrix (Q of the QR decomposition of a Gaussian matrix).
    fn orthogonal(&mut self, n: usize) -> DMatrix<f64> {
        let g = DMatrix::from_fn(n, n, |_, _| self.normal());
        g.qr().q()
    }

    /// `Q·diag(λ)·Qᵀ` as a row-major array, symmetrised.
    fn rotated(&mut self, lambda: &[f64]) -> Vec<f64> {
        let n = lambda.len();
        let q = self.orthogonal(n);
        let a = &q * DMatrix::from_diagonal(&DVector::from_column_slice(lambda)) * q.transpose();
        let a = (&a + a.transpose()) * 0.5;
        a.transpose().as_slice().to_vec()
    }

    /// `Q·diag(λ)·Qᵀ` with `Q` a rotation by a small angle (1e-4 to 1e-2 rad per plane, the Q
    /// factor of `I + S`, `S` skew-symmetric): what the AHRS's warm path hands Jacobi, a
    /// matrix in the state's previous eigenbasis.
    fn nearly_diagonal(&mut self, lambda: &[f64]) -> Vec<f64> {
        let n = lambda.len();
        let eps = 10f64.powf(-4.0 + 2.0 * self.next());
        let mut s = DMatrix::zeros(n, n);
        for i in 0..n {
            for j in i + 1..n {
                let x = eps * self.normal();
                s[(i, j)] = x;
                s[(j, i)] = -x;
            }
        }
        let q = (DMatrix::identity(n, n) + s).qr().q();
        let a = &q * DMatrix::from_diagonal(&DVector::from_column_slice(lambda)) * q.transpose();
        let a = (&a + a.transpose()) * 0.5;
        a.transpose().as_slice().to_vec()
    }

    /// `n − 1` negative values with a spread of up to 1e6, and 0.
    fn bingham_z(&mut self, n: usize) -> Vec<f64> {
        let spread = 6.0 * self.next();
        let scale = 10f64.powf(2.0 * self.next());
        let mut z: Vec<f64> = (1..n)
            .map(|_| -scale * 10f64.powf(spread * self.next()))
            .collect();
        z.push(0.0);
        z
    }

    /// Positive values summing to 1 with a spread of up to 1e6.
    fn moment(&mut self, n: usize) -> Vec<f64> {
        let spread = 6.0 * self.next();
        let w: Vec<f64> = (0..n).map(|_| 10f64.powf(-spread * self.next())).collect();
        let s: f64 = w.iter().sum();
        w.iter().map(|x| x / s).collect()
    }
}

/// The three sets of n×n matrices (row-major).
fn sets(n: usize) -> Vec<(&'static str, Vec<Vec<f64>>)> {
    let mut r = Uniform(20240611 + n as u64);
    let precision: Vec<Vec<f64>> = (0..N)
        .map(|_| {
            let z = r.bingham_z(n);
            r.rotated(&z)
        })
        .collect();
    let sum: Vec<Vec<f64>> = (0..N)
        .map(|_| {
            let (z1, z2) = (r.bingham_z(n), r.bingham_z(n));
            let (a, b) = (r.rotated(&z1), r.rotated(&z2));
            a.iter().zip(&b).map(|(x, y)| x + y).collect()
        })
        .collect();
    let moment: Vec<Vec<f64>> = (0..N)
        .map(|_| {
            let w = r.moment(n);
            r.rotated(&w)
        })
        .collect();
    vec![
        ("precision", precision),
        ("precision sum", sum),
        ("moment", moment),
    ]
}

/// The AHRS's warm path (n = 4): a posterior exponent (every `z` below the mode in the
/// thousands, the concentrations of a spread of a degree or so) and a composed second moment
/// (eigenvalues 1 and 1e-6 to 1e-3), each nearly diagonal in the basis Jacobi receives.
fn warm_sets() -> Vec<(&'static str, Vec<Vec<f64>>)> {
    let mut r = Uniform(20261129);
    let exponent: Vec<Vec<f64>> = (0..N)
        .map(|_| {
            let mut z: Vec<f64> = (0..3).map(|_| -1e3 * 10f64.powf(2.0 * r.next())).collect();
            z.sort_by(f64::total_cmp);
            z.push(0.0);
            r.nearly_diagonal(&z)
        })
        .collect();
    let moment: Vec<Vec<f64>> = (0..N)
        .map(|_| {
            let mut w: Vec<f64> = (0..3).map(|_| 10f64.powf(-6.0 + 3.0 * r.next())).collect();
            w.push(1.0);
            let s: f64 = w.iter().sum();
            let w: Vec<f64> = w.iter().map(|x| x / s).collect();
            r.nearly_diagonal(&w)
        })
        .collect();
    vec![("exponent, warm", exponent), ("moment, warm", moment)]
}

type Solver = fn(usize, &mut [f64], &mut [f64], &mut [f64], &mut [f64]);

fn run<const NN: usize, const N2: usize, const D: usize>(set: &[Vec<f64>], solve: Solver) -> f64 {
    let n = D;
    let mut acc = 0.0;
    let (mut m, mut v, mut d, mut w) = ([0.0; NN], [0.0; NN], [0.0; D], [0.0; N2]);
    for a in set {
        m.copy_from_slice(black_box(a));
        solve(n, &mut m, &mut v, &mut d, &mut w);
        acc += d[0] + v[1];
    }
    acc
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("eigen");
    g.throughput(Throughput::Elements(N as u64));
    for (name, set) in sets(4) {
        g.bench_function(format!("4x4 {name}"), |b| {
            b.iter(|| run::<16, 8, 4>(&set, linalg::jacobi_in_place))
        });
        g.bench_function(format!("4x4 {name} general"), |b| {
            b.iter(|| run::<16, 8, 4>(&set, linalg::jacobi_general))
        });
    }
    for (name, set) in warm_sets() {
        g.bench_function(format!("4x4 {name}"), |b| {
            b.iter(|| run::<16, 8, 4>(&set, linalg::jacobi_in_place))
        });
    }
    for (name, set) in sets(2) {
        g.bench_function(format!("2x2 {name}"), |b| {
            b.iter(|| run::<4, 4, 2>(&set, linalg::jacobi_in_place))
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(3));
    targets = bench
}
criterion_main!(benches);
