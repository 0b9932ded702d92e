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
//! Files: this one holds the public fitting API and the solution type (`Derivs`); `newton`
//! the Newton iteration for d ≥ 3 with its starts; `asymptotic` the series of the moment map
//! for concentrated Binghams that corrects its steps (d = 3, 4); `pair` the closed-form d = 2
//! solver.

mod asymptotic;
mod newton;
mod pair;

use nalgebra::allocator::Allocator;
use nalgebra::{Const, DMatrix, DefaultAllocator, Dim, Dyn};

use crate::canonical::{normalize_eigen, unit};
use crate::distribution::Bingham;
use crate::error::{check_dim, check_finite, Error, Result};
use crate::linalg::{sym_eigen, symmetrize, Square, Vector};
use crate::quaternion::compose_moments;

use newton::{solve_z, Start};

/// Smallest accepted eigenvalue of the trace-normalized second moment. Below it the moment
/// is singular to working precision (the eigenvalues of `S` are only known to about 1e-16) and
/// the maximum-likelihood concentration would be `−∞`. ω̂ = 1e-13 corresponds to z ≈ −5e12.
pub const OMEGA_MIN: f64 = 1e-13;
/// Convergence tolerance: `max_i |ω_i(z) − ω̂_i| / ω̂_i`.
pub const MLE_TOL: f64 = 1e-13;

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
    // The decomposition is scale-free, and Newton normalizes its target by its sum: the
    // eigenvalues are used as they are (no division by the trace on the way).
    let (m, l) = sym_eigen(&symmetrize(s))?;
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
        Some(d) => solve_z(&l, Start::Evaluated(d)).or_else(|_| solve_z(&l, Start::Cold)),
        None => solve_z(&l, Start::Cold),
    }?;
    let (mm, zz) = normalize_eigen(&m, &sol.z);
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

/// `log F`'s gradient `ω` and Hessian at a point `z` (as the solver sees it: `z[d−1] = 0`).
/// In a solution returned by [`solve_z`] the Hessian may be that of the previous iterate (see
/// [`newton::newton`]). `hess` holds the Hessian row-major in its storage (`hess.as_slice()`, as
/// [`newton::newton`] reads and writes it).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Derivs<D: Dim>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    pub(crate) z: Vector<D>,
    pub(crate) grad: Vector<D>,
    pub(crate) hess: Square<D>,
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
}
