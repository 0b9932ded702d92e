//! The AHRS harness's inputs and checks: the getters as bits, a simulated IMU, spoiled samples,
//! realistic and hostile arguments of `bingham_ahrs_set_state` with the status they must get, and
//! the check of an accepted state.

use bingham::ffi::bingham_status::*;
use bingham::ffi::*;
use testkit::fuzz::{
    check_state, check_unit, concentration, extreme, identity, non_finite, orthogonal,
    orthogonality_error, z_moderate, z_vector,
};
use testkit::{norm, Rng64};

use crate::case::spoil;
use crate::kinds::Kind::*;
use crate::status::last_error;
use crate::vectors::rotate;

pub(crate) fn ahrs_sentinel() -> *mut bingham_ahrs {
    0xDEAD_BEE0usize as *mut bingham_ahrs
}

/// The largest turn (rad) of one gyroscope sample, `|gyr|·dt`, beyond which the sample is
/// refused (not a rate).
pub(crate) const MAX_TURN: f64 = 1e6;

/// The range of a sample's time step (s): `BINGHAM_AHRS_MIN_SAMPLE_TIME` to
/// `BINGHAM_AHRS_MAX_STEP_TIME`.
pub(crate) const STEP_RANGE: std::ops::RangeInclusive<f64> = 1e-6..=10.0;

/// What the AHRS makes of a gyroscope sample taken `h` seconds after the previous one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Gyro {
    /// a rate, used
    Usable,
    /// "no gyroscope sample" (a gap the AHRS carries the orientation through): a NaN/±Inf
    /// entry
    Gap,
    /// refused: finite, turning by more than [`MAX_TURN`] rad in `h` (entries so large that
    /// the vector's norm overflows included)
    Refused,
    /// within rounding of the limit (the library's step may be `h` snapped to the nominal
    /// period): either
    Ambiguous,
}

pub(crate) fn gyro_kind(g: &[f64], h: f64) -> Gyro {
    let n = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    if g.iter().any(|v| !v.is_finite()) {
        return Gyro::Gap;
    }
    let turn = n * h;
    if (turn - MAX_TURN).abs() <= 1e-5 * MAX_TURN {
        Gyro::Ambiguous
    } else if !turn.is_finite() || turn > MAX_TURN {
        Gyro::Refused
    } else {
        Gyro::Usable
    }
}

/// The health readout (`bingham_ahrs_health`).
pub(crate) fn ahrs_health(a: *const bingham_ahrs) -> Result<bingham_ahrs_health_report, String> {
    // SAFETY: a plain struct of numbers; a is live.
    let mut h: bingham_ahrs_health_report = unsafe { std::mem::zeroed() };
    let st = unsafe { bingham_ahrs_health(a, &mut h) };
    if st != BINGHAM_OK {
        return Err(format!("bingham_ahrs_health: {}", last_error()));
    }
    Ok(h)
}

/// Everything the getters show, as bits: q (4), M (16), z (4), bias (3), spread (4), the bias
/// covariance (9: finite, symmetric to 1e-12 of its largest variance, diagonal ≥ 0), the
/// orientation covariance (9: finite, symmetric to 1e-14 of its trace, diagonal ≥ 0, 2×2
/// principal minors ≥ 0 up to rounding, the trace the square of the total spread,
/// within 1e-12 relative), the health readout (its 11 doubles, finite, the missing times ≥ 0, and the
/// reference flag), and the magnetometer latency estimate (status, value: OK with a finite
/// value ≥ 0, or NOT_CONVERGED with the output untouched).
pub(crate) fn ahrs_bits(a: *const bingham_ahrs) -> Result<Vec<u64>, String> {
    let (mut q, mut m, mut z, mut b, mut s) = ([0.0; 4], [0.0; 16], [0.0; 4], [0.0; 3], [0.0; 4]);
    let mut g = [0.0; 3];
    let (mut c, mut oc) = ([0.0; 9], [0.0; 9]);
    // SAFETY: a is live; buffers of the documented lengths.
    let sts = unsafe {
        [
            bingham_ahrs_quaternion(a, q.as_mut_ptr()),
            bingham_ahrs_state(a, m.as_mut_ptr(), z.as_mut_ptr()),
            bingham_ahrs_gyro_bias(a, b.as_mut_ptr()),
            bingham_ahrs_gyro_scale(a, g.as_mut_ptr()),
            bingham_ahrs_gyro_bias_covariance(a, c.as_mut_ptr()),
            bingham_ahrs_orientation_covariance(a, oc.as_mut_ptr()),
        ]
    };
    if sts.iter().any(|&st| st != BINGHAM_OK) {
        return Err(format!("a getter failed: {}", last_error()));
    }
    // SAFETY: as above.
    let st = unsafe { bingham_ahrs_angular_spread(a, s.as_mut_ptr()) };
    if st != BINGHAM_OK {
        // log F is total for every finite z: the moments of any valid state can be evaluated.
        return Err(format!("angular spread failed: {}", last_error()));
    }
    let mut l = [f64::from_bits(0x7FF4_DEAD_BEEF_0001)];
    // SAFETY: as above.
    let st = unsafe { bingham_ahrs_mag_latency_estimate(a, l.as_mut_ptr()) };
    match st {
        BINGHAM_OK if l[0].is_finite() && l[0] >= 0.0 => {}
        BINGHAM_ERR_NOT_CONVERGED if l[0].to_bits() == 0x7FF4_DEAD_BEEF_0001 => {}
        _ => {
            return Err(format!(
                "latency estimate: status {st:?}, value {:e} ({})",
                l[0],
                last_error()
            ))
        }
    }
    check_unit(&q, 1e-12).map_err(|e| format!("quaternion {q:?}: {e}"))?;
    if q[0] < 0.0 {
        return Err(format!("quaternion {q:?} with w < 0"));
    }
    check_state(&m, &z, 4).map_err(|e| format!("AHRS state: {e}"))?;
    if b.iter()
        .chain(&s)
        .any(|v| !v.is_finite() || (s.contains(v) && *v < 0.0))
    {
        return Err(format!("bias {b:?} / spread {s:?}"));
    }
    // the scale error is clipped to ±0.05 (the header's contract)
    if g.iter().any(|v| !v.is_finite() || v.abs() > 0.05) {
        return Err(format!("gyroscope scale {g:?}: not finite or beyond ±0.05"));
    }
    let scale = (0..3).map(|i| c[4 * i]).fold(0.0, f64::max);
    let asymmetric =
        (0..3).any(|i| (0..3).any(|j| (c[3 * i + j] - c[3 * j + i]).abs() > 1e-12 * scale));
    if c.iter().any(|v| !v.is_finite()) || (0..3).any(|i| c[4 * i] < 0.0) || asymmetric {
        return Err(format!(
            "bias covariance {c:?} (scale {scale:e}): not finite, symmetric, diagonal ≥ 0"
        ));
    }
    // The header states trace == spread[3]² (to rounding): both take the pending process
    // noise's positive semi-definite part, also after a step with strong coupling (fast
    // rotation, a step of seconds), where that noise has negative parts.
    let tr = oc[0] + oc[4] + oc[8];
    let s2 = s[3] * s[3];
    let asymmetric =
        (0..3).any(|i| (0..3).any(|j| (oc[3 * i + j] - oc[3 * j + i]).abs() > 1e-14 * tr));
    let minors_ok = (0..3).all(|i| {
        let j = (i + 1) % 3;
        oc[4 * i] * oc[4 * j] - oc[3 * i + j] * oc[3 * j + i] >= -1e-13 * tr * tr
    });
    if oc.iter().any(|v| !v.is_finite())
        || (0..3).any(|i| oc[4 * i] < 0.0)
        || asymmetric
        || !minors_ok
        || (s2 - tr).abs() > 1e-12 * tr
    {
        return Err(format!(
            "orientation covariance {oc:?} (trace {tr:e}, spread² {s2:e}): not finite, \
             symmetric, positive semi-definite with the trace the squared total spread"
        ));
    }
    let h = ahrs_health(a)?;
    let hv = [
        h.score,
        h.gravity_score,
        h.tilt_score,
        h.heading_score,
        h.tilt_innovation,
        h.heading_innovation,
        h.mag_rejected,
        h.mag_dip,
        h.gyr_missing_time,
        h.acc_missing_time,
        h.mag_missing_time,
    ];
    if hv.iter().any(|v| !v.is_finite())
        || hv[8..].iter().any(|&v| v < 0.0)
        || !(h.has_mag_reference == 0 || h.has_mag_reference == 1)
    {
        return Err(format!(
            "health readout {hv:?}, reference {}",
            h.has_mag_reference
        ));
    }
    Ok(q.iter()
        .chain(&m)
        .chain(&z)
        .chain(&b)
        .chain(&g)
        .chain(&s)
        .chain(&c)
        .chain(&oc)
        .chain(&hv)
        .chain(&l)
        .map(|v| v.to_bits())
        .chain([st as u64, h.has_mag_reference as u64])
        .collect())
}

/// A simulated IMU: a true orientation turning with a random smooth rate; gravity up, a field
/// pointing north and down (ENU), plus noise and occasional linear accelerations.
pub(crate) struct Imu {
    pub(crate) q: [f64; 4],
    pub(crate) w: [f64; 3],
}

impl Imu {
    pub(crate) fn sample(&mut self, rng: &mut Rng64, dt: f64) -> [[f64; 3]; 3] {
        for w in self.w.iter_mut() {
            *w = 0.98 * *w + 0.1 * rng.normal();
        }
        let dt = if dt.is_finite() { dt.min(0.1) } else { 0.01 };
        let h = 0.5 * dt;
        let dq = [1.0, h * self.w[0], h * self.w[1], h * self.w[2]];
        let q = self.q;
        let mut p = [
            q[0] * dq[0] - q[1] * dq[1] - q[2] * dq[2] - q[3] * dq[3],
            q[0] * dq[1] + q[1] * dq[0] + q[2] * dq[3] - q[3] * dq[2],
            q[0] * dq[2] - q[1] * dq[3] + q[2] * dq[0] + q[3] * dq[1],
            q[0] * dq[3] + q[1] * dq[2] - q[2] * dq[1] + q[3] * dq[0],
        ];
        let n = norm(&p);
        p.iter_mut().for_each(|v| *v /= n);
        self.q = p;
        let conj = [p[0], -p[1], -p[2], -p[3]];
        let lin = if rng.chance(0.05) { 3.0 } else { 0.0 };
        let acc = rotate(&conj, &[lin, 0.0, 9.81]);
        let mag = rotate(&conj, &[0.0, 20.0, -40.0]);
        let gyr = [0, 1, 2].map(|i| self.w[i] + 0.002 * rng.normal());
        [
            gyr,
            acc.map(|v| v + 0.05 * rng.normal()),
            mag.map(|v| v + 0.3 * rng.normal()),
        ]
    }
}

/// Spoils one entry or vector of a sample (0 gyroscope, 1 accelerometer, 2 magnetometer);
/// returns the vector made non-finite, if any (each means "no sample" of that sensor, except
/// the accelerometer of the first sample, which is refused; a finite gyroscope is refused when
/// it turns by more than [`MAX_TURN`] rad in the sample, see [`gyro_kind`]).
pub(crate) fn spoil_sample(rng: &mut Rng64, s: &mut [[f64; 3]; 3]) -> (Option<usize>, String) {
    let v = rng.below(3);
    match rng.below(4) {
        0 | 1 => {
            let i = rng.below(3);
            s[v][i] = non_finite(rng);
            (Some(v), format!("sample[{v}][{i}] = {}", s[v][i]))
        }
        2 => {
            let i = rng.below(3);
            s[v][i] = extreme(rng);
            (None, format!("sample[{v}][{i}] = {:e}", s[v][i]))
        }
        _ => {
            let f = *rng.pick(&[0.0, 1e-300, 5e-324, 1e154, 1e300, f64::MAX, -1.0]);
            s[v].iter_mut().for_each(|x| *x *= f);
            (None, format!("sample[{v}] *= {f:e}"))
        }
    }
}

/// Arguments of `bingham_ahrs_set_state`: M (4×4 row-major) and z, with a description.
/// Realistic (the mode at or near the true orientation, a start uncertainty) or hostile: any
/// orthogonal M, huge / tiny / subnormal / positive / repeated z, z spanning more than a double,
/// any order and shift, M not orthogonal (or within the tolerance), NaN/Inf entries.
pub(crate) fn ahrs_state_args(rng: &mut Rng64, truth: &[f64; 4]) -> (Vec<f64>, Vec<f64>, String) {
    let mut desc = String::new();
    let mut m = match rng.below(4) {
        0 => identity(4),
        1 => orthogonal(rng, 4),
        _ => {
            // columns q⊗i, q⊗j, q⊗k, q (left multiplication by q): the mode is q
            let s = if rng.chance(0.5) {
                0.0
            } else {
                rng.log_uniform(-6.0, 0.0)
            };
            let q: Vec<f64> = truth.iter().map(|v| v + s * rng.normal()).collect();
            let n = norm(&q);
            let [w, x, y, z] = [0, 1, 2, 3].map(|i| q[i] / n);
            let l = [[w, -x, -y, -z], [x, w, -z, y], [y, z, w, -x], [z, -y, x, w]];
            (0..16).map(|k| l[k / 4][(k % 4 + 1) % 4]).collect()
        }
    };
    let mut z: Vec<f64> = match rng.below(8) {
        0..=3 => {
            // a start uncertainty: the last column the most concentrated
            let k = rng.log_uniform(-1.0, 7.0);
            (0..4)
                .map(|i| {
                    if i == 3 {
                        0.0
                    } else {
                        -k * rng.range(0.5, 2.0)
                    }
                })
                .collect()
        }
        4 => z_vector(rng, 4),
        5 => (0..4)
            .map(|_| {
                *rng.pick(&[
                    -f64::MAX,
                    -1e300,
                    -1e200,
                    -1e15,
                    -1e-300,
                    -5e-324,
                    -0.0,
                    0.0,
                    5e-324,
                    1e300,
                    f64::MAX,
                ])
            })
            .collect(),
        6 => {
            // spanning about the largest double (beyond it: refused)
            let mut z = z_moderate(rng, 4);
            let i = rng.below(4);
            let j = (i + 1 + rng.below(3)) % 4;
            z[i] = *rng.pick(&[f64::MAX, 1e308, 9e307, 8.9e307]);
            z[j] = -*rng.pick(&[f64::MAX, 1e308, 9e307, 8.9e307, 1e300]);
            z
        }
        _ => vec![concentration(rng); 4], // uniform
    };
    if rng.chance(0.2) {
        let c = rng.range(-1e3, 1e3);
        z.iter_mut().for_each(|v| *v += c);
        desc += &format!("z += {c:e}; ");
    }
    if rng.chance(0.3) {
        // another order: the columns of M along
        let (i, j) = (rng.below(4), rng.below(4));
        z.swap(i, j);
        for r in 0..4 {
            m.swap(r * 4 + i, r * 4 + j);
        }
    }
    match rng.below(12) {
        0 => {
            let i = rng.below(16);
            m[i] = non_finite(rng);
            desc += &format!("M[{i}] = {}", m[i]);
        }
        1 => {
            let i = rng.below(4);
            z[i] = non_finite(rng);
            desc += &format!("z[{i}] = {}", z[i]);
        }
        2 | 3 => desc += &spoil(rng, M, &mut m, 4),
        _ => {}
    }
    (m, z, desc)
}

/// The status `bingham_ahrs_set_state` must return for valid pointers: `INVALID_ARGUMENT` for
/// NaN/Inf, M not orthogonal or z spanning more than a double, else `OK`; `None` where M is so
/// close to the orthogonality tolerance that rounding decides.
pub(crate) fn ahrs_state_expected(m: &[f64], z: &[f64]) -> Option<bingham_status> {
    if m.iter().chain(z).any(|v| !v.is_finite()) {
        return Some(BINGHAM_ERR_INVALID_ARGUMENT);
    }
    let e = orthogonality_error(m, 4);
    let mx = z.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let mn = z.iter().cloned().fold(f64::INFINITY, f64::min);
    if e.is_nan() || e > 2e-6 || !(mx - mn).is_finite() {
        Some(BINGHAM_ERR_INVALID_ARGUMENT)
    } else if e > 0.5e-6 {
        None
    } else {
        Some(BINGHAM_OK)
    }
}

/// After an accepted `bingham_ahrs_set_state(a, m, z)`: the state is the normalized
/// Bingham(m, z) (z sorted ascending and shifted to z[3] = 0, each column of M with its z, up
/// to sign and within groups of equal z), and the quaternion is ± the mode of Bingham(m, z),
/// exactly the last column of the state's M with w ≥ 0.
pub(crate) fn check_set_state(a: *const bingham_ahrs, m: &[f64], z: &[f64]) -> Result<(), String> {
    let (mut q, mut ms, mut zs) = ([0.0; 4], [0.0; 16], [0.0; 4]);
    // SAFETY: a is live; buffers of the documented lengths.
    let sts = unsafe {
        [
            bingham_ahrs_quaternion(a, q.as_mut_ptr()),
            bingham_ahrs_state(a, ms.as_mut_ptr(), zs.as_mut_ptr()),
        ]
    };
    if sts.iter().any(|&st| st != BINGHAM_OK) {
        return Err(format!("a getter failed: {}", last_error()));
    }
    let mut sorted = z.to_vec();
    sorted.sort_by(f64::total_cmp);
    let want_z: Vec<f64> = (0..4)
        .map(|k| if k == 3 { 0.0 } else { sorted[k] - sorted[3] })
        .collect();
    if zs.iter().zip(&want_z).any(|(a, b)| a != b) {
        return Err(format!("state z {zs:?}, expected {want_z:?}"));
    }
    let col = |m: &[f64], i: usize| -> Vec<f64> {
        let c: Vec<f64> = (0..4).map(|r| m[r * 4 + i]).collect();
        let n = norm(&c);
        c.iter().map(|v| v / n).collect()
    };
    let dot = |u: &[f64], v: &[f64]| -> f64 { u.iter().zip(v).map(|(a, b)| a * b).sum() };
    // |u|² within the span of the given columns whose z equals v (≈ 1 if u lies in it)
    let in_span = |u: &[f64], v: f64| -> f64 {
        (0..4)
            .filter(|&i| z[i] == v)
            .map(|i| dot(u, &col(m, i)).powi(2))
            .sum()
    };
    let tol = 1e-12 + 8.0 * orthogonality_error(m, 4);
    for (k, &v) in sorted.iter().enumerate() {
        let s = in_span(&col(&ms, k), v);
        if (s - 1.0).abs() > tol {
            return Err(format!(
                "state column {k} is not a principal direction of z = {v:e} (|proj|² = {s})"
            ));
        }
    }
    let c3: Vec<f64> = (0..4).map(|r| ms[r * 4 + 3]).collect();
    let want_q: Vec<f64> = if c3[0] < 0.0 {
        c3.iter().map(|v| -v).collect()
    } else {
        c3
    };
    if q.iter()
        .zip(&want_q)
        .any(|(a, b)| a.to_bits() != b.to_bits())
    {
        return Err(format!(
            "quaternion {q:?} is not ± the last column of the state's M {want_q:?}"
        ));
    }
    let s = in_span(&q, sorted[3]);
    if (s - 1.0).abs() > tol {
        return Err(format!(
            "quaternion {q:?} is not ± the mode of the given state (|proj|² = {s})"
        ));
    }
    Ok(())
}
