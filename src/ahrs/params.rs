//! The AHRS parameters: their meaning, units, the tuned defaults and their validation.

use super::bias::SCALE_MAX;
use crate::error::{Error, Result};

/// The default `gyro_scale_std` (see [`AhrsParams::gyro_scale_std`]).
const GYRO_SCALE_STD: f64 = 0.001;

/// The smallest sampling period (s) the AHRS accepts.
pub const MIN_SAMPLE_TIME: f64 = 1e-6;

/// The largest sampling period (s) the AHRS accepts (`BINGHAM_AHRS_MAX_SAMPLE_TIME` in C): the
/// sample rate must be at least 1 Hz. The AHRS integrates the gyroscope between samples, which
/// needs many samples per second (IMUs run at 50 Hz to a few kHz); a `sample_time` above 1 s is
/// almost always a rate in Hz passed where the period in seconds is expected, and is refused
/// with a message saying so. `bingham_ahrs_params_from_rate()` in C (`AhrsParams::from_rate` in
/// Rust) takes the rate instead.
pub const MAX_SAMPLE_TIME: f64 = 1.0;

/// The largest time step (s) of one sample (`BINGHAM_AHRS_MAX_STEP_TIME` in C): a gap up to 10 s
/// is predicted through (the gyroscope's last rate held, the spread widened by what that
/// cannot know); a longer one is refused, as it is more likely a timestamp error (ms for s, a
/// clock reset) than a stream that resumed.
pub const MAX_STEP_TIME: f64 = 10.0;

/// The smallest process noise per step (rad) the AHRS accepts (`gyro_noise·√sample_time`): below
/// it the state's concentrations could grow past what the moment matching resolves.
pub const MIN_STEP_NOISE: f64 = 1e-6;

/// The largest sensor latency (s) the AHRS accepts for `mag_latency` and `acc_latency`
/// (`BINGHAM_AHRS_MAX_LATENCY` in C). The compensation turns a sample by the current rate
/// times the latency (a constant-rate extrapolation), which only holds over a fraction of the
/// motion's time scale; real offsets between the channels of an IMU are milliseconds to a few
/// tens of milliseconds. The bound also refuses a latency given in milliseconds instead of
/// seconds.
pub const MAX_LATENCY: f64 = 0.5;

/// The value of [`AhrsParams::mag_latency`] that compensates the AHRS's online estimate of
/// the magnetometer's latency (`BINGHAM_AHRS_LATENCY_ESTIMATE` in C; the default).
pub const LATENCY_ESTIMATE: f64 = -1.0;

/// Parameters of the AHRS (`bingham_ahrs_params` in C, `AhrsParams` in Rust). The defaults —
/// `bingham_ahrs_params_default()` / `bingham_ahrs_params_from_rate()` in C,
/// `AhrsParams::new(sample_time)` / `AhrsParams::from_rate(hz)` in Rust — are one set
/// for all recordings and sample rates, tuned on the nine BROAD trials and a simulated IMU
/// suite; docs/guide.md ("The defaults and why") gives the mechanism behind each value. Angles in radians,
/// times in seconds. Fill it with the defaults, then change fields if needed.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AhrsParams {
    /// Sampling period in seconds, the period, not the rate: 0.01 for 100 Hz. From 1e-6 to 1
    /// (`BINGHAM_AHRS_MIN_SAMPLE_TIME` to `BINGHAM_AHRS_MAX_SAMPLE_TIME`).
    pub sample_time: f64,
    /// Orientation process noise in rad/√s: the prediction adds isotropic rotation noise of
    /// variance `gyro_noise²` per second (the gyroscope's noise and model error; the bias's
    /// uncertainty is added separately, see `bias_std`).
    pub gyro_noise: f64,
    /// Angular standard deviation (rad) of the low-passed accelerometer direction as a
    /// measurement of "up". Its errors (linear accelerations that have not averaged out) are
    /// correlated over `acc_tau`, so it is worth `1/(acc_noise²·acc_tau)` rad⁻² of tilt
    /// precision per second, whatever the sample rate.
    pub acc_noise: f64,
    /// Linear-acceleration rejection scale in m/s²: `κ` is divided by
    /// `1 + ((|ā| − gravity)/acc_reject)²`, `ā` the low-passed accelerometer.
    pub acc_reject: f64,
    /// Time constant (s) of the accelerometer's low-pass filter in the gyroscope-integrated
    /// (quasi-inertial) frame: linear accelerations average out there, gravity does not.
    pub acc_tau: f64,
    /// Time constant (s) of the magnetometer's low-pass filter in the same frame.
    pub mag_tau: f64,
    /// Magnitude of gravity in m/s².
    pub gravity: f64,
    /// Angular standard deviation (rad) of the low-passed field's heading as a measurement of
    /// the heading; worth `1/(mag_noise²·mag_tau)` rad⁻² of heading precision per second in a
    /// homogeneous field, divided by `1 + 2·V_h/mag_noise²` where the field's direction is
    /// measured to vary by `V_h` (rad²) as the sensor moves (the local field's deviation,
    /// correlated over `mag_tau`, is an error of the heading reference).
    pub mag_noise: f64,
    /// Relative tolerance on the magnetic field's norm before a sample counts as disturbed.
    pub mag_norm_tol: f64,
    /// Tolerance (rad) on the field's dip angle before a sample counts as disturbed.
    pub mag_dip_tol: f64,
    /// Time constant (s) with which the reference norm and dip follow undisturbed samples.
    pub mag_ref_time: f64,
    /// A disturbance whose norm and dip stay steady this long (s) becomes the new reference.
    pub mag_new_time: f64,
    /// Forgetting time (s) of the gyroscope-bias estimate: the bias is modelled as a random
    /// walk whose variance grows by `bias_std²` per `bias_time`, so older evidence about it
    /// counts less. `0` disables the estimation in motion (the bias is then learned at rest
    /// only; its uncertainty still widens the orientation's spread).
    pub bias_time: f64,
    /// Largest gyroscope bias (rad/s) per axis the estimate may reach.
    pub bias_max: f64,
    /// Time (s) the sensor must be still before the bias is taken from the gyroscope. The
    /// gyroscope's samples of a still phase then measure the bias (their mean) and the
    /// gyroscope's noise (their spread), weighed against the bias's uncertainty in a Kalman
    /// step; the phase's first half second and its last (the motion's edges, which the rest
    /// test sees late) are left out.
    pub rest_time: f64,
    /// Rest threshold on the gyroscope's deviation from its low-pass value (rad/s).
    pub rest_gyro: f64,
    /// Rest threshold on the accelerometer's deviation from its low-pass value (m/s²).
    pub rest_acc: f64,
    /// Angular standard deviation (rad) of the initial tilt and heading.
    pub init_std: f64,
    /// Latency (s, 0 to 0.5 = `BINGHAM_AHRS_MAX_LATENCY`) of the magnetometer behind the
    /// gyroscope: magnetometer sample k shows the field of the time `t_k − mag_latency`. Each
    /// field sample is turned forward by the bias-corrected rate of its sample times the
    /// latency (in the sensor frame `m ← exp(−[ω]× mag_latency) m`: the rotation by the
    /// rotation vector `−ω·mag_latency`) before the disturbance test and the low-pass filter.
    /// `LATENCY_ESTIMATE` (−1, `BINGHAM_AHRS_LATENCY_ESTIMATE` in C; the default): compensate
    /// the AHRS's own online estimate (`bingham_ahrs_mag_latency_estimate()` in C,
    /// `Ahrs::mag_latency_estimate` in Rust), none until it exists. `0`: no compensation. The
    /// time of gyroscope sample k is taken as its interval (t_{k−1}, t_k], the interval over
    /// which the prediction turns the state with it.
    pub mag_latency: f64,
    /// Latency (s, 0 to 0.5 = `BINGHAM_AHRS_MAX_LATENCY`) of the accelerometer behind the
    /// gyroscope, compensated as `mag_latency`: each sample is turned forward by the rate times
    /// the latency before the low-pass filter. Default 0: no compensation.
    pub acc_latency: f64,
    /// Initial standard deviation (rad/s, per axis) of the gyroscope bias: the Kalman filter of
    /// the bias starts from 0 with this uncertainty, which sets how fast a bias is learned
    /// from the corrections during motion, and how much an unknown bias widens the
    /// orientation's spread.
    pub bias_std: f64,
    /// Process noise (√s) per rad/s of rotation rate: the orientation's noise variance grows by
    /// `(gyro_scale_noise·|ω|)²` per second on top of `gyro_noise²` (scale-factor and
    /// axis-misalignment errors, and residual latency, turn into angle errors in proportion
    /// to the rate).
    pub gyro_scale_noise: f64,
    /// Initial standard deviation (relative, per axis, 0 to 0.05) of the gyroscope's scale
    /// error: the gyroscope reads `(1 + s_i)` times the rate about its axis `i` (plus the
    /// bias), and the Kalman filter of the bias estimates `s` with it from the same
    /// corrections (module `bias`; `Ahrs::gyro_scale`), starting from 0 with this
    /// uncertainty and holding it constant (no random walk: a scale error is a property of
    /// the sensor's calibration). A rate-proportional heading drift (a fast spin while the
    /// magnetometer is rejected) is then taken out of the rate instead of absorbed by the
    /// bias. `0` disables the estimation (the scale error is then only in the process noise,
    /// `gyro_scale_noise`).
    pub gyro_scale_std: f64,
}

impl AhrsParams {
    /// The default (tuned) parameters for the sampling period `sample_time` (s; 0.01 for
    /// 100 Hz). Not validated here: [`AhrsParams::validate`] (called by `Ahrs::new`) checks it;
    /// [`AhrsParams::from_rate`] builds and checks them from the rate in Hz.
    pub fn new(sample_time: f64) -> AhrsParams {
        AhrsParams {
            sample_time,
            gyro_noise: 0.008,
            acc_noise: 0.0099,
            acc_reject: 1.0,
            acc_tau: 1.5,
            mag_tau: 3.0,
            gravity: 9.81,
            mag_noise: 0.0104,
            mag_norm_tol: 0.1,
            mag_dip_tol: 10f64.to_radians(),
            mag_ref_time: 20.0,
            mag_new_time: 20.0,
            bias_time: 100.0,
            bias_max: 2f64.to_radians(),
            rest_time: 1.5,
            rest_gyro: 2f64.to_radians(),
            rest_acc: 0.5,
            init_std: 0.1,
            mag_latency: LATENCY_ESTIMATE,
            acc_latency: 0.0,
            bias_std: 0.5f64.to_radians(),
            gyro_scale_noise: 0.004,
            gyro_scale_std: GYRO_SCALE_STD,
        }
    }

    /// The default (tuned) parameters for the sample rate `hz` (samples per second): those of
    /// [`AhrsParams::new`]`(1.0 / hz)`, validated (`bingham_ahrs_params_from_rate()` in C).
    ///
    /// Errors: [`Error::InvalidArgument`] if `hz` is not finite or not > 0, below 1 Hz
    /// (`1 / MAX_SAMPLE_TIME`: a period above [`MAX_SAMPLE_TIME`]) or above 1 MHz
    /// (`1 / MIN_SAMPLE_TIME`: a period below [`MIN_SAMPLE_TIME`]).
    pub fn from_rate(hz: f64) -> Result<AhrsParams> {
        if !(hz.is_finite() && hz > 0.0) {
            return Err(Error::InvalidArgument(format!(
                "the AHRS sample rate `hz` must be finite and > 0 Hz, got {hz}"
            )));
        }
        let sample_time = 1.0 / hz;
        if sample_time > MAX_SAMPLE_TIME {
            return Err(Error::InvalidArgument(format!(
                "the AHRS sample rate `hz` = {hz} Hz is below {} Hz (a period above \
                 {MAX_SAMPLE_TIME} s, the largest accepted): the AHRS integrates the gyroscope \
                 and needs at least one sample per second",
                1.0 / MAX_SAMPLE_TIME
            )));
        }
        if sample_time < MIN_SAMPLE_TIME {
            return Err(Error::InvalidArgument(format!(
                "the AHRS sample rate `hz` = {hz} Hz is above {} Hz (a period below \
                 {MIN_SAMPLE_TIME:e} s, the smallest accepted)",
                1.0 / MIN_SAMPLE_TIME
            )));
        }
        let params = AhrsParams::new(sample_time);
        params.validate()?;
        Ok(params)
    }

    /// Checks every field (finite; periods, noises and thresholds positive; `bias_time ≥ 0`;
    /// `sample_time` within [`MIN_SAMPLE_TIME`, `MAX_SAMPLE_TIME`]; the process noise per step
    /// at least [`MIN_STEP_NOISE`]; `mag_latency` and `acc_latency` within 0 to
    /// [`MAX_LATENCY`], `mag_latency` also [`LATENCY_ESTIMATE`]). A `sample_time` above
    /// [`MAX_SAMPLE_TIME`] (1 s) is refused as a likely rate in Hz: the message asks "did you
    /// pass a rate in Hz?" and gives the period to pass instead.
    pub fn validate(&self) -> Result<()> {
        let positive = [
            ("sample_time", self.sample_time),
            ("gyro_noise", self.gyro_noise),
            ("acc_noise", self.acc_noise),
            ("acc_reject", self.acc_reject),
            ("acc_tau", self.acc_tau),
            ("mag_tau", self.mag_tau),
            ("gravity", self.gravity),
            ("mag_noise", self.mag_noise),
            ("mag_norm_tol", self.mag_norm_tol),
            ("mag_dip_tol", self.mag_dip_tol),
            ("mag_ref_time", self.mag_ref_time),
            ("mag_new_time", self.mag_new_time),
            ("bias_max", self.bias_max),
            ("rest_time", self.rest_time),
            ("rest_gyro", self.rest_gyro),
            ("rest_acc", self.rest_acc),
            ("init_std", self.init_std),
            ("bias_std", self.bias_std),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidArgument(format!(
                    "AHRS parameter `{name}` must be finite and > 0, got {v}"
                )));
            }
        }
        if self.sample_time > MAX_SAMPLE_TIME {
            let hz = self.sample_time;
            return Err(Error::InvalidArgument(format!(
                "AHRS parameter `sample_time` = {hz} s is above {MAX_SAMPLE_TIME} s (the \
                 largest period accepted): did you pass a rate in Hz? `sample_time` is the period in \
                 seconds (for {hz} Hz pass {}), or build the parameters from the rate with \
                 AhrsParams::from_rate({hz}) (bingham_ahrs_params_from_rate({hz}, &p) in C)",
                1.0 / hz
            )));
        }
        if self.sample_time < MIN_SAMPLE_TIME {
            return Err(Error::InvalidArgument(format!(
                "AHRS parameter `sample_time` must lie in [{MIN_SAMPLE_TIME:e}, \
                 {MAX_SAMPLE_TIME}] s, got {}",
                self.sample_time
            )));
        }
        let step = self.gyro_noise * self.sample_time.sqrt();
        if step < MIN_STEP_NOISE {
            return Err(Error::InvalidArgument(format!(
                "AHRS parameters `gyro_noise`·√`sample_time` = {step:e} rad (the process noise per \
                 step) must be at least {MIN_STEP_NOISE:e} rad"
            )));
        }
        if !(self.bias_time.is_finite() && self.bias_time >= 0.0) {
            return Err(Error::InvalidArgument(format!(
                "AHRS parameter `bias_time` must be finite and >= 0, got {}",
                self.bias_time
            )));
        }
        if !(self.gyro_scale_std.is_finite() && (0.0..=SCALE_MAX).contains(&self.gyro_scale_std)) {
            return Err(Error::InvalidArgument(format!(
                "AHRS parameter `gyro_scale_std` must lie in [0, {SCALE_MAX}], got {}",
                self.gyro_scale_std
            )));
        }
        if !(self.gyro_scale_noise.is_finite() && self.gyro_scale_noise >= 0.0) {
            return Err(Error::InvalidArgument(format!(
                "AHRS parameter `gyro_scale_noise` must be finite and >= 0, got {}",
                self.gyro_scale_noise
            )));
        }
        for (name, v) in [
            ("mag_latency", self.mag_latency),
            ("acc_latency", self.acc_latency),
        ] {
            let auto = name == "mag_latency" && v == LATENCY_ESTIMATE;
            if !(auto || (0.0..=MAX_LATENCY).contains(&v)) {
                return Err(Error::InvalidArgument(format!(
                    "AHRS parameter `{name}` must lie in [0, {MAX_LATENCY}] s{}, got {v}",
                    if name == "mag_latency" {
                        " or be LATENCY_ESTIMATE (-1: the online estimate)"
                    } else {
                        ""
                    }
                )));
            }
        }
        Ok(())
    }
}
