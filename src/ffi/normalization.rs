//! The normalization constant of the C API, over [`crate::normalization`]:
//! `bingham_normalization_constant`, `bingham_log_normalization_constant` (exact and
//! saddlepoint) and `bingham_log_normalization_hessian`. Thin wrappers: check `d` and the
//! pointers, read `z`, call the core, copy the results out. No mathematics here beyond
//! `F = exp(log F)` and `∂F/∂z_i = F ∂ log F/∂z_i`.

use super::args::{args, Arg};
use super::guard::{dim, guard, Failure, FfiResult};
use super::status::bingham_status;
use crate::normalization::{log_normalization_into, Method};

/// Runs `f` with a zeroed buffer of `d` doubles: on the stack for d ≤ 4 (zeroing a buffer of
/// `MAX_DIM` doubles on every call cost about as much as the d = 2 call's argument checks), on
/// the heap beyond (where the evaluation itself takes microseconds).
fn with_buffer<R>(d: usize, f: impl FnOnce(&mut [f64]) -> R) -> R {
    if d <= 4 {
        f(&mut [0.0; 4][..d])
    } else {
        f(&mut vec![0.0; d])
    }
}

/// Shared body of the log-normalization functions.
///
/// # Safety
/// `z` has `d` readable doubles; `log_f` is writable; `dlog_f` NULL or `d` writable doubles.
unsafe fn log_normalization_ffi(
    d: usize,
    z: *const f64,
    log_f: *mut f64,
    dlog_f: *mut f64,
    method: Method,
) -> FfiResult<()> {
    dim(d)?;
    // SAFETY: forwarded caller contract.
    let (zs, log_f, dlog_f) = unsafe { args!(z: [d], log_f: out, dlog_f: opt out [d]).read()? };
    with_buffer(d, |grad| {
        let lf = log_normalization_into(zs, method, dlog_f.is_some().then_some(&mut *grad), None)?;
        // SAFETY: every input has been read; lengths 1 and d.
        unsafe {
            log_f.set(lf);
            if let Some(dlog_f) = dlog_f {
                dlog_f.write(grad);
            }
        }
        Ok(())
    })
}

/// The normalization constant `F(Z) = ∫_{S^{d-1}} exp(xᵀ Z x) dx` and, optionally, its gradient.
///
/// F is taken with respect to the **surface measure** of the unit sphere, so `F(0) = |S^{d-1}|`:
/// 2π for d = 2, 4π for d = 3, 2π² for d = 4 (other libraries use other scalings; compare
/// ratios). Exact to near machine precision: closed form (d = 2), 1-D quadrature (d = 3, 4), a
/// contour integral (d ≥ 5).
///
/// - `d`: dimension, 2..64.
/// - `z`: the d concentrations, any order and any shift (F(Z + cI) = e^c F(Z)), all finite.
/// - `f`: receives F(Z).
/// - `df`: `NULL`, or receives the d partial derivatives ∂F/∂z_i, in the order of the input `z`.
///
/// F overflows a `double` for large positive z (roughly max z > 700) and underflows for very
/// negative z: then this returns `BINGHAM_ERR_NUMERICAL` (never an infinite or zero F);
/// use `bingham_log_normalization_constant()`, which works for any finite z.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION` (d), `BINGHAM_ERR_NULL_ARGUMENT` (`z`, `f`),
/// `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf in z), `BINGHAM_ERR_NUMERICAL` (F not representable).
/// On error nothing is written.
///
/// # Safety
/// `z`: d readable doubles; `f`: one writable double; `df`: `NULL` or d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_normalization_constant(
    d: usize,
    z: *const f64,
    f: *mut f64,
    df: *mut f64,
) -> bingham_status {
    guard("bingham_normalization_constant", || {
        dim(d)?;
        // SAFETY: caller contract.
        let (zs, f, df) = unsafe { args!(z: [d], f: out, df: opt out [d]).read()? };
        with_buffer(d, |grad| {
            let lf = log_normalization_into(zs, Method::Exact, Some(&mut *grad), None)?;
            let value = lf.exp();
            if !value.is_normal() {
                return Err(Failure::new(
                    bingham_status::BINGHAM_ERR_NUMERICAL,
                    format!(
                        "F = exp({lf:.6e}) is not representable as a double (overflow or \
                         underflow); use bingham_log_normalization_constant"
                    ),
                ));
            }
            // ∂F/∂z_i = F ω_i
            for w in grad.iter_mut() {
                *w *= value;
            }
            // SAFETY: every input has been read; lengths 1 and d.
            unsafe {
                f.set(value);
                if let Some(df) = df {
                    df.write(grad);
                }
            }
            Ok(())
        })
    })
}

/// The natural logarithm of the normalization constant, `log F(Z)`, and optionally its gradient.
///
/// Same F as `bingham_normalization_constant()` (surface measure, F(0) = |S^{d-1}|), exact to
/// near machine precision, finite for every finite z.
///
/// - `d`: dimension, 2..64.
/// - `z`: the d concentrations, any order and shift, all finite.
/// - `log_f`: receives log F(Z).
/// - `dlog_f`: `NULL`, or receives `∂ log F/∂z_i = E[x_i²]` (in the principal frame), in the order
///   of the input `z`; these are the eigenvalues ω_i of the second moment and sum to 1.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION`, `BINGHAM_ERR_NULL_ARGUMENT` (`z`, `log_f`),
/// `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf), `BINGHAM_ERR_NUMERICAL`. On error nothing is written.
///
/// # Safety
/// `z`: d readable doubles; `log_f`: one writable double; `dlog_f`: `NULL` or d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_log_normalization_constant(
    d: usize,
    z: *const f64,
    log_f: *mut f64,
    dlog_f: *mut f64,
) -> bingham_status {
    guard("bingham_log_normalization_constant", || {
        // SAFETY: forwarded caller contract.
        unsafe { log_normalization_ffi(d, z, log_f, dlog_f, Method::Exact) }
    })
}

/// **Approximate** `log F(Z)` and gradient by the third-order saddlepoint approximation of Kume &
/// Wood (2005), as used by other Bingham libraries.
///
/// Provided for comparison and for users who need agreement with those libraries; the relative
/// error of F is up to several percent (measured in the repository's `docs/accuracy.md`) and the
/// gradient entries do not sum exactly to 1. Prefer `bingham_log_normalization_constant()`, which
/// is exact.
///
/// Arguments, errors and safety as for `bingham_log_normalization_constant()`.
///
/// # Safety
/// `z`: d readable doubles; `log_f`: one writable double; `dlog_f`: `NULL` or d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_log_normalization_constant_saddlepoint(
    d: usize,
    z: *const f64,
    log_f: *mut f64,
    dlog_f: *mut f64,
) -> bingham_status {
    guard("bingham_log_normalization_constant_saddlepoint", || {
        // SAFETY: forwarded caller contract.
        unsafe { log_normalization_ffi(d, z, log_f, dlog_f, Method::Saddlepoint) }
    })
}

/// `log F(Z)` with its gradient and Hessian (exact).
///
/// - `d`: dimension, 2..64; `z`: d concentrations, any order and shift, all finite.
/// - `log_f`: receives log F(Z).
/// - `dlog_f`: `NULL`, or receives ∂ log F/∂z_i (input order), as in
///   `bingham_log_normalization_constant()`.
/// - `d2log_f`: receives the d×d row-major Hessian ∂² log F/∂z_i∂z_j = Cov(x_i², x_j²)
///   (input order; symmetric; each row sums to 0).
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION`, `BINGHAM_ERR_NULL_ARGUMENT` (`z`, `log_f`,
/// `d2log_f`), `BINGHAM_ERR_INVALID_ARGUMENT`, `BINGHAM_ERR_NUMERICAL`. On error nothing is written.
///
/// # Safety
/// `z`: d readable doubles; `log_f`: one writable double; `dlog_f`: `NULL` or d writable doubles;
/// `d2log_f`: d*d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_log_normalization_hessian(
    d: usize,
    z: *const f64,
    log_f: *mut f64,
    dlog_f: *mut f64,
    d2log_f: *mut f64,
) -> bingham_status {
    guard("bingham_log_normalization_hessian", || {
        dim(d)?;
        // SAFETY: caller contract.
        let (zs, log_f, dlog_f, d2log_f) =
            unsafe { args!(z: [d], log_f: out, dlog_f: opt out [d], d2log_f: out [d * d]).read()? };
        let mut grad = vec![0.0; d];
        let mut hess = vec![0.0; d * d];
        let lf = log_normalization_into(zs, Method::Exact, Some(&mut grad), Some(&mut hess))?;
        // SAFETY: every input has been read; lengths 1, d, d*d.
        unsafe {
            log_f.set(lf);
            if let Some(dlog_f) = dlog_f {
                dlog_f.write(&grad);
            }
            d2log_f.write(&hess);
        }
        Ok(())
    })
}
