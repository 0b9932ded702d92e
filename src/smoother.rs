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
//! its magnetic reference (the field's norm and dip, against which it tests for disturbances)
//! is the forward pass's final one, not its first sample's, which may lie in a disturbance;
//! at sample `k` the smoother takes its *predicted* state: the state after sample `k+1` turned
//! by the gyroscope to sample `k`, before sample `k`'s accelerometer and magnetometer, which
//! the forward posterior holds already. Its gyroscope has the forward pass's final bias
//! estimate taken out, so that its bias estimate starts near the truth (its stated bias
//! variance still starts at `bias_std²`).
//!
//! The product is formed in the tangent space of the forward mode with the stated (calibrated)
//! covariances of both passes ([`Ahrs::orientation_covariance`]): with `δ` the rotation vector
//! (world frame) from the forward mode to the backward one, `C_s = (C_f⁻¹ + C_b⁻¹)⁻¹`, the
//! smoothed mode `exp(C_f (C_f + C_b)⁻¹ δ / 2) ⊗ q_f` and its covariance `C_s` (computed as
//! `C_f − C_f (C_f + C_b)⁻¹ C_f`, which stays finite when the backward pass knows nothing).
//! A backward state farther from the forward one than the two covariances allow (squared
//! Mahalanobis distance above [`DEFAULT_GATE`]) has its covariance widened until it is not.
//! The gyroscope bias is smoothed the same way from the two passes' estimates and covariances.
//!
//! Approximations (docs/design.md): the AHRS low-passes the accelerometer (`acc_tau`) and the
//! magnetometer (`mag_tau`) and corrects every 20 ms, so a pass's state holds sample `k`'s own
//! measurement only through its share of an average; the backward predicted state holds none
//! of samples `≤ k`, the forward posterior none of samples `> k`: nothing is counted twice. The
//! magnetometer's latency (lagging the gyroscope) is a lead in reversed time: the backward pass
//! reads the field samples shifted by the forward pass's latency (the parameter, or the
//! forward's final estimate), interpolated linearly. Without any magnetometer sample the
//! heading is only defined by the forward pass's start, so the backward pass starts from the
//! forward pass's final state (its heading convention; the tilt of the last samples is then
//! counted twice, over the last `acc_tau` only).
//!
//! Memory: the forward pass's mode (4 `f64`) and stated covariance (6 `f32`) per sample,
//! [`BYTES_PER_SAMPLE`] bytes; with the smoothed bias requested, its estimate and covariance
//! too ([`BIAS_BYTES_PER_SAMPLE`] more). Nothing else grows with the recording.

use nalgebra::{Matrix3, Matrix4, Vector3, Vector4};

use crate::ahrs::{Ahrs, AhrsParams, LATENCY_ESTIMATE};
use crate::error::{Error, Result};
use crate::quaternion::q4;

/// The bytes the smoother allocates per sample (the forward mode as 4 `f64` and its stated
/// covariance as 6 `f32`), besides the caller's inputs and outputs.
pub const BYTES_PER_SAMPLE: usize = std::mem::size_of::<Forward>();

/// The bytes the smoother allocates per sample in addition to [`BYTES_PER_SAMPLE`] when the
/// smoothed gyroscope bias is requested (the forward bias estimate as 3 `f32` and its
/// covariance as 6 `f32`).
pub const BIAS_BYTES_PER_SAMPLE: usize = std::mem::size_of::<ForwardBias>();

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
    /// Whether the backward pass takes the forward pass's final magnetic reference (the field's
    /// norm and dip its disturbance test compares with) instead of its first sample's (default
    /// true).
    pub forward_mag_reference: bool,
    /// Whether the backward pass's gyroscope has the forward pass's final bias estimate taken
    /// out (default true).
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

fn unpack(c: &[f32; 6]) -> Matrix3<f64> {
    let [a, b, d, e, f, g] = c.map(f64::from);
    Matrix3::new(a, b, d, b, e, f, d, f, g)
}

fn matrix9(c: &[f64; 9]) -> Matrix3<f64> {
    Matrix3::from_row_slice(c)
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

/// The fusion of two Gaussian estimates `(x_f, C_f)`, `(x_f + δ, C_b)`: the shift from `x_f`
/// and the fused covariance, `C_f (C_f + C_b)⁻¹ δ` and `C_f − C_f (C_f + C_b)⁻¹ C_f`. `None`
/// when `C_f + C_b` is singular or not finite.
fn fuse(
    cf: &Matrix3<f64>,
    cb: &Matrix3<f64>,
    delta: &Vector3<f64>,
) -> Option<(Vector3<f64>, Matrix3<f64>)> {
    let s = cf + cb;
    let chol = s.cholesky()?;
    // K = C_f S⁻¹ (S, C_f symmetric): Kᵀ = S⁻¹ C_f
    let kt = chol.solve(cf);
    let shift = kt.transpose() * delta;
    let cs = cf - kt.transpose() * cf;
    let cs = 0.5 * (cs + cs.transpose());
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
/// bias output), freed before it returns.
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
    let mut fwd = Vec::new();
    fwd.try_reserve_exact(n).map_err(|_| {
        Error::InvalidArgument(format!("cannot allocate the smoother's {n} samples"))
    })?;
    let mut bias = Vec::new();
    if want_bias {
        bias.try_reserve_exact(n).map_err(|_| {
            Error::InvalidArgument(format!("cannot allocate the smoother's {n} bias samples"))
        })?;
    }
    let bias_store = want_bias.then_some(&mut bias);
    run(params, options, input, &mut fwd, bias_store)?;
    if options.bias == BiasMode::SecondPass {
        // the gyroscope minus the smoothed bias, the passes again: the bias estimates then
        // start at the smoothed bias instead of zero
        let mut gyr2 = Vec::new();
        gyr2.try_reserve_exact(n).map_err(|_| {
            Error::InvalidArgument(format!("cannot allocate the smoother's {n} samples"))
        })?;
        gyr2.extend(
            input
                .gyr
                .iter()
                .zip(&bias)
                .map(|(g, b)| std::array::from_fn::<f64, 3, _>(|j| g[j] - f64::from(b.b[j]))),
        );
        let first = bias.clone();
        let input2 = SmoothInput {
            gyr: &gyr2,
            ..*input
        };
        fwd.clear();
        bias.clear();
        run(params, options, &input2, &mut fwd, Some(&mut bias))?;
        // the bias output: the first passes' smoothed bias plus the second's residual
        for (b, f) in bias.iter_mut().zip(&first) {
            for j in 0..3 {
                b.b[j] += f.b[j];
            }
        }
    }
    // success: the outputs
    for (o, f) in out.quat.iter_mut().zip(&fwd) {
        *o = f.q;
    }
    if let Some(s) = out.spread {
        for (o, f) in s.iter_mut().zip(&fwd) {
            let c = f.c.map(f64::from);
            *o = (c[0] + c[3] + c[5]).max(0.0).sqrt();
        }
    }
    if let Some(c) = out.covariance {
        for (o, f) in c.iter_mut().zip(&fwd) {
            let m = unpack(&f.c);
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

/// The forward and the backward pass: `fwd` (and `bias`) filled with the smoothed values.
fn run(
    params: &AhrsParams,
    options: &SmoothOptions,
    input: &SmoothInput<'_>,
    fwd: &mut Vec<Forward>,
    mut bias: Option<&mut Vec<ForwardBias>>,
) -> Result<()> {
    let n = input.gyr.len();
    let nominal = params.sample_time;
    // the forward pass: the online AHRS
    let mut ahrs = Ahrs::new(params)?;
    let exact = options.fusion == Fusion::Bingham;
    let mut exponents: Vec<Matrix4<f64>> = Vec::new();
    for k in 0..n {
        let m = input.mag.map(|m| &m[k]);
        let dt = step_time(input.time, k, nominal);
        ahrs.update_dt(dt, &input.gyr[k], &input.acc[k], m)
            .map_err(|e| prefix(e, &format!("sample {k}")))?;
        let c = matrix9(&ahrs.orientation_covariance()?);
        fwd.push(Forward {
            q: ahrs.quaternion(),
            c: pack(&c),
        });
        if exact {
            exponents.push(exponent(&ahrs)?);
        }
        if let Some(b) = bias.as_deref_mut() {
            let g = ahrs.gyro_bias();
            b.push(ForwardBias {
                b: g.map(|x| x as f32),
                p: pack(&matrix9(&ahrs.gyro_bias_covariance())),
            });
        }
    }
    // the backward pass's magnetometer: the forward's latency as a shift of the samples
    let mag_latency = if params.mag_latency == LATENCY_ESTIMATE {
        ahrs.mag_latency_estimate().unwrap_or(0.0)
    } else {
        params.mag_latency
    };
    let mag_shift = mag_latency / nominal;
    let acc_shift = params.acc_latency / nominal;
    let has_mag = input
        .mag
        .is_some_and(|m| m.iter().any(|r| usable(r) && r.iter().any(|x| *x != 0.0)));
    let mut bp = *params;
    bp.mag_latency = 0.0;
    bp.acc_latency = 0.0;
    // the backward pass's gyroscope: the forward pass's final bias estimate taken out, so that
    // the backward bias estimate (of what remains) starts near zero instead of at the bias;
    // its stated bias variance still starts at bias_std² (conservative: nothing counted twice)
    let b_end = if options.bias_start {
        ahrs.gyro_bias()
    } else {
        [0.0; 3]
    };
    let mut back = Ahrs::new(&bp)?;
    if has_mag {
        if options.uniform_start {
            // uniform: the backward pass holds the future's evidence only
            let eye = [
                1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
            ];
            back.set_state(&eye, &[0.0; 4])?;
        }
        // else: the AHRS's own start from its first sample (the recording's last): evidence of
        // that sample only, which no forward posterior before it holds
    } else {
        // the heading's convention is the forward pass's start: carry it over
        let mut m = [0.0; 16];
        let mut z = [0.0; 4];
        ahrs.state_into(&mut m, &mut z)?;
        back.set_state(&m, &z)?;
    }
    let mut started = false;
    for k in (0..n).rev() {
        // the backward pass's sample for sample k: the turn from k+1 to k, k's own sensors
        let (g, dt) = if k + 1 < n {
            (input.gyr[k + 1], step_time(input.time, k + 1, nominal))
        } else {
            (input.gyr[k], nominal)
        };
        let g = [b_end[0] - g[0], b_end[1] - g[1], b_end[2] - g[2]];
        if started {
            // the predicted state at k: the state after k+1 turned by the gyroscope to k
            let b = back.gyro_bias();
            let qb = if usable(&g) {
                let w = [(g[0] - b[0]) * dt, (g[1] - b[1]) * dt, (g[2] - b[2]) * dt];
                q4::mul(&back.quaternion(), &q4::from_rotation_vector(&w))
            } else {
                back.quaternion()
            };
            let mut cb = matrix9(&back.orientation_covariance()?);
            let f = &mut fwd[k];
            let qf = f.q;
            let cf = unpack(&f.c);
            let d = q4::to_rotation_vector(&q4::mul(&qb, &q4::conj(&qf)));
            let dv = Vector3::new(d[0], d[1], d[2]);
            // the consistency gate: a backward state farther from the forward one than their
            // covariances allow (a start, a magnetic reference taken in a disturbance) is
            // widened until it is consistent
            if options.gate > 0.0 {
                if let Some(chol) = (cf + cb).cholesky() {
                    let m2 = dv.dot(&chol.solve(&dv));
                    if m2 > options.gate {
                        cb *= m2 / options.gate;
                    }
                }
            }
            if let Some((shift, cs)) = fuse(&cf, &cb, &dv) {
                let q = if exact {
                    // the backward exponent turned to k: p(q) = p_{k+1}(q ⊗ dq*)
                    let dq = q4::conj(&q4::mul(&q4::conj(&back.quaternion()), &qb));
                    let r = Matrix4::from_fn(|i, j| {
                        let mut e = [0.0; 4];
                        e[j] = 1.0;
                        q4::mul(&e, &dq)[i]
                    });
                    let a = exponents[k] + r.transpose() * exponent(&back)? * r;
                    let eig = a.symmetric_eigen();
                    let i = eig.eigenvalues.imax();
                    let v = eig.eigenvectors.column(i);
                    [v[0], v[1], v[2], v[3]]
                } else {
                    q4::mul(&q4::from_rotation_vector(&[shift.x, shift.y, shift.z]), &qf)
                };
                let nq = q.iter().map(|x| x * x).sum::<f64>().sqrt();
                let s = if q[0] < 0.0 { -1.0 / nq } else { 1.0 / nq };
                f.q = q.map(|x| x * s);
                f.c = pack(&cs);
            }
            if let Some(bs) = bias.as_deref_mut() {
                let fb = &mut bs[k];
                let bf = Vector3::new(fb.b[0], fb.b[1], fb.b[2]).map(f64::from);
                let pf = unpack(&fb.p);
                let bb = Vector3::from(b_end) - Vector3::from(b);
                let pb = matrix9(&back.gyro_bias_covariance());
                if let Some((shift, ps)) = fuse(&pf, &pb, &(bb - bf)) {
                    let bsm = bf + shift;
                    fb.b = [bsm.x as f32, bsm.y as f32, bsm.z as f32];
                    fb.p = pack(&ps);
                }
            }
        }
        let acc = shifted(input.acc, k, acc_shift);
        let mag = input.mag.map(|m| shifted(m, k, mag_shift));
        if !started {
            // the backward pass starts at the last sample with a usable accelerometer
            let a2 = acc.iter().map(|x| x * x).sum::<f64>();
            if !(a2.is_finite() && a2.sqrt() >= 0.25 * params.gravity) {
                continue;
            }
        }
        back.update_dt(dt, &g, &acc, mag.as_ref())
            .map_err(|e| prefix(e, &format!("backward pass, sample {k}")))?;
        if !started && options.forward_mag_reference {
            // the field's reference (norm and dip, what the disturbance test compares with)
            // from the forward pass over the whole recording, not from the last sample, which
            // may lie in a disturbance (a magnet attached for the rest of the recording)
            if let Some(r) = ahrs.mag_reference() {
                back.set_mag_reference(r);
            }
        }
        started = true;
    }
    Ok(())
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
