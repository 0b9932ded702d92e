//! The AHRS's estimator: its state, the first sample, and each sample after it (the
//! per-sensor steps are in `step.rs`, the readouts in `readouts.rs`, the batch calls in
//! `batch.rs`).

use nalgebra::Matrix3;

use crate::error::{Error, Result};
use crate::filter::BinghamFilter;
use crate::observation::observation_exponent;
use crate::quaternion::q4;

use super::accel::Accel;
use super::gyro::Gyro;
use super::latency::{turn_forward, LatencyEstimator};
use super::lowpass::Coeffs;
use super::magnetic::{heading_exponent, Magnetic};
use super::params::{AhrsParams, LATENCY_ESTIMATE, MAX_STEP_TIME, MIN_SAMPLE_TIME};
use super::rest::Rest;
use super::state::SampleState;
use super::step::{correction_due, step};
use super::timing::SensorTimes;
use super::vec3::{cross3, norm3, scale3, UP};

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

/// The AHRS. Create it with [`Ahrs::new`], feed it samples with [`Ahrs::update`] (or
/// [`Ahrs::update_batch`]), read [`Ahrs::quaternion`], [`Ahrs::state_into`] and
/// [`Ahrs::angular_spread`]. `Send` and `Sync`; no global state.
#[derive(Debug, Clone)]
pub struct Ahrs {
    pub(super) params: AhrsParams,
    pub(super) coeffs: Coeffs,
    pub(super) filter: Option<BinghamFilter>,
    /// What a sample changes besides the Bingham state: the bias, the low-pass filters, the
    /// rest and magnetic tests, the health readout (committed at the end of the sample).
    pub(super) sample_state: SampleState,
    /// The online estimate of the magnetometer's latency (a readout; not used by the filter).
    pub(super) latency: LatencyEstimator,
    /// Whether the latency estimate is kept (see [`Ahrs::without_latency_estimate`]).
    pub(super) estimate_latency: bool,
    pub(super) samples: u64,
    /// The timestamp (s) of the last sample of a timed batch ([`Ahrs::update_batch_timed`]).
    pub(super) last_time: Option<f64>,
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
    /// samples since then, at most [`CORRECTION_PERIOD`](super::lowpass::CORRECTION_PERIOD), is added at the next correction; the
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
    pub(super) fn step_dt(
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
}
