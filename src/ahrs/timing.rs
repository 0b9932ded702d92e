//! Time in the AHRS: each sample's own time step, gaps in the gyroscope, and how much of the
//! current correction period each sensor's samples cover.
//!
//! - **A time step per sample.** A sample's interval `h` is the time since the previous sample
//!   (the nominal `sample_time`, or the caller's timestamps). The gyroscope's turn, the process
//!   noise, the bias's random walk and every first-order filter use `h`; the second-order
//!   low-pass filters (fixed-coefficient Butterworth filters) take the sample `round(h/dt)`
//!   times (a zero-order hold over dropped samples).
//! - **A gyroscope sample covers one nominal period.** When `h` exceeds 1.5 nominal periods
//!   (dropped packets), the rest of the interval, `h − dt`, is turned with the mean of the
//!   previous and the current bias-corrected rates, and its error — the rate's change over the
//!   interval, which nothing measured — is added to the process noise (see
//!   [`GyroHold::extrapolation_variance`]). A missing gyroscope sample (a NaN row) is a gap of
//!   the whole interval, turned with the last rate held.
//! - **Evidence only from samples.** The accelerometer's and magnetometer's evidence of a
//!   correction period is worth the time their usable samples cover in it (the low-passed
//!   averages carry the information of the samples that went into them; an average no sample
//!   has refreshed carries none that the state has not already used). A sensor whose samples
//!   have stopped gives no evidence, and the orientation's spread grows by the process noise;
//!   after a loss longer than the sensor's averaging time its average restarts from the next
//!   sample.

use super::vec3::norm3;

/// Time constant (s) of the running mean squares of the angular acceleration and of the rate
/// that size the error of a rate carried over a gap (the motion's own time scale).
const MOTION_TIME: f64 = 1.0;

/// The gyroscope's last rate and the motion's running statistics, for gaps.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct GyroHold {
    /// The last bias-corrected rate (rad/s, body frame of that sample); `None` before one.
    rate: Option<[f64; 3]>,
    /// Running mean square of the rate's change per second (rad²/s⁴).
    accel_ms: f64,
    /// Running mean square of the rate (rad²/s²).
    rate_ms: f64,
}

impl GyroHold {
    /// The last bias-corrected rate, or zero before the first.
    pub(super) fn rate(&self) -> [f64; 3] {
        self.rate.unwrap_or([0.0; 3])
    }

    /// The rate for an uncovered stretch before a sample of rate `now`: the mean of the last
    /// rate and `now` (the rate's linear interpolation, averaged over the stretch).
    pub(super) fn bridge(&self, now: &[f64; 3]) -> [f64; 3] {
        match self.rate {
            Some(r) => [
                0.5 * (r[0] + now[0]),
                0.5 * (r[1] + now[1]),
                0.5 * (r[2] + now[2]),
            ],
            None => *now,
        }
    }

    /// A gyroscope sample of bias-corrected rate `now` after an interval of `h` seconds.
    pub(super) fn push(&mut self, now: &[f64; 3], h: f64) {
        let a = (h / MOTION_TIME).min(1.0);
        if let Some(r) = self.rate {
            let d = norm3(&[now[0] - r[0], now[1] - r[1], now[2] - r[2]]) / h;
            self.accel_ms += a * (d * d - self.accel_ms);
        }
        let w = norm3(now);
        self.rate_ms += a * (w * w - self.rate_ms);
        self.rate = Some(*now);
    }

    /// The variance (rad² per axis) of the turn over `u` seconds that no gyroscope sample
    /// covered, the rate carried over it (`held`: the last rate; otherwise the mean of the two
    /// ends). The rate's change over the stretch is unknown: with the recent RMS angular
    /// acceleration `α`, a held rate errs by about `α u²/2`, an interpolated one by half that;
    /// never more than the turn the recent RMS rate makes in that time, `2·ω_rms·u` (the
    /// motion does not keep accelerating).
    pub(super) fn extrapolation_variance(&self, u: f64, held: bool) -> f64 {
        if u <= 0.0 {
            return 0.0;
        }
        let k = if held { 0.5 } else { 0.25 };
        let by_accel = k * self.accel_ms.sqrt() * u * u;
        let by_rate = 2.0 * self.rate_ms.sqrt() * u;
        let s = by_accel.min(by_rate);
        // each axis carries a third of the squared error of the turn vector
        s * s / 3.0
    }
}

/// How long each sensor has been missing and how much of the current correction period its
/// samples cover.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct SensorTimes {
    /// Seconds since the last usable sample of each sensor (0 right after one; counted from the
    /// AHRS's first sample for a sensor never seen).
    pub(super) gyr_missing: f64,
    pub(super) acc_missing: f64,
    pub(super) mag_missing: f64,
    /// Seconds of the current correction period, and those covered by usable accelerometer
    /// samples and by magnetometer samples the disturbance test let through.
    pub(super) period: f64,
    pub(super) acc_covered: f64,
    pub(super) mag_covered: f64,
}

impl SensorTimes {
    /// One sample of interval `h`: which sensors had a usable sample, and whether the field
    /// sample was used.
    pub(super) fn sample(&mut self, h: f64, gyr: bool, acc: bool, mag: bool, mag_used: bool) {
        let age = |missing: &mut f64, present: bool| {
            *missing = if present { 0.0 } else { *missing + h };
        };
        age(&mut self.gyr_missing, gyr);
        age(&mut self.acc_missing, acc);
        age(&mut self.mag_missing, mag);
        self.period += h;
        if acc {
            self.acc_covered += h;
        }
        if mag_used {
            self.mag_covered += h;
        }
    }

    /// The period's sums, taken out at a correction: `(period, acc covered, mag covered)`.
    pub(super) fn take_period(&mut self) -> (f64, f64, f64) {
        let out = (self.period, self.acc_covered, self.mag_covered);
        self.period = 0.0;
        self.acc_covered = 0.0;
        self.mag_covered = 0.0;
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_held_rate_errs_by_the_angular_acceleration_over_half_the_squared_gap() {
        let mut g = GyroHold::default();
        // a rate ramping at 2 rad/s² about x, sampled at 100 Hz for 30 s
        for k in 0..3000 {
            g.push(&[2.0 * 0.01 * f64::from(k), 0.0, 0.0], 0.01);
        }
        // α = 2 rad/s² (the running mean square has settled to 4 within e^−30)
        let u = 0.1;
        let v = g.extrapolation_variance(u, true);
        let expected = 0.5 * 2.0 * u * u;
        assert!(((3.0 * v).sqrt() - expected).abs() < 1e-3 * expected, "{v}");
        // an interpolated stretch: half the error
        let vi = g.extrapolation_variance(u, false);
        assert!(((3.0 * vi).sqrt() - 0.5 * expected).abs() < 1e-3 * expected);
        // a long gap: capped by the turn at twice the RMS rate
        let long = g.extrapolation_variance(100.0, true);
        assert!((3.0 * long).sqrt() <= 2.0 * g.rate_ms.sqrt() * 100.0 * (1.0 + 1e-12));
        assert_eq!(g.extrapolation_variance(0.0, true), 0.0);
    }

    #[test]
    fn coverage_counts_only_the_sensors_samples() {
        let mut t = SensorTimes::default();
        t.sample(0.01, true, true, true, true);
        t.sample(0.01, true, false, true, false);
        t.sample(0.02, false, true, false, false);
        let (p, a, m) = t.take_period();
        assert!((p - 0.04).abs() < 1e-15 && (a - 0.03).abs() < 1e-15 && m == 0.01);
        assert!((t.gyr_missing - 0.02).abs() < 1e-15 && t.acc_missing == 0.0);
        assert!((t.mag_missing - 0.02).abs() < 1e-15);
        assert_eq!(t.take_period(), (0.0, 0.0, 0.0));
    }
}
