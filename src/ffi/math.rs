//! The distribution functions of the C API: thin wrappers that check pointers and lengths, call
//! the core, and copy results out. No mathematics here beyond `F = exp(log F)`.
//!
//! Pattern of every function: check `d` (before reading any array), check the required
//! pointers, read and validate the inputs, compute into library-owned buffers, and only then copy
//! into the caller's outputs. So on any error no output is touched, and outputs may overlap
//! inputs (in-place use, e.g. `bingham_multiply(d, m, z, m2, z2, m, z)`).

use nalgebra::DMatrix;
use rand::rngs::StdRng;
use rand::SeedableRng;

use super::guard::{dim, guard, len2, need, optional, read, write, write1, Failure, FfiResult};
use super::status::bingham_status;
use crate::distribution::Bingham;
use crate::mle::{mle_from_samples, mle_from_second_moment};
use crate::normalization::{log_normalization_into, Method};

/// Reads `(m, z)` (d×d row-major, length d) and builds the normalized distribution.
///
/// # Safety
/// As for [`read`]: `m` points to `d*d` and `z` to `d` readable doubles (or is NULL → error).
unsafe fn distribution(
    d: usize,
    m_name: &str,
    m: *const f64,
    z_name: &str,
    z: *const f64,
) -> FfiResult<Bingham> {
    // SAFETY: forwarded caller contract; d <= 64 so d*d cannot overflow.
    let (ms, zs) = unsafe { (read(m_name, m, d * d)?, read(z_name, z, d)?) };
    Bingham::from_row_major(d, ms, zs)
        .map_err(|e| Failure::from(e).context(format_args!("(`{m_name}`, `{z_name}`)")))
}

/// Copies a distribution to the caller's `m` (d×d row-major) and `z` (length d).
///
/// # Safety
/// As for [`write`]: `m` has `d*d`, `z` has `d` writable doubles, both checked non-NULL.
unsafe fn write_distribution(b: &Bingham, m: *mut f64, z: *mut f64) {
    let mr = b.m_row_major();
    // SAFETY: forwarded caller contract; lengths d*d and d.
    unsafe {
        write(m, &mr);
        write(z, b.z().as_slice());
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
    need("z", z)?;
    need("log_f", log_f)?;
    let want_grad = optional("dlog_f", dlog_f)?;
    // SAFETY: caller contract.
    let zs = unsafe { read("z", z, d)? };
    let mut grad = [0.0; crate::error::MAX_DIM];
    let lf = log_normalization_into(zs, method, want_grad.then_some(&mut grad[..d]), None)?;
    // SAFETY: pointers checked; lengths 1 and d per the contract.
    unsafe {
        write1(log_f, lf);
        if want_grad {
            write(dlog_f, &grad[..d]);
        }
    }
    Ok(())
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
        need("z", z)?;
        need("f", f)?;
        let want_grad = optional("df", df)?;
        // SAFETY: caller contract.
        let zs = unsafe { read("z", z, d)? };
        let mut grad = [0.0; crate::error::MAX_DIM];
        let lf = log_normalization_into(zs, Method::Exact, Some(&mut grad[..d]), None)?;
        let value = lf.exp();
        if !value.is_normal() {
            return Err(Failure::new(
                bingham_status::BINGHAM_ERR_NUMERICAL,
                format!(
                    "F = exp({lf:.6e}) is not representable as a double (overflow or underflow); \
                     use bingham_log_normalization_constant"
                ),
            ));
        }
        let dfv: Vec<f64> = grad[..d].iter().map(|w| value * w).collect();
        // SAFETY: pointers checked; lengths 1 and d per the contract.
        unsafe {
            write1(f, value);
            if want_grad {
                write(df, &dfv);
            }
        }
        Ok(())
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
/// - `dlog_f`: `NULL`, or receives ∂ log F/∂z_i = E[x_i²] (in the principal frame), in the order
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
        need("z", z)?;
        need("log_f", log_f)?;
        let want_grad = optional("dlog_f", dlog_f)?;
        need("d2log_f", d2log_f)?;
        // SAFETY: caller contract.
        let zs = unsafe { read("z", z, d)? };
        let mut grad = vec![0.0; d];
        let mut hess = vec![0.0; d * d];
        let lf = log_normalization_into(zs, Method::Exact, Some(&mut grad), Some(&mut hess))?;
        // SAFETY: pointers checked; lengths 1, d, d*d per the contract.
        unsafe {
            write1(log_f, lf);
            if want_grad {
                write(dlog_f, &grad);
            }
            write(d2log_f, &hess);
        }
        Ok(())
    })
}

/// The second moment `S = E[x xᵀ] = M diag(ω) Mᵀ` of Bingham(M, Z) (the covariance, as E[x] = 0),
/// with ω_i = ∂ log F/∂z_i; trace S = 1.
///
/// - `d`: 2..64.
/// - `m`: d×d row-major orthogonal matrix (max |MᵀM − I| ≤ `BINGHAM_ORTHOGONALITY_TOL`), columns
///   are the principal directions.
/// - `z`: d concentrations, column i of `m` belongs to `z[i]`; any order and shift.
/// - `s`: receives S, d×d row-major, symmetric.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION`, `BINGHAM_ERR_NULL_ARGUMENT`,
/// `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf, M not orthogonal), `BINGHAM_ERR_NUMERICAL`.
/// On error nothing is written.
///
/// # Safety
/// `m`: d*d and `z`: d readable doubles; `s`: d*d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_second_moment(
    d: usize,
    m: *const f64,
    z: *const f64,
    s: *mut f64,
) -> bingham_status {
    guard("bingham_second_moment", || {
        dim(d)?;
        need("m", m)?;
        need("z", z)?;
        need("s", s)?;
        // SAFETY: caller contract.
        let b = unsafe { distribution(d, "m", m, "z", z)? };
        let sm = b.second_moment()?.transpose(); // column-major storage of the transpose = row-major
                                                 // SAFETY: pointer checked; length d*d.
        unsafe { write(s, sm.as_slice()) };
        Ok(())
    })
}

/// Maximum-likelihood (moment-matching) Bingham distribution for a second-moment matrix S.
///
/// Finds M, Z with `E[x xᵀ] = S`: M from the eigenvectors of S, Z by solving ω(Z) = eigenvalues
/// of S. This is the MLE for samples whose scatter matrix is S.
///
/// - `d`: 2..64.
/// - `s`: d×d row-major, symmetric (up to rounding), positive semi-definite, non-zero. It is
///   normalized by its trace, so any positive multiple of E[x xᵀ] (e.g. Σ w_k x_k x_kᵀ) works.
/// - `m`: receives the d×d row-major orthogonal M (columns: eigenvectors of S, ascending
///   eigenvalues; the last column is the mode). Column signs are arbitrary.
/// - `z`: receives the d concentrations, ascending, z[d-1] = 0. Eigenvalues of S near 0 give
///   very negative z (large concentration); equal eigenvalues give equal z.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION`, `BINGHAM_ERR_NULL_ARGUMENT`,
/// `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf, not symmetric PSD, zero trace),
/// `BINGHAM_ERR_NOT_CONVERGED`, `BINGHAM_ERR_NUMERICAL`. On error nothing is written.
///
/// # Safety
/// `s`: d*d readable doubles; `m`: d*d and `z`: d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_mle(
    d: usize,
    s: *const f64,
    m: *mut f64,
    z: *mut f64,
) -> bingham_status {
    guard("bingham_mle", || {
        dim(d)?;
        need("s", s)?;
        need("m", m)?;
        need("z", z)?;
        // SAFETY: caller contract.
        let ss = unsafe { read("s", s, d * d)? };
        let b = mle_from_second_moment(&DMatrix::from_row_slice(d, d, ss))?;
        // SAFETY: pointers checked; lengths d*d and d.
        unsafe { write_distribution(&b, m, z) };
        Ok(())
    })
}

/// Maximum-likelihood Bingham distribution for (optionally weighted) samples on the sphere.
///
/// Equivalent to `bingham_mle()` of the scatter matrix `Σ w_k x_k x_kᵀ / Σ w_k`.
///
/// - `d`: 2..64; `n`: number of samples, ≥ 1.
/// - `x`: n×d row-major, each row a unit vector (|‖x_k‖ − 1| ≤ `BINGHAM_UNIT_TOL`). Antipodal
///   points are equivalent.
/// - `w`: `NULL` (equal weights) or n weights, all ≥ 0 with a positive sum.
/// - `m`, `z`: receive the fit, as in `bingham_mle()`.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION` (d; n*d overflow), `BINGHAM_ERR_NULL_ARGUMENT`,
/// `BINGHAM_ERR_INVALID_ARGUMENT` (n = 0, NaN/Inf, non-unit row, bad weights),
/// `BINGHAM_ERR_NOT_CONVERGED`, `BINGHAM_ERR_NUMERICAL`. On error nothing is written.
///
/// # Safety
/// `x`: n*d readable doubles; `w`: `NULL` or n readable doubles; `m`: d*d and `z`: d writable
/// doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_mle_samples(
    d: usize,
    n: usize,
    x: *const f64,
    w: *const f64,
    m: *mut f64,
    z: *mut f64,
) -> bingham_status {
    guard("bingham_mle_samples", || {
        dim(d)?;
        let nd = len2("x", n, d)?;
        if n == 0 {
            return Err(Failure::argument("n = 0: at least one sample is needed"));
        }
        need("x", x)?;
        let has_w = optional("w", w)?;
        need("m", m)?;
        need("z", z)?;
        // SAFETY: caller contract.
        let xs = unsafe { read("x", x, nd)? };
        let ws = if has_w {
            // SAFETY: caller contract.
            Some(unsafe { read("w", w, n)? })
        } else {
            None
        };
        let b = mle_from_samples(d, xs, ws)?;
        // SAFETY: pointers checked; lengths d*d and d.
        unsafe { write_distribution(&b, m, z) };
        Ok(())
    })
}

/// Product of two Bingham densities (Bayes' rule), renormalized:
/// `f1(x) f2(x) ∝ Bingham(M, Z)` with `M Z Mᵀ = eig(M1 Z1 M1ᵀ + M2 Z2 M2ᵀ)`. Exact.
///
/// - `d`: 2..64.
/// - `m1`, `z1`, `m2`, `z2`: the two factors (d×d row-major orthogonal, length d; any order and
///   shift of z).
/// - `m`, `z`: receive the product, z ascending with z[d-1] = 0, the last column of `m` the mode.
///   May be the same arrays as `m1`/`z1` or `m2`/`z2` (in-place update).
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION`, `BINGHAM_ERR_NULL_ARGUMENT`,
/// `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf, M not orthogonal), `BINGHAM_ERR_NUMERICAL`.
/// On error nothing is written.
///
/// # Safety
/// `m1`, `m2`: d*d and `z1`, `z2`: d readable doubles; `m`: d*d and `z`: d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_multiply(
    d: usize,
    m1: *const f64,
    z1: *const f64,
    m2: *const f64,
    z2: *const f64,
    m: *mut f64,
    z: *mut f64,
) -> bingham_status {
    guard("bingham_multiply", || {
        // SAFETY: forwarded caller contract.
        unsafe { binary(d, m1, z1, m2, z2, m, z, |a, b| a.multiply(b)) }
    })
}

/// Composition (the distribution of `x ⊕ y` for independent x ~ (m1, z1), y ~ (m2, z2)),
/// approximated by the Bingham distribution with the same second moment (moment matching;
/// the composed moment itself is exact). d = 2 and d = 4 only.
///
/// `⊕` is complex multiplication for d = 2 (x = (re, im)) and the Hamilton product for d = 4 with
/// **scalar-first** quaternions (w, x, y, z): `x ⊕ y = L(x) y`. Used for the prediction step of
/// the Bingham filter (state ⊕ noise).
///
/// Arguments as for `bingham_multiply()`; outputs may alias inputs.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION` (d not 2 or 4), `BINGHAM_ERR_NULL_ARGUMENT`,
/// `BINGHAM_ERR_INVALID_ARGUMENT`, `BINGHAM_ERR_NOT_CONVERGED`, `BINGHAM_ERR_NUMERICAL`.
/// On error nothing is written.
///
/// # Safety
/// `m1`, `m2`: d*d and `z1`, `z2`: d readable doubles; `m`: d*d and `z`: d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_compose(
    d: usize,
    m1: *const f64,
    z1: *const f64,
    m2: *const f64,
    z2: *const f64,
    m: *mut f64,
    z: *mut f64,
) -> bingham_status {
    guard("bingham_compose", || {
        // SAFETY: forwarded caller contract.
        unsafe { binary(d, m1, z1, m2, z2, m, z, |a, b| a.compose(b)) }
    })
}

/// Shared body of `bingham_multiply` and `bingham_compose`.
///
/// # Safety
/// Caller contract of the exported functions.
#[allow(clippy::too_many_arguments)]
unsafe fn binary(
    d: usize,
    m1: *const f64,
    z1: *const f64,
    m2: *const f64,
    z2: *const f64,
    m: *mut f64,
    z: *mut f64,
    op: impl FnOnce(&Bingham, &Bingham) -> crate::error::Result<Bingham>,
) -> FfiResult<()> {
    dim(d)?;
    need("m1", m1)?;
    need("z1", z1)?;
    need("m2", m2)?;
    need("z2", z2)?;
    need("m", m)?;
    need("z", z)?;
    // SAFETY: caller contract of the exported function (lengths d*d and d).
    let (a, b) = unsafe {
        (
            distribution(d, "m1", m1, "z1", z1)?,
            distribution(d, "m2", m2, "z2", z2)?,
        )
    };
    let r = op(&a, &b)?;
    // SAFETY: pointers checked; lengths d*d and d.
    unsafe { write_distribution(&r, m, z) };
    Ok(())
}

/// Shared body of `bingham_pdf` and `bingham_log_pdf`.
///
/// # Safety
/// Caller contract of the exported functions.
#[allow(clippy::too_many_arguments)]
unsafe fn pointwise(
    d: usize,
    m: *const f64,
    z: *const f64,
    n: usize,
    x: *const f64,
    p_name: &str,
    p: *mut f64,
    f: impl Fn(f64) -> f64,
) -> FfiResult<()> {
    dim(d)?;
    let nd = len2("x", n, d)?;
    need("m", m)?;
    need("z", z)?;
    if n > 0 {
        need("x", x)?;
        need(p_name, p)?;
    }
    // SAFETY: caller contract.
    let b = unsafe { distribution(d, "m", m, "z", z)? };
    // SAFETY: caller contract.
    let xs = unsafe { read("x", x, nd)? };
    let mut values = Vec::new();
    values.try_reserve_exact(n).map_err(|_| {
        Failure::new(
            bingham_status::BINGHAM_ERR_NUMERICAL,
            format!("cannot allocate memory for n = {n} values"),
        )
    })?;
    // One normalization for all points.
    let log_f = if n > 0 { b.log_normalization()? } else { 0.0 };
    for (i, row) in xs.chunks_exact(d).enumerate() {
        let v = b
            .log_pdf_given(row, log_f)
            .map_err(|e| Failure::from(e).context(format_args!("x row {i}")))?;
        values.push(f(v));
    }
    if n > 0 {
        // SAFETY: p checked non-NULL; n writable doubles.
        unsafe { write(p, &values) };
    }
    Ok(())
}

/// The density `f(x) = exp(xᵀ M Z Mᵀ x) / F(Z)` at n points, with respect to the surface measure
/// of S^{d-1} (so it integrates to 1 over the sphere; for d = 2 it is a density in the angle).
///
/// - `d`: 2..64; `m`, `z`: the distribution (d×d row-major orthogonal, length d).
/// - `n`: number of points (0 is allowed: nothing is done, `x` and `p` may then be `NULL`).
/// - `x`: n×d row-major, each row a unit vector (|‖x‖ − 1| ≤ `BINGHAM_UNIT_TOL`).
/// - `p`: receives the n densities. May overflow to +Inf for extreme concentrations: use
///   `bingham_log_pdf()` there.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION` (d; n*d overflow), `BINGHAM_ERR_NULL_ARGUMENT`,
/// `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf, M not orthogonal, a row not unit: the message names
/// the row), `BINGHAM_ERR_NUMERICAL`. All points are checked before anything is written.
///
/// # Safety
/// `m`: d*d and `z`: d readable doubles; `x`: n*d readable doubles; `p`: n writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_pdf(
    d: usize,
    m: *const f64,
    z: *const f64,
    n: usize,
    x: *const f64,
    p: *mut f64,
) -> bingham_status {
    guard("bingham_pdf", || {
        // SAFETY: forwarded caller contract.
        unsafe { pointwise(d, m, z, n, x, "p", p, f64::exp) }
    })
}

/// The natural logarithm of the density, `xᵀ M Z Mᵀ x − log F(Z)`, at n points; finite for every
/// finite input. Arguments, errors and safety as for `bingham_pdf()`, with `log_p` for `p`.
///
/// # Safety
/// `m`: d*d and `z`: d readable doubles; `x`: n*d readable doubles; `log_p`: n writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_log_pdf(
    d: usize,
    m: *const f64,
    z: *const f64,
    n: usize,
    x: *const f64,
    log_p: *mut f64,
) -> bingham_status {
    guard("bingham_log_pdf", || {
        // SAFETY: forwarded caller contract.
        unsafe { pointwise(d, m, z, n, x, "log_p", log_p, |v| v) }
    })
}

/// Differential entropy `H = −E[log f(x)] = log F(Z) − Σ z_i ω_i` in nats, with respect to the
/// surface measure (H = log |S^{d-1}| for the uniform distribution; negative for concentrated
/// ones).
///
/// - `d`, `m`, `z`: the distribution; `h`: receives H.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION`, `BINGHAM_ERR_NULL_ARGUMENT`,
/// `BINGHAM_ERR_INVALID_ARGUMENT`, `BINGHAM_ERR_NUMERICAL`. On error nothing is written.
///
/// # Safety
/// `m`: d*d and `z`: d readable doubles; `h`: one writable double.
#[no_mangle]
pub unsafe extern "C" fn bingham_entropy(
    d: usize,
    m: *const f64,
    z: *const f64,
    h: *mut f64,
) -> bingham_status {
    guard("bingham_entropy", || {
        dim(d)?;
        need("m", m)?;
        need("z", z)?;
        need("h", h)?;
        // SAFETY: caller contract.
        let b = unsafe { distribution(d, "m", m, "z", z)? };
        let value = b.entropy()?;
        // SAFETY: pointer checked.
        unsafe { write1(h, value) };
        Ok(())
    })
}

/// Kullback–Leibler divergence `KL(p1 ‖ p2) = E_{p1}[log p1(x) − log p2(x)] ≥ 0` in nats, between
/// p1 = Bingham(m1, z1) and p2 = Bingham(m2, z2) of the same dimension.
///
/// - `d`: 2..64; `m1`, `z1`, `m2`, `z2`: the two distributions; `kl`: receives the divergence.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION`, `BINGHAM_ERR_NULL_ARGUMENT`,
/// `BINGHAM_ERR_INVALID_ARGUMENT`, `BINGHAM_ERR_NUMERICAL`. On error nothing is written.
///
/// # Safety
/// `m1`, `m2`: d*d and `z1`, `z2`: d readable doubles; `kl`: one writable double.
#[no_mangle]
pub unsafe extern "C" fn bingham_kl_divergence(
    d: usize,
    m1: *const f64,
    z1: *const f64,
    m2: *const f64,
    z2: *const f64,
    kl: *mut f64,
) -> bingham_status {
    guard("bingham_kl_divergence", || {
        dim(d)?;
        need("m1", m1)?;
        need("z1", z1)?;
        need("m2", m2)?;
        need("z2", z2)?;
        need("kl", kl)?;
        // SAFETY: caller contract.
        let (a, b) = unsafe {
            (
                distribution(d, "m1", m1, "z1", z1)?,
                distribution(d, "m2", m2, "z2", z2)?,
            )
        };
        let value = a.kl_divergence(&b)?;
        // SAFETY: pointer checked.
        unsafe { write1(kl, value) };
        Ok(())
    })
}

/// Draws n independent samples from Bingham(M, Z).
///
/// Deterministic: the same `seed` gives the same samples with the same library version (the
/// generator may change between versions). Thread-safe; there is no global random state.
///
/// - `d`, `m`, `z`: the distribution.
/// - `seed`: any 64-bit value.
/// - `n`: number of samples (0 allowed: nothing is done, `x_out` may be `NULL`).
/// - `x_out`: receives n×d row-major unit vectors. The sign of each sample is arbitrary
///   (x and −x are equally likely).
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION` (d; n*d overflow), `BINGHAM_ERR_NULL_ARGUMENT`,
/// `BINGHAM_ERR_INVALID_ARGUMENT`, `BINGHAM_ERR_NUMERICAL`. On error nothing is written.
///
/// # Safety
/// `m`: d*d and `z`: d readable doubles; `x_out`: n*d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_sample(
    d: usize,
    m: *const f64,
    z: *const f64,
    seed: u64,
    n: usize,
    x_out: *mut f64,
) -> bingham_status {
    guard("bingham_sample", || {
        dim(d)?;
        let nd = len2("x_out", n, d)?;
        need("m", m)?;
        need("z", z)?;
        if n > 0 {
            need("x_out", x_out)?;
        }
        // SAFETY: caller contract.
        let b = unsafe { distribution(d, "m", m, "z", z)? };
        let mut rng = StdRng::seed_from_u64(seed);
        // Collect into one buffer, drawing in chunks to bound the peak memory; an allocation
        // failure (absurd n) is reported instead of aborting the process.
        let mut flat = Vec::new();
        flat.try_reserve_exact(nd).map_err(|_| {
            Failure::new(
                bingham_status::BINGHAM_ERR_NUMERICAL,
                format!("cannot allocate memory for n = {n} samples"),
            )
        })?;
        const CHUNK: usize = 4096;
        let mut left = n;
        while left > 0 {
            let k = left.min(CHUNK);
            for v in b.sample(&mut rng, k) {
                flat.extend_from_slice(v.as_slice());
            }
            left -= k;
        }
        if flat.len() != nd || flat.iter().any(|v| !v.is_finite()) {
            return Err(Failure::new(
                bingham_status::BINGHAM_ERR_NUMERICAL,
                "the sampler produced an unusable result",
            ));
        }
        if n > 0 {
            // SAFETY: pointer checked; n*d writable doubles.
            unsafe { write(x_out, &flat) };
        }
        Ok(())
    })
}

/// Shared body of the rotations.
///
/// # Safety
/// Caller contract of the exported functions.
#[allow(clippy::too_many_arguments)]
unsafe fn rotate(
    d: usize,
    m: *const f64,
    z: *const f64,
    u: *const f64,
    m_out: *mut f64,
    z_out: *mut f64,
    op: impl FnOnce(&Bingham, &[f64]) -> crate::error::Result<Bingham>,
) -> FfiResult<()> {
    dim(d)?;
    need("m", m)?;
    need("z", z)?;
    need("u", u)?;
    need("m_out", m_out)?;
    need("z_out", z_out)?;
    // SAFETY: caller contract.
    let b = unsafe { distribution(d, "m", m, "z", z)? };
    // SAFETY: caller contract.
    let us = unsafe { read("u", u, d)? };
    let r = op(&b, us)?;
    // SAFETY: pointers checked; lengths d*d and d.
    unsafe { write_distribution(&r, m_out, z_out) };
    Ok(())
}

/// The distribution of `u ⊕ x` for x ~ Bingham(M, Z) and a fixed unit `u`: Bingham(L(u) M, Z).
/// Exact. d = 2 (complex (re, im)) and d = 4 (quaternion, **scalar first** (w, x, y, z)) only.
///
/// - `d`: 2 or 4; `m`, `z`: the distribution; `u`: d entries, unit length
///   (|‖u‖ − 1| ≤ `BINGHAM_UNIT_TOL`).
/// - `m_out`, `z_out`: receive the rotated distribution (z sorted, shifted; may alias `m`, `z`).
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION` (d not 2 or 4), `BINGHAM_ERR_NULL_ARGUMENT`,
/// `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf, M not orthogonal, u not unit). On error nothing is
/// written.
///
/// # Safety
/// `m`: d*d, `z` and `u`: d readable doubles; `m_out`: d*d and `z_out`: d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_rotate_left(
    d: usize,
    m: *const f64,
    z: *const f64,
    u: *const f64,
    m_out: *mut f64,
    z_out: *mut f64,
) -> bingham_status {
    guard("bingham_rotate_left", || {
        // SAFETY: forwarded caller contract.
        unsafe { rotate(d, m, z, u, m_out, z_out, |b, u| b.rotate_left(u)) }
    })
}

/// The distribution of `x ⊕ u` for x ~ Bingham(M, Z) and a fixed unit `u`: Bingham(R(u) M, Z)
/// with `x ⊕ u = R(u) x`. Exact. d = 2 and d = 4 only; arguments, errors and safety as for
/// `bingham_rotate_left()`.
///
/// # Safety
/// `m`: d*d, `z` and `u`: d readable doubles; `m_out`: d*d and `z_out`: d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_rotate_right(
    d: usize,
    m: *const f64,
    z: *const f64,
    u: *const f64,
    m_out: *mut f64,
    z_out: *mut f64,
) -> bingham_status {
    guard("bingham_rotate_right", || {
        // SAFETY: forwarded caller contract.
        unsafe { rotate(d, m, z, u, m_out, z_out, |b, u| b.rotate_right(u)) }
    })
}

/// The mode of Bingham(M, Z): the unit principal direction with the largest z (the last column of
/// M after sorting). The distribution is antipodally symmetric, so `-mode` is a mode as well; if
/// the largest z is repeated, the mode is not unique and one of them is returned.
///
/// - `d`, `m`, `z`: the distribution; `mode`: receives d doubles, a unit vector.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION`, `BINGHAM_ERR_NULL_ARGUMENT`,
/// `BINGHAM_ERR_INVALID_ARGUMENT`. On error nothing is written.
///
/// # Safety
/// `m`: d*d and `z`: d readable doubles; `mode`: d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_mode(
    d: usize,
    m: *const f64,
    z: *const f64,
    mode: *mut f64,
) -> bingham_status {
    guard("bingham_mode", || {
        dim(d)?;
        need("m", m)?;
        need("z", z)?;
        need("mode", mode)?;
        // SAFETY: caller contract.
        let b = unsafe { distribution(d, "m", m, "z", z)? };
        let v = b.mode();
        // SAFETY: pointer checked; d writable doubles.
        unsafe { write(mode, v.as_slice()) };
        Ok(())
    })
}

/// The likelihood of a measured direction as a Bingham distribution of the orientation (d = 4).
///
/// A sensor measures the unit direction `body` (sensor frame) of the known unit direction
/// `reference` (world frame), with von Mises–Fisher noise of concentration `kappa` (for small
/// noise, `kappa ≈ 1/σ²` with σ the angular standard deviation in radians) on the measured
/// direction. Orientation convention: the unit quaternion q (scalar first) maps sensor to world,
/// `v_world = q v_sensor q*`, rotation matrix `R(q)`. The likelihood
/// `p(b | q) ∝ exp(kappa rᵀ R(q) b) = exp(qᵀ (kappa K) q)` is a Bingham density in q, with K
/// Davenport's 4×4 matrix of the pair (symmetric, traceless, eigenvalues −1, −1, 1, 1).
///
/// - `body`, `reference`: 3 doubles each, unit norm within `BINGHAM_UNIT_TOL` (then normalized).
/// - `kappa`: finite, ≥ 0 (0 gives the uniform distribution).
/// - `m`: receives the 4×4 row-major M (the eigenvectors of K; the last two columns span the
///   rotations that map `body` onto `reference`); `z`: receives `(−2 kappa, −2 kappa, 0, 0)`.
///   The rotation about `reference` is not observed: the distribution is flat along it.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT`, `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf, non-unit
/// vector, `kappa` negative or not finite). On error nothing is written.
///
/// # Safety
/// `body`, `reference`: 3 readable doubles each; `m`: 16 and `z`: 4 writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_vector_observation(
    body: *const f64,
    reference: *const f64,
    kappa: f64,
    m: *mut f64,
    z: *mut f64,
) -> bingham_status {
    guard("bingham_vector_observation", || {
        need("body", body)?;
        need("reference", reference)?;
        need("m", m)?;
        need("z", z)?;
        // SAFETY: caller contract; 3 doubles each.
        let (b, r) = unsafe { (read("body", body, 3)?, read("reference", reference, 3)?) };
        let obs = crate::observation::vector_observation(b, r, kappa)?;
        // SAFETY: pointers checked; lengths 16 and 4.
        unsafe { write_distribution(&obs, m, z) };
        Ok(())
    })
}

/// Isotropic rotation noise with angular standard deviation `sigma` (radians) as a Bingham
/// distribution with its mode at the identity: the distribution to pass as process noise
/// (`m_w`, `z_w`) or measurement noise.
///
/// - d = 4: the rotation by a Gaussian rotation vector with standard deviation `sigma` per axis,
///   as a quaternion (scalar first); d = 2: the unit complex number `(cos a, sin a)` with a
///   Gaussian angle a of standard deviation `sigma`.
/// - The result has exactly that distribution's second moment (closed form; for d = 4
///   `E[cos θ] = (1 − σ²) exp(−σ²/2)` of the rotation angle θ) and is its moment-matched
///   (maximum-likelihood) Bingham fit. For small sigma, z ≈ −2/σ² (d = 4), −1/(2σ²) (d = 2).
/// - `m`: receives d×d row-major M, last column the identity `(1, 0, …)`; `z`: d concentrations,
///   ascending, `z[d-1] = 0`.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION` (d not 2 or 4), `BINGHAM_ERR_NULL_ARGUMENT`,
/// `BINGHAM_ERR_INVALID_ARGUMENT` (`sigma` ≤ 0, not finite, or below about 6e-7 rad, where the
/// concentration leaves the MLE's range). On error nothing is written.
///
/// # Safety
/// `m`: d*d and `z`: d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_noise_from_angle_std(
    d: usize,
    sigma: f64,
    m: *mut f64,
    z: *mut f64,
) -> bingham_status {
    guard("bingham_noise_from_angle_std", || {
        if d != 2 && d != 4 {
            return Err(Failure::dimension(format!(
                "rotation noise exists for d = 2 and d = 4, got d = {d}"
            )));
        }
        need("m", m)?;
        need("z", z)?;
        let b = crate::observation::noise_from_angle_std(d, sigma)?;
        // SAFETY: pointers checked; lengths d*d and d.
        unsafe { write_distribution(&b, m, z) };
        Ok(())
    })
}

/// The angular spread (radians) of a Bingham distribution of axes (d = 2) or rotations (d = 4,
/// quaternions): an uncertainty readout with an exact meaning.
///
/// With ω the moments (`ω_i = E[(m_iᵀ x)²]`, m_i column i of M after normalization, ascending)
/// and k = 2 for d = 4, k = 1 for d = 2:
/// - `spread[i]`, i < d − 1: `k sqrt(ω_i)`, the spread along principal direction i (for d = 4:
///   the RMS of the rotation's component about the axis of column i, in the `2 sin(θ/2)` sense);
/// - `spread[d-1]`: the total, `k sqrt(1 − ω_{d-1})`. For d = 4 this is exactly the RMS of
///   `2 sin(θ/2)`, θ the rotation angle between x and the mode; for d = 2 the RMS of `sin α`,
///   α the angle between the axes. To second order both are the RMS angle (a distribution with
///   RMS angle 5° reads 5°). The squares of the per-axis values add up to the total's square.
///
/// - `m`, `z`: the distribution (as everywhere); `spread`: receives d doubles.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION` (d not 2 or 4), `BINGHAM_ERR_NULL_ARGUMENT`,
/// `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf, M not orthogonal). On error nothing is written.
///
/// # Safety
/// `m`: d*d and `z`: d readable doubles; `spread`: d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_angular_spread(
    d: usize,
    m: *const f64,
    z: *const f64,
    spread: *mut f64,
) -> bingham_status {
    guard("bingham_angular_spread", || {
        if d != 2 && d != 4 {
            return Err(Failure::dimension(format!(
                "the angular spread exists for d = 2 and d = 4, got d = {d}"
            )));
        }
        need("m", m)?;
        need("z", z)?;
        need("spread", spread)?;
        // SAFETY: caller contract.
        let b = unsafe { distribution(d, "m", m, "z", z)? };
        let s = crate::observation::angular_spread(&b)?;
        // SAFETY: pointer checked; length d.
        unsafe { write(spread, &s) };
        Ok(())
    })
}
