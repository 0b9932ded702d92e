//! The sampled check and refinement of the nonlinear steps: randomized quasi-Monte Carlo
//! estimates ([`super::rqmc`]) of the second moment a step returns, with their standard errors,
//! refined until the error estimate meets the caller's tolerance or the call budget is spent.
//!
//! - **Update**: the posterior's second moment is estimated as the deterministic
//!   approximation's exact moment plus the difference of two self-normalized importance
//!   estimates on the same points — one with the posterior's weights `prior · L / envelope`, one
//!   with the approximation's `approximation / envelope` (a control variate: the difference is
//!   exactly 0 when the approximation is the posterior, and small when it is close). Where the
//!   correction is large against the tolerance the envelope is moved to the corrected estimate
//!   and the sampling restarts there (adaptive importance sampling).
//! - **Prediction**: the second moment of `a(x)` under the state by importance sampling from the
//!   state's envelope.
//!
//! In both, the points per replicate double until `3 × standard error ≤ tolerance`. The method
//! with its derivation: `docs/design.md`, section "Nonlinear steps".

use super::control_variate::{Features, PooledSums, ReplicateSums, MAX_FEATURES};
use super::options::{
    NonlinearMethod, NonlinearOptions, NonlinearReport, DEFAULT_PREDICT_TOLERANCE,
    DEFAULT_UPDATE_TOLERANCE,
};
use super::rqmc::{
    mean_and_error, outer_packed, packed, shifts, unpack, Acg, Sobol, WeightedSums, REPLICATES,
};
use crate::distribution::omega;
use crate::error::{Error, Result};
use crate::filter::noise::capped;
use crate::filter::state::Core;
use crate::filter::types::{Mat, Vect, MAX_CONCENTRATION};
use crate::linalg::congruence;
use crate::mle::fit_second_moment;

/// Points per replicate of the first sampled round (`× REPLICATES` calls).
const INITIAL_POINTS: usize = 8;

/// Below this effective share of the posterior's weights the sampled estimate's standard error
/// is not trusted (too few points carry the estimate); the points are doubled or the envelope
/// moved.
const MIN_SHARE: f64 = 0.05;

/// The envelope is moved to the corrected estimate when the correction is larger than this
/// many tolerances (or the mode moves by more than [`RECENTER_MODE`] spreads): sampling from a
/// closer envelope then costs fewer points than refining the far one.
const RECENTER_TOLERANCES: f64 = 5.0;

/// See [`RECENTER_TOLERANCES`].
const RECENTER_MODE: f64 = 0.25;

/// A correction counts as real (not the estimate's noise) beyond this many standard errors.
const RECENTER_SIGMAS: f64 = 4.0;

/// The most envelope moves per update (each restarts the sampling; beyond, points are doubled).
const MAX_MOVES: usize = 6;

/// Multiplier of the standard error in the error estimates.
const SIGMAS: f64 = 3.0;

/// The error estimates of a sampled second moment in the principal coordinates `y` of the
/// envelope: the largest entry error and the mode error as a fraction of the spread.
struct Estimate<const D: usize> {
    entries: f64,
    mode: f64,
    /// The mode's move from the envelope's, as a fraction of the spread `√(1 − E[y_top²])`.
    tilt: f64,
}

fn estimate<const D: usize>(s_y: &Mat<D>, se: &[f64; 10]) -> Estimate<D> {
    let nu = D * (D + 1) / 2;
    let entries = SIGMAS * se[..nu].iter().fold(0.0f64, |a, &b| a.max(b));
    let top = D - 1;
    let spread2: f64 = (0..top).map(|j| s_y[(j, j)].max(0.0)).sum();
    let spread = spread2.sqrt().max(f64::MIN_POSITIVE);
    let (mut m2, mut t2) = (0.0, 0.0);
    for j in 0..top {
        let gap = (s_y[(top, top)] - s_y[(j, j)]).max(f64::MIN_POSITIVE);
        m2 += (se[packed::<D>(j, top)] / gap).powi(2);
        t2 += (s_y[(j, top)] / gap).powi(2);
    }
    Estimate {
        entries,
        mode: SIGMAS * m2.sqrt() / spread,
        tilt: t2.sqrt() / spread,
    }
}

fn budget_refusal(what: &str, used: usize, max: usize, detail: String) -> Error {
    Error::NotConverged(format!(
        "nonlinear {what}: the call budget ({max} calls, {used} used) ran out before the error \
         estimate met the tolerance: {detail}"
    ))
}

impl<const D: usize> Core<D> {
    /// The posterior's second moment by sampling around the deterministic approximation
    /// `Bingham(m, z)`, checked against `opts`; returns the fitted posterior and the report.
    /// `calls` counts the callback calls so far (the deterministic part's included).
    pub(super) fn sampled_update<L>(
        &self,
        m: Mat<D>,
        z: Vect<D>,
        log_l: &mut L,
        opts: &NonlinearOptions,
        calls: &mut usize,
    ) -> Result<(Mat<D>, Vect<D>, NonlinearReport)>
    where
        L: FnMut(&Vect<D>) -> Result<f64>,
    {
        let tolerance = opts.tolerance_or(DEFAULT_UPDATE_TOLERANCE);
        let prior = congruence(&self.m, &self.z);
        let sh = shifts();
        let (mut qm, mut qz) = (m, z);
        // The latest estimate (error, mode error, share, points), for a refusal's message.
        let mut last = (f64::INFINITY, f64::INFINITY, 0.0, 0usize);
        let mut moves = 0usize;
        loop {
            let acg = Acg::new(&qm, &capped(&qz))?;
            let omega_q = omega(&capped(&qz))?;
            let zq = capped(&qz);
            let mut post = [WeightedSums::<10>::new(); REPLICATES];
            let mut approx = [WeightedSums::<10>::new(); REPLICATES];
            let mut sobol = Sobol::new();
            let mut done = 0usize;
            let mut target = INITIAL_POINTS;
            loop {
                if *calls + (target - done) * REPLICATES > opts.max_calls {
                    let (err, mode, share, points) = last;
                    return Err(budget_refusal(
                        "update",
                        *calls,
                        opts.max_calls,
                        format!(
                            "second-moment error estimate {err:.2e} (tolerance {tolerance:.1e}), \
                             mode error estimate {mode:.3} spreads (tolerance {}), effective \
                             sample share {share:.3} with {points} points",
                            opts.mode_tolerance
                        ),
                    ));
                }
                let (mut x, mut y) = (Vect::<D>::zeros(), Vect::<D>::zeros());
                let mut g = [0.0; 10];
                while done < target {
                    let bits = sobol.next_bits();
                    for r in 0..REPLICATES {
                        let b = [bits[0] ^ sh[r][0], bits[1] ^ sh[r][1], bits[2] ^ sh[r][2]];
                        let l_env = acg.point(b, &mut x, &mut y);
                        *calls += 1;
                        let l = log_l(&x)?;
                        let l_prior = (x.transpose() * prior * x)[(0, 0)];
                        let l_approx: f64 = (0..D).map(|i| zq[i] * y[i] * y[i]).sum();
                        outer_packed::<D>(&y, &mut g);
                        post[r].add(l_prior + l - l_env, &g);
                        approx[r].add(l_approx - l_env, &g);
                    }
                    done += 1;
                }
                // Per-replicate corrections and their pooled value.
                let mut diffs = [[0.0; 10]; REPLICATES];
                let (mut pp, mut pa) = (post[0], approx[0]);
                for r in 0..REPLICATES {
                    let (a, b) = (post[r].mean(), approx[r].mean());
                    diffs[r] = core::array::from_fn(|k| a[k] - b[k]);
                    if r > 0 {
                        pp = pp.pooled(&post[r]);
                        pa = pa.pooled(&approx[r]);
                    }
                }
                let (_, se) = mean_and_error(&diffs);
                let (a, b) = (pp.mean(), pa.mean());
                let correction: [f64; 10] = core::array::from_fn(|k| a[k] - b[k]);
                let s_y = Mat::<D>::from_diagonal(&omega_q) + unpack::<D>(&correction);
                let e = estimate::<D>(&s_y, &se);
                let share = pp.share();
                last = (e.entries, e.mode, share, done * REPLICATES);
                let s = qm * s_y * qm.transpose();
                let big = correction[..D * (D + 1) / 2]
                    .iter()
                    .fold(0.0f64, |acc, v| acc.max(v.abs()));
                // A correction that is both large and clearly above its own noise.
                let significant = (0..D * (D + 1) / 2).any(|k| {
                    correction[k].abs() > RECENTER_TOLERANCES * tolerance
                        && correction[k].abs() > RECENTER_SIGMAS * se[k]
                });
                if e.entries <= tolerance && e.mode <= opts.mode_tolerance && share >= MIN_SHARE {
                    let report = NonlinearReport {
                        calls: *calls,
                        error_estimate: e.entries,
                        mode_error_estimate: e.mode,
                        method: NonlinearMethod::Sampled,
                        samples: done * REPLICATES,
                        effective_share: share,
                    };
                    // An approximation sharper than MAX_CONCENTRATION was sampled through its
                    // capped envelope: refitting the moment would cap the result too, so the
                    // approximation itself stands where the correction allows it (below).
                    let refit = if qz[0] < -MAX_CONCENTRATION {
                        Err(Error::Numerical("sharper than the sampled envelope".into()))
                    } else {
                        fit_second_moment(&s, None)
                    };
                    return match refit {
                        Ok((m_new, z_new, _)) => Ok((m_new, z_new, report)),
                        // The corrected moment is not positive definite: the posterior is so
                        // concentrated that the estimate's noise reaches its smallest
                        // eigenvalues. The envelope's distribution stands where the correction
                        // itself is within the tolerance (its error is then at most the
                        // correction plus the estimate's).
                        Err(_) if big + e.entries <= tolerance => Ok((
                            qm,
                            qz,
                            NonlinearReport {
                                error_estimate: big + e.entries,
                                ..report
                            },
                        )),
                        Err(_) => Err(Error::NotConverged(format!(
                            "nonlinear update: the corrected second moment is not positive \
                             definite (the posterior is sharper than the sampled estimate \
                             resolves) and the correction ({big:.2e}) exceeds the tolerance \
                             ({tolerance:.1e})"
                        ))),
                    };
                }
                let tilted = e.tilt > RECENTER_MODE && e.tilt > RECENTER_SIGMAS / SIGMAS * e.mode;
                if moves < MAX_MOVES && (significant || tilted) {
                    // Move the envelope to the corrected estimate (when it is a valid moment).
                    if let Ok((m_new, z_new, _)) = fit_second_moment(&s, None) {
                        qm = m_new;
                        qz = z_new;
                        moves += 1;
                        break;
                    }
                }
                target *= 2;
            }
        }
    }

    /// The second moment of `a(x)` under the state by sampling, to `opts.tolerance`.
    pub(super) fn sampled_prediction<F>(
        &self,
        a: &mut F,
        omega: &[f64],
        hess: &[f64],
        opts: &NonlinearOptions,
        calls: &mut usize,
    ) -> Result<(Mat<D>, NonlinearReport)>
    where
        F: FnMut(&Vect<D>, usize) -> Result<Vect<D>>,
    {
        let tolerance = opts.tolerance_or(DEFAULT_PREDICT_TOLERANCE);
        let zc = capped(&self.z);
        let acg = Acg::new(&self.m, &zc)?;
        let features = Features::new(D, omega, hess);
        let nh = features.n;
        let sh = shifts();
        let nu = D * (D + 1) / 2;
        let mut sums = [ReplicateSums::new(); REPLICATES];
        let mut pooled = PooledSums::new();
        let mut sobol = Sobol::new();
        let mut done = 0usize;
        let mut target = INITIAL_POINTS;
        let mut last = (f64::INFINITY, 0usize);
        loop {
            if *calls + (target - done) * REPLICATES > opts.max_calls {
                let (err, points) = last;
                return Err(budget_refusal(
                    "prediction",
                    *calls,
                    opts.max_calls,
                    format!(
                        "second-moment error estimate {err:.2e} (tolerance {tolerance:.1e}) \
                         with {points} points"
                    ),
                ));
            }
            let (mut x, mut y) = (Vect::<D>::zeros(), Vect::<D>::zeros());
            let (mut g, mut h) = ([0.0; 10], [0.0; MAX_FEATURES]);
            while done < target {
                let bits = sobol.next_bits();
                for (r, s) in sums.iter_mut().enumerate() {
                    let b = [bits[0] ^ sh[r][0], bits[1] ^ sh[r][1], bits[2] ^ sh[r][2]];
                    let l_env = acg.point(b, &mut x, &mut y);
                    let v = a(&x, *calls)?;
                    *calls += 1;
                    let l_state: f64 = (0..D).map(|i| zc[i] * y[i] * y[i]).sum();
                    outer_packed::<D>(&v, &mut g);
                    features.at(y.as_slice(), &mut h);
                    s.add(l_state - l_env, &h, &g);
                    pooled.add(l_state - l_env, &h, nh, &g);
                }
                done += 1;
            }
            let beta = pooled.coefficients(nh, nu);
            let ests: [[f64; 10]; REPLICATES] =
                core::array::from_fn(|r| sums[r].adjusted(&beta, &features, nu));
            let (mean, se) = mean_and_error(&ests);
            let err = SIGMAS * se[..nu].iter().fold(0.0f64, |acc, &v| acc.max(v));
            let share = pooled.share();
            last = (err, done * REPLICATES);
            if err <= tolerance && share >= MIN_SHARE {
                return Ok((
                    unpack::<D>(&mean),
                    NonlinearReport {
                        calls: *calls,
                        error_estimate: err,
                        mode_error_estimate: 0.0,
                        method: NonlinearMethod::Sampled,
                        samples: done * REPLICATES,
                        effective_share: share,
                    },
                ));
            }
            target *= 2;
        }
    }
}
