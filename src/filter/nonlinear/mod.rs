//! The nonlinear steps of the filter ([`BinghamFilter::predict_nonlinear`],
//! [`BinghamFilter::update_nonlinear`] and their `_opts` forms): a transition or a
//! log-likelihood given as a callback, the result a Bingham distribution whose second moment
//! meets the caller's tolerance ([`NonlinearOptions`]) or an error. The method is in
//! `docs/design.md`, section "Nonlinear steps".
//!
//! The files: `steps` (the two steps at the deterministic points of the state: the prediction
//! with its embedded error estimate, the update by tempered linearization and importance
//! correction), `sampled` (the sampled check and refinement where the deterministic points do
//! not meet the tolerance), `rqmc` (the randomized quasi-Monte Carlo points and sums it
//! uses), `control_variate` (the sampled prediction's regression control variates), `options`
//! (the options, the defaults and the report).
//!
//! [`BinghamFilter::predict_nonlinear`]: super::BinghamFilter::predict_nonlinear
//! [`BinghamFilter::update_nonlinear`]: super::BinghamFilter::update_nonlinear

mod control_variate;
mod options;
mod rqmc;
mod sampled;
mod steps;

pub use options::{
    NonlinearMethod, NonlinearOptions, NonlinearReport, DEFAULT_MAX_CALLS, DEFAULT_MODE_TOLERANCE,
    DEFAULT_PREDICT_TOLERANCE, DEFAULT_UPDATE_TOLERANCE,
};
pub use steps::{CORRECTION_PASSES, MAX_TEMPERING_STEPS, MIN_CORRECTION_SHARE, TEMPERING_RESIDUAL};
