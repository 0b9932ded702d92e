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

use std::sync::atomic::{AtomicBool, Ordering};

use nalgebra::{Matrix3, Matrix4, Vector3, Vector4};

use crate::ahrs::{Ahrs, AhrsParams, MagReference, StatedCoupling, LATENCY_ESTIMATE};
use crate::error::{Error, Result};
use crate::quaternion::q4;

/// The bytes the smoother allocates per sample, besides the caller's inputs and outputs: each
/// pass's mode as 4 `f64` and stated covariance as 6 `f32` (the backward pass keeps its own, so
/// that it can run while the forward pass does, module documentation "Threads").
pub const BYTES_PER_SAMPLE: usize = 2 * std::mem::size_of::<Forward>();

/// The bytes the smoother allocates per sample in addition to [`BYTES_PER_SAMPLE`] when the
/// smoothed gyroscope bias is requested (each pass's bias estimate as 3 `f32` and its
/// covariance as 6 `f32`).
pub const BIAS_BYTES_PER_SAMPLE: usize = 2 * std::mem::size_of::<ForwardBias>();

/// One recording: timestamps (optional), gyroscope, accelerometer and magnetometer samples.
#[derive(Debug, Clone, Copy)]
pub struct SmoothInput<'a> {
    /// The timestamp (s, strictly increasing, any origin) of each sample; `None`: uniformly
    /// spaced by [`AhrsParams::sample_time`].
    pub time: Option<&'a [f64]>,
    /// The gyroscope (rad/s), one row per sample; a non-finite row: no sample (a gap).
    pub gyr: &'a [[f64; 3]],
    /// The accelerometer (m/s²), the same length; a non-finite row: no sample.
    pub acc: &'a [[f64; 3]],
    /// The magnetometer (any unit), the same length, or `None`; a non-finite row: no sample.
    pub mag: Option<&'a [[f64; 3]]>,
}

/// Where the smoother writes, each one row per sample (the inputs' length).
#[derive(Debug)]
pub struct SmoothOutput<'a> {
    /// The smoothed orientation (sensor → world ENU, scalar first, `w ≥ 0`).
    pub quat: &'a mut [[f64; 4]],
    /// The total angular spread (rad) of the smoothed orientation: the square root of the
    /// trace of its covariance.
    pub spread: Option<&'a mut [f64]>,
    /// The smoothed gyroscope bias (rad/s, sensor frame).
    pub bias: Option<&'a mut [[f64; 3]]>,
    /// The covariance (rad², 3×3 row-major) of the smoothed orientation's error as a rotation
    /// vector in the world frame, as [`Ahrs::orientation_covariance`] defines it.
    pub covariance: Option<&'a mut [[f64; 9]]>,
}

/// How the bias is smoothed (docs/accuracy/ahrs.md, "The offline smoother", compares them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BiasMode {
    /// One forward and one backward pass; the bias output is the two estimates fused by their
    /// covariances.
    Fused,
    /// Then both passes again on the gyroscope minus the fused bias (twice the time).
    SecondPass,
}

/// The smoother's options besides the AHRS parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmoothOptions {
    /// How the bias is smoothed; default [`BiasMode::Fused`].
    pub bias: BiasMode,
    /// How the two passes' orientations are multiplied; default [`Fusion::Tangent`].
    pub fusion: Fusion,
    /// Whether the backward pass starts from a uniform orientation (true) or, as the online
    /// AHRS does, from its first sample's accelerometer and magnetometer (false, the default).
    pub uniform_start: bool,
    /// Whether the backward pass takes the forward pass's magnetic reference at the handoff (the
    /// field's norm and dip its disturbance test compares with, and the variation of the field
    /// measured so far) instead of its first sample's (default true).
    pub forward_mag_reference: bool,
    /// Whether the backward pass's gyroscope has the forward pass's bias estimate at the handoff
    /// taken out (default true).
    pub bias_start: bool,
    /// The consistency gate: the squared Mahalanobis distance between the two passes above
    /// which the backward covariance is widened by `distance² / gate` (0: no gate; default
    /// [`DEFAULT_GATE`]).
    pub gate: f64,
}

/// The default consistency gate of [`SmoothOptions::gate`].
pub const DEFAULT_GATE: f64 = 16.0;

/// How the forward posterior and the backward prediction are multiplied (docs/accuracy/ahrs.md,
/// "The offline smoother", compares them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fusion {
    /// In the tangent space of the forward mode, with both passes' stated (calibrated)
    /// covariances.
    Tangent,
    /// The exact product of the two Bingham states (their exponents added) for the mode; the
    /// covariance as [`Fusion::Tangent`] states it.
    Bingham,
}

impl Default for SmoothOptions {
    fn default() -> SmoothOptions {
        SmoothOptions {
            bias: BiasMode::Fused,
            fusion: Fusion::Tangent,
            uniform_start: false,
            forward_mag_reference: true,
            bias_start: true,
            gate: DEFAULT_GATE,
        }
    }
}

/// What the forward pass keeps per sample; the backward pass replaces it by the smoothed
/// values in place.
#[derive(Debug, Clone, Copy)]
struct Forward {
    q: [f64; 4],
    /// The covariance's upper triangle: xx, xy, xz, yy, yz, zz.
    c: [f32; 6],
}

/// The forward bias estimate and its covariance (upper triangle), per sample.
#[derive(Debug, Clone, Copy)]
struct ForwardBias {
    b: [f32; 3],
    p: [f32; 6],
}

fn pack(c: &Matrix3<f64>) -> [f32; 6] {
    [
        c[(0, 0)] as f32,
        (0.5 * (c[(0, 1)] + c[(1, 0)])) as f32,
        (0.5 * (c[(0, 2)] + c[(2, 0)])) as f32,
        c[(1, 1)] as f32,
        (0.5 * (c[(1, 2)] + c[(2, 1)])) as f32,
        c[(2, 2)] as f32,
    ]
}

/// [`pack`] of a row-major 3×3.
fn pack9(c: &[f64; 9]) -> [f32; 6] {
    [
        c[0] as f32,
        (0.5 * (c[1] + c[3])) as f32,
        (0.5 * (c[2] + c[6])) as f32,
        c[4] as f32,
        (0.5 * (c[5] + c[7])) as f32,
        c[8] as f32,
    ]
}

fn unpack(c: &[f32; 6]) -> Matrix3<f64> {
    let [a, b, d, e, f, g] = c.map(f64::from);
    Matrix3::new(a, b, d, b, e, f, d, f, g)
}

/// `e` with `what` in front of its message.
fn prefix(e: Error, what: &str) -> Error {
    match e {
        Error::InvalidDimension(m) => Error::InvalidDimension(format!("{what}: {m}")),
        Error::InvalidArgument(m) => Error::InvalidArgument(format!("{what}: {m}")),
        Error::NotConverged(m) => Error::NotConverged(format!("{what}: {m}")),
        Error::Numerical(m) => Error::Numerical(format!("{what}: {m}")),
        Error::Callback(m) => Error::Callback(format!("{what}: {m}")),
    }
}

/// The Cholesky factor `L` (lower, `S = L Lᵀ`) of a symmetric 3×3 `S` (its lower triangle
/// read), packed as `[l00, l10, l11, l20, l21, l22]`; `None` unless `S` is positive definite
/// (a pivot zero, negative or NaN).
fn cholesky3(s: &Matrix3<f64>) -> Option<[f64; 6]> {
    let pivot = |d: f64| (d > 0.0).then(|| d.sqrt());
    let l00 = pivot(s[(0, 0)])?;
    let l10 = s[(1, 0)] / l00;
    let l20 = s[(2, 0)] / l00;
    let l11 = pivot(s[(1, 1)] - l10 * l10)?;
    let l21 = (s[(2, 1)] - l20 * l10) / l11;
    let l22 = pivot(s[(2, 2)] - l20 * l20 - l21 * l21)?;
    Some([l00, l10, l11, l20, l21, l22])
}

/// `L⁻¹ b` for the packed factor `l` of [`cholesky3`] (forward substitution).
fn forward3(l: &[f64; 6], b: &Vector3<f64>) -> Vector3<f64> {
    let y0 = b.x / l[0];
    let y1 = (b.y - l[1] * y0) / l[2];
    let y2 = (b.z - l[3] * y0 - l[4] * y1) / l[5];
    Vector3::new(y0, y1, y2)
}

/// The fusion of two Gaussian estimates `(x_f, C_f)`, `(x_f + δ, C_b)`: the shift from `x_f`
/// and the fused covariance, `C_f (C_f + C_b)⁻¹ δ` and `C_f − C_f (C_f + C_b)⁻¹ C_f`. `None`
/// when `C_f + C_b` is not positive definite or the result not finite.
fn fuse(
    cf: &Matrix3<f64>,
    cb: &Matrix3<f64>,
    delta: &Vector3<f64>,
) -> Option<(Vector3<f64>, Matrix3<f64>)> {
    let l = cholesky3(&(cf + cb))?;
    fuse_with(&l, cf, &forward3(&l, delta))
}

/// [`fuse`] with the Cholesky factor `l` of `S = C_f + C_b` ([`cholesky3`]) and `y = L⁻¹ δ`
/// given: with `W = L⁻¹ C_f`, the shift `C_f S⁻¹ δ = Wᵀ y` and the covariance
/// `C_f − C_f S⁻¹ C_f = C_f − Wᵀ W` (symmetric by construction; forward substitutions only).
fn fuse_with(
    l: &[f64; 6],
    cf: &Matrix3<f64>,
    y: &Vector3<f64>,
) -> Option<(Vector3<f64>, Matrix3<f64>)> {
    let w = Matrix3::from_columns(&[
        forward3(l, &cf.column(0).into_owned()),
        forward3(l, &cf.column(1).into_owned()),
        forward3(l, &cf.column(2).into_owned()),
    ]);
    let shift = w.tr_mul(y);
    let ww = w.tr_mul(&w);
    // C_f's symmetric part (the stored covariances are symmetric) minus WᵀW, mirrored
    let cs = Matrix3::from_fn(|i, j| {
        let (i, j) = if i <= j { (i, j) } else { (j, i) };
        0.5 * (cf[(i, j)] + cf[(j, i)]) - ww[(i, j)]
    });
    (shift.iter().all(|x| x.is_finite()) && cs.iter().all(|x| x.is_finite())).then_some((shift, cs))
}

/// Whether a row is a sample (every value finite, the norm representable).
fn usable(v: &[f64; 3]) -> bool {
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

/// The seconds of recording the forward pass runs alone before it hands its bias estimate,
/// magnetic reference and latency estimate to the backward pass, which then runs concurrently
/// with it (module documentation, "Threads").
pub const HANDOFF_TIME: f64 = 30.0;

/// The seconds of recording after [`HANDOFF_TIME`] below which the passes run one after the
/// other, the backward pass starting from the forward pass's final values (a second thread
/// would gain little).
pub const PARALLEL_TIME: f64 = 30.0;

/// The forward pass's values the backward pass starts from, taken after sample
/// [`handoff_index`].
#[derive(Debug, Clone, Copy)]
struct Handoff {
    /// The bias estimate taken out of the backward pass's gyroscope.
    bias: [f64; 3],
    /// The magnetic reference (norm, dip) the backward pass's disturbance test compares with,
    /// and the field's variation the forward pass measured.
    mag_reference: Option<MagReference>,
    /// The magnetometer's latency (s) by which the backward pass shifts the field samples.
    mag_latency: f64,
    /// Without a magnetometer: the forward pass's final state, the backward pass's start.
    state: Option<([f64; 16], [f64; 4])>,
    /// The forward pass's heading coupling, which the smoothed covariance takes.
    coupling: StatedCoupling,
}

impl Handoff {
    fn take(
        ahrs: &Ahrs,
        params: &AhrsParams,
        options: &SmoothOptions,
        has_mag: bool,
    ) -> Result<Handoff> {
        let mag_latency = if params.mag_latency == LATENCY_ESTIMATE {
            ahrs.mag_latency_estimate().unwrap_or(0.0)
        } else {
            params.mag_latency
        };
        let state = if has_mag {
            None
        } else {
            let mut m = [0.0; 16];
            let mut z = [0.0; 4];
            ahrs.state_into(&mut m, &mut z)?;
            Some((m, z))
        };
        Ok(Handoff {
            bias: if options.bias_start {
                ahrs.gyro_bias()
            } else {
                [0.0; 3]
            },
            mag_reference: if options.forward_mag_reference {
                ahrs.mag_reference()
            } else {
                None
            },
            mag_latency,
            state,
            coupling: if options.forward_mag_reference {
                ahrs.stated_coupling()
            } else {
                StatedCoupling::NONE
            },
        })
    }
}

/// The earliest sample after which the forward pass hands its values to the backward pass
/// (later while it has no latency estimate, [`latency_ready`]): [`HANDOFF_TIME`] into the recording (in nominal periods) when a magnetometer is present and
/// at least [`PARALLEL_TIME`] follows; otherwise the last sample (without a magnetometer the
/// backward pass starts from the forward pass's final state, its heading convention). A
/// function of the recording alone: the result does not depend on whether the passes run
/// concurrently.
fn handoff_index(n: usize, nominal: f64, has_mag: bool) -> usize {
    let warm = (HANDOFF_TIME / nominal).ceil();
    let rest = (PARALLEL_TIME / nominal).ceil();
    if has_mag && (n as f64) > warm + rest {
        warm as usize
    } else {
        n.saturating_sub(1)
    }
}

/// Whether the forward pass has the magnetometer's latency the backward pass needs: the
/// parameter, or the forward pass's estimate once there is one.
fn latency_ready(ahrs: &Ahrs, params: &AhrsParams) -> bool {
    params.mag_latency != LATENCY_ESTIMATE || ahrs.mag_latency_estimate().is_some()
}

/// What a pass keeps per sample: its mode and stated covariance, its bias estimate and
/// covariance if wanted, its Bingham exponent if the exact product is wanted.
struct Pass {
    states: Vec<Forward>,
    bias: Option<Vec<ForwardBias>>,
    exponents: Vec<Matrix4<f64>>,
}

/// A vector with room for `n` elements, or the error saying it cannot be allocated.
fn room<T>(n: usize, what: &str) -> Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        Error::InvalidArgument(format!("cannot allocate the smoother's {n} {what}"))
    })?;
    Ok(v)
}

impl Pass {
    fn new(n: usize, want_bias: bool, exact: bool) -> Result<Pass> {
        Ok(Pass {
            states: room(n, "samples")?,
            bias: if want_bias {
                Some(room(n, "bias samples")?)
            } else {
                None
            },
            exponents: if exact {
                room(n, "exponents")?
            } else {
                Vec::new()
            },
        })
    }
}

/// The forward pass: the online AHRS over the recording, its states into `store`, the handoff
/// taken after sample `at`.
fn forward_pass(
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
            .map_err(|e| prefix(e, &format!("sample {k}")))?;
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
fn backward_pass(
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
            .map_err(|e| prefix(e, &format!("backward pass, sample {k}")))?;
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

/// The product at one sample (module documentation): the forward state `f` (and bias `fb`)
/// replaced by the smoothed one, from the backward prediction `b` (and `bb`); `exps` the two
/// Bingham exponents for [`Fusion::Bingham`].
fn product(
    options: &SmoothOptions,
    f: &mut Forward,
    b: &Forward,
    exps: Option<(&Matrix4<f64>, &Matrix4<f64>)>,
    bias: Option<(&mut ForwardBias, &ForwardBias)>,
) {
    let qf = f.q;
    let cf = unpack(&f.c);
    let mut cb = unpack(&b.c);
    let d = q4::to_rotation_vector(&q4::mul(&b.q, &q4::conj(&qf)));
    let dv = Vector3::new(d[0], d[1], d[2]);
    // one Cholesky factor of C_f + C_b and L⁻¹δ serve the gate and the product
    let mut chol = cholesky3(&(cf + cb)).map(|l| (l, forward3(&l, &dv)));
    // the consistency gate: a backward state farther from the forward one than their
    // covariances allow (a start, a magnetic reference taken in a disturbance) is widened
    // until it is consistent (the squared Mahalanobis distance δᵀ(C_f + C_b)⁻¹δ = |L⁻¹δ|²)
    if options.gate > 0.0 {
        if let Some((_, y)) = &chol {
            let m2 = y.norm_squared();
            if m2 > options.gate {
                cb *= m2 / options.gate;
                chol = cholesky3(&(cf + cb)).map(|l| (l, forward3(&l, &dv)));
            }
        }
    }
    if let Some((shift, cs)) = chol.and_then(|(l, y)| fuse_with(&l, &cf, &y)) {
        let q = match exps {
            Some((ef, eb)) => {
                let a = ef + eb;
                let eig = a.symmetric_eigen();
                let i = eig.eigenvalues.imax();
                let v = eig.eigenvectors.column(i);
                [v[0], v[1], v[2], v[3]]
            }
            None => q4::mul(&q4::from_rotation_vector(&[shift.x, shift.y, shift.z]), &qf),
        };
        let nq = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        let s = if q[0] < 0.0 { -1.0 / nq } else { 1.0 / nq };
        f.q = q.map(|x| x * s);
        f.c = pack(&cs);
    }
    if let Some((fb, bb)) = bias {
        let bf = Vector3::new(fb.b[0], fb.b[1], fb.b[2]).map(f64::from);
        let pf = unpack(&fb.p);
        let bbv = Vector3::new(bb.b[0], bb.b[1], bb.b[2]).map(f64::from);
        let pb = unpack(&bb.p);
        if let Some((shift, ps)) = fuse(&pf, &pb, &(bbv - bf)) {
            let bsm = bf + shift;
            fb.b = [bsm.x as f32, bsm.y as f32, bsm.z as f32];
            fb.p = pack(&ps);
        }
    }
}

/// The number of samples from which the product runs on two threads when the passes ran one
/// after the other.
const PARALLEL_PRODUCT: usize = 1 << 14;

/// The samples per [`Chunk`] of the backward pass.
const CHUNK: usize = 4096;

/// A run of consecutive samples of the backward pass: its predicted states (and bias,
/// exponents) of the samples `lo … lo + len − 1`, stored from the highest down. The backward
/// pass hands them over as it goes, so that with the passes concurrent the forward pass's
/// thread forms the product of each while the backward pass goes on.
struct Chunk {
    lo: usize,
    pass: Pass,
}

/// A run of samples for the product: the forward states (and bias, exponents) in order, the
/// backward predictions of the same samples stored in reverse (`back[len − 1 − i]` for
/// `states[i]`).
struct Half<'a> {
    states: &'a mut [Forward],
    exponents: &'a [Matrix4<f64>],
    bias: Option<&'a mut [ForwardBias]>,
    back: &'a [Forward],
    back_exponents: &'a [Matrix4<f64>],
    back_bias: Option<&'a [ForwardBias]>,
}

impl Half<'_> {
    fn apply(mut self, options: &SmoothOptions) {
        let len = self.states.len();
        let exact = !self.exponents.is_empty();
        for i in 0..len {
            let j = len - 1 - i;
            let exps = exact.then(|| (&self.exponents[i], &self.back_exponents[j]));
            let bias = match (self.bias.as_deref_mut(), self.back_bias) {
                (Some(f), Some(b)) => Some((&mut f[i], &b[j])),
                _ => None,
            };
            product(options, &mut self.states[i], &self.back[j], exps, bias);
        }
    }
}

/// The forward pass's states (and exponents, bias) of the samples from `offset` on.
struct Span<'a> {
    offset: usize,
    states: &'a mut [Forward],
    exponents: &'a [Matrix4<f64>],
    bias: Option<&'a mut [ForwardBias]>,
}

impl Span<'_> {
    /// The product at the samples of `chunk` (within the span).
    fn apply(&mut self, options: &SmoothOptions, chunk: &Chunk) {
        let len = chunk.pass.states.len();
        let r = chunk.lo - self.offset..chunk.lo - self.offset + len;
        Half {
            states: &mut self.states[r.clone()],
            exponents: if self.exponents.is_empty() {
                &[]
            } else {
                &self.exponents[r.clone()]
            },
            bias: self.bias.as_deref_mut().map(|b| &mut b[r]),
            back: &chunk.pass.states,
            back_exponents: &chunk.pass.exponents,
            back_bias: chunk.pass.bias.as_deref(),
        }
        .apply(options);
    }
}

/// The span of `fwd`'s samples below `at` and that from `at` on.
fn split_at(fwd: &mut Pass, at: usize) -> (Span<'_>, Span<'_>) {
    let (s_lo, s_hi) = fwd.states.split_at_mut(at);
    let (e_lo, e_hi) = if fwd.exponents.is_empty() {
        (&[][..], &[][..])
    } else {
        fwd.exponents.split_at(at)
    };
    let (b_lo, b_hi) = match fwd.bias.as_mut() {
        Some(b) => {
            let (l, h) = b.split_at_mut(at);
            (Some(l), Some(h))
        }
        None => (None, None),
    };
    (
        Span {
            offset: 0,
            states: s_lo,
            exponents: e_lo,
            bias: b_lo,
        },
        Span {
            offset: at,
            states: s_hi,
            exponents: e_hi,
            bias: b_hi,
        },
    )
}

/// The forward and the backward pass and their product: the smoothed states (and bias).
/// With [`handoff_index`] before the last sample the backward pass runs on a second thread
/// from the handoff on (module documentation, "Threads"), and the forward pass's thread, once
/// its pass is done, forms the product at the backward pass's chunks as they come; one thread
/// if the second cannot be started, with the same result (the product at a sample is a
/// function of the two passes' states there alone). Passes run one after the other form the
/// product afterwards, on two threads from [`PARALLEL_PRODUCT`] samples on. Also returns the
/// heading's coupling to the tilt for the output ([`coupling`]).
fn run(
    params: &AhrsParams,
    options: &SmoothOptions,
    input: &SmoothInput<'_>,
    want_bias: bool,
    threads: bool,
) -> Result<(Vec<Forward>, Option<Vec<ForwardBias>>, StatedCoupling)> {
    let n = input.gyr.len();
    let exact = options.fusion == Fusion::Bingham;
    let has_mag = input
        .mag
        .is_some_and(|m| m.iter().any(|r| usable(r) && r.iter().any(|x| *x != 0.0)));
    let at = handoff_index(n, params.sample_time, has_mag);
    let mut fwd = Pass::new(n, want_bias, exact)?;
    let abort = AtomicBool::new(false);
    let mut handoff = None;
    let mut back_result = None;
    std::thread::scope(|s| -> Result<()> {
        let (tx, rx) = std::sync::mpsc::channel::<Handoff>();
        let (chunk_tx, chunk_rx) = std::sync::mpsc::channel::<Chunk>();
        let abort_ref = &abort;
        let thread = if threads && at + 1 < n {
            std::thread::Builder::new()
                .name("bingham-smooth".into())
                .spawn_scoped(s, move || -> Option<Result<usize>> {
                    let h = rx.recv().ok()?;
                    // a closed channel: the forward pass failed, and nobody waits for these
                    let emit = |c: Chunk| {
                        let _ = chunk_tx.send(c);
                    };
                    Some(backward_pass(
                        params, options, input, &h, want_bias, abort_ref, emit,
                    ))
                })
                .ok()
        } else {
            drop(chunk_tx);
            None
        };
        let concurrent = thread.is_some();
        let fres = forward_pass(params, options, input, has_mag, at, &mut fwd, |h| {
            handoff = Some(h);
            if concurrent {
                // a closed channel: the thread has ended, the result says why
                let _ = tx.send(h);
            }
        });
        drop(tx);
        if fres.is_err() {
            abort.store(true, Ordering::Relaxed);
        } else if concurrent {
            // the product at each chunk as the backward pass hands it over, until it ends
            let (_, mut all) = split_at(&mut fwd, 0);
            for chunk in chunk_rx.iter() {
                all.apply(options, &chunk);
            }
        }
        if let Some(t) = thread {
            back_result = Some(
                t.join()
                    .unwrap_or_else(|_| {
                        Some(Err(Error::Numerical(
                            "the smoother's backward pass panicked".into(),
                        )))
                    })
                    .unwrap_or(Ok(0)),
            );
        }
        fres
    })?;
    if let Some(r) = back_result {
        r?;
        return Ok((fwd.states, fwd.bias, coupling(handoff.as_ref())));
    }
    // the passes one after the other: the backward pass's chunks kept, then the product
    let k = coupling(handoff.as_ref());
    let h = handoff
        .ok_or_else(|| Error::Numerical("the smoother's forward pass gave no handoff".into()))?;
    let mut chunks = Vec::new();
    backward_pass(params, options, input, &h, want_bias, &abort, |c| {
        chunks.push(c)
    })?;
    let total: usize = chunks.iter().map(|c| c.pass.states.len()).sum();
    // the chunks descend: the first half of them (the upper samples) on a second thread
    let half = chunks.len() / 2;
    if threads && total >= PARALLEL_PRODUCT && half > 0 {
        let mid = chunks[half - 1].lo;
        let (upper, lower) = chunks.split_at(half);
        let (mut lo, hi) = split_at(&mut fwd, mid);
        let hi = std::sync::Mutex::new(Some(hi));
        let run_hi = || {
            if let Some(mut h) = hi.lock().ok().and_then(|mut h| h.take()) {
                for c in upper {
                    h.apply(options, c);
                }
            }
        };
        std::thread::scope(|s| {
            // no thread: the half is left for this one
            let _ = std::thread::Builder::new()
                .name("bingham-smooth".into())
                .spawn_scoped(s, run_hi);
            for c in lower {
                lo.apply(options, c);
            }
        });
        run_hi();
    } else {
        let (_, mut all) = split_at(&mut fwd, 0);
        for c in &chunks {
            all.apply(options, c);
        }
    }
    Ok((fwd.states, fwd.bias, k))
}

/// The heading's coupling to the tilt (module `ahrs::uncertainty`) with the magnetic reference
/// of the handoff (0 without one).
fn coupling(handoff: Option<&Handoff>) -> StatedCoupling {
    handoff.map_or(StatedCoupling::NONE, |h| h.coupling)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (SplitMix64) and normal deviates (Box–Muller).
    struct Rng(u64);
    impl Rng {
        fn uniform(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }
        fn normal(&mut self) -> f64 {
            let u = self.uniform().max(1e-300);
            (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * self.uniform()).cos()
        }
    }

    /// The product step against importance sampling: orientations drawn from the forward
    /// density (`exp(φ/2) ⊗ q_f`, `φ ~ N(0, C_f)` in the world frame), weighted by the backward
    /// density (`exp(−½ δᵀ C_b⁻¹ δ)`, `δ` the rotation vector from `q_b`); the weighted mean
    /// rotation vector about `q_f` and its covariance against `fuse`, to three standard errors
    /// of the weighted means (the variance's to a relative 5 %).
    #[test]
    fn the_product_step_matches_importance_sampling() {
        let mut rng = Rng(42);
        let qf = q4::from_rotation_vector(&[0.3, -1.1, 2.0]);
        let cf = Matrix3::new(4e-4, 1e-4, 0.0, 1e-4, 3e-4, -5e-5, 0.0, -5e-5, 9e-4);
        let cb = Matrix3::new(6e-4, -2e-4, 1e-4, -2e-4, 8e-4, 0.0, 1e-4, 0.0, 2e-4);
        let d_true = Vector3::new(0.02, -0.015, 0.03);
        let qb = q4::mul(
            &q4::from_rotation_vector(&[d_true.x, d_true.y, d_true.z]),
            &qf,
        );
        let d = q4::to_rotation_vector(&q4::mul(&qb, &q4::conj(&qf)));
        let (shift, cs) = fuse(&cf, &cb, &Vector3::new(d[0], d[1], d[2])).unwrap();
        let lf = cf.cholesky().unwrap().l();
        let cb_inv = cb.try_inverse().unwrap();
        let n = 400_000;
        let (mut sw, mut sw2) = (0.0, 0.0);
        let mut m1 = Vector3::zeros();
        let mut m2 = Matrix3::zeros();
        let mut samples = Vec::with_capacity(n);
        for _ in 0..n {
            let phi = lf * Vector3::new(rng.normal(), rng.normal(), rng.normal());
            let q = q4::mul(&q4::from_rotation_vector(&[phi.x, phi.y, phi.z]), &qf);
            let e = q4::to_rotation_vector(&q4::mul(&q, &q4::conj(&qb)));
            let e = Vector3::new(e[0], e[1], e[2]);
            let w = (-0.5 * (e.transpose() * cb_inv * e)[0]).exp();
            sw += w;
            sw2 += w * w;
            m1 += w * phi;
            samples.push((w, phi));
        }
        let mean = m1 / sw;
        for (w, phi) in &samples {
            let r = phi - mean;
            m2 += *w * r * r.transpose();
        }
        let cov = m2 / sw;
        // the effective sample size sets the weighted mean's standard error
        let ess = sw * sw / sw2;
        for i in 0..3 {
            let se = (cov[(i, i)] / ess).sqrt();
            assert!(
                (mean[i] - shift[i]).abs() < 3.0 * se,
                "axis {i}: sampled {} vs fused {} (se {se})",
                mean[i],
                shift[i]
            );
            assert!(
                (cov[(i, i)] / cs[(i, i)] - 1.0).abs() < 0.05,
                "axis {i}: sampled variance {} vs fused {}",
                cov[(i, i)],
                cs[(i, i)]
            );
        }
    }

    /// The passes on two threads give the result of one thread bit for bit (the handoff and
    /// the product at each sample are functions of the recording alone), with the bias and the
    /// exact product, on a recording long enough for both to be concurrent (the product formed
    /// chunk by chunk as the backward pass goes), and on one without a magnetometer (the passes
    /// in turn, the product's halves on two threads).
    #[test]
    fn two_threads_give_the_result_of_one() {
        let mut rng = Rng(7);
        let dt = 0.01;
        let n = 9000; // 90 s: the handoff after 30 s, 60 s concurrent
        let mut gyr = Vec::with_capacity(n);
        let mut acc = Vec::with_capacity(n);
        let mut mag = Vec::with_capacity(n);
        let mut q = [1.0, 0.0, 0.0, 0.0];
        for k in 0..n {
            let t = k as f64 * dt;
            let w = [
                0.5 * (0.7 * t).sin(),
                0.4 * (0.3 * t).cos(),
                0.6 * (0.2 * t).sin(),
            ];
            q = q4::mul(&q, &q4::from_rotation_vector(&w.map(|x| x * dt)));
            let r = q4::to_matrix(&q);
            // the world's gravity reaction (up) and field (north, down) in the sensor frame
            let body = |v: [f64; 3]| -> [f64; 3] {
                std::array::from_fn(|i| r[0][i] * v[0] + r[1][i] * v[1] + r[2][i] * v[2])
            };
            let a = body([0.0, 0.0, 9.81]);
            let m = body([0.0, 20.0, -40.0]);
            gyr.push(std::array::from_fn(|i| w[i] + 0.01 + 0.002 * rng.normal()));
            acc.push(std::array::from_fn(|i| a[i] + 0.05 * rng.normal()));
            mag.push(std::array::from_fn(|i| m[i] + 0.3 * rng.normal()));
        }
        let input = SmoothInput {
            time: None,
            gyr: &gyr,
            acc: &acc,
            mag: Some(&mag),
        };
        // a fixed latency: the handoff at HANDOFF_TIME; the estimate: when it exists
        for (latency, fusion) in [
            (0.0, Fusion::Tangent),
            (0.0, Fusion::Bingham),
            (LATENCY_ESTIMATE, Fusion::Tangent),
        ] {
            let mut params = AhrsParams::new(dt);
            params.mag_latency = latency;
            let options = SmoothOptions {
                fusion,
                ..SmoothOptions::default()
            };
            let at = handoff_index(n, dt, true);
            assert!(at + 1 < n && at > 0, "{at}");
            assert_threads_agree(&params, &options, &input);
        }
        // without the magnetometer the passes run in turn, and over PARALLEL_PRODUCT samples
        // the product's two halves (of the backward pass's chunks) on two threads
        let long = 3 * n;
        let (gyr2, acc2): (Vec<_>, Vec<_>) = (0..long).map(|k| (gyr[k % n], acc[k % n])).unzip();
        let input = SmoothInput {
            time: None,
            gyr: &gyr2,
            acc: &acc2,
            mag: None,
        };
        let params = AhrsParams::new(dt);
        let options = SmoothOptions::default();
        assert!(long > PARALLEL_PRODUCT + CHUNK);
        assert_threads_agree(&params, &options, &input);
    }

    /// The smoother with one thread and with two: every smoothed state and bias bit for bit.
    fn assert_threads_agree(params: &AhrsParams, options: &SmoothOptions, input: &SmoothInput<'_>) {
        let (f1, b1, k1) = run(params, options, input, true, false).unwrap();
        let (f2, b2, k2) = run(params, options, input, true, true).unwrap();
        let (b1, b2) = (b1.unwrap(), b2.unwrap());
        assert_eq!(k1, k2);
        assert_eq!((f1.len(), b1.len()), (input.gyr.len(), input.gyr.len()));
        for k in 0..input.gyr.len() {
            assert_eq!(f1[k].q, f2[k].q, "sample {k}");
            assert_eq!(f1[k].c, f2[k].c, "sample {k}");
            assert_eq!(b1[k].b, b2[k].b, "sample {k}");
            assert_eq!(b1[k].p, b2[k].p, "sample {k}");
        }
    }

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
