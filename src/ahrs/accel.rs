//! The accelerometer in the AHRS: its average in the gyroscope-integrated frame (per sample)
//! and, at a correction, the tilt evidence of that average.
//!
//! - **Per sample** (step 3 of the module `ahrs`): the low-pass filter (second-order
//!   Butterworth, `acc_tau`; module `lowpass`) keeps its state in the sensor frame turned by
//!   every gyroscope increment, so it averages in the gyroscope-integrated frame, where gravity
//!   stands still and linear accelerations average out. A sample is first turned forward by
//!   its latency (`acc_latency`, module `latency`); one with `|acc| < gravity/4` (free fall) is
//!   skipped. A long step is taken as several nominal samples of the same value.
//! - **Restarts** (module `timing`): after a loss of the accelerometer longer than `acc_tau`,
//!   or after a gyroscope gap that turned the average by more than `acc_noise`, the average
//!   starts again from the next sample.
//! - **At a correction** (step 5.2): the average's direction `ā/|ā|` is a vector observation
//!   of "up" with `κ_a = T_acc/(acc_noise²·acc_tau) / (1 + ((|ā| − gravity)/acc_reject)²)`,
//!   `T_acc` the time the period's usable samples cover: evidence per second of a measurement
//!   whose errors are correlated over `acc_tau`, lowered while the average's norm is off
//!   gravity (linear acceleration). Its innovation is the angle between the predicted and the
//!   observed "up" (2 degrees of freedom), with the variance
//!   `acc_noise²·(1 + ((|ā| − gravity)/acc_reject)²)`. The average's norm against gravity is
//!   the health readout's gravity score.

use super::evidence::{Evidence, Innovation};
use super::gyro::Turn;
use super::latency::turn_forward;
use super::lowpass::{Coeffs, InertialLowPass};
use super::params::AhrsParams;
use super::vec3::{norm3, scale3, UP};
use crate::observation::observation_exponent;
use crate::quaternion::q4;

/// The accelerometer's state in the AHRS.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Accel {
    /// The low-passed specific force in the gyroscope-integrated frame.
    filter: InertialLowPass,
    /// Whether the average waits to be restarted by the next sample: a gyroscope gap turned it
    /// with a carried rate by more than the accelerometer's own noise.
    restart: bool,
}

impl Accel {
    /// An accelerometer whose average starts from the sample `acc` (coefficients of `c`).
    pub(super) fn new(c: &Coeffs, acc: &[f64; 3]) -> Accel {
        Accel {
            filter: InertialLowPass::new(c.acc, c.acc_warmup, acc),
            restart: false,
        }
    }

    /// Before the sample's other steps: a sample `acc` after a loss longer than `acc_tau`
    /// (`missing` seconds without a usable sample), or after a gap that turned the average,
    /// restarts the average from it (what the old one holds was turned by the gyroscope alone
    /// since).
    pub(super) fn restart_if_stale(
        &mut self,
        p: &AhrsParams,
        c: &Coeffs,
        missing: f64,
        acc: Option<&[f64; 3]>,
    ) {
        if let Some(a) = acc {
            if missing > p.acc_tau || self.restart {
                self.filter = InertialLowPass::new(c.acc, c.acc_warmup, a);
                self.restart = false;
            }
        }
    }

    /// A gyroscope gap has ended that turned the averages with a carried rate by the variance
    /// `turned` (rad², the turn vector's): beyond the accelerometer's noise, the average
    /// restarts at the next sample.
    pub(super) fn after_gap(&mut self, p: &AhrsParams, turned: f64) {
        self.restart |= turned > p.acc_noise * p.acc_noise;
    }

    /// One sample (step 3): the average turned by the gyroscope's increment, then fed with
    /// `acc` (turned forward by its latency; `repeat` nominal samples). Returns whether the
    /// sample was usable (present and not in free fall).
    pub(super) fn step(
        &mut self,
        p: &AhrsParams,
        c: &Coeffs,
        turn: &Turn,
        repeat: u32,
        acc: Option<&[f64; 3]>,
    ) -> bool {
        self.filter.turn(&turn.dq);
        let mut acc_used = false;
        if let Some(a) = acc {
            let a = turn_forward(a, &turn.w_lead, c.acc_lead);
            if norm3(&a) >= 0.25 * p.gravity {
                for _ in 0..repeat {
                    self.filter.step(&a);
                }
                acc_used = true;
            }
        }
        acc_used
    }

    /// The tilt evidence of a correction (step 5.2) whose usable samples covered `t_acc`
    /// seconds, with the prior's mode `q_prior`; `None` without samples in the period or an
    /// average too short to show gravity.
    pub(super) fn tilt_evidence(
        &self,
        p: &AhrsParams,
        t_acc: f64,
        q_prior: &[f64; 4],
    ) -> Option<Evidence> {
        let an = norm3(&self.filter.y);
        if t_acc > 0.0 && an >= 0.25 * p.gravity && an.is_finite() {
            let excess = (an - p.gravity) / p.acc_reject;
            let widen = 1.0 + excess * excess;
            let kappa = t_acc / (p.acc_noise * p.acc_noise * p.acc_tau) / widen;
            let up_b = scale3(&self.filter.y, 1.0 / an);
            Some(Evidence {
                exponent: observation_exponent(&up_b, &UP, kappa),
                innovation: Innovation::tilt(&q4::rotate_inverse(q_prior, &UP), &up_b),
                var: p.acc_noise * p.acc_noise * widen,
            })
        } else {
            None
        }
    }

    /// The average's deviation from gravity in units of `acc_reject` (the health readout's
    /// gravity score), for a correction whose usable samples covered `t_acc` seconds; `None`
    /// without samples in the period.
    pub(super) fn gravity_excess(&self, p: &AhrsParams, t_acc: f64) -> Option<f64> {
        let an = norm3(&self.filter.y);
        (t_acc > 0.0 && an.is_finite()).then(|| (an - p.gravity) / p.acc_reject)
    }
}
