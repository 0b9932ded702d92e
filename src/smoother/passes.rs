//! The two passes of the AHRS over the recording: the forward pass, and the backward pass over
//! the reversed recording from the forward pass's handoff, which hands its predicted states over
//! in chunks.

use std::sync::atomic::{AtomicBool, Ordering};

use nalgebra::{Matrix4, Vector4};

use super::handoff::{latency_ready, Handoff};
use super::store::{pack9, Forward, ForwardBias, Pass};
use super::types::{Fusion, SmoothInput, SmoothOptions};
use crate::ahrs::{Ahrs, AhrsParams};
use crate::error::Result;
use crate::quaternion::q4;

/// Whether a row is a sample (every value finite, the norm representable).
pub(super) fn usable(v: &[f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite()) && (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).is_finite()
}

/// The row at the fractional index `k + s` (linear interpolation; a non-finite neighbour or an
/// index past the end gives NaN: no sample).
fn shifted(rows: &[[f64; 3]], k: usize, s: f64) -> [f64; 3] {
    if s == 0.0 {
        return rows[k];
    }
    let i = s.floor();
    let f = s - i;
    let i0 = k as f64 + i;
    let nan = [f64::NAN; 3];
    if i0 < 0.0 || i0 + 1.0 > rows.len() as f64 {
        return nan;
    }
    let i0 = i0 as usize;
    let a = rows[i0];
    if f == 0.0 {
        return a;
    }
    let Some(b) = rows.get(i0 + 1) else {
        return nan;
    };
    std::array::from_fn(|j| a[j] + f * (b[j] - a[j]))
}

/// The exponent `M diag(z) Mᵀ` of an AHRS's Bingham state.
fn exponent(a: &Ahrs) -> Result<Matrix4<f64>> {
    let mut m = [0.0; 16];
    let mut z = [0.0; 4];
    a.state_into(&mut m, &mut z)?;
    let m = Matrix4::from_row_slice(&m);
    Ok(m * Matrix4::from_diagonal(&Vector4::from(z)) * m.transpose())
}

/// The time step of sample `k` (`t[k] − t[k−1]`; the nominal period without timestamps and
/// for the first sample), within a millionth of the nominal period taken as it (as
/// [`Ahrs::update_dt`] does, so that the backward pass's turns are those of the untimed call).
fn step_time(time: Option<&[f64]>, k: usize, nominal: f64) -> f64 {
    match time {
        Some(t) if k > 0 => {
            let dt = t[k] - t[k - 1];
            if (dt - nominal).abs() <= 1e-6 * nominal {
                nominal
            } else {
                dt
            }
        }
        _ => nominal,
    }
}

/// The forward pass: the online AHRS over the recording, its states into `store`, the handoff
/// taken after sample `at`.
pub(super) fn forward_pass(
    params: &AhrsParams,
    options: &SmoothOptions,
    input: &SmoothInput<'_>,
    has_mag: bool,
    at: usize,
    store: &mut Pass,
    mut handoff: impl FnMut(Handoff),
) -> Result<()> {
    let nominal = params.sample_time;
    let mut ahrs = Ahrs::new(params)?;
    let exact = options.fusion == Fusion::Bingham;
    let n = input.gyr.len();
    let stride = ((1.0 / nominal).ceil() as usize).max(1);
    let mut handed = false;
    for k in 0..n {
        let m = input.mag.map(|m| &m[k]);
        let dt = step_time(input.time, k, nominal);
        ahrs.update_dt(dt, &input.gyr[k], &input.acc[k], m)
            .map_err(|e| e.prefixed(&format!("sample {k}")))?;
        store.states.push(Forward {
            q: ahrs.quaternion(),
            c: pack9(&ahrs.filter_covariance()?),
        });
        if exact {
            store.exponents.push(exponent(&ahrs)?);
        }
        if let Some(b) = store.bias.as_mut() {
            b.push(ForwardBias {
                b: ahrs.gyro_bias().map(|x| x as f32),
                p: pack9(&ahrs.gyro_bias_covariance()),
            });
        }
        // the handoff: at `at` or, when the latency is the forward pass's estimate, at the
        // first whole second after it with an estimate; at the last sample at the latest
        if !handed
            && k >= at
            && (k + 1 == n || ((k - at) % stride == 0 && latency_ready(&ahrs, params)))
        {
            handed = true;
            handoff(Handoff::take(&ahrs, params, options, has_mag)?);
        }
    }
    Ok(())
}

/// The backward pass (module documentation) from the forward pass's handoff: its predicted
/// state at every sample `k < start`, `start` the sample it starts at (the last with a usable
/// accelerometer), which it returns, handed to `emit` in [`Chunk`]s of [`CHUNK`] samples (the
/// last one shorter), from the highest samples down. Stops (returning `Ok(0)`) when `abort` is
/// set.
pub(super) fn backward_pass(
    params: &AhrsParams,
    options: &SmoothOptions,
    input: &SmoothInput<'_>,
    handoff: &Handoff,
    want_bias: bool,
    abort: &AtomicBool,
    mut emit: impl FnMut(Chunk),
) -> Result<usize> {
    let n = input.gyr.len();
    let nominal = params.sample_time;
    let exact = options.fusion == Fusion::Bingham;
    let mut store = Pass::new(CHUNK.min(n), want_bias, exact)?;
    // the backward pass's magnetometer: the forward's latency as a shift of the samples
    let mag_shift = handoff.mag_latency / nominal;
    let acc_shift = params.acc_latency / nominal;
    let mut bp = *params;
    bp.mag_latency = 0.0;
    bp.acc_latency = 0.0;
    // the backward pass's gyroscope: the forward pass's bias estimate taken out, so that the
    // backward bias estimate (of what remains) starts near zero instead of at the bias; its
    // stated bias variance still starts at bias_std² (conservative: nothing counted twice)
    let b_end = handoff.bias;
    let mut back = Ahrs::new(&bp)?;
    // its own latency estimate is not used (`mag_latency` 0) and not read
    back.without_latency_estimate();
    match &handoff.state {
        // without a magnetometer the heading's convention is the forward pass's start: carry
        // it over
        Some((m, z)) => back.set_state(m, z)?,
        None => {
            if options.uniform_start {
                // uniform: the backward pass holds the future's evidence only
                let eye = [
                    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
                ];
                back.set_state(&eye, &[0.0; 4])?;
            }
            // else: the AHRS's own start from its first sample (the recording's last):
            // evidence of that sample only, which no forward posterior before it holds
        }
    }
    let mut start = None;
    for k in (0..n).rev() {
        if k % 4096 == 0 && abort.load(Ordering::Relaxed) {
            return Ok(0);
        }
        // the backward pass's sample for sample k: the turn from k+1 to k, k's own sensors;
        // over a longer interval (dropped samples) the recorded sample k+1 covers the end of
        // the interval, and the rest is bridged with the mean of the rates of k+1 and k, as
        // the forward pass bridges it (module `gyro`)
        let (g, dt) = if k + 1 < n {
            (input.gyr[k + 1], step_time(input.time, k + 1, nominal))
        } else {
            (input.gyr[k], nominal)
        };
        let g = [b_end[0] - g[0], b_end[1] - g[1], b_end[2] - g[2]];
        let far = input.gyr[k];
        let far = [b_end[0] - far[0], b_end[1] - far[1], b_end[2] - far[2]];
        if start.is_some() {
            // the predicted state at k: the state after k+1 turned by the gyroscope to k
            let b = back.gyro_bias();
            let qk = back.quaternion();
            let qb = back.reversed_prediction(dt, &g, &far);
            store.states.push(Forward {
                q: qb,
                c: pack9(&back.filter_covariance()?),
            });
            if exact {
                // the backward exponent turned to k: p(q) = p_{k+1}(q ⊗ dq*)
                let dq = q4::conj(&q4::mul(&q4::conj(&qk), &qb));
                let r = Matrix4::from_fn(|i, j| {
                    let mut e = [0.0; 4];
                    e[j] = 1.0;
                    q4::mul(&e, &dq)[i]
                });
                store.exponents.push(r.transpose() * exponent(&back)? * r);
            }
            if let Some(bs) = store.bias.as_mut() {
                // the backward estimate of the original gyroscope's bias
                let bb: [f64; 3] = std::array::from_fn(|j| b_end[j] - b[j]);
                bs.push(ForwardBias {
                    b: bb.map(|x| x as f32),
                    p: pack9(&back.gyro_bias_covariance()),
                });
            }
            if store.states.len() == CHUNK || k == 0 {
                let next = Pass::new(CHUNK.min(k), want_bias, exact)?;
                emit(Chunk {
                    lo: k,
                    pass: std::mem::replace(&mut store, next),
                });
            }
        }
        let acc = shifted(input.acc, k, acc_shift);
        let mag = input.mag.map(|m| shifted(m, k, mag_shift));
        if start.is_none() {
            // the backward pass starts at the last sample with a usable accelerometer
            let a2 = acc.iter().map(|x| x * x).sum::<f64>();
            if !(a2.is_finite() && a2.sqrt() >= 0.25 * params.gravity) {
                continue;
            }
        }
        back.update_reversed(dt, &g, &far, &acc, mag.as_ref())
            .map_err(|e| e.prefixed(&format!("backward pass, sample {k}")))?;
        if start.is_none() {
            // the field's reference (norm and dip, what the disturbance test compares with)
            // from the forward pass, not from the last sample, which may lie in a disturbance
            // (a magnet attached for the rest of the recording), with the field's variation the
            // forward pass measured (which widens the heading evidence from the start on)
            if let Some(r) = &handoff.mag_reference {
                back.set_mag_reference(r);
            }
            start = Some(k);
        }
    }
    Ok(start.unwrap_or(0))
}

/// The samples per [`Chunk`] of the backward pass.
pub(super) const CHUNK: usize = 4096;

/// A run of consecutive samples of the backward pass: its predicted states (and bias,
/// exponents) of the samples `lo … lo + len − 1`, stored from the highest down. The backward
/// pass hands them over as it goes, so that with the passes concurrent the forward pass's
/// thread forms the product of each while the backward pass goes on.
pub(super) struct Chunk {
    pub(super) lo: usize,
    pub(super) pass: Pass,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shifted_rows_interpolate_and_end_in_nan() {
        let rows = [[0.0, 0.0, 0.0], [1.0, 2.0, 3.0], [2.0, 4.0, 6.0]];
        assert_eq!(shifted(&rows, 0, 0.5), [0.5, 1.0, 1.5]);
        assert_eq!(shifted(&rows, 1, 1.0), [2.0, 4.0, 6.0]);
        assert!(shifted(&rows, 2, 0.5)[0].is_nan());
        assert!(shifted(&rows, 0, -0.5)[0].is_nan());
        assert_eq!(shifted(&rows, 1, 0.0), rows[1]);
    }
}
