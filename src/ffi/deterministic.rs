//! Deterministic samples of a Bingham distribution (the C side of
//! [`crate::deterministic`]): weighted points whose weighted moments are those of the
//! distribution, for propagating it through a nonlinear function. Thin wrappers: check `d`, the
//! scheme and the pointers, read the inputs, call the core, copy the result out.

use std::os::raw::c_int;

use super::args::{args, Arg};
use super::guard::{dim, guard, Failure, FfiResult};
use super::status::bingham_status;
use crate::deterministic::{max_count, Reproduced, Scheme};

/// Scheme of `bingham_deterministic_samples()`: the TAC 2016 points (Gilitschenski, Kurz,
/// Julier & Hanebeck, "Unscented Orientation Estimation Based on the Bingham Distribution",
/// IEEE TAC 2016; libDirectional's `sampleDeterministic`) with the weighting parameter
/// `lambda` in [0, 1] (libDirectional's default 0.5): `2d - 1` points that reproduce the
/// second moment exactly, not the fourth moments.
pub const BINGHAM_SAMPLES_TAC2016: c_int = 0;

/// Scheme of `bingham_deterministic_samples()`: the moment-matched points, `2d² - 4d + 3` of
/// them (3, 9, 19 for d = 2, 3, 4) reproducing every second and fourth moment exactly (for a
/// concentrated distribution they tend to the degree-5 Gaussian cubature). Where no positive
/// point set of that kind exists (for d ≥ 4 some distributions with a very broad axis next to
/// a moderately sharp one, about 5 % of random z for d = 4; and |z| beyond about 1e150) it
/// returns the `2d - 1` TAC 2016 points with `lambda` = 0.5 instead, which reproduce the
/// second moment only, and says so (`*reproduced` = 2). `lambda` is ignored.
pub const BINGHAM_SAMPLES_MOMENTS: c_int = 1;

/// The core's scheme for a C scheme code (`lambda` is used by TAC 2016 only; the core checks
/// its range).
fn scheme_of(scheme: c_int, lambda: f64) -> FfiResult<Scheme> {
    match scheme {
        BINGHAM_SAMPLES_TAC2016 => Ok(Scheme::Tac2016 { lambda }),
        BINGHAM_SAMPLES_MOMENTS => Ok(Scheme::Moments),
        _ => Err(Failure::argument(format!(
            "unknown scheme {scheme} (BINGHAM_SAMPLES_TAC2016 = {BINGHAM_SAMPLES_TAC2016}, \
             BINGHAM_SAMPLES_MOMENTS = {BINGHAM_SAMPLES_MOMENTS})"
        ))),
    }
}

fn scheme_name(scheme: c_int) -> &'static str {
    if scheme == BINGHAM_SAMPLES_TAC2016 {
        "BINGHAM_SAMPLES_TAC2016"
    } else {
        "BINGHAM_SAMPLES_MOMENTS"
    }
}

/// The largest number of points `bingham_deterministic_samples()` returns for `d` and `scheme`:
/// the capacity its `points` (capacity x d doubles) and `weights` (capacity doubles) must have.
///
/// - `d`: 2..64.
/// - `scheme`: `BINGHAM_SAMPLES_TAC2016` (`2d - 1` points) or `BINGHAM_SAMPLES_MOMENTS`
///   (`2d² - 4d + 3` points: 3, 9, 19 for d = 2, 3, 4; 7939 for d = 64).
/// - `count`: receives the number.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION` (d), `BINGHAM_ERR_INVALID_ARGUMENT` (unknown
/// `scheme`), `BINGHAM_ERR_NULL_ARGUMENT` (`count`). On error `*count` is not written.
///
/// # Safety
/// `count`: one writable `size_t`.
#[no_mangle]
pub unsafe extern "C" fn bingham_deterministic_sample_count(
    d: usize,
    scheme: c_int,
    count: *mut usize,
) -> bingham_status {
    guard("bingham_deterministic_sample_count", || {
        dim(d)?;
        let s = scheme_of(scheme, 0.5)?;
        // SAFETY: caller contract; one writable size_t.
        let (count,) = unsafe { args!(count: out).read()? };
        // SAFETY: checked place.
        unsafe { count.set(max_count(d, s)) };
        Ok(())
    })
}

/// Deterministic samples of Bingham(M, z): weighted unit vectors whose weighted moments are
/// those of the distribution, for propagating it through a nonlinear function `a` (the
/// "unscented" idea on the sphere): `E[g(a(x))] ≈ Σ_k weights[k] g(a(points[k]))`.
///
/// The points are built in the principal coordinates `y = Mᵀ x` and mapped back by `x = M y`:
/// the mode first, then points around it along the other principal directions (pairs
/// `(mode ± t_i m_i)/‖·‖`) and, for `BINGHAM_SAMPLES_MOMENTS`, along pairs of them (quadruples
/// `(mode ± t_i m_i ± t_j m_j)/‖·‖`; for a "girdle" — two directions much sharper than a
/// third, broad one — the broad direction gets two further centers, with pairs around each). Every point lies in the mode's
/// hemisphere (`−x` is the same point of a Bingham distribution).
///
/// - `d`: 2..64. Checked before any array is read.
/// - `m`: d x d row-major orthogonal (max |MᵀM − I| ≤ `BINGHAM_ORTHOGONALITY_TOL`), columns
///   are the principal directions; `z`: d concentrations, `z[i]` belongs to column i, any order
///   and shift.
/// - `scheme`: `BINGHAM_SAMPLES_TAC2016` (exact second moment, `2d - 1` points) or
///   `BINGHAM_SAMPLES_MOMENTS` (exact second and fourth moments, `2d² - 4d + 3` points, or the
///   TAC 2016 points where that set does not exist); see the constants.
/// - `lambda`: the TAC 2016 weighting parameter, in [0, 1] (0.5 is libDirectional's
///   default): the mode's weight is `lambda * ω_mode` (0: no point at the mode; 1: the pairs
///   lie on the principal axes themselves). Ignored by `BINGHAM_SAMPLES_MOMENTS`.
/// - `capacity`: the number of points `points` and `weights` can hold; must be at least
///   `bingham_deterministic_sample_count(d, scheme)` (the largest count the scheme may return,
///   even where it returns fewer).
/// - `points`: receives `*count` unit vectors, row-major `*count x d` (one point per row); the
///   rows beyond `*count` are not written.
/// - `weights`: receives `*count` weights, each ≥ 0, summing to 1.
/// - `count`: receives the number of points written.
/// - `reproduced`: `NULL`, or receives what the weighted points reproduce exactly (to
///   rounding): 2 = the second moment `E[x xᵀ] = M diag(ω) Mᵀ` (ω_i = ∂ log F/∂z_i); 4 = the
///   second and every fourth moment `E[x_i x_j x_k x_l]`.
///
/// Deterministic: the same inputs give the same points, bit for bit.
///
/// Errors: `BINGHAM_ERR_INVALID_DIMENSION` (d; `capacity` smaller than the needed count, the
/// message says the count), `BINGHAM_ERR_INVALID_ARGUMENT` (unknown `scheme`, `lambda` not in
/// [0, 1] for TAC 2016, NaN/Inf, `m` not orthogonal), `BINGHAM_ERR_NULL_ARGUMENT` (`m`, `z`,
/// `points`, `weights`, `count`), `BINGHAM_ERR_NUMERICAL` (the moments of F cannot be
/// evaluated). On error nothing is written.
///
/// # Safety
/// `m`: d*d and `z`: d readable doubles; `points`: capacity*d and `weights`: capacity writable
/// doubles; `count`: a writable `size_t`; `reproduced`: `NULL` or a writable `int`.
#[no_mangle]
pub unsafe extern "C" fn bingham_deterministic_samples(
    d: usize,
    m: *const f64,
    z: *const f64,
    scheme: c_int,
    lambda: f64,
    capacity: usize,
    points: *mut f64,
    weights: *mut f64,
    count: *mut usize,
    reproduced: *mut c_int,
) -> bingham_status {
    guard("bingham_deterministic_samples", || {
        dim(d)?;
        let s = scheme_of(scheme, lambda)?;
        let list = args!(
            (m, z): bingham [d],
            points: out [capacity.saturating_mul(d)],
            weights: out [capacity],
            count: out,
            reproduced: opt out,
        );
        list.check()?;
        // the capacity: after the pointers, before anything is read
        let needed = max_count(d, s);
        if capacity < needed {
            return Err(Failure::dimension(format!(
                "`capacity` = {capacity} is less than the {needed} points {} may return for \
                 d = {d} (see bingham_deterministic_sample_count)",
                scheme_name(scheme)
            )));
        }
        // SAFETY: checked above; caller contract: lengths d*d and d (d <= 64), capacity*d and
        // capacity writable doubles, a writable size_t and int.
        let (b, points, weights, count, reproduced) = unsafe { list.take()? };
        let samples = b.deterministic_samples(s)?;
        let n = samples.count();
        debug_assert!(n <= capacity && samples.points.len() == n * d);
        let code: c_int = match samples.reproduced {
            Reproduced::SecondMoment => 2,
            Reproduced::FourthMoments => 4,
        };
        // SAFETY: every input has been read; n*d <= capacity*d and n <= capacity values.
        unsafe {
            points.write(&samples.points);
            weights.write(&samples.weights);
            count.set(n);
            if let Some(reproduced) = reproduced {
                reproduced.set(code);
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distribution::Bingham;
    use bingham_status::*;

    #[test]
    fn counts_and_errors() {
        let mut n = 0usize;
        // SAFETY: `n` is a writable size_t; NULL is refused before any write.
        unsafe {
            assert_eq!(
                bingham_deterministic_sample_count(4, BINGHAM_SAMPLES_MOMENTS, &mut n),
                BINGHAM_OK
            );
            assert_eq!(n, 19);
            assert_eq!(
                bingham_deterministic_sample_count(3, BINGHAM_SAMPLES_TAC2016, &mut n),
                BINGHAM_OK
            );
            assert_eq!(n, 5);
            assert_eq!(
                bingham_deterministic_sample_count(3, 2, &mut n),
                BINGHAM_ERR_INVALID_ARGUMENT
            );
            assert_eq!(
                bingham_deterministic_sample_count(1, 0, &mut n),
                BINGHAM_ERR_INVALID_DIMENSION
            );
            assert_eq!(
                bingham_deterministic_sample_count(2, 0, std::ptr::null_mut()),
                BINGHAM_ERR_NULL_ARGUMENT
            );
        }
        assert_eq!(n, 5);
    }

    #[test]
    fn samples_match_the_core() {
        let m = [0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        let z = [-3.0, -1.0, 0.0];
        let mut pts = [7.0; 27];
        let mut w = [7.0; 9];
        let (mut n, mut r) = (0usize, 0 as c_int);
        // SAFETY: arrays of the documented lengths (capacity 9).
        let st = unsafe {
            bingham_deterministic_samples(
                3,
                m.as_ptr(),
                z.as_ptr(),
                BINGHAM_SAMPLES_MOMENTS,
                0.5,
                9,
                pts.as_mut_ptr(),
                w.as_mut_ptr(),
                &mut n,
                &mut r,
            )
        };
        assert_eq!(st, BINGHAM_OK);
        let core = Bingham::from_row_major(3, &m, &z)
            .unwrap()
            .deterministic_samples(Scheme::Moments)
            .unwrap();
        assert_eq!(n, core.count());
        assert_eq!(&pts[..n * 3], &core.points[..]);
        assert_eq!(&w[..n], &core.weights[..]);
        assert_eq!(r, 4);
        // too small a capacity: nothing written
        let mut w2 = [7.0; 9];
        let mut n2 = 99usize;
        // SAFETY: as above; the call fails before writing.
        let st = unsafe {
            bingham_deterministic_samples(
                3,
                m.as_ptr(),
                z.as_ptr(),
                BINGHAM_SAMPLES_MOMENTS,
                0.5,
                8,
                pts.as_mut_ptr(),
                w2.as_mut_ptr(),
                &mut n2,
                std::ptr::null_mut(),
            )
        };
        assert_eq!(st, BINGHAM_ERR_INVALID_DIMENSION);
        assert_eq!((n2, w2), (99, [7.0; 9]));
    }
}
