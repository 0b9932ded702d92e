//! log F + gradient (and, for d = 3, 4, + Hessian, as the MLE's Newton steps ask) across the
//! range (criterion). Targets: d = 2 ≤ 40 ns, d = 4 log F + ∇ ≤ 0.8 µs.
//! `d4_path` runs the d = 4 quadrature on each compiled kernel this CPU supports
//! (`Path::detected` picks one of them for every other call). `omega_concentrated_d4`: ω of a
//! concentrated d = 4 Bingham through the distribution (the concentrated series) against the
//! public log F + ∇ (the quadrature).

use bingham::normalization::{log_f_with_path, log_normalization_into, Method, Path};
use bingham::Bingham;
use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use nalgebra::{DMatrix, DVector};

fn cases(d: usize) -> Vec<(&'static str, Vec<f64>)> {
    match d {
        2 => vec![
            ("uniform", vec![0.0, 0.0]),
            ("z=-1", vec![-1.0, 0.0]),
            ("z=-100", vec![-100.0, 0.0]),
            ("z=-1e4", vec![-1e4, 0.0]),
            ("z=-1e6", vec![-1e6, 0.0]),
        ],
        3 => vec![
            ("uniform", vec![0.0, 0.0, 0.0]),
            ("(-10,-1,0)", vec![-10.0, -1.0, 0.0]),
            ("(-1e3,-1e2,0)", vec![-1e3, -1e2, 0.0]),
            ("(-1e6,-10,0)", vec![-1e6, -10.0, 0.0]),
            ("(-1e6,-1e6,0)", vec![-1e6, -1e6, 0.0]),
        ],
        _ => vec![
            ("uniform", vec![0.0; 4]),
            ("(-1,-1,-1,0)", vec![-1.0, -1.0, -1.0, 0.0]),
            ("(-200,-200,-2,0)", vec![-200.0, -200.0, -2.0, 0.0]),
            ("(-1e4,-1e3,-1e2,0)", vec![-1e4, -1e3, -1e2, 0.0]),
            ("(-5e4,-5e4,0,0)", vec![-5e4, -5e4, 0.0, 0.0]),
            ("(-1e6,-10,-1,0)", vec![-1e6, -10.0, -1.0, 0.0]),
            ("(-1e6,-1e6,-1e6,0)", vec![-1e6, -1e6, -1e6, 0.0]),
        ],
    }
}

fn bench(c: &mut Criterion) {
    for d in [2usize, 3, 4] {
        let mut g = c.benchmark_group(format!("log_f_grad_d{d}"));
        for (name, z) in cases(d) {
            g.bench_with_input(BenchmarkId::from_parameter(name), &z, |b, z| {
                let mut grad = [0.0; 4];
                b.iter(|| {
                    log_normalization_into(black_box(z), Method::Exact, Some(&mut grad[..d]), None)
                        .unwrap()
                })
            });
        }
        g.finish();
    }
    for d in [3usize, 4] {
        let mut g = c.benchmark_group(format!("log_f_grad_hess_d{d}"));
        for (name, z) in cases(d) {
            g.bench_with_input(BenchmarkId::from_parameter(name), &z, |b, z| {
                let mut grad = [0.0; 4];
                let mut hess = [0.0; 16];
                b.iter(|| {
                    log_normalization_into(
                        black_box(z),
                        Method::Exact,
                        Some(&mut grad[..d]),
                        Some(&mut hess[..d * d]),
                    )
                    .unwrap()
                })
            });
        }
        g.finish();
    }
    let mut g = c.benchmark_group("d4_path");
    for path in Path::ALL.into_iter().filter(|p| p.available()) {
        for (name, z) in cases(4).into_iter().filter(|(n, _)| n.starts_with("(-1e")) {
            for hessian in [false, true] {
                let id = format!("{path:?}/{}/{name}", if hessian { "hess" } else { "grad" });
                g.bench_with_input(BenchmarkId::from_parameter(id), &z, |b, z| {
                    let mut grad = [0.0; 4];
                    let mut hess = [0.0; 16];
                    b.iter(|| {
                        log_f_with_path(
                            black_box(z),
                            path,
                            Some(&mut grad),
                            hessian.then_some(&mut hess[..]),
                        )
                        .unwrap()
                    })
                });
            }
        }
    }
    g.finish();
    // ω of a concentrated d = 4 Bingham (the AHRS's posteriors: every |z| in the thousands):
    // through the distribution (the crate's callers: the concentrated series where its bound
    // holds) against the public log F + ∇ (always the quadrature)
    let mut g = c.benchmark_group("omega_concentrated_d4");
    for z in [[-9000.0, -6500.0, -3000.0, 0.0], [-4e4, -4e4, -2e3, 0.0]] {
        let name = format!("({},{},{},0)", z[0], z[1], z[2]);
        let b4 = Bingham::new(DMatrix::identity(4, 4), DVector::from_column_slice(&z)).unwrap();
        g.bench_function(BenchmarkId::new("bingham_omega", &name), |b| {
            b.iter(|| black_box(&b4).omega().unwrap())
        });
        g.bench_function(BenchmarkId::new("quadrature", &name), |b| {
            let mut grad = [0.0; 4];
            b.iter(|| {
                log_normalization_into(black_box(&z), Method::Exact, Some(&mut grad), None).unwrap()
            })
        });
    }
    g.finish();
    let mut g = c.benchmark_group("log_f_grad_general");
    for d in [5usize, 8] {
        let z: Vec<f64> = (0..d).map(|i| -10.0 * (d - 1 - i) as f64).collect();
        g.bench_with_input(BenchmarkId::from_parameter(format!("d={d}")), &z, |b, z| {
            let mut grad = vec![0.0; z.len()];
            b.iter(|| {
                log_normalization_into(black_box(z), Method::Exact, Some(&mut grad), None).unwrap()
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(std::time::Duration::from_millis(500)).measurement_time(std::time::Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
