//! The magnetic reference (the field's norm and dip), the disturbance decided per phase, the
//! field averaged in the world frame of the estimate, and the heading observation it gives.
//!
//! - **Per phase, with hysteresis.** A field whose norm (low-passed over
//!   [`MAG_TEST_TIME`](super::lowpass::MAG_TEST_TIME), so that the sensor's noise does not trip
//!   the test at high sample rates) differs from the reference by more than `mag_norm_tol`
//!   (relative) or whose dip differs by more than `mag_dip_tol` starts a disturbed phase; the
//!   phase ends only after [`RECOVER_TIME`] of samples that all pass. A
//!   field that passes the test now and then near a magnet is not representative of the
//!   undisturbed one (the samples that pass are a biased subset), so nothing of a disturbed
//!   phase is used; the average continues after it from where it was (it lives in the world
//!   frame of the estimate, so it is still valid), and a few samples that pass at the start
//!   of the next phase move it no more than any others.
//! - **A new reference** only from a disturbance whose norm and dip stay steady while the
//!   sensor rotates (at least [`NEW_REF_RATE`]) for `mag_new_time` seconds of rotation: a
//!   homogeneous new field keeps its norm and dip however the sensor turns; a magnet fixed to
//!   the sensor does not.
//! - **Averaged in the world frame of the estimate.** Each undisturbed sample is mapped to the
//!   world with the current estimate (gyroscope and accelerometer corrections included) and
//!   low-passed there (`mag_tau`). Each heading correction the AHRS makes turns the average
//!   with it, so that the average stays the field relative to the current heading; tilt
//!   corrections do not (the samples were mapped with the tilt known at their time, which the
//!   accelerometer keeps right; turning the average by gyroscope increments instead, as in a
//!   gyroscope-only frame, would carry the gyroscope's drift into the average during sustained
//!   rotation, multiplied by tan(dip) in heading).

use nalgebra::Matrix4;

use super::evidence::{Evidence, Innovation};
use super::gyro::Turn;
use super::latency::turn_forward;
use super::lowpass::{Coeffs, InertialLowPass};
use super::params::AhrsParams;
use super::uncertainty::{Inhomogeneity, MIN_COS2_DIP};
use super::vec3::{dot3, norm3, UP};
use crate::filter::Core;
use crate::quaternion::q4;

/// The heading reference's error taken as correlated over the heading average's `mag_tau`
/// (module documentation of [`Magnetic::heading_evidence`]): an exponential autocorrelation
/// `V_h·exp(−|t|/mag_tau)` has the spectral density `2·V_h·mag_tau` at zero frequency, twice
/// that of white noise of the same variance averaged over `mag_tau`.
const REFERENCE_CORRELATION: f64 = 2.0;

/// Time (s) a field must pass the disturbance test without interruption to end a disturbed
/// phase (VQF uses the same half second).
pub(super) const RECOVER_TIME: f64 = 0.5;

/// Rotation rate (rad/s, 20°/s) above which a steady disturbance counts toward a new reference.
pub(super) const NEW_REF_RATE: f64 = 0.35;

/// What one pass over a recording hands another (module `smoother`): the field's reference
/// (norm, dip in rad) and the variation of the field it measured over the motion (module
/// `uncertainty`), which widens the heading evidence by the local field's deviations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MagReference {
    norm_dip: (f64, f64),
    inhomogeneity: Inhomogeneity,
}

/// The magnetometer's state in the AHRS.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Magnetic {
    /// Reference norm and dip (rad); `None` before the first field.
    reference: Option<(f64, f64)>,
    /// The candidate for a new reference, and the seconds of rotation it has held.
    cand: (f64, f64),
    cand_time: f64,
    /// The sample's norm and dip, low-passed over [`MAG_TEST_TIME`](super::lowpass::MAG_TEST_TIME) (what the test sees).
    tested: Option<(f64, f64)>,
    /// Whether the current phase is disturbed, and how long the test has passed since.
    disturbed: bool,
    clean_time: f64,
    /// The field in the world frame of the estimate, low-passed (`None` until the first
    /// sample of an undisturbed phase).
    lp: Option<InertialLowPass>,
    /// Whether the average waits to be restarted by the next sample: a gyroscope gap turned it
    /// with a carried rate by more than the magnetometer's own noise.
    restart: bool,
    /// The variation of the used samples' norm and dip (module `uncertainty`).
    inhomogeneity: Inhomogeneity,
    /// The state's stated tilt variance (rad² per axis) as of the last correction.
    tilt_variance: f64,
}

impl Magnetic {
    pub(super) fn new() -> Magnetic {
        Magnetic {
            reference: None,
            cand: (0.0, 0.0),
            cand_time: 0.0,
            tested: None,
            disturbed: false,
            clean_time: 0.0,
            lp: None,
            restart: false,
            inhomogeneity: Inhomogeneity::default(),
            tilt_variance: 0.0,
        }
    }

    /// The variance (rad²) of the heading reference's error: the field's directional variance
    /// from the norm's and the dip's variation, or their deviation now where that is larger
    /// ([`Inhomogeneity::evidence_variance`]), over `cos²(dip)` (module `uncertainty`); 0
    /// without a reference.
    pub(super) fn heading_reference_variance(&self) -> f64 {
        self.over_cos2_dip(self.inhomogeneity.evidence_variance())
    }

    /// The heading reference's variance (rad²) as the stated covariance takes it: the local
    /// field's own directional variance, without the state's tilt error
    /// ([`Inhomogeneity::field_variance`]), over `cos²(dip)`; 0 without a reference.
    pub(super) fn stated_heading_reference_variance(&self) -> f64 {
        self.over_cos2_dip(self.inhomogeneity.field_variance())
    }

    /// A directional variance `v` (rad²) of the field turned into the heading's: over
    /// `cos²(dip)` of the reference, held at [`MIN_COS2_DIP`] (a field within 5° of the
    /// vertical gives no heading, `heading_error`); 0 without a reference.
    fn over_cos2_dip(&self, v: f64) -> f64 {
        let Some((_, dip)) = self.reference else {
            return 0.0;
        };
        let c = dip.cos();
        v / (c * c).max(MIN_COS2_DIP)
    }

    /// The state's stated tilt variance (rad² per axis) after a correction, which the
    /// following samples' dips carry.
    pub(super) fn set_tilt_variance(&mut self, v: f64) {
        self.tilt_variance = v;
    }

    /// Whether a reference exists and the current phase is undisturbed.
    pub(super) fn trusted(&self) -> bool {
        self.reference.is_some() && !self.disturbed
    }

    /// The reference field's dip (rad above the horizon), if there is a reference.
    pub(super) fn reference_dip(&self) -> Option<f64> {
        self.reference.map(|(_, dip)| dip)
    }

    /// The reference (norm and dip) with the variation of the field measured so far, if there
    /// is a reference.
    pub(super) fn reference(&self) -> Option<MagReference> {
        self.reference.map(|norm_dip| MagReference {
            norm_dip,
            inhomogeneity: self.inhomogeneity,
        })
    }

    /// Replaces the reference norm and dip (the next sample's test compares against it) and
    /// the averages of the field's variation ([`Inhomogeneity::with_averages_of`]).
    pub(super) fn set_reference(&mut self, r: &MagReference) {
        self.reference = Some(r.norm_dip);
        self.cand = r.norm_dip;
        self.cand_time = 0.0;
        self.inhomogeneity = self.inhomogeneity.with_averages_of(&r.inhomogeneity);
    }

    /// Sets the reference from a field sample `m` seen with the body-frame "up" `up_b`.
    pub(super) fn start(&mut self, m: &[f64; 3], up_b: &[f64; 3]) {
        let (norm, dip) = norm_dip(m, up_b);
        self.reference = Some((norm, dip));
        self.cand = (norm, dip);
        self.tested = Some((norm, dip));
        self.disturbed = false;
        self.clean_time = 0.0;
    }

    /// Drops the world-frame average (the next used sample starts a new one): after a loss of
    /// the magnetometer longer than `mag_tau`, the old average was turned by the gyroscope
    /// alone since its last sample.
    pub(super) fn restart_average(&mut self) {
        self.lp = None;
    }

    /// Before the sample's other steps: a field sample (`present`) after a loss longer than
    /// `mag_tau` (`missing` seconds without one), or after a gap that turned the average,
    /// restarts the average.
    pub(super) fn restart_if_stale(&mut self, p: &AhrsParams, missing: f64, present: bool) {
        if present && (missing > p.mag_tau || self.restart) {
            self.restart_average();
            self.restart = false;
        }
    }

    /// A gyroscope gap has ended that turned the averages with a carried rate by the variance
    /// `turned` (rad², the turn vector's): beyond the magnetometer's noise, the average
    /// restarts at the next sample.
    pub(super) fn after_gap(&mut self, p: &AhrsParams, turned: f64) {
        self.restart |= turned > p.mag_noise * p.mag_noise;
    }

    /// One sample (step 4 of the module `ahrs`; `mag` `None` without a usable field sample),
    /// `h` seconds after the previous one, with the state `core` after the gyroscope's `turn`:
    /// the field turned forward by its latency, then [`Magnetic::observe`]. Returns `None`
    /// without a sample, else whether it was used.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn step(
        &mut self,
        p: &AhrsParams,
        c: &Coeffs,
        core: &Core<4>,
        turn: &Turn,
        h: f64,
        repeat: u32,
        mag: Option<&[f64; 3]>,
    ) -> Option<bool> {
        let m = turn_forward(mag?, &turn.w_lead, c.mag_lead);
        Some(self.observe(&core.mode(), &m, turn.rate, h, repeat, p, c))
    }

    /// One field sample `m` (sensor frame, latency-compensated) with the current estimate `q`
    /// and the rotation rate `rate` (rad/s), `h` seconds after the previous sample, which the
    /// average takes as `repeat` nominal samples: the disturbance test, the reference and the
    /// average. Returns whether the sample was used (undisturbed phase).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn observe(
        &mut self,
        q: &[f64; 4],
        m: &[f64; 3],
        rate: f64,
        h: f64,
        repeat: u32,
        p: &AhrsParams,
        c: &Coeffs,
    ) -> bool {
        let up_b = q4::rotate_inverse(q, &UP);
        let (raw_norm, raw_dip) = norm_dip(m, &up_b);
        // the test sees norm and dip low-passed over MAG_TEST_TIME, so that the sensor's noise
        // does not fail it now and then at high sample rates (both are rotation-invariant)
        let (norm, dip) = match self.tested {
            Some((n, d)) => (
                n + c.mag_test * (raw_norm - n),
                d + c.mag_test * (raw_dip - d),
            ),
            None => (raw_norm, raw_dip),
        };
        self.tested = Some((norm, dip));
        let dt = h;
        let (rn, rd) = *self.reference.get_or_insert((norm, dip));
        let passes = (norm - rn).abs() <= p.mag_norm_tol * rn && (dip - rd).abs() <= p.mag_dip_tol;
        if !passes {
            if !self.disturbed {
                self.cand = (norm, dip);
                self.cand_time = 0.0;
            }
            self.disturbed = true;
            self.clean_time = 0.0;
            self.follow_candidate(norm, dip, rate, h, p, c);
            return false;
        }
        self.cand_time = 0.0;
        if self.disturbed {
            self.clean_time += dt;
            if self.clean_time < RECOVER_TIME {
                return false;
            }
            self.disturbed = false;
        }
        let k = c.mag_ref;
        self.reference = Some((rn + k * (norm - rn), rd + k * (dip - rd)));
        self.inhomogeneity
            .push(raw_norm, raw_dip, h, self.tilt_variance, p.mag_tau);
        let mw = q4::rotate(q, m);
        match self.lp.as_mut() {
            Some(lp) => (0..repeat).for_each(|_| lp.step(&mw)),
            None => self.lp = Some(InertialLowPass::new(c.mag, c.mag_warmup, &mw)),
        }
        true
    }

    /// A disturbed sample: the candidate follows a steady field and becomes the reference
    /// after `mag_new_time` seconds of rotation.
    fn follow_candidate(
        &mut self,
        norm: f64,
        dip: f64,
        rate: f64,
        h: f64,
        p: &AhrsParams,
        c: &Coeffs,
    ) {
        let (cn, cd) = self.cand;
        let steady = (norm - cn).abs() <= p.mag_norm_tol * cn && (dip - cd).abs() <= p.mag_dip_tol;
        if !steady {
            self.cand = (norm, dip);
            self.cand_time = 0.0;
            return;
        }
        let k = c.candidate;
        self.cand = (cn + k * (norm - cn), cd + k * (dip - cd));
        if rate >= NEW_REF_RATE {
            self.cand_time += h;
        }
        if self.cand_time >= p.mag_new_time {
            self.reference = Some(self.cand);
            self.cand_time = 0.0;
            self.disturbed = false;
            self.clean_time = 0.0;
            self.lp = None;
        }
    }

    /// The heading error `δ` (rad) of the estimate: the rotation about the vertical that turns
    /// the averaged horizontal field onto north (`None` outside an undisturbed phase or for a
    /// field along the vertical).
    pub(super) fn heading_error(&self) -> Option<f64> {
        if !self.trusted() {
            return None;
        }
        let y = self.lp.as_ref()?.y;
        let h = (y[0] * y[0] + y[1] * y[1]).sqrt();
        (h > 1e-3 * norm3(&y)).then(|| y[0].atan2(y[1]))
    }

    /// The heading evidence of a correction (step 5.3 of the module `ahrs`) whose used samples
    /// covered `t_mag` seconds, with the prior's mode `q_prior`: the heading error `δ` of the
    /// average gives the heading-only observation `exp(−2κ_m e_z²)`, `e = q ⊗ q_m*`, `q_m` the
    /// prior mode turned by `δ` about the vertical, `κ_m = T_mag/(mag_noise²·mag_tau·w)`; its
    /// innovation `δ` (1 degree of freedom) has the variance `mag_noise²·w`. `None` without
    /// used samples in the period or a heading error (disturbed, no reference, a vertical
    /// field).
    ///
    /// `w = 1 + 2·V_h/mag_noise²` ([`REFERENCE_CORRELATION`]) widens the evidence by the
    /// heading reference's error: the local field deviates from the reference's direction by
    /// the variance `V_h` ([`Magnetic::heading_reference_variance`]), and that deviation is
    /// not white: it changes with the position, on the motion's time scale, and what changes
    /// slower than the average's `mag_tau` passes into the heading whole. Taken as correlated
    /// over `mag_tau` (exponentially), its spectral density at zero frequency is
    /// `2·V_h·mag_tau`, which adds to the sensor noise's `mag_noise²·mag_tau` (the evidence
    /// per second is the inverse of the sum). The dip is measured against the state's "up", so
    /// `V_h` also holds the state's own tilt error, which the heading evidence inherits as well
    /// (a tilt error about north turns the averaged field's heading by `tan(dip)` times it).
    /// With a homogeneous field and a settled tilt `V_h ≈ 0` and `w ≈ 1`.
    pub(super) fn heading_evidence(
        &self,
        p: &AhrsParams,
        t_mag: f64,
        q_prior: &[f64; 4],
    ) -> Option<Evidence> {
        let delta = if t_mag > 0.0 {
            self.heading_error()
        } else {
            None
        }?;
        let white = p.mag_noise * p.mag_noise;
        let widen = 1.0 + REFERENCE_CORRELATION * self.heading_reference_variance() / white;
        let kappa = t_mag / (white * p.mag_tau * widen);
        let rz = [(0.5 * delta).cos(), 0.0, 0.0, (0.5 * delta).sin()];
        Some(Evidence {
            exponent: heading_exponent(&q4::mul(&rz, q_prior), kappa),
            innovation: Innovation::heading(&q4::rotate_inverse(q_prior, &UP), delta),
            var: white * widen,
        })
    }

    /// After a correction with this heading evidence (step 5.7 of the module `ahrs`): the
    /// average turned with the heading correction from the prior's mode `q_prior` to the
    /// posterior's `q_post`, so that it stays the field relative to the current heading (tilt
    /// corrections do not turn it: its samples were mapped with the tilt known at their time).
    pub(super) fn follow_correction(&mut self, q_prior: &[f64; 4], q_post: &[f64; 4]) {
        let mut dw = q4::mul(q_post, &q4::conj(q_prior));
        if dw[0] < 0.0 {
            dw = dw.map(|v| -v);
        }
        self.turn_heading(2.0 * dw[3].atan2(dw[0]));
    }

    /// Turns the average with a heading correction of the estimate, `q ← Rz(gamma) ⊗ q`
    /// (`gamma` in rad about the world vertical): the heading error left is `δ − gamma`.
    pub(super) fn turn_heading(&mut self, gamma: f64) {
        if let Some(lp) = self.lp.as_mut() {
            // turn(dq) applies R(dq)ᵀ: pass the inverse rotation Rz(−γ)
            lp.turn(&[(0.5 * gamma).cos(), 0.0, 0.0, -(0.5 * gamma).sin()]);
        }
    }
}

/// Norm and dip (rad: the angle of `m` above the horizontal, `asin(m·up/|m|)`) of a field
/// sample seen with the body-frame up `up_b`.
fn norm_dip(m: &[f64; 3], up_b: &[f64; 3]) -> (f64, f64) {
    let norm = norm3(m);
    (norm, (dot3(m, up_b) / norm).clamp(-1.0, 1.0).asin())
}

/// The exponent matrix `−2κ u uᵀ` of the heading likelihood `exp(−2κ e_z²)`, `e = q ⊗ q_m*`:
/// `e_z = uᵀ q` with `u` the last row of `R(q_m*)` (`x ⊕ y = R(y) x`). At the mode it is the
/// von Mises density `exp(κ cos ψ)` of the heading error `ψ` to second order: precision `κ`
/// (rad⁻²) about the vertical, none on the tilt.
pub(super) fn heading_exponent(q_m: &[f64; 4], kappa: f64) -> Matrix4<f64> {
    let c = q4::conj(q_m);
    // Row 3 of R(c) (see quaternion::right_matrix): [c3, c2, −c1, c0].
    let u = [c[3], c[2], -c[1], c[0]];
    Matrix4::from_fn(|i, j| -2.0 * kappa * u[i] * u[j])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(dip_deg: f64, heading: f64) -> [f64; 3] {
        let d = dip_deg.to_radians();
        [
            50.0 * d.cos() * heading.sin(),
            50.0 * d.cos() * heading.cos(),
            -50.0 * d.sin(),
        ]
    }

    #[test]
    fn a_disturbed_phase_ends_only_after_the_recovery_time() {
        let p = AhrsParams::new(0.01);
        let c = Coeffs::new(&p);
        let q = [1.0, 0.0, 0.0, 0.0];
        let mut m = Magnetic::new();
        m.start(&field(60.0, 0.0), &UP);
        assert!(m.observe(&q, &field(60.0, 0.0), 0.0, p.sample_time, 1, &p, &c));
        // 0.2 s of a disturbed field (norm +30 %)
        let bad = field(60.0, 0.0).map(|v| v * 1.3);
        for _ in 0..20 {
            m.observe(&q, &bad, 0.0, p.sample_time, 1, &p, &c);
        }
        assert!(!m.trusted());
        // then a clean field: not used for the first 0.5 s (the low-passed norm also needs a
        // few samples to come back within tolerance), used from 0.8 s on
        for _ in 0..50 {
            assert!(!m.observe(&q, &field(60.0, 0.0), 0.0, p.sample_time, 1, &p, &c));
        }
        for _ in 0..30 {
            m.observe(&q, &field(60.0, 0.0), 0.0, p.sample_time, 1, &p, &c);
        }
        assert!(m.observe(&q, &field(60.0, 0.0), 0.0, p.sample_time, 1, &p, &c));
        assert!(m.heading_error().is_some());
    }

    #[test]
    fn a_steady_new_field_becomes_the_reference_only_while_rotating() {
        let p = AhrsParams {
            mag_new_time: 1.0,
            ..AhrsParams::new(0.01)
        };
        let c = Coeffs::new(&p);
        let q = [1.0, 0.0, 0.0, 0.0];
        let mut m = Magnetic::new();
        m.start(&field(60.0, 0.0), &UP);
        let new = field(40.0, 0.0).map(|v| v * 1.5);
        for _ in 0..300 {
            assert!(!m.observe(&q, &new, 0.0, p.sample_time, 1, &p, &c));
        }
        for _ in 0..100 {
            m.observe(&q, &new, 1.0, p.sample_time, 1, &p, &c);
        }
        assert!(m.trusted());
        assert!(m.observe(&q, &new, 1.0, p.sample_time, 1, &p, &c));
    }

    #[test]
    fn the_heading_error_turns_with_a_correction() {
        let p = AhrsParams::new(0.01);
        let c = Coeffs::new(&p);
        let q = [1.0, 0.0, 0.0, 0.0];
        let mut m = Magnetic::new();
        m.start(&field(60.0, 0.3), &UP);
        for _ in 0..10 {
            m.observe(&q, &field(60.0, 0.3), 0.0, p.sample_time, 1, &p, &c);
        }
        let d = m.heading_error().unwrap();
        assert!((d - 0.3).abs() < 1e-9, "{d}");
        // the estimate is turned by 0.1 about the vertical: the error left is 0.2
        m.turn_heading(0.1);
        let d = m.heading_error().unwrap();
        assert!((d - 0.2).abs() < 1e-9, "{d}");
    }
}
