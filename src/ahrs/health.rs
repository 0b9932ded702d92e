//! The AHRS's health readout: how well the sensors agree with the model, so that a mistake in
//! the input (units, signs, axes, the period) shows instead of yielding a confident wrong
//! orientation.
//!
//! At every correction (module `ahrs`, step 5.4) the innovation of each sensor's evidence item
//! (module `evidence`) — the low-passed accelerometer direction `ā`, the heading error `δ` of
//! the averaged field — is compared with the prediction before the correction, each normalized by the variance it should have if the model held: the state's
//! own spread in that direction (from the prior's precision `Λ`, `Σ = (Λ + 3/π² I)⁻¹`, body
//! frame: no angle's variance exceeds a uniform angle's, π²/3) plus the
//! measurement's (`acc_noise²·(1 + ((|ā| − g)/acc_reject)²)` for the direction of "up",
//! `mag_noise²` for the heading — the parameters' own meaning). With `b̂` the predicted
//! body-frame "up" and `e` the tilt innovation (the angle between `b̂` and `ā` along the great
//! circle, a vector in the plane perpendicular to `b̂`):
//!
//! - tilt: `ν_a = eᵀ (P Σ' P + σ_a² P)⁺ e`, `Σ' = [b̂]× Σ [b̂]×ᵀ`, `P = I − b̂ b̂ᵀ` (2 degrees of
//!   freedom, a χ²₂ variable when the model holds and the errors are Gaussian);
//! - heading: `ν_m = δ² / (b̂ᵀ Σ b̂ + σ_m²)` (1 degree of freedom).
//!
//! Each is averaged per degree of freedom over [`HEALTH_TIME`] (an exponential average over
//! the corrections, which come every correction period at every sample rate), so that one burst of linear
//! acceleration does not count as a mistake while a wrong model, which disagrees all the time,
//! does. A third average does not depend on the state's spread: the gravity score
//! `((|ā| − g)/acc_reject)²`. The accelerometer is low-passed in the frame the gyroscope
//! integrates, where gravity keeps its norm only if the gyroscope turns that frame as the
//! sensor turns; a gain error (a gyroscope in °/s, a wrong sample time) turns gravity in that
//! frame and its average shrinks — while the rate-dependent process noise such a mistake
//! inflates would let the state's spread explain any innovation. The score is the largest of
//! the three averages: about 1 or less when the model holds, and the readout flags the input
//! when it exceeds [`HEALTH_THRESHOLD`].
//!
//! What the score cannot see, the readout reports directly: the fraction of magnetometer
//! samples the disturbance test refused over the last [`HEALTH_TIME`] (a magnetometer whose
//! axes are swapped or mirrored fails the test most of the time once the sensor turns), and the
//! field's dip. An accelerometer whose sign is flipped (gravity instead of specific force) is
//! consistent with every other signal — the negation commutes with every rotation, so an
//! upside-down world explains the samples as well as the right one — except through the sign
//! of the dip: the Earth's field points below the horizon north of the magnetic equator, so a
//! negative dip there means a flipped accelerometer (or magnetometer).

use std::f64::consts::PI;

use nalgebra::{Matrix3, Vector3};

use super::bias::pinv;
use super::evidence::{present, Evidence, Innovation};
use super::timing::SensorTimes;

/// The time constant (s) of the health averages (`BINGHAM_AHRS_HEALTH_TIME` in C): long enough that one burst of linear
/// acceleration (a fraction of a second) or a short magnetic disturbance does not raise the
/// score past the threshold, short enough to flag a wrong input within seconds of motion.
pub const HEALTH_TIME: f64 = 5.0;

/// The score above which the readout flags the input as inconsistent with the model
/// (`BINGHAM_AHRS_HEALTH_THRESHOLD` in C): the average normalized innovation is this many
/// times what the model predicts. Measured (python/tests/test_health.py, docs/accuracy.md
/// "AHRS health"): correct input stays at or below 2.5 on the simulated suite and the BROAD
/// recordings; a gyroscope in °/s and a sample time 2× or 0.5× the truth exceed it within
/// 10 s of motion.
pub const HEALTH_THRESHOLD: f64 = 10.0;

/// The AHRS's health readout (`bingham_ahrs_health_report` in C, from `bingham_ahrs_health()`):
/// how well the sensors have agreed with the model over the last `BINGHAM_AHRS_HEALTH_TIME`
/// (5 s). Definitions in docs/guide.md ("Health readout"), measured figures in
/// docs/accuracy.md ("AHRS health"). All values finite; before the first correction all zero.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AhrsHealth {
    /// The largest of `gravity_score`, `tilt_score` and `heading_score`: about 1 or less when
    /// the sensors agree with the model; above `BINGHAM_AHRS_HEALTH_THRESHOLD` (10) the input
    /// is likely wrong (a gyroscope in °/s instead of rad/s, a wrong sample time).
    pub score: f64,
    /// The squared deviation of the low-passed accelerometer's norm from `gravity`, in units
    /// of `acc_reject`, averaged over `BINGHAM_AHRS_HEALTH_TIME` (5 s).
    pub gravity_score: f64,
    /// The normalized tilt innovation per degree of freedom, averaged over `BINGHAM_AHRS_HEALTH_TIME` (5 s).
    pub tilt_score: f64,
    /// The normalized heading innovation, averaged over `BINGHAM_AHRS_HEALTH_TIME` (5 s) of corrections
    /// with a heading observation (0 without one).
    pub heading_score: f64,
    /// The angle (rad) between the predicted and the low-passed accelerometer's "up" at the
    /// last correction.
    pub tilt_innovation: f64,
    /// The heading error (rad, about the world vertical) of the averaged field at the last
    /// correction with a heading observation (0 without one).
    pub heading_innovation: f64,
    /// The fraction (0 to 1) of magnetometer samples the disturbance test refused, averaged
    /// over `BINGHAM_AHRS_HEALTH_TIME` (5 s) of samples that carried a field (0 without any).
    pub mag_rejected: f64,
    /// The dip of the reference field (rad), positive when the field points below the
    /// horizon (north of the magnetic equator); 0 without a reference (`has_mag_reference`
    /// = 0). Of the wrong sign for the place: a flipped accelerometer (or magnetometer).
    pub mag_dip: f64,
    /// 1 when a magnetic reference exists (a field has been seen), else 0.
    pub has_mag_reference: i32,
    /// Seconds since the last gyroscope sample (0 when the last sample had one; a NaN row is
    /// a missing sample): the AHRS carries the last rate through a gap and widens the spread.
    pub gyr_missing_time: f64,
    /// Seconds since the last usable accelerometer sample (0 when the last sample had one; a
    /// NaN row or free fall is none): without it there is no tilt evidence.
    pub acc_missing_time: f64,
    /// Seconds since the last magnetometer sample (0 when the last sample had one; NULL, a NaN
    /// row or a zero field is none; counted from the first sample for a magnetometer never
    /// seen): without it there is no heading evidence. A field the disturbance test refuses
    /// is a sample (see `mag_rejected`).
    pub mag_missing_time: f64,
}

/// An exponential average with its start-up bias removed (the mean of the values seen so far,
/// weighted towards the recent ones).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct Average {
    sum: f64,
    weight: f64,
}

impl Average {
    /// Adds `x` with the weight `alpha` (0 to 1) relative to the past.
    pub(super) fn push(&mut self, x: f64, alpha: f64) {
        self.sum += alpha * (x - self.sum);
        self.weight += alpha * (1.0 - self.weight);
    }

    /// Whether a value has been pushed.
    pub(super) fn is_empty(&self) -> bool {
        self.weight <= 0.0
    }

    /// The average (0 before the first value).
    pub(super) fn value(&self) -> f64 {
        if self.weight > 0.0 {
            self.sum / self.weight
        } else {
            0.0
        }
    }
}

/// The normalized innovations of one correction, per degree of freedom (`None` for a sensor
/// that gave no evidence).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct Innovations {
    /// The tilt's `ν_a / 2`.
    pub(super) tilt: Option<f64>,
    /// The heading's `ν_m`.
    pub(super) heading: Option<f64>,
    /// The tilt's `ν_a / 2` over its mean if the model held ([`expected_nis`]).
    pub(super) tilt_scale: Option<f64>,
    /// The heading's `ν_m` over its mean if the model held.
    pub(super) heading_scale: Option<f64>,
    /// The prior state's variance (rad², as the model has it) per tilt axis, with the tilt.
    pub(super) tilt_variance: Option<f64>,
}

impl Innovations {
    /// The largest of the two (0 without an observation).
    pub(super) fn largest(&self) -> f64 {
        self.tilt.unwrap_or(0.0).max(self.heading.unwrap_or(0.0))
    }
}

/// The running state of the readout, part of the AHRS's per-sample state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct HealthState {
    gravity: Average,
    tilt: Average,
    heading: Average,
    rejected: Average,
    tilt_innovation: f64,
    heading_innovation: f64,
}

impl HealthState {
    /// One magnetometer sample that carried a field, of duration `dt` (s): `used` whether the
    /// disturbance test let it through.
    pub(super) fn mag_sample(&mut self, used: bool, dt: f64) {
        let alpha = (dt / HEALTH_TIME).min(1.0);
        self.rejected.push(if used { 0.0 } else { 1.0 }, alpha);
    }

    /// The gravity score of a correction of period `t` (s): `excess` the low-passed
    /// accelerometer's deviation from gravity in units of `acc_reject` (`None` without an
    /// accelerometer sample in the period).
    pub(super) fn gravity(&mut self, t: f64, excess: Option<f64>) {
        let alpha = (t / HEALTH_TIME).min(1.0);
        if let Some(x) = excess {
            self.gravity.push(x * x, alpha);
        }
    }

    /// One correction of period `t` (s) with the prior's body-frame precision `lam` (rad⁻²)
    /// and the sensors' evidence (module `evidence`; `None` for a sensor without evidence this
    /// period): each innovation, normalized by its variance (the state's spread plus the
    /// measurement's `var`), per degree of freedom, feeds the average of what it observes.
    /// Returns the correction's largest normalized innovation per degree of freedom (0
    /// without evidence).
    pub(super) fn correction(
        &mut self,
        t: f64,
        lam: &Matrix3<f64>,
        evidence: &[Option<Evidence>],
    ) -> Innovations {
        let alpha = (t / HEALTH_TIME).min(1.0);
        let mut out = Innovations::default();
        if present(evidence).next().is_none() {
            return out;
        }
        // The state's covariance (rad², body frame; see `covariance`).
        let sigma = covariance(lam);
        for ev in present(evidence) {
            // the state's variance along "up" (the heading's, and what the tilt does not see)
            let (Innovation::Tilt { up, .. } | Innovation::Heading { up, .. }) = &ev.innovation;
            let along_up = (up.transpose() * sigma * up)[0].max(0.0);
            // the state's variance along what the sensor sees, per degree of freedom, and the
            // normalized innovation
            let (p, nis) = match &ev.innovation {
                Innovation::Tilt { up, e, .. } => (
                    0.5 * (sigma.trace() - along_up).max(0.0),
                    tilt_nis(&sigma, up, e, ev.var) / ev.innovation.dof(),
                ),
                Innovation::Heading { angle, .. } => (
                    along_up,
                    angle * angle / (along_up + ev.var) / ev.innovation.dof(),
                ),
            };
            let scale = nis / expected_nis(p, ev.var);
            match &ev.innovation {
                Innovation::Tilt { angle, .. } => {
                    self.tilt.push(nis, alpha);
                    self.tilt_innovation = *angle;
                    out.tilt = Some(nis);
                    out.tilt_scale = Some(scale);
                    out.tilt_variance = Some(p);
                }
                Innovation::Heading { angle, .. } => {
                    self.heading.push(nis, alpha);
                    self.heading_innovation = *angle;
                    out.heading = Some(nis);
                    out.heading_scale = Some(scale);
                }
            }
        }
        out
    }

    /// The readout, with the reference dip `dip_above` (rad above the horizon, as the
    /// magnetometer's state keeps it) if there is a reference.
    pub(super) fn readout(&self, dip_above: Option<f64>, times: &SensorTimes) -> AhrsHealth {
        let (gravity, tilt, heading) = (
            self.gravity.value(),
            self.tilt.value(),
            self.heading.value(),
        );
        AhrsHealth {
            score: gravity.max(tilt).max(heading),
            gravity_score: gravity,
            tilt_score: tilt,
            heading_score: heading,
            tilt_innovation: self.tilt_innovation,
            heading_innovation: self.heading_innovation,
            mag_rejected: self.rejected.value(),
            mag_dip: dip_above.map_or(0.0, |d| -d),
            has_mag_reference: i32::from(dip_above.is_some()),
            gyr_missing_time: times.gyr_missing,
            acc_missing_time: times.acc_missing,
            mag_missing_time: times.mag_missing,
        }
    }
}

/// The mean of a normalized innovation `ν = δ²/(P + r)` per degree of freedom when the model
/// holds, for a state of variance `P` observed through a low-passed measurement of variance
/// `r`: `(P² + r²)/(P + r)²`, between 1/2 (`P = r`) and 1. The health readout divides by
/// `P + r` as if the state's and the measurement's errors were independent; they are not. The
/// measurement's error is correlated over its low-pass time constant `τ`, over which the state
/// has followed the same measurement: with the evidence worth `1/(rτ)` per second, the state's
/// error `ε` is driven by the measurement's error `v` through the gain `K = P/(rτ)`, and in the
/// steady state `Cov(ε, v) = −K r/(K + 1/τ) = −P r/(P + r)`, so that the innovation `v − ε`
/// has the variance `P + r + 2 Cov(ε, v) = (P² + r²)/(P + r)` (module `uncertainty` divides
/// by this to read the noises' scale from the innovations).
pub(super) fn expected_nis(p: f64, r: f64) -> f64 {
    let t = p + r;
    if t > 0.0 {
        ((p * p + r * r) / (t * t)).clamp(0.5, 1.0)
    } else {
        1.0
    }
}

/// The state's covariance (rad², body frame) from its precision `lam`: `(Λ + 3/π² I)⁻¹`. An
/// angle's error cannot have a larger variance than a uniformly unknown angle's, π²/3: adding
/// that precision, 3/π², to every direction keeps a direction the state knows nothing about (a
/// heading before the first field) from counting as a certain one (a pseudo-inverse would give
/// it variance 0) and changes a well-known direction's variance by a negligible fraction. `Λ`
/// is positive semi-definite, so the sum is positive definite and a Cholesky factorization
/// inverts it (the eigendecomposition of [`pinv`] only for a matrix that is not, e.g. NaN).
fn covariance(lam: &Matrix3<f64>) -> Matrix3<f64> {
    let a = lam + Matrix3::identity() * (3.0 / (PI * PI));
    match a.cholesky() {
        Some(c) => c.inverse(),
        None => pinv(&a),
    }
}

/// The normalized tilt innovation `ν_a = eᵀ S⁺ e`, `S = P [b̂]× Σ [b̂]×ᵀ P + σ_a² P` (module
/// documentation), computed in an orthonormal basis `u₁, u₂` of the plane perpendicular to
/// `b̂` (the unit predicted "up"), where `S` is the positive definite 2×2 matrix
/// `[[u₂ᵀΣu₂ + σ_a², −u₁ᵀΣu₂], [−u₁ᵀΣu₂, u₁ᵀΣu₁ + σ_a²]]` (`[b̂]×ᵀ u₁ = −u₂`,
/// `[b̂]×ᵀ u₂ = u₁`) and `e = e₁u₁ + e₂u₂` lies in that plane.
fn tilt_nis(sigma: &Matrix3<f64>, bh: &Vector3<f64>, e: &Vector3<f64>, var_a: f64) -> f64 {
    // a unit vector perpendicular to b̂: from the axis least aligned with it
    let axis = if bh.x.abs() <= bh.y.abs() && bh.x.abs() <= bh.z.abs() {
        Vector3::x()
    } else if bh.y.abs() <= bh.z.abs() {
        Vector3::y()
    } else {
        Vector3::z()
    };
    let u1 = bh.cross(&axis).normalize();
    let u2 = bh.cross(&u1);
    let s11 = (u2.transpose() * sigma * u2)[0] + var_a;
    let s22 = (u1.transpose() * sigma * u1)[0] + var_a;
    let s12 = -(u1.transpose() * sigma * u2)[0];
    let (e1, e2) = (u1.dot(e), u2.dot(e));
    let det = s11 * s22 - s12 * s12;
    if det > 0.0 {
        (s22 * e1 * e1 - 2.0 * s12 * e1 * e2 + s11 * e2 * e2) / det
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix4;

    const UP: [f64; 3] = [0.0, 0.0, 1.0];

    /// A tilt evidence item observing the body-frame "up" `b` with variance `var` (the
    /// predicted "up" the z axis).
    fn tilt(b: &[f64; 3], var: f64) -> Option<Evidence> {
        Some(Evidence {
            exponent: Matrix4::zeros(),
            innovation: Innovation::tilt(&UP, b),
            var,
        })
    }

    /// A heading evidence item of heading error `delta` with variance `var`.
    fn heading(delta: f64, var: f64) -> Option<Evidence> {
        Some(Evidence {
            exponent: Matrix4::zeros(),
            innovation: Innovation::heading(&UP, delta),
            var,
        })
    }

    #[test]
    fn the_average_is_the_mean_of_equal_values_from_the_start() {
        let mut a = Average::default();
        for _ in 0..3 {
            a.push(2.5, 0.01);
        }
        assert!((a.value() - 2.5).abs() < 1e-12);
    }

    #[test]
    fn an_unknown_heading_makes_no_heading_innovation_surprising() {
        // tilt known to 0.01 rad, heading not at all (precision 0 about up): a heading error
        // of 3 rad counts against the variance of a uniform angle, π²/3, not against 0
        let lam = Matrix3::from_diagonal(&Vector3::new(1e4, 1e4, 0.0));
        let mut h = HealthState::default();
        h.correction(0.02, &lam, &[heading(3.0, 1e-4)]);
        let r = h.readout(None, &SensorTimes::default());
        assert!(r.heading_score < 3.0, "{}", r.heading_score);
        assert!(r.heading_score > 2.0, "{}", r.heading_score);
    }

    #[test]
    fn a_tilt_innovation_of_one_standard_deviation_scores_one_half_per_axis() {
        // prior precision 1/σ² isotropic, measurement variance 0: an innovation of σ along
        // one tangent direction gives ν = 1, per degree of freedom 1/2
        let sd: f64 = 0.01;
        let lam = Matrix3::identity() / (sd * sd);
        let mut h = HealthState::default();
        let b = [sd.sin(), 0.0, sd.cos()];
        h.correction(0.02, &lam, &[tilt(&b, 0.0), None]);
        let r = h.readout(None, &SensorTimes::default());
        // the variance is 1/(1/σ² + 3/π²): ν = σ²·(1/σ² + 3/π²)
        let reg = 3.0 / (PI * PI);
        let want = 0.5 * (1.0 + reg * sd * sd);
        assert!((r.tilt_score - want).abs() < 1e-12, "{}", r.tilt_score);
        assert!((r.tilt_innovation - sd).abs() < 1e-12);
        // the heading variance adds the prior's spread about up and the measurement's
        h.gravity(0.02, Some(0.5));
        h.correction(0.02, &lam, &[None, heading(2.0 * sd, sd * sd)]);
        let r = h.readout(Some(-1.0), &SensorTimes::default());
        let var = 1.0 / (1.0 / (sd * sd) + reg) + sd * sd;
        assert!(
            (r.heading_score - 4.0 * sd * sd / var).abs() < 1e-9,
            "{}",
            r.heading_score
        );
        assert_eq!(r.score, r.heading_score);
        assert!((r.gravity_score - 0.25).abs() < 1e-12);
        assert_eq!(r.mag_dip, 1.0);
        assert_eq!(r.has_mag_reference, 1);
    }
    #[test]
    fn the_tangent_plane_form_equals_the_pseudo_inverse_of_the_3x3_innovation_covariance() {
        // the definition ν = eᵀ (P [b̂]× Σ [b̂]×ᵀ P + σ² P)⁺ e and Σ = pinv(Λ + 3/π² I) against
        // the Cholesky inverse and the 2×2 form, for states of every conditioning
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for case in 0..200 {
            let a = Matrix3::from_fn(|_, _| next());
            let scale = 10f64.powf(6.0 * next().abs());
            let mut lam = a * a.transpose() * scale;
            if case % 4 == 0 {
                // one direction unknown (a heading before the first field)
                lam[(2, 2)] = 0.0;
                lam[(0, 2)] = 0.0;
                lam[(1, 2)] = 0.0;
                lam[(2, 0)] = 0.0;
                lam[(2, 1)] = 0.0;
            }
            let reference = pinv(&(lam + Matrix3::identity() * (3.0 / (PI * PI))));
            let sigma = covariance(&lam);
            assert!(
                (sigma - reference).norm() <= 1e-9 * reference.norm(),
                "case {case}"
            );
            let bh = Vector3::new(next(), next(), next()).normalize();
            let raw = Vector3::new(next(), next(), next()) * 0.01;
            let e = raw - bh * bh.dot(&raw);
            let var_a = if case % 3 == 0 {
                0.0
            } else {
                1e-4 * next().abs()
            };
            let k = bh.cross_matrix();
            let p = Matrix3::identity() - bh * bh.transpose();
            let s = p * (k * reference * k.transpose()) * p + p * var_a;
            let want = (e.transpose() * pinv(&s) * e)[0];
            let got = tilt_nis(&sigma, &bh, &e, var_a);
            assert!(
                (got - want).abs() <= 1e-8 * want.abs().max(1e-300),
                "case {case}: {got} vs {want}"
            );
        }
    }
}
