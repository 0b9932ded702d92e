//! The nonlinear steps: prediction through a transition callback at the deterministic points
//! of the state, and the update with a log-likelihood callback by progressive (tempered)
//! linearization and importance correction (see [`super::BinghamFilter::update_nonlinear`]).

use super::noise::{capped, Role};
use super::nonlinear_options::{
    NonlinearMethod, NonlinearOptions, NonlinearReport, DEFAULT_PREDICT_TOLERANCE,
};
use super::{Core, Mat, Vect, MAX_CONCENTRATION};
use crate::canonical::UNIT_TOL;
use crate::deterministic::{
    for_each_point, for_each_principal, for_each_probe, plan, Reproduced, Scheme,
};
use crate::distribution::bayes_product;
use crate::error::{Error, Result};
use crate::linalg::cholesky_solve;
use crate::linalg::congruence;
use crate::mle::fit_second_moment;
use crate::quaternion::compose_moments;

/// The largest part of `log L` not captured by the fitted exponent (its largest residual over
/// the current deterministic points) one tempering step of
/// [`BinghamFilter::update_nonlinear`](crate::filter::BinghamFilter::update_nonlinear) applies: a step applies `L^{Δβ}` with
/// `Δβ · residual ≤ TEMPERING_RESIDUAL`.
pub const TEMPERING_RESIDUAL: f64 = 1.0;

/// Importance-corrected moment matches at the end of [`BinghamFilter::update_nonlinear`](crate::filter::BinghamFilter::update_nonlinear).
pub const CORRECTION_PASSES: usize = 2;

/// The importance correction of [`BinghamFilter::update_nonlinear`](crate::filter::BinghamFilter::update_nonlinear) is skipped when its
/// weights' effective share `(Σ w r)² / (Σ w · Σ w r²)` falls below this (the approximation is
/// then too far from the posterior for the points to correct it).
pub const MIN_CORRECTION_SHARE: f64 = 0.5;

/// The most tempering steps [`BinghamFilter::update_nonlinear`](crate::filter::BinghamFilter::update_nonlinear) takes.
pub const MAX_TEMPERING_STEPS: usize = 200;

/// The most deterministic points a filter step uses (the Moments scheme for d = 4).
const MAX_POINTS: usize = 19; // also 7 + 12 probes (d = 4 fallback), 3 + 2 (d = 2)

/// The evaluated points of a nonlinear update: deterministic points of the current
/// approximation with their weights and the log-likelihood there (on the stack).
struct EvaluatedPoints<const D: usize> {
    x: [Vect<D>; MAX_POINTS],
    /// Moment weights (fit weights for probes).
    w: [f64; MAX_POINTS],
    /// Fit-only points (no moment weight).
    probe: [bool; MAX_POINTS],
    l: [f64; MAX_POINTS],
    n: usize,
}

/// `log_l(x)`, with a failure or a non-finite value turned into [`Error::Callback`] naming the
/// point and `stage`.
fn checked_log_l<L>(log_l: &mut L, x: &[f64], stage: std::fmt::Arguments<'_>) -> Result<f64>
where
    L: FnMut(&[f64]) -> std::result::Result<f64, String>,
{
    let l = log_l(x).map_err(|msg| {
        Error::Callback(format!("log-likelihood failed at {x:?} ({stage}): {msg}"))
    })?;
    if !l.is_finite() {
        return Err(Error::Callback(format!(
            "log-likelihood returned {l} at {x:?}: not finite"
        )));
    }
    Ok(l)
}

/// The deterministic prediction is accepted where the embedded rule's difference is below this
/// fraction of the tolerance (see [`NonlinearMethod::Deterministic`]).
const EMBEDDED_MARGIN: f64 = 0.1;

/// Unknowns of a symmetric `P` for d = 4.
const MAX_UNKNOWNS: usize = 10;

impl<const D: usize> EvaluatedPoints<D> {
    fn new() -> Self {
        EvaluatedPoints {
            x: [Vect::<D>::zeros(); MAX_POINTS],
            w: [0.0; MAX_POINTS],
            probe: [false; MAX_POINTS],
            l: [0.0; MAX_POINTS],
            n: 0,
        }
    }

    /// The largest residual `|l_k − c − x_kᵀ P x_k|` over the points (fit-only points
    /// included), `c` the weighted mean offset (the fit's constant).
    #[allow(clippy::needless_range_loop)] // parallel arrays
    fn misfit(&self, p: &Mat<D>) -> f64 {
        // Relative to the largest log-likelihood, as in the fit (a huge constant cancels).
        let hi = self.l[..self.n]
            .iter()
            .fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        let mut r = [0.0; MAX_POINTS];
        let (mut sw, mut c) = (0.0, 0.0);
        for k in 0..self.n {
            let x = &self.x[k];
            r[k] = (self.l[k] - hi) - (x.transpose() * p * x)[(0, 0)];
            c += self.w[k] * r[k];
            sw += self.w[k];
        }
        let c = c / sw;
        r[..self.n]
            .iter()
            .fold(0.0, |a, &v| f64::max(a, (v - c).abs()))
    }

    /// The symmetric `P` minimizing `Σ_k w_k (l_k − c − x_kᵀ P x_k)²` (the constant `c` is
    /// absorbed in `P`'s trace, since `xᵀ x = 1`): the weighted least-squares fit of a Bingham
    /// exponent to the log-likelihood at the points. Exact when `log L` is such an exponent.
    ///
    /// The fit is done in the scaled principal coordinates `u_i = (mᵀx)_i / s_i` of the
    /// distribution the points come from (`s_i` the largest `|(mᵀx)_i|` over the points), so
    /// the normal equations stay well conditioned however concentrated the points are.
    #[allow(clippy::needless_range_loop)] // small dense normal equations
    fn fit_exponent(&self, m: &Mat<D>) -> Mat<D> {
        let nu = D * (D + 1) / 2;
        let hi = self.l[..self.n]
            .iter()
            .fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        let mut ys = [Vect::<D>::zeros(); MAX_POINTS];
        let mut scale = [0.0f64; D];
        for k in 0..self.n {
            ys[k] = m.transpose() * self.x[k];
            for i in 0..D {
                scale[i] = scale[i].max(ys[k][i].abs());
            }
        }
        for v in scale.iter_mut() {
            if v.is_nan() || *v <= 0.0 {
                *v = 1.0;
            }
        }
        let mut a = [0.0; MAX_UNKNOWNS * MAX_UNKNOWNS];
        let mut b = [0.0; MAX_UNKNOWNS];
        let mut phi = [0.0; MAX_UNKNOWNS];
        for k in 0..self.n {
            let y = &ys[k];
            let mut u = 0;
            for i in 0..D {
                for j in i..D {
                    let (ui, uj) = (y[i] / scale[i], y[j] / scale[j]);
                    phi[u] = if i == j { ui * ui } else { 2.0 * ui * uj };
                    u += 1;
                }
            }
            let (w, l) = (self.w[k], self.l[k] - hi);
            for r in 0..nu {
                b[r] += w * l * phi[r];
                for c in 0..nu {
                    a[r * nu + c] += w * phi[r] * phi[c];
                }
            }
        }
        // A tiny ridge keeps the normal equations definite.
        let tr: f64 = (0..nu).map(|r| a[r * nu + r]).sum();
        for r in 0..nu {
            a[r * nu + r] += 1e-12 * tr / nu as f64;
        }
        if !cholesky_solve(nu, &mut a[..nu * nu], &mut b[..nu]) {
            // Not numerically definite even with the ridge (no usable points): no exponent.
            b.fill(0.0);
        }
        let mut py = Mat::<D>::zeros();
        let mut u = 0;
        for i in 0..D {
            for j in i..D {
                let v = b[u] / (scale[i] * scale[j]);
                py[(i, j)] = v;
                py[(j, i)] = v;
                u += 1;
            }
        }
        m * py * m.transpose()
    }
}

impl<const D: usize> Core<D> {
    /// Visits the deterministic points (Moments scheme) of `Bingham(m, z)` with the
    /// concentrations capped as in the prediction, followed (if `probes`) by the fit-only probe points of
    /// [`for_each_probe`] (visited with a negative weight: `−w`).
    fn visit_points_and_probes(
        m: &Mat<D>,
        z: &Vect<D>,
        probes: bool,
        mut visit: impl FnMut(&Vect<D>, f64) -> Result<()>,
    ) -> Result<()> {
        let zc = capped(z);
        let mut grad = [0.0; D];
        let mut hess = [0.0; 16];
        let p = plan::<D>(
            zc.as_slice(),
            Scheme::Moments,
            &mut grad,
            &mut hess[..D * D],
        )?;
        for_each_point(m, &p, &grad, &hess[..D * D], &mut visit)?;
        if probes {
            for_each_probe(m, &p, |x, w| visit(x, -w))?;
        }
        Ok(())
    }

    pub(super) fn predict_nonlinear<F>(
        &mut self,
        a: &mut F,
        m_w: &[f64],
        z_w: &[f64],
        opts: &NonlinearOptions,
    ) -> Result<NonlinearReport>
    where
        F: FnMut(&[f64], &mut [f64]) -> std::result::Result<(), String>,
    {
        opts.check()?;
        let noise_moment = self.process.get(Role::Process, m_w, z_w)?.moment;
        let mut calls = 0usize;
        let mut eval = |x: &Vect<D>, k: usize| -> Result<Vect<D>> {
            let mut out = [0.0; D];
            a(x.as_slice(), &mut out).map_err(|msg| {
                Error::Callback(format!(
                    "transition failed at sample {k} {x:?}: {msg}",
                    x = x.as_slice()
                ))
            })?;
            let v = Vect::<D>::from_column_slice(&out);
            let n = v.norm();
            if !(n.is_finite() && (n - 1.0).abs() <= UNIT_TOL) {
                return Err(Error::Callback(format!(
                    "transition returned {out:?} at sample {k}: not a finite unit vector \
                     (norm {n}, tolerance {UNIT_TOL:e})"
                )));
            }
            Ok(v / n)
        };
        // The deterministic points, with the second-moment rule embedded in them.
        let zc = capped(&self.z);
        let mut grad = [0.0; D];
        let mut hess = [0.0; 16];
        let p = plan::<D>(
            zc.as_slice(),
            Scheme::Moments,
            &mut grad,
            &mut hess[..D * D],
        )?;
        let mut s = Mat::<D>::zeros();
        let mut low = Mat::<D>::zeros();
        let mut low_weight = 0.0;
        let mut mode_value = Vect::<D>::zeros();
        let m = self.m;
        for_each_principal(&p, &grad, &hess[..D * D], |y: &[f64], wt: f64| {
            if calls >= opts.max_calls {
                return Err(Error::NotConverged(format!(
                    "nonlinear prediction: the call budget ({} calls) is smaller than the \
                     {} deterministic points",
                    opts.max_calls,
                    p.count()
                )));
            }
            // x = M y (normalized), as `for_each_point` builds it.
            let mut x = Vect::<D>::zeros();
            for (k, &yk) in y.iter().enumerate() {
                if yk != 0.0 {
                    x.axpy(yk, &m.column(k), 1.0);
                }
            }
            let n = x.norm();
            x /= n;
            let v = eval(&x, calls)?;
            calls += 1;
            s.ger(wt, &v, &v, 1.0);
            // The embedded rule: the mode and the points on one principal axis (one non-zero
            // non-mode coordinate), weighted to carry E[y_i²] = ω_i per axis.
            let mut axis = None;
            let mut off = 0;
            for (i, &yi) in y[..D - 1].iter().enumerate() {
                if yi != 0.0 {
                    axis = Some(i);
                    off += 1;
                }
            }
            match (off, axis) {
                (0, _) => mode_value = v,
                (1, Some(i)) => {
                    let yi = y[i] / n;
                    let w = grad[i] / (2.0 * yi * yi);
                    low.ger(w, &v, &v, 1.0);
                    low_weight += w;
                }
                _ => {}
            }
            Ok(())
        })?;
        low.ger(1.0 - low_weight, &mode_value, &mode_value, 1.0);
        let embedded = if p.reproduced() == Reproduced::FourthMoments {
            (s - low).abs().max()
        } else {
            // The fallback set (the TAC 2016 points, λ = 1/2) reproduces only the second
            // moment and embeds no lower rule: a second rule of the same degree (λ = 1: the
            // pairs on the principal axes) on its own points gives the estimate instead.
            let mut g2 = [0.0; D];
            let mut h2 = [0.0; 16];
            let p2 = plan::<D>(
                zc.as_slice(),
                Scheme::Tac2016 { lambda: 1.0 },
                &mut g2,
                &mut h2[..D * D],
            )?;
            let mut s2 = Mat::<D>::zeros();
            for_each_point(
                &self.m,
                &p2,
                &g2,
                &h2[..D * D],
                &mut |x: &Vect<D>, wt: f64| {
                    if calls >= opts.max_calls {
                        return Err(Error::NotConverged(format!(
                            "nonlinear prediction: the call budget ({} calls) is smaller than the \
                         deterministic points",
                            opts.max_calls
                        )));
                    }
                    let v = eval(x, calls)?;
                    calls += 1;
                    s2.ger(wt, &v, &v, 1.0);
                    Ok(())
                },
            )?;
            (s - s2).abs().max()
        };
        let tolerance = opts.tolerance_or(DEFAULT_PREDICT_TOLERANCE);
        let (s, report) = if embedded <= EMBEDDED_MARGIN * tolerance {
            let report = NonlinearReport {
                calls,
                error_estimate: embedded,
                mode_error_estimate: 0.0,
                method: NonlinearMethod::Deterministic,
                samples: 0,
                effective_share: 1.0,
            };
            (s, report)
        } else {
            self.sampled_prediction(&mut eval, &grad, &hess[..D * D], opts, &mut calls)?
        };
        let c = compose_moments(&s, &noise_moment);
        let (m_new, z_new, solution) = fit_second_moment(&c, self.predicted.as_ref())?;
        self.m = m_new;
        self.z = z_new;
        self.predicted = Some(solution);
        Ok(report)
    }

    /// The deterministic points of `Bingham(m, z)` with the log-likelihood at each.
    fn evaluate_log_l<L>(
        m: &Mat<D>,
        z: &Vect<D>,
        log_l: &mut L,
        iteration: usize,
        out: &mut EvaluatedPoints<D>,
    ) -> Result<()>
    where
        L: FnMut(&[f64]) -> std::result::Result<f64, String>,
    {
        out.n = 0;
        Self::visit_points_and_probes(m, z, true, |x, wt| {
            let l = checked_log_l(
                log_l,
                x.as_slice(),
                format_args!("linearization {iteration}"),
            )?;
            let k = out.n;
            out.x[k] = *x;
            out.w[k] = wt.abs();
            out.probe[k] = wt < 0.0;
            out.l[k] = l;
            out.n += 1;
            Ok(())
        })
    }

    /// The moment-matched posterior from the deterministic points of its approximation
    /// `Bingham(m, z)`: the points are reweighted by `prior(x) L(x) / approximation(x)` (close
    /// to constant when the approximation is good, and exactly constant when it is the
    /// posterior) and the Bingham distribution with their second moment is fitted.
    #[allow(clippy::needless_range_loop)] // parallel arrays
    fn importance_correction<L>(
        &self,
        m: &Mat<D>,
        z: &Vect<D>,
        log_l: &mut L,
        points: &mut EvaluatedPoints<D>,
        step: usize,
    ) -> Result<(Mat<D>, Vect<D>)>
    where
        L: FnMut(&[f64]) -> std::result::Result<f64, String>,
    {
        if z[0] < -MAX_CONCENTRATION {
            // The points would be those of the capped distribution, not of the approximation.
            return Ok((*m, *z));
        }
        Self::evaluate_log_l(m, z, log_l, step, points)?;
        let prior = congruence(&self.m, &self.z);
        let approx = congruence(m, z);
        let mut lr = [0.0; MAX_POINTS];
        let mut top = f64::NEG_INFINITY;
        for k in 0..points.n {
            let x = &points.x[k];
            let e = (x.transpose() * (prior - approx) * x)[(0, 0)];
            lr[k] = points.l[k] + e;
            if !points.probe[k] {
                top = top.max(lr[k]);
            }
        }
        let mut s = Mat::<D>::zeros();
        // The weights' effective share: (Σ w r)² / (Σ w · Σ w r²), 1 for a constant ratio r.
        let (mut sw, mut swr, mut swr2) = (0.0, 0.0, 0.0);
        for k in 0..points.n {
            if points.probe[k] {
                continue;
            }
            let x = &points.x[k];
            let r = (lr[k] - top).exp();
            s.ger(points.w[k] * r, x, x, 1.0);
            sw += points.w[k];
            swr += points.w[k] * r;
            swr2 += points.w[k] * r * r;
        }
        if swr * swr < MIN_CORRECTION_SHARE * sw * swr2 {
            // The approximation is too far from the posterior for the points to correct it
            // (their weights would collapse): keep it.
            return Ok((*m, *z));
        }
        // A moment too close to singular (an approximation sharper than the MLE can represent,
        // |z| ≳ 1e13) cannot be refitted: the approximation stands.
        match fit_second_moment(&s, None) {
            Ok((m_new, z_new, _)) => Ok((m_new, z_new)),
            Err(_) => Ok((*m, *z)),
        }
    }

    /// The deterministic approximation of the posterior (tempering and importance correction),
    /// not yet checked; the state is not changed.
    fn deterministic_update<L>(&self, log_l: &mut L) -> Result<(Mat<D>, Vect<D>)>
    where
        L: FnMut(&[f64]) -> std::result::Result<f64, String>,
    {
        let mut points = EvaluatedPoints::<D>::new();
        let (mut m, mut z) = (self.m, self.z);
        let mut remaining = 1.0f64;
        for step in 0..MAX_TEMPERING_STEPS {
            Self::evaluate_log_l(&m, &z, log_l, step, &mut points)?;
            let p = points.fit_exponent(&m);
            // The fitted exponent's spread over the points decides the step.
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for k in 0..points.n {
                let x = &points.x[k];
                let q = (x.transpose() * p * x)[(0, 0)];
                lo = lo.min(q);
                hi = hi.max(q);
            }
            let spread = hi - lo;
            // Where the exponent fits log L at every sample (to rounding: log L is a Bingham
            // exponent there), the rest of the likelihood is applied at once.
            // The step is limited by the part of log L the exponent does not capture (the fit's
            // residual over the points): a log-quadratic likelihood is applied at once.
            let misfit = points.misfit(&p).max(1e-12 * spread);
            let last = misfit * remaining <= TEMPERING_RESIDUAL;
            let db = if last {
                remaining
            } else {
                TEMPERING_RESIDUAL / misfit
            };
            let (m_new, z_new) = bayes_product(&m, &z, &(p * db))?;
            m = m_new;
            z = z_new;
            if last {
                for pass in 0..CORRECTION_PASSES {
                    (m, z) =
                        self.importance_correction(&m, &z, log_l, &mut points, step + 1 + pass)?;
                }
                return Ok((m, z));
            }
            remaining -= db;
        }
        Err(Error::NotConverged(format!(
            "nonlinear update: the likelihood was not absorbed in {MAX_TEMPERING_STEPS} \
             tempering steps ({remaining:.3} of its exponent left); it is far sharper than \
             the prior or multimodal"
        )))
    }

    /// The nonlinear update with its error controlled by `opts` (see
    /// [`super::BinghamFilter::update_nonlinear_opts`]); the state changes only on success.
    pub(super) fn update_nonlinear<L>(
        &mut self,
        log_l: &mut L,
        opts: &NonlinearOptions,
    ) -> Result<NonlinearReport>
    where
        L: FnMut(&[f64]) -> std::result::Result<f64, String>,
    {
        opts.check()?;
        let mut calls = 0usize;
        let max_calls = opts.max_calls;
        let mut over = false;
        let mut counted = |x: &[f64]| -> std::result::Result<f64, String> {
            if calls >= max_calls {
                over = true;
                return Err("call budget exhausted".into());
            }
            calls += 1;
            log_l(x)
        };
        let (m, z) = match self.deterministic_update(&mut counted) {
            Ok(v) => v,
            Err(_) if over => {
                return Err(Error::NotConverged(format!(
                    "nonlinear update: the call budget ({max_calls} calls) ran out in the \
                     deterministic approximation, before any error estimate"
                )))
            }
            Err(e) => return Err(e),
        };

        let mut checked =
            |x: &Vect<D>| checked_log_l(log_l, x.as_slice(), format_args!("sampled check"));
        let (m, z, report) = self.sampled_update(m, z, &mut checked, opts, &mut calls)?;
        self.m = m;
        self.z = z;
        Ok(report)
    }
}
