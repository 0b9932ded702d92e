//! Maximum-likelihood estimation (moment matching): the Bingham whose second moment equals a
//! given one.
//!
//! Eigendecompose `S = M diag(ω̂) Mᵀ` (ω̂ ascending), then solve `ω_i(z) = ω̂_i` for `i < d`
//! with `z_d = 0` by Newton's method with the exact Jacobian `∂ω_i/∂z_j = Cov(x_i², x_j²)`
//! (positive definite on the constrained space) and a backtracking line search on the
//! relative residual. The solution is unique; it exists iff all ω̂_i > 0.
//!
//! One implementation, generic over the dimension type (see the `matrix` module): the public
//! functions (`Dyn`, or the stack types for d ≤ 4) and the filter's predict (`Const<2>`,
//! `Const<4>`, warm-started from the previous prediction's solution and derivatives) both call
//! `fit_second_moment`. The composition [`Bingham::compose`] (moment matching) lives here too.
//!
//! Files: this one holds the public fitting API; `solution` the solution type (`Derivs`) and
//! what the solvers share; `newton` the Newton iteration for d ≥ 3 with its starts; `asymptotic`
//! the series of the moment map for concentrated Binghams that corrects its steps (d = 3, 4);
//! `d2` the closed-form d = 2 solver.

mod asymptotic;
mod d2;
mod newton;
mod solution;

use nalgebra::allocator::Allocator;
use nalgebra::{Const, DMatrix, DefaultAllocator, Dim, Dyn};

use crate::canonical::{normalize_eigen, unit};
use crate::distribution::Bingham;
use crate::error::{check_dim, check_finite, Error, Result};
use crate::linalg::{
    in_basis, sym_eigen, sym_eigen_in_basis, symmetrize, warm_basis, Square, Vector,
};
use crate::quaternion::compose_moments;

use newton::{solve_z, Start};
pub(crate) use solution::Derivs;
pub use solution::MLE_TOL;

/// Smallest accepted eigenvalue of the trace-normalized second moment. Below it the moment
/// is singular to working precision (the eigenvalues of `S` are only known to about 1e-16) and
/// the maximum-likelihood concentration would be `−∞`. ω̂ = 1e-13 corresponds to z ≈ −5e12.
pub const OMEGA_MIN: f64 = 1e-13;

/// The Bingham distribution with second moment `s` (d×d, symmetric within 1e-10·trace,
/// positive semidefinite, any positive scale: it is normalized by its trace).
/// Errors: wrong shape, non-finite or asymmetric input, trace ≤ 0, an eigenvalue below
/// `OMEGA_MIN` (singular moment), or no convergence.
pub fn mle_from_second_moment(s: &DMatrix<f64>) -> Result<Bingham> {
    let d = s.nrows();
    check_dim(d)?;
    if s.ncols() != d {
        return Err(Error::InvalidDimension(format!(
            "second moment must be square, got {}x{}",
            s.nrows(),
            s.ncols()
        )));
    }
    check_finite("S", s.as_slice())?;
    let tr = s.trace();
    if tr.is_nan() || tr <= 0.0 {
        return Err(Error::InvalidArgument(format!(
            "second moment must have a positive trace, got {tr}"
        )));
    }
    let mut asym = 0.0f64;
    for i in 0..d {
        for j in i + 1..d {
            asym = asym.max((s[(i, j)] - s[(j, i)]).abs() / tr);
        }
    }
    if asym > 1e-10 {
        return Err(Error::InvalidArgument(format!(
            "second moment is not symmetric: max |S − Sᵀ|/tr S = {asym:e}"
        )));
    }
    // The same function for every d; d ≤ 4 on the stack.
    match d {
        2 => fit_matrix(Const::<2>, s),
        3 => fit_matrix(Const::<3>, s),
        4 => fit_matrix(Const::<4>, s),
        _ => fit_matrix(Dyn(d), s),
    }
}

/// [`fit_second_moment`] of the validated `s` as a [`Bingham`], computed in the dimension type
/// `d`.
fn fit_matrix<D: Dim>(d: D, s: &DMatrix<f64>) -> Result<Bingham>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let a = Square::from_fn_generic(d, d, |i, j| s[(i, j)]);
    let (m, z, _) = fit_second_moment(&a, None)?;
    Ok(Bingham::from_normalized_parts(&m, &z))
}

/// The Bingham distribution with second moment `s` (symmetric PSD, any positive scale), with
/// an optional warm start (a previous solution with its derivatives; on failure from there the
/// cold start is tried). Returns normalized `(M, z)` and the solution's derivatives (for the
/// next warm start). No validation beyond the trace and the smallest eigenvalue (the caller's
/// moments are finite and symmetric to rounding).
pub(crate) fn fit_second_moment<D: Dim>(
    s: &Square<D>,
    warm: Option<&Derivs<D>>,
) -> Result<(Square<D>, Vector<D>, Derivs<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    fit_second_moment_nearest(s, warm)
}

/// [`fit_second_moment`] warm-started from the one of `starts` (previous solutions with their
/// derivatives) whose moments `ω` are nearest the target's (the largest relative difference
/// over the first `d − 1`, Newton's residual); cold without any. Only the start differs: the
/// solution is the one every start converges to, within the same tolerance. A filter that
/// keeps several previous solutions (the spin filter: its targets change shape from step to
/// step but come back as the object turns) starts Newton closer and saves evaluations.
pub(crate) fn fit_second_moment_nearest<'a, D: Dim>(
    s: &Square<D>,
    starts: impl IntoIterator<Item = &'a Derivs<D>>,
) -> Result<(Square<D>, Vector<D>, Derivs<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let tr = checked_trace(s)?;
    // The decomposition is scale-free, and Newton normalizes its target by its sum: the
    // eigenvalues are used as they are (no division by the trace on the way).
    let (m, l) = sym_eigen(&symmetrize(s))?;
    fit_eigen(tr, &m, &l, starts)
}

/// [`fit_second_moment`] with the eigendecomposition of `s` warm-started from `basis` (an
/// orthonormal matrix whose columns nearly diagonalize `s`, [`warm_basis`]: the filter's
/// previous principal directions; see [`sym_eigen_in_basis`]); cold when `basis` is not
/// orthonormal enough, for d = 2, and when the decomposition in that basis fails (e.g. a
/// non-finite entry there). The same result as [`fit_second_moment`] up to rounding.
pub(crate) fn fit_second_moment_in_basis<D: Dim>(
    s: &Square<D>,
    basis: &Square<D>,
    warm: Option<&Derivs<D>>,
) -> Result<(Square<D>, Vector<D>, Derivs<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    // (d = 2 is one closed-form rotation either way: nothing to save)
    if s.nrows() < 3 || !warm_basis(basis) {
        return fit_second_moment(s, warm);
    }
    let tr = checked_trace(s)?;
    // (a moment that overflows in this basis, or any other failure there: the cold path)
    match sym_eigen_in_basis(&in_basis(s, basis), basis) {
        Ok((m, l)) => fit_eigen(tr, &m, &l, warm),
        Err(_) => fit_second_moment(s, warm),
    }
}

/// The trace of the second moment `s`, which must be positive and finite.
fn checked_trace<D: Dim>(s: &Square<D>) -> Result<f64>
where
    DefaultAllocator: Allocator<D, D>,
{
    let tr: f64 = (0..s.nrows()).map(|i| s[(i, i)]).sum();
    if tr.is_nan() || tr <= 0.0 {
        return Err(Error::InvalidArgument(format!(
            "second moment must have a positive trace, got {tr}"
        )));
    }
    if !tr.is_finite() {
        return Err(Error::InvalidArgument(format!(
            "second moment's trace overflows a double ({tr})"
        )));
    }
    Ok(tr)
}

/// The fit from the eigendecomposition `m`, `l` (ascending) of a second moment with trace
/// `tr`: the singularity check, the choice of the nearest of `starts`, Newton, normalization.
fn fit_eigen<'a, D: Dim>(
    tr: f64,
    m: &Square<D>,
    l: &Vector<D>,
    starts: impl IntoIterator<Item = &'a Derivs<D>>,
) -> Result<(Square<D>, Vector<D>, Derivs<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    if l[0] < OMEGA_MIN * tr {
        return Err(Error::InvalidArgument(format!(
            "second moment is singular or not positive semidefinite: smallest eigenvalue \
             (after normalizing the trace to 1) is {:e} < {OMEGA_MIN:e}; the MLE would have \
             infinite concentration",
            l[0] / tr
        )));
    }
    let sum: f64 = l.iter().sum();
    let n = l.len();
    let distance = |c: &Derivs<D>| -> f64 {
        (0..n - 1)
            .map(|i| {
                let t = l[i] / sum;
                ((c.grad[i] - t) / t).abs()
            })
            .fold(0.0, f64::max)
    };
    let warm = starts
        .into_iter()
        .map(|c| (distance(c), c))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, c)| c);
    let (sol, _) = match warm {
        Some(d) => solve_z(l, Start::Evaluated(d)).or_else(|_| solve_z(l, Start::Cold)),
        None => solve_z(l, Start::Cold),
    }?;
    let (mm, zz) = normalize_eigen(m, &sol.z);
    Ok((mm, zz, sol))
}

/// MLE from `n = x.len()/d` unit vectors (row-major, each within `UNIT_TOL` of unit norm) with
/// optional non-negative weights (`w.len() == n`, positive sum): the MLE of the weighted second
/// moment `Σ w_k x_k x_kᵀ / Σ w_k`.
pub fn mle_from_samples(d: usize, x: &[f64], w: Option<&[f64]>) -> Result<Bingham> {
    check_dim(d)?;
    if x.is_empty() || x.len() % d != 0 {
        return Err(Error::InvalidDimension(format!(
            "samples must hold n*d values with n ≥ 1, got {} values for d = {d}",
            x.len()
        )));
    }
    let n = x.len() / d;
    if let Some(w) = w {
        if w.len() != n {
            return Err(Error::InvalidDimension(format!(
                "weights have length {}, expected n = {n}",
                w.len()
            )));
        }
        check_finite("w", w)?;
        if let Some(i) = w.iter().position(|&v| v < 0.0) {
            return Err(Error::InvalidArgument(format!(
                "w[{i}] = {} is negative",
                w[i]
            )));
        }
        if w.iter().sum::<f64>() <= 0.0 {
            return Err(Error::InvalidArgument("weights sum to zero".into()));
        }
    }
    let mut s = DMatrix::zeros(d, d);
    for k in 0..n {
        let v = unit(&format!("sample {k}"), Dyn(d), &x[k * d..(k + 1) * d])?;
        let wk = w.map_or(1.0, |w| w[k]);
        s.ger(wk, &v, &v, 1.0);
    }
    mle_from_second_moment(&s)
}

/// Number of Newton steps the MLE takes for the target `ω̂` (diagnostics and benchmarks).
#[doc(hidden)]
pub fn newton_steps(target: &[f64]) -> Result<usize> {
    let t = Vector::from_column_slice_generic(Dyn(target.len()), nalgebra::U1, target);
    Ok(solve_z(&t, Start::Cold)?.1)
}

impl Bingham {
    /// Composition `x ⊕ y` of independent `x ~ self`, `y ~ other` (complex multiplication for
    /// d = 2, Hamilton product for d = 4), approximated by the Bingham with the same second
    /// moment (exact moment matching: `E[(x⊕y)(x⊕y)ᵀ] = Σ_ab A_ab L_a B L_bᵀ`, then the MLE).
    pub fn compose(&self, other: &Bingham) -> Result<Bingham> {
        let d = self.dim();
        if other.dim() != d || !(d == 2 || d == 4) {
            return Err(Error::InvalidDimension(format!(
                "composition is defined for d = 2 (complex) and d = 4 (quaternions) with equal \
                 dimensions, got {} and {}",
                d,
                other.dim()
            )));
        }
        let a = self.second_moment()?;
        let b = other.second_moment()?;
        mle_from_second_moment(&compose_moments(&a, &b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distribution::log_f_omega;
    use nalgebra::SVector;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1.0)
    }

    #[test]
    fn fixed_and_dynamic_sizes_give_the_same_fit() {
        let z = SVector::<f64, 4>::from([-250.0, -180.0, -2.0, 0.0]);
        let (_, w) = log_f_omega(&z).unwrap();
        let q = crate::quaternion::left(Const::<4>, &[0.5, 0.5, -0.5, 0.5]);
        let s = crate::linalg::congruence(&q, &w);
        let (m, zf, _) = fit_second_moment(&s, None).unwrap();
        let sd = DMatrix::from_column_slice(4, 4, s.as_slice());
        let (md, zd, _) = fit_second_moment(&sd, None).unwrap();
        assert_eq!(m.as_slice(), md.as_slice());
        assert_eq!(zf.as_slice(), zd.as_slice());
        for i in 0..4 {
            assert!(close(zf[i], z[i], 1e-9));
        }
    }

    /// The fit warm-started in the previous principal directions (a Jacobi eigenbasis; the
    /// moment's own directions a small rotation away, as after a prediction) against the
    /// concentrations and directions the moment was built from, and against the cold fit.
    #[test]
    fn fit_in_a_nearby_basis_matches_the_generating_state() {
        use crate::quaternion::{left, q4};
        let mut r = testkit::xorshift(23);
        let (mut worst_z, mut worst_cold, mut worst_mode) = (0.0f64, 0.0f64, 0.0f64);
        let (mut m_last, mut s_last) =
            (nalgebra::Matrix4::identity(), nalgebra::Matrix4::identity());
        for _ in 0..100 {
            let g = nalgebra::Matrix4::from_fn(|_, _| r());
            let (m0, _) = sym_eigen(&(g + g.transpose())).unwrap();
            let u = q4::from_rotation_vector(&[1e-2 * r(), 1e-2 * r(), 1e-2 * r()]);
            let m = left(Const::<4>, &u) * m0;
            let z1 = -(10f64.powf(3.0 + 2.0 * (r() + 0.5)));
            let z3 = -(10f64.powf(3.0 + 2.0 * (r() + 0.5)));
            let mut z = [z1, z1 * (1.0 - 1e-3 * (r() + 0.5)), z3, 0.0];
            z.sort_by(f64::total_cmp);
            let z = SVector::<f64, 4>::from(z);
            let (_, w) = log_f_omega(&z).unwrap();
            let s = crate::linalg::congruence(&m, &w);
            let (mw, zw, _) = fit_second_moment_in_basis(&s, &m0, None).unwrap();
            let (_, zc, _) = fit_second_moment(&s, None).unwrap();
            for i in 0..3 {
                worst_z = worst_z.max(((zw[i] - z[i]) / z[i]).abs());
                worst_cold = worst_cold.max(((zw[i] - zc[i]) / zc[i]).abs());
            }
            let sign = if mw.column(3).dot(&m.column(3)) < 0.0 {
                -1.0
            } else {
                1.0
            };
            worst_mode = worst_mode.max((mw.column(3) - m.column(3) * sign).amax());
            (m_last, s_last) = (m0, s);
        }
        // measured: 9.4e-12, 5.8e-12 and 1.5 ulps
        assert!(
            worst_z <= 1e-10 && worst_cold <= 1e-10,
            "{worst_z:e} {worst_cold:e}"
        );
        assert!(worst_mode <= 4.0 * f64::EPSILON, "{worst_mode:e}");
        // a basis that is not orthonormal enough: the cold fit, bit for bit
        let drifted = m_last * (1.0 + 8.0 * f64::EPSILON);
        let warm = fit_second_moment_in_basis(&s_last, &drifted, None).unwrap();
        let cold = fit_second_moment(&s_last, None).unwrap();
        assert_eq!((warm.0, warm.1), (cold.0, cold.1));
    }
}
