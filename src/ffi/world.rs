//! World-frame steps of the filter handle `bingham_filter` (the C side of
//! [`crate::filter::BinghamFilter::predict_world`] and its siblings): the first-order model of
//! Glover & Kaelbling (2013), with the control and the noises acting on the left.

use super::args::args;
use super::filter::{bingham_filter, noise_step};
use super::guard::{guard, handle, handle_mut};
use super::status::bingham_status;

/// World-frame prediction (Glover & Kaelbling 2013): the state becomes the distribution of
/// `w ∘ u ∘ x`, `w ~ Bingham(m_w, z_w)`, where `q ∘ r` is the Hamilton product `q r` ("rotate by
/// r, then by q"): the control `u` and the noise act on the left, in the world frame.
/// `bingham_filter_predict_rotation()` composes on the right (`x (+) u (+) w`, body frame); the
/// two agree for d = 2 (complex multiplication commutes) and, without `u`, for a noise that is
/// isotropic about the identity.
///
/// - `u`: d entries, unit length (within `BINGHAM_UNIT_TOL`, then normalized), applied exactly
///   (`u ∘ x ~ Bingham(L(u) M, z)`); `NULL` means the identity.
/// - `m_w`, `z_w`: the noise, as in `bingham_filter_predict()` (cached the same way).
///
/// Exact in the second moment (the composition's second moment is exact, the new state its
/// moment-matched Bingham), like `bingham_filter_predict()`.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`f`, `m_w`, `z_w`), `BINGHAM_ERR_INVALID_ARGUMENT`
/// (NaN/Inf, `u` not unit, `m_w` not orthogonal), `BINGHAM_ERR_NOT_CONVERGED` /
/// `BINGHAM_ERR_NUMERICAL` (moment matching). On error the filter is unchanged.
///
/// # Safety
/// `f`: a live handle; `u`: `NULL` or d readable doubles; `m_w`: d*d and `z_w`: d readable
/// doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_predict_world(
    f: *mut bingham_filter,
    u: *const f64,
    m_w: *const f64,
    z_w: *const f64,
) -> bingham_status {
    guard("bingham_filter_predict_world", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle_mut("f", f)? };
        let d = filter.inner.dim();
        let noise = [("m_w", m_w), ("z_w", z_w)];
        // SAFETY: caller contract.
        unsafe {
            noise_step(d, args!(u: opt [d]), noise, (), |(u,), m, z| {
                filter.inner.predict_world(u, m, z)
            })
        }
    })
}

/// World-frame update (exact Bayes product): conditions the state on `y = v ∘ x`,
/// `v ~ Bingham(m_v, z_v)` (the noise on the left; `bingham_filter_update()` has `x (+) v`). The
/// likelihood `f_v(y ∘ x^-1)` is the Bingham density of `x` with the principal directions
/// `conj(m_i) ∘ y` (the columns `m_i` of `m_v`) and the concentrations `z_v`, equal to
/// `bingham_multiply()` of the state with that density.
///
/// - `y`: d entries, unit length (within `BINGHAM_UNIT_TOL`, then normalized); its sign does not
///   matter.
/// - `m_v`, `z_v`: the observation noise, as in `bingham_filter_update()` (cached the same way).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`f`, `y`, `m_v`, `z_v`), `BINGHAM_ERR_INVALID_ARGUMENT`
/// (NaN/Inf, `y` not unit, `m_v` not orthogonal), `BINGHAM_ERR_NUMERICAL` (concentrations
/// overflowing a double). On error the filter is unchanged.
///
/// # Safety
/// `f`: a live handle; `y`: d, `m_v`: d*d and `z_v`: d readable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_update_world(
    f: *mut bingham_filter,
    y: *const f64,
    m_v: *const f64,
    z_v: *const f64,
) -> bingham_status {
    guard("bingham_filter_update_world", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle_mut("f", f)? };
        let d = filter.inner.dim();
        let noise = [("m_v", m_v), ("z_v", z_v)];
        // SAFETY: caller contract.
        unsafe {
            noise_step(d, args!(y: [d]), noise, (), |(y,), m, z| {
                filter.inner.update_world(y, m, z)
            })
        }
    })
}

/// The natural logarithm of the predictive density of `y = v ∘ x` under the current state,
/// `log ∫ f_state(x) f_v(y ∘ x^-1) dx`, without changing the filter: a density on the unit
/// sphere with respect to the surface measure, as in `bingham_filter_log_likelihood()` (exact).
/// What a bank of filters compares, and what picks between the interpretations of an ambiguous
/// observation.
///
/// - `y`, `m_v`, `z_v`: as in `bingham_filter_update_world()`; `log_l`: receives the value.
///
/// Errors: as `bingham_filter_update_world()`, plus `BINGHAM_ERR_NULL_ARGUMENT` (`log_l`). On
/// error `*log_l` is not written.
///
/// # Safety
/// `f`: a live handle; `y`: d, `m_v`: d*d and `z_v`: d readable doubles; `log_l`: one writable
/// double.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_log_likelihood_world(
    f: *const bingham_filter,
    y: *const f64,
    m_v: *const f64,
    z_v: *const f64,
    log_l: *mut f64,
) -> bingham_status {
    guard("bingham_filter_log_likelihood_world", || {
        // SAFETY: caller contract.
        let filter = unsafe { handle("f", f)? };
        let d = filter.inner.dim();
        let noise = [("m_v", m_v), ("z_v", z_v)];
        // SAFETY: caller contract.
        unsafe {
            noise_step(d, args!(y: [d]), noise, args!(log_l: out), |(y,), m, z| {
                filter.inner.log_likelihood_world(y, m, z)
            })
        }
    })
}
