//! Composition `x ⊕ y = L(x) y = R(y) x` for d = 2 (complex numbers `(re, im)`) and d = 4
//! (quaternions, scalar first `(w, x, y, z)`, Hamilton product).
//!
//! The matrix helpers take slices of length 2 or 4 (callers check); other lengths give an
//! empty matrix.

use nalgebra::DMatrix;

/// `L(x)` with `x ⊕ y = L(x) y` (`x.len()` 2 or 4).
pub fn left_matrix(x: &[f64]) -> DMatrix<f64> {
    match x.len() {
        2 => DMatrix::from_row_slice(2, 2, &[x[0], -x[1], x[1], x[0]]),
        4 => DMatrix::from_row_slice(
            4,
            4,
            &[
                x[0], -x[1], -x[2], -x[3], //
                x[1], x[0], -x[3], x[2], //
                x[2], x[3], x[0], -x[1], //
                x[3], -x[2], x[1], x[0],
            ],
        ),
        _ => DMatrix::zeros(0, 0),
    }
}

/// `R(u)` with `x ⊕ u = R(u) x` (`u.len()` 2 or 4).
pub fn right_matrix(u: &[f64]) -> DMatrix<f64> {
    match u.len() {
        2 => left_matrix(u),
        4 => DMatrix::from_row_slice(
            4,
            4,
            &[
                u[0], -u[1], -u[2], -u[3], //
                u[1], u[0], u[3], -u[2], //
                u[2], -u[3], u[0], u[1], //
                u[3], u[2], -u[1], u[0],
            ],
        ),
        _ => DMatrix::zeros(0, 0),
    }
}

/// `x ⊕ y` (complex or Hamilton product); `None` unless both have length 2 or both 4.
pub fn compose(x: &[f64], y: &[f64]) -> Option<Vec<f64>> {
    if x.len() != y.len() || !(x.len() == 2 || x.len() == 4) {
        return None;
    }
    let l = left_matrix(x);
    Some(
        (l * nalgebra::DVector::from_column_slice(y))
            .as_slice()
            .to_vec(),
    )
}

/// The conjugate `D x`, `D = diag(1, −1, …, −1)` (the inverse of a unit element).
pub fn conjugate(x: &[f64]) -> Vec<f64> {
    x.iter()
        .enumerate()
        .map(|(i, v)| if i == 0 { *v } else { -*v })
        .collect()
}
