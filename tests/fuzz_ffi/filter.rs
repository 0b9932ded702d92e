//! The filter: random call sequences (the body-frame steps, the vector observation and the
//! world-frame steps `bingham_filter_predict_world` / `_update_world` /
//! `_log_likelihood_world`, whose `u = NULL` is the identity, not an error; the surprise
//! `bingham_filter_surprise`, finite and ≥ 0 on success; the gated update
//! `bingham_filter_update_gated`, with any `max_surprise` (0, χ² levels, huge, +Inf = no gate;
//! NaN, −Inf and negative ones refused), its `surprise` output sometimes aliasing an input (valid
//! in-place use): on success `accepted` is 1 exactly when the surprise, which equals
//! `bingham_filter_surprise` on the twin, is at most `max_surprise`, a gated-out call leaves the
//! state unchanged, and the twin, given `bingham_filter_update` only when accepted, stays
//! bit-identical).
//!
//! One case is one sequence: a filter (created with random, sometimes hostile, parameters) and a
//! "twin" created alike that receives only the calls that succeeded on the first. After every call:
//! on error the state (read with get_state) is bit-for-bit unchanged and the message names the
//! function; on success the state is a valid Bingham; and the two filters stay bit-identical, which
//! shows that a failed call also left the hidden state (warm start, noise caches) unaffected.

use std::collections::BTreeMap;

use bingham::ffi::bingham_status::*;
use bingham::ffi::*;
use testkit::fuzz::{
    check_state, dangling, extreme, identity, non_finite, orthogonal, z_moderate, z_vector, Buf,
};
use testkit::{norm, Rng64};

use crate::case::spoil;
use crate::drivers::{cases_for, run_sequences, stats_wanted, SHARE_FILTER};
use crate::kinds::Kind::*;
use crate::kinds::{kind_len, Kind};
use crate::status::{check_error_message, last_error, prime_last_error, status_name};

/// A sentinel handle value: a pointer output that must stay untouched on error.
fn handle_sentinel() -> *mut bingham_filter {
    0xDEAD_BEE0usize as *mut bingham_filter
}

/// The fill of `bingham_filter_update_gated`'s `accepted` output (and the word after it).
const ACCEPTED_SENTINEL: i32 = 0x5A5A_5A5A;

pub(crate) fn filter_state(f: *const bingham_filter, d: usize) -> (Vec<f64>, Vec<f64>) {
    let mut m = vec![0.0; d * d];
    let mut z = vec![0.0; d];
    // SAFETY: f is a live handle of dimension d; buffers of length d*d and d.
    let st = unsafe { bingham_filter_get_state(f, m.as_mut_ptr(), z.as_mut_ptr()) };
    assert_eq!(st, BINGHAM_OK, "get_state: {}", last_error());
    (m, z)
}

pub(crate) fn state_bits(f: *const bingham_filter, d: usize) -> Vec<u64> {
    let (m, z) = filter_state(f, d);
    m.iter().chain(&z).map(|v| v.to_bits()).collect()
}

/// Filter noise parameters: mostly realistic (identity or rotated mode, |z| from 1e-3 to 1e7),
/// sometimes extreme (up to 1e13 and beyond, all equal = uniform noise).
pub(crate) fn filter_noise(rng: &mut Rng64, d: usize) -> (Vec<f64>, Vec<f64>) {
    let m = if rng.chance(0.5) {
        identity(d)
    } else {
        orthogonal(rng, d)
    };
    let mut z: Vec<f64> = (0..d)
        .map(|_| match rng.below(10) {
            0 => 0.0,
            1 => -rng.log_uniform(7.0, 13.0),
            2 => -rng.log_uniform(-3.0, 0.0),
            _ => -rng.log_uniform(0.0, 7.0),
        })
        .collect();
    match rng.below(12) {
        0 => z.iter_mut().for_each(|v| *v = 0.0),
        1 => {
            let v = -rng.log_uniform(0.0, 4.0);
            z.iter_mut().for_each(|x| *x = v);
        }
        2 => {
            let i = rng.below(d);
            z[i] = -rng.log_uniform(13.0, 300.0);
        }
        _ => {}
    }
    // the mode column gets the largest z most of the time (zero-mean noise)
    if rng.chance(0.8) {
        let top = (0..d).max_by(|&a, &b| z[a].total_cmp(&z[b])).unwrap();
        z.swap(0, top);
        let mut zz = vec![0.0; d];
        // column 0 of the identity is (1, 0, …): the identity quaternion is the mode
        zz[0] = z[0];
        zz[1..].copy_from_slice(&z[1..]);
        z = zz;
    }
    (m, z)
}

/// A measurement relative to the current state: the mode, near it, antipodal, orthogonal, or
/// random.
fn filter_measurement(rng: &mut Rng64, m: &[f64], d: usize) -> Vec<f64> {
    let mode: Vec<f64> = (0..d).map(|r| m[r * d + d - 1]).collect();
    match rng.below(6) {
        0 => mode,
        1 => mode.iter().map(|v| -v).collect(),
        2 => (0..d).map(|r| m[r * d]).collect(), // orthogonal to the mode
        3 => {
            let s = rng.log_uniform(-8.0, 0.0);
            let v: Vec<f64> = mode.iter().map(|x| x + s * rng.normal()).collect();
            let n = norm(&v);
            v.iter().map(|x| x / n).collect()
        }
        _ => rng.unit_vector(d),
    }
}

/// What the next call does to one of its array arguments.
#[derive(Debug, Clone, PartialEq)]
enum FAttack {
    None,
    NullHandle,
    MisalignedHandle,
    Null(usize),
    Misaligned(usize),
    NonFinite(usize),
    /// finite but not acceptable (e.g. non-unit, non-orthogonal) or extreme
    Bad(usize),
    /// the (single double) output written into the first entry of input i: a valid call
    Alias(usize),
}

struct FArgs {
    arrays: Vec<Vec<f64>>,
    kinds: Vec<Kind>,
    attack: FAttack,
    desc: String,
}

fn spoil_filter_args(rng: &mut Rng64, a: &mut FArgs, d: usize) {
    let k = a.arrays.len();
    let r = rng.uniform();
    a.attack = if r < 0.70 || k == 0 {
        FAttack::None
    } else if r < 0.74 {
        FAttack::NullHandle
    } else if r < 0.76 {
        FAttack::MisalignedHandle
    } else if r < 0.81 {
        FAttack::Null(rng.below(k))
    } else if r < 0.84 {
        FAttack::Misaligned(rng.below(k))
    } else if r < 0.91 {
        let i = rng.below(k);
        let j = rng.below(a.arrays[i].len());
        a.arrays[i][j] = non_finite(rng);
        FAttack::NonFinite(i)
    } else {
        let i = rng.below(k);
        let kind = a.kinds[i];
        let what = match kind {
            // the scalar kappa (passed by value): negative, or finite but extreme
            One => {
                a.arrays[i][0] = if rng.chance(0.5) {
                    -rng.log_uniform(-300.0, 300.0)
                } else {
                    extreme(rng)
                };
                format!("kappa = {:e}", a.arrays[i][0])
            }
            // a 3-vector (body / reference) of any filter
            _ if a.arrays[i].len() == 3 => spoil(rng, U, &mut a.arrays[i], 3),
            _ => spoil(rng, kind, &mut a.arrays[i], d),
        };
        a.desc = format!("{} spoiled: {what}", a.desc);
        FAttack::Bad(i)
    };
    // kappa is passed by value: no pointer to make NULL or misaligned
    if let FAttack::Null(i) | FAttack::Misaligned(i) = a.attack {
        if a.kinds.get(i) == Some(&One) {
            a.attack = FAttack::None;
        }
    }
}

/// Calls one filter function on `f` with the arrays of `a` (as the attack says), sets
/// `out_*` where the function has outputs; returns the status. With an alias attack the output
/// is written into an input buffer and, on success, copied from there into `outs[0]`.
///
/// # Safety
/// `f` is a live handle of dimension `d`; array lengths match the function.
unsafe fn filter_call(
    op: usize,
    f: *mut bingham_filter,
    a: &FArgs,
    outs: &mut [Buf],
    out_ptr: &mut [*mut bingham_filter; 1],
    out_dim: &mut [usize; 2],
    out_acc: &mut [i32; 2],
) -> bingham_status {
    let mut bufs: Vec<Buf> = a.arrays.iter().map(|v| Buf::from(v)).collect();
    let mut p: Vec<*const f64> = bufs.iter_mut().map(|b| b.ptr() as *const f64).collect();
    let mut fp = f;
    let mut op_out: Vec<*mut f64> = outs.iter_mut().map(|b| b.ptr()).collect();
    let n_in = p.len();
    match a.attack {
        FAttack::NullHandle => fp = std::ptr::null_mut(),
        FAttack::MisalignedHandle => fp = f.cast::<u8>().wrapping_add(4).cast(),
        FAttack::Null(i) if i < n_in => p[i] = std::ptr::null(),
        FAttack::Null(i) if i - n_in < op_out.len() => op_out[i - n_in] = std::ptr::null_mut(),
        FAttack::Misaligned(i) if i < n_in => p[i] = bufs[i].misaligned(1 + i % 7),
        FAttack::Misaligned(i) if i - n_in < op_out.len() => {
            op_out[i - n_in] = outs[i - n_in].misaligned(3)
        }
        FAttack::Alias(i) => op_out[0] = bufs[i].ptr(),
        _ => {}
    }
    let o = |i: usize| op_out.get(i).copied().unwrap_or(std::ptr::null_mut());
    // SAFETY: forwarded; pointers are valid buffers, NULL, misaligned or the handle.
    let st = unsafe {
        match op {
            0 => bingham_filter_predict(fp, p[0], p[1]),
            1 => bingham_filter_predict_rotation(fp, p[0], p[1], p[2]),
            2 => bingham_filter_update(fp, p[0], p[1], p[2]),
            3 => bingham_filter_set_state(fp, p[0], p[1]),
            4 => bingham_filter_log_likelihood(fp, p[0], p[1], p[2], o(0)),
            9 => bingham_filter_update_vector(fp, p[0], p[1], a.arrays[2][0]),
            10 => bingham_filter_log_likelihood_vector(fp, p[0], p[1], a.arrays[2][0], o(0)),
            11 => bingham_filter_angular_spread(fp, o(0)),
            12 => bingham_filter_predict_world(fp, p[0], p[1], p[2]),
            13 => bingham_filter_update_world(fp, p[0], p[1], p[2]),
            14 => bingham_filter_log_likelihood_world(fp, p[0], p[1], p[2], o(0)),
            15 => bingham_filter_surprise(fp, p[0], p[1], p[2], o(0)),
            16 => {
                // `accepted` is the argument after `surprise`
                let acc = out_acc.as_mut_ptr();
                let ap = match a.attack {
                    FAttack::Null(i) if i == n_in + 1 => std::ptr::null_mut(),
                    FAttack::Misaligned(i) if i == n_in + 1 => {
                        acc.cast::<u8>().wrapping_add(1).cast()
                    }
                    _ => acc,
                };
                bingham_filter_update_gated(fp, p[0], p[1], p[2], a.arrays[3][0], o(0), ap)
            }
            5 => bingham_filter_get_state(fp, o(0), o(1)),
            6 => bingham_filter_mode(fp, o(0)),
            7 => {
                let dp = if matches!(a.attack, FAttack::Null(_)) {
                    std::ptr::null_mut()
                } else if matches!(a.attack, FAttack::Misaligned(_)) {
                    out_dim.as_mut_ptr().cast::<u8>().wrapping_add(3).cast()
                } else {
                    out_dim.as_mut_ptr()
                };
                bingham_filter_dim(fp, dp)
            }
            8 => {
                let op = if matches!(a.attack, FAttack::Null(_)) {
                    std::ptr::null_mut()
                } else if matches!(a.attack, FAttack::Misaligned(_)) {
                    out_ptr.as_mut_ptr().cast::<u8>().wrapping_add(2).cast()
                } else {
                    out_ptr.as_mut_ptr()
                };
                bingham_filter_clone(fp, op)
            }
            _ => unreachable!(),
        }
    };
    let aliased = match a.attack {
        FAttack::Alias(i) if st == BINGHAM_OK => Some(i),
        _ => None,
    };
    for (i, b) in bufs.iter().enumerate() {
        assert!(
            b.values()
                .iter()
                .zip(&a.arrays[i])
                .enumerate()
                .all(|(j, (x, y))| x.to_bits() == y.to_bits() || (aliased == Some(i) && j == 0))
                && b.guards_ok(),
            "filter op {op}: input {i} was modified"
        );
    }
    if let Some(i) = aliased {
        // SAFETY: outs[0] holds one double.
        unsafe { outs[0].ptr().write(bufs[i].values()[0]) };
    }
    st
}

const FILTER_OPS: [&str; 17] = [
    "bingham_filter_predict",
    "bingham_filter_predict_rotation",
    "bingham_filter_update",
    "bingham_filter_set_state",
    "bingham_filter_log_likelihood",
    "bingham_filter_get_state",
    "bingham_filter_mode",
    "bingham_filter_dim",
    "bingham_filter_clone",
    "bingham_filter_update_vector",
    "bingham_filter_log_likelihood_vector",
    "bingham_filter_angular_spread",
    "bingham_filter_predict_world",
    "bingham_filter_update_world",
    "bingham_filter_log_likelihood_world",
    "bingham_filter_surprise",
    "bingham_filter_update_gated",
];

/// The operations that must not change the state (const handle, or outputs only).
fn read_only(op: usize) -> bool {
    matches!(op, 4..=8 | 10 | 11 | 14 | 15)
}

/// The operations with output arrays or pointer outputs (which the harness may make NULL).
fn has_outputs(op: usize) -> bool {
    matches!(op, 4..=8 | 10 | 11 | 14..=16)
}

/// A `max_surprise` for `bingham_filter_update_gated`: 0, the χ² tail levels, random, huge, or
/// +Inf (no gate).
fn max_surprise(rng: &mut Rng64) -> f64 {
    match rng.below(8) {
        0 => *rng.pick(&[0.0, -0.0, 5e-324, f64::MAX, f64::INFINITY]),
        1 | 2 => *rng.pick(&[1.0, 3.0, 10.83, 16.27]),
        _ => rng.log_uniform(-3.0, 4.0),
    }
}

/// `bingham_filter_predict_world` with `u = NULL`: the identity control, a valid call.
fn null_is_identity(op: usize, attack: &FAttack) -> bool {
    op == 12 && *attack == FAttack::Null(0)
}

/// A direction (unit 3-vector) for `bingham_filter_update_vector`: random, or an axis, or a
/// tiny perturbation of one (exactly (anti)parallel pairs of body and reference included).
pub(crate) fn direction(rng: &mut Rng64) -> Vec<f64> {
    match rng.below(4) {
        0 => {
            let mut v = vec![0.0; 3];
            v[rng.below(3)] = if rng.chance(0.5) { 1.0 } else { -1.0 };
            v
        }
        1 => {
            let mut v = vec![0.0, 0.0, 1.0];
            v[0] = rng.log_uniform(-12.0, -4.0);
            let n = norm(&v);
            v.iter().map(|x| x / n).collect()
        }
        _ => rng.unit_vector(3),
    }
}

/// A concentration of a direction measurement: mostly realistic, sometimes 0 or huge.
pub(crate) fn vector_kappa(rng: &mut Rng64) -> f64 {
    match rng.below(10) {
        0 => 0.0,
        1 => rng.log_uniform(6.0, 300.0),
        2 => rng.log_uniform(-300.0, -3.0),
        _ => rng.log_uniform(-3.0, 6.0),
    }
}

/// Runs one random sequence; returns the number of calls made and their statuses.
fn filter_sequence(
    seed: u64,
    verbose: bool,
    stats: &mut BTreeMap<String, u64>,
) -> Result<u64, String> {
    let mut rng = Rng64::new(seed);
    let mut calls = 0u64;
    let count = |stats: &mut BTreeMap<String, u64>, op: &str, st: bingham_status| {
        let op = op.trim_start_matches("bingham_filter_");
        *stats
            .entry(format!("{op}:{}", status_name(st)))
            .or_default() += 1;
    };

    // --- creation, possibly hostile
    let d_try = match rng.below(20) {
        0 => *rng.pick(&[0usize, 1, 3, 5, 8, 64, 65, usize::MAX]),
        1..=9 => 2,
        _ => 4,
    };
    let dl = if (2..=64).contains(&d_try) { d_try } else { 2 };
    let mut m0 = if rng.chance(0.3) {
        identity(dl)
    } else {
        orthogonal(&mut rng, dl)
    };
    let mut z0 = if rng.chance(0.5) {
        z_moderate(&mut rng, dl)
    } else {
        z_vector(&mut rng, dl)
    };
    let mut args = FArgs {
        arrays: vec![m0.clone(), z0.clone()],
        kinds: vec![M, Z],
        attack: FAttack::None,
        desc: String::new(),
    };
    if rng.chance(0.3) {
        spoil_filter_args(&mut rng, &mut args, dl);
    }
    let mut out = [handle_sentinel()];
    {
        let mut bufs: Vec<Buf> = args.arrays.iter().map(|v| Buf::from(v)).collect();
        let mut p: Vec<*const f64> = bufs.iter_mut().map(|b| b.ptr() as *const f64).collect();
        let mut op = out.as_mut_ptr();
        let dang = !(2..=64).contains(&d_try);
        match args.attack {
            FAttack::Null(i) => p[i] = std::ptr::null(),
            FAttack::Misaligned(i) => p[i] = bufs[i].misaligned(5),
            FAttack::NullHandle => op = std::ptr::null_mut(),
            FAttack::MisalignedHandle => op = op.cast::<u8>().wrapping_add(1).cast(),
            _ => {}
        }
        if dang {
            p = vec![dangling(); 2];
        }
        prime_last_error("bingham_filter_new");
        // SAFETY: buffers of length dl*dl and dl (dl = d_try when d_try is 2 or 4; otherwise
        // the function must refuse d before reading; dangling pointers prove it).
        let st = unsafe { bingham_filter_new(d_try, p[0], p[1], op) };
        calls += 1;
        count(stats, "new", st);
        if verbose {
            eprintln!(
                "new(d = {d_try}, {:?}, attack {:?}) -> {}",
                args.arrays,
                args.attack,
                status_name(st)
            );
        }
        if st == BINGHAM_ERR_PANIC {
            return Err(format!("bingham_filter_new panicked: {}", last_error()));
        }
        let want = if d_try != 2 && d_try != 4 {
            Some(BINGHAM_ERR_INVALID_DIMENSION)
        } else {
            match args.attack {
                FAttack::Null(_)
                | FAttack::Misaligned(_)
                | FAttack::NullHandle
                | FAttack::MisalignedHandle => Some(BINGHAM_ERR_NULL_ARGUMENT),
                FAttack::NonFinite(_) => Some(BINGHAM_ERR_INVALID_ARGUMENT),
                _ => None,
            }
        };
        if let Some(w) = want {
            if st != w {
                return Err(format!(
                    "bingham_filter_new: status {} instead of {}",
                    status_name(st),
                    status_name(w)
                ));
            }
        }
        if st != BINGHAM_OK {
            if out[0] != handle_sentinel() {
                return Err("bingham_filter_new wrote *out on error".into());
            }
            check_error_message("bingham_filter_new")?;
            // retry with valid parameters so that the sequence has a filter
            let d = if rng.chance(0.5) { 2 } else { 4 };
            m0 = orthogonal(&mut rng, d);
            z0 = z_moderate(&mut rng, d);
            // SAFETY: valid buffers.
            let st = unsafe { bingham_filter_new(d, m0.as_ptr(), z0.as_ptr(), out.as_mut_ptr()) };
            if st != BINGHAM_OK {
                return Err(format!(
                    "bingham_filter_new with valid parameters: {}",
                    last_error()
                ));
            }
        } else {
            m0 = args.arrays[0].clone();
            z0 = args.arrays[1].clone();
        }
    }
    let mut f = out[0];
    let d = m0.len().isqrt();
    let mut twin: *mut bingham_filter = std::ptr::null_mut();
    // SAFETY: the same (valid) parameters.
    let st = unsafe { bingham_filter_new(d, m0.as_ptr(), z0.as_ptr(), &mut twin) };
    if st != BINGHAM_OK {
        return Err(format!("twin creation failed: {}", last_error()));
    }
    let (m, z) = filter_state(f, d);
    check_state(&m, &z, d).map_err(|e| format!("new: state invalid: {e}"))?;

    // noises reused during the sequence (exercising the caches) and fresh ones
    let pool: Vec<(Vec<f64>, Vec<f64>)> = (0..3).map(|_| filter_noise(&mut rng, d)).collect();
    let steps = 1 + rng.below(40);
    let mut result = Ok(());
    for step in 0..steps {
        let op = match rng.below(34) {
            0..=5 => 0,
            6..=7 => 1,
            8..=13 => 2,
            14 => 3,
            15..=16 => 4,
            17 => 5,
            18 => 6,
            20..=21 => 9,
            22..=23 => 10,
            24 => 11,
            25..=26 => 12,
            27..=28 => 13,
            29 => 14,
            31 => 15,
            32..=33 => 16,
            _ => {
                if rng.chance(0.5) {
                    7
                } else {
                    8
                }
            }
        };
        let name = FILTER_OPS[op];
        let (sm, _) = filter_state(f, d);
        let noise = if rng.chance(0.8) {
            pool[rng.below(pool.len())].clone()
        } else {
            filter_noise(&mut rng, d)
        };
        let mut a = match op {
            0 => FArgs {
                arrays: vec![noise.0, noise.1],
                kinds: vec![M, Z],
                attack: FAttack::None,
                desc: String::new(),
            },
            1 | 12 => FArgs {
                arrays: vec![rng.unit_vector(d), noise.0, noise.1],
                kinds: vec![U, M, Z],
                attack: FAttack::None,
                desc: String::new(),
            },
            2 | 4 | 13 | 14 | 15 => FArgs {
                arrays: vec![filter_measurement(&mut rng, &sm, d), noise.0, noise.1],
                kinds: vec![U, M, Z],
                attack: FAttack::None,
                desc: String::new(),
            },
            16 => FArgs {
                arrays: vec![
                    filter_measurement(&mut rng, &sm, d),
                    noise.0,
                    noise.1,
                    vec![max_surprise(&mut rng)],
                ],
                kinds: vec![U, M, Z, One],
                attack: FAttack::None,
                desc: String::new(),
            },
            3 => FArgs {
                arrays: vec![orthogonal(&mut rng, d), z_vector(&mut rng, d)],
                kinds: vec![M, Z],
                attack: FAttack::None,
                desc: String::new(),
            },
            9 | 10 => {
                let body = direction(&mut rng);
                // the reference: unrelated, equal, or opposite to the measured direction
                let reference = match rng.below(4) {
                    0 => body.clone(),
                    1 => body.iter().map(|v| -v).collect(),
                    _ => direction(&mut rng),
                };
                FArgs {
                    arrays: vec![body, reference, vec![vector_kappa(&mut rng)]],
                    kinds: vec![U, U, One],
                    attack: FAttack::None,
                    desc: String::new(),
                }
            }
            _ => FArgs {
                arrays: vec![],
                kinds: vec![],
                attack: FAttack::None,
                desc: String::new(),
            },
        };
        spoil_filter_args(&mut rng, &mut a, d);
        if op == 16 {
            // max_surprise: +Inf (no gate), ±0 and positive values are valid
            if let FAttack::NonFinite(3) | FAttack::Bad(3) = a.attack {
                let v = a.arrays[3][0];
                if v == f64::INFINITY || v >= 0.0 {
                    a.attack = FAttack::None;
                }
                a.desc = format!("{} max_surprise {v:e}", a.desc);
            }
            if a.attack == FAttack::None && rng.chance(0.1) {
                // `surprise` written over the first entry of the measurement or the noise
                a.attack = FAttack::Alias(rng.below(3));
            }
        }
        if op == 12 && a.attack == FAttack::None && rng.chance(0.25) {
            // no control: u = NULL
            a.attack = FAttack::Null(0);
        }
        // outputs: array outputs count as argument indices after the inputs
        let out_kinds: &[Kind] = match op {
            4 | 10 | 14..=16 => &[One],
            5 => &[DD, D],
            6 | 11 => &[D],
            _ => &[],
        };
        let n_args = a.arrays.len() + out_kinds.len() + usize::from(op == 7 || op == 8 || op == 16);
        if matches!(a.attack, FAttack::None) && has_outputs(op) && rng.chance(0.25) {
            let i = a.arrays.len() + rng.below(n_args - a.arrays.len());
            a.attack = if rng.chance(0.5) {
                FAttack::Null(i)
            } else {
                FAttack::Misaligned(i)
            };
        }
        if matches!(a.attack, FAttack::None) && op >= 5 && rng.chance(0.1) {
            a.attack = if rng.chance(0.5) {
                FAttack::NullHandle
            } else {
                FAttack::MisalignedHandle
            };
        }
        let mut outs: Vec<Buf> = out_kinds
            .iter()
            .map(|&k| Buf::sentinel(kind_len(k, d, 0)))
            .collect();
        let mut out_ptr = [handle_sentinel()];
        let mut out_dim = [usize::MAX; 2];
        let mut out_acc = [ACCEPTED_SENTINEL; 2];
        let before = state_bits(f, d);
        prime_last_error(name);
        if verbose {
            eprintln!(
                "step {step}: {name} {:?} attack {:?} {}",
                a.arrays, a.attack, a.desc
            );
        }
        // SAFETY: f is live with dimension d; arrays have the lengths for d.
        let st = unsafe {
            filter_call(
                op,
                f,
                &a,
                &mut outs,
                &mut out_ptr,
                &mut out_dim,
                &mut out_acc,
            )
        };
        calls += 1;
        count(stats, name, st);
        if verbose {
            eprintln!(
                "    -> {}, state z = {:?}",
                status_name(st),
                filter_state(f, d).1
            );
        }
        let ctx = format!("step {step} {name} (attack {:?} {})", a.attack, a.desc);
        let fail = |msg: String| Err(format!("{ctx}: {msg}"));
        if st == BINGHAM_ERR_PANIC {
            result = fail(format!("panic: {}", last_error()));
            break;
        }
        let want = match a.attack {
            _ if null_is_identity(op, &a.attack) => None,
            FAttack::NullHandle
            | FAttack::MisalignedHandle
            | FAttack::Null(_)
            | FAttack::Misaligned(_) => Some(BINGHAM_ERR_NULL_ARGUMENT),
            FAttack::NonFinite(_) => Some(BINGHAM_ERR_INVALID_ARGUMENT),
            // a negative max_surprise (the valid ones were made attack-free above)
            FAttack::Bad(3) if op == 16 => Some(BINGHAM_ERR_INVALID_ARGUMENT),
            _ => None,
        };
        if let Some(w) = want {
            if st != w {
                result = fail(format!(
                    "status {} instead of {}",
                    status_name(st),
                    status_name(w)
                ));
                break;
            }
        }
        let after = state_bits(f, d);
        if st != BINGHAM_OK {
            if after != before {
                result = fail(format!(
                    "failed with {} but changed the state",
                    status_name(st)
                ));
                break;
            }
            if outs.iter().any(|b| !b.untouched())
                || out_ptr[0] != handle_sentinel()
                || out_dim != [usize::MAX; 2]
                || out_acc != [ACCEPTED_SENTINEL; 2]
            {
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
            if (op == 9 || op == 10) && d == 2 && matches!(a.attack, FAttack::None) {
                // a d = 2 filter has no orientation to observe a direction with
                if st != BINGHAM_ERR_INVALID_DIMENSION {
                    result = fail(format!(
                        "d = 2: {} instead of INVALID_DIMENSION",
                        status_name(st)
                    ));
                    break;
                }
                continue;
            }
            let valid = matches!(a.attack, FAttack::None | FAttack::Alias(_))
                || null_is_identity(op, &a.attack);
            if valid && op != 3 {
                // valid arguments: the documented failures are NOT_CONVERGED / NUMERICAL only
                if st != BINGHAM_ERR_NOT_CONVERGED && st != BINGHAM_ERR_NUMERICAL {
                    result = fail(format!("valid arguments refused: {}", last_error()));
                    break;
                }
                if verbose {
                    eprintln!("    {}", last_error());
                }
            }
            continue;
        }
        // success
        if (op == 9 || op == 10) && d == 2 {
            result = fail("OK from a d = 2 filter".into());
            break;
        }
        if read_only(op) && after != before {
            result = fail("a read-only call changed the state".into());
            break;
        }
        let (m, z) = filter_state(f, d);
        if let Err(e) = check_state(&m, &z, d) {
            result = fail(format!("state invalid after success: {e}"));
            break;
        }
        match op {
            4 | 10 | 14 => {
                let v = outs[0].values()[0];
                if !v.is_finite() || !outs[0].guards_ok() {
                    result = fail(format!("log-likelihood {v}"));
                    break;
                }
            }
            15 => {
                let v = outs[0].values()[0];
                if !v.is_finite() || v < 0.0 || !outs[0].guards_ok() {
                    result = fail(format!("surprise {v}"));
                    break;
                }
            }
            16 => {
                let (s, max_s) = (outs[0].values()[0], a.arrays[3][0]);
                if !s.is_finite() || s < 0.0 || !outs[0].guards_ok() {
                    result = fail(format!("surprise {s}"));
                    break;
                }
                if out_acc[1] != ACCEPTED_SENTINEL || out_acc[0] != i32::from(s <= max_s) {
                    result = fail(format!(
                        "accepted {out_acc:?} with surprise {s:e}, max_surprise {max_s:e}"
                    ));
                    break;
                }
                if out_acc[0] == 0 && after != before {
                    result = fail("gated out, but the state changed".into());
                    break;
                }
                if out_acc[0] == 0 {
                    *stats.entry("update_gated:OK gated out".into()).or_default() += 1;
                }
                // the twin, still in the state before the call: the same surprise, and the plain
                // update gives the same state when the measurement was accepted
                let [y, mv, zv] = [0, 1, 2].map(|i| a.arrays[i].as_ptr());
                let mut s2 = [f64::NAN];
                // SAFETY: twin is live with dimension d; arrays of the lengths for d.
                let st2 = unsafe { bingham_filter_surprise(twin, y, mv, zv, s2.as_mut_ptr()) };
                if st2 != BINGHAM_OK || s2[0].to_bits() != s.to_bits() {
                    result = fail(format!(
                        "surprise {s:e}, but bingham_filter_surprise gives {:e} ({})",
                        s2[0],
                        status_name(st2)
                    ));
                    break;
                }
                // SAFETY: as above.
                if out_acc[0] == 1
                    && unsafe { bingham_filter_update(twin, y, mv, zv) } != BINGHAM_OK
                {
                    result = fail(format!(
                        "accepted, but bingham_filter_update fails: {}",
                        last_error()
                    ));
                    break;
                }
            }
            11 => {
                let v = outs[0].values();
                let k = if d == 4 { 2.0 } else { 1.0 };
                // per axis and total: finite, in [0, k], the squares of the parts add up
                let parts: f64 = v[..d - 1].iter().map(|x| x * x).sum();
                if !outs[0].guards_ok()
                    || v.iter().any(|x| !x.is_finite() || *x < 0.0 || *x > k)
                    || (parts - v[d - 1] * v[d - 1]).abs() > 1e-9 * (v[d - 1] * v[d - 1]) + 1e-300
                {
                    result = fail(format!("angular spread {v:?}"));
                    break;
                }
            }
            5 => {
                let got: Vec<u64> = outs[0]
                    .values()
                    .iter()
                    .chain(&outs[1].values())
                    .map(|v| v.to_bits())
                    .collect();
                if got != after || !outs[0].guards_ok() || !outs[1].guards_ok() {
                    result = fail("get_state output differs from the state".into());
                    break;
                }
            }
            6 => {
                let v = outs[0].values();
                let col: Vec<f64> = (0..d).map(|r| m[r * d + d - 1]).collect();
                if v.iter().zip(&col).any(|(a, b)| a.to_bits() != b.to_bits())
                    || !outs[0].guards_ok()
                {
                    result = fail(format!("mode {v:?} is not the last column of M {col:?}"));
                    break;
                }
            }
            7 if out_dim[0] != d || out_dim[1] != usize::MAX => {
                result = fail(format!("dim wrote {out_dim:?}"));
                break;
            }
            8 => {
                let c = out_ptr[0];
                if c.is_null() || c == handle_sentinel() {
                    result = fail("clone returned no handle".into());
                    break;
                }
                if state_bits(c, d) != after {
                    result = fail("clone differs from the original".into());
                    break;
                }
                // continue with the clone half of the time (the original is freed)
                // SAFETY: both are live handles; the one not kept is freed once.
                unsafe {
                    if rng.chance(0.5) {
                        bingham_filter_free(f);
                        f = c;
                    } else {
                        bingham_filter_free(c);
                    }
                }
            }
            _ => {}
        }
        // the twin repeats the successful call (same arguments); states must agree bit for bit
        // (the gated update's twin was given the plain update above)
        if !read_only(op) && op != 16 {
            let mut twin_outs: Vec<Buf> = vec![];
            let mut tp = [handle_sentinel()];
            let mut td = [usize::MAX; 2];
            let mut ta = [ACCEPTED_SENTINEL; 2];
            // SAFETY: twin is live with dimension d.
            let st2 =
                unsafe { filter_call(op, twin, &a, &mut twin_outs, &mut tp, &mut td, &mut ta) };
            if st2 != BINGHAM_OK {
                result = fail(format!("twin failed: {}", last_error()));
                break;
            }
        }
        if state_bits(twin, d) != state_bits(f, d) {
            result = fail("the twin (which saw only the successful calls) differs: a failed call changed hidden state".into());
            break;
        }
    }
    // SAFETY: live handles, freed once; free(NULL) is a no-op.
    unsafe {
        bingham_filter_free(f);
        bingham_filter_free(twin);
        bingham_filter_free(std::ptr::null_mut());
    }
    result.map(|()| calls)
}

#[test]
fn fuzz_filter_sequences() {
    // each sequence makes ~20 calls on average: count calls, not sequences
    let mut stats: BTreeMap<String, u64> = BTreeMap::new();
    run_sequences(
        "bingham_filter",
        "filter",
        99,
        cases_for(1.0, 1.0, SHARE_FILTER),
        |seed, verbose| filter_sequence(seed, verbose, &mut stats),
    );
    if stats_wanted() {
        eprintln!("bingham_filter statuses: {stats:?}");
    }
}
