//! log F + gradient for d ≥ 5 (the steepest-descent Laplace inversion, `normalization/general.rs`)
//! over several shapes of `z` (criterion). Target: d = 8 ≤ 30 µs.
//!
//! Cases (d = 8 unless named otherwise): `ladder` `z_i = −10·(d−1−i)` (as in
//! `benches/normalization.rs`), `uniform` (`z = 0`), `one_huge` (one `|z| = 1e6`, the rest
//! moderate), `cluster` (seven near-equal values far from the mode, the slowest-converging shape
//! known), `near_ties` (two pairs a hair apart), `random_lin` (uniform in `[−1e6, 0]⁸`),
//! `random_log` (log-uniform magnitudes in `[1e-3, 1e6]`); `d5_ladder`; and `ladder_hess`
//! (with the Hessian).

use bingham::normalization::{log_normalization_into, Method};
use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};

/// Deterministic uniform numbers in [0, 1).
fn uniform(n: usize, mut state: u64) -> Vec<f64> {
    (0..n)
        .map(|_| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        })
        .collect()
}

fn cases() -> Vec<(&'static str, Vec<f64>)> {
    let ladder = |d: usize| {
        (0..d)
            .map(|i| -10.0 * (d - 1 - i) as f64)
            .collect::<Vec<f64>>()
    };
    let mut random_lin: Vec<f64> = uniform(8, 11).iter().map(|u| -1e6 * u).collect();
    random_lin[7] = 0.0;
    let random_log: Vec<f64> = uniform(8, 23)
        .iter()
        .map(|u| -(10f64).powf(-3.0 + 9.0 * u))
        .collect();
    vec![
        ("ladder", ladder(8)),
        ("uniform", vec![0.0; 8]),
        (
            "one_huge",
            vec![-1e6, -30.0, -20.0, -10.0, -5.0, -2.0, -1.0, 0.0],
        ),
        (
            "cluster",
            vec![-40.0, -39.0, -38.0, -37.0, -36.0, -35.0, -34.0, 0.0],
        ),
        (
            "near_ties",
            vec![
                -300.0,
                -50.0,
                -20.0,
                -20.0 + 1e-9,
                -3.0,
                -3.0 + 1e-6,
                -1.0,
                0.0,
            ],
        ),
        ("random_lin", random_lin),
        ("random_log", random_log),
        ("d5_ladder", ladder(5)),
    ]
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("log_f_grad_d8");
    for (name, z) in cases() {
        g.bench_with_input(BenchmarkId::from_parameter(name), &z, |b, z| {
            let mut grad = vec![0.0; z.len()];
            b.iter(|| {
                log_normalization_into(black_box(z), Method::Exact, Some(&mut grad), None).unwrap()
            })
        });
    }
    let z: Vec<f64> = (0..8).map(|i| -10.0 * (7 - i) as f64).collect();
    g.bench_with_input(BenchmarkId::from_parameter("ladder_hess"), &z, |b, z| {
        let (mut grad, mut hess) = (vec![0.0; 8], vec![0.0; 64]);
        b.iter(|| {
            log_normalization_into(
                black_box(z),
                Method::Exact,
                Some(&mut grad),
                Some(&mut hess),
            )
            .unwrap()
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(std::time::Duration::from_millis(500)).measurement_time(std::time::Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
