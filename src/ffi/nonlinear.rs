//! The nonlinear steps of the filter handle (`bingham_filter_predict_nonlinear`,
//! `bingham_filter_update_nonlinear` and their `_opts` forms with a tolerance, a call budget and a
//! report): the callback types and thin wrappers over
//! [`crate::filter::BinghamFilter::predict_nonlinear_opts`] /
//! [`crate::filter::BinghamFilter::update_nonlinear_opts`].

use std::os::raw::{c_int, c_void};

use super::args::{args, Arg, Opt, ValueOut};
use super::filter::bingham_filter;
use super::guard::{guard, handle, handle_mut, Failure, FfiResult};
use super::status::bingham_status;
use crate::filter::{NonlinearMethod, NonlinearOptions, NonlinearReport};

/// The transition function `a` of `bingham_filter_predict_nonlinear()` (system model
/// `x[k+1] = a(x[k]) (+) w[k]`).
///
/// Called with `x_in`: a unit vector of d doubles (the filter's dimension; a quaternion, scalar
/// first, for d = 4), owned by the library and valid during the call only. It must write the
/// unit vector `a(x_in)` to `x_out` (d doubles; unit within `BINGHAM_UNIT_TOL`, it is then
/// normalized; its sign does not matter) and return 0. `x_out` is filled with NaN before each
/// call, so an output left unwritten is caught. `user_data` is the pointer passed to
/// `bingham_filter_predict_nonlinear()`, unchanged.
///
/// A non-zero return means failure: the prediction stops and returns `BINGHAM_ERR_CALLBACK`
/// with the filter unchanged; so does an output that is not finite or not unit length. The
/// message of `bingham_last_error_message()` names the point and the returned code or value.
///
/// Contract (the caller's, not checked): `a(-x) = ±a(x)` (an axis / rotation and its negative
/// are the same, so `a` must respect the sign symmetry). The function is called on the calling
/// thread, synchronously, a fixed number of times per prediction (see
/// `bingham_filter_predict_nonlinear()`). It must return normally: it must not unwind (a C++
/// exception, a Rust panic) or `longjmp` through the library, which is undefined behaviour
/// (catch exceptions inside and return non-zero instead), and it must not call functions on
/// the same filter handle (other library functions, e.g. on other handles, are fine).
#[allow(non_camel_case_types)]
pub type bingham_transition_fn = Option<
    unsafe extern "C" fn(x_in: *const f64, x_out: *mut f64, user_data: *mut c_void) -> c_int,
>;

/// The log-likelihood function of `bingham_filter_update_nonlinear()`: the natural logarithm
/// of the likelihood `L(x) = p(measurement | x)` up to an additive constant (a log-likelihood,
/// so sharp likelihoods do not underflow).
///
/// Called with `x`: a unit vector of d doubles (a quaternion, scalar first, for d = 4), owned by
/// the library and valid during the call only. It must write `log L(x)` (finite) to `*log_l`
/// and return 0. `*log_l` holds NaN before each call, so a value left unwritten is caught.
/// `user_data` is the pointer passed to `bingham_filter_update_nonlinear()`, unchanged.
///
/// A non-zero return means failure: the update stops and returns `BINGHAM_ERR_CALLBACK` with
/// the filter unchanged; so does a value that is not finite (a likelihood of exactly 0 has no
/// finite logarithm: return a large negative number instead).
///
/// Contract (the caller's, not checked): `L(-x) = L(x)`. Called on the calling thread,
/// synchronously (how often: see `bingham_filter_update_nonlinear()`); it must return normally
/// (no unwinding or `longjmp` through the library) and must not call functions on the same
/// filter handle.
#[allow(non_camel_case_types)]
pub type bingham_log_likelihood_fn =
    Option<unsafe extern "C" fn(x: *const f64, log_l: *mut f64, user_data: *mut c_void) -> c_int>;

/// Nonlinear prediction step: the state becomes the distribution of `a(x) (+) w`,
/// `w ~ Bingham(m_w, z_w)`, for a transition function `a` given as a C callback.
///
/// The new state is the Bingham distribution whose second moment is that of `a(x)` (`x` from
/// the state) composed exactly with the noise's (moment matching), as in
/// `bingham_filter_predict()`. The second moment of `a(x)` meets the default tolerance
/// (`BINGHAM_NONLINEAR_PREDICT_TOLERANCE`, 5e-4 per entry; what it means:
/// `bingham_nonlinear_options.tolerance`) within 20000 calls of `fn`, or the prediction is
/// refused (`BINGHAM_ERR_NOT_CONVERGED`). With `a` the identity this equals
/// `bingham_filter_predict()` to rounding. The method: `docs/design.md`, section "Nonlinear
/// steps".
///
/// - `fn`: the transition function (see `bingham_transition_fn` for its contract), called once
///   per sample, in the order of `bingham_deterministic_samples()`: 3 times for d = 2, 19 times
///   for d = 4 (7 + 7 where the moment-matched set does not exist and two TAC 2016 rules are
///   compared), then at sampled points where the estimate asks (at most 20000 calls); the first
///   failing call ends the prediction.
/// - `user_data`: passed to every call of `fn` unchanged; may be `NULL`.
/// - `m_w`, `z_w`: the process noise, as in `bingham_filter_predict()` (cached likewise).
///
/// Concentrations below `-BINGHAM_FILTER_MAX_CONCENTRATION` (state or noise) are raised to it
/// for this computation, as in `bingham_filter_predict()`. No heap allocation once the noise is
/// cached (beyond what `fn` does).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`f`, `fn`, `m_w`, `z_w`), `BINGHAM_ERR_INVALID_ARGUMENT`
/// (NaN/Inf, `m_w` not orthogonal), `BINGHAM_ERR_CALLBACK` (`fn` returned non-zero, or an output
/// that is not finite or not unit), `BINGHAM_ERR_NOT_CONVERGED` (the tolerance not met within
/// the budget; moment matching) / `BINGHAM_ERR_NUMERICAL` (moment matching). The arguments are
/// checked before `fn` is first called. On error the filter is unchanged.
///
/// # Safety
/// `f`: a live handle; `fn`: a function honouring the contract of `bingham_transition_fn`;
/// `m_w`: d*d and `z_w`: d readable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_predict_nonlinear(
    f: *mut bingham_filter,
    r#fn: bingham_transition_fn,
    user_data: *mut c_void,
    m_w: *const f64,
    z_w: *const f64,
) -> bingham_status {
    guard("bingham_filter_predict_nonlinear", || {
        // SAFETY: caller contract (no options, no report).
        unsafe {
            predict(
                f,
                r#fn,
                user_data,
                m_w,
                z_w,
                std::ptr::null(),
                std::ptr::null_mut(),
            )
        }
    })
}

/// Nonlinear measurement update (Bayes' rule): the state becomes the Bingham approximation of
/// the posterior `∝ prior(x) · L(x)`, for a likelihood `L` given by its logarithm as a C callback
/// (e.g. a sensor that sees a nonlinear function of the orientation).
///
/// The likelihood is absorbed at the deterministic samples of the current approximation (the
/// `BINGHAM_SAMPLES_MOMENTS` points of `bingham_deterministic_samples()`, plus fit-only points
/// where those are too few: 5 calls of `fn` per round for d = 2, 19 for d = 4), in as many
/// rounds as `log L`'s distance from a quadratic form needs (bounded), and the result is
/// checked and corrected by sampling around it. OK means the error estimates met the default
/// tolerances: 2.5e-3 per entry of the posterior's second moment
/// (`BINGHAM_NONLINEAR_UPDATE_TOLERANCE`; what it means: `bingham_nonlinear_options.tolerance`)
/// and 0.05 spreads for its mode, within 20000 calls of `fn` (beyond,
/// `BINGHAM_ERR_NOT_CONVERGED`); see `bingham_filter_update_nonlinear_opts()`. A likelihood
/// that is a Bingham density is applied exactly. The method: `docs/design.md`, section
/// "Nonlinear steps"; measured call counts: `docs/accuracy.md` (nonlinear models).
///
/// For a likelihood that is a Bingham density with known parameters, `bingham_filter_update()`
/// / `bingham_multiply()` compute the same product directly.
///
/// - `fn`: the log-likelihood (see `bingham_log_likelihood_fn` for its contract).
/// - `user_data`: passed to every call of `fn` unchanged; may be `NULL`.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`f`, `fn`; checked before `fn` is first called),
/// `BINGHAM_ERR_CALLBACK` (`fn` returned non-zero or a value that is not finite; the first such
/// call ends the update), `BINGHAM_ERR_NOT_CONVERGED` (not absorbed within the limit, the
/// tolerance not met within 20000 calls, or a fit did not converge), `BINGHAM_ERR_NUMERICAL`.
/// On error the filter is unchanged.
///
/// # Safety
/// `f`: a live handle; `fn`: a function honouring the contract of `bingham_log_likelihood_fn`.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_update_nonlinear(
    f: *mut bingham_filter,
    r#fn: bingham_log_likelihood_fn,
    user_data: *mut c_void,
) -> bingham_status {
    guard("bingham_filter_update_nonlinear", || {
        // SAFETY: caller contract (no options, no report).
        unsafe { update(f, r#fn, user_data, std::ptr::null(), std::ptr::null_mut()) }
    })
}

/// How `bingham_filter_predict_nonlinear_opts()` and `bingham_filter_update_nonlinear_opts()`
/// control their error. Fill it with `bingham_nonlinear_options_default()` and change what you
/// need; `NULL` options mean the defaults.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct bingham_nonlinear_options {
    /// The largest accepted error estimate (absolute) of any entry of the result's second
    /// moment `E[x xᵀ]` (entries lie in [−1, 1]; for the prediction, before the noise is
    /// composed in). Finite and ≥ 0; 0 (the default) means the step's own default: 5e-4 for the
    /// prediction, 2.5e-3 for the update (`BINGHAM_NONLINEAR_PREDICT_TOLERANCE`,
    /// `BINGHAM_NONLINEAR_UPDATE_TOLERANCE`; their reasons in `docs/guide.md`). The estimate is
    /// statistical, not a bound: three standard errors of the sampled estimate (or, for a
    /// prediction the deterministic points settle, the difference of their two rules); the
    /// error exceeds it rarely, not never. The method: `docs/design.md`, section "Nonlinear
    /// steps".
    pub tolerance: f64,
    /// Update only: the largest accepted error estimate of the posterior mode as a fraction of
    /// the posterior's spread `sqrt(1 − largest eigenvalue of E[x xᵀ])` (both as chords between
    /// unit vectors). Positive and finite; default 0.05.
    pub mode_tolerance: f64,
    /// The most callback calls the step may make (≥ 1); a step that would need more is refused
    /// with `BINGHAM_ERR_NOT_CONVERGED`. Default 20000.
    pub max_calls: usize,
}

/// `bingham_nonlinear_report.method`: the deterministic points alone (prediction only: their
/// embedded error estimate was below a tenth of the tolerance).
pub const BINGHAM_NONLINEAR_DETERMINISTIC: c_int = 0;

/// `bingham_nonlinear_report.method`: randomized quasi-Monte Carlo over the deterministic
/// result's envelope (the update always; the prediction where the points' estimate asks).
pub const BINGHAM_NONLINEAR_SAMPLED: c_int = 1;

/// The prediction's default tolerance (see `bingham_nonlinear_options.tolerance`).
pub const BINGHAM_NONLINEAR_PREDICT_TOLERANCE: f64 = 5e-4;

/// The update's default tolerance (see `bingham_nonlinear_options.tolerance`).
pub const BINGHAM_NONLINEAR_UPDATE_TOLERANCE: f64 = 2.5e-3;

// The header's literals (cbindgen writes literals only) are the core's defaults.
const _: () = assert!(
    BINGHAM_NONLINEAR_PREDICT_TOLERANCE == crate::filter::DEFAULT_PREDICT_TOLERANCE
        && BINGHAM_NONLINEAR_UPDATE_TOLERANCE == crate::filter::DEFAULT_UPDATE_TOLERANCE
);

/// What a nonlinear step measured (written only on success).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct bingham_nonlinear_report {
    /// Callback calls made.
    pub calls: usize,
    /// The error estimate (absolute) of the result's second moment, largest entry: three
    /// standard errors of the sampled estimate (sampled), or the difference of the
    /// deterministic points' two rules (deterministic). At most the tolerance.
    pub error_estimate: f64,
    /// Update: the error estimate of the mode as a fraction of the posterior's spread (at most
    /// the mode tolerance); prediction: 0 (not estimated).
    pub mode_error_estimate: f64,
    /// `BINGHAM_NONLINEAR_DETERMINISTIC` or `BINGHAM_NONLINEAR_SAMPLED`.
    pub method: c_int,
    /// Sampled points behind the result (0 when deterministic).
    pub samples: usize,
    /// The effective sample share `(Σw)² / (n Σw²)` of the final importance weights, in (0, 1]
    /// (1 when nothing was sampled).
    pub effective_share: f64,
}

/// Fills `*opts` with the defaults: `tolerance` 0 (the step's default), `mode_tolerance`
/// 0.05, `max_calls` 20000.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`opts`).
///
/// # Safety
/// `opts`: a writable `bingham_nonlinear_options`.
#[no_mangle]
pub unsafe extern "C" fn bingham_nonlinear_options_default(
    opts: *mut bingham_nonlinear_options,
) -> bingham_status {
    guard("bingham_nonlinear_options_default", || {
        // SAFETY: caller contract.
        let place = unsafe { args!(opts: out).read()? };
        // SAFETY: nothing else was read.
        unsafe { place.0.set(to_c_options(&NonlinearOptions::default())) };
        Ok(())
    })
}

/// `bingham_filter_predict_nonlinear()` with its error controlled by `opts` and what it
/// measured written to `report`.
///
/// The predicted second moment `E[a(x) a(x)ᵀ]` (before the noise is composed in) is computed
/// with an error estimate of at most `opts->tolerance` in every entry; a model the
/// deterministic points integrate exactly (the identity, a rotation) costs no calls beyond
/// theirs (see `bingham_filter_predict_nonlinear()`). A prediction that would need more than
/// `opts->max_calls` calls of `fn` is refused with `BINGHAM_ERR_NOT_CONVERGED` and a message
/// that gives the estimate reached; the filter is then unchanged. The method:
/// `docs/design.md`, section "Nonlinear steps"; figures: `docs/accuracy.md` (nonlinear
/// models).
///
/// - `opts`: the tolerance and the budget (`NULL`: the defaults).
/// - `report`: receives what was measured (`NULL`: not wanted); written only on success.
///
/// Errors: those of `bingham_filter_predict_nonlinear()`; `BINGHAM_ERR_INVALID_ARGUMENT` (an
/// option out of range); `BINGHAM_ERR_NOT_CONVERGED` (the tolerance was not met within the
/// budget). The arguments (options included) are checked before `fn` is first called.
///
/// # Safety
/// As for `bingham_filter_predict_nonlinear()`; `opts`: `NULL` or a readable
/// `bingham_nonlinear_options`; `report`: `NULL` or a writable `bingham_nonlinear_report`.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_predict_nonlinear_opts(
    f: *mut bingham_filter,
    r#fn: bingham_transition_fn,
    user_data: *mut c_void,
    m_w: *const f64,
    z_w: *const f64,
    opts: *const bingham_nonlinear_options,
    report: *mut bingham_nonlinear_report,
) -> bingham_status {
    guard("bingham_filter_predict_nonlinear_opts", || {
        // SAFETY: caller contract.
        unsafe { predict(f, r#fn, user_data, m_w, z_w, opts, report) }
    })
}

/// `bingham_filter_update_nonlinear()` with its error controlled by `opts` and what it measured
/// written to `report`.
///
/// The posterior's second moment is computed with an error estimate of at most
/// `opts->tolerance` in every entry and its mode with one of at most `opts->mode_tolerance`
/// spreads (a Bingham likelihood stays exact: the check changes nothing where the
/// deterministic approximation is the posterior). An update that would need more than
/// `opts->max_calls` calls of `fn` (the deterministic part's included) is refused with
/// `BINGHAM_ERR_NOT_CONVERGED` and a message giving the estimates reached; the filter is then
/// unchanged. Multimodal posteriors: the sampling sees the mode(s) near the deterministic
/// approximation; a separate mode far from the prior's bulk may be missed (see
/// `docs/guide.md`). The method: `docs/design.md`, section "Nonlinear steps"; figures:
/// `docs/accuracy.md` (nonlinear models).
///
/// - `opts`: the tolerances and the budget (`NULL`: the defaults).
/// - `report`: receives what was measured (`NULL`: not wanted); written only on success.
///
/// Errors: those of `bingham_filter_update_nonlinear()`; `BINGHAM_ERR_INVALID_ARGUMENT` (an
/// option out of range); `BINGHAM_ERR_NOT_CONVERGED` (the tolerance was not met within the
/// budget). The arguments (options included) are checked before `fn` is first called.
///
/// # Safety
/// As for `bingham_filter_update_nonlinear()`; `opts`: `NULL` or a readable
/// `bingham_nonlinear_options`; `report`: `NULL` or a writable `bingham_nonlinear_report`.
#[no_mangle]
pub unsafe extern "C" fn bingham_filter_update_nonlinear_opts(
    f: *mut bingham_filter,
    r#fn: bingham_log_likelihood_fn,
    user_data: *mut c_void,
    opts: *const bingham_nonlinear_options,
    report: *mut bingham_nonlinear_report,
) -> bingham_status {
    guard("bingham_filter_update_nonlinear_opts", || {
        // SAFETY: caller contract.
        unsafe { update(f, r#fn, user_data, opts, report) }
    })
}

fn to_c_options(o: &NonlinearOptions) -> bingham_nonlinear_options {
    bingham_nonlinear_options {
        tolerance: o.tolerance,
        mode_tolerance: o.mode_tolerance,
        max_calls: o.max_calls,
    }
}

fn to_c_report(r: &NonlinearReport) -> bingham_nonlinear_report {
    bingham_nonlinear_report {
        calls: r.calls,
        error_estimate: r.error_estimate,
        mode_error_estimate: r.mode_error_estimate,
        method: match r.method {
            NonlinearMethod::Deterministic => BINGHAM_NONLINEAR_DETERMINISTIC,
            NonlinearMethod::Sampled => BINGHAM_NONLINEAR_SAMPLED,
        },
        samples: r.samples,
        effective_share: r.effective_share,
    }
}

/// The options behind `opts` (`NULL`: the defaults), checked.
///
/// # Safety
/// `opts`: `NULL` or a readable `bingham_nonlinear_options`.
unsafe fn read_options(opts: *const bingham_nonlinear_options) -> FfiResult<NonlinearOptions> {
    let o = if opts.is_null() {
        NonlinearOptions::default()
    } else {
        // SAFETY: caller contract; checked for alignment.
        let c = unsafe { handle("opts", opts)? };
        NonlinearOptions {
            tolerance: c.tolerance,
            mode_tolerance: c.mode_tolerance,
            max_calls: c.max_calls,
        }
    };
    o.check()?;
    Ok(o)
}

/// The frame both nonlinear steps share: the handle, the callback (NULL refused), the report
/// place (NULL: not wanted; checked before anything runs), the options; `step` runs the step
/// and its report is stored only on success.
///
/// # Safety
/// `f`: NULL or a live handle; `opts`: NULL or readable; `report`: NULL or writable.
unsafe fn nonlinear_step<C>(
    f: *mut bingham_filter,
    callback: Option<C>,
    opts: *const bingham_nonlinear_options,
    report: *mut bingham_nonlinear_report,
    step: impl FnOnce(&mut bingham_filter, C, &NonlinearOptions) -> FfiResult<NonlinearReport>,
) -> FfiResult<()> {
    // SAFETY: caller contract.
    let filter = unsafe { handle_mut("f", f)? };
    let callback = callback.ok_or_else(|| Failure::null("fn"))?;
    let out = Opt::when(!report.is_null(), ValueOut::new("report", report));
    out.check()?;
    // SAFETY: caller contract.
    let options = unsafe { read_options(opts)? };
    let r = step(filter, callback, &options)?;
    // SAFETY: checked above; every input has been read.
    if let Some(place) = unsafe { out.take()? } {
        // SAFETY: as above.
        unsafe { place.set(to_c_report(&r)) };
    }
    Ok(())
}

/// The shared body of the predictions.
///
/// # Safety
/// The contract of `bingham_filter_predict_nonlinear_opts()`.
unsafe fn predict(
    f: *mut bingham_filter,
    callback: bingham_transition_fn,
    user_data: *mut c_void,
    m_w: *const f64,
    z_w: *const f64,
    opts: *const bingham_nonlinear_options,
    report: *mut bingham_nonlinear_report,
) -> FfiResult<()> {
    let step = |filter: &mut bingham_filter,
                callback: unsafe extern "C" fn(*const f64, *mut f64, *mut c_void) -> c_int,
                options: &NonlinearOptions| {
        let transition = |x: &[f64], out: &mut [f64]| -> Result<(), String> {
            out.fill(f64::NAN);
            // SAFETY: `x` and `out` are library-owned arrays of d doubles, valid for the call;
            // the callback's own contract is the caller's (see `bingham_transition_fn`).
            let rc = unsafe { callback(x.as_ptr(), out.as_mut_ptr(), user_data) };
            if rc != 0 {
                Err(format!("callback returned {rc}"))
            } else {
                Ok(())
            }
        };
        let d = filter.inner.dim();
        // SAFETY: caller contract: `m_w` d*d and `z_w` d readable doubles.
        let (m, z) = unsafe { args!(m_w: [d * d], z_w: [d]).read()? };
        Ok(filter
            .inner
            .predict_nonlinear_opts(transition, m, z, options)?)
    };
    // SAFETY: forwarded caller contract.
    unsafe { nonlinear_step(f, callback, opts, report, step) }
}

/// The shared body of the updates.
///
/// # Safety
/// The contract of `bingham_filter_update_nonlinear_opts()`.
unsafe fn update(
    f: *mut bingham_filter,
    callback: bingham_log_likelihood_fn,
    user_data: *mut c_void,
    opts: *const bingham_nonlinear_options,
    report: *mut bingham_nonlinear_report,
) -> FfiResult<()> {
    let step = |filter: &mut bingham_filter,
                callback: unsafe extern "C" fn(*const f64, *mut f64, *mut c_void) -> c_int,
                options: &NonlinearOptions| {
        let log_l = |x: &[f64]| -> Result<f64, String> {
            let mut value = f64::NAN;
            // SAFETY: `x` is a library-owned array of d doubles and `value` a local double,
            // both valid for the call; the callback's contract is the caller's.
            let rc = unsafe { callback(x.as_ptr(), &mut value, user_data) };
            if rc != 0 {
                Err(format!("callback returned {rc}"))
            } else {
                Ok(value)
            }
        };
        Ok(filter.inner.update_nonlinear_opts(log_l, options)?)
    };
    // SAFETY: forwarded caller contract.
    unsafe { nonlinear_step(f, callback, opts, report, step) }
}
