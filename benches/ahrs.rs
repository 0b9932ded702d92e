//! The AHRS and the vector-observation helpers (criterion).
//!
//! The AHRS runs on a pre-generated simulated IMU stream at 100 Hz (smooth motion, gyroscope
//! bias and noise, accelerometer and magnetometer with noise), cycled: one sample per
//! iteration, so the state stays in its normal operating range. The same motion sampled at
//! 286 Hz and 1 kHz (`…_286hz`, `…_1khz`): the online latency estimate's work per sample grows
//! with its lag window (5, 13 and 33 lags).

use bingham::ahrs::{Ahrs, AhrsParams};
use bingham::filter::BinghamFilter;
use bingham::observation::{noise_from_angle_std, vector_observation};
use criterion::{black_box, criterion_group, criterion_main, Criterion};

mod imu_stream;

const DT: f64 = 0.01;

struct Sample {
    gyr: [f64; 3],
    acc: [f64; 3],
    mag: [f64; 3],
}

/// 60 s of simulated IMU data at 100 Hz.
fn stream() -> Vec<Sample> {
    stream_at(DT)
}

/// 60 s of simulated IMU data at the sample time `dt` (the shared stream, `imu_stream.rs`).
fn stream_at(dt: f64) -> Vec<Sample> {
    imu_stream::stream(dt, (60.0 / dt).round() as usize)
        .into_iter()
        .map(|[gyr, acc, mag]| Sample { gyr, acc, mag })
        .collect()
}

fn bench_ahrs(c: &mut Criterion) {
    let streams = [
        (DT, stream()),
        (1.0 / 285.714, stream_at(1.0 / 285.714)),
        (1e-3, stream_at(1e-3)),
    ];
    let mut g = c.benchmark_group("ahrs");
    for (name, with_mag, which) in [
        ("ahrs_update_gyr_acc_mag", true, 0),
        ("ahrs_update_gyr_acc", false, 0),
        ("ahrs_update_gyr_acc_mag_286hz", true, 1),
        ("ahrs_update_gyr_acc_mag_1khz", true, 2),
    ] {
        let (dt, data) = &streams[which];
        let mut a = Ahrs::new(&AhrsParams::new(*dt)).unwrap();
        let mut k = 0usize;
        g.bench_function(name, |b| {
            b.iter(|| {
                let s = &data[k % data.len()];
                k += 1;
                let mag = with_mag.then_some(&s.mag);
                a.update(black_box(&s.gyr), black_box(&s.acc), black_box(mag))
                    .unwrap();
            })
        });
    }
    g.finish();
}

/// The readouts of the stated uncertainty after 30 s of the 100 Hz stream: the spread along
/// the principal directions and the 3×3 covariance (both from the stated covariance, module
/// `ahrs::uncertainty`), what a batch call with spreads adds per sample.
fn bench_readout(c: &mut Criterion) {
    let data = stream();
    let mut a = Ahrs::new(&AhrsParams::new(DT)).unwrap();
    for s in &data[..3000] {
        a.update(&s.gyr, &s.acc, Some(&s.mag)).unwrap();
    }
    let mut g = c.benchmark_group("ahrs_readout");
    g.bench_function("angular_spread", |b| {
        let mut out = [0.0; 4];
        b.iter(|| {
            black_box(&a).angular_spread(&mut out).unwrap();
            black_box(out)
        })
    });
    g.bench_function("orientation_covariance", |b| {
        b.iter(|| black_box(&a).orientation_covariance().unwrap())
    });
    g.finish();
}

fn bench_vector(c: &mut Criterion) {
    let mut g = c.benchmark_group("vector");
    let dirs: Vec<[f64; 3]> = stream()
        .iter()
        .take(1000)
        .map(|s| {
            let n = (s.acc[0] * s.acc[0] + s.acc[1] * s.acc[1] + s.acc[2] * s.acc[2]).sqrt();
            [s.acc[0] / n, s.acc[1] / n, s.acc[2] / n]
        })
        .collect();
    let up = [0.0, 0.0, 1.0];
    let id = [
        1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    ];
    let fresh = || BinghamFilter::new(4, &id, &[-50.0, -50.0, -50.0, 0.0]).unwrap();
    let mut f = fresh();
    let mut k = 0usize;
    g.bench_function("filter_update_vector", |b| {
        b.iter(|| {
            // Restart now and then: without predictions the state only sharpens.
            if k % 100 == 0 {
                f = fresh();
            }
            let d = &dirs[k % dirs.len()];
            k += 1;
            f.update_vector(black_box(d), black_box(&up), black_box(3.0))
                .unwrap();
        })
    });
    let mut k = 0usize;
    g.bench_function("vector_observation", |b| {
        b.iter(|| {
            let d = &dirs[k % dirs.len()];
            k += 1;
            vector_observation(black_box(d), black_box(&up), black_box(3.0)).unwrap()
        })
    });
    g.bench_function("noise_from_angle_std", |b| {
        b.iter(|| noise_from_angle_std(black_box(4), black_box(0.01)).unwrap())
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(3));
    targets = bench_ahrs, bench_readout, bench_vector
}
criterion_main!(benches);
