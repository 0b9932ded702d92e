//! The functions that fill a struct with defaults: `bingham_ahrs_params_default` (a period),
//! `bingham_ahrs_params_from_rate` (a rate) and `bingham_nonlinear_options_default`.
//!
//! Arguments: typical periods and rates, the bounds (1e-6 s, 1 s, 1 Hz, 1e6 Hz) and the doubles
//! next to them, 0 and −0, negative, subnormal, huge, NaN and ±Inf values; the struct pointer
//! valid, NULL or misaligned, the struct itself a sentinel-filled, guard-worded buffer. Every case
//! checks the status the header prescribes (NULL / misaligned → `NULL_ARGUMENT`; a period outside
//! 1e-6..1 s or not finite → `INVALID_ARGUMENT`), that an error writes nothing and names the
//! function (a period above 1 s asks whether a rate was passed), and that a success writes the
//! whole struct and nothing around it: finite parameters with the given `sample_time` and the
//! documented latencies, accepted by `bingham_ahrs_new`; for `bingham_ahrs_params_from_rate(hz)`
//! exactly the status and bytes of `bingham_ahrs_params_default(1.0 / hz)`; the documented
//! nonlinear defaults (tolerance 0, mode tolerance 0.05, 20000 calls).

use bingham::ffi::bingham_status::*;
use bingham::ffi::*;
use testkit::fuzz::{extreme, non_finite, Buf};
use testkit::Rng64;

use crate::drivers::{cases_for, drive};
use crate::status::{check_error_message, last_error, prime_last_error, status_code, status_name};
use crate::vectors::expect;

/// Share of `BINGHAM_FUZZ_CASES` for each of the two tests here (on top of the other shares).
const SHARE_DEFAULTS: f64 = 0.01;

/// `bingham_ahrs_params` as doubles (it holds nothing else).
fn params_words() -> usize {
    let size = std::mem::size_of::<bingham_ahrs_params>();
    assert_eq!(
        size % 8,
        0,
        "bingham_ahrs_params is not a struct of doubles"
    );
    size / 8
}

/// The doubles next to `v`.
fn neighbours(v: f64) -> [f64; 3] {
    [
        f64::from_bits(v.to_bits() - 1),
        v,
        f64::from_bits(v.to_bits() + 1),
    ]
}

/// A period (s) or a rate (Hz): typical, at or next to the bounds, or hostile.
fn period_or_rate(rng: &mut Rng64, rate: bool) -> f64 {
    let typical = *rng.pick(&[100.0, 200.0, 285.714, 400.0, 1000.0, 50.0, 1.5, 2e5]);
    match rng.below(8) {
        0 => non_finite(rng),
        1 => extreme(rng),
        2 => {
            let bound = *rng.pick(&[1e-6, 1.0, 1e6]);
            *rng.pick(&neighbours(bound))
        }
        3 => *rng.pick(&[0.0, -0.0, -0.01, -100.0, 5e-324, 1e-300, 1e300, f64::MAX]),
        4 => rng.log_uniform(-8.0, 8.0),
        _ if rate => typical,
        _ => 1.0 / typical,
    }
}

/// A NULL (Some(0)) or misaligned (Some(1..8)) struct pointer, else None.
fn struct_attack(rng: &mut Rng64) -> Option<usize> {
    rng.chance(0.1)
        .then(|| if rng.chance(0.5) { 0 } else { 1 + rng.below(7) })
}

fn ahrs_params_case(seed: u64, verbose: bool) -> Result<&'static str, String> {
    let mut rng = Rng64::new(seed);
    let from_rate = rng.chance(0.5);
    let x = period_or_rate(&mut rng, from_rate);
    let attack = struct_attack(&mut rng);
    let name = if from_rate {
        "bingham_ahrs_params_from_rate"
    } else {
        "bingham_ahrs_params_default"
    };
    if verbose {
        eprintln!("{name}({x:e}), pointer {attack:?}");
    }
    let words = params_words();
    let mut out = Buf::sentinel(words);
    let p: *mut bingham_ahrs_params = match attack {
        None => out.ptr().cast(),
        Some(0) => std::ptr::null_mut(),
        Some(k) => out.misaligned(k).cast(),
    };
    prime_last_error(name);
    // SAFETY: p is NULL, misaligned (both refused before any access) or a buffer of the
    // struct's size.
    let st = unsafe {
        if from_rate {
            bingham_ahrs_params_from_rate(x, p)
        } else {
            bingham_ahrs_params_default(x, p)
        }
    };
    let code = status_code(st);
    if !(0..=7).contains(&code) || st == BINGHAM_ERR_PANIC {
        return Err(format!("status {code}: {}", last_error()));
    }
    // the period the defaults are for; the bounds are on it (1e-6..1 s)
    let period = if from_rate { 1.0 / x } else { x };
    let valid = x.is_finite() && x > 0.0 && (1e-6..=1.0).contains(&period);
    let want = if attack.is_some() {
        BINGHAM_ERR_NULL_ARGUMENT
    } else if valid {
        BINGHAM_OK
    } else {
        BINGHAM_ERR_INVALID_ARGUMENT
    };
    expect(
        st,
        Some(want),
        &format!("{name}({x:e}), pointer {attack:?}"),
    )?;
    if st != BINGHAM_OK {
        if !out.untouched() {
            return Err(format!("{} but *p was written", status_name(st)));
        }
        check_error_message(name)?;
        let msg = last_error();
        if st == BINGHAM_ERR_INVALID_ARGUMENT {
            let names = if from_rate { "`hz`" } else { "sample_time" };
            if !msg.contains(names) {
                return Err(format!("the message does not name {names}: {msg}"));
            }
            if !from_rate && period > 1.0 && period.is_finite() && !msg.contains("rate in Hz") {
                return Err(format!("a period of {x:e} s: no hint at a rate: {msg}"));
            }
        }
    } else {
        if !out.guards_ok() || !out.fully_written() {
            return Err("the parameters were not written exactly".into());
        }
        let v = out.values();
        if let Some(bad) = v.iter().find(|v| !v.is_finite()) {
            return Err(format!("a parameter is {bad}: {v:?}"));
        }
        // SAFETY: out holds a bingham_ahrs_params (a struct of doubles).
        let params: bingham_ahrs_params = unsafe { out.ptr().cast::<bingham_ahrs_params>().read() };
        if params.sample_time.to_bits() != period.to_bits()
            || params.mag_latency != -1.0
            || params.acc_latency != 0.0
        {
            return Err(format!(
                "sample_time {:e} (expected {period:e}), mag_latency {} (−1), acc_latency {} (0)",
                params.sample_time, params.mag_latency, params.acc_latency
            ));
        }
        if rng.chance(0.2) {
            let mut a = std::ptr::null_mut();
            // SAFETY: a valid struct and out-pointer; the handle is freed below.
            let st = unsafe { bingham_ahrs_new(&params, &mut a) };
            if st != BINGHAM_OK {
                return Err(format!("bingham_ahrs_new refused them: {}", last_error()));
            }
            // SAFETY: a live handle, freed once.
            unsafe { bingham_ahrs_free(a) };
        }
    }
    if from_rate && attack.is_none() {
        // exactly bingham_ahrs_params_default(1.0 / hz)
        let mut twin = Buf::sentinel(words);
        // SAFETY: a buffer of the struct's size.
        let st2 = unsafe { bingham_ahrs_params_default(period, twin.ptr().cast()) };
        if st2 != st || twin.bits() != out.bits() {
            return Err(format!(
                "from_rate({x:e}): {}, params_default({period:e}): {} or other bytes",
                status_name(st),
                status_name(st2)
            ));
        }
    }
    Ok(status_name(st))
}

fn nonlinear_options_case(seed: u64, verbose: bool) -> Result<&'static str, String> {
    let mut rng = Rng64::new(seed);
    let attack = struct_attack(&mut rng);
    if verbose {
        eprintln!("pointer {attack:?}");
    }
    let size = std::mem::size_of::<bingham_nonlinear_options>();
    assert_eq!(
        size, 24,
        "bingham_nonlinear_options: two doubles and a size_t"
    );
    let mut out = Buf::sentinel(3);
    let p: *mut bingham_nonlinear_options = match attack {
        None => out.ptr().cast(),
        Some(0) => std::ptr::null_mut(),
        Some(k) => out.misaligned(k).cast(),
    };
    let name = "bingham_nonlinear_options_default";
    prime_last_error(name);
    // SAFETY: NULL, misaligned (refused before any access) or 24 writable bytes.
    let st = unsafe { bingham_nonlinear_options_default(p) };
    let want = if attack.is_some() {
        BINGHAM_ERR_NULL_ARGUMENT
    } else {
        BINGHAM_OK
    };
    expect(st, Some(want), &format!("pointer {attack:?}"))?;
    if st != BINGHAM_OK {
        if !out.untouched() {
            return Err(format!("{} but *opts was written", status_name(st)));
        }
        check_error_message(name)?;
        return Ok(status_name(st));
    }
    if !out.guards_ok() || !out.fully_written() {
        return Err("the options were not written exactly".into());
    }
    // SAFETY: out holds a bingham_nonlinear_options.
    let o = unsafe { out.ptr().cast::<bingham_nonlinear_options>().read() };
    if o.tolerance.to_bits() != 0 || o.mode_tolerance != 0.05 || o.max_calls != 20_000 {
        return Err(format!(
            "defaults {o:?}, documented: tolerance 0, mode_tolerance 0.05, max_calls 20000"
        ));
    }
    Ok(status_name(st))
}

#[test]
fn fuzz_ahrs_params() {
    let n = cases_for(1.0, 1.0, SHARE_DEFAULTS);
    drive("bingham_ahrs_params", 60, n, ahrs_params_case);
}

#[test]
fn fuzz_nonlinear_options_default() {
    let n = cases_for(1.0, 1.0, SHARE_DEFAULTS);
    drive(
        "bingham_nonlinear_options_default",
        61,
        n,
        nonlinear_options_case,
    );
}
