//! The AHRS's filter coefficients and the second-order low-pass filter of a vector fixed in
//! the quasi-inertial frame (turned with every gyroscope increment).

use super::params::AhrsParams;
use super::vec3::scale3;
use crate::quaternion::q4;

/// First-order low-pass coefficient for time constant `tau` at period `dt`.
pub(super) fn lp_coeff(dt: f64, tau: f64) -> f64 {
    1.0 - (-dt / tau).exp()
}

/// The number of samples in one time constant `tau` (at least 1, at most `u32::MAX`).
pub(super) fn warmup(dt: f64, tau: f64) -> u32 {
    (tau / dt).ceil().clamp(1.0, f64::from(u32::MAX)) as u32
}

/// Time constant (s) of the low-pass filters of the rest detection.
pub(super) const REST_FILTER_TIME: f64 = 0.5;

/// Time constant (s) of the band limit of the samples the rest test compares with their
/// low-pass values (a 50 Hz bandwidth, whatever the sample rate).
pub(super) const REST_NOISE_TIME: f64 = 0.02;

/// Time constant (s) with which a disturbed field's candidate reference follows it.
pub(super) const CANDIDATE_TIME: f64 = 1.0;

/// Time constant (s) of the low-pass filter of the norm and dip the magnetic disturbance test
/// sees (module `magnetic`).
pub(super) const MAG_TEST_TIME: f64 = 0.015;

/// The filter coefficients that follow from the parameters (computed once).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Coeffs {
    pub(super) rest_filter: f64,
    /// The coefficient of the band limit of the rest test's samples.
    pub(super) rest_noise: f64,
    pub(super) mag_ref: f64,
    pub(super) candidate: f64,
    /// The low-pass coefficient of the norm and dip the disturbance test sees.
    pub(super) mag_test: f64,
    pub(super) acc: [f64; 5],
    pub(super) mag: [f64; 5],
    /// Warm-up lengths (samples) of the accelerometer's and magnetometer's low-pass filters.
    pub(super) acc_warmup: u32,
    pub(super) mag_warmup: u32,
    /// The latencies in sample times (`acc_latency / sample_time`, `mag_latency / sample_time`):
    /// the factor from a gyroscope increment to the compensating turn.
    pub(super) acc_lead: f64,
    pub(super) mag_lead: f64,
    /// Samples per correction step (`CORRECTION_PERIOD / sample_time`, rounded, at least 1),
    /// and the time they span (s).
    pub(super) correct_every: u32,
    pub(super) correct_time: f64,
}

/// The period (s) of the AHRS's correction steps (the Bingham composition with the process
/// noise accumulated since the last step, and the Bayes update with the accelerometer and
/// magnetometer evidence accumulated over it). The orientation follows the gyroscope at every
/// sample, the sensors' averages and the disturbance test run at every sample, and a period's
/// evidence is worth the time its samples cover: the period only sets how often the evidence
/// is applied. The corrections act on time scales of a second and longer (the averages'
/// `acc_tau` and `mag_tau`, the bias), so the period adds a delay of half a period to
/// them. 50 ms is a quarter of the shortest period measured to cost accuracy (the table in
/// docs/accuracy/ahrs.md, "The correction period"); a correction costs several times a
/// sample's prediction (docs/speed.md, "round five"), so the period sets the cost per sample at
/// the rates where it spans few samples (every third sample at 50 Hz).
pub const CORRECTION_PERIOD: f64 = 0.05;

impl Coeffs {
    pub(super) fn new(p: &AhrsParams) -> Coeffs {
        let dt = p.sample_time;
        Coeffs {
            rest_filter: lp_coeff(dt, REST_FILTER_TIME),
            rest_noise: lp_coeff(dt, REST_NOISE_TIME),
            mag_ref: lp_coeff(dt, p.mag_ref_time),
            candidate: lp_coeff(dt, CANDIDATE_TIME),
            mag_test: lp_coeff(dt, MAG_TEST_TIME),
            acc: butterworth(dt, p.acc_tau),
            mag: butterworth(dt, p.mag_tau),
            acc_warmup: warmup(dt, p.acc_tau),
            mag_warmup: warmup(dt, p.mag_tau),
            acc_lead: p.acc_latency / dt,
            mag_lead: p.mag_latency.max(0.0) / dt,
            correct_every: correct_every(dt),
            correct_time: f64::from(correct_every(dt)) * dt,
        }
    }
}

impl Coeffs {
    /// The coefficients for one step of `h` seconds: the first-order filters' coefficients for
    /// `h`, the rest (the second-order filters, which take a long step as `round(h/dt)` nominal
    /// samples; the latency leads; the correction period) as for the nominal period. The
    /// nominal coefficients themselves when `h` is the nominal period.
    pub(super) fn at_step(&self, p: &AhrsParams, h: f64) -> Coeffs {
        if h == p.sample_time {
            return *self;
        }
        Coeffs {
            rest_filter: lp_coeff(h, REST_FILTER_TIME),
            rest_noise: lp_coeff(h, REST_NOISE_TIME),
            mag_ref: lp_coeff(h, p.mag_ref_time),
            candidate: lp_coeff(h, CANDIDATE_TIME),
            mag_test: lp_coeff(h, MAG_TEST_TIME),
            ..*self
        }
    }
}

fn correct_every(dt: f64) -> u32 {
    (CORRECTION_PERIOD / dt)
        .round()
        .clamp(1.0, f64::from(u32::MAX)) as u32
}

/// Coefficients `(b0, b1, b2, a1, a2)` of a second-order Butterworth low-pass filter with time
/// constant `tau` (cut-off `√2/(2πτ)`) at period `dt` (bilinear transform).
pub(super) fn butterworth(dt: f64, tau: f64) -> [f64; 5] {
    let fc = std::f64::consts::SQRT_2 / (2.0 * std::f64::consts::PI * tau);
    let c = (std::f64::consts::PI * fc * dt).tan();
    let d = c * c + std::f64::consts::SQRT_2 * c + 1.0;
    let b0 = c * c / d;
    [
        b0,
        2.0 * b0,
        b0,
        2.0 * (c * c - 1.0) / d,
        (1.0 - std::f64::consts::SQRT_2 * c + c * c) / d,
    ]
}

/// A second-order low-pass filter of a vector that is fixed in the quasi-inertial frame: its
/// output and states are expressed in the sensor frame and turned with every gyroscope
/// increment, so the filter averages in the frame where gravity and the magnetic field stand
/// still. It starts as a running mean over its first `τ/dt` samples (so the first output is not
/// one noisy sample held for a time constant) and continues from that mean in steady state.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct InertialLowPass {
    pub(super) coeff: [f64; 5],
    pub(super) y: [f64; 3],
    pub(super) s0: [f64; 3],
    pub(super) s1: [f64; 3],
    /// Samples averaged so far while warming up, and how many the warm-up takes.
    pub(super) count: u32,
    pub(super) warmup: u32,
}

impl InertialLowPass {
    /// The filter started at the sample `x`; `warmup` samples are averaged before the
    /// second-order filter takes over.
    pub(super) fn new(coeff: [f64; 5], warmup: u32, x: &[f64; 3]) -> InertialLowPass {
        let mut f = InertialLowPass {
            coeff,
            y: *x,
            s0: [0.0; 3],
            s1: [0.0; 3],
            count: 1,
            warmup,
        };
        if f.count >= f.warmup {
            f.settle();
        }
        f
    }

    /// Puts the second-order filter in steady state at the current output.
    pub(super) fn settle(&mut self) {
        let [b0, _, b2, _, a2] = self.coeff;
        self.s0 = scale3(&self.y, 1.0 - b0);
        self.s1 = scale3(&self.y, b2 - a2);
    }

    /// Expresses the state in the next sensor frame (`dq` the body-frame increment).
    pub(super) fn turn(&mut self, dq: &[f64; 4]) {
        self.y = q4::rotate_inverse(dq, &self.y);
        self.s0 = q4::rotate_inverse(dq, &self.s0);
        self.s1 = q4::rotate_inverse(dq, &self.s1);
    }

    /// One sample: the running mean while warming up, then direct form II transposed.
    pub(super) fn step(&mut self, x: &[f64; 3]) {
        if self.count < self.warmup {
            self.count += 1;
            let k = 1.0 / f64::from(self.count);
            for (y, &xi) in self.y.iter_mut().zip(x) {
                *y += k * (xi - *y);
            }
            if self.count == self.warmup {
                self.settle();
            }
            return;
        }
        let [b0, b1, b2, a1, a2] = self.coeff;
        for (i, &xi) in x.iter().enumerate() {
            let y = b0 * xi + self.s0[i];
            self.s0[i] = b1 * xi - a1 * y + self.s1[i];
            self.s1[i] = b2 * xi - a2 * y;
            self.y[i] = y;
        }
    }
}
