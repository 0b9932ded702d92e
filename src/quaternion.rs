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

/// Fixed-size helpers for unit quaternions (scalar first) used by the AHRS.
pub mod q4 {
    /// The Hamilton product `a ⊗ b`.
    pub fn mul(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
        [
            a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
            a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
            a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
            a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
        ]
    }

    /// The conjugate (the inverse of a unit quaternion).
    pub fn conj(q: &[f64; 4]) -> [f64; 4] {
        [q[0], -q[1], -q[2], -q[3]]
    }

    /// `R(q) v = q ⊗ v ⊗ q*` (for unit `q`).
    pub fn rotate(q: &[f64; 4], v: &[f64; 3]) -> [f64; 3] {
        let (w, x, y, z) = (q[0], q[1], q[2], q[3]);
        // t = 2 (u × v), v' = v + w t + u × t, u the vector part.
        let t = [
            2.0 * (y * v[2] - z * v[1]),
            2.0 * (z * v[0] - x * v[2]),
            2.0 * (x * v[1] - y * v[0]),
        ];
        [
            v[0] + w * t[0] + (y * t[2] - z * t[1]),
            v[1] + w * t[1] + (z * t[0] - x * t[2]),
            v[2] + w * t[2] + (x * t[1] - y * t[0]),
        ]
    }

    /// `R(q)ᵀ v` (for unit `q`).
    pub fn rotate_inverse(q: &[f64; 4], v: &[f64; 3]) -> [f64; 3] {
        rotate(&conj(q), v)
    }

    /// The unit quaternion of the rotation vector `v` (axis × angle, radians): `exp(v/2)`.
    pub fn from_rotation_vector(v: &[f64; 3]) -> [f64; 4] {
        let theta = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let half = 0.5 * theta;
        // sin(θ/2)/θ, by its series where θ is tiny (relative error below 1e-17).
        let s = if theta < 1e-4 {
            0.5 - theta * theta / 48.0
        } else {
            half.sin() / theta
        };
        [half.cos(), s * v[0], s * v[1], s * v[2]]
    }

    /// The rotation vector of a unit quaternion (angle in `[0, π]`; `q` and `−q` give the same).
    pub fn to_rotation_vector(q: &[f64; 4]) -> [f64; 3] {
        let sgn = if q[0] < 0.0 { -1.0 } else { 1.0 };
        let (w, v) = (sgn * q[0], [sgn * q[1], sgn * q[2], sgn * q[3]]);
        let s = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        // angle / sin(angle/2), angle = 2 atan2(s, w)
        let f = if s < 1e-12 {
            2.0 / w.max(f64::MIN_POSITIVE)
        } else {
            2.0 * s.atan2(w) / s
        };
        [f * v[0], f * v[1], f * v[2]]
    }

    /// The unit quaternion of a rotation matrix (row-major, `v_world = R v_body`).
    pub fn from_matrix(r: &[[f64; 3]; 3]) -> [f64; 4] {
        let tr = r[0][0] + r[1][1] + r[2][2];
        let q = if tr > 0.0 {
            let s = (tr + 1.0).sqrt() * 2.0;
            [
                0.25 * s,
                (r[2][1] - r[1][2]) / s,
                (r[0][2] - r[2][0]) / s,
                (r[1][0] - r[0][1]) / s,
            ]
        } else if r[0][0] > r[1][1] && r[0][0] > r[2][2] {
            let s = (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt() * 2.0;
            [
                (r[2][1] - r[1][2]) / s,
                0.25 * s,
                (r[0][1] + r[1][0]) / s,
                (r[0][2] + r[2][0]) / s,
            ]
        } else if r[1][1] > r[2][2] {
            let s = (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt() * 2.0;
            [
                (r[0][2] - r[2][0]) / s,
                (r[0][1] + r[1][0]) / s,
                0.25 * s,
                (r[1][2] + r[2][1]) / s,
            ]
        } else {
            let s = (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt() * 2.0;
            [
                (r[1][0] - r[0][1]) / s,
                (r[0][2] + r[2][0]) / s,
                (r[1][2] + r[2][1]) / s,
                0.25 * s,
            ]
        };
        let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
        [q[0] / n, q[1] / n, q[2] / n, q[3] / n]
    }
}
