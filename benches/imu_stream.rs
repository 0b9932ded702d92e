//! The simulated IMU stream the AHRS benchmarks share (`benches/ahrs.rs`, `benches/ffi.rs`):
//! smooth motion up to about 1.5 rad/s, a gyroscope bias of 0.008 rad/s per axis, white noise
//! of 0.005 rad/s, 0.05 m/s² and 0.5 µT per sample, a 44.7 µT field with a 63° dip.

use bingham::quaternion::q4;
use testkit::Rng64;

/// `n` samples `[gyr, acc, mag]` at the sample time `dt` (s).
pub fn stream(dt: f64, n: usize) -> Vec<[[f64; 3]; 3]> {
    let mut rng = Rng64(7);
    let mut q = [1.0, 0.0, 0.0, 0.0];
    let bias = [0.008, -0.008, 0.008];
    (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            let w = [
                0.9 * (0.7 * t).sin() + 0.3 * (5.2 * t).sin(),
                0.7 * (0.4 * t + 1.0).sin() + 0.25 * (3.8 * t).cos(),
                1.2 * (0.3 * t + 0.5).sin(),
            ];
            q = q4::mul(
                &q,
                &q4::from_rotation_vector(&[w[0] * dt, w[1] * dt, w[2] * dt]),
            );
            let a = q4::rotate_inverse(&q, &[0.0, 0.0, 9.81]);
            let m = q4::rotate_inverse(&q, &[0.0, 20.0, -40.0]);
            let gyr = [0, 1, 2].map(|i| w[i] + bias[i] + 0.005 * rng.normal());
            let acc = [0, 1, 2].map(|i| a[i] + 0.05 * rng.normal());
            let mag = [0, 1, 2].map(|i| m[i] + 0.5 * rng.normal());
            [gyr, acc, mag]
        })
        .collect()
}
