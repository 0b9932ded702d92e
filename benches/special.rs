//! Throughput of the scaled Bessel functions (`i01e` is called at every quadrature node of the
//! d = 3, 4 normalization constant).
//!
//! Each benchmark evaluates 1024 arguments per iteration and reports elements per second; divide the
//! median time by 1024 for the cost of one call. The code paths: pieces of width 1/4 on [0, 8),
//! 16 pieces per octave on [8, 128), asymptotic series beyond. "sweep" mimics a quadrature rule
//! (arguments sorted; 13 % below 8, 31 % in [8, 128), 56 % beyond); "shuffled" is the same set in
//! random order, so the branch between the code paths is unpredictable.

use std::hint::black_box;

use bingham::special::{bessel_q, i01e};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use testkit::Lcg;

const N: usize = 1024;

/// Deterministic uniform numbers in [0, 1).
fn uniform(n: usize, seed: u64) -> Vec<f64> {
    let mut r = Lcg(seed);
    (0..n).map(|_| r.uniform()).collect()
}

fn sets() -> Vec<(&'static str, Vec<f64>)> {
    let u = uniform(N, 7);
    let small: Vec<f64> = u.iter().map(|v| 8.0 * v).collect();
    let medium: Vec<f64> = u.iter().map(|v| 8.0 + 120.0 * v).collect();
    let large: Vec<f64> = u
        .iter()
        .map(|v| 128.0 * (1e6f64 / 128.0).powf(*v))
        .collect();
    // x = u·z/2 at the nodes u of a rule on [0, 1], |z| = 1000: half of them uniform, half
    // clustered near 0 (as after a substitution that resolves a boundary layer).
    let mut sweep: Vec<f64> = (0..N)
        .map(|k| {
            let v = (k as f64 + 0.5) / N as f64;
            if k % 2 == 0 {
                500.0 * v
            } else {
                500.0 * v * v * v
            }
        })
        .collect();
    sweep.sort_by(f64::total_cmp);
    let mut shuffled = sweep.clone();
    let keys = uniform(N, 11);
    let mut idx: Vec<usize> = (0..N).collect();
    idx.sort_by(|&a, &b| keys[a].total_cmp(&keys[b]));
    for (dst, &src) in shuffled.iter_mut().zip(&idx) {
        *dst = sweep[src];
    }
    vec![
        ("small [0,8)", small),
        ("medium [8,128)", medium),
        ("large [128,1e6]", large),
        ("sweep [0,500]", sweep),
        ("shuffled [0,500]", shuffled),
    ]
}

fn bench(c: &mut Criterion) {
    let sets = sets();
    let mut g = c.benchmark_group("i01e");
    g.throughput(Throughput::Elements(N as u64));
    for (name, xs) in &sets {
        g.bench_function(*name, |b| {
            b.iter(|| {
                let mut acc = 0.0;
                for &x in black_box(xs.as_slice()) {
                    let (i0, i1, d) = i01e(x);
                    acc += i0 + i1 + d;
                }
                acc
            })
        });
    }
    g.finish();

    let mut g = c.benchmark_group("bessel_q");
    g.throughput(Throughput::Elements(N as u64));
    let (name, xs) = &sets[3];
    g.bench_function(*name, |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &x in black_box(xs.as_slice()) {
                acc += bessel_q(x);
            }
            acc
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
