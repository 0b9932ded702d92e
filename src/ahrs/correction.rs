//! The correction (step 5 of the module `ahrs`, every [`CORRECTION_PERIOD`]): the prior (the
//! state composed with the accumulated process noise), one exact Bayes product with the
//! sensors' evidence, and the bias learned from the move of the mode.
//!
//! The sensors' evidence comes as a list of [`Evidence`] items (module `evidence`), one per
//! sensor, `None` for a sensor without evidence this period; this file reads the list, not the
//! sensors. The order of the steps is in the module `ahrs`.
//!
//! [`CORRECTION_PERIOD`]: super::lowpass::CORRECTION_PERIOD

use nalgebra::{Matrix3, Matrix4, Vector3, Vector4};

use super::bias::{evidence_precision, noise_moment, pinv, precision, BiasState};
use super::evidence::{present, Evidence};
use super::params::AhrsParams;
use super::vec3::{cross3, UP};
use crate::error::Result;
use crate::filter::Core;
use crate::quaternion::q4;

/// A correction whose innovation exceeds this many of its predicted standard deviations (the
/// health readout's normalized innovation per degree of freedom above its square) teaches the
/// bias nothing (module `bias`: the coupling models small errors).
const OUTLIER: f64 = 5.0;

/// The largest move of the mode (rad) at a correction that teaches the bias: the coupling's
/// first-order model (module `bias`) errs by the square of the angle, 1 % at 0.1 rad. A
/// correction moves the mode by 1e-4 to 1e-2 rad in tracking; larger moves are recoveries
/// (a wrong start, after a gap), not bias.
const LINEAR_MOVE: f64 = 0.1;

/// The prior of a correction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Prior {
    /// The prior's precision of the orientation error at its mode (rad⁻², body frame).
    pub(super) lam: Matrix3<f64>,
    /// The prior's mode.
    pub(super) mode: [f64; 4],
}

/// The result of a correction's Bayes product.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Update {
    /// The prior it started from.
    pub(super) prior: Prior,
    /// The posterior's mode.
    pub(super) mode: [f64; 4],
    /// `omega(z)` of the posterior.
    pub(super) omega: [f64; 4],
    /// The posterior covariance in the prior's frame (the pseudo-inverse of the prior's
    /// precision plus the evidence's, both at the prior mode).
    sigma: Matrix3<f64>,
}

/// Step 5.1: the state `core` (with `omega`, its `omega(z)`) composed with the process noise
/// accumulated since the last correction (taken out of `bias`): the Bingham with the moment of
/// `exp(θ/2)`, `θ ~ N(0, Q)`, then moment matching.
pub(super) fn prior(core: &mut Core<4>, omega: &[f64; 4], bias: &mut BiasState) -> Result<Prior> {
    let noise = bias.take_pending();
    core.compose_moment(&Vector4::from(*omega), &noise_moment(&noise))?;
    let lam = {
        let (m, z) = core.params();
        precision(m, z)
    };
    Ok(Prior {
        lam,
        mode: core.mode(),
    })
}

/// Step 5.5: one exact Bayes product of the prior (`core`, `prior`) with every sensor's
/// evidence (none: the state is left as it is).
pub(super) fn update(
    core: &mut Core<4>,
    prior: &Prior,
    evidence: &[Option<Evidence>],
) -> Result<Update> {
    let mut exponent = Matrix4::zeros();
    let mut observed = false;
    for e in present(evidence) {
        exponent += e.exponent;
        observed = true;
    }
    if observed {
        core.update_precision(&exponent)?;
    }
    let omega = core.omega()?;
    // The posterior covariance in the prior's frame (the prior's precision plus the
    // evidence's, both at the prior mode: the Gaussian conditioning of the bias needs the two
    // in one frame; nearly unobserved directions of the two states need not line up).
    let sigma = pinv(&(prior.lam + evidence_precision(&prior.mode, &exponent)));
    Ok(Update {
        prior: *prior,
        mode: core.mode(),
        omega: [omega[0], omega[1], omega[2], omega[3]],
        sigma,
    })
}

/// Step 5.6: the bias learned from the move of the mode of `update` (module `bias`), unless
/// the sensor is at rest (`at_rest`: the gyroscope measures the bias better then) or the state
/// is recovering from a large error: a gyroscope gap in the period (`gap`), the largest
/// normalized innovation per degree of freedom of the health readout (`innovation`) beyond
/// [`OUTLIER`]², or a move or an innovation of the `evidence` beyond [`LINEAR_MOVE`]. A
/// recovery also decouples the bias from the orientation.
pub(super) fn learn_bias(
    p: &AhrsParams,
    bias: &mut BiasState,
    update: &Update,
    evidence: &[Option<Evidence>],
    innovation: f64,
    gap: bool,
    at_rest: bool,
) {
    let (q_prior, q_post) = (&update.prior.mode, &update.mode);
    // The bias from the move of the mode. Without a heading observation the mode may slide
    // about the vertical (nearly equal concentrations: the heading is uniform, its mode
    // arbitrary), so only the tilt part of the move counts, taken from the body-frame "up" of
    // the two modes, which a slide leaves unchanged: `up_post ≈ up_prior + up_prior × μ`, so
    // `μ_⊥ = up_post × up_prior`.
    let mu = if present(evidence).any(|e| e.innovation.observes_heading()) {
        Vector3::from(q4::to_rotation_vector(&q4::mul(&q4::conj(q_prior), q_post)))
    } else {
        let up_prior = q4::rotate_inverse(q_prior, &UP);
        let up_post = q4::rotate_inverse(q_post, &UP);
        Vector3::from(cross3(&up_post, &up_prior))
    };
    // At rest the gyroscope measures the bias directly (module `rest`), far better than the
    // corrections can: they do not teach it then. Nor after a gyroscope gap in the period: the
    // move of the mode then answers the carried rate's error, not the bias.
    // Nor from an innovation the prior calls impossible (beyond OUTLIER standard deviations:
    // a start far off, a wrong state set): the coupling is a linear-Gaussian model of small
    // errors, and read literally the moves that such an innovation makes are a bias of degrees
    // per second.
    // An innovation or a move larger than LINEAR_MOVE is beyond that model too, whatever the
    // prior's spread: the state is recovering from a large error, not tracking a bias.
    let largest_angle = present(evidence).fold(0.0f64, |a, e| a.max(e.innovation.angle()));
    let recovering = gap
        || innovation > OUTLIER * OUTLIER
        || mu.norm() > LINEAR_MOVE
        || largest_angle > LINEAR_MOVE;
    let learn = p.bias_time > 0.0 && !at_rest && !recovering;
    bias.correct(&update.prior.lam, &mu, &update.sigma, learn);
    if recovering {
        // what the recovery taught the orientation is not evidence about the bias: the
        // coupling starts afresh, so that the next correction does not read the recovery's
        // moves as the effect of a bias
        bias.decouple();
    }
    bias.clip(p.bias_max);
}
