//! The moment-matching Newton iteration (d ≥ 3; d = 2 is handed to `d2`) and its starting
//! points: [`solve_z`] on the solver's types, [`newton`] on slices, [`initial_guess`] for a
//! cold start.

use nalgebra::allocator::Allocator;
use nalgebra::DefaultAllocator;
use nalgebra::Dim;

use super::asymptotic;
use super::d2::{newton_pair, pair_solve};
use super::solution::{Derivs, NewtonStart, MLE_TOL};
use crate::error::{Error, Result, MAX_DIM};
use crate::linalg::{cholesky_solve, zero_vector, zeros, Vector};
use crate::normalization::{log_normalization_into, omega_series, Method};

const MAX_ITER: usize = 200;

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

/// The MLE's Newton iteration, allocation-free for d ≤ 4. Solves `ω(z) = target` (ascending,
/// positive; normalized by its sum) for `z` (`z[d−1] = 0`). On success `z`, `grad` and `hess`
/// (d×d row-major) hold the solution and the derivatives of `log F` there, and the number of
/// steps is returned.
///
/// Newton's method on `G_i(z) = 1/ω_i(z) − 1/ω̂_i` (i < d): `1/ω_i ≈ 2|z_i|` for large
/// concentrations, so `G` is nearly linear where `ω` itself is not, and few steps suffice from
/// [`initial_guess`]. The Jacobian is `−diag(1/ω²) H` with `H` the exact Hessian of `log F`;
/// the step solves `H Δ = ω² ∘ G`. A backtracking line search on `Σ (ω̂_i/ω_i − 1)²`
/// safeguards it; tolerance `MLE_TOL` on `max_i |ω_i − ω̂_i|/ω̂_i`. For d = 3, 4 and
/// concentrated points the step is corrected for the curvature of `G` its series predicts
/// (`asymptotic`; in the spin filter's fits one step from a residual near 1e-2 ends 7–200
/// times closer, so that the next step finishes). When a full step is
/// expected to end the iteration (quadratic convergence judged from the previous step predicts
/// a residual below `MLE_TOL/10`) its point is evaluated without the Hessian first (a wrong
/// prediction costs one such evaluation); if it has converged, the returned Hessian is
/// the previous iterate's (it then only serves as a warm start).
///
/// d = 2 is the same iteration on the single equation `1/ω_1 − 1/ω̂_1 = 0` in closed form
/// ([`newton_pair`]), without the matrix machinery; its returned Hessian is the solution's.
///
/// For d = 3, 4 at points where the concentrated series of ω holds (every concentration below
/// the mode ≳ 95: the AHRS's states), each evaluation takes ω from that series (to 1e-16, the
/// quadrature's accuracy) and the Hessian from the series of `1/ω` ([`derivatives`]; within
/// 2.4e-7 of the exact one at 80, 1e-12 from 1000 up): the steps barely change, the
/// convergence test is the same, and no quadrature runs. The returned Hessian is then that
/// approximation (it only serves as a warm start).
///
/// Where every concentration below the mode of the start is at least 2000 (d = 3, 4: the
/// AHRS's fits), the series' own moment equation is solved first
/// ([`asymptotic::series_root`]); its root is returned (one step) if the exact `ω` there meets
/// `MLE_TOL`, with the series' Hessian, and the iteration above runs otherwise.
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
        derivatives(z, grad, hess)?;
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
    // The concentrated case (d = 3, 4; the AHRS's fits): the series' own root, checked on the
    // exact ω, replaces the iteration (one evaluation instead of two, no step correction).
    if (d == 3 || d == 4) && resid(grad) > MLE_TOL {
        let mut zr = [0.0; CAP];
        zr[..d].copy_from_slice(z);
        let mut dinv = [[0.0; 3]; 3];
        if asymptotic::series_root(t, &mut zr[..d], &mut dinv)
            && omega_only(&zr[..d], tgrad).is_ok()
            && resid(tgrad) <= MLE_TOL
            && asymptotic::hessian_from(&dinv, tgrad, hess)
        {
            z.copy_from_slice(&zr[..d]);
            grad.copy_from_slice(tgrad);
            return Ok(1);
        }
    }
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
        asymptotic::correct_step(z, grad, hess, &mut step[..k]);
        let mut alpha = 1.0;
        let mut accepted = false;
        for _ls in 0..60 {
            for i in 0..k {
                trial[i] = z[i] + alpha * step[i];
            }
            trial[k] = 0.0;
            if finishing
                && alpha == 1.0
                && omega_only(trial, tgrad).is_ok()
                && resid(tgrad) <= MLE_TOL
            {
                z.copy_from_slice(trial);
                grad.copy_from_slice(tgrad);
                return Ok(iter + 1);
            }
            let ok = derivatives(trial, tgrad, thess.get());
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

/// ω and the Hessian of `log F` at `z` into `grad` and `hess` for the Newton iteration: for
/// d = 3, 4 where the concentrated series of ω holds (`omega_series`: every concentration
/// below the mode ≳ 95, ω to its error bound 1e-16), ω from it and the Hessian from the series
/// of `1/ω` (`asymptotic::series_hessian`, about 1e-7 relative or better: it only shapes the
/// steps); otherwise both by the exact method (the quadrature).
fn derivatives(z: &[f64], grad: &mut [f64], hess: &mut [f64]) -> Result<()> {
    if omega_series(z, grad) && asymptotic::series_hessian(z, grad, hess) {
        return Ok(());
    }
    log_normalization_into(z, Method::Exact, Some(grad), Some(hess)).map(|_| ())
}

/// ω alone at `z` into `grad`: the concentrated series where it holds (see [`derivatives`]),
/// otherwise the exact method.
fn omega_only(z: &[f64], grad: &mut [f64]) -> Result<()> {
    if omega_series(z, grad) {
        return Ok(());
    }
    log_normalization_into(z, Method::Exact, Some(grad), None).map(|_| ())
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distribution::log_f_omega;
    use crate::linalg::Square;
    use nalgebra::{Const, SVector};

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
}
