//! The offline smoother (the C side of [`crate::smoother`]): one call over a whole recording.
//! Thin wrappers: check pointers, read the samples, call the core (which writes the outputs
//! only once it has succeeded).

use super::args::{args, Arg};
use super::guard::{guard, handle};
use super::status::bingham_status;
use crate::ahrs::AhrsParams;
use crate::smoother::{smooth, SmoothInput, SmoothOutput};

/// Smooths a whole recording: the orientation at every sample from all samples, before and
/// after it (the online AHRS forward, the same AHRS over the reversed recording backward, their
/// densities multiplied; design: docs/design.md, "The offline smoother"; accuracy:
/// docs/accuracy/ahrs.md). For recorded logs (motion analysis, replayed robot logs); for live
/// use take `bingham_ahrs_update_batch()`.
///
/// - `p`: the AHRS parameters (as for `bingham_ahrs_new()`; `sample_time` the period of the
///   rows).
/// - `gyr` (rad/s), `acc` (m/s²): n×3 row-major; `mag`: n×3 row-major (any consistent unit)
///   or `NULL`. Row k is the sample at time k·`sample_time`; a row holding NaN (or ±Inf) means
///   "no sample" of that sensor at that time, as in `bingham_ahrs_update_batch()`.
/// - `quat`: n×4 row-major output, the smoothed orientation (w, x, y, z per row, sensor →
///   world ENU, w ≥ 0).
/// - `spread`: n doubles or `NULL`: the smoothed orientation's total angular standard
///   deviation (rad; the square root of the trace of its covariance, see
///   `bingham_ahrs_smooth_ex()`).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`p`, `gyr`, `acc`, `quat` NULL),
/// `BINGHAM_ERR_INVALID_DIMENSION` (n×4 overflows), `BINGHAM_ERR_INVALID_ARGUMENT` (a bad
/// parameter; a sample the AHRS refuses: a gyroscope row turning more than 1e6 rad, the first
/// sample without a finite accelerometer showing gravity; the message names the index; the
/// working memory not available: "cannot allocate"), `BINGHAM_ERR_NUMERICAL`. On any error
/// nothing is written. `n = 0` does nothing.
///
/// Memory: allocates 112 bytes per sample (`n·112`: each pass's orientation and its
/// covariance), freed before it returns; nothing else grows with n (one hour at 1 kHz: about
/// 400 MB). Time: two AHRS passes (docs/speed.md), which overlap in wall time on two cores.
///
/// Threads: uses at most two threads, the caller's and one it starts and joins before it
/// returns: on a recording longer than 60 s with a magnetometer the backward pass runs
/// concurrently with the forward pass from a fixed point on (30 s into the recording, or the
/// first second after it at which the forward pass has its latency estimate). The result
/// depends on the samples only, never on the scheduling: it is the same bit for bit when the
/// second thread cannot be started (then the call runs on the caller's thread alone).
/// Thread safety: no shared state; concurrent calls are independent.
///
/// # Safety
/// `p`: a readable `bingham_ahrs_params`; `gyr`, `acc`: n*3 readable doubles; `mag`: `NULL` or
/// n*3 readable doubles; `quat`: n*4 writable doubles; `spread`: `NULL` or n writable doubles;
/// outputs not overlapping the inputs.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_smooth(
    p: *const AhrsParams,
    n: usize,
    gyr: *const f64,
    acc: *const f64,
    mag: *const f64,
    quat: *mut f64,
    spread: *mut f64,
) -> bingham_status {
    guard("bingham_ahrs_smooth", || {
        // SAFETY: forwarded caller contract.
        unsafe {
            smooth_ex(
                p,
                n,
                std::ptr::null(),
                gyr,
                acc,
                mag,
                quat,
                spread,
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            )
        }
    })
}

/// As `bingham_ahrs_smooth()`, with timestamps and the further outputs; every added pointer
/// may be `NULL` (one call with optional arguments rather than one call per output, so that a
/// caller wanting several outputs runs the passes once).
///
/// - `t`: n doubles (s, strictly increasing, any origin): when each sample was taken, each
///   processed with its own time step as in `bingham_ahrs_update_batch_timed()` (steps within
///   a millionth of `sample_time` are taken as it); `NULL`: uniformly spaced by `sample_time`.
/// - `bias`: n×3 row-major output or `NULL`: the smoothed gyroscope bias (rad/s, sensor
///   frame): the forward and the backward pass's estimates fused by their covariances.
/// - `covariance`: n×9 row-major output or `NULL`: per sample the 3×3 covariance (rad²,
///   row-major) of the smoothed orientation's error as a rotation vector in the world frame
///   (ENU), as `bingham_ahrs_orientation_covariance()` defines it (kept as single-precision
///   floats inside: about 7 significant digits).
///
/// Errors: those of `bingham_ahrs_smooth()`, and `BINGHAM_ERR_INVALID_ARGUMENT` for a
/// timestamp that is not finite or not after the previous one, or a step above
/// `BINGHAM_AHRS_MAX_STEP_TIME` (the message names the index). On any error nothing is written.
///
/// Memory: `n·112` bytes, `n·184` with `bias` (each pass's bias estimate and its covariance
/// too), freed before it returns. Threads and thread safety as `bingham_ahrs_smooth()`.
///
/// # Safety
/// As `bingham_ahrs_smooth()`; `t`: `NULL` or n readable doubles; `bias`: `NULL` or n*3
/// writable doubles; `covariance`: `NULL` or n*9 writable doubles; outputs not overlapping the
/// inputs or each other.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_smooth_ex(
    p: *const AhrsParams,
    n: usize,
    t: *const f64,
    gyr: *const f64,
    acc: *const f64,
    mag: *const f64,
    quat: *mut f64,
    spread: *mut f64,
    bias: *mut f64,
    covariance: *mut f64,
) -> bingham_status {
    guard("bingham_ahrs_smooth_ex", || {
        // SAFETY: forwarded caller contract.
        unsafe { smooth_ex(p, n, t, gyr, acc, mag, quat, spread, bias, covariance) }
    })
}

/// The body of both exports.
///
/// # Safety
/// The exports' contract.
#[allow(clippy::too_many_arguments)]
unsafe fn smooth_ex(
    p: *const AhrsParams,
    n: usize,
    t: *const f64,
    gyr: *const f64,
    acc: *const f64,
    mag: *const f64,
    quat: *mut f64,
    spread: *mut f64,
    bias: *mut f64,
    covariance: *mut f64,
) -> super::guard::FfiResult<()> {
    // SAFETY: caller contract.
    let params = unsafe { handle("p", p)? };
    // SAFETY: caller contract: n rows of 3 readable doubles, n timestamps or NULL, n rows of
    // 4 (n, 3, 9) writable doubles, not overlapping.
    let (time, g, a, q, m, s, b, c) = unsafe {
        args!(
            t: opt raw [n],
            gyr: rows [n; 3],
            acc: rows [n; 3],
            quat: mut rows [n; 4],
            mag: opt rows [n; 3],
            spread: opt mut [n],
            bias: opt mut rows [n; 3],
            covariance: opt mut rows [n; 9]
        )
        .read()?
    };
    let input = SmoothInput {
        time,
        gyr: g,
        acc: a,
        mag: m,
    };
    let out = SmoothOutput {
        quat: q,
        spread: s,
        bias: b,
        covariance: c,
    };
    smooth(params, &input, out)?;
    Ok(())
}
