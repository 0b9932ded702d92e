//! The AHRS's readouts: the stated uncertainty (module `uncertainty`), the health, the bias
//! and scale estimates, the latency estimate, and what the offline smoother hands between its
//! passes.

use nalgebra::{Matrix3, Vector3};

use crate::error::{Error, Result};
use crate::quaternion::q4;

use super::bias;
use super::estimator::Ahrs;
use super::health::AhrsHealth;
use super::magnetic::MagReference;
use super::uncertainty::{self, StatedCoupling};

/// A stated covariance (rad², world frame) and the state's principal directions at the mode
/// (world frame, unit vectors).
type Stated = (Matrix3<f64>, [Vector3<f64>; 3]);

impl Ahrs {
    /// The angular spread of the state (radians): `out[0..3]` the standard deviations along
    /// the state's principal directions, `out[3]` the total (≈ the RMS rotation angle between
    /// the truth and the estimate), the square roots of the variances of
    /// [`Ahrs::orientation_covariance`] along those directions and of its trace: the state's
    /// own spread with the process noise accumulated since the last correction, scaled by
    /// what the innovations show, widened by the heading reference's error and with the
    /// heading error a tilt error brings through the magnetometer (module `uncertainty`).
    /// Before the first sample: that of the uniform distribution.
    pub fn angular_spread(&self, out: &mut [f64; 4]) -> Result<()> {
        let Some((c, world_dirs)) = self.stated(true)? else {
            crate::observation::spread_from_omega(&[0.25; 4], out);
            return Ok(());
        };
        // the stated covariance's variances along the principal directions (world frame):
        // their sum is its trace
        let v: [f64; 3] = std::array::from_fn(|i| {
            let d = world_dirs[i];
            (d.transpose() * c * d)[0].max(0.0)
        });
        for (o, x) in out.iter_mut().zip(&v) {
            *o = x.sqrt();
        }
        out[3] = (v[0] + v[1] + v[2]).sqrt();
        Ok(())
    }

    /// The covariance (rad², 3×3 row-major) of the orientation error as a rotation vector in
    /// the world frame (ENU): `q_true = exp(φ/2) ⊗ q̂` (`φ` about the world's x east, y north,
    /// z up; `q̂` [`Ahrs::quaternion`]), what `sensor_msgs/Imu.orientation_covariance` holds
    /// for an orientation of the IMU in an ENU world (REP 103). From the state's second
    /// moments (`4 Σ ω_i u_i u_iᵀ`, `u_i` the principal directions at the mode) plus the process
    /// noise accumulated since the last correction, each direction scaled by the innovations'
    /// average (tilt and heading apart), plus the heading reference's variance about the
    /// vertical (module `uncertainty`, docs/design.md "AHRS"): its trace is the square of the
    /// total [`Ahrs::angular_spread`]. Before the first sample: that of a uniform
    /// orientation's spread.
    pub fn orientation_covariance(&self) -> Result<[f64; 9]> {
        Ok(symmetric9(
            // before the first sample the uniform distribution: ω_i = 1/4
            &self
                .stated_covariance(true)?
                .unwrap_or_else(Matrix3::identity),
        ))
    }

    /// The covariance of the errors the filter models (rad², 3×3 row-major, world frame): the
    /// tilt and the heading the magnetometer shows; [`Ahrs::orientation_covariance`] before the
    /// heading's coupling to the tilt. Crate-internal: the offline smoother (`crate::smoother`)
    /// multiplies the two passes with it.
    pub(crate) fn filter_covariance(&self) -> Result<[f64; 9]> {
        Ok(symmetric9(
            &self
                .stated_covariance(false)?
                .unwrap_or_else(Matrix3::identity),
        ))
    }

    /// The heading's coupling to the tilt of the stated covariance now (module `uncertainty`),
    /// to apply to another covariance of the errors the filter models. Crate-internal: the
    /// offline smoother (`crate::smoother`) applies the forward pass's to the smoothed one.
    pub(crate) fn stated_coupling(&self) -> StatedCoupling {
        let p = self.stated_parts(true);
        StatedCoupling {
            coupling: p.coupling,
            steady: p.tilt_ref_steady,
        }
    }

    /// The stated covariance (world frame, module `uncertainty`), with the heading's coupling to
    /// the tilt if `coupled`; `None` before the first sample.
    fn stated_covariance(&self, coupled: bool) -> Result<Option<Matrix3<f64>>> {
        Ok(self.stated(coupled)?.map(|(c, _)| c))
    }

    /// The stated covariance as [`Ahrs::stated_covariance`] has it, and the state's principal
    /// directions at the mode in the world frame (unit vectors).
    fn stated(&self, coupled: bool) -> Result<Option<Stated>> {
        let Some(f) = &self.filter else {
            return Ok(None);
        };
        let core = f.core4()?;
        let (m, _) = core.params();
        let q = core.mode();
        let r = q4::to_matrix(&q);
        let r = Matrix3::from_fn(|i, j| r[i][j]);
        let dirs = bias::principal_directions(m, &q);
        // the pending noise made positive semi-definite, as the next correction takes it
        let pending = bias::psd(&self.sample_state.bias.pending);
        let c = uncertainty::stated(&r, &dirs, &pending, &self.stated_parts(coupled));
        Ok(Some((c, dirs.map(|d| r * d))))
    }

    /// What the stated covariance is made of besides the principal directions, with the
    /// heading's coupling to the tilt if `coupled`.
    fn stated_parts(&self, coupled: bool) -> uncertainty::Parts {
        let s = &self.sample_state;
        let p = &self.params;
        let coupling = match s.mag.reference_dip() {
            Some(dip) if coupled => uncertainty::Coupling::new(dip, p.acc_tau, p.mag_tau),
            _ => uncertainty::Coupling::NONE,
        };
        uncertainty::Parts {
            var: std::array::from_fn(|i| 4.0 * s.omega[i]),
            scales: s.calib.scales(),
            tilt_ref: s.calib.tilt_reference_variance(),
            tilt_ref_steady: s.calib.steady_tilt_reference_variance(),
            heading_ref: s.mag.stated_heading_reference_variance(),
            gap: s.gyro.gap_stated,
            scale_root: s.bias.scale_root(),
            coupling,
        }
    }

    /// The health readout (module `health`): how well the sensors agree with the model
    /// over the last [`HEALTH_TIME`](super::health::HEALTH_TIME) seconds; `score` above [`HEALTH_THRESHOLD`](super::health::HEALTH_THRESHOLD) flags an
    /// input mistake (units, period, axes). All zero before the first correction.
    pub fn health(&self) -> AhrsHealth {
        self.sample_state.health.readout(
            self.sample_state.mag.reference_dip(),
            &self.sample_state.times,
        )
    }

    /// The magnetic reference (the field's norm and dip, and the variation of the field
    /// measured so far), if there is one. Crate-internal: the offline smoother
    /// (`crate::smoother`) hands the forward pass's to its backward pass.
    pub(crate) fn mag_reference(&self) -> Option<MagReference> {
        self.sample_state.mag.reference()
    }

    /// Replaces the magnetic reference (see [`Ahrs::mag_reference`]).
    pub(crate) fn set_mag_reference(&mut self, r: &MagReference) {
        self.sample_state.mag.set_reference(r);
    }

    /// The gyroscope bias estimate (rad/s, sensor frame).
    pub fn gyro_bias(&self) -> [f64; 3] {
        let b = &self.sample_state.bias.b;
        [b[0], b[1], b[2]]
    }

    /// The gyroscope scale-error estimate (relative, per sensor axis: the gyroscope reads
    /// `(1 + s_i)` times the rate about axis `i`, plus the bias); zero when `gyro_scale_std` is 0.
    pub fn gyro_scale(&self) -> [f64; 3] {
        let s = &self.sample_state.bias.s;
        [s[0], s[1], s[2]]
    }

    /// The covariance of the gyroscope bias estimate ((rad/s)², 3×3 row-major, sensor frame):
    /// starts at `bias_std²·I`, shrinks as the corrections (and rests) teach the bias, grows
    /// by `bias_std²/bias_time` per second (over a rest the growth is held, and a third of it is
    /// added when the rest ends).
    pub fn gyro_bias_covariance(&self) -> [f64; 9] {
        let p = &self.sample_state.bias.bias_covariance();
        let mut out = [0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                out[3 * i + j] = p[(i, j)];
            }
        }
        out
    }

    /// The online estimate of the magnetometer's latency behind the gyroscope (s, within 0 and
    /// 40 ms in samples rounded up to an even number, at least 2 and at most 32 samples), from
    /// the IMU alone: the lag at which the field's change best fits `dm/dt = −ω × m` (see the
    /// module documentation, "Latency"). A readout: the filter does not use it (set
    /// [`AhrsParams::mag_latency`](super::params::AhrsParams::mag_latency) to compensate a latency); it estimates the latency of the raw
    /// samples whatever `mag_latency` is. The value is shrunk towards 0 by its own standard
    /// error `σ` (from two halves of the data): `L·max(0, 1 − σ²/L²)`, so that a latency the
    /// data cannot tell from none reads 0 (module `latency`); it is the value the default
    /// ([`LATENCY_ESTIMATE`](super::params::LATENCY_ESTIMATE)) compensates.
    ///
    /// `None` until 5 s of informative motion have been seen — seconds of samples weighted by
    /// `g²/(g² + 1)`, `g` the change of the rotation rate across the lag window perpendicular
    /// to the field, in rad/s² (a constant rotation fits every lag and counts little) — with
    /// the magnetometer present and undisturbed, or when the residuals do not single out a lag.
    pub fn mag_latency_estimate(&self) -> Option<f64> {
        self.latency.estimate()
    }

    /// Stops the latency estimate (from the next sample on; [`Ahrs::mag_latency_estimate`]
    /// then stays what it was), for an AHRS whose estimate nobody reads and whose
    /// `mag_latency` is not [`LATENCY_ESTIMATE`](super::params::LATENCY_ESTIMATE), so that the filter does not use it either:
    /// every other output is the same bit for bit. Crate-internal: the offline smoother's
    /// backward pass (`crate::smoother`), whose magnetometer samples are shifted by the forward
    /// pass's estimate instead.
    pub(crate) fn without_latency_estimate(&mut self) {
        self.estimate_latency = false;
    }

    /// The latency estimate, or an [`Error::NotConverged`] saying why there is none.
    pub(crate) fn mag_latency_estimate_or_error(&self) -> Result<f64> {
        self.latency
            .estimate()
            .ok_or_else(|| Error::NotConverged(self.latency.why_none()))
    }
}

/// A 3×3 matrix as 9 row-major values, made exactly symmetric.
fn symmetric9(c: &Matrix3<f64>) -> [f64; 9] {
    std::array::from_fn(|k| {
        let (i, j) = (k / 3, k % 3);
        0.5 * (c[(i, j)] + c[(j, i)])
    })
}
