//! The canonical form of user-supplied parameters, generic over the dimension (see
//! [`crate::linalg`]): the pair `(M, z)` of a Bingham distribution (sort `z` ascending with the
//! columns of `M`, shift so `z[d−1] = 0`, re-orthonormalize `M`) and unit vectors.
//! [`crate::Bingham`], the filter and the observations all go through these functions.

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, U1};

use crate::error::{check_finite, Error, Result};
use crate::linalg::{
    argsort, from_row_major, orthogonality_error, reorthonormalize, Square, Vector,
};

/// Largest accepted `max |MᵀM − I|` for a user-supplied `M`; `M` is then re-orthonormalized.
pub const ORTHOGONALITY_TOL: f64 = 1e-6;
/// Largest `max |MᵀM − I|` (8ε) for which a user-supplied `M` is kept without
/// re-orthonormalization.
const ORTHONORMAL_AS_IS: f64 = 8.0 * f64::EPSILON;
/// Largest accepted `|‖x‖ − 1|` for a user-supplied unit vector; it is then normalized. 1e-3:
/// a quaternion written with 4 or 5 decimals (a CSV, a log, a config file) is off unit length by
/// up to about 1e-4 and is harmlessly normalized, while a vector that is not a unit vector at
/// all (an unnormalized direction, a wrong field, a rate in place of an angle) is refused.
pub const UNIT_TOL: f64 = 1e-3;

/// Sorts `z` ascending (moving the columns of `m` along, stable for ties), shifts it so
/// `z[d−1] = 0` and re-orthonormalizes `m`. No validation: for finite parameters, `m`
/// orthonormal to rounding (the entries of `z` may overflow on the shift: callers check).
pub(crate) fn normalize<D: Dim>(m: &Square<D>, z: &Vector<D>) -> (Square<D>, Vector<D>)
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let (mut ms, zs) = normalize_eigen(m, z);
    reorthonormalize(&mut ms);
    (ms, zs)
}

/// [`normalize`] without the re-orthonormalization, for `m` that is orthonormal to a few ulps
/// already: the eigenvectors of [`crate::linalg::sym_eigen`] (its Jacobi rotations keep
/// `MᵀM = I` to a few ulps, `crate::linalg`). The filter's prediction and update take `M` from
/// a fresh eigendecomposition every step, so no error accumulates from step to step.
pub(crate) fn normalize_eigen<D: Dim>(m: &Square<D>, z: &Vector<D>) -> (Square<D>, Vector<D>)
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let (d, _) = m.shape_generic();
    let n = d.value();
    let idx = argsort(z);
    let zmax = z[idx[n - 1]];
    let mut zs = Vector::from_fn_generic(d, U1, |k, _| z[idx[k]] - zmax);
    let ms = Square::from_fn_generic(d, d, |r, k| m[(r, idx[k])]);
    zs[n - 1] = 0.0;
    (ms, zs)
}

/// Validates finite parameters and normalizes them ([`normalize`], without the
/// re-orthonormalization if `M` is orthonormal to 8ε already): `max |MᵀM − I| ≤
/// ORTHOGONALITY_TOL`, and the span of `z` must not overflow. `m_name`, `z_name` name the
/// arguments in the messages.
pub(crate) fn check_normalize<D: Dim>(
    m_name: &str,
    m: &Square<D>,
    z_name: &str,
    z: &Vector<D>,
) -> Result<(Square<D>, Vector<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let err = orthogonality_error(m);
    if err.is_nan() || err > ORTHOGONALITY_TOL {
        return Err(Error::InvalidArgument(format!(
            "`{m_name}` is not orthogonal: max |MᵀM − I| = {err:e} exceeds {ORTHOGONALITY_TOL:e}"
        )));
    }
    // An M orthonormal to a few ulps already (as every M the library returns: Jacobi keeps
    // `MᵀM = I` within 6ε) is kept as it is, so that handing a state back (`set_state` with
    // what `state` returned) reproduces it bit for bit; Gram–Schmidt would only move its last
    // bits.
    let (mm, zz) = if err <= ORTHONORMAL_AS_IS {
        normalize_eigen(m, z)
    } else {
        normalize(m, z)
    };
    // The shift z − max z overflows when the entries span more than the largest double
    // (e.g. z = (MAX, −MAX)): refuse instead of returning a −Inf concentration.
    if let Some(i) = zz.iter().position(|v| !v.is_finite()) {
        return Err(Error::InvalidArgument(format!(
            "`{z_name}`: max z − min z overflows a double (sorted entry {i}); the \
             concentrations must span less than about 1.8e308"
        )));
    }
    Ok((mm, zz))
}

/// Validates `(M, z)` given as slices (`m` row-major of length d², `z` of length d): lengths,
/// finiteness, then [`check_normalize`].
pub(crate) fn params_row_major<D: Dim>(
    d: D,
    m_name: &str,
    m: &[f64],
    z_name: &str,
    z: &[f64],
) -> Result<(Square<D>, Vector<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let n = d.value();
    if m.len() != n * n || z.len() != n {
        return Err(Error::InvalidDimension(format!(
            "expected `{m_name}` of length {} and `{z_name}` of length {n} (d = {n}), got {} and {}",
            n * n,
            m.len(),
            z.len()
        )));
    }
    check_finite(z_name, z)?;
    check_finite(m_name, m)?;
    let mm = from_row_major(d, m);
    let zz = Vector::from_column_slice_generic(d, U1, z);
    check_normalize(m_name, &mm, z_name, &zz)
}

/// Checks that `x` has length d, is finite and has unit norm within [`UNIT_TOL`]; returns it
/// normalized.
pub(crate) fn unit<D: Dim>(what: &str, d: D, x: &[f64]) -> Result<Vector<D>>
where
    DefaultAllocator: Allocator<D>,
{
    if x.len() != d.value() {
        return Err(Error::InvalidDimension(format!(
            "`{what}` has length {}, expected d = {}",
            x.len(),
            d.value()
        )));
    }
    check_finite(what, x)?;
    let n = x.iter().map(|v| v * v).sum::<f64>().sqrt();
    if n.is_nan() || (n - 1.0).abs() > UNIT_TOL {
        return Err(Error::InvalidArgument(format!(
            "`{what}` must be a unit vector: its norm is {n}, more than {UNIT_TOL} from 1 \
             (normalize it first; within the tolerance the library normalizes it)"
        )));
    }
    Ok(Vector::from_fn_generic(d, U1, |i, _| x[i] / n))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Const, Dyn};

    #[test]
    fn normalizes_and_refuses() {
        // z sorted with the columns, shifted, M re-orthonormalized
        let (m, z) =
            params_row_major(Const::<2>, "m", &[0.0, 1.0, 1.0, 0.0], "z", &[3.0, 1.0]).unwrap();
        assert_eq!(z.as_slice(), &[-2.0, 0.0]);
        assert_eq!(m.as_slice(), &[1.0, 0.0, 0.0, 1.0]);
        let e = params_row_major(Dyn(2), "m_w", &[1.0, 0.0, 2e-6, 1.0], "z_w", &[0.0, 0.0]);
        assert!(
            matches!(e, Err(Error::InvalidArgument(ref s)) if s.contains("`m_w` is not orthogonal"))
        );
        let e = params_row_major(
            Dyn(2),
            "m",
            &[1.0, 0.0, 0.0, 1.0],
            "z",
            &[f64::MAX, -f64::MAX],
        );
        assert!(matches!(e, Err(Error::InvalidArgument(ref s)) if s.contains("overflows")));
        let e = params_row_major(Dyn(2), "m", &[1.0, 0.0, 0.0, 1.0], "z", &[f64::NAN, 0.0]);
        assert!(matches!(e, Err(Error::InvalidArgument(ref s)) if s.contains("z[0]")));
        let e = params_row_major(Const::<4>, "m", &[1.0, 0.0, 0.0, 1.0], "z", &[0.0, 0.0]);
        assert!(matches!(e, Err(Error::InvalidDimension(_))));
    }

    #[test]
    fn unit_vectors() {
        let u = unit("u", Const::<2>, &[0.6, 0.8 + 1e-7]).unwrap();
        assert!((u.norm() - 1.0).abs() < 1e-15);
        assert!(unit("u", Dyn(2), &[0.6, 0.9]).is_err());
        assert!(unit("u", Dyn(3), &[0.6, 0.8]).is_err());
        assert!(unit("u", Dyn(2), &[f64::INFINITY, 0.0]).is_err());
    }
}
