//! The second-order quaternion Bingham filter behind the opaque handle `bingham_spin_filter`
//! (the C side of [`crate::filter::SpinFilter`]). Thin wrappers: check pointers, read and
//! validate the inputs, call the core, copy results out; a failed call leaves the filter as it
//! was.

use super::args::{args, get_into, Arg};
use super::guard::{free_handle, guard, handle, handle_mut};
use super::status::bingham_status;
use crate::filter::SpinFilter;

/// The second-order quaternion Bingham filter of Glover & Kaelbling (2013): the orientation `x`
/// and the spin `v` (the rotation per time step) of an object observed without a gyroscope,
/// e.g. by a camera.
///
/// An opaque handle: create it with `bingham_spin_filter_new()` (or
/// `bingham_spin_filter_clone()`), release it with `bingham_spin_filter_free()`. The caller owns
/// it.
///
/// Model (quaternions scalar first `(w, x, y, z)`; `q ∘ r` is the Hamilton product `q r`,
/// "rotate by r, then by q"): `v[n] = w[n] ∘ u[n] ∘ v[n-1]`, `x[n] = v[n-1] ∘ x[n-1]`,
/// `y[n] = o[n] ∘ x[n]`, with Bingham noises `w` (process, on the spin) and `o` (observation),
/// and an optional known control `u` (a change of spin). The state is the product of two
/// Bingham marginals, orientation `(M_x, z_x)` and spin `(M_v, z_v)` (4 x 4 row-major with
/// orthonormal columns, the last column the mode; z ascending, `z[3] = 0`). A step: the
/// orientation's prior is the composition `B_v ∘ B_x`, times the observation's likelihood
/// (exact product); the spin is multiplied by the observation's evidence about it (the
/// composition of the likelihood with the inverse of the previous orientation), then rotated by
/// `u` and composed with `w`. Approximations: the product of marginals, and moment matching of
/// each composition (exact in the second moment). Derivation in `docs/design.md`.
///
/// Thread safety: a handle may be used by one thread at a time (functions taking
/// `bingham_spin_filter *` modify it; functions taking `const bingham_spin_filter *` may run
/// concurrently on the same handle). Different handles are independent; no global state.
///
/// Memory: after the first step with given noise parameters (cached inside the handle, keyed
/// on their bit patterns), a step performs no heap allocation.
#[allow(non_camel_case_types)]
pub struct bingham_spin_filter {
    inner: SpinFilter,
}

/// Creates a spin filter with the orientation prior `Bingham(m_x, z_x)` and the spin prior
/// `Bingham(m_v, z_v)`.
///
/// - `m_x`, `m_v`: 4 x 4 row-major orthogonal (within `BINGHAM_ORTHOGONALITY_TOL`;
///   re-orthonormalized); `z_x`, `z_v`: 4 concentrations each, `z[i]` for column i, any order
///   and shift. `z_x` all equal (e.g. 0) is the uniform orientation prior (nothing known).
///   A spin prior centred on "no spin" has the mode `(1, 0, 0, 0)`.
/// - `out`: receives the new handle (free it with `bingham_spin_filter_free()`).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT`, `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf, a matrix not
/// orthogonal). On error `*out` is not written.
///
/// # Safety
/// `m_x`, `m_v`: 16 and `z_x`, `z_v`: 4 readable doubles; `out`: a writable
/// `bingham_spin_filter *`.
#[no_mangle]
pub unsafe extern "C" fn bingham_spin_filter_new(
    m_x: *const f64,
    z_x: *const f64,
    m_v: *const f64,
    z_v: *const f64,
    out: *mut *mut bingham_spin_filter,
) -> bingham_status {
    guard("bingham_spin_filter_new", || {
        // SAFETY: caller contract; the stated lengths.
        let (mx, zx, mv, zv, out) =
            unsafe { args!(m_x: [16], z_x: [4], m_v: [16], z_v: [4], out: out).read()? };
        let inner = SpinFilter::new(mx, zx, mv, zv)?;
        // SAFETY: every input has been read; written last.
        unsafe { out.set_handle(bingham_spin_filter { inner }) };
        Ok(())
    })
}

/// Releases a spin filter created by `bingham_spin_filter_new()` or
/// `bingham_spin_filter_clone()`. `NULL` is a no-op. The handle must not be used afterwards.
///
/// # Safety
/// `f` must be `NULL` or a live handle from this library, not freed before and not in use by
/// another thread.
#[no_mangle]
pub unsafe extern "C" fn bingham_spin_filter_free(f: *mut bingham_spin_filter) {
    let _ = std::panic::catch_unwind(|| {
        // SAFETY: caller contract.
        unsafe { free_handle(f) }
    });
}

/// Creates an independent copy of a spin filter (state and cached noises), e.g. for a bank of
/// hypotheses or to try a step.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`f`, `out`). On error `*out` is not written.
///
/// # Safety
/// `f`: a live handle; `out`: a writable `bingham_spin_filter *`.
#[no_mangle]
pub unsafe extern "C" fn bingham_spin_filter_clone(
    f: *const bingham_spin_filter,
    out: *mut *mut bingham_spin_filter,
) -> bingham_status {
    guard("bingham_spin_filter_clone", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        // SAFETY: caller contract.
        let (out,) = unsafe { args!(out: out).read()? };
        let copy = bingham_spin_filter {
            inner: filter.inner.clone(),
        };
        // SAFETY: checked place.
        unsafe { out.set_handle(copy) };
        Ok(())
    })
}

/// One time step: `v ← w ∘ u ∘ v`, `x ← v ∘ x` (the previous spin), then, if `y` is not `NULL`,
/// the observation `y = o ∘ x`, `o ~ Bingham(m_o, z_o)`.
///
/// - `u`: the control (a known change of spin), 4 doubles, unit within `BINGHAM_UNIT_TOL`
///   (then normalized), or `NULL` for none.
/// - `m_w`, `z_w`: the process noise on the spin (4 x 4 row-major orthogonal, 4
///   concentrations; mode `(1, 0, 0, 0)` for zero-mean noise). Cached.
/// - `y`: the observed orientation, 4 doubles, unit within `BINGHAM_UNIT_TOL` (its sign does not
///   matter), or `NULL` when nothing is observed this step (prediction only; then `m_o` and
///   `z_o` are ignored and may be `NULL`).
/// - `m_o`, `z_o`: the observation noise (as `m_w`, `z_w`). Cached.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`f`, `m_w`, `z_w`; `m_o`, `z_o` when `y` is given),
/// `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf, `u` or `y` not unit, a matrix not orthogonal),
/// `BINGHAM_ERR_NOT_CONVERGED` / `BINGHAM_ERR_NUMERICAL` (moment matching, overflow). On error
/// the filter is unchanged.
///
/// # Safety
/// `f`: a live handle; `u`, `y`: `NULL` or 4 readable doubles; `m_w`, `m_o`: 16 and `z_w`,
/// `z_o`: 4 readable doubles (`m_o`, `z_o` only read when `y` is not `NULL`).
#[no_mangle]
pub unsafe extern "C" fn bingham_spin_filter_step(
    f: *mut bingham_spin_filter,
    u: *const f64,
    m_w: *const f64,
    z_w: *const f64,
    y: *const f64,
    m_o: *const f64,
    z_o: *const f64,
) -> bingham_status {
    guard("bingham_spin_filter_step", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle_mut("f", f)? };
        let observed = !y.is_null();
        // SAFETY: caller contract; the stated lengths, `m_o`/`z_o` only with `y`.
        let (u, mw, zw, y, mo, zo) = unsafe {
            args!(
                u: opt [4],
                m_w: [16],
                z_w: [4],
                y: opt [4],
                m_o: [16] if observed,
                z_o: [4] if observed
            )
            .read()?
        };
        filter
            .inner
            .step(u, mw, zw, y, mo.unwrap_or_default(), zo.unwrap_or_default())?;
        Ok(())
    })
}

/// The natural logarithm of the predictive density of the observation `y = o ∘ x`,
/// `o ~ Bingham(m_o, z_o)`, for the step about to be taken: `log ∫ f(y | x) (B_v ∘ B_x)(x) dx`,
/// a density on the unit sphere S^3 with respect to the surface measure (antipodally
/// symmetric). The filter's state is not changed. A bank of spin filters sums it over time to
/// compare its hypotheses; between two interpretations of an ambiguous observation, the one
/// with the larger value is the more probable.
///
/// Cost: the first call after a step (or after `bingham_spin_filter_set_state()`) computes the
/// orientation's prediction `B_v ∘ B_x` and the handle keeps it until the state changes, so
/// further calls and the next `bingham_spin_filter_step()` reuse it (the same results as
/// without it, bit for bit). Calls on one handle from several threads at once are safe.
///
/// - `y`, `m_o`, `z_o`: as in `bingham_spin_filter_step()` (`y` required here);
///   `log_l`: receives the value.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT`, `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf, `y` not unit,
/// `m_o` not orthogonal), `BINGHAM_ERR_NOT_CONVERGED` / `BINGHAM_ERR_NUMERICAL`. On error
/// `*log_l` is not written.
///
/// # Safety
/// `f`: a live handle; `y`: 4, `m_o`: 16 and `z_o`: 4 readable doubles; `log_l`: one writable
/// double.
#[no_mangle]
pub unsafe extern "C" fn bingham_spin_filter_log_likelihood(
    f: *const bingham_spin_filter,
    y: *const f64,
    m_o: *const f64,
    z_o: *const f64,
    log_l: *mut f64,
) -> bingham_status {
    guard("bingham_spin_filter_log_likelihood", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        // SAFETY: caller contract; the stated lengths.
        let (y, mo, zo, log_l) = unsafe { args!(y: [4], m_o: [16], z_o: [4], log_l: out).read()? };
        let value = filter.inner.log_likelihood(y, mo, zo)?;
        // SAFETY: every input has been read.
        unsafe { log_l.set(value) };
        Ok(())
    })
}

/// Replaces both marginals (validated as in `bingham_spin_filter_new()`); the cached noises
/// stay.
///
/// Errors: as `bingham_spin_filter_new()`. On error the filter is unchanged.
///
/// # Safety
/// `f`: a live handle; `m_x`, `m_v`: 16 and `z_x`, `z_v`: 4 readable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_spin_filter_set_state(
    f: *mut bingham_spin_filter,
    m_x: *const f64,
    z_x: *const f64,
    m_v: *const f64,
    z_v: *const f64,
) -> bingham_status {
    guard("bingham_spin_filter_set_state", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle_mut("f", f)? };
        // SAFETY: caller contract; the stated lengths.
        let (mx, zx, mv, zv) = unsafe { args!(m_x: [16], z_x: [4], m_v: [16], z_v: [4]).read()? };
        filter.inner.set_state(mx, zx, mv, zv)?;
        Ok(())
    })
}

/// Copies both marginals: `m_x` (16, row-major, orthonormal columns, the last the orientation's
/// mode), `z_x` (4, ascending, last 0), `m_v`, `z_v` the same for the spin.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT`; then nothing is written.
///
/// # Safety
/// `f`: a live handle; `m_x`, `m_v`: 16 and `z_x`, `z_v`: 4 writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_spin_filter_get_state(
    f: *const bingham_spin_filter,
    m_x: *mut f64,
    z_x: *mut f64,
    m_v: *mut f64,
    z_v: *mut f64,
) -> bingham_status {
    guard("bingham_spin_filter_get_state", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        // SAFETY: caller contract; the stated lengths.
        unsafe {
            get_into(
                args!(m_x: out [16], z_x: out [4], m_v: out [16], z_v: out [4]),
                |v| {
                    let (mx, rest) = v.split_at_mut(16);
                    let (zx, rest) = rest.split_at_mut(4);
                    let (mv, zv) = rest.split_at_mut(16);
                    filter.inner.state_into(mx, zx, mv, zv)
                },
            )
        }
    })
}

/// The orientation's mode: the estimate, a unit quaternion (scalar first; its negative is the
/// same rotation), written to `q` (4 doubles).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT`; then nothing is written.
///
/// # Safety
/// `f`: a live handle; `q`: 4 writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_spin_filter_orientation_mode(
    f: *const bingham_spin_filter,
    q: *mut f64,
) -> bingham_status {
    guard("bingham_spin_filter_orientation_mode", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        // SAFETY: caller contract; 4 writable doubles.
        unsafe {
            get_into(args!(q: out [4]), |v| {
                v.copy_from_slice(&filter.inner.orientation_mode());
                Ok(())
            })
        }
    })
}

/// The spin's mode: the most probable rotation per time step, a unit quaternion (scalar
/// first), written to `q` (4 doubles). Its rotation angle divided by the step's duration is the
/// angular rate.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT`; then nothing is written.
///
/// # Safety
/// `f`: a live handle; `q`: 4 writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_spin_filter_spin_mode(
    f: *const bingham_spin_filter,
    q: *mut f64,
) -> bingham_status {
    guard("bingham_spin_filter_spin_mode", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        // SAFETY: caller contract; 4 writable doubles.
        unsafe {
            get_into(args!(q: out [4]), |v| {
                v.copy_from_slice(&filter.inner.spin_mode());
                Ok(())
            })
        }
    })
}

/// The angular spreads (radians) of the orientation (`x_spread`) and of the spin (`v_spread`,
/// radians per step), 4 doubles each, as `bingham_filter_angular_spread()`: entries 0–2 along
/// the principal directions (columns 0–2 of the marginal's M), entry 3 the total (the RMS of
/// `2 sin(θ/2)`, θ the rotation angle from the mode).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT`, `BINGHAM_ERR_NUMERICAL` (an extremely concentrated
/// marginal). On error nothing is written.
///
/// # Safety
/// `f`: a live handle; `x_spread`, `v_spread`: 4 writable doubles each.
#[no_mangle]
pub unsafe extern "C" fn bingham_spin_filter_angular_spread(
    f: *const bingham_spin_filter,
    x_spread: *mut f64,
    v_spread: *mut f64,
) -> bingham_status {
    guard("bingham_spin_filter_angular_spread", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        // SAFETY: caller contract; 4 writable doubles each.
        unsafe {
            get_into(args!(x_spread: out [4], v_spread: out [4]), |v| {
                let (xs, vs) = v.split_at_mut(4);
                filter.inner.angular_spread_into(xs, vs)
            })
        }
    })
}
