//! The offline smoother: the orientation at every sample of a whole recording, from the samples
//! before it and after it, with its uncertainty (issue 36; the derivation is in
//! docs/design.md, "The offline smoother").
//!
//! `p(x_k | all samples) ∝ p(x_k | samples ≤ k) · p(samples > k | x_k)`. The first factor is
//! the online AHRS's posterior (the forward pass, [`Ahrs`] over the recording as it is). The
//! second is the likelihood of the rest of the recording, which the same AHRS computes when it
//! runs over the reversed recording (the backward pass): the body turns by `−ω` in reversed
//! time, so the backward pass's gyroscope sample for sample `k` is `−gyr[k+1]` (the forward
//! pass turns by `gyr[k]` between samples `k−1` and `k`), its time step `t[k+1] − t[k]`, its
//! gyroscope bias the negative of the forward's. It starts as the online AHRS does, from its
//! first sample (the recording's last), whose evidence no forward posterior before it holds;
//! its magnetic reference (the field's norm and dip, against which it tests for disturbances,
//! and the field's variation over the motion, which widens the heading evidence) is the forward
//! pass's (at the handoff, below), not its first sample's, which may lie in a disturbance;
//! at sample `k` the smoother takes its *predicted* state: the state after sample `k+1` turned
//! by the gyroscope to sample `k`, before sample `k`'s accelerometer and magnetometer, which
//! the forward posterior holds already. Its gyroscope has the forward pass's bias estimate
//! (at the handoff) taken out, so that its bias estimate starts near the truth (its stated bias
//! variance still starts at `bias_std²`).
//!
//! The product is formed in the tangent space of the forward mode with the stated (calibrated)
//! covariances of both passes before the heading's coupling to the tilt (the errors each
//! filter models; [`Ahrs::orientation_covariance`] without its last step): with `δ` the rotation vector
//! (world frame) from the forward mode to the backward one, `C_s = (C_f⁻¹ + C_b⁻¹)⁻¹`, the
//! smoothed mode `exp(C_f (C_f + C_b)⁻¹ δ / 2) ⊗ q_f` and its covariance `C_s` (computed as
//! `C_f − C_f (C_f + C_b)⁻¹ C_f`, which stays finite when the backward pass knows nothing).
//! A backward state farther from the forward one than the two covariances allow (squared
//! Mahalanobis distance above [`DEFAULT_GATE`]) has its covariance widened until it is not.
//! The gyroscope bias is smoothed the same way from the two passes' estimates and covariances.
//! The smoothed covariance output then takes the coupling (module `ahrs::uncertainty`) of the
//! forward pass at the handoff (its reference's dip, its tilt reference's steady part, which
//! takes the whole coupling, the rest the filter's share): the tilt error the two passes share —
//! an accelerometer's offset tilts both alike — leaves the heading by `tan(dip)` times it in
//! the smoothed estimate as in each pass, but taken into the product it would move the heading
//! by the passes' tilt difference, which is not what their heading errors differ by.
//!
//! Approximations (docs/design.md): the AHRS low-passes the accelerometer (`acc_tau`) and the
//! magnetometer (`mag_tau`) and corrects every 50 ms, so a pass's state holds sample `k`'s own
//! measurement only through its share of an average; the backward predicted state holds none
//! of samples `≤ k`, the forward posterior none of samples `> k`: nothing is counted twice. The
//! magnetometer's latency (lagging the gyroscope) is a lead in reversed time: the backward pass
//! reads the field samples shifted by the forward pass's latency (the parameter, or the
//! forward's estimate at the handoff), interpolated linearly. Without any magnetometer sample the
//! heading is only defined by the forward pass's start, so the backward pass starts from the
//! forward pass's final state (its heading convention; the tilt of the last samples is then
//! counted twice, over the last `acc_tau` only).
//!
//! Threads: the backward pass needs three things of the forward pass — its bias estimate, its
//! magnetic reference and its latency estimate — which it takes at the **handoff**: the
//! forward pass's values after [`HANDOFF_TIME`] (30 s) of the recording or, when the latency
//! is the forward pass's estimate (the default), after the first whole second from then on at
//! which that estimate exists. From the handoff on the two passes run concurrently, the
//! backward one on a second thread, which hands its states over in chunks of 4096 samples; the
//! forward pass's thread, which ends first (its pass started earlier), forms the product at
//! each chunk while the backward pass goes on. Passes run in turn form the product afterwards,
//! its two halves on two threads. A call uses at most two threads (the caller's and one it
//! starts and joins before it returns). The product at a sample is a function of the two
//! passes' states there alone, and the handoff is a function of the recording alone (its
//! length, sample time and samples), never of the scheduling: the result is the same bit for
//! bit whether the second thread runs, is slow, or cannot be started (then one thread does
//! both, in turn).
//! Recordings of at most [`HANDOFF_TIME`] + [`PARALLEL_TIME`], recordings without a
//! magnetometer (whose backward pass starts from the forward pass's final state) and those in
//! which the forward pass has no latency estimate before its end take the forward pass's
//! final values and run the passes one after the other. The function holds no shared state:
//! concurrent calls are independent (each with its own threads).
//!
//! Memory: each pass's mode (4 `f64`) and stated covariance (6 `f32`) per sample,
//! [`BYTES_PER_SAMPLE`] bytes; with the smoothed bias requested, each pass's estimate and
//! covariance too ([`BIAS_BYTES_PER_SAMPLE`] more). Nothing else grows with the recording.
//!
//! [`Ahrs`]: crate::ahrs::Ahrs
//! [`Ahrs::orientation_covariance`]: crate::ahrs::Ahrs::orientation_covariance

mod fusion;
mod handoff;
mod passes;
mod store;
#[cfg(test)]
mod tests;
mod threads;
mod types;

pub use handoff::{HANDOFF_TIME, PARALLEL_TIME};
pub use store::{BIAS_BYTES_PER_SAMPLE, BYTES_PER_SAMPLE};
pub use types::{BiasMode, Fusion, SmoothInput, SmoothOptions, SmoothOutput, DEFAULT_GATE};

use store::{room, unpack, Forward};
use threads::run;

use crate::ahrs::AhrsParams;
use crate::error::{Error, Result};

/// The smoothed orientation of a whole recording (module documentation), with the default
/// [`SmoothOptions`]. Validation as [`Ahrs::update_batch_timed`] (the parameters, the
/// lengths, finite strictly increasing timestamps, the first sample with a usable
/// accelerometer, every sample's time step and turn); on an error the outputs are untouched.
/// `n = 0` is no error (nothing to write).
///
/// Allocates [`BYTES_PER_SAMPLE`] bytes per sample (plus [`BIAS_BYTES_PER_SAMPLE`] with the
/// bias output), freed before it returns. Uses at most two threads (the caller's and one it
/// joins before it returns; module documentation, "Threads"); the result does not depend on
/// them. Thread-safe: no shared state.
///
/// [`Ahrs::update_batch_timed`]: crate::ahrs::Ahrs::update_batch_timed
pub fn smooth(params: &AhrsParams, input: &SmoothInput<'_>, out: SmoothOutput<'_>) -> Result<()> {
    smooth_with(params, &SmoothOptions::default(), input, out)
}

/// [`smooth`] with options.
pub fn smooth_with(
    params: &AhrsParams,
    options: &SmoothOptions,
    input: &SmoothInput<'_>,
    out: SmoothOutput<'_>,
) -> Result<()> {
    params.validate()?;
    let n = input.gyr.len();
    let lengths_ok = input.acc.len() == n
        && input.time.is_none_or(|t| t.len() == n)
        && input.mag.is_none_or(|m| m.len() == n)
        && out.quat.len() == n
        && out.spread.as_ref().is_none_or(|s| s.len() == n)
        && out.bias.as_ref().is_none_or(|s| s.len() == n)
        && out.covariance.as_ref().is_none_or(|s| s.len() == n);
    if !lengths_ok {
        return Err(Error::InvalidDimension(
            "the smoother's arrays must all have the same number of samples".into(),
        ));
    }
    if let Some(t) = input.time {
        for k in 0..n {
            let ok = t[k].is_finite() && (k == 0 || t[k] > t[k - 1]);
            if !ok {
                return Err(Error::InvalidArgument(format!(
                    "sample {k}: timestamp {} s is not finite or not after the previous one \
                     (timestamps must increase strictly)",
                    t[k]
                )));
            }
        }
    }
    if n == 0 {
        return Ok(());
    }
    let want_bias = out.bias.is_some() || options.bias == BiasMode::SecondPass;
    let (mut fwd, mut bias, mut k) = run(params, options, input, want_bias, true)?;
    if options.bias == BiasMode::SecondPass {
        // the gyroscope minus the smoothed bias, the passes again: the bias estimates then
        // start at the smoothed bias instead of zero
        let first = bias.unwrap_or_default();
        let mut gyr2 = room(n, "samples")?;
        gyr2.extend(
            input
                .gyr
                .iter()
                .zip(&first)
                .map(|(g, b)| std::array::from_fn::<f64, 3, _>(|j| g[j] - f64::from(b.b[j]))),
        );
        let input2 = SmoothInput {
            gyr: &gyr2,
            ..*input
        };
        drop(fwd);
        let (fwd2, bias2, k2) = run(params, options, &input2, true, true)?;
        fwd = fwd2;
        k = k2;
        let mut second = bias2.unwrap_or_default();
        // the bias output: the first passes' smoothed bias plus the second's residual
        for (b, f) in second.iter_mut().zip(&first) {
            for j in 0..3 {
                b.b[j] += f.b[j];
            }
        }
        bias = Some(second);
    }
    let bias = bias.unwrap_or_default();
    // success: the outputs
    for (o, f) in out.quat.iter_mut().zip(&fwd) {
        *o = f.q;
    }
    // the smoothed covariance with the heading's coupling to the tilt (module documentation)
    let stated = |f: &Forward| k.apply(&unpack(&f.c));
    if let Some(s) = out.spread {
        for (o, f) in s.iter_mut().zip(&fwd) {
            *o = stated(f).trace().max(0.0).sqrt();
        }
    }
    if let Some(c) = out.covariance {
        for (o, f) in c.iter_mut().zip(&fwd) {
            let m = stated(f);
            for i in 0..3 {
                for j in 0..3 {
                    o[3 * i + j] = m[(i, j)];
                }
            }
        }
    }
    if let Some(b) = out.bias {
        for (o, f) in b.iter_mut().zip(&bias) {
            *o = f.b.map(f64::from);
        }
    }
    Ok(())
}
