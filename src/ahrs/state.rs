//! The state a sample of the AHRS changes besides the Bingham state: one part per sensor, the
//! gyroscope bias, the sensors' times and the health readout (module `ahrs`: changed in place by
//! the steps of a sample, a copy taken before it restored when the sample is refused).

use super::accel::Accel;
use super::bias::BiasState;
use super::gyro::Gyro;
use super::health::HealthState;
use super::lowpass::Coeffs;
use super::magnetic::Magnetic;
use super::params::AhrsParams;
use super::rest::Rest;
use super::timing::SensorTimes;
use super::uncertainty::Calibration;

/// The state a sample changes besides the Bingham state (small; changed in place, restored from
/// a copy when the sample is refused): one part per sensor, the bias, the times, the health readout.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct SampleState {
    /// The gyroscope bias's Kalman filter and the accumulated process noise (module `bias`).
    pub(super) bias: BiasState,
    /// The rest detection and the samples of the current still phase (module `rest`).
    pub(super) rest: Rest,
    /// The gyroscope's last rate, the motion's statistics and gaps (module `gyro`).
    pub(super) gyro: Gyro,
    /// The accelerometer's average (module `accel`).
    pub(super) accel: Accel,
    /// The magnetometer's reference, disturbance state and average (module `magnetic`).
    pub(super) mag: Magnetic,
    /// Each sensor's missing time and its coverage of the correction period.
    pub(super) times: SensorTimes,
    /// `omega(z)` of the Bingham state (cached for the next composition and the spread).
    pub(super) omega: [f64; 4],
    /// The running state of the health readout.
    pub(super) health: HealthState,
    /// The innovations' averages that scale the stated covariance (module `uncertainty`).
    pub(super) calib: Calibration,
}

impl SampleState {
    /// The state before the first sample, with the parameters `p` and their coefficients `c`.
    pub(super) fn new(p: &AhrsParams, c: &Coeffs) -> SampleState {
        SampleState {
            bias: BiasState::new(p.bias_std, p.gyro_scale_std),
            rest: Rest::default(),
            gyro: Gyro::default(),
            accel: Accel::new(c, &[0.0; 3]),
            mag: Magnetic::new(),
            times: SensorTimes::default(),
            omega: [0.25; 4],
            health: HealthState::default(),
            calib: Calibration::default(),
        }
    }
}
