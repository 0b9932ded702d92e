//! One sample after the first: the per-sensor steps in the order of the module documentation,
//! and the correction at the end of each correction period.

use crate::error::Result;
use crate::filter::Core;

use super::correction;
use super::lowpass::Coeffs;
use super::params::AhrsParams;
use super::state::SampleState;

/// One sample after the first on the working copies, `h` seconds after the previous one: the
/// per-sensor steps in the order of the module documentation. Returns the gyroscope increment
/// and whether the field sample was used.
#[allow(clippy::too_many_arguments)]
pub(super) fn step(
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
pub(super) fn correction_due(p: &AhrsParams, c: &Coeffs, period: f64) -> bool {
    period >= c.correct_time - 0.5 * p.sample_time
}
