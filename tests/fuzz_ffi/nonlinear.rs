//! The nonlinear filter steps.
//!
//! bingham_filter_predict_nonlinear / bingham_filter_update_nonlinear: random sequences on a filter
//! and a twin (as for the filter above) with callbacks that succeed (identity, rotations, sign
//! flips, smooth odd maps, outputs unit within the tolerance; quadratic, constant, huge and
//! non-quadratic log-likelihoods) or fail in every way (non-zero return, NaN, ±Inf, non-unit or zero
//! output, nothing written), always or only at the k-th call. A failing callback gives
//! BINGHAM_ERR_CALLBACK after exactly k + 1 calls, with the state (and, through the twin, the hidden
//! state) unchanged; invalid arguments are refused before the first call; the callbacks always see
//! a unit vector, a NaN-filled output and their own user pointer. Half the steps go through the
//! `_opts` forms with random tolerances and budgets (from 1 call) or the defaults of
//! `bingham_nonlinear_options_default`, and now and then an invalid option: never more calls than the budget, a report written only on success and consistent with
//! the calls counted and the tolerance, invalid options refused before any call.

use std::collections::BTreeMap;
use std::os::raw::c_int;
use std::os::raw::c_void;

use bingham::ffi::bingham_status::*;
use bingham::ffi::*;
use testkit::fuzz::{
    check_state, check_unit, congruence, extreme, non_finite, orthogonal, z_moderate, z_vector, Buf,
};
use testkit::{norm, Rng64};

use crate::drivers::{cases_for, run_sequences, stats_wanted, SHARE_NONLINEAR};
use crate::filter::{filter_noise, filter_state, state_bits};
use crate::status::{check_error_message, last_error, prime_last_error, status_code, status_name};

// -- the callbacks

const CB_MAGIC: u64 = 0xB1E5_5ED0_CA11_BAC5;

/// What a callback does when it misbehaves.
#[derive(Debug, Clone, Copy, PartialEq)]
enum CbBad {
    Rc(c_int),
    Nan(usize),
    Inf(usize, f64),
    /// the (otherwise valid) output times this factor: not unit
    Scale(f64),
    Zero,
    /// returns 0 without writing
    Nothing,
}

/// What a callback does otherwise.
#[derive(Debug, Clone, PartialEq)]
enum CbGood {
    Identity,
    /// x -> x (+) u
    Rotate(Vec<f64>),
    Negate,
    /// x -> normalize(x + c x³) (odd)
    Cubic(f64),
    /// identity times s, |s − 1| within the tolerance
    AlmostUnit(f64),
    /// log L = xᵀ P x
    Quadratic(Vec<f64>),
    Constant(f64),
    /// log L = −kappa (1 − (vᵀx)²)²
    Quartic(f64, Vec<f64>),
}

#[derive(Debug, Clone)]
struct CbCtx {
    magic: u64,
    d: usize,
    good: CbGood,
    bad: Option<CbBad>,
    /// misbehave at this call only (None: at every call, if `bad` is set)
    fail_at: Option<usize>,
    calls: usize,
    /// the call at which the callback misbehaved
    triggered: Option<usize>,
    /// a contract violation seen by the callback (x not unit, output not NaN-filled, ...)
    violation: Option<String>,
}

impl CbCtx {
    fn new(d: usize, good: CbGood, bad: Option<CbBad>, fail_at: Option<usize>) -> CbCtx {
        CbCtx {
            magic: CB_MAGIC,
            d,
            good,
            bad,
            fail_at,
            calls: 0,
            triggered: None,
            violation: None,
        }
    }

    fn reset(&mut self) {
        self.calls = 0;
        self.triggered = None;
        self.violation = None;
    }

    /// The call index, and whether to misbehave now.
    fn enter(&mut self, x: &[f64]) -> bool {
        let k = self.calls;
        self.calls += 1;
        if self.violation.is_none() {
            if let Err(e) = check_unit(x, 1e-12) {
                self.violation = Some(format!("call {k}: x = {x:?}: {e}"));
            }
        }
        let now = self.bad.is_some() && self.fail_at.is_none_or(|j| j == k);
        if now && self.triggered.is_none() {
            self.triggered = Some(k);
        }
        now
    }
}

fn compose(x: &[f64], u: &[f64]) -> Vec<f64> {
    if x.len() == 2 {
        vec![x[0] * u[0] - x[1] * u[1], x[0] * u[1] + x[1] * u[0]]
    } else {
        vec![
            x[0] * u[0] - x[1] * u[1] - x[2] * u[2] - x[3] * u[3],
            x[0] * u[1] + x[1] * u[0] + x[2] * u[3] - x[3] * u[2],
            x[0] * u[2] - x[1] * u[3] + x[2] * u[0] + x[3] * u[1],
            x[0] * u[3] + x[1] * u[2] - x[2] * u[1] + x[3] * u[0],
        ]
    }
}

/// `bingham_transition_fn` driven by a `CbCtx`. Must not panic (it is called through C).
unsafe extern "C" fn fuzz_transition(
    x_in: *const f64,
    x_out: *mut f64,
    user: *mut c_void,
) -> c_int {
    // SAFETY: user is the CbCtx passed with this callback; x_in, x_out have d doubles each
    // (the library's contract, checked below as far as possible).
    let c = unsafe { &mut *user.cast::<CbCtx>() };
    if c.magic != CB_MAGIC {
        return 99;
    }
    let d = c.d;
    // SAFETY: as above.
    let (x, out) = unsafe {
        (
            std::slice::from_raw_parts(x_in, d),
            std::slice::from_raw_parts_mut(x_out, d),
        )
    };
    if c.violation.is_none() && !out.iter().all(|v| v.is_nan()) {
        c.violation = Some(format!("call {}: x_out = {out:?} not NaN-filled", c.calls));
    }
    let bad = c.enter(x);
    let mut y = match &c.good {
        CbGood::Rotate(u) => compose(x, u),
        CbGood::Negate => x.iter().map(|v| -v).collect(),
        CbGood::Cubic(k) => {
            let v: Vec<f64> = x.iter().map(|t| t + k * t * t * t).collect();
            let n = norm(&v);
            v.iter().map(|t| t / n).collect()
        }
        CbGood::AlmostUnit(s) => x.iter().map(|t| t * s).collect(),
        _ => x.to_vec(),
    };
    if bad {
        match c.bad {
            Some(CbBad::Rc(rc)) => return rc,
            Some(CbBad::Nan(i)) => y[i % d] = f64::NAN,
            Some(CbBad::Inf(i, s)) => y[i % d] = s * f64::INFINITY,
            Some(CbBad::Scale(s)) => y.iter_mut().for_each(|t| *t *= s),
            Some(CbBad::Zero) => y.iter_mut().for_each(|t| *t = 0.0),
            Some(CbBad::Nothing) | None => return 0,
        }
    }
    out.copy_from_slice(&y);
    0
}

/// `bingham_log_likelihood_fn` driven by a `CbCtx`. Must not panic.
unsafe extern "C" fn fuzz_log_likelihood(
    x: *const f64,
    log_l: *mut f64,
    user: *mut c_void,
) -> c_int {
    // SAFETY: user is the CbCtx passed with this callback; x has d doubles, log_l one.
    let c = unsafe { &mut *user.cast::<CbCtx>() };
    if c.magic != CB_MAGIC {
        return 99;
    }
    let d = c.d;
    // SAFETY: as above.
    let (x, out) = unsafe { (std::slice::from_raw_parts(x, d), &mut *log_l) };
    if c.violation.is_none() && !out.is_nan() {
        c.violation = Some(format!("call {}: *log_l = {out} not NaN", c.calls));
    }
    let bad = c.enter(x);
    let v = match &c.good {
        CbGood::Quadratic(p) => (0..d)
            .map(|i| (0..d).map(|j| x[i] * p[i * d + j] * x[j]).sum::<f64>())
            .sum(),
        CbGood::Constant(v) => *v,
        CbGood::Quartic(kappa, v) => {
            let c: f64 = (0..d).map(|i| v[i] * x[i]).sum();
            let s2 = 1.0 - c * c;
            -kappa * s2 * s2
        }
        _ => 0.0,
    };
    if bad {
        match c.bad {
            Some(CbBad::Rc(rc)) => return rc,
            Some(CbBad::Nan(_)) => *out = f64::NAN,
            Some(CbBad::Inf(_, s)) => *out = s * f64::INFINITY,
            Some(CbBad::Nothing) | None | Some(_) => return 0,
        }
        return 0;
    }
    *out = v;
    0
}

fn nonzero_rc(rng: &mut Rng64) -> c_int {
    match rng.below(4) {
        0 => 1,
        1 => -1,
        2 => *rng.pick(&[c_int::MIN, c_int::MAX, 42]),
        _ => (rng.next_u64() as c_int) | 1,
    }
}

fn transition_ctx(rng: &mut Rng64, d: usize) -> CbCtx {
    let good = match rng.below(6) {
        0 | 1 => CbGood::Identity,
        2 => CbGood::Rotate(rng.unit_vector(d)),
        3 => CbGood::Negate,
        4 => CbGood::Cubic(rng.range(-0.5, 0.5)),
        _ => CbGood::AlmostUnit(1.0 + rng.range(-1e-8, 1e-8)),
    };
    let bad = if rng.chance(0.5) {
        Some(match rng.below(6) {
            0 => CbBad::Rc(nonzero_rc(rng)),
            1 => CbBad::Nan(rng.below(4)),
            2 => CbBad::Inf(rng.below(4), if rng.chance(0.5) { 1.0 } else { -1.0 }),
            3 => CbBad::Scale(match rng.below(4) {
                // beyond BINGHAM_UNIT_TOL = 1e-3
                0 => 1.0 + rng.log_uniform(-2.9, 0.0),
                1 => 1.0 - rng.log_uniform(-2.9, -0.1),
                2 => rng.log_uniform(10.0, 300.0),
                _ => rng.log_uniform(-320.0, -10.0),
            }),
            4 => CbBad::Zero,
            _ => CbBad::Nothing,
        })
    } else {
        None
    };
    let fail_at = if rng.chance(0.6) {
        Some(rng.below(25))
    } else {
        None
    };
    CbCtx::new(d, good, bad, fail_at)
}

fn likelihood_ctx(rng: &mut Rng64, d: usize) -> CbCtx {
    let good = match rng.below(6) {
        0..=2 => {
            let m = orthogonal(rng, d);
            let top = if rng.chance(0.9) { 2.5 } else { 12.0 };
            let scale = rng.log_uniform(-3.0, top);
            let w: Vec<f64> = (0..d).map(|_| -scale * rng.uniform()).collect();
            CbGood::Quadratic(congruence(&m, &w, d))
        }
        3 => CbGood::Constant(match rng.below(3) {
            0 => 0.0,
            1 => rng.range(-1e3, 1e3),
            _ => extreme(rng),
        }),
        _ => CbGood::Quartic(rng.log_uniform(-2.0, 2.0), rng.unit_vector(d)),
    };
    let bad = if rng.chance(0.5) {
        Some(match rng.below(4) {
            0 => CbBad::Rc(nonzero_rc(rng)),
            1 => CbBad::Nan(0),
            2 => CbBad::Inf(0, if rng.chance(0.5) { 1.0 } else { -1.0 }),
            _ => CbBad::Nothing,
        })
    } else {
        None
    };
    let fail_at = if rng.chance(0.6) {
        Some(rng.below(60))
    } else {
        None
    };
    CbCtx::new(d, good, bad, fail_at)
}

/// An argument fault of a nonlinear step.
#[derive(Debug, Clone, Copy, PartialEq)]
enum NlFault {
    None,
    NullHandle,
    MisalignedHandle,
    NullFn,
    /// m_w (0) or z_w (1): NULL
    NullNoise(usize),
    MisalignedNoise(usize),
    NonFiniteNoise(usize),
}

/// Runs one nonlinear sequence; returns the number of calls made.
fn nonlinear_sequence(
    seed: u64,
    verbose: bool,
    stats: &mut BTreeMap<String, u64>,
) -> Result<u64, String> {
    let mut rng = Rng64::new(seed);
    let d = if rng.chance(0.5) { 2 } else { 4 };
    let m0 = orthogonal(&mut rng, d);
    let mut z0 = if rng.chance(0.7) {
        z_moderate(&mut rng, d)
    } else {
        z_vector(&mut rng, d)
    };
    let (zmax, zmin) = z0
        .iter()
        .fold((f64::NEG_INFINITY, f64::INFINITY), |(a, b), &v| {
            (a.max(v), b.min(v))
        });
    if !(zmax - zmin).is_finite() {
        // (refused by bingham_filter_new; the sequences of the filter test cover that)
        z0 = z_moderate(&mut rng, d);
    }
    let (mut f, mut twin) = (std::ptr::null_mut(), std::ptr::null_mut());
    // SAFETY: valid buffers and out-pointers.
    let (s1, s2) = unsafe {
        (
            bingham_filter_new(d, m0.as_ptr(), z0.as_ptr(), &mut f),
            bingham_filter_new(d, m0.as_ptr(), z0.as_ptr(), &mut twin),
        )
    };
    if s1 != BINGHAM_OK || s2 != BINGHAM_OK {
        return Err(format!("bingham_filter_new: {}", last_error()));
    }
    let pool: Vec<(Vec<f64>, Vec<f64>)> = (0..2).map(|_| filter_noise(&mut rng, d)).collect();
    if verbose {
        eprintln!("d = {d}, m0 = {m0:?}, z0 = {z0:?}, noise pool {pool:?}");
    }
    let steps = 1 + rng.below(12);
    let mut calls = 0u64;
    let mut result = Ok(());
    for step in 0..steps {
        let predict = rng.chance(0.5);
        let name = if predict {
            "bingham_filter_predict_nonlinear"
        } else {
            "bingham_filter_update_nonlinear"
        };
        let mut ctx = if predict {
            transition_ctx(&mut rng, d)
        } else {
            likelihood_ctx(&mut rng, d)
        };
        let (mut mw, mut zw) = pool[rng.below(pool.len())].clone();
        let fault = match rng.below(24) {
            0 => NlFault::NullHandle,
            1 => NlFault::MisalignedHandle,
            2 => NlFault::NullFn,
            3 if predict => NlFault::NullNoise(rng.below(2)),
            4 if predict => NlFault::MisalignedNoise(rng.below(2)),
            5 if predict => NlFault::NonFiniteNoise(rng.below(2)),
            _ => NlFault::None,
        };
        if let NlFault::NonFiniteNoise(i) = fault {
            let v = if i == 0 { &mut mw } else { &mut zw };
            let j = rng.below(v.len());
            v[j] = non_finite(&mut rng);
        }
        let mut mwb = Buf::from(&mw);
        let mut zwb = Buf::from(&zw);
        let mut mp = mwb.ptr() as *const f64;
        let mut zp = zwb.ptr() as *const f64;
        match fault {
            NlFault::NullNoise(0) => mp = std::ptr::null(),
            NlFault::NullNoise(_) => zp = std::ptr::null(),
            NlFault::MisalignedNoise(0) => mp = mwb.misaligned(3),
            NlFault::MisalignedNoise(_) => zp = zwb.misaligned(5),
            _ => {}
        }
        let fp = match fault {
            NlFault::NullHandle => std::ptr::null_mut(),
            NlFault::MisalignedHandle => f.cast::<u8>().wrapping_add(4).cast(),
            _ => f,
        };
        // Half the steps through the `_opts` forms: random valid options (a tolerance of 0 =
        // the default, or 1e-4 .. 0.1; budgets from 1 call), now and then one invalid field
        // (refused before any call); a report or NULL.
        let use_opts = rng.chance(0.5);
        let mut opts = bingham_nonlinear_options {
            tolerance: if rng.chance(0.3) {
                0.0
            } else {
                rng.log_uniform(-4.0, -1.0)
            },
            mode_tolerance: rng.log_uniform(-2.0, 0.0),
            max_calls: if rng.chance(0.3) {
                1 + rng.below(400)
            } else {
                20_000
            },
        };
        if use_opts && rng.chance(0.25) {
            // the library's defaults, as a caller starts from them
            // SAFETY: a writable bingham_nonlinear_options.
            let st = unsafe { bingham_nonlinear_options_default(&mut opts) };
            if st != BINGHAM_OK {
                result = Err(format!(
                    "step {step}: bingham_nonlinear_options_default: {}",
                    last_error()
                ));
                break;
            }
        }
        let bad_opts = use_opts && fault == NlFault::None && rng.chance(0.15);
        if bad_opts {
            match rng.below(3) {
                0 => {
                    opts.tolerance = if rng.chance(0.5) {
                        -opts.tolerance - 1e-9
                    } else {
                        non_finite(&mut rng)
                    }
                }
                1 => {
                    opts.mode_tolerance = if rng.chance(0.5) {
                        0.0
                    } else {
                        non_finite(&mut rng)
                    }
                }
                _ => opts.max_calls = 0,
            }
        }
        let want_report = use_opts && rng.chance(0.7);
        let sentinel = bingham_nonlinear_report {
            calls: 0x5a5a,
            error_estimate: -7.0,
            mode_error_estimate: -7.0,
            method: -7,
            samples: 0x5a5a,
            effective_share: -7.0,
        };
        let mut report = sentinel;
        let report_ptr: *mut bingham_nonlinear_report = if want_report {
            &mut report
        } else {
            std::ptr::null_mut()
        };
        let opts_ptr: *const bingham_nonlinear_options = &opts;
        let name = match (use_opts, predict) {
            (true, true) => "bingham_filter_predict_nonlinear_opts",
            (true, false) => "bingham_filter_update_nonlinear_opts",
            _ => name,
        };
        let before = state_bits(f, d);
        prime_last_error(name);
        if verbose {
            eprintln!("step {step}: {name} {fault:?} {ctx:?} opts {use_opts} {opts:?}");
        }
        let user = (&mut ctx as *mut CbCtx).cast::<c_void>();
        // SAFETY: f is live (or NULL / misaligned: refused); the callbacks match the contract;
        // noise buffers of d*d and d doubles, or NULL / misaligned (refused).
        let st = unsafe {
            if predict {
                let cb: bingham_transition_fn = if fault == NlFault::NullFn {
                    None
                } else {
                    Some(fuzz_transition)
                };
                if use_opts {
                    bingham_filter_predict_nonlinear_opts(
                        fp, cb, user, mp, zp, opts_ptr, report_ptr,
                    )
                } else {
                    bingham_filter_predict_nonlinear(fp, cb, user, mp, zp)
                }
            } else {
                let cb: bingham_log_likelihood_fn = if fault == NlFault::NullFn {
                    None
                } else {
                    Some(fuzz_log_likelihood)
                };
                if use_opts {
                    bingham_filter_update_nonlinear_opts(fp, cb, user, opts_ptr, report_ptr)
                } else {
                    bingham_filter_update_nonlinear(fp, cb, user)
                }
            }
        };
        calls += 1;
        *stats
            .entry(format!(
                "{}:{}",
                if predict { "predict" } else { "update" },
                status_name(st)
            ))
            .or_default() += 1;
        if verbose {
            eprintln!(
                "    -> {} after {} callback calls (triggered {:?}) {}",
                status_name(st),
                ctx.calls,
                ctx.triggered,
                if st == BINGHAM_OK {
                    String::new()
                } else {
                    last_error()
                }
            );
        }
        let ctx_desc = format!("step {step} {name} {fault:?} {ctx:?}");
        let fail = |msg: String| Err(format!("{ctx_desc}: {msg}"));
        let code = status_code(st);
        if !(0..=7).contains(&code) || st == BINGHAM_ERR_PANIC {
            result = fail(format!("status {code}: {}", last_error()));
            break;
        }
        if mwb
            .values()
            .iter()
            .zip(&mw)
            .any(|(a, b)| a.to_bits() != b.to_bits())
            || zwb
                .values()
                .iter()
                .zip(&zw)
                .any(|(a, b)| a.to_bits() != b.to_bits())
            || !mwb.guards_ok()
            || !zwb.guards_ok()
        {
            result = fail("the noise was modified".into());
            break;
        }
        if let Some(v) = &ctx.violation {
            result = fail(format!("callback contract violated by the library: {v}"));
            break;
        }
        let budget = if use_opts { opts.max_calls } else { 20_000 };
        if ctx.calls > budget {
            result = fail(format!(
                "{} callback calls beyond the budget of {budget}",
                ctx.calls
            ));
            break;
        }
        if want_report && st != BINGHAM_OK && format!("{report:?}") != format!("{sentinel:?}") {
            result = fail(format!("{} but the report was written", status_name(st)));
            break;
        }
        if want_report && st == BINGHAM_OK {
            let tol = match (opts.tolerance, predict) {
                (t, _) if t > 0.0 => t,
                (_, true) => BINGHAM_NONLINEAR_PREDICT_TOLERANCE,
                (_, false) => BINGHAM_NONLINEAR_UPDATE_TOLERANCE,
            };
            let ok = report.calls == ctx.calls
                && report.error_estimate <= tol
                && (report.method == BINGHAM_NONLINEAR_DETERMINISTIC
                    || report.method == BINGHAM_NONLINEAR_SAMPLED)
                && report.effective_share > 0.0
                && report.effective_share <= 1.0
                && (predict || report.mode_error_estimate <= opts.mode_tolerance);
            if !ok {
                result = fail(format!(
                    "report {report:?} inconsistent with {} calls and tolerance {tol}",
                    ctx.calls
                ));
                break;
            }
        }
        let want = match fault {
            NlFault::None if bad_opts => Some(BINGHAM_ERR_INVALID_ARGUMENT),
            NlFault::None => None,
            NlFault::NonFiniteNoise(_) => Some(BINGHAM_ERR_INVALID_ARGUMENT),
            _ => Some(BINGHAM_ERR_NULL_ARGUMENT),
        };
        if let Some(w) = want {
            if st != w || ctx.calls != 0 {
                result = fail(format!(
                    "{} after {} callback calls instead of {} before any",
                    status_name(st),
                    ctx.calls,
                    status_name(w)
                ));
                break;
            }
        } else if let Some(k) = ctx.triggered {
            if st != BINGHAM_ERR_CALLBACK || ctx.calls != k + 1 {
                result = fail(format!(
                    "the callback misbehaved at call {k}: {} after {} calls ({})",
                    status_name(st),
                    ctx.calls,
                    last_error()
                ));
                break;
            }
        } else if !matches!(
            st,
            BINGHAM_OK | BINGHAM_ERR_NOT_CONVERGED | BINGHAM_ERR_NUMERICAL
        ) {
            result = fail(format!("valid call refused: {}", last_error()));
            break;
        }
        let after = state_bits(f, d);
        if st != BINGHAM_OK {
            if after != before {
                result = fail(format!("{} but the state changed", status_name(st)));
                break;
            }
            if let Err(e) = check_error_message(name) {
                result = fail(e);
                break;
            }
        } else {
            let (m, z) = filter_state(f, d);
            if let Err(e) = check_state(&m, &z, d) {
                result = fail(format!("state invalid after success: {e}"));
                break;
            }
            // the twin repeats the successful call
            ctx.reset();
            let user = (&mut ctx as *mut CbCtx).cast::<c_void>();
            // SAFETY: as above, with valid arguments.
            let twin_opts: *const bingham_nonlinear_options =
                if use_opts { opts_ptr } else { std::ptr::null() };
            let st2 = unsafe {
                if predict {
                    bingham_filter_predict_nonlinear_opts(
                        twin,
                        Some(fuzz_transition),
                        user,
                        mw.as_ptr(),
                        zw.as_ptr(),
                        twin_opts,
                        std::ptr::null_mut(),
                    )
                } else {
                    bingham_filter_update_nonlinear_opts(
                        twin,
                        Some(fuzz_log_likelihood),
                        user,
                        twin_opts,
                        std::ptr::null_mut(),
                    )
                }
            };
            if st2 != BINGHAM_OK {
                result = fail(format!("twin failed: {}", last_error()));
                break;
            }
        }
        if state_bits(twin, d) != state_bits(f, d) {
            result = fail(
                "the twin (which saw only the successful calls) differs: a failed call changed hidden state"
                    .into(),
            );
            break;
        }
        // now and then a linear step on both, to move the state and exercise the caches
        if rng.chance(0.3) {
            let (pm, pz) = &pool[rng.below(pool.len())];
            // SAFETY: live handles, valid noise buffers.
            let (a, b) = unsafe {
                (
                    bingham_filter_predict(f, pm.as_ptr(), pz.as_ptr()),
                    bingham_filter_predict(twin, pm.as_ptr(), pz.as_ptr()),
                )
            };
            if a != b {
                result = fail("linear predict differs between filter and twin".into());
                break;
            }
        }
    }
    // SAFETY: live handles, freed once.
    unsafe {
        bingham_filter_free(f);
        bingham_filter_free(twin);
    }
    result.map(|()| calls)
}

#[test]
fn fuzz_filter_nonlinear() {
    let mut stats: BTreeMap<String, u64> = BTreeMap::new();
    run_sequences(
        "bingham_filter_nonlinear",
        "filter_nonlinear",
        52,
        cases_for(4.0, 10.0, SHARE_NONLINEAR),
        |seed, verbose| nonlinear_sequence(seed, verbose, &mut stats),
    );
    if stats_wanted() {
        eprintln!("bingham_filter_nonlinear statuses: {stats:?}");
    }
}
