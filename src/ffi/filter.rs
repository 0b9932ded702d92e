//! The recursive Bingham filter behind the opaque handle `bingham_filter` (the C side of
//! [`crate::filter::BinghamFilter`]). Thin wrappers: check pointers, read and validate the
//! inputs, call the core, copy results out. The core computes every new state completely before
//! it assigns it, so a failed call leaves the filter exactly as it was.

use super::args::{args, get_into, Arg, ArrayIn, Store};
use super::guard::{free_handle, guard, handle, handle_mut, Failure, FfiResult};
use super::status::bingham_status;
use crate::filter::BinghamFilter;

/// Concentrations of the state and of the process noise below `-BINGHAM_FILTER_MAX_CONCENTRATION`
/// are raised to it before a prediction (see `bingham_filter_predict()`); an angular spread of
/// about 7 microradians.
pub const BINGHAM_FILTER_MAX_CONCENTRATION: f64 = 1e10;

/// A recursive Bingham filter for axes in the plane (d = 2) or orientations in space (d = 4,
/// unit quaternions, scalar first), after Kurz, Gilitschenski, Julier & Hanebeck (JAIF 2014).
///
/// An opaque handle: create it with `bingham_filter_new()` (or `bingham_filter_clone()`),
/// release it with `bingham_filter_free()`. The caller owns it.
///
/// System model `x[k+1] = x[k] (+) w[k]`, measurement model `z[k] = x[k] (+) v[k]`, where `(+)` is
/// complex multiplication (d = 2, vectors `(re, im)`) or the Hamilton product (d = 4, quaternions
/// `(w, x, y, z)`), and the noises `w`, `v` are Bingham distributed. The state is a Bingham
/// distribution `(M, z)`: M is d x d row-major with orthonormal columns, the last column is the
/// mode (the estimate; its negative is the same axis / rotation); z ascending with `z[d-1] = 0`.
///
/// Thread safety: a handle may be used by one thread at a time (functions that take a
/// `bingham_filter *` modify it; functions taking `const bingham_filter *` may run concurrently
/// with each other on the same handle). Different handles are fully independent; the library
/// has no global mutable state.
///
/// Memory: after the first prediction and update with given noise parameters, the filter steps
/// perform no heap allocation. The noise parameters are cached inside the handle (keyed on their
/// exact bit patterns), so passing the same noise arrays every step costs nothing extra.
#[allow(non_camel_case_types)]
pub struct bingham_filter {
    pub(super) inner: BinghamFilter,
}

/// Creates a filter with the initial estimate `Bingham(m0, z0)`.
///
/// - `d`: 2 (axes: complex numbers `(re, im)`) or 4 (unit quaternions, scalar first
///   `(w, x, y, z)`). Checked before any array is read.
/// - `m0`: d x d row-major orthogonal matrix (max |MᵀM - I| <= `BINGHAM_ORTHOGONALITY_TOL`; it
///   is re-orthonormalized), columns are the principal directions.
/// - `z0`: d concentrations, `z0[i]` belongs to column i of `m0`; any order and shift.
/// - `out`: receives the new handle. Free it with `bingham_filter_free()`.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION` (d not 2 or 4), `BINGHAM_ERR_NULL_ARGUMENT` (`m0`,
/// `z0`, `out`), `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf, `m0` not orthogonal). On error `*out`
/// is not written.
///
/// # Safety
/// `m0`: d*d and `z0`: d readable doubles; `out`: a writable `bingham_filter *`.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_new(
    d: usize,
    m0: *const f64,
    z0: *const f64,
    out: *mut *mut bingham_filter,
) -> bingham_status {
    guard("bingham_filter_new", || {
        if d != 2 && d != 4 {
            return Err(Failure::dimension(format!(
                "the filter exists for d = 2 (axes) and d = 4 (quaternions), got d = {d}"
            )));
        }
        // SAFETY: caller contract; lengths d*d and d.
        let (ms, zs, out) = unsafe { args!(m0: [d * d], z0: [d], out: out).read()? };
        let inner = BinghamFilter::new(d, ms, zs)?;
        // SAFETY: every input has been read; written last.
        unsafe { out.set_handle(bingham_filter { inner }) };
        Ok(())
    })
}

/// Releases a filter created by `bingham_filter_new()` or `bingham_filter_clone()`. `NULL` is a
/// no-op. The handle must not be used afterwards.
///
/// # Safety
/// `f` must be `NULL` or a live handle from this library, not freed before and not in use by
/// another thread.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_free(f: *mut bingham_filter) {
    // Dropping plain data cannot panic; the guard keeps the promise that nothing unwinds into C.
    let _ = std::panic::catch_unwind(|| {
        // SAFETY: caller contract.
        unsafe { free_handle(f) }
    });
}

/// Creates an independent copy of a filter (state and cached noise parameters): both then evolve
/// separately, e.g. for a bank of hypotheses.
///
/// - `f`: the filter to copy; `out`: receives the new handle (free it with
///   `bingham_filter_free()`).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`f`, `out`). On error `*out` is not written.
///
/// # Safety
/// `f`: a live handle; `out`: a writable `bingham_filter *`.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_clone(
    f: *const bingham_filter,
    out: *mut *mut bingham_filter,
) -> bingham_status {
    guard("bingham_filter_clone", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        // SAFETY: caller contract.
        let (out,) = unsafe { args!(out: out).read()? };
        let copy = bingham_filter {
            inner: filter.inner.clone(),
        };
        // SAFETY: checked place.
        unsafe { out.set_handle(copy) };
        Ok(())
    })
}

/// The filter's dimension d (2 or 4), the length of its vectors (d) and matrices (d*d).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`f`, `d`); then `*d` is not written.
///
/// # Safety
/// `f`: a live handle; `d`: a writable `size_t`.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_dim(
    f: *const bingham_filter,
    d: *mut usize,
) -> bingham_status {
    guard("bingham_filter_dim", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        // SAFETY: caller contract; one writable size_t.
        let (d,) = unsafe { args!(d: out).read()? };
        // SAFETY: checked place.
        unsafe { d.set(filter.inner.dim()) };
        Ok(())
    })
}

/// Replaces the estimate by `Bingham(m, z)` (e.g. to re-initialize); the dimension stays.
///
/// - `m`: d x d row-major orthogonal (within `BINGHAM_ORTHOGONALITY_TOL`), `z`: d concentrations
///   (any order and shift), d = `bingham_filter_dim()`.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`f`, `m`, `z`), `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf,
/// `m` not orthogonal). On error the filter is unchanged.
///
/// # Safety
/// `f`: a live handle; `m`: d*d and `z`: d readable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_set_state(
    f: *mut bingham_filter,
    m: *const f64,
    z: *const f64,
) -> bingham_status {
    guard("bingham_filter_set_state", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle_mut("f", f)? };
        let d = filter.inner.dim();
        // SAFETY: caller contract; lengths d*d and d.
        let (ms, zs) = unsafe { args!(m: [d * d], z: [d]).read()? };
        filter.inner.set_state(ms, zs)?;
        Ok(())
    })
}

/// Copies the current estimate `Bingham(M, z)`.
///
/// - `m`: receives M, d x d row-major with orthonormal columns (the principal directions); the
///   last column is the mode.
/// - `z`: receives the d concentrations, ascending, `z[d-1] = 0` (column i of M belongs to `z[i]`).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`f`, `m`, `z`); then nothing is written.
///
/// # Safety
/// `f`: a live handle; `m`: d*d and `z`: d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_get_state(
    f: *const bingham_filter,
    m: *mut f64,
    z: *mut f64,
) -> bingham_status {
    guard("bingham_filter_get_state", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        let d = filter.inner.dim();
        // SAFETY: caller contract; d*d and d writable doubles.
        unsafe {
            get_into(args!(m: out [d * d], z: out [d]), |v| {
                let (m, z) = v.split_at_mut(d * d);
                filter.inner.state_into(m, z)
            })
        }
    })
}

/// The estimate: the mode of the state, the unit principal direction with the largest
/// concentration (the last column of M). For d = 4 a unit quaternion, scalar first; for d = 2 a
/// unit vector `(cos a, sin a)` of the axis angle a. `-mode` describes the same axis / rotation.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`f`, `mode`); then nothing is written.
///
/// # Safety
/// `f`: a live handle; `mode`: d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_mode(
    f: *const bingham_filter,
    mode: *mut f64,
) -> bingham_status {
    guard("bingham_filter_mode", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        let d = filter.inner.dim();
        // SAFETY: caller contract; d writable doubles.
        unsafe { get_into(args!(mode: out [d]), |v| filter.inner.mode_into(v)) }
    })
}

/// Shared body of the steps that read a noise `(m_*, z_*)` (d×d row-major and d doubles):
/// `bingham_filter_predict`, `_predict_rotation`, `_predict_nonlinear`, `_update` and
/// `_log_likelihood`. Checks the pointers of `before` (the arguments before the noise: the
/// rotation or the measurement), of the noise and of `after` (the output, if any), in this
/// order, then reads them in the same order, runs `step` and stores its result in `after`.
///
/// # Safety
/// The caller's contract for the arguments (the noise: d*d and d readable doubles).
pub(super) unsafe fn noise_step<B: Arg, A: Arg, R>(
    d: usize,
    before: B,
    [(m_name, m), (z_name, z)]: [(&'static str, *const f64); 2],
    after: A,
    step: impl FnOnce(B::Value, &[f64], &[f64]) -> crate::error::Result<R>,
) -> FfiResult<()>
where
    A::Value: Store<R>,
{
    let noise = (ArrayIn::new(m_name, m, d * d), ArrayIn::new(z_name, z, d));
    // SAFETY: forwarded contract.
    let (before, (ms, zs), after) = unsafe { (before, noise, after).read()? };
    let value = step(before, ms, zs)?;
    // SAFETY: every input has been read.
    unsafe { after.store(value) };
    Ok(())
}

/// Prediction step: the state becomes the distribution of `x (+) w`, `w ~ Bingham(m_w, z_w)`
/// (JAIF Sec. 6.1: exact second moment of the composition, then the moment-matched Bingham).
///
/// - `m_w`: d x d row-major orthogonal (within `BINGHAM_ORTHOGONALITY_TOL`), `z_w`: d
///   concentrations (any order and shift). The mode of the noise may carry a known offset (a
///   nominal rotation per step); zero-mean noise has the mode `(1, 0)` resp. `(1, 0, 0, 0)`.
///   Typically the same arrays every step: their moments are computed once and cached.
///
/// Concentrations below `-BINGHAM_FILTER_MAX_CONCENTRATION` (state or noise) are raised to it
/// for this computation, so a very sharp state never makes the prediction fail.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`f`, `m_w`, `z_w`), `BINGHAM_ERR_INVALID_ARGUMENT`
/// (NaN/Inf, `m_w` not orthogonal), `BINGHAM_ERR_NOT_CONVERGED` / `BINGHAM_ERR_NUMERICAL` (moment
/// matching). On error the filter is unchanged.
///
/// # Safety
/// `f`: a live handle; `m_w`: d*d and `z_w`: d readable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_predict(
    f: *mut bingham_filter,
    m_w: *const f64,
    z_w: *const f64,
) -> bingham_status {
    guard("bingham_filter_predict", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle_mut("f", f)? };
        let noise = [("m_w", m_w), ("z_w", z_w)];
        // SAFETY: caller contract.
        unsafe {
            noise_step(filter.inner.dim(), (), noise, (), |(), m, z| {
                filter.inner.predict(m, z)
            })
        }
    })
}

/// Prediction step with a known rotation: the state becomes the distribution of
/// `x (+) u (+) w`, `w ~ Bingham(m_w, z_w)`.
///
/// - `u`: d entries, unit length (|‖u‖ - 1| <= `BINGHAM_UNIT_TOL`, then normalized): e.g. the
///   rotation increment integrated from a gyroscope over the step (quaternion, scalar first, in
///   the body frame: `x (+) u` applies `u` after `x` in the sense of the Hamilton product), or
///   `(cos a, sin a)` to turn an axis by a (d = 2). Applied exactly (`x (+) u ~ Bingham(R(u) M, z)`).
/// - `m_w`, `z_w`: the noise, as in `bingham_filter_predict()`.
///
/// Errors: as `bingham_filter_predict()`, plus `BINGHAM_ERR_NULL_ARGUMENT` (`u`) and
/// `BINGHAM_ERR_INVALID_ARGUMENT` (`u` NaN/Inf or not unit). On error the filter is unchanged.
///
/// # Safety
/// `f`: a live handle; `u`: d, `m_w`: d*d and `z_w`: d readable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_predict_rotation(
    f: *mut bingham_filter,
    u: *const f64,
    m_w: *const f64,
    z_w: *const f64,
) -> bingham_status {
    guard("bingham_filter_predict_rotation", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle_mut("f", f)? };
        let d = filter.inner.dim();
        let noise = [("m_w", m_w), ("z_w", z_w)];
        // SAFETY: caller contract.
        unsafe {
            noise_step(d, args!(u: [d]), noise, (), |(u,), m, z| {
                filter.inner.predict_rotation(u, m, z)
            })
        }
    })
}

/// Measurement update (Bayes' rule, exact): conditions the state on `measurement = x (+) v`,
/// `v ~ Bingham(m_v, z_v)` (JAIF Sec. 6.2).
///
/// - `measurement`: d entries, unit length (|‖z‖ - 1| <= `BINGHAM_UNIT_TOL`, then normalized);
///   its sign does not matter (an axis / a rotation).
/// - `m_v`, `z_v`: the measurement noise, d x d row-major orthogonal and d concentrations; its
///   mode is usually the identity `(1, 0)` resp. `(1, 0, 0, 0)`. Cached like the process noise.
///
/// Any finite concentration is handled (the state may become arbitrarily sharp).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`f`, `measurement`, `m_v`, `z_v`),
/// `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf, measurement not unit, `m_v` not orthogonal),
/// `BINGHAM_ERR_NUMERICAL` (concentrations overflowing a double). On error the filter is
/// unchanged.
///
/// # Safety
/// `f`: a live handle; `measurement`: d, `m_v`: d*d and `z_v`: d readable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_update(
    f: *mut bingham_filter,
    measurement: *const f64,
    m_v: *const f64,
    z_v: *const f64,
) -> bingham_status {
    guard("bingham_filter_update", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle_mut("f", f)? };
        let d = filter.inner.dim();
        let noise = [("m_v", m_v), ("z_v", z_v)];
        // SAFETY: caller contract.
        unsafe {
            noise_step(d, args!(measurement: [d]), noise, (), |(y,), m, z| {
                filter.inner.update(y, m, z)
            })
        }
    })
}

/// The natural logarithm of the predictive density of a measurement under the current state,
/// `log p(z) = log ∫ f_state(x) f_v(x^-1 (+) z) dx`, without changing the filter: for gating
/// (reject measurements with a small value) and for weighting the filters of a bank (the
/// likelihood of each hypothesis).
///
/// `p` is a probability density of the measurement on the unit sphere S^{d-1} with respect to
/// the surface measure (it integrates to 1 over the circle, resp. the 3-sphere) and is
/// antipodally symmetric. Exact (no moment matching involved).
///
/// - `measurement`, `m_v`, `z_v`: as in `bingham_filter_update()`.
/// - `out`: receives log p.
///
/// Errors: as `bingham_filter_update()`, plus `BINGHAM_ERR_NULL_ARGUMENT` (`out`). On error
/// `*out` is not written.
///
/// # Safety
/// `f`: a live handle; `measurement`: d, `m_v`: d*d and `z_v`: d readable doubles; `out`: one
/// writable double.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_log_likelihood(
    f: *const bingham_filter,
    measurement: *const f64,
    m_v: *const f64,
    z_v: *const f64,
    out: *mut f64,
) -> bingham_status {
    guard("bingham_filter_log_likelihood", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        let d = filter.inner.dim();
        let noise = [("m_v", m_v), ("z_v", z_v)];
        // SAFETY: caller contract.
        unsafe {
            noise_step(
                d,
                args!(measurement: [d]),
                noise,
                args!(out: out),
                |(y,), m, z| filter.inner.log_likelihood(y, m, z),
            )
        }
    })
}

/// The surprise of a measurement under the current state, a health readout on a fixed scale:
/// `s = 2 (log p(y_hat) - log p(measurement)) >= 0`, `p` the predictive density of
/// `bingham_filter_log_likelihood()` and `y_hat = x_hat (+) v_hat` the predicted measurement
/// (the modes of the state and the noise). When the state and the noise are concentrated and
/// the model holds, `s` is a chi-square variable with d - 1 degrees of freedom: mean 3 for
/// quaternions, above 16.27 with probability 0.1 % (d = 2: mean 1, above 10.83 with 0.1 %). A
/// measurement that does not fit — a quaternion in (x, y, z, w) order, a fix in another frame
/// — scores in the hundreds. Broad directions of the state or noise contribute little. The
/// filter is not changed. Use it to monitor a stream of fixes, or gate with
/// `bingham_filter_update_gated()`.
///
/// Errors: as `bingham_filter_log_likelihood()`. On error `*surprise` is not written.
///
/// # Safety
/// `f`: a live handle; `measurement`: d, `m_v`: d*d and `z_v`: d readable doubles;
/// `surprise`: one writable double.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_surprise(
    f: *const bingham_filter,
    measurement: *const f64,
    m_v: *const f64,
    z_v: *const f64,
    surprise: *mut f64,
) -> bingham_status {
    guard("bingham_filter_surprise", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        let d = filter.inner.dim();
        let noise = [("m_v", m_v), ("z_v", z_v)];
        // SAFETY: caller contract.
        unsafe {
            noise_step(
                d,
                args!(measurement: [d]),
                noise,
                args!(surprise: out),
                |(y,), m, z| filter.inner.surprise(y, m, z),
            )
        }
    })
}

/// The update with a likelihood gate: `bingham_filter_update()` if the measurement's surprise
/// (`bingham_filter_surprise()`) is at most `max_surprise`, otherwise the filter is left as it
/// was. Writes the surprise into `*surprise` and 1 (applied) or 0 (gated out) into `*accepted`;
/// a gated-out measurement returns `BINGHAM_OK`. `max_surprise`: >= 0, or `INFINITY` (no gate);
/// e.g. 16.27 rejects 0.1 % of the measurements of a correct quaternion model.
///
/// Errors: those of `bingham_filter_update()`, `BINGHAM_ERR_NULL_ARGUMENT` (`surprise`,
/// `accepted`), `BINGHAM_ERR_INVALID_ARGUMENT` (`max_surprise` NaN or negative). On error
/// nothing is written and the filter is unchanged.
///
/// # Safety
/// `f`: a live handle; `measurement`: d, `m_v`: d*d and `z_v`: d readable doubles;
/// `surprise`: one writable double; `accepted`: one writable `int32_t`.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_update_gated(
    f: *mut bingham_filter,
    measurement: *const f64,
    m_v: *const f64,
    z_v: *const f64,
    max_surprise: f64,
    surprise: *mut f64,
    accepted: *mut i32,
) -> bingham_status {
    guard("bingham_filter_update_gated", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle_mut("f", f)? };
        let d = filter.inner.dim();
        let noise = [("m_v", m_v), ("z_v", z_v)];
        // SAFETY: caller contract.
        unsafe {
            noise_step(
                d,
                args!(measurement: [d]),
                noise,
                args!(surprise: out, accepted: out),
                |(y,), m, z| {
                    let g = filter.inner.update_gated(y, m, z, max_surprise)?;
                    Ok((g.surprise, i32::from(g.accepted)))
                },
            )
        }
    })
}

/// Measurement update with a measured direction (d = 4 filters): `body` (sensor frame) is a
/// noisy measurement of the known world direction `reference`, with von Mises–Fisher noise of
/// concentration `kappa` (see `bingham_vector_observation()`; the filter's quaternion maps
/// sensor to world). The likelihood is a Bingham density of the orientation, so the update is
/// an exact Bayes product (equal to `bingham_multiply()` of the state with
/// `bingham_vector_observation()`); the rotation about `reference` is not observed.
///
/// - `body`, `reference`: 3 doubles each, unit within `BINGHAM_UNIT_TOL`; `kappa`: finite, ≥ 0.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT`, `BINGHAM_ERR_INVALID_DIMENSION` (a d = 2 filter),
/// `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf, non-unit vector, bad `kappa`),
/// `BINGHAM_ERR_NUMERICAL` (overflow). On error the filter is unchanged.
///
/// # Safety
/// `f`: a live handle; `body`, `reference`: 3 readable doubles each.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_update_vector(
    f: *mut bingham_filter,
    body: *const f64,
    reference: *const f64,
    kappa: f64,
) -> bingham_status {
    guard("bingham_filter_update_vector", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle_mut("f", f)? };
        // SAFETY: caller contract; 3 doubles each.
        let (b, r) = unsafe { args!(body: [3], reference: [3]).read()? };
        filter.inner.update_vector(b, r, kappa)?;
        Ok(())
    })
}

/// The natural logarithm of the predictive density of a measured direction under the current
/// state (d = 4): `log ∫ f_state(q) p(body | q) dq`, with `p(b | q)` the von Mises–Fisher
/// density `kappa / (4π sinh kappa) exp(kappa rᵀ R(q) b)` on the unit sphere of directions
/// (surface measure). Exact. For gating (an outlier has a low value) and adaptive `kappa`. The
/// filter is not changed.
///
/// - `body`, `reference`, `kappa`: as in `bingham_filter_update_vector()`; `out`: receives the
///   value.
///
/// Errors: as `bingham_filter_update_vector()`, plus `BINGHAM_ERR_NULL_ARGUMENT` (`out`). On
/// error `*out` is not written.
///
/// # Safety
/// `f`: a live handle; `body`, `reference`: 3 readable doubles each; `out`: one writable double.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_log_likelihood_vector(
    f: *const bingham_filter,
    body: *const f64,
    reference: *const f64,
    kappa: f64,
    out: *mut f64,
) -> bingham_status {
    guard("bingham_filter_log_likelihood_vector", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        // SAFETY: caller contract; 3 doubles each, one writable double.
        let (b, r, out) = unsafe { args!(body: [3], reference: [3], out: out).read()? };
        let value = filter.inner.log_likelihood_vector(b, r, kappa)?;
        // SAFETY: every input has been read.
        unsafe { out.set(value) };
        Ok(())
    })
}

/// The angular spread (radians) of the filter's state, as `bingham_angular_spread()`:
/// `spread[i]` (i < d − 1) along principal direction i (column i of the state's M),
/// `spread[d-1]` the total (d = 4: the RMS of `2 sin(θ/2)`, θ the rotation angle from the mode,
/// ≈ the RMS angle).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`f`, `spread`), `BINGHAM_ERR_NUMERICAL` (the moments
/// of an extremely concentrated state cannot be evaluated). On error nothing is written.
///
/// # Safety
/// `f`: a live handle; `spread`: d writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_angular_spread(
    f: *const bingham_filter,
    spread: *mut f64,
) -> bingham_status {
    guard("bingham_filter_angular_spread", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        let d = filter.inner.dim();
        // SAFETY: caller contract; d writable doubles.
        unsafe {
            get_into(args!(spread: out [d]), |v| {
                filter.inner.angular_spread_into(v)
            })
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filter::MAX_CONCENTRATION;

    #[test]
    fn max_concentration_matches_core() {
        assert_eq!(BINGHAM_FILTER_MAX_CONCENTRATION, MAX_CONCENTRATION);
    }

    #[test]
    fn handle_lifecycle() {
        let m = [1.0, 0.0, 0.0, 1.0];
        let z = [-1.0, 0.0];
        let mut f: *mut bingham_filter = std::ptr::null_mut();
        let mut g: *mut bingham_filter = std::ptr::null_mut();
        let mut d = 0usize;
        // SAFETY: valid arrays and out-pointers; handles freed once.
        unsafe {
            assert_eq!(
                bingham_filter_new(2, m.as_ptr(), z.as_ptr(), &mut f),
                bingham_status::BINGHAM_OK
            );
            assert_eq!(bingham_filter_clone(f, &mut g), bingham_status::BINGHAM_OK);
            assert_eq!(bingham_filter_dim(g, &mut d), bingham_status::BINGHAM_OK);
            assert_eq!(d, 2);
            bingham_filter_free(f);
            bingham_filter_free(g);
            bingham_filter_free(std::ptr::null_mut());
        }
    }
}
