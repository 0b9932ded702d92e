//! The offline smoother (criterion): `bingham::smoother::smooth` over 10 s of the shared
//! simulated IMU stream (`imu_stream.rs`) at 286 Hz (BROAD's rate) and 100 Hz, the whole
//! recording per iteration; criterion's throughput gives the time per sample. The online AHRS
//! over the same samples (`ahrs_batch_…`) is the peer: the smoother is two AHRS passes and the
//! product of their densities per sample. 10 s is below the smoother's threshold for running
//! its passes concurrently (`HANDOFF_TIME + PARALLEL_TIME`, 60 s): these medians are the
//! one-thread path (CPU time and wall time alike); `examples/python/bench_smooth.py` times the
//! two-thread path on BROAD's three-minute trials.

use bingham::ahrs::{Ahrs, AhrsParams};
use bingham::smoother::{smooth, SmoothInput, SmoothOutput};
use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};

mod imu_stream;

fn bench_smoother(c: &mut Criterion) {
    let mut g = c.benchmark_group("smoother");
    for (name, dt) in [("286hz", 1.0f64 / 285.714), ("100hz", 0.01)] {
        let n = (10.0 / dt).round() as usize;
        let data = imu_stream::stream(dt, n);
        let gyr: Vec<[f64; 3]> = data.iter().map(|s| s[0]).collect();
        let acc: Vec<[f64; 3]> = data.iter().map(|s| s[1]).collect();
        let mag: Vec<[f64; 3]> = data.iter().map(|s| s[2]).collect();
        let p = AhrsParams::new(dt);
        let mut quat = vec![[0.0; 4]; n];
        let mut spread = vec![0.0; n];
        g.throughput(Throughput::Elements(n as u64));
        g.bench_function(format!("smooth_{name}"), |b| {
            b.iter(|| {
                let input = SmoothInput {
                    time: None,
                    gyr: black_box(&gyr),
                    acc: black_box(&acc),
                    mag: Some(black_box(&mag)),
                };
                let out = SmoothOutput {
                    quat: &mut quat,
                    spread: Some(&mut spread),
                    bias: None,
                    covariance: None,
                };
                smooth(&p, &input, out).unwrap();
            })
        });
        g.bench_function(format!("ahrs_batch_{name}"), |b| {
            b.iter(|| {
                let mut a = Ahrs::new(&p).unwrap();
                a.update_batch(
                    black_box(&gyr),
                    black_box(&acc),
                    Some(black_box(&mag)),
                    &mut quat,
                    Some(&mut spread),
                )
                .unwrap();
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(3))
        .sample_size(10);
    targets = bench_smoother
}
criterion_main!(benches);
