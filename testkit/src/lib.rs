//! Test helpers of the bingham crate, shared by its unit tests (`src/`), integration tests
//! (`tests/`) and benchmarks (`benches/`). Dev-only (never published) and independent of
//! `bingham`, so that the library's own unit tests can use it as well.
//!
//! - the deterministic generators: SplitMix64 [`Rng64`] (and [`mix`] for per-case seeds),
//!   xorshift64 ([`xorshift`], [`xorshift_uniform`], [`XorShift64`]) and an LCG ([`Lcg`]);
//! - [`read_reference`]: the high-precision reference tables `tests/data/normalization_d*.csv`;
//! - independent references: [`rel`], [`norm`], the 3-vector helpers [`dot3`], [`dist3`],
//!   [`matvec`], the textbook rotation matrix [`rot`], [`gauss_legendre`];
//! - [`imu`]: the AHRS and smoother tests' orientation helpers (angle, world → sensor, RMS);
//! - [`fuzz`]: generators of valid and hostile inputs, sentinel-guarded buffers, invariant checks
//!   and a crash reporter (the C ABI fuzz harness, the thread and long-run tests);
//! - [`scenarios`]: the filter scenarios of JAIF Sec. 7 and their simulation, given the
//!   library's sampler.

pub mod fuzz;
pub mod imu;
mod reference;
mod rng;
pub mod scenarios;

pub use reference::{read_reference, RefRow};
pub use rng::{mix, xorshift, xorshift_uniform, Lcg, Rng64, XorShift64};

/// Relative error |a − b| / |b| (absolute when |b| < floor).
pub fn rel(a: f64, b: f64, floor: f64) -> f64 {
    (a - b).abs() / b.abs().max(floor)
}

/// The Euclidean norm.
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// `a · b` of 3-vectors.
pub fn dot3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `|a − b|` of 3-vectors.
pub fn dist3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// `R v` for a 3×3 matrix given by its rows.
pub fn matvec(r: &[[f64; 3]; 3], v: &[f64; 3]) -> [f64; 3] {
    [
        r[0][0] * v[0] + r[0][1] * v[1] + r[0][2] * v[2],
        r[1][0] * v[0] + r[1][1] * v[1] + r[1][2] * v[2],
        r[2][0] * v[0] + r[2][1] * v[1] + r[2][2] * v[2],
    ]
}

/// The Hamilton product `a b` (scalar first), written out (independent of the crate's `q4`).
pub fn qmul(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// The unit quaternion of the rotation vector `w` (rad): `(cos(θ/2), sin(θ/2) w/θ)`, θ = |w|.
pub fn qexp(w: &[f64; 3]) -> [f64; 4] {
    let th = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    if th == 0.0 {
        return [1.0, 0.0, 0.0, 0.0];
    }
    let s = (0.5 * th).sin() / th;
    [(0.5 * th).cos(), s * w[0], s * w[1], s * w[2]]
}

/// `R(q)` of a unit quaternion (scalar first, `v_world = q v q*`), the textbook formula.
pub fn rot(q: &[f64; 4]) -> [[f64; 3]; 3] {
    let (w, x, y, z) = (q[0], q[1], q[2], q[3]);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton on the three-term recurrence; written
/// here, independent of the library's).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    use std::f64::consts::PI;
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n {
        let mut t = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, t);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * t * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (t * p1 - p0) / (t * t - 1.0);
            let dt = p1 / dp;
            t -= dt;
            if dt.abs() < 1e-16 {
                break;
            }
        }
        x[i] = t;
        w[i] = 2.0 / ((1.0 - t * t) * dp * dp);
    }
    (x, w)
}
