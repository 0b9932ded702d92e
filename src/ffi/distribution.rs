//! The functions of a distribution `(m, z)` in the C API, over [`crate::distribution::Bingham`]:
//! its second moment, products and compositions of two distributions, density, entropy,
//! Kullback–Leibler divergence, random samples, rotations and mode. Thin wrappers: check `d`
//! and the pointers, read and validate the distributions, call the core, copy the results out.

use rand::rngs::StdRng;
use rand::SeedableRng;

use super::args::{args, Arg, Output, Store};
use super::guard::{dim, guard, len2, Failure, FfiResult};
use super::status::bingham_status;
use crate::distribution::Bingham;

/// The second moment `S = E[x xᵀ] = M diag(ω) Mᵀ` of Bingham(M, Z) (the covariance, as `E[x] = 0`),
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
        // SAFETY: caller contract.
        let (b, s) = unsafe { args!((m, z): bingham [d], s: out [d * d]).read()? };
        // column-major storage of the transpose = row-major
        let sm = b.second_moment()?.transpose();
        // SAFETY: every input has been read; length d*d.
        unsafe { s.write(sm.as_slice()) };
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
        let out = args!((m, z): out bingham);
        // SAFETY: forwarded caller contract.
        unsafe { binary(d, m1, z1, m2, z2, out, Bingham::multiply) }
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
        let out = args!((m, z): out bingham);
        // SAFETY: forwarded caller contract.
        unsafe { binary(d, m1, z1, m2, z2, out, Bingham::compose) }
    })
}

/// Shared body of the functions of two distributions (`bingham_multiply`, `bingham_compose`,
/// `bingham_kl_divergence`): checks `d`, the pointers of both distributions and then those of
/// `out`, reads the distributions, and stores the result of `op` in `out`.
///
/// # Safety
/// Caller contract of the exported functions.
unsafe fn binary<O: Arg, V>(
    d: usize,
    m1: *const f64,
    z1: *const f64,
    m2: *const f64,
    z2: *const f64,
    out: O,
    op: impl FnOnce(&Bingham, &Bingham) -> crate::error::Result<V>,
) -> FfiResult<()>
where
    O::Value: Store<V>,
{
    dim(d)?;
    // SAFETY: caller contract of the exported function (lengths d*d and d).
    let ((a, b), out) =
        unsafe { (args!((m1, z1): bingham [d], (m2, z2): bingham [d]), out).read()? };
    let r = op(&a, &b)?;
    // SAFETY: every input has been read.
    unsafe { out.store(r) };
    Ok(())
}

/// Shared body of `bingham_pdf` and `bingham_log_pdf`; `p` is their output (n doubles, required
/// when n > 0).
///
/// # Safety
/// Caller contract of the exported functions.
unsafe fn pointwise(
    d: usize,
    m: *const f64,
    z: *const f64,
    n: usize,
    x: *const f64,
    p: impl Arg<Value = (Option<Output>,)>,
    f: impl Fn(f64) -> f64,
) -> FfiResult<()> {
    dim(d)?;
    let nd = len2("x", n, d)?;
    // SAFETY: caller contract.
    let ((b, xs), (p,)) = unsafe { (args!((m, z): bingham [d], x: [nd] if n > 0), p).read()? };
    let mut values = Vec::new();
    values.try_reserve_exact(n).map_err(|_| {
        Failure::new(
            bingham_status::BINGHAM_ERR_NUMERICAL,
            format!("cannot allocate memory for n = {n} values"),
        )
    })?;
    // One normalization for all points.
    let log_f = if n > 0 { b.log_normalization()? } else { 0.0 };
    for (i, row) in xs.unwrap_or_default().chunks_exact(d).enumerate() {
        let v = b
            .log_pdf_given(row, log_f)
            .map_err(|e| Failure::from(e).context(format_args!("x row {i}")))?;
        values.push(f(v));
    }
    if let Some(p) = p {
        // SAFETY: every input has been read; n values.
        unsafe { p.write(&values) };
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
        unsafe { pointwise(d, m, z, n, x, args!(p: out [n] if n > 0), f64::exp) }
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
        unsafe { pointwise(d, m, z, n, x, args!(log_p: out [n] if n > 0), |v| v) }
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
        // SAFETY: caller contract.
        let (b, h) = unsafe { args!((m, z): bingham [d], h: out).read()? };
        let value = b.entropy()?;
        // SAFETY: every input has been read.
        unsafe { h.set(value) };
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
        // SAFETY: forwarded caller contract.
        unsafe { binary(d, m1, z1, m2, z2, args!(kl: out), Bingham::kl_divergence) }
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
        // SAFETY: caller contract.
        let (b, x_out) = unsafe { args!((m, z): bingham [d], x_out: out [nd] if n > 0).read()? };
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
        if let Some(x_out) = x_out {
            // SAFETY: every input has been read; n*d values.
            unsafe { x_out.write(&flat) };
        }
        Ok(())
    })
}

/// Shared body of the rotations.
///
/// # Safety
/// Caller contract of the exported functions.
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
    // SAFETY: caller contract.
    let (b, us, out) =
        unsafe { args!((m, z): bingham [d], u: [d], (m_out, z_out): out bingham).read()? };
    let r = op(&b, us)?;
    // SAFETY: every input has been read; lengths d*d and d.
    unsafe { out.write(&r) };
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
        // SAFETY: caller contract.
        let (b, mode) = unsafe { args!((m, z): bingham [d], mode: out [d]).read()? };
        let v = b.mode();
        // SAFETY: every input has been read; d values.
        unsafe { mode.write(v.as_slice()) };
        Ok(())
    })
}
