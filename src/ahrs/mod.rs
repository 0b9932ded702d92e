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

mod accel;
mod batch;
mod bias;
mod correction;
mod estimator;
mod evidence;
mod gyro;
mod health;
mod latency;
mod lowpass;
mod magnetic;
mod params;
mod readouts;
mod rest;
mod state;
mod step;
mod timing;
mod uncertainty;
mod vec3;

pub use estimator::{Ahrs, MAX_TURN};
pub use health::{AhrsHealth, HEALTH_THRESHOLD, HEALTH_TIME};
pub use lowpass::CORRECTION_PERIOD;
pub(crate) use magnetic::MagReference;
pub use params::{
    AhrsParams, LATENCY_ESTIMATE, MAX_LATENCY, MAX_SAMPLE_TIME, MAX_STEP_TIME, MIN_SAMPLE_TIME,
    MIN_STEP_NOISE,
};
pub(crate) use uncertainty::StatedCoupling;
