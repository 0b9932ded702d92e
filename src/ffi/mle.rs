//! Maximum-likelihood fits of the C API, over [`crate::mle`]: `bingham_mle` (from a second
//! moment) and `bingham_mle_samples` (from points on the sphere). Thin wrappers: check `d`, `n`
//! and the pointers, read the inputs, call the core, copy the fitted distribution out.

use nalgebra::DMatrix;

use super::args::{args, Arg};
use super::guard::{dim, guard, len2, Failure};
use super::status::bingham_status;
use crate::mle::{mle_from_samples, mle_from_second_moment};

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
        // SAFETY: caller contract.
        let (ss, out) = unsafe { args!(s: [d * d], (m, z): out bingham).read()? };
        let b = mle_from_second_moment(&DMatrix::from_row_slice(d, d, ss))?;
        // SAFETY: every input has been read; lengths d*d and d.
        unsafe { out.write(&b) };
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
        // SAFETY: caller contract.
        let (xs, ws, out) = unsafe { args!(x: [nd], w: opt [n], (m, z): out bingham).read()? };
        let b = mle_from_samples(d, xs, ws)?;
        // SAFETY: every input has been read; lengths d*d and d.
        unsafe { out.write(&b) };
        Ok(())
    })
}
