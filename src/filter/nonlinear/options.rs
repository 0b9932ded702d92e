//! The options and the report of the nonlinear steps
//! ([`BinghamFilter::update_nonlinear_opts`](crate::filter::BinghamFilter::update_nonlinear_opts),
//! [`BinghamFilter::predict_nonlinear_opts`](crate::filter::BinghamFilter::predict_nonlinear_opts)):
//! a tolerance on the error estimate, a budget of callback calls, and what a step measured.

use crate::error::{Error, Result};

/// The prediction's default tolerance (used where [`NonlinearOptions::tolerance`] is 0): the
/// largest accepted error estimate of any entry of the predicted second moment `E[a(x) a(x)ᵀ]`
/// (entries lie in `[−1, 1]`). Why this value: a prediction's error is not corrected by
/// anything that follows it (an update is), so errors of a stretch of predictions without
/// measurements add up — independent errors of 5e-4 over 100 steps stay near 5e-3, below what
/// moment matching of a filter step resolves in practice. Randomized QMC reaches it with about
/// 4 000 calls where the deterministic points do not.
pub const DEFAULT_PREDICT_TOLERANCE: f64 = 5e-4;

/// The update's default tolerance (used where [`NonlinearOptions::tolerance`] is 0): the
/// largest accepted error estimate of any entry of the posterior's second moment. Why this
/// value: a quarter of 0.01, the difference below which two posteriors' moments are taken as
/// equal in the acceptance test (`tests/nonlinear_trust.rs`), so that an estimate at the
/// tolerance (3 standard errors) leaves a margin for the estimate's own error; the next
/// measurements correct an update's residual error, a prediction's they do not.
pub const DEFAULT_UPDATE_TOLERANCE: f64 = 2.5e-3;

/// Default [`NonlinearOptions::mode_tolerance`]: the largest accepted error estimate of the
/// posterior mode, as a fraction of the posterior's spread.
pub const DEFAULT_MODE_TOLERANCE: f64 = 0.05;

/// Default [`NonlinearOptions::max_calls`]: the most callback calls of one step.
pub const DEFAULT_MAX_CALLS: usize = 20_000;

/// How a nonlinear step's error is controlled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NonlinearOptions {
    /// The largest accepted error estimate (absolute) of any entry of the result's second
    /// moment `E[x xᵀ]` (before the prediction's noise is composed in); non-negative and
    /// finite, 0 = the step's default ([`DEFAULT_PREDICT_TOLERANCE`],
    /// [`DEFAULT_UPDATE_TOLERANCE`]). The estimate is statistical, not a bound: three
    /// standard errors of the sampled estimate (or, for a prediction the deterministic points
    /// settle, the difference of their two rules); the error exceeds it rarely, not never.
    /// The method: `docs/design.md`, section "Nonlinear steps".
    pub tolerance: f64,
    /// Update only: the largest accepted error estimate of the posterior mode as a fraction of
    /// the posterior's spread `√(1 − λ_max(E[x xᵀ]))` (both as the chord between unit
    /// vectors). Positive and finite.
    pub mode_tolerance: f64,
    /// The most callback calls the step may make (at least 1); a step that needs more is
    /// refused with [`Error::NotConverged`].
    pub max_calls: usize,
}

impl Default for NonlinearOptions {
    fn default() -> Self {
        NonlinearOptions {
            tolerance: 0.0,
            mode_tolerance: DEFAULT_MODE_TOLERANCE,
            max_calls: DEFAULT_MAX_CALLS,
        }
    }
}

impl NonlinearOptions {
    /// The tolerance in force for a step whose default is `default`.
    pub(crate) fn tolerance_or(&self, default: f64) -> f64 {
        if self.tolerance == 0.0 {
            default
        } else {
            self.tolerance
        }
    }

    /// Checks the fields (finite tolerances, a budget of at least one call).
    pub fn check(&self) -> Result<()> {
        let t = self.tolerance;
        if !(t.is_finite() && t >= 0.0) {
            return Err(Error::InvalidArgument(format!(
                "options.tolerance must be finite and non-negative (0: the default), got {t}"
            )));
        }
        let v = self.mode_tolerance;
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::InvalidArgument(format!(
                "options.mode_tolerance must be positive and finite, got {v}"
            )));
        }
        if self.max_calls == 0 {
            return Err(Error::InvalidArgument(
                "options.max_calls must be at least 1".into(),
            ));
        }
        Ok(())
    }
}

/// How the result of a nonlinear step was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NonlinearMethod {
    /// Prediction only: the deterministic points alone, accepted where the error estimate —
    /// the difference between the 19-point rule (exact for every fourth moment) and the
    /// second-moment rule embedded in the same points, an estimate of the lower rule's error —
    /// is below a tenth of the tolerance (a margin: the difference is an estimate, not a
    /// bound). Exact models (the identity, a rotation) take this path at no extra cost.
    Deterministic,
    /// Randomized quasi-Monte Carlo over the deterministic result's envelope (the update
    /// always, the prediction where the deterministic points' estimate asks for it); the error
    /// estimate is three standard errors of the sampled estimate.
    Sampled,
}

/// What a nonlinear step measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NonlinearReport {
    /// Callback calls made.
    pub calls: usize,
    /// The error estimate of the second moment's largest entry error (absolute), at most the
    /// tolerance.
    pub error_estimate: f64,
    /// Update: the error estimate of the mode as a fraction of the spread (at most the mode
    /// tolerance); prediction: 0 (not estimated).
    pub mode_error_estimate: f64,
    /// How the result was obtained.
    pub method: NonlinearMethod,
    /// Sampled points used for the result (0 for [`NonlinearMethod::Deterministic`]).
    pub samples: usize,
    /// The effective sample share of the final importance weights, `(Σw)² / (n Σw²)` in
    /// `(0, 1]` (1 when nothing was sampled).
    pub effective_share: f64,
}
