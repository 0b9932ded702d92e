//! An attitude and heading reference system (AHRS) on the recursive Bingham filter: gyroscope,
//! accelerometer and (optionally) magnetometer, every sensor an exact Bayes step on a Bingham
//! state of the orientation.
//!
//! Conventions: the orientation `q = (w, x, y, z)` (scalar first) maps the sensor frame to the
//! world frame **ENU** (x east, y magnetic north, z up): `v_world = q ⊗ v_sensor ⊗ q*`.
//! Units: gyroscope rad/s, accelerometer m/s² (specific force: `+g` up at rest), magnetometer in
//! any consistent unit.
//!
//! # One sample
//!
//! 1. **Rest detection and gyroscope bias.** The gyroscope and accelerometer are low-pass
//!    filtered; while both stay within thresholds of their low-pass values for
//!    [`AhrsParams::rest_time`], the sensor is at rest and the bias estimate moves toward the
//!    low-passed rate. During motion the bias follows the corrections the observations make
//!    (an integral term, time constant [`AhrsParams::bias_time`]), clipped to
//!    [`AhrsParams::bias_max`].
//! 2. **Prediction** `q ← q ⊗ Δq ⊗ w`: `Δq` the body-frame increment of the bias-corrected rate
//!    (exact rotation of the Bingham state), `w` isotropic rotation noise of standard deviation
//!    `gyro_noise·√dt` ([`crate::observation::noise_from_angle_std`], moment-matched exactly).
//! 3. **Accelerometer** as a vector observation of "up" ([`crate::observation::davenport_matrix`])
//!    with `a` the accelerometer low-passed in the gyroscope-integrated (quasi-inertial) frame
//!    (second-order Butterworth, time constant `acc_tau`; its states are turned with every
//!    gyroscope increment; it starts as a running mean over its first `acc_tau`): gravity stands
//!    still there while linear accelerations average out. The likelihood
//!    `exp(κ upᵀ R(q) a/|a|)` is Bingham in `q`, the update exact, heading untouched.
//!    `κ = 1/acc_noise²`, reduced when `|a|` departs from `gravity`:
//!    `κ / (1 + ((|a| − g)/acc_reject)²)`. Samples with `|acc| < gravity/4` (free fall, or no
//!    accelerometer data) are not fed to the low-pass filter.
//! 4. **Magnetometer** as a heading observation that cannot tilt the estimate: the field,
//!    low-passed like the accelerometer (`mag_tau`; disturbed samples are not fed), is
//!    rotated to the world frame with the current estimate, its horizontal direction gives the
//!    heading error `δ`, and the likelihood `exp(−2κ e_z²)` with `e = q ⊗ q_m*`,
//!    `q_m = Rz(δ) ⊗ q̂` (the von Mises density `exp(κ cos ψ)` of the heading error `ψ`, written
//!    in `q`) is a Bingham density whose only concentrated direction is the rotation about the
//!    vertical: at the estimate it carries no tilt information at all. `κ = 1/mag_noise²`.
//!    Magnetic disturbances are rejected: the field's norm and dip angle are tracked; a sample
//!    whose norm differs from the reference by more than `mag_norm_tol` (relative) or whose dip
//!    differs by more than `mag_dip_tol` is not used. A disturbance that stays constant for
//!    `mag_new_time` becomes the new reference.
//!
//! # Latency
//!
//! With [`AhrsParams::mag_latency`] (or [`AhrsParams::acc_latency`]) `L > 0`, each magnetometer
//! (accelerometer) sample is first turned forward by the bias-corrected rate of its sample over
//! the latency, `v ← exp(−[ω]× L) v` (the rotation by the rotation vector `−ω·L`), so that it
//! shows the field (specific force) at the end of the sample's gyroscope interval; the
//! disturbance test and the low-pass filters see the turned samples. Default 0: the samples are
//! used as they are.
//!
//! Independently, the AHRS estimates the magnetometer's latency from the raw samples
//! ([`Ahrs::mag_latency_estimate`]): in a homogeneous field `dm/dt = −ω × m` in the sensor
//! frame, exactly `m_k − m_{k−s} = −φ × (m_k + m_{k−s})/2` over a span of `s` samples (`φ` the
//! Cayley vector of the rotation the gyroscope composes over the span); the residual of this
//! relation with the gyroscope taken `j` samples earlier is smallest at the latency. The
//! exponentially forgotten mean squares of the residuals for lags `j = 0 … W` (W: 40 ms, at
//! most 32 samples, at least 2; span `s = W`; pairs weighted by the change of the rate they
//! see, memory 30 s of informative motion; only undisturbed samples) give the estimate as the
//! vertex of a parabola through the smallest and its neighbours. Convention: gyroscope sample k
//! is the rate over (t_{k−1}, t_k], as in the prediction; then the estimate has no half-sample
//! offset. Fixed-size buffers, no allocation.
//!
//! The first sample initializes the state: tilt from the accelerometer, heading from the
//! magnetometer (without one the heading is uniform: honestly unknown), each with the
//! concentration of [`AhrsParams::init_std`] — unless a start was given with
//! [`Ahrs::set_state`].
//!
//! Every step is allocation-free; a refused sample leaves the AHRS exactly as it was.

use nalgebra::Matrix4;

use crate::error::{Error, Result};
use crate::filter::{BinghamFilter, Noise};
use crate::observation::{noise_from_angle_std, observation_exponent};
use crate::quaternion::q4;

mod latency;
mod lowpass;
mod params;
mod vec3;

use latency::{turn_forward, LatencyEstimator};
use lowpass::{Coeffs, InertialLowPass};
pub use params::{AhrsParams, MAX_LATENCY, MAX_SAMPLE_TIME, MIN_SAMPLE_TIME, MIN_STEP_NOISE};
use vec3::{cross3, dot3, norm3, scale3};

/// The world's "up" (ENU).
const UP: [f64; 3] = [0.0, 0.0, 1.0];

fn check_sample(what: &str, v: &[f64; 3]) -> Result<()> {
    match v.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(i) => Err(Error::InvalidArgument(format!(
            "`{what}[{i}]` = {} is not finite",
            v[i]
        ))),
    }
}

/// The exponent matrix `−2κ u uᵀ` of the heading likelihood `exp(−2κ e_z²)`, `e = q ⊗ q_m*`:
/// `e_z = uᵀ q` with `u` the last row of `R(q_m*)` (`x ⊕ y = R(y) x`).
fn heading_exponent(q_m: &[f64; 4], kappa: f64) -> Matrix4<f64> {
    let c = q4::conj(q_m);
    // Row 3 of R(c) (see quaternion::right_matrix): [c3, c2, −c1, c0].
    let u = [c[3], c[2], -c[1], c[0]];
    Matrix4::from_fn(|i, j| -2.0 * kappa * u[i] * u[j])
}

/// Magnetic disturbance tracking (norm and dip of the field).
#[derive(Debug, Clone, PartialEq)]
struct MagRef {
    norm: f64,
    dip: f64,
    /// The current candidate for a new reference and how long it has held.
    cand_norm: f64,
    cand_dip: f64,
    cand_time: f64,
}

/// The AHRS. Create it with [`Ahrs::new`], feed it samples with [`Ahrs::update`] (or
/// [`Ahrs::update_batch`]), read [`Ahrs::quaternion`], [`Ahrs::state_into`] and
/// [`Ahrs::angular_spread`]. `Send` and `Sync`; no global state.
#[derive(Debug, Clone)]
pub struct Ahrs {
    params: AhrsParams,
    coeffs: Coeffs,
    /// The process noise, prepared once (fixed for the AHRS's life).
    noise: Noise<4>,
    filter: Option<BinghamFilter>,
    bias: [f64; 3],
    gyr_lp: [f64; 3],
    acc_lp: [f64; 3],
    rest_timer: f64,
    mag: Option<MagRef>,
    acc_filter: InertialLowPass,
    mag_filter: Option<InertialLowPass>,
    /// The online estimate of the magnetometer's latency (a readout; not used by the filter).
    latency: LatencyEstimator,
    samples: u64,
}

impl Ahrs {
    /// An AHRS with the given parameters (validated). It initializes itself from the first
    /// sample. Errors: [`Error::InvalidArgument`] for a bad parameter.
    pub fn new(params: &AhrsParams) -> Result<Ahrs> {
        params.validate()?;
        let noise = noise_from_angle_std(4, params.gyro_noise * params.sample_time.sqrt())?;
        let noise = Noise::process(&noise.m_row_major(), noise.z().as_slice())?;
        let coeffs = Coeffs::new(params);
        Ok(Ahrs {
            params: *params,
            coeffs,
            noise,
            filter: None,
            bias: [0.0; 3],
            gyr_lp: [0.0; 3],
            acc_lp: [0.0; 3],
            rest_timer: 0.0,
            mag: None,
            acc_filter: InertialLowPass::new(coeffs.acc, coeffs.acc_warmup, &[0.0; 3]),
            mag_filter: None,
            latency: LatencyEstimator::new(params.sample_time),
            samples: 0,
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
                let q = f.core4().map_or([1.0, 0.0, 0.0, 0.0], |c| c.mode4());
                if q[0] < 0.0 {
                    [-q[0], -q[1], -q[2], -q[3]]
                } else {
                    q
                }
            }
            None => [1.0, 0.0, 0.0, 0.0],
        }
    }

    /// The Bingham state `(M row-major 4×4, z)` into the buffers (lengths 16 and 4). Before the
    /// first sample: the uniform distribution (`M = I`, `z = 0`).
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
    /// magnetic reference are kept. Set before the first sample, it replaces the
    /// self-initialization: the first sample then only primes the low-pass filters.
    ///
    /// Errors: [`Error::InvalidDimension`] (lengths), [`Error::InvalidArgument`] (NaN/Inf, `M`
    /// not orthogonal); the AHRS is then unchanged.
    pub fn set_state(&mut self, m: &[f64], z: &[f64]) -> Result<()> {
        match self.filter.as_mut() {
            Some(f) => f.set_state(m, z),
            None => {
                self.filter = Some(BinghamFilter::new(4, m, z)?);
                Ok(())
            }
        }
    }

    /// The underlying filter (`None` before the first sample).
    pub fn filter(&self) -> Option<&BinghamFilter> {
        self.filter.as_ref()
    }

    /// The angular spread of the state (radians, see
    /// [`crate::observation::spread_from_omega`]): `out[0..3]` along the principal directions,
    /// `out[3]` the total (≈ the RMS rotation angle between the truth and the estimate, if the
    /// state is calibrated). Before the first sample: that of the uniform distribution.
    pub fn angular_spread(&self, out: &mut [f64; 4]) -> Result<()> {
        match &self.filter {
            Some(f) => f.angular_spread_into(out),
            None => {
                crate::observation::spread_from_omega(&[0.25; 4], out);
                Ok(())
            }
        }
    }

    /// The gyroscope bias estimate (rad/s, sensor frame).
    pub fn gyro_bias(&self) -> [f64; 3] {
        self.bias
    }

    /// The online estimate of the magnetometer's latency behind the gyroscope (s, within 0 and
    /// 40 ms or 32 samples, whichever is smaller; at least 2 samples), from the IMU alone: the
    /// lag at which the field's change best fits `dm/dt = −ω × m` (see the module
    /// documentation, "Latency"). A readout: the filter does not use it (set
    /// [`AhrsParams::mag_latency`] to compensate a latency); it estimates the latency of the raw
    /// samples whatever `mag_latency` is.
    ///
    /// `None` until 5 s of informative motion have been seen — seconds of samples weighted by
    /// `g²/(g² + 1)`, `g` the change of the rotation rate across the lag window perpendicular
    /// to the field, in rad/s² (a constant rotation fits every lag and counts little) — with
    /// the magnetometer present and undisturbed, or when the residuals do not single out a lag.
    pub fn mag_latency_estimate(&self) -> Option<f64> {
        self.latency.estimate()
    }

    /// The latency estimate, or an [`Error::NotConverged`] saying why there is none.
    pub(crate) fn mag_latency_estimate_or_error(&self) -> Result<f64> {
        self.latency
            .estimate()
            .ok_or_else(|| Error::NotConverged(self.latency.why_none()))
    }

    /// Processes one sample: `gyr` (rad/s), `acc` (m/s²), `mag` (any unit, or `None`).
    ///
    /// Refused (error, nothing changed): NaN/Inf in any value ([`Error::InvalidArgument`]);
    /// the first sample with `|acc| < gravity/4` (no tilt to start from). Skipped parts (not an
    /// error): the accelerometer update when `|acc| < gravity/4` (free fall), the magnetometer
    /// update for a zero field, a field along the vertical, or a disturbed field.
    pub fn update(&mut self, gyr: &[f64; 3], acc: &[f64; 3], mag: Option<&[f64; 3]>) -> Result<()> {
        check_sample("gyr", gyr)?;
        check_sample("acc", acc)?;
        if let Some(m) = mag {
            check_sample("mag", m)?;
        }
        let mag = mag.filter(|m| norm3(m) > 0.0);
        if self.samples == 0 {
            return self.initialize(gyr, acc, mag);
        }
        // Work on a copy of the filter: the state is assigned only when every step succeeded.
        let mut filter = self.filter.clone().expect("initialized");
        let f = filter.core4_mut()?;
        let p = &self.params;
        let dt = p.sample_time;

        // 1. Rest detection and the bias at rest.
        let c = &self.coeffs;
        let mut gyr_lp = self.gyr_lp;
        let mut acc_lp = self.acc_lp;
        for i in 0..3 {
            gyr_lp[i] += c.rest_filter * (gyr[i] - gyr_lp[i]);
            acc_lp[i] += c.rest_filter * (acc[i] - acc_lp[i]);
        }
        let dg = norm3(&[gyr[0] - gyr_lp[0], gyr[1] - gyr_lp[1], gyr[2] - gyr_lp[2]]);
        let da = norm3(&[acc[0] - acc_lp[0], acc[1] - acc_lp[1], acc[2] - acc_lp[2]]);
        let still = dg < p.rest_gyro && da < p.rest_acc && norm3(&gyr_lp) < 2.0 * p.bias_max;
        let rest_timer = if still { self.rest_timer + dt } else { 0.0 };
        let mut bias = self.bias;
        if rest_timer >= p.rest_time {
            for i in 0..3 {
                bias[i] += c.rest_bias * (gyr_lp[i] - bias[i]);
            }
        }

        // 2. Prediction with the body-frame increment of the bias-corrected rate.
        let w = [
            (gyr[0] - bias[0]) * dt,
            (gyr[1] - bias[1]) * dt,
            (gyr[2] - bias[2]) * dt,
        ];
        let dq = q4::from_rotation_vector(&w);
        f.predict_prepared(&dq, &self.noise)?;
        let q_prior = f.mode4();
        // Latency compensation: each sample turned forward by the rate over its latency.
        let acc_now = turn_forward(acc, &w, c.acc_lead);
        let mag_now = mag.map(|m| turn_forward(m, &w, c.mag_lead));

        // 3. Accelerometer: "up" seen in the sensor frame, low-passed in the inertial frame.
        let mut acc_filter = self.acc_filter.clone();
        acc_filter.turn(&dq);
        if norm3(&acc_now) >= 0.25 * p.gravity {
            acc_filter.step(&acc_now);
        }
        let an = norm3(&acc_filter.y);
        if an >= 0.25 * p.gravity {
            let excess = (an - p.gravity) / p.acc_reject;
            let kappa = 1.0 / (p.acc_noise * p.acc_noise) / (1.0 + excess * excess);
            let b = scale3(&acc_filter.y, 1.0 / an);
            f.update_precision(&observation_exponent(&b, &UP, kappa))?;
        }

        // 4. Magnetometer: heading only, with disturbance rejection, low-passed as the
        // accelerometer (disturbed samples are not fed to the filter).
        let mut mag_ref = self.mag.clone();
        let mut mag_filter = self.mag_filter.clone();
        let mut heading_observed = false;
        let mut mag_undisturbed = false;
        if let Some(mf) = mag_filter.as_mut() {
            mf.turn(&dq);
        }
        if let Some(m) = mag_now.as_ref() {
            let q = f.mode4();
            if let Some(kappa) = self.magnetic_weight(&q, m, &mut mag_ref) {
                mag_undisturbed = true;
                let mf =
                    mag_filter.get_or_insert_with(|| InertialLowPass::new(c.mag, c.mag_warmup, m));
                mf.step(m);
                let mw = q4::rotate(&q, &mf.y);
                let h = (mw[0] * mw[0] + mw[1] * mw[1]).sqrt();
                if h > 1e-3 * norm3(&mf.y) {
                    // δ rotates the horizontal field onto north (Rz(δ) (sin δ, cos δ) = (0, 1)).
                    let delta = mw[0].atan2(mw[1]);
                    let rz = [(0.5 * delta).cos(), 0.0, 0.0, (0.5 * delta).sin()];
                    let q_m = q4::mul(&rz, &q);
                    f.update_precision(&heading_exponent(&q_m, kappa))?;
                    heading_observed = true;
                }
            }
        }

        // 5. Bias from the correction during motion (integral feedback).
        if p.bias_time > 0.0 && rest_timer < p.rest_time {
            let q_post = f.mode4();
            let corr = if heading_observed {
                q4::to_rotation_vector(&q4::mul(&q4::conj(&q_prior), &q_post))
            } else {
                // Without a heading observation the mode may slide along the unobserved
                // rotation about the vertical (nearly equal concentrations): keep only the tilt
                // correction, which such a slide leaves unchanged (body frame, small angles).
                let up_prior = q4::rotate_inverse(&q_prior, &UP);
                let up_post = q4::rotate_inverse(&q_post, &UP);
                cross3(&up_post, &up_prior)
            };
            for i in 0..3 {
                bias[i] -= corr[i] / p.bias_time;
            }
        }
        for b in bias.iter_mut() {
            *b = b.clamp(-p.bias_max, p.bias_max);
        }

        self.filter = Some(filter);
        self.bias = bias;
        self.gyr_lp = gyr_lp;
        self.acc_lp = acc_lp;
        self.rest_timer = rest_timer;
        self.mag = mag_ref;
        self.acc_filter = acc_filter;
        self.mag_filter = mag_filter;
        // the latency estimate works on the raw samples (infallible: after every fallible step)
        self.latency
            .push(&dq, if mag_undisturbed { mag } else { None });
        self.samples += 1;
        Ok(())
    }

    /// The heading concentration for this magnetometer sample, or `None` when the field is
    /// disturbed; updates the disturbance tracking in `r`.
    fn magnetic_weight(&self, q: &[f64; 4], m: &[f64; 3], r: &mut Option<MagRef>) -> Option<f64> {
        let p = &self.params;
        let norm = norm3(m);
        let up_b = q4::rotate_inverse(q, &UP);
        let dip = (dot3(m, &up_b) / norm).clamp(-1.0, 1.0).asin();
        let reference = r.get_or_insert(MagRef {
            norm,
            dip,
            cand_norm: norm,
            cand_dip: dip,
            cand_time: 0.0,
        });
        let dt = p.sample_time;
        let disturbed = (norm - reference.norm).abs() > p.mag_norm_tol * reference.norm
            || (dip - reference.dip).abs() > p.mag_dip_tol;
        if !disturbed {
            let k = self.coeffs.mag_ref;
            reference.norm += k * (norm - reference.norm);
            reference.dip += k * (dip - reference.dip);
            reference.cand_norm = norm;
            reference.cand_dip = dip;
            reference.cand_time = 0.0;
            return Some(1.0 / (p.mag_noise * p.mag_noise));
        }
        // A steady disturbance: follow the candidate; accept it once it has held long enough.
        let steady = (norm - reference.cand_norm).abs() <= p.mag_norm_tol * reference.cand_norm
            && (dip - reference.cand_dip).abs() <= p.mag_dip_tol;
        if steady {
            let k = self.coeffs.candidate;
            reference.cand_norm += k * (norm - reference.cand_norm);
            reference.cand_dip += k * (dip - reference.cand_dip);
            reference.cand_time += dt;
            if reference.cand_time >= p.mag_new_time {
                reference.norm = reference.cand_norm;
                reference.dip = reference.cand_dip;
                reference.cand_time = 0.0;
            }
        } else {
            reference.cand_norm = norm;
            reference.cand_dip = dip;
            reference.cand_time = 0.0;
        }
        None
    }

    /// The first sample: tilt from `acc`, heading from `mag` (uniform without it).
    fn initialize(&mut self, gyr: &[f64; 3], acc: &[f64; 3], mag: Option<&[f64; 3]>) -> Result<()> {
        let p = self.params;
        let acc_raw = acc;
        // the latency compensation of `update`, with the rate of this sample
        let w = scale3(
            &[
                gyr[0] - self.bias[0],
                gyr[1] - self.bias[1],
                gyr[2] - self.bias[2],
            ],
            p.sample_time,
        );
        let acc = &turn_forward(acc, &w, self.coeffs.acc_lead);
        let mag_now = mag.map(|m| turn_forward(m, &w, self.coeffs.mag_lead));
        let mag = mag_now.as_ref();
        let an = norm3(acc);
        if an < 0.25 * p.gravity {
            return Err(Error::InvalidArgument(format!(
                "the first sample must show gravity: |acc| = {an} < gravity/4 (free fall or \
                 no data); the AHRS starts from a sample with a usable accelerometer"
            )));
        }
        let up_b = scale3(acc, 1.0 / an);
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
        if !given {
            f.core4_mut()?
                .update_precision(&observation_exponent(&up_b, &UP, kappa))?;
        }
        let mut mag_ref = None;
        if let Some(m) = mag {
            let east_b = cross3(m, &up_b);
            let en = norm3(&east_b);
            if en > 1e-3 * norm3(m) {
                let east_b = scale3(&east_b, 1.0 / en);
                let north_b = cross3(&up_b, &east_b);
                let q0 = q4::from_matrix(&[east_b, north_b, up_b]);
                if !given {
                    f.core4_mut()?
                        .update_precision(&heading_exponent(&q0, kappa))?;
                }
                let norm = norm3(m);
                let dip = (dot3(m, &up_b) / norm).clamp(-1.0, 1.0).asin();
                mag_ref = Some(MagRef {
                    norm,
                    dip,
                    cand_norm: norm,
                    cand_dip: dip,
                    cand_time: 0.0,
                });
            }
        }
        self.filter = Some(f);
        self.gyr_lp = *gyr;
        self.acc_lp = *acc_raw;
        self.acc_filter = InertialLowPass::new(self.coeffs.acc, self.coeffs.acc_warmup, acc);
        self.mag_filter =
            mag.map(|m| InertialLowPass::new(self.coeffs.mag, self.coeffs.mag_warmup, m));
        self.mag = mag_ref;
        self.samples = 1;
        Ok(())
    }

    /// Processes `gyr.len()` samples (`acc` the same length, `mag` too or `None`), writing the
    /// quaternion after each into `quat` (and, if given, the total angular spread into
    /// `spread`, see [`Ahrs::update_spread`]). Stops at the first refused sample: the samples
    /// before it are processed and their outputs written, the refused one changes nothing; the
    /// error names the index.
    pub fn update_batch(
        &mut self,
        gyr: &[[f64; 3]],
        acc: &[[f64; 3]],
        mag: Option<&[[f64; 3]]>,
        quat: &mut [[f64; 4]],
        mut spread: Option<&mut [f64]>,
    ) -> Result<()> {
        let n = gyr.len();
        let lengths_ok = acc.len() == n
            && quat.len() == n
            && mag.is_none_or(|m| m.len() == n)
            && spread.as_ref().is_none_or(|s| s.len() == n);
        if !lengths_ok {
            return Err(Error::InvalidDimension(
                "batch arrays must all have the same number of samples".into(),
            ));
        }
        for k in 0..n {
            let m = mag.map(|m| &m[k]);
            match spread.as_deref_mut() {
                Some(s) => {
                    s[k] = self
                        .update_spread(&gyr[k], &acc[k], m)
                        .map_err(|e| prefix(e, k))?
                }
                None => self.update(&gyr[k], &acc[k], m).map_err(|e| prefix(e, k))?,
            }
            quat[k] = self.quaternion();
        }
        Ok(())
    }

    /// [`Ahrs::update`] followed by the total angular spread (radians) of the new state, as one
    /// step: if the spread cannot be evaluated, the sample is refused and nothing changes.
    pub fn update_spread(
        &mut self,
        gyr: &[f64; 3],
        acc: &[f64; 3],
        mag: Option<&[f64; 3]>,
    ) -> Result<f64> {
        let mut next = self.clone();
        next.update(gyr, acc, mag)?;
        let mut out = [0.0; 4];
        next.angular_spread(&mut out)?;
        *self = next;
        Ok(out[3])
    }
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
