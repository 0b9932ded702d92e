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

use nalgebra::allocator::Allocator;
use nalgebra::{Const, DMatrix, DefaultAllocator, Dim, Dyn};

use crate::canonical::{normalize_eigen, unit};
use crate::distribution::Bingham;
use crate::error::{check_dim, check_finite, Error, Result, MAX_DIM};
use crate::linalg::{cholesky_solve, sym_eigen, symmetrize, zero_vector, zeros, Square, Vector};
use crate::normalization::d2::pair_moments;
use crate::normalization::{log_normalization_into, Method};
use crate::quaternion::compose_moments;

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
/// [`newton`]). `hess` holds the Hessian row-major in its storage (`hess.as_slice()`, as
/// [`newton`] reads and writes it).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Derivs<D: Dim>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    pub(crate) z: Vector<D>,
    pub(crate) grad: Vector<D>,
    pub(crate) hess: Square<D>,
}

/// Where the moment-matching Newton iteration starts.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Start<'a, D: Dim>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    /// From [`initial_guess`] (each `z_i` from the d = 2 problem of the pair `(i, d)`).
    Cold,
    /// From a previous solution with its derivatives (e.g. the filter's previous prediction).
    Evaluated(&'a Derivs<D>),
}

/// Solves `ω(z) = target` (ascending, positive) for `z` (`z[d−1] = 0`) with [`newton`].
/// Returns the solution with its derivatives (the next call's [`Start::Evaluated`]) and the
/// number of Newton steps; the returned Hessian may be the previous iterate's (see [`newton`]).
/// Allocation-free for fixed sizes.
pub(crate) fn solve_z<D: Dim>(target: &Vector<D>, start: Start<'_, D>) -> Result<(Derivs<D>, usize)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let (d, _) = target.shape_generic();
    let (mut sol, from) = match start {
        Start::Evaluated(prev) => (prev.clone(), NewtonStart::Evaluated),
        Start::Cold => (
            Derivs {
                z: zero_vector(d),
                grad: zero_vector(d),
                hess: zeros(d),
            },
            NewtonStart::Guess,
        ),
    };
    let steps = newton(
        target.as_slice(),
        from,
        sol.z.as_mut_slice(),
        sol.grad.as_mut_slice(),
        sol.hess.as_mut_slice(),
    )?;
    Ok((sol, steps))
}

/// A d×d scratch matrix on the stack for d ≤ 4, on the heap otherwise.
struct Scratch {
    small: [f64; 16],
    big: Vec<f64>,
    len: usize,
}

impl Scratch {
    fn new(len: usize) -> Self {
        Scratch {
            small: [0.0; 16],
            big: if len > 16 { vec![0.0; len] } else { Vec::new() },
            len,
        }
    }
    fn get(&mut self) -> &mut [f64] {
        if self.len <= 16 {
            &mut self.small[..self.len]
        } else {
            &mut self.big[..]
        }
    }
}

/// Where [`newton`] starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum NewtonStart {
    /// From [`initial_guess`].
    Guess,
    /// From the point in `z` whose gradient and Hessian are already in `grad` and `hess`.
    Evaluated,
}

/// The MLE's Newton iteration, allocation-free for d ≤ 4. Solves `ω(z) = target` (ascending,
/// positive; normalized by its sum) for `z` (`z[d−1] = 0`). On success `z`, `grad` and `hess`
/// (d×d row-major) hold the solution and the derivatives of `log F` there, and the number of
/// steps is returned.
///
/// Newton's method on `G_i(z) = 1/ω_i(z) − 1/ω̂_i` (i < d): `1/ω_i ≈ 2|z_i|` for large
/// concentrations, so `G` is nearly linear where `ω` itself is not, and few steps suffice from
/// [`initial_guess`]. The Jacobian is `−diag(1/ω²) H` with `H` the exact Hessian of `log F`;
/// the step solves `H Δ = ω² ∘ G`. A backtracking line search on `Σ (ω̂_i/ω_i − 1)²`
/// safeguards it; tolerance `MLE_TOL` on `max_i |ω_i − ω̂_i|/ω̂_i`. When a full step is
/// expected to end the iteration (quadratic convergence judged from the previous step predicts
/// a residual below `MLE_TOL/10`) its point is evaluated without the Hessian first (a wrong
/// prediction costs one such evaluation); if it has converged, the returned Hessian is
/// the previous iterate's (it then only serves as a warm start).
///
/// d = 2 is the same iteration on the single equation `1/ω_1 − 1/ω̂_1 = 0` in closed form
/// ([`newton_pair`]), without the matrix machinery; its returned Hessian is the solution's.
pub(crate) fn newton(
    target: &[f64],
    from: NewtonStart,
    z: &mut [f64],
    grad: &mut [f64],
    hess: &mut [f64],
) -> Result<usize> {
    // (d = 2 without the matrix machinery: it was three quarters of a d = 2 filter step; for
    // larger d only the size of the stack scratch differs)
    if target.len() == 2 {
        return newton_pair(target, from, z, grad, hess);
    }
    if target.len() <= 4 {
        newton_on::<4>(target, from, z, grad, hess)
    } else {
        newton_on::<MAX_DIM>(target, from, z, grad, hess)
    }
}

/// [`newton`] with stack scratch vectors of capacity `CAP ≥ d`.
fn newton_on<const CAP: usize>(
    target: &[f64],
    from: NewtonStart,
    z: &mut [f64],
    grad: &mut [f64],
    hess: &mut [f64],
) -> Result<usize> {
    let d = target.len();
    let k = d - 1;
    let sum: f64 = target.iter().sum();
    let mut t = [0.0; CAP];
    for i in 0..d {
        t[i] = target[i] / sum;
    }
    let t = &t[..d];
    if from == NewtonStart::Guess {
        initial_guess(t, z);
    }
    if from != NewtonStart::Evaluated {
        log_normalization_into(z, Method::Exact, Some(&mut *grad), Some(&mut *hess))?;
    }
    let resid = |g: &[f64]| -> f64 {
        (0..k)
            .map(|i| ((g[i] - t[i]) / t[i]).abs())
            .fold(0.0, f64::max)
    };
    let merit = |g: &[f64]| -> f64 { (0..k).map(|i| (t[i] / g[i] - 1.0).powi(2)).sum() };
    let mut tgrad = [0.0; CAP];
    let tgrad = &mut tgrad[..d];
    let mut thess = Scratch::new(d * d);
    let mut jac = Scratch::new(k * k);
    let mut step = [0.0; CAP];
    let mut trial = [0.0; CAP];
    let trial = &mut trial[..d];
    let mut phi = merit(grad);
    let mut previous_resid: Option<f64> = None;
    for iter in 0..MAX_ITER {
        let r = resid(grad);
        if r <= MLE_TOL {
            return Ok(iter);
        }
        let finishing = previous_resid.is_some_and(|rp| (r / (rp * rp)) * r * r <= 0.1 * MLE_TOL);
        previous_resid = Some(r);
        {
            let j = jac.get();
            for a in 0..k {
                for b in 0..k {
                    j[a * k + b] = hess[a * d + b];
                }
                step[a] = grad[a] * grad[a] * (1.0 / grad[a] - 1.0 / t[a]);
            }
        }
        if !cholesky_solve(k, jac.get(), &mut step[..k]) || !step[..k].iter().all(|v| v.is_finite())
        {
            return Err(Error::NotConverged(
                "MLE: the Hessian of log F is not numerically positive definite".into(),
            ));
        }
        let mut alpha = 1.0;
        let mut accepted = false;
        for _ls in 0..60 {
            for i in 0..k {
                trial[i] = z[i] + alpha * step[i];
            }
            trial[k] = 0.0;
            if finishing
                && alpha == 1.0
                && log_normalization_into(trial, Method::Exact, Some(&mut *tgrad), None).is_ok()
                && resid(tgrad) <= MLE_TOL
            {
                z.copy_from_slice(trial);
                grad.copy_from_slice(tgrad);
                return Ok(iter + 1);
            }
            let ok =
                log_normalization_into(trial, Method::Exact, Some(&mut *tgrad), Some(thess.get()));
            if ok.is_ok() {
                let p = merit(tgrad);
                if p < phi * (1.0 - 1e-4 * alpha) || resid(tgrad) <= MLE_TOL {
                    accepted = true;
                    phi = p;
                    break;
                }
            }
            alpha *= 0.5;
        }
        if !accepted {
            // The rounding floor of ω is reached: accept when already close.
            if resid(grad) <= 1e3 * MLE_TOL {
                return Ok(iter);
            }
            return Err(Error::NotConverged(format!(
                "MLE: line search failed at relative residual {:e}",
                resid(grad)
            )));
        }
        z.copy_from_slice(trial);
        grad.copy_from_slice(tgrad);
        hess.copy_from_slice(thess.get());
    }
    Err(Error::NotConverged(format!(
        "MLE: no convergence in {MAX_ITER} Newton steps (relative residual {:e})",
        resid(grad)
    )))
}

/// Starting point of the MLE's Newton iteration, from the d = 2 problems of the pairs `(i, d)`.
///
/// Conditional on the other coordinates, `(x_i, x_d)` lies on a circle of radius² `ρ² =
/// x_i² + x_d²` and is a d = 2 Bingham with concentration `z_i ρ²`; so `ω̂_i = E[ρ² ω₂(z_i ρ²)]`
/// exactly (`ω₂(κ) = ω_1([κ, 0])`), with `E[ρ²] = ω̂_i + ω̂_d`. With `κ_p` solving the pair's own
/// problem `ω₂(κ_p) = r = ω̂_i/(ω̂_i + ω̂_d)`:
/// * if `ρ²` were constant, `z_i = κ_p/E[ρ²]` — this is also exact to leading order for
///   large concentrations, where `ω̂_i ≈ 1/(2|z_i|)` whatever the distribution of `ρ²`;
/// * near `z = 0` the linearization gives `z_i = κ_p E[ρ²]/E[ρ⁴]`, i.e. the factor
///   `1/(1 + Var ρ²/E[ρ²]²)` on the first form.
///
/// The start uses `z_i = κ_p / (E[ρ²] (1 + φ(|κ_p|) v/E[ρ²]²))`, with `φ(k) = 1/(1 + (k/4.4)²)`
/// (1 at `z = 0`, → 0 for concentrated pairs; fitted to the exact ratio over random d = 4
/// problems) and `v = μ(1 − μ) q/(1 + q)` a model of `Var ρ² = Var Σ_{j ∉ {i,d}} x_j²` from
/// `μ = Σ ω̂_j`, `q = 2 Σ ω̂_j²/μ` over the other coordinates (a Beta law with that mean whose
/// variance tends to the Gaussian `2 Σ ω̂_j²` for concentrated coordinates; within 0.7–1.1 of
/// the exact variance on the same problems). Measured over random `z` (|z_i| from 1e-2 to 1e6,
/// ties included), the start's median relative residual in ω is 1.7e-5 (d = 3), 1e-3 (d = 4),
/// 2.4e-3 (d = 5) against 1.3e-4, 8e-3, 1.8e-2 with `κ_p` alone; uniform moments give `z = 0`.
/// Newton then typically needs one to three steps (mean 2.0 for d = 4, 2.5 for d = 6). Only a
/// starting point: accuracy comes from Newton.
pub(crate) fn initial_guess(t: &[f64], z: &mut [f64]) {
    let d = t.len();
    let last = t[d - 1];
    for i in 0..d - 1 {
        let m = t[i] + last;
        let r = t[i] / m;
        if r >= 0.5 {
            z[i] = 0.0;
            continue;
        }
        // (only a start: the last point also serves if it missed the tolerance)
        let kp = pair_solve(t[i], last, None, 1e-12).0.x;
        let (mut mu, mut sq) = (0.0, 0.0);
        for (j, &tj) in t[..d - 1].iter().enumerate() {
            if j != i {
                mu += tj;
                sq += tj * tj;
            }
        }
        let v = if mu > 0.0 {
            let q = 2.0 * sq / mu;
            mu * (1.0 - mu) * q / (1.0 + q)
        } else {
            0.0
        };
        let k = -kp / 4.4;
        let phi = 1.0 / (1.0 + k * k);
        z[i] = kp / (m * (1.0 + phi * v / (m * m)));
    }
    z[d - 1] = 0.0;
}

/// [`newton`] for d = 2: `ω_1([z_1, 0]) = ω̂_1/(ω̂_1 + ω̂_2)` by [`pair_solve`] to `MLE_TOL`,
/// from the evaluated point in `z`, `grad`, `hess` or from [`banerjee`]'s start. Writes the
/// solution and its derivatives (this is the only evaluation the Hessian of the solution needs
/// in d = 2: [`pair_moments`] returns it with ω).
fn newton_pair(
    target: &[f64],
    from: NewtonStart,
    z: &mut [f64],
    grad: &mut [f64],
    hess: &mut [f64],
) -> Result<usize> {
    let start = match from {
        NewtonStart::Evaluated => Some(PairPoint {
            x: z[0],
            w1: grad[0],
            w2: grad[1],
            h: hess[0],
        }),
        NewtonStart::Guess => None,
    };
    let (p, steps) = pair_solve(target[0], target[1], start, MLE_TOL);
    let steps = steps.ok_or_else(|| {
        let r = target[0] / (target[0] + target[1]);
        Error::NotConverged(format!(
            "MLE (d = 2): no convergence (relative residual {:e})",
            ((p.w1 - r) / r).abs()
        ))
    })?;
    z[0] = p.x;
    z[1] = 0.0;
    grad[0] = p.w1;
    grad[1] = p.w2;
    hess.copy_from_slice(&[p.h, -p.h, -p.h, p.h]);
    Ok(steps)
}

/// A point of the d = 2 moment equation: `z = [x, 0]` with `ω = (w1, w2)` and `h = ∂ω_1/∂z_1`.
#[derive(Debug, Clone, Copy)]
struct PairPoint {
    x: f64,
    w1: f64,
    w2: f64,
    h: f64,
}

impl PairPoint {
    fn at(x: f64) -> PairPoint {
        let (w1, w2, h) = pair_moments(x);
        PairPoint { x, w1, w2, h }
    }
}

/// Most evaluations [`pair_solve`] makes (Newton needs two to four for 1e-13; each bisection
/// halves the bracket).
const PAIR_MAX_ITER: usize = 100;

/// `Φ(ω_1)`: the z_1 of Banerjee et al.'s approximation of the d = 2 moment equation's
/// solution, `κ ≈ ρ(2 − ρ²)/(1 − ρ²)` with `ρ = 1 − 2ω_1 = I1(κ)/I0(κ)` and `z_1 = −2κ`,
/// written in `ω_1` (`1 − ρ² = q = 4ω_1(1 − ω_1)`) so that it keeps its relative accuracy for
/// concentrated `ω_1`: `Φ = −2ρ(1 + q)/q`. Exact in both limits (`z_1 → 0` and `z_1 → −∞`) and
/// within 7 % between (measured: largest deviation 6.1 % of `z_1` at `ρ = 0.875`). The start of
/// [`pair_solve`].
fn banerjee(w: f64) -> f64 {
    let q = 4.0 * w * (1.0 - w);
    -2.0 * (1.0 - 2.0 * w) * (1.0 + q) / q
}

/// Solves `ω_1([x, 0]) = r = a/(a + b)` for `x ≤ 0` (`0 < a ≤ b`, i.e. `0 < r ≤ 1/2`) to
/// `|ω_1/r − 1| ≤ tol`, from `start`
/// (an evaluated point) or from `x = Φ(r)` ([`banerjee`], within 7 %). Newton's method on
/// `1/ω_1 − 1/r`, nearly linear in `x` (`1/ω_1 ≈ 2|x|` when concentrated): `Δ = ω_1²(1/ω_1 −
/// 1/r)/h = −ω_1 (ω_1/r − 1)/h`, `h = ∂ω_1/∂x`; where `h` has underflowed (|x| ≳ 1e154) its
/// asymptote `2ω_1²` is used. The root is kept in a bracket (`ω_1` increases with `x`): a step
/// that leaves it bisects instead (geometrically where the bracket spans orders of
/// magnitude), so the iteration converges from any start. Returns the last
/// point and the number of Newton steps, `None` if the bracket collapsed (or the steps ran out)
/// above the tolerance (beyond the rounding floor of `1e3·tol`).
fn pair_solve(a: f64, b: f64, start: Option<PairPoint>, tol: f64) -> (PairPoint, Option<usize>) {
    // r and 1/r as two independent divisions (not one after the other)
    let (r, inv_r) = (a / (a + b), (a + b) / a);
    if r >= 0.5 {
        return (PairPoint::at(0.0), Some(0));
    }
    let mut p = match start {
        Some(p) if p.x <= 0.0 && p.x.is_finite() => p,
        _ => {
            let x = banerjee(r);
            PairPoint::at(if x.is_finite() { x.min(0.0) } else { -1.0 })
        }
    };
    // ω_1(lo) < r < ω_1(hi)
    let (mut lo, mut hi) = (f64::NEG_INFINITY, 0.0f64);
    let mut steps = 0;
    while steps < PAIR_MAX_ITER {
        let err = p.w1 * inv_r - 1.0;
        if err.abs() <= tol {
            return (p, Some(steps));
        }
        if err > 0.0 {
            hi = hi.min(p.x);
        } else {
            lo = lo.max(p.x);
        }
        // Δ = −ω_1·err/h; where h is not a normal number (it underflows for |x| ≳ 1e154) its
        // asymptote 2ω_1² gives Δ = −err/(2ω_1)
        let next = if p.h.is_normal() {
            p.x - p.w1 * err / p.h
        } else {
            p.x - err / (2.0 * p.w1)
        };
        let next = if next > lo && next < hi {
            next
        } else if lo.is_finite() {
            // bisection; geometric where the bracket spans orders of magnitude
            if hi < 0.0 && lo < 4.0 * hi {
                -(-lo).sqrt() * (-hi).sqrt()
            } else if hi == 0.0 && lo < -4.0 {
                -(-lo).sqrt()
            } else {
                0.5 * (lo + hi)
            }
        } else {
            // no lower end yet: twice as far out as the upper one (or −1 from 0)
            2.0 * hi.min(-0.5)
        };
        if next == p.x || next == lo || next == hi {
            break;
        }
        p = PairPoint::at(next);
        steps += 1;
    }
    let converged = (p.w1 * inv_r - 1.0).abs() <= 1e3 * tol;
    (p, converged.then_some(steps))
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

    /// The exact derivatives of `log F` at `z` (as `newton` evaluates them).
    fn exact_derivs<const D: usize>(z: &SVector<f64, D>) -> Derivs<Const<D>> {
        let mut d = Derivs {
            z: *z,
            grad: SVector::zeros(),
            hess: Square::zeros_generic(Const::<D>, Const::<D>),
        };
        log_normalization_into(
            z.as_slice(),
            Method::Exact,
            Some(d.grad.as_mut_slice()),
            Some(d.hess.as_mut_slice()),
        )
        .unwrap();
        d
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1.0)
    }

    /// The warm start (the filter's: a previous solution whose Hessian may be stale) reaches the
    /// cold start's solution; restarted at its own solution the solver takes no step.
    fn warm_start<const D: usize>(z0: [f64; D]) {
        let z0 = SVector::<f64, D>::from(z0);
        let (_, w0) = log_f_omega(&z0).unwrap();
        let (sol, _) = solve_z(&w0, Start::Cold).unwrap();
        for i in 0..D {
            assert!(close(sol.z[i], z0[i], 1e-9), "z0 = {z0:?}: {:?}", sol.z);
        }
        let (again, steps) = solve_z(&w0, Start::Evaluated(&sol)).unwrap();
        assert_eq!(steps, 0);
        assert_eq!(again, sol);
        let z1 = z0 * 1.3;
        let (_, w1) = log_f_omega(&z1).unwrap();
        let (cold, _) = solve_z(&w1, Start::Cold).unwrap();
        let (warm, _) = solve_z(&w1, Start::Evaluated(&sol)).unwrap();
        let (exact, _) = solve_z(&w1, Start::Evaluated(&exact_derivs(&sol.z))).unwrap();
        for i in 0..D {
            assert!(
                close(warm.z[i], cold.z[i], 1e-12),
                "z1 = {z1:?}: warm {:?}",
                warm.z
            );
            assert!(
                close(exact.z[i], cold.z[i], 1e-12),
                "z1 = {z1:?}: exact {:?}",
                exact.z
            );
            assert!(
                close(cold.z[i], z1[i], 1e-9),
                "z1 = {z1:?}: cold {:?}",
                cold.z
            );
        }
    }

    #[test]
    fn warm_start_reaches_the_cold_start_solution() {
        warm_start([-1.0, 0.0]);
        warm_start([-150.0, 0.0]);
        warm_start([-3e7, 0.0]);
        warm_start([-1.0, -1.0, -1.0, 0.0]);
        warm_start([-250.0, -180.0, -2.0, 0.0]);
        warm_start([-1e6, -1e3, -10.0, 0.0]);
    }

    /// d = 2 ([`pair_solve`]): the moment equation of `z = [x, 0]` solved back to `x` over the
    /// whole range (|x| from 1e-6 to 1e300), cold and from starts far on either side, to the
    /// tolerance in ω and to the matching accuracy in `x`.
    #[test]
    fn pair_solve_inverts_the_d2_moment_equation_everywhere() {
        let mut xs = vec![0.0];
        let mut e = -6.0;
        while e <= 300.0 {
            xs.push(-(10f64.powf(e)));
            e += 0.37;
        }
        for &x in &xs {
            let (w1, w2, h) = pair_moments(x);
            let inv_r = (w1 + w2) / w1;
            let starts = [
                None,
                Some(PairPoint::at(0.0)),
                Some(PairPoint::at(x * 0.5)),
                Some(PairPoint::at((x * 2.0).max(-f64::MAX))),
                Some(PairPoint::at(-1e300)),
                Some(PairPoint { x, w1, w2, h }),
            ];
            for start in starts {
                let (p, steps) = pair_solve(w1, w2, start, MLE_TOL);
                let steps = steps.unwrap_or_else(|| panic!("x = {x:e}, start {start:?}: {p:?}"));
                assert!(steps <= 60, "x = {x:e}: {steps} steps");
                assert!((p.w1 * inv_r - 1.0).abs() <= MLE_TOL, "x = {x:e}: {p:?}");
                // the tolerance in ω moves x by up to tol·ω_1/h (≈ tol·|x| when concentrated,
                // 4·tol near 0); where h underflows, ω_1 ≈ 1/(2|x|)
                let cond = if h > 0.0 { w1 / h } else { x.abs() };
                assert!(
                    (p.x - x).abs() <= 2.0 * MLE_TOL * cond + 1e-14 * x.abs(),
                    "x = {x:e}, start {start:?}: got {}",
                    p.x
                );
                let (w1p, w2p, hp) = pair_moments(p.x);
                assert_eq!((p.w1, p.w2, p.h), (w1p, w2p, hp));
            }
        }
        // r = 1/2 (ties) is z = 0
        assert_eq!(pair_solve(1.0, 1.0, None, MLE_TOL).0.x, 0.0);
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
