//! Composition `x ⊕ y = L(x) y = R(y) x` for d = 2 (complex numbers `(re, im)`) and d = 4
//! (quaternions, scalar first `(w, x, y, z)`, Hamilton product), and the second moment of a
//! composition.
//!
//! The products use the multiplication tables of ℂ and ℍ: `L(x)_{ik} = s_{ik} x_{i⊻k}` with the
//! sign tables below (`⊻` is bitwise xor), so `x ⊕ y = L(x) y`, `x ⊕ u = R(u) x` with
//! `R(u)_{ij} = s_{i,i⊻j} u_{i⊻j}`, and the basis matrices `L_a = L(e_a)` are signed
//! permutations: `(L_a)_{i,i⊻a} = s_{i,i⊻a}`. The crate-internal functions are generic over the
//! dimension type (see the `matrix` module); the public matrix helpers take slices of length 2 or 4
//! (callers check); other lengths give an empty matrix.

// Index loops mirror the matrix formulas more clearly than iterators.
#![allow(clippy::needless_range_loop)]

use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DefaultAllocator, Dim, Dyn};

use crate::linalg::{symmetrize, zeros, Square};

/// Signs of `L(x)` for complex numbers: `L(x) = [[x0, −x1], [x1, x0]]`.
const SIGN2: [[f64; 2]; 2] = [[1.0, -1.0], [1.0, 1.0]];
/// Signs of `L(x)` for quaternions (scalar first), see [`left_matrix`].
const SIGN4: [[f64; 4]; 4] = [
    [1.0, -1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0, -1.0],
    [1.0, -1.0, 1.0, 1.0],
];

/// `s_{ik}`: the sign of `x_{i⊻k}` in row `i`, column `k` of `L(x)` (`n` = 2 or 4).
#[inline(always)]
fn sign(n: usize, i: usize, k: usize) -> f64 {
    if n == 2 {
        SIGN2[i][k]
    } else {
        SIGN4[i][k]
    }
}

/// Panics unless `n` is 2 or 4 (a programming error: callers check the dimension).
#[inline(always)]
fn assert_dim(n: usize) {
    assert!(n == 2 || n == 4, "products exist for d = 2 and 4");
}

/// `L(x)`, with `x ⊕ y = L(x) y` (`x` of length 2 or 4).
pub(crate) fn left<D: Dim>(d: D, x: &[f64]) -> Square<D>
where
    DefaultAllocator: Allocator<D, D>,
{
    let n = d.value();
    assert_dim(n);
    Square::from_fn_generic(d, d, |i, k| sign(n, i, k) * x[i ^ k])
}

/// `R(u)`, with `x ⊕ u = R(u) x` (`u` of length 2 or 4).
pub(crate) fn right<D: Dim>(d: D, u: &[f64]) -> Square<D>
where
    DefaultAllocator: Allocator<D, D>,
{
    let n = d.value();
    assert_dim(n);
    Square::from_fn_generic(d, d, |i, j| sign(n, i, i ^ j) * u[i ^ j])
}

/// `Σ_ab A_ab L_a B L_bᵀ`: the second moment of `x ⊕ y` for independent `x`, `y` with second
/// moments `A`, `B` (d = 2 or 4; symmetrized).
pub(crate) fn compose_moments<D: Dim>(a: &Square<D>, b: &Square<D>) -> Square<D>
where
    DefaultAllocator: Allocator<D, D>,
{
    let (d, _) = a.shape_generic();
    let n = d.value();
    assert_dim(n);
    let mut c = zeros(d);
    for i in 0..n {
        for j in 0..n {
            let mut t = 0.0;
            for x in 0..n {
                let (ix, sx) = (i ^ x, sign(n, i, i ^ x));
                for y in 0..n {
                    let jy = j ^ y;
                    t += a[(x, y)] * sx * sign(n, j, jy) * b[(ix, jy)];
                }
            }
            c[(i, j)] = t;
        }
    }
    symmetrize(&c)
}

/// `L(x)` with `x ⊕ y = L(x) y` (`x.len()` 2 or 4).
pub fn left_matrix(x: &[f64]) -> DMatrix<f64> {
    match x.len() {
        2 | 4 => left(Dyn(x.len()), x),
        _ => DMatrix::zeros(0, 0),
    }
}

/// `R(u)` with `x ⊕ u = R(u) x` (`u.len()` 2 or 4).
pub fn right_matrix(u: &[f64]) -> DMatrix<f64> {
    match u.len() {
        2 | 4 => right(Dyn(u.len()), u),
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
    ///
    /// Below [`SERIES_ANGLE`] (every gyroscope increment of an IMU sampled at 50 Hz or faster
    /// below 12 rad/s) `cos(θ/2)` and `sin(θ/2)/θ` come from their Taylor series in
    /// `(θ/2)²`, truncated where the first omitted term is below 1e-17 relative: as exact as
    /// the library's `sin` and `cos` (within an ulp of them, `tests/q4.rs`), a tenth of
    /// their cost.
    pub fn from_rotation_vector(v: &[f64; 3]) -> [f64; 4] {
        let t2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        let (c, s) = if t2 < SERIES_ANGLE * SERIES_ANGLE {
            // h = θ/2, x = h²: cos h = Σ (−x)^k/(2k)!, sin(h)/θ = ½ Σ (−x)^k/(2k+1)!
            let x = 0.25 * t2;
            let c = 1.0
                - x * (1.0 / 2.0
                    - x * (1.0 / 24.0
                        - x * (1.0 / 720.0 - x * (1.0 / 40_320.0 - x * (1.0 / 3_628_800.0)))));
            let s = 0.5
                * (1.0
                    - x * (1.0 / 6.0
                        - x * (1.0 / 120.0 - x * (1.0 / 5_040.0 - x * (1.0 / 362_880.0)))));
            (c, s)
        } else {
            let theta = t2.sqrt();
            let half = 0.5 * theta;
            (half.cos(), half.sin() / theta)
        };
        [c, s * v[0], s * v[1], s * v[2]]
    }

    /// The largest angle (rad) [`from_rotation_vector`] takes by its series: at `θ/2` = 0.125
    /// the first omitted terms, `(θ/2)¹²/12!` of the cosine and `(θ/2)¹⁰/11!` of the sine's
    /// ratio, are 3.0e-20 and 2.3e-17 relative.
    pub const SERIES_ANGLE: f64 = 0.25;

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

    /// The rotation matrix `R(q)` of a unit quaternion (row-major, `v_world = R v_body`); the
    /// inverse of [`from_matrix`].
    pub fn to_matrix(q: &[f64; 4]) -> [[f64; 3]; 3] {
        let (w, x, y, z) = (q[0], q[1], q[2], q[3]);
        [
            [
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y - w * z),
                2.0 * (x * z + w * y),
            ],
            [
                2.0 * (x * y + w * z),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z - w * x),
            ],
            [
                2.0 * (x * z - w * y),
                2.0 * (y * z + w * x),
                1.0 - 2.0 * (x * x + y * y),
            ],
        ]
    }
}

#[cfg(test)]
mod q4_matrix_tests {
    use super::q4;

    #[test]
    fn to_matrix_is_rotate_and_from_matrix_inverts_it() {
        for v in [[0.3, -0.2, 0.5], [2.9, 0.1, -0.4], [0.0, 0.0, 3.1]] {
            let q = q4::from_rotation_vector(&v);
            let r = q4::to_matrix(&q);
            for e in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.2, -0.7, 0.4]] {
                let want = q4::rotate(&q, &e);
                for i in 0..3 {
                    let got = r[i][0] * e[0] + r[i][1] * e[1] + r[i][2] * e[2];
                    assert!((got - want[i]).abs() < 1e-15);
                }
            }
            let back = q4::from_matrix(&r);
            let d: f64 = back.iter().zip(&q).map(|(a, b)| a * b).sum();
            assert!((d.abs() - 1.0).abs() < 1e-14);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Const, SMatrix, SVector};

    use testkit::xorshift;

    fn unit_random<const D: usize>(r: &mut impl FnMut() -> f64) -> SVector<f64, D> {
        SVector::<f64, D>::from_fn(|_, _| r()).normalize()
    }

    /// The sign tables against the written-out products of `q4` and the definitions.
    fn products<const D: usize>() {
        let mut r = xorshift(7 + D as u64);
        for _ in 0..50 {
            let x = unit_random::<D>(&mut r);
            let y = unit_random::<D>(&mut r);
            let (lf, rf) = (
                left(Const::<D>, x.as_slice()),
                right(Const::<D>, y.as_slice()),
            );
            let p = lf * y;
            let rx = rf * x;
            let q: Vec<f64> = if D == 4 {
                let a = [x[0], x[1], x[2], x[3]];
                let b = [y[0], y[1], y[2], y[3]];
                q4::mul(&a, &b).to_vec()
            } else {
                vec![x[0] * y[0] - x[1] * y[1], x[0] * y[1] + x[1] * y[0]]
            };
            for i in 0..D {
                assert!((p[i] - q[i]).abs() < 1e-15);
                assert!((rx[i] - q[i]).abs() < 1e-15);
            }
            assert_eq!(compose(x.as_slice(), y.as_slice()).unwrap(), p.as_slice());
        }
    }

    #[test]
    fn product_tables_match_the_products() {
        products::<2>();
        products::<4>();
        assert_eq!(left_matrix(&[1.0, 2.0, 3.0]).len(), 0);
        assert!(compose(&[1.0, 0.0], &[1.0, 0.0, 0.0, 0.0]).is_none());
    }

    /// The second moment of `x ⊕ y` against its definition `E[L(x) y yᵀ L(x)ᵀ]` with `x`, `y`
    /// taking finitely many values (weights `p`, `q`): `A = Σ p_k x_k x_kᵀ`, `B` likewise.
    fn composed_moment<const D: usize>() {
        let mut r = xorshift(11 + D as u64);
        for _ in 0..10 {
            let xs: Vec<SVector<f64, D>> = (0..3).map(|_| unit_random::<D>(&mut r)).collect();
            let ys: Vec<SVector<f64, D>> = (0..3).map(|_| unit_random::<D>(&mut r)).collect();
            let p = [0.2, 0.3, 0.5];
            let q = [0.6, 0.1, 0.3];
            let mut a = SMatrix::<f64, D, D>::zeros();
            let mut b = SMatrix::<f64, D, D>::zeros();
            let mut expect = SMatrix::<f64, D, D>::zeros();
            for (k, x) in xs.iter().enumerate() {
                a += x * x.transpose() * p[k];
                for (l, y) in ys.iter().enumerate() {
                    let xy = left(Const::<D>, x.as_slice()) * y;
                    expect += xy * xy.transpose() * (p[k] * q[l]);
                }
            }
            for (l, y) in ys.iter().enumerate() {
                b += y * y.transpose() * q[l];
            }
            let c = compose_moments(&a, &b);
            assert!((c - expect).amax() < 1e-15, "d = {D}");
            let cd = compose_moments(
                &DMatrix::from_column_slice(D, D, a.as_slice()),
                &DMatrix::from_column_slice(D, D, b.as_slice()),
            );
            assert_eq!(cd.as_slice(), c.as_slice());
        }
    }

    #[test]
    fn composition_of_moments_is_the_moment_of_the_composition() {
        composed_moment::<2>();
        composed_moment::<4>();
    }
}
