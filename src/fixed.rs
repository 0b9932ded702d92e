//! Fixed-size, allocation-free counterparts of the core operations for `D ∈ {2, 4}`: the hot
//! path of the recursive filter ([`crate::filter`]).
//!
//! Everything works on stack arrays (`[[f64; D]; D]`, row-major: `m[i][j]` is row `i`, column
//! `j`) and mirrors the general (heap-allocating, `nalgebra::DMatrix`) code of
//! [`crate::distribution`] and [`crate::mle`] step by step, so the two paths agree to rounding:
//! validation and normalization of parameters (`Bingham::new`), second moments, the composition
//! of moments, the symmetric eigendecomposition (the same Jacobi routine; for `D = 2` its single
//! rotation written out), the moment-matching MLE (`mle::newton` itself, the general path's
//! solver, here resuming from a previous solution whose derivatives are known) and the Bayes
//! product. The unit tests below check bitwise agreement of the building blocks, `tests/filter.rs`
//! the agreement of whole filter steps with the general path.
//!
//! Products use the multiplication tables of ℂ and ℍ (scalar first): `L(x)_{ik} = s_{ik} x_{i⊻k}`
//! with the sign tables below (`⊻` is bitwise xor), so `x ⊕ y = L(x) y`,
//! `x ⊕ u = R(u) x` with `R(u)_{ij} = s_{i,i⊻j} u_{i⊻j}`, and the basis matrices
//! `L_a = L(e_a)` are signed permutations: `(L_a)_{i,i⊻a} = s_{i,i⊻a}`.

// Index loops mirror the matrix formulas (and the general path) more clearly than iterators.
#![allow(clippy::needless_range_loop)]

use crate::distribution::{ORTHOGONALITY_TOL, UNIT_TOL};
use crate::error::{Error, Result};
use crate::linalg::jacobi_in_place;
use crate::mle::{newton, NewtonStart, OMEGA_MIN};
use crate::normalization::{log_normalization_into, Method};

/// A `D×D` matrix, row-major (`m[i][j]`: row `i`, column `j`).
pub(crate) type Mat<const D: usize> = [[f64; D]; D];

/// Signs of `L(x)` for complex numbers: `L(x) = [[x0, −x1], [x1, x0]]`.
const SIGN2: [[f64; 2]; 2] = [[1.0, -1.0], [1.0, 1.0]];
/// Signs of `L(x)` for quaternions (scalar first), see `quaternion::left_matrix`.
const SIGN4: [[f64; 4]; 4] = [
    [1.0, -1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0, -1.0],
    [1.0, -1.0, 1.0, 1.0],
];

/// `s_{ik}`: the sign of `x_{i⊻k}` in row `i`, column `k` of `L(x)`.
#[inline(always)]
fn sign<const D: usize>(i: usize, k: usize) -> f64 {
    if D == 2 {
        SIGN2[i][k]
    } else {
        SIGN4[i][k]
    }
}

/// Panics unless `D` is 2 or 4 (a programming error: the filter only instantiates these).
#[inline(always)]
fn assert_dim<const D: usize>() {
    assert!(D == 2 || D == 4, "fixed-size helpers exist for D = 2 and 4");
}

/// The zero matrix.
#[inline(always)]
pub(crate) fn zeros<const D: usize>() -> Mat<D> {
    [[0.0; D]; D]
}

/// `L(x)`, with `x ⊕ y = L(x) y`.
pub(crate) fn left<const D: usize>(x: &[f64; D]) -> Mat<D> {
    assert_dim::<D>();
    let mut l = zeros::<D>();
    for (i, row) in l.iter_mut().enumerate() {
        for (k, v) in row.iter_mut().enumerate() {
            *v = sign::<D>(i, k) * x[i ^ k];
        }
    }
    l
}

/// `R(u)`, with `x ⊕ u = R(u) x`.
pub(crate) fn right<const D: usize>(u: &[f64; D]) -> Mat<D> {
    assert_dim::<D>();
    let mut r = zeros::<D>();
    for (i, row) in r.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = sign::<D>(i, i ^ j) * u[i ^ j];
        }
    }
    r
}

/// `x ⊕ y` (complex or Hamilton product, scalar first).
#[cfg(test)]
pub(crate) fn product<const D: usize>(x: &[f64; D], y: &[f64; D]) -> [f64; D] {
    mat_vec(&left(x), y)
}

/// `A x`.
#[cfg(test)]
pub(crate) fn mat_vec<const D: usize>(a: &Mat<D>, x: &[f64; D]) -> [f64; D] {
    let mut r = [0.0; D];
    for (ri, row) in r.iter_mut().zip(a.iter()) {
        *ri = row.iter().zip(x.iter()).map(|(a, b)| a * b).sum();
    }
    r
}

/// `A B`.
pub(crate) fn mat_mul<const D: usize>(a: &Mat<D>, b: &Mat<D>) -> Mat<D> {
    let mut c = zeros::<D>();
    for i in 0..D {
        for j in 0..D {
            let mut s = 0.0;
            for k in 0..D {
                s += a[i][k] * b[k][j];
            }
            c[i][j] = s;
        }
    }
    c
}

/// `(A + Aᵀ) / 2`.
fn symmetrize<const D: usize>(a: &Mat<D>) -> Mat<D> {
    let mut s = zeros::<D>();
    for i in 0..D {
        for j in 0..D {
            s[i][j] = (a[i][j] + a[j][i]) * 0.5;
        }
    }
    s
}

/// `M diag(w) Mᵀ`, symmetrized (the second moment for `w = ω`, the precision `M Z Mᵀ` for `w = z`).
pub(crate) fn congruence<const D: usize>(m: &Mat<D>, w: &[f64; D]) -> Mat<D> {
    let mut s = zeros::<D>();
    for i in 0..D {
        for j in 0..D {
            let mut t = 0.0;
            for k in 0..D {
                t += m[i][k] * w[k] * m[j][k];
            }
            s[i][j] = t;
        }
    }
    symmetrize(&s)
}

/// `Σ_ab A_ab L_a B L_bᵀ`: the second moment of `x ⊕ y` for independent `x`, `y` with second
/// moments `A`, `B` (symmetrized).
pub(crate) fn compose_moments<const D: usize>(a: &Mat<D>, b: &Mat<D>) -> Mat<D> {
    assert_dim::<D>();
    let mut c = zeros::<D>();
    for i in 0..D {
        for j in 0..D {
            let mut t = 0.0;
            for (x, arow) in a.iter().enumerate() {
                let (ix, sx) = (i ^ x, sign::<D>(i, i ^ x));
                for (y, &axy) in arow.iter().enumerate() {
                    let jy = j ^ y;
                    t += axy * sx * sign::<D>(j, jy) * b[ix][jy];
                }
            }
            c[i][j] = t;
        }
    }
    symmetrize(&c)
}

/// Max-abs deviation of `MᵀM` from the identity.
pub(crate) fn orthogonality_error<const D: usize>(m: &Mat<D>) -> f64 {
    let mut e: f64 = 0.0;
    for i in 0..D {
        for j in 0..D {
            let mut g = 0.0;
            for row in m.iter() {
                g += row[i] * row[j];
            }
            let t = if i == j { 1.0 } else { 0.0 };
            e = e.max((g - t).abs());
        }
    }
    e
}

/// Modified Gram–Schmidt (twice) from the last column (the mode) to the first, as
/// `distribution::reorthonormalize`.
pub(crate) fn reorthonormalize<const D: usize>(m: &mut Mat<D>) {
    for _pass in 0..2 {
        for j in (0..D).rev() {
            for k in (j + 1)..D {
                let dot: f64 = (0..D).map(|i| m[i][j] * m[i][k]).sum();
                for row in m.iter_mut() {
                    row[j] -= dot * row[k];
                }
            }
            let n = (0..D).map(|i| m[i][j] * m[i][j]).sum::<f64>().sqrt();
            let inv = 1.0 / n;
            for row in m.iter_mut() {
                row[j] *= inv;
            }
        }
    }
}

/// Indices `0..D` stably sorted by `key` (ascending, `total_cmp`).
fn argsort<const D: usize>(key: &[f64; D]) -> [usize; D] {
    let mut idx = [0usize; D];
    for (i, v) in idx.iter_mut().enumerate() {
        *v = i;
    }
    // insertion sort: stable, like the `sort_by` of the general path
    for a in 1..D {
        let mut b = a;
        while b > 0 && key[idx[b - 1]].total_cmp(&key[idx[b]]).is_gt() {
            idx.swap(b - 1, b);
            b -= 1;
        }
    }
    idx
}

/// Sort `z` ascending (columns of `m` along), shift so `z[D−1] = 0`, re-orthonormalize `m`:
/// `Bingham::from_parts_unchecked`.
pub(crate) fn normalize<const D: usize>(m: &Mat<D>, z: &[f64; D]) -> (Mat<D>, [f64; D]) {
    let idx = argsort(z);
    let zmax = z[idx[D - 1]];
    let mut zs = [0.0; D];
    let mut ms = zeros::<D>();
    for (k, &i) in idx.iter().enumerate() {
        zs[k] = z[i] - zmax;
        for r in 0..D {
            ms[r][k] = m[r][i];
        }
    }
    reorthonormalize(&mut ms);
    zs[D - 1] = 0.0;
    (ms, zs)
}

/// Checks that every value is finite (message as `error::check_finite`).
fn check_finite(what: &str, values: &[f64]) -> Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(Error::InvalidArgument(format!(
            "{what}[{i}] = {} is not finite",
            values[i]
        ))),
    }
}

/// Validates `(M, z)` (`m` row-major, length D², `z` length D) and normalizes them, as
/// `Bingham::from_row_major`: lengths, finiteness, `max |MᵀM − I| ≤ ORTHOGONALITY_TOL`; then
/// sort, shift and re-orthonormalize.
pub(crate) fn params<const D: usize>(
    m_name: &str,
    m: &[f64],
    z_name: &str,
    z: &[f64],
) -> Result<(Mat<D>, [f64; D])> {
    if m.len() != D * D || z.len() != D {
        return Err(Error::InvalidDimension(format!(
            "expected `{m_name}` of length {} and `{z_name}` of length {D} (d = {D}), got {} and {}",
            D * D,
            m.len(),
            z.len()
        )));
    }
    check_finite(z_name, z)?;
    check_finite(m_name, m)?;
    let mut mm = zeros::<D>();
    let mut zz = [0.0; D];
    for i in 0..D {
        zz[i] = z[i];
        for j in 0..D {
            mm[i][j] = m[i * D + j];
        }
    }
    let err = orthogonality_error(&mm);
    if err.is_nan() || err > ORTHOGONALITY_TOL {
        return Err(Error::InvalidArgument(format!(
            "`{m_name}` is not orthogonal: max |MᵀM − I| = {err:e} exceeds {ORTHOGONALITY_TOL:e}"
        )));
    }
    let (mm, zz) = normalize(&mm, &zz);
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

/// Checks that `x` has length D, is finite and has unit norm within `UNIT_TOL`; returns it
/// normalized (as `distribution::unit_vector`).
pub(crate) fn unit<const D: usize>(what: &str, x: &[f64]) -> Result<[f64; D]> {
    if x.len() != D {
        return Err(Error::InvalidDimension(format!(
            "`{what}` has length {}, expected d = {D}",
            x.len()
        )));
    }
    check_finite(what, x)?;
    let n = x.iter().map(|v| v * v).sum::<f64>().sqrt();
    if n.is_nan() || (n - 1.0).abs() > UNIT_TOL {
        return Err(Error::InvalidArgument(format!(
            "`{what}` must be a unit vector: its norm is {n} (tolerance {UNIT_TOL})"
        )));
    }
    let mut v = [0.0; D];
    for (vi, xi) in v.iter_mut().zip(x.iter()) {
        *vi = xi / n;
    }
    Ok(v)
}

/// `log F(z)` and `ω = ∇ log F(z)` (exact method; allocation-free for D ≤ 4).
pub(crate) fn log_f_omega<const D: usize>(z: &[f64; D]) -> Result<(f64, [f64; D])> {
    let mut w = [0.0; D];
    let lf = log_normalization_into(z, Method::Exact, Some(&mut w), None)?;
    Ok((lf, w))
}

/// Eigendecomposition of a symmetric matrix by the crate's Jacobi routine: eigenvalues
/// ascending with matching eigenvectors as columns, each column's largest-magnitude entry
/// positive (as `distribution::sym_eigen_ascending`).
pub(crate) fn sym_eigen<const D: usize>(c: &Mat<D>) -> Result<(Mat<D>, [f64; D])> {
    if !c.iter().flatten().all(|v| v.is_finite()) {
        return Err(Error::Numerical(
            "eigendecomposition of a non-finite matrix".into(),
        ));
    }
    let mut v = [0.0; 16];
    let mut d = [0.0; 4];
    if D == 2 {
        jacobi_2x2(c[0][0], c[0][1], c[1][1], &mut v, &mut d);
    } else {
        let mut a = [0.0; 16];
        for i in 0..D {
            for j in 0..D {
                a[i * D + j] = c[i][j];
            }
        }
        let mut work = [0.0; 8];
        jacobi_in_place(
            D,
            &mut a[..D * D],
            &mut v[..D * D],
            &mut d[..D],
            &mut work[..2 * D],
        );
    }
    let mut vals = [0.0; D];
    vals.copy_from_slice(&d[..D]);
    let idx = argsort(&vals);
    let mut sorted = [0.0; D];
    let mut vecs = zeros::<D>();
    for (k, &i) in idx.iter().enumerate() {
        sorted[k] = vals[i];
        let mut big = 0.0f64;
        for r in 0..D {
            let x = v[r * D + i];
            if x.abs() > big.abs() {
                big = x;
            }
        }
        let s = if big < 0.0 { -1.0 } else { 1.0 };
        for r in 0..D {
            vecs[r][k] = s * v[r * D + i];
        }
    }
    if !sorted.iter().all(|v| v.is_finite()) || !vecs.iter().flatten().all(|v| v.is_finite()) {
        return Err(Error::Numerical(
            "eigendecomposition produced non-finite values".into(),
        ));
    }
    Ok((vecs, sorted))
}

/// `jacobi_in_place` for `n = 2`, operation for operation: the single rotation of its first
/// sweep (the second sweep finds the off-diagonal zero and stops), without its loop overhead.
/// `v` receives the eigenvectors as columns (row-major 2×2), `d` the eigenvalues (unsorted).
fn jacobi_2x2(a00: f64, a01: f64, a11: f64, v: &mut [f64; 16], d: &mut [f64; 4]) {
    v[..4].copy_from_slice(&[1.0, 0.0, 0.0, 1.0]);
    d[0] = a00;
    d[1] = a11;
    // first sweep: tresh = 0.2·|a01|/4 < |a01| whenever a01 ≠ 0
    if a01 == 0.0 {
        return;
    }
    let g = 100.0 * a01.abs();
    let h = a11 - a00;
    let t = if h.abs() + g == h.abs() {
        a01 / h
    } else {
        let theta = 0.5 * h / a01;
        let t = 1.0 / (theta.abs() + (1.0 + theta * theta).sqrt());
        if theta < 0.0 {
            -t
        } else {
            t
        }
    };
    let c = 1.0 / (1.0 + t * t).sqrt();
    let s = t * c;
    let tau = s / (1.0 + c);
    let ht = t * a01;
    // d[p] -= h, d[q] += h through the accumulators b and z of the sweep
    d[0] = a00 + -ht;
    d[1] = a11 + ht;
    // rotations of the rows of v = I: (g, h) = (1, 0) and (0, 1)
    v[0] = 1.0 - s * (0.0 + tau);
    v[1] = 0.0 + s * (1.0 - 0.0 * tau);
    v[2] = 0.0 - s * (1.0 + 0.0 * tau);
    v[3] = 1.0 + s * (0.0 - tau);
}

/// `log F`'s gradient `ω` and Hessian at a point `z` (as the solver sees it: `z[D−1] = 0`).
/// In a solution returned by [`solve_z`] the Hessian may be that of the previous iterate (see
/// there).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Derivs<const D: usize> {
    pub(crate) z: [f64; D],
    pub(crate) grad: [f64; D],
    pub(crate) hess: Mat<D>,
}

#[cfg(test)]
fn derivs<const D: usize>(z: &[f64; D]) -> Result<Derivs<D>> {
    let mut grad = [0.0; D];
    let mut h = [0.0; 16];
    log_normalization_into(z, Method::Exact, Some(&mut grad), Some(&mut h[..D * D]))?;
    let mut hess = zeros::<D>();
    for (i, row) in hess.iter_mut().enumerate() {
        row.copy_from_slice(&h[i * D..(i + 1) * D]);
    }
    Ok(Derivs { z: *z, grad, hess })
}

/// Where the moment-matching Newton iteration starts.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Start<'a, const D: usize> {
    /// The start `mle::solve_z_into` takes without a guess (`mle::initial_guess`: each `z_i`
    /// from the d = 2 problem of the pair `(i, d)`).
    Cold,
    /// A previous solution with its derivatives (as `solve_z_into` started there, minus the
    /// evaluation at the start, which is already known).
    Evaluated(&'a Derivs<D>),
}

/// Solves `ω(z) = target` (ascending, positive) for `z` (`z[D−1] = 0`) with the MLE's Newton
/// iteration `mle::newton` (the same code as the general path), on stack arrays. Returns the
/// solution with its derivatives (the next call's [`Start::Evaluated`]) and the number of steps;
/// the returned Hessian may be the previous iterate's (see `mle::newton`).
pub(crate) fn solve_z<const D: usize>(
    target: &[f64; D],
    start: Start<'_, D>,
) -> Result<(Derivs<D>, usize)> {
    let mut z = [0.0; D];
    let mut grad = [0.0; D];
    let mut h = [0.0; 16];
    let from = match start {
        Start::Evaluated(d) => {
            z = d.z;
            grad = d.grad;
            for (i, row) in d.hess.iter().enumerate() {
                h[i * D..(i + 1) * D].copy_from_slice(row);
            }
            NewtonStart::Evaluated
        }
        Start::Cold => NewtonStart::Guess,
    };
    let steps = newton(target, from, &mut z, &mut grad, &mut h[..D * D])?;
    let mut hess = zeros::<D>();
    for (i, row) in hess.iter_mut().enumerate() {
        row.copy_from_slice(&h[i * D..(i + 1) * D]);
    }
    Ok((Derivs { z, grad, hess }, steps))
}

/// The Bingham distribution with second moment `s` (symmetric PSD, any positive scale), as
/// `mle::mle_from_second_moment`, with an optional warm start (the previous solution with its
/// derivatives; on failure from there the cold start is tried). Returns normalized `(M, z)`
/// and the solution's derivatives (for the next warm start).
pub(crate) fn mle<const D: usize>(
    s: &Mat<D>,
    warm: Option<&Derivs<D>>,
) -> Result<(Mat<D>, [f64; D], Derivs<D>)> {
    let tr: f64 = (0..D).map(|i| s[i][i]).sum();
    if tr.is_nan() || tr <= 0.0 {
        return Err(Error::InvalidArgument(format!(
            "second moment must have a positive trace, got {tr}"
        )));
    }
    let mut sn = zeros::<D>();
    for i in 0..D {
        for j in 0..D {
            sn[i][j] = s[i][j] / tr;
        }
    }
    let (m, w) = sym_eigen(&symmetrize(&sn))?;
    if w[0] < OMEGA_MIN {
        return Err(Error::InvalidArgument(format!(
            "second moment is singular or not positive semidefinite: smallest eigenvalue \
             (after normalizing the trace to 1) is {:e} < {OMEGA_MIN:e}; the MLE would have \
             infinite concentration",
            w[0]
        )));
    }
    let (sol, _) = match warm {
        Some(d) => solve_z(&w, Start::Evaluated(d)).or_else(|_| solve_z(&w, Start::Cold)),
        None => solve_z(&w, Start::Cold),
    }?;
    let (mm, zz) = normalize(&m, &sol.z);
    Ok((mm, zz, sol))
}

/// Bayes' product of `Bingham(m1, z1)` and the density `∝ exp(xᵀ P2 x)` (`P2` symmetric: a
/// Bingham's `M2 Z2 M2ᵀ`, or a vector observation's `κ K`): eigendecomposition of
/// `M1 Z1 M1ᵀ + P2 = V Λ Vᵀ` (ascending). Returns `(V, Λ)` unshifted, so the caller can
/// use `max Λ` (the log of the normalization's shift). To keep the Jacobi iteration away from
/// overflow for huge concentrations the matrix is scaled by a power of two first (exact, and the
/// Jacobi rotations are invariant under it).
pub(crate) fn product_eigen_precision<const D: usize>(
    m1: &Mat<D>,
    z1: &[f64; D],
    p2: &Mat<D>,
) -> Result<(Mat<D>, [f64; D])> {
    let p1 = congruence(m1, z1);
    let mut c = zeros::<D>();
    let mut big: f64 = 0.0;
    for i in 0..D {
        for j in 0..D {
            c[i][j] = p1[i][j] + p2[i][j];
            big = big.max(c[i][j].abs());
        }
    }
    if !big.is_finite() {
        return Err(Error::Numerical(
            "Bayes product: the concentrations overflow".into(),
        ));
    }
    let scale = if big > 1e100 || (big > 0.0 && big < 1e-100) {
        let e = big.log2().floor() as i32;
        Some(e)
    } else {
        None
    };
    if let Some(e) = scale {
        let f = 2f64.powi(-e);
        c.iter_mut().flatten().for_each(|v| *v *= f);
    }
    let (v, mut l) = sym_eigen(&c)?;
    if let Some(e) = scale {
        let f = 2f64.powi(e);
        l.iter_mut().for_each(|v| *v *= f);
        if !l.iter().all(|v| v.is_finite()) {
            return Err(Error::Numerical(
                "Bayes product: the concentrations overflow".into(),
            ));
        }
    }
    Ok((v, l))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quaternion::{left_matrix, right_matrix};

    fn xorshift(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    fn unit_random<const D: usize>(r: &mut impl FnMut() -> f64) -> [f64; D] {
        let mut x = [0.0; D];
        x.iter_mut().for_each(|v| *v = r());
        let n = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        x.iter_mut().for_each(|v| *v /= n);
        x
    }

    fn products<const D: usize>() {
        let mut r = xorshift(7 + D as u64);
        for _ in 0..50 {
            let x = unit_random::<D>(&mut r);
            let y = unit_random::<D>(&mut r);
            let l = left_matrix(&x);
            let rm = right_matrix(&y);
            let (lf, rf) = (left(&x), right(&y));
            for i in 0..D {
                for j in 0..D {
                    assert_eq!(lf[i][j], l[(i, j)]);
                    assert_eq!(rf[i][j], rm[(i, j)]);
                }
            }
            let p = product(&x, &y);
            let q = crate::quaternion::compose(&x, &y).unwrap();
            let rx = mat_vec(&rf, &x);
            for i in 0..D {
                assert!((p[i] - q[i]).abs() < 1e-15);
                assert!((rx[i] - q[i]).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn product_tables_match_the_quaternion_module() {
        products::<2>();
        products::<4>();
    }

    #[test]
    fn jacobi_2x2_is_jacobi_in_place() {
        let mut r = xorshift(3);
        let mut cases = vec![
            (1.0, 0.0, 2.0),
            (1.0, 1e-300, 1.0),
            (2.0, 3.0, 2.0),
            (-1e12, 5.0, 0.0),
        ];
        for _ in 0..1000 {
            let s = 10f64.powf(8.0 * r());
            cases.push((s * r(), s * r() * 10f64.powf(6.0 * r()), s * r()));
        }
        for (a, b, c) in cases {
            let mut v = [0.0; 16];
            let mut d = [0.0; 4];
            jacobi_2x2(a, b, c, &mut v, &mut d);
            let mut m = [a, b, b, c];
            let (mut v2, mut d2, mut w) = ([0.0; 4], [0.0; 2], [0.0; 4]);
            jacobi_in_place(2, &mut m, &mut v2, &mut d2, &mut w);
            assert_eq!(&v[..4], &v2[..], "{a} {b} {c}");
            assert_eq!(&d[..2], &d2[..], "{a} {b} {c}");
        }
    }

    fn solver_matches<const D: usize>(z0: [f64; D]) {
        let (_, w) = log_f_omega(&z0).unwrap();
        let (sol, _) = solve_z(&w, Start::Cold).unwrap();
        let mut reference = [0.0; D];
        crate::mle::solve_z_into(&w, None, &mut reference).unwrap();
        assert_eq!(sol.z, reference, "cold start, z0 = {z0:?}");
        // warm start from a nearby solution: same iterates as solve_z_into started there
        let mut z1 = z0;
        z1.iter_mut().for_each(|v| *v *= 1.3);
        let (_, w1) = log_f_omega(&z1).unwrap();
        let (sol1, _) = solve_z(&w1, Start::Evaluated(&sol)).unwrap();
        crate::mle::solve_z_into(&w1, Some(&sol.z), &mut reference).unwrap();
        for i in 0..D {
            // the same iteration, but its first step may use the previous iterate's Hessian
            assert!(
                (sol1.z[i] - reference[i]).abs() <= 1e-12 * reference[i].abs().max(1.0),
                "warm start, z1 = {z1:?}: {:?} vs {reference:?}",
                sol1.z
            );
        }
        // started from exact derivatives the iterates are those of solve_z_into
        let exact = derivs(&sol.z).unwrap();
        let (sol2, _) = solve_z(&w1, Start::Evaluated(&exact)).unwrap();
        assert_eq!(
            sol2.z, reference,
            "warm start from exact derivatives, z1 = {z1:?}"
        );
        for i in 0..D - 1 {
            assert!((sol1.z[i] - z1[i]).abs() <= 1e-9 * z1[i].abs().max(1.0));
        }
    }

    #[test]
    fn solver_is_solve_z_into_step_for_step() {
        solver_matches([-1.0, 0.0]);
        solver_matches([-150.0, 0.0]);
        solver_matches([-3e7, 0.0]);
        solver_matches([-1.0, -1.0, -1.0, 0.0]);
        solver_matches([-250.0, -180.0, -2.0, 0.0]);
        solver_matches([-1e6, -1e3, -10.0, 0.0]);
    }

    #[test]
    fn composition_of_moments_matches_the_general_path() {
        let mut r = xorshift(11);
        for d in [2usize, 4] {
            for _ in 0..20 {
                let a = nalgebra::DMatrix::from_fn(d, d, |_, _| r());
                let b = nalgebra::DMatrix::from_fn(d, d, |_, _| r());
                let (a, b) = (&a * a.transpose(), &b * b.transpose());
                let c = crate::distribution::compose_moments(&a, &b);
                let err = if d == 2 {
                    let f = |m: &nalgebra::DMatrix<f64>| {
                        [[m[(0, 0)], m[(0, 1)]], [m[(1, 0)], m[(1, 1)]]]
                    };
                    let cf = compose_moments::<2>(&f(&a), &f(&b));
                    (0..4)
                        .map(|k| (cf[k / 2][k % 2] - c[(k / 2, k % 2)]).abs())
                        .fold(0.0, f64::max)
                } else {
                    let f = |m: &nalgebra::DMatrix<f64>| {
                        let mut o = [[0.0; 4]; 4];
                        for i in 0..4 {
                            for j in 0..4 {
                                o[i][j] = m[(i, j)];
                            }
                        }
                        o
                    };
                    let cf = compose_moments::<4>(&f(&a), &f(&b));
                    (0..16)
                        .map(|k| (cf[k / 4][k % 4] - c[(k / 4, k % 4)]).abs())
                        .fold(0.0, f64::max)
                };
                assert!(err < 1e-14, "d = {d}: {err:e}");
            }
        }
    }
}
