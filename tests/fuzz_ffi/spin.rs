//! The spin filter (`bingham_spin_filter_*`): random call sequences.
//!
//! One case is one sequence: a spin filter created with random, sometimes hostile, priors
//! (uniform orientation and spin priors `z = 0` included; NaN/Inf, non-orthogonal `M`, NULL and
//! misaligned pointers, concentrations from ±1e300 to −1e-300), and a twin created alike that
//! receives only the calls that succeeded on the first. The calls: `step` (control `u` and
//! observation `y` each present or NULL; without `y` the observation noise is not read, so it is
//! passed as NULL, as a dangling pointer or as garbage and must be ignored), `log_likelihood`,
//! `set_state`, `get_state`, the two modes, the spreads and `clone`, with noises drawn like the
//! filter's (identity or rotated mode, |z| from 1e-3 to 1e300, uniform) and one argument at a
//! time made NULL, misaligned, non-finite or otherwise bad (non-unit, non-orthogonal, extreme).
//!
//! After every call: the status is the one the header prescribes where the arguments decide it
//! (NULL / misaligned → `NULL_ARGUMENT`, NaN/Inf → `INVALID_ARGUMENT`; never `PANIC`), valid
//! arguments fail only with `NOT_CONVERGED` / `NUMERICAL`; on error the state (both marginals,
//! read with get_state) is bit-for-bit unchanged, no output is written and the message names the
//! function; on success both marginals are valid Bingham parameters, read-only calls leave the
//! state as it was, get_state / the modes / the spreads agree with the state; and the twin stays
//! bit-identical, which shows that a failed call also left the hidden state (warm starts, noise
//! caches) as it was.

use std::collections::BTreeMap;

use bingham::ffi::bingham_status::*;
use bingham::ffi::*;
use testkit::fuzz::{
    check_state, dangling, identity, non_finite, orthogonal, z_moderate, z_vector, Buf,
};
use testkit::{norm, Rng64};

use crate::case::spoil;
use crate::drivers::{cases_for, run_sequences, stats_wanted, SHARE_SPIN};
use crate::filter::filter_noise;
use crate::kinds::Kind::{self, *};
use crate::status::{check_error_message, last_error, prime_last_error, status_name};

fn handle_sentinel() -> *mut bingham_spin_filter {
    0xDEAD_BEE0usize as *mut bingham_spin_filter
}

/// Both marginals `(m_x, z_x, m_v, z_v)`.
fn spin_state(f: *const bingham_spin_filter) -> [Vec<f64>; 4] {
    let mut s = [vec![0.0; 16], vec![0.0; 4], vec![0.0; 16], vec![0.0; 4]];
    let [mx, zx, mv, zv] = &mut s;
    // SAFETY: f is a live handle; buffers of the documented lengths.
    let st = unsafe {
        bingham_spin_filter_get_state(
            f,
            mx.as_mut_ptr(),
            zx.as_mut_ptr(),
            mv.as_mut_ptr(),
            zv.as_mut_ptr(),
        )
    };
    assert_eq!(st, BINGHAM_OK, "get_state: {}", last_error());
    s
}

fn state_bits(f: *const bingham_spin_filter) -> Vec<u64> {
    spin_state(f).concat().iter().map(|v| v.to_bits()).collect()
}

fn check_spin_state(f: *const bingham_spin_filter) -> Result<(), String> {
    let [mx, zx, mv, zv] = spin_state(f);
    check_state(&mx, &zx, 4).map_err(|e| format!("orientation marginal: {e}"))?;
    check_state(&mv, &zv, 4).map_err(|e| format!("spin marginal: {e}"))
}

/// What the next call does to one of its pointer arguments (inputs first, then outputs).
#[derive(Debug, Clone, PartialEq)]
enum Attack {
    None,
    NullHandle,
    MisalignedHandle,
    Null(usize),
    Misaligned(usize),
    NonFinite(usize),
    /// finite but not acceptable (non-unit, non-orthogonal) or extreme
    Bad(usize),
}

/// How an input is passed besides the attack: its buffer, NULL (an absent optional `u` / `y`),
/// or a dangling pointer (an input that must not be read).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Pass {
    Buffer,
    Null,
    Dangling,
}

struct Args {
    arrays: Vec<Vec<f64>>,
    kinds: Vec<Kind>,
    /// NULL is a valid value (`u`, `y` of a step)
    optional: Vec<bool>,
    pass: Vec<Pass>,
    attack: Attack,
    desc: String,
}

impl Args {
    fn new(arrays: Vec<(Vec<f64>, Kind, bool)>) -> Args {
        let n = arrays.len();
        let (mut a, mut k, mut o) = (vec![], vec![], vec![]);
        for (v, kind, opt) in arrays {
            a.push(v);
            k.push(kind);
            o.push(opt);
        }
        Args {
            arrays: a,
            kinds: k,
            optional: o,
            pass: vec![Pass::Buffer; n],
            attack: Attack::None,
            desc: String::new(),
        }
    }
}

const SPIN_OPS: [&str; 8] = [
    "bingham_spin_filter_step",
    "bingham_spin_filter_log_likelihood",
    "bingham_spin_filter_set_state",
    "bingham_spin_filter_get_state",
    "bingham_spin_filter_orientation_mode",
    "bingham_spin_filter_spin_mode",
    "bingham_spin_filter_angular_spread",
    "bingham_spin_filter_clone",
];

/// The output buffers of each operation (the clone's handle output is separate).
fn out_lens(op: usize) -> &'static [usize] {
    match op {
        1 => &[1],
        3 => &[16, 4, 16, 4],
        4 | 5 => &[4],
        6 => &[4, 4],
        _ => &[],
    }
}

fn read_only(op: usize) -> bool {
    op == 1 || op >= 3
}

/// Whether input `i` of `op` is not read: the observation noise of a step without `y`.
fn ignored(op: usize, a: &Args, i: usize) -> bool {
    let y_null = op == 0 && (a.pass[3] == Pass::Null || a.attack == Attack::Null(3));
    y_null && (i == 4 || i == 5)
}

/// The status the header prescribes for these arguments, if they decide it.
fn prescribed(op: usize, a: &Args) -> Option<bingham_status> {
    let n_in = a.arrays.len();
    match a.attack {
        Attack::NullHandle | Attack::MisalignedHandle => Some(BINGHAM_ERR_NULL_ARGUMENT),
        Attack::Null(i) if i < n_in && (a.optional[i] || ignored(op, a, i)) => None,
        Attack::Misaligned(i) if i < n_in && ignored(op, a, i) => None,
        Attack::Null(_) | Attack::Misaligned(_) => Some(BINGHAM_ERR_NULL_ARGUMENT),
        Attack::NonFinite(i) if ignored(op, a, i) => None,
        Attack::NonFinite(_) => Some(BINGHAM_ERR_INVALID_ARGUMENT),
        _ => None,
    }
}

/// The arguments are valid (the attack, if any, hits nothing that is read, or is a NULL that
/// means "absent").
fn valid_args(op: usize, a: &Args) -> bool {
    match a.attack {
        Attack::None => true,
        Attack::Null(i) if i < a.arrays.len() && a.optional[i] => true,
        Attack::Null(i) | Attack::Misaligned(i) | Attack::NonFinite(i) | Attack::Bad(i) => {
            ignored(op, a, i)
        }
        _ => false,
    }
}

fn spoil_args(rng: &mut Rng64, a: &mut Args, n_out: usize) {
    let k = a.arrays.len();
    let r = rng.uniform();
    a.attack = if r < 0.62 || k + n_out == 0 {
        Attack::None
    } else if r < 0.66 {
        Attack::NullHandle
    } else if r < 0.68 {
        Attack::MisalignedHandle
    } else if r < 0.76 {
        Attack::Null(rng.below(k + n_out))
    } else if r < 0.80 {
        Attack::Misaligned(rng.below(k + n_out))
    } else if r < 0.90 && k > 0 {
        let i = rng.below(k);
        let j = rng.below(a.arrays[i].len());
        a.arrays[i][j] = non_finite(rng);
        Attack::NonFinite(i)
    } else if k > 0 {
        let i = rng.below(k);
        let what = spoil(rng, a.kinds[i], &mut a.arrays[i], 4);
        a.desc = format!("{} spoiled: {what}", a.desc);
        Attack::Bad(i)
    } else {
        Attack::None
    };
}

/// Calls operation `op` on `f`; returns the status. Inputs are checked to be unchanged.
///
/// # Safety
/// `f` is a live handle; the arrays have the documented lengths.
unsafe fn spin_call(
    op: usize,
    f: *mut bingham_spin_filter,
    a: &Args,
    outs: &mut [Buf],
    out_handle: &mut [*mut bingham_spin_filter; 1],
) -> bingham_status {
    let mut bufs: Vec<Buf> = a.arrays.iter().map(|v| Buf::from(v)).collect();
    let n_in = bufs.len();
    let mut p: Vec<*const f64> = bufs
        .iter_mut()
        .zip(&a.pass)
        .map(|(b, pass)| match pass {
            Pass::Buffer => b.ptr() as *const f64,
            Pass::Null => std::ptr::null(),
            Pass::Dangling => dangling() as *const f64,
        })
        .collect();
    let mut o: Vec<*mut f64> = outs.iter_mut().map(|b| b.ptr()).collect();
    let mut hp = out_handle.as_mut_ptr();
    let mut fp = f;
    match a.attack {
        Attack::NullHandle => fp = std::ptr::null_mut(),
        Attack::MisalignedHandle => fp = f.cast::<u8>().wrapping_add(4).cast(),
        Attack::Null(i) if i < n_in => p[i] = std::ptr::null(),
        Attack::Misaligned(i) if i < n_in => p[i] = bufs[i].misaligned(1 + i % 7),
        Attack::Null(_) if op == 7 => hp = std::ptr::null_mut(),
        Attack::Misaligned(_) if op == 7 => hp = hp.cast::<u8>().wrapping_add(2).cast(),
        Attack::Null(i) if i - n_in < o.len() => o[i - n_in] = std::ptr::null_mut(),
        Attack::Misaligned(i) if i - n_in < o.len() => o[i - n_in] = outs[i - n_in].misaligned(3),
        _ => {}
    }
    // SAFETY: forwarded; pointers are valid buffers of the documented lengths, NULL, misaligned,
    // dangling (never read) or the handle.
    let st = unsafe {
        match op {
            0 => bingham_spin_filter_step(fp, p[0], p[1], p[2], p[3], p[4], p[5]),
            1 => bingham_spin_filter_log_likelihood(fp, p[0], p[1], p[2], o[0]),
            2 => bingham_spin_filter_set_state(fp, p[0], p[1], p[2], p[3]),
            3 => bingham_spin_filter_get_state(fp, o[0], o[1], o[2], o[3]),
            4 => bingham_spin_filter_orientation_mode(fp, o[0]),
            5 => bingham_spin_filter_spin_mode(fp, o[0]),
            6 => bingham_spin_filter_angular_spread(fp, o[0], o[1]),
            7 => bingham_spin_filter_clone(fp, hp),
            _ => unreachable!(),
        }
    };
    for (i, b) in bufs.iter().enumerate() {
        assert!(
            b.values()
                .iter()
                .zip(&a.arrays[i])
                .all(|(x, y)| x.to_bits() == y.to_bits())
                && b.guards_ok(),
            "spin op {op}: input {i} was modified"
        );
    }
    st
}

/// Concentrations of a prior: moderate, any (hostile included), or uniform (all zero).
fn prior_z(rng: &mut Rng64) -> Vec<f64> {
    match rng.below(10) {
        0..=1 => vec![0.0; 4],
        2..=5 => z_moderate(rng, 4),
        _ => z_vector(rng, 4),
    }
}

fn prior_m(rng: &mut Rng64) -> Vec<f64> {
    if rng.chance(0.3) {
        identity(4)
    } else {
        orthogonal(rng, 4)
    }
}

/// An observation relative to the current orientation: its mode, the antipode, near it, or
/// random.
fn observation(rng: &mut Rng64, mx: &[f64]) -> Vec<f64> {
    let mode: Vec<f64> = (0..4).map(|r| mx[r * 4 + 3]).collect();
    match rng.below(5) {
        0 => mode,
        1 => mode.iter().map(|v| -v).collect(),
        2 => {
            let s = rng.log_uniform(-8.0, 0.0);
            let v: Vec<f64> = mode.iter().map(|x| x + s * rng.normal()).collect();
            let n = norm(&v);
            v.iter().map(|x| x / n).collect()
        }
        _ => rng.unit_vector(4),
    }
}

/// A control: near the identity or random.
fn control(rng: &mut Rng64) -> Vec<f64> {
    if rng.chance(0.5) {
        let v: Vec<f64> = (0..4)
            .map(|i| if i == 0 { 1.0 } else { 0.1 * rng.normal() })
            .collect();
        let n = norm(&v);
        v.iter().map(|x| x / n).collect()
    } else {
        rng.unit_vector(4)
    }
}

/// Creates the filter (possibly with hostile arguments) and its twin.
fn create(
    rng: &mut Rng64,
    verbose: bool,
    stats: &mut BTreeMap<String, u64>,
) -> Result<(*mut bingham_spin_filter, *mut bingham_spin_filter), String> {
    let name = "bingham_spin_filter_new";
    let mut a = Args::new(vec![
        (prior_m(rng), M, false),
        (prior_z(rng), Z, false),
        (prior_m(rng), M, false),
        (prior_z(rng), Z, false),
    ]);
    if rng.chance(0.4) {
        spoil_args(rng, &mut a, 1);
        if matches!(a.attack, Attack::NullHandle | Attack::MisalignedHandle) {
            // no handle argument: aim at `out` instead
            a.attack = if a.attack == Attack::NullHandle {
                Attack::Null(4)
            } else {
                Attack::Misaligned(4)
            };
        }
    }
    let mut bufs: Vec<Buf> = a.arrays.iter().map(|v| Buf::from(v)).collect();
    let mut p: Vec<*const f64> = bufs.iter_mut().map(|b| b.ptr() as *const f64).collect();
    let mut out = [handle_sentinel()];
    let mut op = out.as_mut_ptr();
    match a.attack {
        Attack::Null(4) => op = std::ptr::null_mut(),
        Attack::Misaligned(4) => op = op.cast::<u8>().wrapping_add(1).cast(),
        Attack::Null(i) => p[i] = std::ptr::null(),
        Attack::Misaligned(i) => p[i] = bufs[i].misaligned(1 + i),
        _ => {}
    }
    prime_last_error(name);
    // SAFETY: buffers of lengths 16, 4, 16, 4, or NULL / misaligned pointers.
    let st = unsafe { bingham_spin_filter_new(p[0], p[1], p[2], p[3], op) };
    *stats.entry(format!("new:{}", status_name(st))).or_default() += 1;
    if verbose {
        eprintln!(
            "new({:?}, attack {:?} {}) -> {}",
            a.arrays,
            a.attack,
            a.desc,
            status_name(st)
        );
    }
    if st == BINGHAM_ERR_PANIC {
        return Err(format!("{name} panicked: {}", last_error()));
    }
    let want = match a.attack {
        Attack::Null(_) | Attack::Misaligned(_) => Some(BINGHAM_ERR_NULL_ARGUMENT),
        Attack::NonFinite(_) => Some(BINGHAM_ERR_INVALID_ARGUMENT),
        _ => None,
    };
    if want.is_some_and(|w| w != st) {
        return Err(format!(
            "{name} (attack {:?}): status {} instead of {}",
            a.attack,
            status_name(st),
            status_name(want.unwrap())
        ));
    }
    let arrays = if st != BINGHAM_OK {
        if out[0] != handle_sentinel() {
            return Err(format!("{name} wrote *out on error"));
        }
        check_error_message(name)?;
        let arrays = vec![
            prior_m(rng),
            z_moderate(rng, 4),
            prior_m(rng),
            z_moderate(rng, 4),
        ];
        // SAFETY: valid buffers.
        let st = unsafe {
            bingham_spin_filter_new(
                arrays[0].as_ptr(),
                arrays[1].as_ptr(),
                arrays[2].as_ptr(),
                arrays[3].as_ptr(),
                out.as_mut_ptr(),
            )
        };
        if st != BINGHAM_OK {
            return Err(format!("{name} with valid parameters: {}", last_error()));
        }
        arrays
    } else {
        a.arrays
    };
    let mut twin = std::ptr::null_mut();
    // SAFETY: the same (accepted) parameters.
    let st = unsafe {
        bingham_spin_filter_new(
            arrays[0].as_ptr(),
            arrays[1].as_ptr(),
            arrays[2].as_ptr(),
            arrays[3].as_ptr(),
            &mut twin,
        )
    };
    if st != BINGHAM_OK {
        return Err(format!("twin creation failed: {}", last_error()));
    }
    check_spin_state(out[0]).map_err(|e| format!("new: {e}"))?;
    Ok((out[0], twin))
}

/// Runs one random sequence; returns the number of calls made.
fn spin_sequence(
    seed: u64,
    verbose: bool,
    stats: &mut BTreeMap<String, u64>,
) -> Result<u64, String> {
    let mut rng = Rng64::new(seed);
    let (mut f, twin) = create(&mut rng, verbose, stats)?;
    let mut calls = 1u64;
    // noises reused during the sequence (exercising the caches) and fresh ones
    let pool: Vec<(Vec<f64>, Vec<f64>)> = (0..3).map(|_| filter_noise(&mut rng, 4)).collect();
    let steps = 1 + rng.below(30);
    let mut result = Ok(());
    for step in 0..steps {
        let op = match rng.below(20) {
            0..=8 => 0,
            9..=11 => 1,
            12 => 2,
            13 => 3,
            14 => 4,
            15 => 5,
            16..=17 => 6,
            _ => 7,
        };
        let name = SPIN_OPS[op];
        let [mx, ..] = spin_state(f);
        let noise = |rng: &mut Rng64| {
            if rng.chance(0.8) {
                pool[rng.below(pool.len())].clone()
            } else {
                filter_noise(rng, 4)
            }
        };
        let mut a = match op {
            0 => {
                let (mw, zw) = noise(&mut rng);
                let (mo, zo) = noise(&mut rng);
                let mut a = Args::new(vec![
                    (control(&mut rng), U, true),
                    (mw, M, false),
                    (zw, Z, false),
                    (observation(&mut rng, &mx), U, true),
                    (mo, M, false),
                    (zo, Z, false),
                ]);
                if rng.chance(0.3) {
                    a.pass[0] = Pass::Null;
                }
                if rng.chance(0.3) {
                    // no observation: the noise is not read (NULL, dangling, or garbage)
                    a.pass[3] = Pass::Null;
                    for i in [4, 5] {
                        match rng.below(4) {
                            0 => a.pass[i] = Pass::Null,
                            1 => a.pass[i] = Pass::Dangling,
                            2 => a.arrays[i].iter_mut().for_each(|v| *v = f64::NAN),
                            _ => {}
                        }
                    }
                }
                a
            }
            1 => {
                let (mo, zo) = noise(&mut rng);
                Args::new(vec![
                    (observation(&mut rng, &mx), U, false),
                    (mo, M, false),
                    (zo, Z, false),
                ])
            }
            2 => Args::new(vec![
                (prior_m(&mut rng), M, false),
                (prior_z(&mut rng), Z, false),
                (prior_m(&mut rng), M, false),
                (prior_z(&mut rng), Z, false),
            ]),
            _ => Args::new(vec![]),
        };
        let n_out = out_lens(op).len() + usize::from(op == 7);
        spoil_args(&mut rng, &mut a, n_out);
        // an attack on an input passed as NULL / dangling: aim it at the handle instead
        if let Attack::Null(i) | Attack::Misaligned(i) | Attack::NonFinite(i) | Attack::Bad(i) =
            a.attack
        {
            if i < a.pass.len() && a.pass[i] != Pass::Buffer {
                a.attack = Attack::NullHandle;
            }
        }
        let mut outs: Vec<Buf> = out_lens(op).iter().map(|&n| Buf::sentinel(n)).collect();
        let mut out_handle = [handle_sentinel()];
        let before = state_bits(f);
        prime_last_error(name);
        if verbose {
            eprintln!(
                "step {step}: {name} {:?} pass {:?} attack {:?} {}",
                a.arrays, a.pass, a.attack, a.desc
            );
        }
        // SAFETY: f is live; arrays of the documented lengths.
        let st = unsafe { spin_call(op, f, &a, &mut outs, &mut out_handle) };
        calls += 1;
        *stats
            .entry(format!(
                "{}:{}",
                name.trim_start_matches("bingham_spin_filter_"),
                status_name(st)
            ))
            .or_default() += 1;
        if verbose {
            eprintln!("    -> {}", status_name(st));
        }
        let ctx = format!(
            "step {step} {name} (pass {:?}, attack {:?} {})",
            a.pass, a.attack, a.desc
        );
        let fail = |msg: String| Err(format!("{ctx}: {msg}"));
        if st == BINGHAM_ERR_PANIC {
            result = fail(format!("panic: {}", last_error()));
            break;
        }
        if let Some(w) = prescribed(op, &a) {
            if st != w {
                result = fail(format!(
                    "status {} instead of {} ({})",
                    status_name(st),
                    status_name(w),
                    if st == BINGHAM_OK {
                        String::new()
                    } else {
                        last_error()
                    }
                ));
                break;
            }
        }
        let after = state_bits(f);
        if st != BINGHAM_OK {
            if after != before {
                result = fail(format!(
                    "failed with {} but changed the state",
                    status_name(st)
                ));
                break;
            }
            if outs.iter().any(|b| !b.untouched()) || out_handle[0] != handle_sentinel() {
                result = fail(format!(
                    "failed with {} but wrote an output",
                    status_name(st)
                ));
                break;
            }
            if let Err(e) = check_error_message(name) {
                result = fail(e);
                break;
            }
            if valid_args(op, &a)
                && op != 2
                && st != BINGHAM_ERR_NOT_CONVERGED
                && st != BINGHAM_ERR_NUMERICAL
            {
                result = fail(format!("valid arguments refused: {}", last_error()));
                break;
            }
        } else {
            if read_only(op) && after != before {
                result = fail("a read-only call changed the state".into());
                break;
            }
            if let Err(e) = check_spin_state(f) {
                result = fail(format!("state invalid after success: {e}"));
                break;
            }
            if outs.iter().any(|b| !b.guards_ok() || !b.fully_written()) {
                result = fail("an output was not fully written, or beyond its end".into());
                break;
            }
            let vals: Vec<Vec<f64>> = outs.iter().map(Buf::values).collect();
            let [mx, _, mv, _] = spin_state(f);
            let col = |m: &[f64]| (0..4).map(|r| m[r * 4 + 3].to_bits()).collect::<Vec<_>>();
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            let bad = match op {
                1 => (!vals[0][0].is_finite()).then(|| format!("log-likelihood {}", vals[0][0])),
                3 => (bits(&vals.concat()) != after)
                    .then(|| "get_state output differs from the state".to_string()),
                4 => (bits(&vals[0]) != col(&mx))
                    .then(|| format!("orientation mode {:?} is not M_x's last column", vals[0])),
                5 => (bits(&vals[0]) != col(&mv))
                    .then(|| format!("spin mode {:?} is not M_v's last column", vals[0])),
                6 => vals
                    .iter()
                    .find(|v| {
                        let parts: f64 = v[..3].iter().map(|x| x * x).sum();
                        v.iter().any(|x| !x.is_finite() || *x < 0.0 || *x > 2.0)
                            || (parts - v[3] * v[3]).abs() > 1e-9 * (v[3] * v[3]) + 1e-300
                    })
                    .map(|v| format!("angular spread {v:?}")),
                7 => {
                    let c = out_handle[0];
                    if c.is_null() || c == handle_sentinel() {
                        Some("clone returned no handle".to_string())
                    } else if state_bits(c) != after {
                        // SAFETY: a live handle, freed once.
                        unsafe { bingham_spin_filter_free(c) };
                        Some("clone differs from the original".to_string())
                    } else {
                        // continue with the clone half of the time (the other is freed)
                        // SAFETY: both are live handles; the one not kept is freed once.
                        unsafe {
                            if rng.chance(0.5) {
                                bingham_spin_filter_free(f);
                                f = c;
                            } else {
                                bingham_spin_filter_free(c);
                            }
                        }
                        None
                    }
                }
                _ => None,
            };
            if let Some(e) = bad {
                result = fail(e);
                break;
            }
            // the twin repeats the successful call with the same arguments
            if !read_only(op) {
                // SAFETY: twin is live.
                let st2 = unsafe { spin_call(op, twin, &a, &mut [], &mut [handle_sentinel()]) };
                if st2 != BINGHAM_OK {
                    result = fail(format!("twin failed: {}", last_error()));
                    break;
                }
            }
        }
        if state_bits(twin) != state_bits(f) {
            result = fail(
                "the twin (which saw only the successful calls) differs: a failed call changed \
                 hidden state"
                    .into(),
            );
            break;
        }
    }
    // SAFETY: live handles, freed once; free(NULL) is a no-op.
    unsafe {
        bingham_spin_filter_free(f);
        bingham_spin_filter_free(twin);
        bingham_spin_filter_free(std::ptr::null_mut());
    }
    result.map(|()| calls)
}

#[test]
fn fuzz_spin_sequences() {
    let mut stats: BTreeMap<String, u64> = BTreeMap::new();
    run_sequences(
        "bingham_spin_filter",
        "spin",
        97,
        cases_for(1.0, 1.0, SHARE_SPIN),
        |seed, verbose| spin_sequence(seed, verbose, &mut stats),
    );
    if stats_wanted() {
        eprintln!("bingham_spin_filter statuses: {stats:?}");
    }
}
