//! Small dense matrices, generic over the dimension: the helpers the distribution, the MLE and
//! the filter share, and the sorted symmetric eigendecomposition.
//!
//! Every function takes nalgebra's `OMatrix<f64, D, D>` / `OVector<f64, D>` for any `D: Dim`:
//! with `D = Const<N>` (`SMatrix`, the filter's d = 2 and 4) everything lives on the stack and
//! no function allocates; with `D = Dyn` (`DMatrix`, [`crate::Bingham`] for any d) the results
//! and the scratch are on the heap. The loops are written out in one fixed summation order, so
//! both instantiations give the same numbers bit for bit.

// Index loops mirror the matrix formulas more clearly than iterators.
#![allow(clippy::needless_range_loop)]

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector, U1};

use super::jacobi::jacobi_in_place;
use crate::error::{Error, Result};

/// A `d×d` matrix of the dimension type `D`.
pub(crate) type Square<D> = OMatrix<f64, D, D>;
/// A vector of length `d` of the dimension type `D`.
pub(crate) type Vector<D> = OVector<f64, D>;

/// The zero `d×d` matrix.
#[inline]
pub(crate) fn zeros<D: Dim>(d: D) -> Square<D>
where
    DefaultAllocator: Allocator<D, D>,
{
    Square::zeros_generic(d, d)
}

/// The zero vector of length `d`.
#[inline]
pub(crate) fn zero_vector<D: Dim>(d: D) -> Vector<D>
where
    DefaultAllocator: Allocator<D>,
{
    Vector::zeros_generic(d, U1)
}

/// The `d×d` matrix stored row-major in `m` (`m.len() == d²`, checked by the caller).
pub(crate) fn from_row_major<D: Dim>(d: D, m: &[f64]) -> Square<D>
where
    DefaultAllocator: Allocator<D, D>,
{
    let n = d.value();
    Square::from_fn_generic(d, d, |i, j| m[i * n + j])
}

/// Writes `m` row-major into `out` (`out.len() == d²`, checked by the caller).
pub(crate) fn write_row_major<D: Dim>(m: &Square<D>, out: &mut [f64])
where
    DefaultAllocator: Allocator<D, D>,
{
    let n = m.nrows();
    for i in 0..n {
        for j in 0..n {
            out[i * n + j] = m[(i, j)];
        }
    }
}

/// `(A + Aᵀ) / 2` (exactly symmetric).
pub(crate) fn symmetrize<D: Dim>(a: &Square<D>) -> Square<D>
where
    DefaultAllocator: Allocator<D, D>,
{
    let (d, _) = a.shape_generic();
    Square::from_fn_generic(d, d, |i, j| (a[(i, j)] + a[(j, i)]) * 0.5)
}

/// `M diag(w) Mᵀ`, symmetrized: the second moment for `w = ω`, the precision `M Z Mᵀ` for
/// `w = z`.
pub(crate) fn congruence<D: Dim>(m: &Square<D>, w: &Vector<D>) -> Square<D>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let (d, _) = m.shape_generic();
    let n = d.value();
    let s = Square::from_fn_generic(d, d, |i, j| {
        let mut t = 0.0;
        for k in 0..n {
            t += m[(i, k)] * w[k] * m[(j, k)];
        }
        t
    });
    symmetrize(&s)
}

/// Max-abs deviation of `MᵀM` from the identity.
pub(crate) fn orthogonality_error<D: Dim>(m: &Square<D>) -> f64
where
    DefaultAllocator: Allocator<D, D>,
{
    let n = m.nrows();
    let mut e: f64 = 0.0;
    for i in 0..n {
        for j in 0..n {
            let mut g = 0.0;
            for r in 0..n {
                g += m[(r, i)] * m[(r, j)];
            }
            let t = if i == j { 1.0 } else { 0.0 };
            e = e.max((g - t).abs());
        }
    }
    e
}

/// Modified Gram–Schmidt (twice), from the last column (the mode) to the first, so the mode's
/// direction is kept exactly up to rounding.
pub(crate) fn reorthonormalize<D: Dim>(m: &mut Square<D>)
where
    DefaultAllocator: Allocator<D, D>,
{
    let n = m.ncols();
    for _pass in 0..2 {
        for j in (0..n).rev() {
            for k in (j + 1)..n {
                let dot: f64 = (0..n).map(|i| m[(i, j)] * m[(i, k)]).sum();
                for i in 0..n {
                    m[(i, j)] -= dot * m[(i, k)];
                }
            }
            let norm = (0..n).map(|i| m[(i, j)] * m[(i, j)]).sum::<f64>().sqrt();
            let inv = 1.0 / norm;
            for i in 0..n {
                m[(i, j)] *= inv;
            }
        }
    }
}

/// Indices `0..d` stably sorted by `key` (ascending, `total_cmp`).
pub(crate) fn argsort<D: Dim>(key: &Vector<D>) -> OVector<usize, D>
where
    DefaultAllocator: Allocator<D>,
{
    let (d, _) = key.shape_generic();
    let mut idx = OVector::<usize, D>::from_fn_generic(d, U1, |i, _| i);
    // insertion sort: stable, and allocation-free for every d
    for a in 1..idx.len() {
        let mut b = a;
        while b > 0 && key[idx[b - 1]].total_cmp(&key[idx[b]]).is_gt() {
            idx.swap_rows(b - 1, b);
            b -= 1;
        }
    }
    idx
}

/// Eigendecomposition of a symmetric matrix by the crate's Jacobi routine
/// ([`crate::linalg::jacobi_in_place`], which reads the upper triangle): eigenvalues ascending
/// (stable order for ties) with matching eigenvectors as columns, each column's
/// largest-magnitude entry positive (deterministic output).
pub(crate) fn sym_eigen<D: Dim>(c: &Square<D>) -> Result<(Square<D>, Vector<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    check_finite_input(c)?;
    let (vt, vals) = jacobi_unsorted(c);
    sort_and_sign(&vals, |r, i| vt[(i, r)])
}

/// Largest `max |MᵀM − I|` of a basis [`sym_eigen_in_basis`] accepts (2^-50 ≈ 8.9e-16, four
/// ulps of 1: what the Jacobi routine's eigenvectors have, so that the warm-started result is
/// orthonormal to a few ulps like the cold one). A basis that has drifted further (the
/// filter's `M` after many exact rotations and warm-started steps) is declined, and the caller
/// decomposes cold, which restores the orthonormality.
pub(crate) const WARM_BASIS_TOL: f64 = 8.881_784_197_001_252e-16;

/// Whether `m` is orthonormal enough to warm-start [`sym_eigen_in_basis`]
/// (`max |MᵀM − I| ≤ WARM_BASIS_TOL`, the upper triangle of `MᵀM` checked; NaN fails).
pub(crate) fn warm_basis<D: Dim>(m: &Square<D>) -> bool
where
    DefaultAllocator: Allocator<D, D>,
{
    let n = m.nrows();
    for i in 0..n {
        for j in i..n {
            let mut g = 0.0;
            for r in 0..n {
                g += m[(r, i)] * m[(r, j)];
            }
            let t = if i == j { 1.0 } else { 0.0 };
            // (a NaN fails the test)
            if (g - t).abs().is_nan() || (g - t).abs() > WARM_BASIS_TOL {
                return false;
            }
        }
    }
    true
}

/// `Mᵀ C M` of a symmetric `c` (the upper triangle computed, the lower mirrored: exactly
/// symmetric): `c` in the basis of the columns of `m`.
pub(crate) fn in_basis<D: Dim>(c: &Square<D>, m: &Square<D>) -> Square<D>
where
    DefaultAllocator: Allocator<D, D>,
{
    let (d, _) = c.shape_generic();
    let n = d.value();
    let cm = Square::from_fn_generic(d, d, |i, j| {
        let mut t = 0.0;
        for k in 0..n {
            t += c[(i, k)] * m[(k, j)];
        }
        t
    });
    let mut b = zeros(d);
    for i in 0..n {
        for j in i..n {
            let mut t = 0.0;
            for k in 0..n {
                t += m[(k, i)] * cm[(k, j)];
            }
            b[(i, j)] = t;
            b[(j, i)] = t;
        }
    }
    b
}

/// [`sym_eigen`] of `M B Mᵀ` given `b` (symmetric, upper triangle read) and an orthonormal `m`
/// ([`warm_basis`]), warm-started from the basis `m`: Jacobi runs on `b` (in the filter `b` is
/// `C` expressed in the previous eigenbasis, nearly diagonal, so it converges in fewer sweeps)
/// and the eigenvectors are `M · V_B`. Same conventions as [`sym_eigen`] (ascending, each
/// column's largest-magnitude entry positive); the eigenpairs agree with those of the cold
/// decomposition of `M B Mᵀ` to rounding.
pub(crate) fn sym_eigen_in_basis<D: Dim>(
    b: &Square<D>,
    m: &Square<D>,
) -> Result<(Square<D>, Vector<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    check_finite_input(b)?;
    let (vt, vals) = jacobi_unsorted(b);
    let (d, _) = b.shape_generic();
    let n = d.value();
    // V = M · V_B, with `vt[(i, k)]` entry k of eigenvector i of `b`
    let v = Square::from_fn_generic(d, d, |r, i| {
        let mut t = 0.0;
        for k in 0..n {
            t += m[(r, k)] * vt[(i, k)];
        }
        t
    });
    sort_and_sign(&vals, |r, i| v[(r, i)])
}

/// The error of [`sym_eigen`] for a matrix with a non-finite entry.
fn check_finite_input<D: Dim>(c: &Square<D>) -> Result<()>
where
    DefaultAllocator: Allocator<D, D>,
{
    if !c.iter().all(|v| v.is_finite()) {
        return Err(Error::Numerical(
            "eigendecomposition of a non-finite matrix".into(),
        ));
    }
    Ok(())
}

/// The Jacobi routine on `c`: `(Vᵀ, λ)` unsorted, row `i` of `Vᵀ` the eigenvector of `λ_i`.
fn jacobi_unsorted<D: Dim>(c: &Square<D>) -> (Square<D>, Vector<D>)
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let (d, _) = c.shape_generic();
    let n = d.value();
    // The column-major storage of `cᵀ` is `c` row-major, as the routine reads it; `v` comes back
    // row-major (eigenvectors as columns), which read column-major is `Vᵀ`.
    let mut a = c.transpose();
    let mut vt = zeros(d);
    let mut vals = zero_vector(d);
    // 2n scratch entries, used only for n ≥ 5 (n ≤ 4 runs on local arrays)
    let mut work = zeros(d);
    jacobi_in_place(
        n,
        a.as_mut_slice(),
        vt.as_mut_slice(),
        vals.as_mut_slice(),
        &mut work.as_mut_slice()[..2 * n],
    );
    (vt, vals)
}

/// The eigenpairs `vals`, `v(r, i)` (entry `r` of the eigenvector of `vals[i]`) sorted
/// ascending (stable for ties), each eigenvector's largest-magnitude entry made positive;
/// non-finite results are an error.
fn sort_and_sign<D: Dim>(
    vals: &Vector<D>,
    v: impl Fn(usize, usize) -> f64,
) -> Result<(Square<D>, Vector<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let (d, _) = vals.shape_generic();
    let n = d.value();
    let idx = argsort(vals);
    let mut sorted = zero_vector(d);
    let mut vecs = zeros(d);
    for (k, &i) in idx.iter().enumerate() {
        sorted[k] = vals[i];
        let mut big = 0.0f64;
        for r in 0..n {
            let x = v(r, i);
            if x.abs() > big.abs() {
                big = x;
            }
        }
        let s = if big < 0.0 { -1.0 } else { 1.0 };
        for r in 0..n {
            vecs[(r, k)] = s * v(r, i);
        }
    }
    if !sorted.iter().all(|v| v.is_finite()) || !vecs.iter().all(|v| v.is_finite()) {
        return Err(Error::Numerical(
            "eigendecomposition produced non-finite values".into(),
        ));
    }
    Ok((vecs, sorted))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Const, DMatrix, Dyn, SMatrix};

    use testkit::xorshift;

    #[test]
    fn sym_eigen_sorts_fixes_signs_and_reconstructs() {
        let mut r = xorshift(5);
        for n in [2usize, 3, 4, 7] {
            for _ in 0..50 {
                let g = DMatrix::from_fn(n, n, |_, _| r());
                let c = symmetrize(&(&g * g.transpose()));
                let (v, l) = sym_eigen(&c).unwrap();
                for k in 1..n {
                    assert!(l[k - 1] <= l[k]);
                }
                for k in 0..n {
                    let big =
                        v.column(k).iter().fold(
                            0.0f64,
                            |a, &x| {
                                if x.abs() > a.abs() {
                                    x
                                } else {
                                    a
                                }
                            },
                        );
                    assert!(big > 0.0);
                }
                let rec = &v * DMatrix::from_diagonal(&l) * v.transpose();
                assert!((rec - &c).amax() < 1e-14);
                assert!(orthogonality_error(&v) < 1e-14);
            }
        }
        let bad = SMatrix::<f64, 2, 2>::new(1.0, f64::NAN, f64::NAN, 1.0);
        assert!(matches!(sym_eigen(&bad), Err(Error::Numerical(_))));
    }

    #[test]
    fn fixed_and_dynamic_sizes_agree_bit_for_bit() {
        let mut r = xorshift(9);
        for _ in 0..20 {
            let g = SMatrix::<f64, 4, 4>::from_fn(|_, _| r());
            let w = nalgebra::SVector::<f64, 4>::from_fn(|_, _| r());
            let gd = DMatrix::from_column_slice(4, 4, g.as_slice());
            let wd = nalgebra::DVector::from_column_slice(w.as_slice());
            let (s, sd) = (congruence(&g, &w), congruence(&gd, &wd));
            assert_eq!(s.as_slice(), sd.as_slice());
            let (v, l) = sym_eigen::<Const<4>>(&s).unwrap();
            let (vd, ld) = sym_eigen::<Dyn>(&sd).unwrap();
            assert_eq!(v.as_slice(), vd.as_slice());
            assert_eq!(l.as_slice(), ld.as_slice());
            let (mut q, mut qd) = (g, gd);
            reorthonormalize(&mut q);
            reorthonormalize(&mut qd);
            assert_eq!(q.as_slice(), qd.as_slice());
            assert!(orthogonality_error(&q) < 1e-15);
        }
    }

    #[test]
    fn argsort_is_stable() {
        let key = nalgebra::DVector::from_vec(vec![2.0, -1.0, 2.0, -0.0, 0.0, -1.0]);
        let idx = argsort(&key);
        assert_eq!(idx.as_slice(), &[1, 5, 3, 4, 0, 2]);
    }

    #[test]
    fn row_major_round_trip() {
        let m: Vec<f64> = (0..9).map(f64::from).collect();
        let a = from_row_major(Dyn(3), &m);
        assert_eq!(a[(0, 1)], 1.0);
        assert_eq!(a[(1, 0)], 3.0);
        let mut out = vec![0.0; 9];
        write_row_major(&a, &mut out);
        assert_eq!(out, m);
    }
}
