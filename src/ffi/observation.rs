//! Orientation observations and noise as distributions in the C API, over
//! [`crate::observation`]: the likelihood of a measured direction
//! (`bingham_vector_observation`), rotation noise from an angular standard deviation
//! (`bingham_noise_from_angle_std`) and the angular spread of a distribution
//! (`bingham_angular_spread`). Thin wrappers: check `d` and the pointers, read the inputs, call
//! the core, copy the results out.

use super::args::{args, Arg};
use super::guard::{guard, Failure, FfiResult};
use super::status::bingham_status;
use crate::observation::{angular_spread, noise_from_angle_std, vector_observation};

/// `d` is 2 (axes in the plane, unit complex numbers) or 4 (rotations, unit quaternions); `what`
/// names the refused object in the message.
fn rotation_dim(d: usize, what: &str) -> FfiResult<()> {
    if d == 2 || d == 4 {
        Ok(())
    } else {
        Err(Failure::dimension(format!(
            "{what} exists for d = 2 and d = 4, got d = {d}"
        )))
    }
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
        // SAFETY: caller contract; 3 doubles each.
        let (b, r, out) = unsafe { args!(body: [3], reference: [3], (m, z): out bingham).read()? };
        let obs = vector_observation(b, r, kappa)?;
        // SAFETY: every input has been read; lengths 16 and 4.
        unsafe { out.write(&obs) };
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
        rotation_dim(d, "rotation noise")?;
        // SAFETY: caller contract.
        let (out,) = unsafe { args!((m, z): out bingham).read()? };
        let b = noise_from_angle_std(d, sigma)?;
        // SAFETY: lengths d*d and d.
        unsafe { out.write(&b) };
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
        rotation_dim(d, "the angular spread")?;
        // SAFETY: caller contract.
        let (b, spread) = unsafe { args!((m, z): bingham [d], spread: out [d]).read()? };
        let s = angular_spread(&b)?;
        // SAFETY: every input has been read; length d.
        unsafe { spread.write(&s) };
        Ok(())
    })
}
