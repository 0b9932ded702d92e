//! Helpers of the AHRS and smoother tests (`tests/ahrs*.rs`, `tests/smoother.rs`), independent
//! of the crate's own quaternion code: the orientation `q = (w, x, y, z)` maps the sensor frame
//! to the world frame.

use crate::rot;

/// `q / |q|`.
pub fn normalize4(q: &[f64; 4]) -> [f64; 4] {
    let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    q.map(|x| x / n)
}

/// `R(q)ᵀ v`: a world vector in the sensor frame.
pub fn to_sensor(q: &[f64; 4], v: &[f64; 3]) -> [f64; 3] {
    let r = rot(q);
    std::array::from_fn(|i| r[0][i] * v[0] + r[1][i] * v[1] + r[2][i] * v[2])
}

/// The rotation angle (rad) between two orientations, `2 acos |⟨a, b⟩|`.
pub fn angle(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    let d = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]).abs();
    2.0 * d.min(1.0).acos()
}

/// The root mean square.
pub fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}
