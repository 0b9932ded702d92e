//! The gyroscope in the AHRS (step 2 of the module `ahrs`): the exact turn of the state by the
//! bias-corrected rate, the process noise accumulated, and gaps.
//!
//! - **The turn.** The state is turned by the body-frame increment of the rate with the bias
//!   and the scale error taken out, `q ← q ⊗ exp(ω̂·dt/2)`, `ω̂ = ω − b̂ − diag(ŝ) ω` (module
//!   `bias`).
//! - **The process noise** of the sample, `(gyro_noise² + (gyro_scale_noise·|ω − b̂|)²)·h`, and
//!   what the bias's uncertainty adds through its coupling (module `bias`), accumulated until
//!   the next correction; the bias's random walk, held over a rest (module `rest`).
//! - **Gaps** (module `timing`): a sample covers one nominal period; the rest of a longer
//!   interval is bridged with the mean of the last and this rate, a missing sample turned
//!   with the last rate, and what that cannot know added to the process noise. When a gap
//!   ends, the averages it turned by more than their noise restart (the sensors decide, from
//!   [`Turn::gap_ended`]).

use nalgebra::Matrix3;

use super::bias::BiasState;
use super::params::AhrsParams;
use super::rest::Rest;
use super::timing::GyroHold;
use super::vec3::{norm3, scale3};
use crate::filter::Core;
use crate::quaternion::q4;

/// The gyroscope's state in the AHRS besides the bias (module `bias`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct Gyro {
    /// The last rate and the motion's statistics, for gaps (module `timing`).
    hold: GyroHold,
    /// The variance (rad² per axis) the current gyroscope gap has added by carrying the rate.
    gap_var: f64,
    /// Whether a gap came in the current correction period (its correction teaches the bias
    /// nothing: the move of the mode answers the carried rate's error).
    pub(super) gap_in_period: bool,
    /// The variance (rad² per axis) that gaps and dropped samples have added and the
    /// corrections have not yet taken out: physical, so the stated covariance carries it
    /// unscaled (module `uncertainty`).
    pub(super) gap_stated: f64,
}

/// What a gyroscope step gives the other sensors' steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Turn {
    /// The body-frame increment the state was turned by (unit quaternion).
    pub(super) dq: [f64; 4],
    /// The turn the latency compensation extrapolates: the rate over one nominal period
    /// (rotation vector, rad).
    pub(super) w_lead: [f64; 3],
    /// The bias-corrected rate's norm (rad/s).
    pub(super) rate: f64,
    /// When a gap ended with this sample: the variance (rad², of the turn vector) by which
    /// the carried rate turned the averages over it.
    pub(super) gap_ended: Option<f64>,
}

impl Gyro {
    /// The increment of a sample `h` seconds after the previous one with the raw rate `gyr`
    /// (rad/s; `None`: a gap, the last rate held), the bias and scale error of `cal` taken out
    /// ([`BiasState::rate`]): what [`Gyro::step`]
    /// turns the state by. With `far` (a pass over reversed time, module `smoother`: the raw
    /// rate on the far side of the interval, the sample before it in recorded time) the
    /// sample's own period comes first and the rest of a longer interval is bridged with the
    /// mean of `gyr` and `far` (the recorded time's bridge, inverted); without it the bridge
    /// is the mean of the last and this rate and comes first. Returns the increment, the
    /// bias-corrected rate, the time the sample covered and whether the rate was held.
    fn increment(
        &self,
        dt: f64,
        cal: &BiasState,
        h: f64,
        gyr: Option<&[f64; 3]>,
        far: Option<&[f64; 3]>,
    ) -> ([f64; 4], [f64; 3], f64, bool) {
        // A sample covers one nominal period; the rest of a longer interval (dropped samples)
        // is bridged with the mean of the last and this rate, a missing sample with the last
        // rate (module `timing`).
        let (omega, bridged, held) = match gyr {
            Some(g) => {
                let omega = cal.rate(g);
                if h > 1.5 * dt {
                    let bridge = match far {
                        Some(f) if f.iter().all(|x| x.is_finite()) => {
                            let f = cal.rate(f);
                            std::array::from_fn(|j| 0.5 * (omega[j] + f[j]))
                        }
                        Some(_) => omega,
                        None => self.hold.bridge(&omega),
                    };
                    (omega, Some((bridge, h - dt)), false)
                } else {
                    (omega, None, false)
                }
            }
            None => (self.hold.rate(), None, true),
        };
        let covered = match (gyr.is_some(), bridged) {
            (false, _) => 0.0,
            (true, Some(_)) => dt,
            (true, None) => h,
        };
        let w = scale3(&omega, if held { h } else { covered });
        let mut dq = q4::from_rotation_vector(&w);
        if let Some((bridge, u)) = bridged {
            let r = q4::from_rotation_vector(&scale3(&bridge, u));
            // recorded time: the bridge, then the sample's own period; reversed: the
            // sample's own period (the last of the interval in recorded time) first
            dq = if far.is_some() {
                q4::mul(&dq, &r)
            } else {
                q4::mul(&r, &dq)
            };
        }
        (dq, omega, covered, held)
    }

    /// The increment [`Gyro::step`] would turn the state by for the same arguments, without
    /// changing anything (the smoother's backward prediction, module `smoother`).
    pub(super) fn preview(
        &self,
        p: &AhrsParams,
        cal: &BiasState,
        h: f64,
        gyr: Option<&[f64; 3]>,
        far: Option<&[f64; 3]>,
    ) -> [f64; 4] {
        self.increment(p.sample_time, cal, h, gyr, far).0
    }

    /// One sample `h` seconds after the previous one (step 2), `gyr` (rad/s; `None`: a gap,
    /// `missing` seconds since the last sample before this one; `far`: see
    /// [`Gyro::increment`]): turns `core`, accumulates the process noise and predicts the bias
    /// (`bias`; its random walk held over a rest of `rest`).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn step(
        &mut self,
        p: &AhrsParams,
        core: &mut Core<4>,
        bias: &mut BiasState,
        rest: &mut Rest,
        missing: f64,
        h: f64,
        gyr: Option<&[f64; 3]>,
        far: Option<&[f64; 3]>,
    ) -> Turn {
        let dt = p.sample_time;
        let (dq, omega, covered, held) = self.increment(dt, bias, h, gyr, far);
        let rate = norm3(&omega);
        core.rotate(&dq);
        // The carried rate's error grows with the whole stretch without a gyroscope sample, not
        // sample by sample: add what this step adds to the stretch's variance.
        let extra = if held {
            let gap = missing + h;
            self.hold.extrapolation_variance(gap, true)
                - self.hold.extrapolation_variance(gap - h, true)
        } else {
            self.hold.extrapolation_variance(h - covered, false)
        };
        let mut gap_ended = None;
        if held {
            self.gap_var += extra;
            self.gap_in_period = true;
        } else if self.gap_var > 0.0 {
            // the gap is over: the averages it turned by more than their noise restart
            gap_ended = Some(3.0 * self.gap_var);
            self.gap_var = 0.0;
        }
        if let Some(g) = gyr {
            self.hold.push(&bias.rate(g), h);
        }
        // the turn the latency compensation extrapolates: the rate over one nominal period
        let w_lead = scale3(&omega, dt);
        let scale = p.gyro_scale_noise * rate;
        // at most 1 rad² per sample: a wider noise is uniform for all purposes
        let q = ((p.gyro_noise * p.gyro_noise + scale * scale) * h + extra).min(1.0);
        self.gap_stated += extra;
        // the bias's random walk: variance per second
        let walk = if p.bias_time > 0.0 {
            p.bias_std * p.bias_std / p.bias_time
        } else {
            0.0
        };
        let mut drift = walk * h;
        // Over a rest the bias is one constant, which the rest's samples measure (module
        // `rest`): its random walk is held, and added when the rest ends as the variance of a
        // random walk's end about its mean over the phase (a third of the walk's variance over
        // the phase).
        if rest.timer >= p.rest_time {
            rest.held += h;
            drift = 0.0;
        } else if rest.held > 0.0 {
            drift += walk * rest.held / 3.0;
            rest.held = 0.0;
        }
        let r = q4::to_matrix(&dq);
        bias.predict(&Matrix3::from_fn(|i, j| r[i][j]), &omega, h, q, drift);
        // the estimate is clipped to ±bias_max: its variance need not grow beyond (2·bias_max)²
        bias.cap_bias(3.0 * 4.0 * p.bias_max * p.bias_max);
        Turn {
            dq,
            w_lead,
            rate,
            gap_ended,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over dropped samples the reversed increment (the inverted rate of the sample after the
    /// interval, `far` the inverted rate of the sample before it) is the exact inverse of the
    /// recorded time's increment: the smoother's backward pass retraces the forward turn.
    #[test]
    fn the_reversed_bridge_inverts_the_forward_one() {
        let dt = 0.01;
        let b = [0.01, -0.02, 0.005];
        let before = [0.7, -1.3, 2.1];
        let after = [1.9, 0.4, -0.8];
        let next = [-2.0, 1.0, 3.0];
        for h in [dt, 1.2 * dt, 2.0 * dt, 5.0 * dt] {
            // recorded time: the last rate is `before`, then the sample `after` h later
            let mut fwd = Gyro::default();
            fwd.hold
                .push(&std::array::from_fn(|j| before[j] - b[j]), dt);
            let mut cal = BiasState::new(0.0, 0.0);
            cal.b = b.into();
            let (dq_f, ..) = fwd.increment(dt, &cal, h, Some(&after), None);
            // reversed time: the last rate is the inverted `next` (the sample after `after`),
            // then the inverted `after` with `before` on the far side, inverted, bias
            // negated (the backward pass's rates are `b − gyr`)
            let inv = |v: &[f64; 3]| -> [f64; 3] { std::array::from_fn(|j| -v[j]) };
            let mut back = Gyro::default();
            back.hold.push(&inv(&next), dt);
            cal.b = inv(&b).into();
            let (dq_b, ..) = back.increment(dt, &cal, h, Some(&inv(&after)), Some(&inv(&before)));
            let id = q4::mul(&dq_f, &dq_b);
            assert!(
                (id[0].abs() - 1.0).abs() < 1e-15 && id[1..].iter().all(|x| x.abs() < 1e-15),
                "h = {h}: {id:?}"
            );
        }
    }
}
