//! An attitude and heading reference system (AHRS) on the recursive Bingham filter: gyroscope,
//! accelerometer and (optionally) magnetometer, every sensor an exact Bayes step on a Bingham
//! state of the orientation, with a Kalman filter of the gyroscope bias coupled to it.
//!
//! Conventions: the orientation `q = (w, x, y, z)` (scalar first) maps the sensor frame to the
//! world frame **ENU** (x east, y magnetic north, z up): `v_world = q ⊗ v_sensor ⊗ q*`.
//! Units: gyroscope rad/s, accelerometer m/s² (specific force: `+g` up at rest), magnetometer in
//! any consistent unit.
//!
//! # One sample: the steps, in this order
//!
//! One seam per sensor: each sensor's per-sample step lives in its own module, and at a
//! correction each sensor contributes one evidence item (module `evidence`: the exponent of its
//! likelihood, its innovation with its degrees of freedom and its variance), which the health
//! readout, the Bayes product and the bias learning read as a list. This list of steps is
//! their order; the function `step` of this module calls them in it.
//!
//! 0. **Restarts.** An average gone stale — its sensor back after a loss longer than its time
//!    constant, or turned by a gyroscope gap by more than its sensor's noise — restarts from
//!    this sample (modules `accel`, `magnetic`; module `timing`).
//! 1. **Rest and the bias at rest** (module `rest`). The gyroscope and accelerometer are
//!    low-pass filtered; while both (band-limited to 20 ms, so that the test sees the same
//!    noise at every sample rate) stay within thresholds of their low-pass values for
//!    [`AhrsParams::rest_time`], the raw gyroscope samples of the still phase measure the
//!    bias, their spread the gyroscope's noise: a Kalman step of the bias with their mean (in
//!    half-second blocks, the edges of the phase left out).
//! 2. **Gyroscope** (module `gyro`). The state is turned exactly by the body-frame increment of
//!    the rate with the bias and the scale error taken out, `q ← q ⊗ Δq`; the process noise of
//!    the sample — `gyro_noise²·dt`, `(gyro_scale_noise·|ω|)²·dt`, what a gap's carried rate
//!    cannot know, and what the bias's and the scale's uncertainty add through their coupling
//!    (module `bias`) — is accumulated.
//! 3. **Accelerometer** (module `accel`; skipped for a non-finite sample or
//!    `|acc| < gravity/4`): low-passed in the gyroscope-integrated frame (second-order
//!    Butterworth, `acc_tau`), where gravity stands still and linear accelerations average out.
//! 4. **Magnetometer** (module `magnetic`; skipped for a missing, zero or non-finite sample):
//!    the disturbance test, decided per phase with hysteresis, and the field averaged in the
//!    world frame of the estimate.
//! 5. **Correction** (module `correction`), every [`CORRECTION_PERIOD`] (50 ms; every sample
//!    at 20 Hz and below):
//!    1. the prior: the state composed with the accumulated process noise (moment matching);
//!    2. the accelerometer's tilt evidence, the likelihood `exp(κ_a upᵀ R(q) ā/|ā|)`
//!       (module `accel`);
//!    3. the magnetometer's heading evidence, von Mises in the heading error of the averaged
//!       field, no tilt information (module `magnetic`);
//!    4. the health readout scores every item's innovation against the prior (module
//!       `health`);
//!    5. one exact Bayes product with every item's exponent;
//!    6. the bias (and the scale error) learned from the move of the mode (module `bias`),
//!       unless at rest or recovering from a large error;
//!    7. the field's average turned with the heading correction (module `magnetic`).
//!
//!    The evidence is per second: `κ_a = T/(acc_noise²·acc_tau)` for a period `T` (divided by
//!    `1 + ((|ā| − g)/acc_reject)²`), `κ_m = T/(mag_noise²·mag_tau·w)` (`w ≥ 1` from the
//!    field's measured variation, module `magnetic`); the same defaults therefore behave the
//!    same at 100 Hz and at 1 kHz.
//!
//! A new sensor (an external heading, say) is a module with its state, its per-sample step and
//! its evidence item, a field of the per-sample state, and its calls in `step`.
//!
//! The state is committed at the end of the sample: a refused sample (non-finite gyroscope, a
//! numerical failure) leaves the AHRS exactly as it was. No allocation, no copy of the filter.
//!
//! # Latency
//!
//! With [`AhrsParams::mag_latency`] (or [`AhrsParams::acc_latency`]) `L > 0`, each magnetometer
//! (accelerometer) sample is first turned forward by the bias-corrected rate of its sample over
//! the latency, `v ← exp(−[ω]× L) v`, so that it shows the field (specific force) at the end of
//! the sample's gyroscope interval. The AHRS estimates the magnetometer's latency from the raw
//! samples ([`Ahrs::mag_latency_estimate`]; the method is in the `latency` module); with
//! `mag_latency` = [`LATENCY_ESTIMATE`] (the default) it compensates that estimate, from the
//! moment it exists (after 5 s of informative motion). The mechanism: during sustained
//! rotation a lag `L` turns the field by `ω·L`, which through the dip becomes a heading error
//! of about `|ω| L tan(dip)`; real sensors have such offsets between channels (BROAD's
//! magnetometer lags by about 12 ms), and the estimate measures it from the IMU alone.
//! `acc_latency` defaults to 0.
//!
//! The first sample initializes the state: tilt from the accelerometer, heading from the
//! magnetometer (without one the heading is uniform: honestly unknown), each with the
//! concentration of [`AhrsParams::init_std`] — unless a start was given with
//! [`Ahrs::set_state`].

use nalgebra::Matrix3;

use crate::error::{Error, Result};
use crate::filter::{BinghamFilter, Core};
use crate::observation::observation_exponent;
use crate::quaternion::q4;

mod accel;
mod bias;
mod correction;
mod evidence;
mod gyro;
mod health;
mod latency;
mod lowpass;
mod magnetic;
mod params;
mod rest;
mod state;
mod timing;
mod uncertainty;
mod vec3;

use accel::Accel;
use gyro::Gyro;
pub use health::{AhrsHealth, HEALTH_THRESHOLD, HEALTH_TIME};
use latency::{turn_forward, LatencyEstimator};
use lowpass::Coeffs;
pub use lowpass::CORRECTION_PERIOD;
pub(crate) use magnetic::MagReference;
use magnetic::{heading_exponent, Magnetic};
pub use params::{
    AhrsParams, LATENCY_ESTIMATE, MAX_LATENCY, MAX_SAMPLE_TIME, MAX_STEP_TIME, MIN_SAMPLE_TIME,
    MIN_STEP_NOISE,
};
use rest::Rest;
use state::SampleState;
use timing::SensorTimes;
pub(crate) use uncertainty::StatedCoupling;
use vec3::{cross3, norm3, scale3, UP};

/// The largest rotation (rad) one gyroscope sample may turn (`|gyr|·sample_time`): a million
/// radians, far beyond any sensor, below where the increment's arithmetic loses meaning.
pub const MAX_TURN: f64 = 1e6;

/// The relative tolerance within which a sample's time step counts as the nominal period.
const SNAP: f64 = 1e-6;

/// Whether a sample is usable: every value finite and its norm representable (a vector of
/// values near the largest double has an overflowing norm: it counts as no sample).
fn usable3(v: &[f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite()) && norm3(v).is_finite()
}

/// A 3×3 matrix as 9 row-major values, made exactly symmetric.
fn symmetric9(c: &Matrix3<f64>) -> [f64; 9] {
    std::array::from_fn(|k| {
        let (i, j) = (k / 3, k % 3);
        0.5 * (c[(i, j)] + c[(j, i)])
    })
}

/// The AHRS. Create it with [`Ahrs::new`], feed it samples with [`Ahrs::update`] (or
/// [`Ahrs::update_batch`]), read [`Ahrs::quaternion`], [`Ahrs::state_into`] and
/// [`Ahrs::angular_spread`]. `Send` and `Sync`; no global state.
#[derive(Debug, Clone)]
pub struct Ahrs {
    params: AhrsParams,
    coeffs: Coeffs,
    filter: Option<BinghamFilter>,
    /// What a sample changes besides the Bingham state: the bias, the low-pass filters, the
    /// rest and magnetic tests, the health readout (committed at the end of the sample).
    sample_state: SampleState,
    /// The online estimate of the magnetometer's latency (a readout; not used by the filter).
    latency: LatencyEstimator,
    /// Whether the latency estimate is kept (see [`Ahrs::without_latency_estimate`]).
    estimate_latency: bool,
    samples: u64,
    /// The timestamp (s) of the last sample of a timed batch ([`Ahrs::update_batch_timed`]).
    last_time: Option<f64>,
}

impl Ahrs {
    /// An AHRS with the given parameters (validated). It initializes itself from the first
    /// sample. Errors: [`Error::InvalidArgument`] for a bad parameter.
    pub fn new(params: &AhrsParams) -> Result<Ahrs> {
        params.validate()?;
        let coeffs = Coeffs::new(params);
        Ok(Ahrs {
            params: *params,
            coeffs,
            filter: None,
            sample_state: SampleState::new(params, &coeffs),
            latency: LatencyEstimator::new(params.sample_time),
            estimate_latency: true,
            samples: 0,
            last_time: None,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &AhrsParams {
        &self.params
    }

    /// Whether there is an estimate: the first sample has been processed or a state was set.
    pub fn is_initialized(&self) -> bool {
        self.filter.is_some()
    }

    /// The number of samples processed.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// The orientation estimate (the Bingham state's mode), sensor → world (ENU), scalar first,
    /// sign chosen with `w ≥ 0`. Before the first sample: the identity.
    pub fn quaternion(&self) -> [f64; 4] {
        match &self.filter {
            Some(f) => {
                let q = f.core4().map_or([1.0, 0.0, 0.0, 0.0], |c| c.mode());
                if q[0] < 0.0 {
                    [-q[0], -q[1], -q[2], -q[3]]
                } else {
                    q
                }
            }
            None => [1.0, 0.0, 0.0, 0.0],
        }
    }

    /// The Bingham state `(M row-major 4×4, z)` into the buffers (lengths 16 and 4): the state
    /// of the last correction step, turned by the gyroscope since (the process noise of the
    /// samples since then, at most [`CORRECTION_PERIOD`], is added at the next correction; the
    /// spread includes it). Before the first sample: the uniform distribution (`M = I`,
    /// `z = 0`).
    pub fn state_into(&self, m: &mut [f64], z: &mut [f64]) -> Result<()> {
        match &self.filter {
            Some(f) => f.state_into(m, z),
            None => {
                if m.len() != 16 || z.len() != 4 {
                    return Err(Error::InvalidDimension(format!(
                        "state buffers must have lengths 16 and 4, got {} and {}",
                        m.len(),
                        z.len()
                    )));
                }
                m.iter_mut().enumerate().for_each(|(k, v)| {
                    *v = if k % 5 == 0 { 1.0 } else { 0.0 };
                });
                z.fill(0.0);
                Ok(())
            }
        }
    }

    /// Replaces the orientation estimate by `Bingham(M, z)` (`m` 4×4 row-major orthogonal,
    /// `z` 4 concentrations in any order and shift; validated as [`BinghamFilter::new`]), e.g.
    /// a known start or a re-initialization. The bias estimate, the low-pass filters and the
    /// magnetic reference are kept; the new state's error is the caller's, so its coupling to
    /// the bias's and the scale error's (which the corrections learn them from) starts afresh,
    /// as after the recovery from a wrong start. Set before the first sample, it replaces the
    /// self-initialization: the first sample then only primes the low-pass filters.
    ///
    /// Errors: [`Error::InvalidDimension`] (lengths), [`Error::InvalidArgument`] (NaN/Inf, `M`
    /// not orthogonal), [`Error::Numerical`] (moments of the state not computable); the AHRS
    /// is then unchanged.
    pub fn set_state(&mut self, m: &[f64], z: &[f64]) -> Result<()> {
        let mut f = BinghamFilter::new(4, m, z)?;
        let omega = f.core4_mut()?.omega()?;
        if let Some(old) = self.filter.as_mut() {
            old.set_state(m, z)?;
        } else {
            self.filter = Some(f);
        }
        self.sample_state.omega = [omega[0], omega[1], omega[2], omega[3]];
        self.sample_state.bias.pending = Matrix3::zeros();
        // the new state carries none of the gaps' variance, nor the part a scale error
        // explained through the old state's coupling (module `uncertainty`)
        self.sample_state.gyro.gap_stated = 0.0;
        self.sample_state.bias.decouple();
        Ok(())
    }

    /// The underlying filter (`None` before the first sample); its state as in
    /// [`Ahrs::state_into`].
    pub fn filter(&self) -> Option<&BinghamFilter> {
        self.filter.as_ref()
    }

    /// The angular spread of the state (radians): `out[0..3]` the standard deviations along
    /// the state's principal directions, `out[3]` the total (≈ the RMS rotation angle between
    /// the truth and the estimate), the square roots of the variances of
    /// [`Ahrs::orientation_covariance`] along those directions and of its trace: the state's
    /// own spread with the process noise accumulated since the last correction, scaled by
    /// what the innovations show, widened by the heading reference's error and with the
    /// heading error a tilt error brings through the magnetometer (module `uncertainty`).
    /// Before the first sample: that of the uniform distribution.
    pub fn angular_spread(&self, out: &mut [f64; 4]) -> Result<()> {
        let Some(f) = &self.filter else {
            crate::observation::spread_from_omega(&[0.25; 4], out);
            return Ok(());
        };
        // the stated covariance's variances along the principal directions (world frame):
        // their sum is its trace
        let core = f.core4()?;
        let (m, _) = core.params();
        let q = core.mode();
        let r = q4::to_matrix(&q);
        let r = Matrix3::from_fn(|i, j| r[i][j]);
        let dirs = bias::principal_directions(m, &q);
        let pending = bias::psd(&self.sample_state.bias.pending);
        let c = uncertainty::stated(&r, &dirs, &pending, &self.stated_parts(true));
        let v: [f64; 3] = std::array::from_fn(|i| {
            let d = r * dirs[i];
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
        Ok(Some(uncertainty::stated(
            &r,
            &dirs,
            &pending,
            &self.stated_parts(coupled),
        )))
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
    /// over the last [`HEALTH_TIME`] seconds; `score` above [`HEALTH_THRESHOLD`] flags an
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
    /// [`AhrsParams::mag_latency`] to compensate a latency); it estimates the latency of the raw
    /// samples whatever `mag_latency` is. The value is shrunk towards 0 by its own standard
    /// error `σ` (from two halves of the data): `L·max(0, 1 − σ²/L²)`, so that a latency the
    /// data cannot tell from none reads 0 (module `latency`); it is the value the default
    /// ([`LATENCY_ESTIMATE`]) compensates.
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
    /// `mag_latency` is not [`LATENCY_ESTIMATE`], so that the filter does not use it either:
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

    /// Processes one sample taken [`AhrsParams::sample_time`] after the previous one: `gyr`
    /// (rad/s), `acc` (m/s²), `mag` (any unit, or `None`). [`Ahrs::update_dt`] with the nominal
    /// period.
    pub fn update(&mut self, gyr: &[f64; 3], acc: &[f64; 3], mag: Option<&[f64; 3]>) -> Result<()> {
        self.update_dt(self.params.sample_time, gyr, acc, mag)
    }

    /// Processes one sample taken `dt` seconds after the previous one (its own time step:
    /// jitter, dropped packets; module `timing`): `gyr` (rad/s), `acc` (m/s²), `mag` (any unit,
    /// or `None`). `dt` of the first sample is not used; a `dt` within a millionth of
    /// [`AhrsParams::sample_time`] is taken as it (so uniformly spaced timestamps give the
    /// results of [`Ahrs::update`] bit for bit).
    ///
    /// Per channel, a non-finite (NaN/Inf) sample means "no sample" of that sensor: a missing
    /// gyroscope sample is a gap, turned with the last rate held and its uncertainty added to
    /// the spread; a missing accelerometer or magnetometer sample gives no evidence. Refused
    /// (error, nothing changed): `dt` not finite or outside [`MIN_SAMPLE_TIME`] …
    /// [`MAX_STEP_TIME`]; a gyroscope sample turning more than [`MAX_TURN`] rad in `dt`; the
    /// first sample without a usable accelerometer (non-finite or `|acc| < gravity/4`: no tilt
    /// to start from); a numerical failure of a correction step ([`Error::Numerical`]).
    /// Skipped parts (not an error): the accelerometer when `|acc| < gravity/4` (free fall),
    /// the magnetometer for a zero field, a field along the vertical, or a disturbed field.
    pub fn update_dt(
        &mut self,
        dt: f64,
        gyr: &[f64; 3],
        acc: &[f64; 3],
        mag: Option<&[f64; 3]>,
    ) -> Result<()> {
        self.step_dt(dt, gyr, acc, mag, None)?;
        self.last_time = None;
        Ok(())
    }

    /// A sample of a pass over reversed time (module `smoother`): [`Ahrs::update_dt`] with
    /// `gyr` the inverted rate of the recorded sample after this one, and `far` the inverted
    /// rate of the recorded sample before the interval, with which the rest of a longer
    /// interval is bridged after the sample's own period (module `gyro`).
    pub(crate) fn update_reversed(
        &mut self,
        dt: f64,
        gyr: &[f64; 3],
        far: &[f64; 3],
        acc: &[f64; 3],
        mag: Option<&[f64; 3]>,
    ) -> Result<()> {
        self.step_dt(dt, gyr, acc, mag, Some(far))?;
        self.last_time = None;
        Ok(())
    }

    /// The mode [`Ahrs::update_reversed`] with these arguments turns the state to before its
    /// correction: the current mode times the gyroscope's increment (the identity before the
    /// first sample). Changes nothing.
    pub(crate) fn reversed_prediction(&self, dt: f64, gyr: &[f64; 3], far: &[f64; 3]) -> [f64; 4] {
        let q = self.quaternion();
        if self.samples == 0 {
            return q;
        }
        let gyr = gyr.iter().all(|x| x.is_finite()).then_some(gyr);
        let dq = self.sample_state.gyro.preview(
            &self.params,
            &self.sample_state.bias,
            self.snap(dt),
            gyr,
            Some(far),
        );
        q4::mul(&q, &dq)
    }

    /// `dt` within [`SNAP`] of the nominal period is the nominal period.
    fn snap(&self, dt: f64) -> f64 {
        let nominal = self.params.sample_time;
        if (dt - nominal).abs() <= SNAP * nominal {
            nominal
        } else {
            dt
        }
    }

    /// [`Ahrs::update_dt`] without forgetting a timed batch's last timestamp.
    fn step_dt(
        &mut self,
        dt: f64,
        gyr: &[f64; 3],
        acc: &[f64; 3],
        mag: Option<&[f64; 3]>,
        far: Option<&[f64; 3]>,
    ) -> Result<()> {
        // A step within a millionth of the nominal period is the nominal period: differences
        // of uniformly spaced timestamps carry rounding, which should not make every sample
        // take the path of an irregular one (nor be refused at the smallest period).
        let dt = self.snap(dt);
        if !(MIN_SAMPLE_TIME..=MAX_STEP_TIME).contains(&dt) {
            return Err(Error::InvalidArgument(format!(
                "the time step dt = {dt} s is not finite or outside {MIN_SAMPLE_TIME:e} to \
                 {MAX_STEP_TIME} s (seconds, not milliseconds)"
            )));
        }
        // a finite rate whose norm overflows is no gap: it turns far more than MAX_TURN
        let gyr = gyr.iter().all(|x| x.is_finite()).then_some(gyr);
        if let Some(g) = gyr {
            let turn = norm3(g) * dt;
            if !turn.is_finite() || turn > MAX_TURN {
                return Err(Error::InvalidArgument(format!(
                    "the gyroscope sample turns by |gyr|·dt = {turn:e} rad, more than \
                     {MAX_TURN:e} rad in one sample: not a rotation rate"
                )));
            }
        }
        let acc = usable3(acc).then_some(acc);
        let mag = mag.filter(|m| usable3(m) && norm3(m) > 0.0);
        if self.samples == 0 {
            return self.initialize(gyr, acc, mag);
        }
        let core = self
            .filter
            .as_mut()
            .ok_or_else(|| Error::Numerical("AHRS without a state after its first sample".into()))?
            .core4_mut()?;
        // the sample works on the state in place; a refused sample puts these copies back.
        // Only a correction can refuse a sample (the other steps cannot fail), so the copies
        // are taken only when this sample ends a correction period: the test `step` makes,
        // on the period this sample completes (the same sum in the same order).
        let saved = correction_due(
            &self.params,
            &self.coeffs,
            self.sample_state.times.period + dt,
        )
        .then(|| (core.save(), self.sample_state.clone()));
        let mut c = self.coeffs;
        if self.params.mag_latency == LATENCY_ESTIMATE {
            c.mag_lead = self.latency.compensated().unwrap_or(0.0) / self.params.sample_time;
        }
        match step(
            &self.params,
            &c,
            core,
            &mut self.sample_state,
            dt,
            gyr,
            far,
            acc,
            mag,
        ) {
            Ok((dq, mag_used)) => {
                // the latency estimate works on the raw samples at the nominal period
                // (infallible, after the rest); a sample off the period is not one of them
                if self.estimate_latency
                    && gyr.is_some()
                    && (dt - self.params.sample_time).abs() <= 0.5 * self.params.sample_time
                {
                    self.latency.push(&dq, if mag_used { mag } else { None });
                }
                self.samples += 1;
                Ok(())
            }
            Err(e) => {
                if let Some((core_saved, state_saved)) = saved {
                    core.restore(core_saved);
                    self.sample_state = state_saved;
                }
                Err(e)
            }
        }
    }

    /// The first sample: tilt from `acc`, heading from `mag` (uniform without it).
    fn initialize(
        &mut self,
        gyr: Option<&[f64; 3]>,
        acc: Option<&[f64; 3]>,
        mag: Option<&[f64; 3]>,
    ) -> Result<()> {
        let p = self.params;
        let c = self.coeffs;
        let Some(acc_raw) = acc else {
            return Err(Error::InvalidArgument(
                "the first sample must show gravity: its accelerometer sample is not finite; \
                 the AHRS starts from a sample with a usable accelerometer"
                    .into(),
            ));
        };
        // without a gyroscope sample the rate is taken as zero (the sensor at rest)
        let gyr = gyr.unwrap_or(&[0.0; 3]);
        // the latency compensation of `update`, with the rate of this sample
        let w = scale3(&self.sample_state.bias.rate(gyr), p.sample_time);
        let acc = turn_forward(acc_raw, &w, c.acc_lead);
        let mag = mag.map(|m| turn_forward(m, &w, c.mag_lead));
        let an = norm3(&acc);
        if an < 0.25 * p.gravity {
            return Err(Error::InvalidArgument(format!(
                "the first sample must show gravity: |acc| = {an} < gravity/4 (free fall or \
                 no data); the AHRS starts from a sample with a usable accelerometer"
            )));
        }
        let up_b = scale3(&acc, 1.0 / an);
        let kappa = 1.0 / (p.init_std * p.init_std);
        // A state given by `set_state` before the first sample is kept as the start.
        let given = self.filter.is_some();
        let mut f = match &self.filter {
            Some(f) => f.clone(),
            None => BinghamFilter::new(
                4,
                &[
                    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
                ],
                &[0.0; 4],
            )?,
        };
        let mut mag_state = Magnetic::new();
        {
            let core = f.core4_mut()?;
            if !given {
                core.update_precision(&observation_exponent(&up_b, &UP, kappa))?;
            }
            if let Some(m) = mag.as_ref() {
                let east_b = cross3(m, &up_b);
                let en = norm3(&east_b);
                if en > 1e-3 * norm3(m) {
                    let east_b = scale3(&east_b, 1.0 / en);
                    let north_b = cross3(&up_b, &east_b);
                    let q0 = q4::from_matrix(&[east_b, north_b, up_b]);
                    if !given {
                        core.update_precision(&heading_exponent(&q0, kappa))?;
                    }
                    mag_state.start(m, &up_b);
                    mag_state.observe(&core.mode(), m, 0.0, p.sample_time, 1, &p, &c);
                }
            }
        }
        let omega = f.core4()?.omega()?;
        self.filter = Some(f);
        self.sample_state.rest = Rest::start(gyr, acc_raw);
        self.sample_state.gyro = Gyro::default();
        self.sample_state.accel = Accel::new(&c, &acc);
        self.sample_state.mag = mag_state;
        self.sample_state.times = SensorTimes::default();
        self.sample_state.omega = [omega[0], omega[1], omega[2], omega[3]];
        self.sample_state.bias.pending = Matrix3::zeros();
        self.samples = 1;
        Ok(())
    }

    /// Processes `gyr.len()` samples (`acc` the same length, `mag` too or `None`), writing the
    /// quaternion after each into `quat` (and, if given, the total angular spread into
    /// `spread`, see [`Ahrs::update_spread`]). A row of NaN in `acc` or `mag` means "no sample"
    /// for that sensor at that time (see [`Ahrs::update`]). Stops at the first refused sample:
    /// the samples before it are processed and their outputs written, the refused one changes
    /// nothing; the error names the index.
    pub fn update_batch(
        &mut self,
        gyr: &[[f64; 3]],
        acc: &[[f64; 3]],
        mag: Option<&[[f64; 3]]>,
        quat: &mut [[f64; 4]],
        spread: Option<&mut [f64]>,
    ) -> Result<()> {
        self.update_batch_health(gyr, acc, mag, quat, spread, None)
    }

    /// [`Ahrs::update_batch`], also writing the health score ([`Ahrs::health`]`.score`) after
    /// each sample into `health` if given (the same length).
    pub fn update_batch_health(
        &mut self,
        gyr: &[[f64; 3]],
        acc: &[[f64; 3]],
        mag: Option<&[[f64; 3]]>,
        quat: &mut [[f64; 4]],
        spread: Option<&mut [f64]>,
        health: Option<&mut [f64]>,
    ) -> Result<()> {
        self.batch(None, gyr, acc, mag, quat, spread, health)
    }

    /// [`Ahrs::update_batch_health`] with a timestamp per sample: `time[k]` (s, strictly
    /// increasing, any origin) is when sample `k` was taken, and each sample is processed with
    /// its own time step ([`Ahrs::update_dt`]): `time[k] − time[k−1]`, for the first sample
    /// `time[0]` minus the last timestamp of the previous timed batch, or the nominal period if
    /// there was none (or a sample without a timestamp came since). A row of NaN in `gyr`,
    /// `acc` or `mag` means "no sample" of that sensor. Stops at the first refused sample (a
    /// timestamp not after the previous one, a step above [`MAX_STEP_TIME`]), as
    /// [`Ahrs::update_batch`] does.
    #[allow(clippy::too_many_arguments)]
    pub fn update_batch_timed(
        &mut self,
        time: &[f64],
        gyr: &[[f64; 3]],
        acc: &[[f64; 3]],
        mag: Option<&[[f64; 3]]>,
        quat: &mut [[f64; 4]],
        spread: Option<&mut [f64]>,
        health: Option<&mut [f64]>,
    ) -> Result<()> {
        self.batch(Some(time), gyr, acc, mag, quat, spread, health)
    }

    /// The batch calls: each sample with the nominal period or its timestamp's step.
    #[allow(clippy::too_many_arguments)]
    fn batch(
        &mut self,
        time: Option<&[f64]>,
        gyr: &[[f64; 3]],
        acc: &[[f64; 3]],
        mag: Option<&[[f64; 3]]>,
        quat: &mut [[f64; 4]],
        mut spread: Option<&mut [f64]>,
        mut health: Option<&mut [f64]>,
    ) -> Result<()> {
        let n = gyr.len();
        let lengths_ok = acc.len() == n
            && quat.len() == n
            && time.is_none_or(|t| t.len() == n)
            && mag.is_none_or(|m| m.len() == n)
            && spread.as_ref().is_none_or(|s| s.len() == n)
            && health.as_ref().is_none_or(|h| h.len() == n);
        if !lengths_ok {
            return Err(Error::InvalidDimension(
                "batch arrays must all have the same number of samples".into(),
            ));
        }
        for k in 0..n {
            let m = mag.map(|m| &m[k]);
            match time {
                Some(t) => {
                    let tk = t[k];
                    let dt = match self.last_time {
                        Some(last) => tk - last,
                        None => self.params.sample_time,
                    };
                    if !tk.is_finite() || dt <= 0.0 {
                        return Err(prefix(
                            Error::InvalidArgument(format!(
                                "timestamp {tk} s is not finite or not after the previous one \
                                 (timestamps must increase strictly)"
                            )),
                            k,
                        ));
                    }
                    self.step_dt(dt, &gyr[k], &acc[k], m, None)
                        .map_err(|e| prefix(e, k))?;
                    self.last_time = Some(tk);
                }
                None => self.update(&gyr[k], &acc[k], m).map_err(|e| prefix(e, k))?,
            }
            if let Some(s) = spread.as_deref_mut() {
                let mut out = [0.0; 4];
                self.angular_spread(&mut out).map_err(|e| prefix(e, k))?;
                s[k] = out[3];
            }
            quat[k] = self.quaternion();
            if let Some(h) = health.as_deref_mut() {
                h[k] = self
                    .sample_state
                    .health
                    .readout(None, &self.sample_state.times)
                    .score;
            }
        }
        Ok(())
    }

    /// [`Ahrs::update`] followed by the total angular spread (radians) of the new state, as one
    /// step (the spread comes from quantities the update keeps; it cannot fail once the
    /// update succeeded).
    pub fn update_spread(
        &mut self,
        gyr: &[f64; 3],
        acc: &[f64; 3],
        mag: Option<&[f64; 3]>,
    ) -> Result<f64> {
        self.update(gyr, acc, mag)?;
        let mut out = [0.0; 4];
        self.angular_spread(&mut out)?;
        Ok(out[3])
    }
}

/// One sample after the first on the working copies, `h` seconds after the previous one: the
/// per-sensor steps in the order of the module documentation. Returns the gyroscope increment
/// and whether the field sample was used.
#[allow(clippy::too_many_arguments)]
fn step(
    p: &AhrsParams,
    nominal: &Coeffs,
    core: &mut Core<4>,
    s: &mut SampleState,
    h: f64,
    gyr: Option<&[f64; 3]>,
    far: Option<&[f64; 3]>,
    acc: Option<&[f64; 3]>,
    mag: Option<&[f64; 3]>,
) -> Result<([f64; 4], bool)> {
    // the first-order filters' coefficients for this step, and the number of nominal samples
    // the second-order filters take it as (a zero-order hold over dropped samples)
    let c = &nominal.at_step(p, h);
    let repeat = (h / p.sample_time).round().clamp(1.0, 1e6) as u32;

    // 0. Averages gone stale (a loss longer than their time constant, a gap that turned them)
    // restart from this sample (module `timing`).
    s.accel.restart_if_stale(p, c, s.times.acc_missing, acc);
    s.mag
        .restart_if_stale(p, s.times.mag_missing, mag.is_some());

    // 1. Rest detection and the bias at rest (without a gyroscope sample the test and the
    // rest's timer wait for the next one).
    if let Some(g) = gyr {
        s.rest.step(p, c, h, g, acc, &mut s.bias);
    }

    // 2. Gyroscope: the exact turn, the process noise accumulated, gaps.
    let gyr_missing = s.times.gyr_missing;
    let turn = s
        .gyro
        .step(p, core, &mut s.bias, &mut s.rest, gyr_missing, h, gyr, far);
    if let Some(turned) = turn.gap_ended {
        s.accel.after_gap(p, turned);
        s.mag.after_gap(p, turned);
    }

    // 3. Accelerometer: low-passed in the gyroscope-integrated frame.
    let acc_used = s.accel.step(p, c, &turn, repeat, acc);

    // 4. Magnetometer: disturbance phases and the world-frame average.
    let mag_seen = s.mag.step(p, c, core, &turn, h, repeat, mag);
    if let Some(used) = mag_seen {
        s.health.mag_sample(used, h);
    }
    let mag_used = mag_seen == Some(true);
    s.times
        .sample(h, gyr.is_some(), acc_used, mag.is_some(), mag_used);

    // 5. Correction, once the samples since the last one span the correction period (the
    // same cadence as `correct_every` nominal samples): the period's length and the time the
    // sensors' samples covered in it (module `timing`).
    if correction_due(p, c, s.times.period) {
        let (t, t_acc, t_mag) = s.times.take_period();
        // 5.1 the prior: the state composed with the accumulated process noise
        let prior_total = 4.0 * (s.omega[0] + s.omega[1] + s.omega[2]) + s.bias.pending.trace();
        let prior = correction::prior(core, &s.omega, &mut s.bias)?;
        // 5.2, 5.3 each sensor's evidence
        let heading = s.mag.heading_evidence(p, t_mag, &prior.mode);
        let mag_observed = heading.is_some();
        let evidence = [s.accel.tilt_evidence(p, t_acc, &prior.mode), heading];
        // 5.4 the health readout scores the innovations against the prior
        let gravity_excess = s.accel.gravity_excess(p, t_acc);
        s.health.gravity(t, gravity_excess);
        let nu = s.health.correction(t, &prior.lam, &evidence);
        let innovation = nu.largest();
        // the stated uncertainty's averages (module `uncertainty`): the excess relative to g,
        // weighted as the tilt evidence is (divided by 1 + excess²: the state follows an
        // accelerometer error only as far as the evidence it gives counts)
        let gravity_dev = gravity_excess.map(|x| x * p.acc_reject / p.gravity / (1.0 + x * x));
        s.calib.correction(t, &nu, gravity_dev);
        if let Some(v) = nu.tilt_variance {
            let (st, _) = s.calib.scales();
            s.mag
                .set_tilt_variance(st * v + s.calib.tilt_reference_variance());
        }
        // 5.5 one exact Bayes product with every exponent
        let update = correction::update(core, &prior, &evidence)?;
        // 5.6 the bias from the move of the mode
        let gap = std::mem::take(&mut s.gyro.gap_in_period);
        let at_rest = s.rest.timer >= p.rest_time;
        correction::learn_bias(p, &mut s.bias, &update, &evidence, innovation, gap, at_rest);
        // 5.7 the field's average turned with the heading correction
        if mag_observed {
            s.mag.follow_correction(&prior.mode, &update.mode);
        }
        s.omega = update.omega;
        // 5.8 the gaps' variance shrinks as the state's does (a Bayes update scales every part
        // of the prior's variance alike, to first order)
        let post_total = 4.0 * (s.omega[0] + s.omega[1] + s.omega[2]);
        if s.gyro.gap_stated > 0.0 && prior_total > 0.0 {
            s.gyro.gap_stated *= (post_total / prior_total).clamp(0.0, 1.0);
        }
    }
    Ok((turn.dq, mag_used))
}

/// Whether a correction period ends once the samples since the last correction span `period`
/// seconds: they span the correction period (`correct_time`, the same cadence as
/// `correct_every` nominal samples) within half a sample.
fn correction_due(p: &AhrsParams, c: &Coeffs, period: f64) -> bool {
    period >= c.correct_time - 0.5 * p.sample_time
}

/// `e` with "sample k: " in front of its message.
fn prefix(e: Error, k: usize) -> Error {
    match e {
        Error::InvalidDimension(m) => Error::InvalidDimension(format!("sample {k}: {m}")),
        Error::InvalidArgument(m) => Error::InvalidArgument(format!("sample {k}: {m}")),
        Error::NotConverged(m) => Error::NotConverged(format!("sample {k}: {m}")),
        Error::Numerical(m) => Error::Numerical(format!("sample {k}: {m}")),
        Error::Callback(m) => Error::Callback(format!("sample {k}: {m}")),
    }
}
