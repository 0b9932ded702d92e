//! Maximum-likelihood estimation (moment matching): the Bingham whose second moment equals a
//! given one.
//!
//! Eigendecompose `S = M diag(ω̂) Mᵀ` (ω̂ ascending), then solve `ω_i(z) = ω̂_i` for `i < d`
//! with `z_d = 0` by Newton's method with the exact Jacobian `∂ω_i/∂z_j = Cov(x_i², x_j²)`
//! (positive definite on the constrained space) and a backtracking line search on the
//! relative residual. The solution is unique; it exists iff all ω̂_i > 0.

use nalgebra::{DMatrix, DVector};

use crate::distribution::{sym_eigen_ascending, unit_vector, Bingham};
use crate::error::{check_dim, check_finite, Error, Result, MAX_DIM};
use crate::normalization::{log_normalization_into, Method};

/// Smallest accepted eigenvalue of the trace-normalized second moment. Below it the moment
/// is singular to working precision (the eigenvalues of `S` are only known to about 1e-16) and
/// the maximum-likelihood concentration would be `−∞`. ω̂ = 1e-13 corresponds to z ≈ −5e12.
pub const OMEGA_MIN: f64 = 1e-13;
/// Convergence tolerance: `max_i |ω_i(z) − ω̂_i| / ω̂_i`.
pub const MLE_TOL: f64 = 1e-13;
const MAX_ITER: usize = 200;

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
    let sn = s / tr;
    let asym = (&sn - sn.transpose()).amax();
    if asym > 1e-10 {
        return Err(Error::InvalidArgument(format!(
            "second moment is not symmetric: max |S − Sᵀ|/tr S = {asym:e}"
        )));
    }
    let sym = (&sn + sn.transpose()) * 0.5;
    let (m, w) = sym_eigen_ascending(sym)?;
    if w[0] < OMEGA_MIN {
        return Err(Error::InvalidArgument(format!(
            "second moment is singular or not positive semidefinite: smallest eigenvalue \
             (after normalizing the trace to 1) is {:e} < {OMEGA_MIN:e}; the MLE would have \
             infinite concentration",
            w[0]
        )));
    }
    let z = solve_z(w.as_slice(), None)?;
    Ok(Bingham::from_parts_unchecked(
        m,
        DVector::from_column_slice(&z),
    ))
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
        let v = unit_vector(&format!("sample {k}"), d, &x[k * d..(k + 1) * d])?;
        let wk = w.map_or(1.0, |w| w[k]);
        s.ger(wk, &v, &v, 1.0);
    }
    mle_from_second_moment(&s)
}

/// Solves `ω(z) = target` (ascending, positive, summing to 1) for `z` (ascending, `z_d = 0`).
/// `start`: an optional initial guess (e.g. the previous filter step).
pub(crate) fn solve_z(target: &[f64], start: Option<&[f64]>) -> Result<Vec<f64>> {
    let d = target.len();
    let k = d - 1;
    let sum: f64 = target.iter().sum();
    let t: Vec<f64> = target.iter().map(|v| v / sum).collect();
    let mut z = vec![0.0; d];
    match start {
        Some(s) if s.len() == d && s.iter().all(|v| v.is_finite()) => {
            z.copy_from_slice(s);
            let top = z[d - 1];
            z.iter_mut().for_each(|v| *v -= top);
        }
        _ => {
            for i in 0..k {
                z[i] = (0.5 / t[d - 1] - 0.5 / t[i]).min(0.0);
            }
        }
    }
    let mut grad = [0.0; MAX_DIM];
    let mut hess = vec![0.0; d * d];
    let resid = |g: &[f64]| -> f64 {
        (0..k)
            .map(|i| ((g[i] - t[i]) / t[i]).abs())
            .fold(0.0, f64::max)
    };
    let merit = |g: &[f64]| -> f64 { (0..k).map(|i| ((g[i] - t[i]) / t[i]).powi(2)).sum() };
    log_normalization_into(&z, Method::Exact, Some(&mut grad[..d]), Some(&mut hess))?;
    let mut phi = merit(&grad[..d]);
    for _iter in 0..MAX_ITER {
        if resid(&grad[..d]) <= MLE_TOL {
            return Ok(z);
        }
        // Newton step on the first d−1 coordinates: J Δ = t − ω.
        let j = DMatrix::from_fn(k, k, |a, b| hess[a * d + b]);
        let rhs = DVector::from_fn(k, |a, _| t[a] - grad[a]);
        let step = match j.clone().cholesky() {
            Some(ch) => ch.solve(&rhs),
            None => match j.lu().solve(&rhs) {
                Some(s) => s,
                None => {
                    return Err(Error::NotConverged(
                        "MLE: singular Jacobian in Newton's method".into(),
                    ))
                }
            },
        };
        if !step.iter().all(|v| v.is_finite()) {
            return Err(Error::NotConverged("MLE: non-finite Newton step".into()));
        }
        let mut alpha = 1.0;
        let mut accepted = false;
        let mut trial = z.clone();
        let mut tgrad = [0.0; MAX_DIM];
        for _ls in 0..60 {
            for i in 0..k {
                trial[i] = z[i] + alpha * step[i];
            }
            let ok = log_normalization_into(&trial, Method::Exact, Some(&mut tgrad[..d]), None);
            if ok.is_ok() {
                let p = merit(&tgrad[..d]);
                if p < phi * (1.0 - 1e-4 * alpha) || p == 0.0 {
                    accepted = true;
                    phi = p;
                    break;
                }
            }
            alpha *= 0.5;
        }
        if !accepted {
            // Rounding floor reached: accept if already close, else fail.
            if resid(&grad[..d]) <= 1e3 * MLE_TOL {
                return Ok(z);
            }
            return Err(Error::NotConverged(format!(
                "MLE: line search failed at relative residual {:e}",
                resid(&grad[..d])
            )));
        }
        z.copy_from_slice(&trial);
        log_normalization_into(&z, Method::Exact, Some(&mut grad[..d]), Some(&mut hess))?;
    }
    Err(Error::NotConverged(format!(
        "MLE: no convergence in {MAX_ITER} Newton steps (relative residual {:e})",
        resid(&grad[..d])
    )))
}
