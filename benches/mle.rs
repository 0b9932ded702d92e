//! MLE from a second moment (criterion). Targets: d = 4 ≤ 4 µs each (issue 11; measured figures in docs/speed.md).

use bingham::{mle_from_second_moment, Bingham};
use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use nalgebra::{DMatrix, DVector};

fn rotation(d: usize) -> DMatrix<f64> {
    let g = DMatrix::from_fn(d, d, |i, j| {
        ((i * 7 + j * 3) as f64 * 0.37).sin() + if i == j { 2.0 } else { 0.0 }
    });
    g.qr().q()
}

fn bench(c: &mut Criterion) {
    let cases: Vec<(&str, Vec<f64>)> = vec![
        ("d2 z=-1", vec![-1.0, 0.0]),
        ("d2 z=-1e4", vec![-1e4, 0.0]),
        ("d2 z=-1e6", vec![-1e6, 0.0]),
        ("d3 (-100,-10,0)", vec![-100.0, -10.0, 0.0]),
        ("d4 (-1,-1,-1,0)", vec![-1.0, -1.0, -1.0, 0.0]),
        ("d4 (-200,-200,-2,0)", vec![-200.0, -200.0, -2.0, 0.0]),
        ("d4 (-1e4,-1e3,-1e2,0)", vec![-1e4, -1e3, -1e2, 0.0]),
        ("d4 (-1e6,-10,-1,0)", vec![-1e6, -10.0, -1.0, 0.0]),
    ];
    let mut g = c.benchmark_group("mle_from_second_moment");
    for (name, z) in cases {
        let d = z.len();
        let s = Bingham::new(rotation(d), DVector::from_vec(z))
            .unwrap()
            .second_moment()
            .unwrap();
        g.bench_with_input(BenchmarkId::from_parameter(name), &s, |b, s| {
            b.iter(|| mle_from_second_moment(black_box(s)).unwrap())
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
