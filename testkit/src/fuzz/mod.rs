//! The C ABI fuzz harness's helpers (`tests/fuzz_ffi/`, also `tests/threads.rs` and
//! `tests/long_run.rs`): generators of valid and hostile inputs, row-major matrices, invariant
//! checks of Bingham states, sentinel-guarded buffers ([`Buf`]), a crash and hang reporter that
//! names the case that was running ([`CaseSlot`]), and the environment settings.

mod buf;
mod crash;

pub use buf::{dangling, guard_words, sentinel, Buf};
pub use crash::{case_timeout_s, install_crash_reporter, CaseSlot};

use std::os::raw::c_char;

use crate::{norm, Rng64};

// ---- values -----------------------------------------------------------------------------------

/// A non-finite value: NaNs with various payloads and signs, ±Inf.
pub fn non_finite(rng: &mut Rng64) -> f64 {
    match rng.below(6) {
        0 => f64::NAN,
        1 => -f64::NAN,
        2 => f64::INFINITY,
        3 => f64::NEG_INFINITY,
        // signalling NaN, random payload
        4 => f64::from_bits(0x7FF0_0000_0000_0000 | (rng.next_u64() & 0x0007_FFFF_FFFF_FFFF) | 1),
        _ => f64::from_bits(0xFFF8_0000_0000_0000 | (rng.next_u64() & 0x0007_FFFF_FFFF_FFFF)),
    }
}

/// A finite but extreme value: ±0, subnormals, the smallest normal, huge magnitudes, random
/// finite bit patterns.
pub fn extreme(rng: &mut Rng64) -> f64 {
    let sign = if rng.chance(0.5) { -1.0 } else { 1.0 };
    sign * match rng.below(8) {
        0 => 0.0,
        1 => f64::from_bits(1 + rng.next_u64() % ((1u64 << 52) - 1)), // subnormal
        2 => f64::MIN_POSITIVE,
        3 => f64::MAX,
        4 => rng.log_uniform(100.0, 308.0),
        5 => rng.log_uniform(-308.0, -100.0),
        6 => 5e-324,
        _ => loop {
            let v = f64::from_bits(rng.next_u64() & 0x7FFF_FFFF_FFFF_FFFF);
            if v.is_finite() {
                break v;
            }
        },
    }
}

/// A concentration as a caller might pass it (any sign and shift): mostly realistic values
/// (|z| up to 1e7 and a few beyond), sometimes extreme finite values.
pub fn concentration(rng: &mut Rng64) -> f64 {
    match rng.below(20) {
        0 => 0.0,
        1 => -rng.uniform(),
        2..=9 => -rng.log_uniform(-3.0, 3.0),
        10..=13 => -rng.log_uniform(3.0, 7.0),
        14 => -rng.log_uniform(7.0, 13.0),
        15 => rng.log_uniform(-3.0, 2.5), // positive (the shift is arbitrary)
        16 => rng.range(-5.0, 5.0),
        17 => -rng.log_uniform(-310.0, -3.0), // tiny, down to subnormal
        18 => -1e6,
        _ => extreme(rng),
    }
}

/// A concentration vector of length `d` with realistic structure: sometimes repeated entries,
/// sometimes all equal (uniform), sometimes one huge spread.
pub fn z_vector(rng: &mut Rng64, d: usize) -> Vec<f64> {
    let mut z: Vec<f64> = (0..d).map(|_| concentration(rng)).collect();
    match rng.below(10) {
        0 => {
            // repeated values
            let v = z[0];
            for x in z.iter_mut() {
                if rng.chance(0.5) {
                    *x = v;
                }
            }
        }
        1 => {
            let v = z[0];
            z.iter_mut().for_each(|x| *x = v);
        }
        2 => {
            // moderate values only (the bread and butter)
            for x in z.iter_mut() {
                *x = -rng.log_uniform(-2.0, 2.5);
            }
        }
        3 => {
            // shifted by a large constant
            let c = rng.range(-1e3, 1e3);
            z.iter_mut().for_each(|x| *x += c);
        }
        _ => {}
    }
    z
}

/// Concentrations within the documented exact range: |z_i| ≤ 1e6 after the shift.
pub fn z_moderate(rng: &mut Rng64, d: usize) -> Vec<f64> {
    (0..d)
        .map(|_| match rng.below(4) {
            0 => -rng.log_uniform(-3.0, 6.0),
            1 => -rng.log_uniform(-1.0, 2.0),
            2 => -rng.uniform(),
            _ => 0.0,
        })
        .collect()
}

// ---- matrices and vectors (row-major) ---------------------------------------------------------

/// The d×d identity, row-major.
pub fn identity(d: usize) -> Vec<f64> {
    let mut m = vec![0.0; d * d];
    for i in 0..d {
        m[i * d + i] = 1.0;
    }
    m
}

/// Applies the Householder reflection `I − 2 v vᵀ` (v unit) from the left to the row-major `m`.
fn reflect_left(m: &mut [f64], d: usize, v: &[f64]) {
    for c in 0..d {
        let dot: f64 = (0..d).map(|r| v[r] * m[r * d + c]).sum();
        for r in 0..d {
            m[r * d + c] -= 2.0 * v[r] * dot;
        }
    }
}

/// A random orthogonal matrix: a signed permutation times up to three Householder reflections
/// (orthonormal to rounding; not Haar-distributed, which does not matter here).
pub fn orthogonal(rng: &mut Rng64, d: usize) -> Vec<f64> {
    let mut m = vec![0.0; d * d];
    let mut perm: Vec<usize> = (0..d).collect();
    for i in (1..d).rev() {
        perm.swap(i, rng.below(i + 1));
    }
    for (r, &c) in perm.iter().enumerate() {
        m[r * d + c] = if rng.chance(0.5) { 1.0 } else { -1.0 };
    }
    if rng.chance(0.1) {
        return m; // signed permutation: exactly orthogonal
    }
    for _ in 0..(1 + rng.below(3)) {
        let v = rng.unit_vector(d);
        reflect_left(&mut m, d, &v);
    }
    m
}

/// `M diag(w) Mᵀ` (row-major, exactly symmetric).
pub fn congruence(m: &[f64], w: &[f64], d: usize) -> Vec<f64> {
    let mut s = vec![0.0; d * d];
    for r in 0..d {
        for c in r..d {
            let v: f64 = (0..d).map(|k| m[r * d + k] * w[k] * m[c * d + k]).sum();
            s[r * d + c] = v;
            s[c * d + r] = v;
        }
    }
    s
}

/// max |MᵀM − I| for a row-major d×d matrix.
pub fn orthogonality_error(m: &[f64], d: usize) -> f64 {
    let mut worst = 0.0f64;
    for a in 0..d {
        for b in a..d {
            let v: f64 = (0..d).map(|r| m[r * d + a] * m[r * d + b]).sum();
            let target = if a == b { 1.0 } else { 0.0 };
            let e = (v - target).abs();
            if e.is_nan() {
                return f64::NAN;
            }
            worst = worst.max(e);
        }
    }
    worst
}

// ---- invariants -------------------------------------------------------------------------------

/// Tolerance of the "valid Bingham state" checks: orthonormality of M, Σω = 1.
pub const STATE_TOL: f64 = 1e-12;

/// A normalized Bingham parameter pair: finite, M orthonormal to 1e-12, z ascending with
/// z[d−1] = 0 exactly.
pub fn check_state(m: &[f64], z: &[f64], d: usize) -> Result<(), String> {
    if m.len() != d * d || z.len() != d {
        return Err(format!(
            "state lengths {} / {} for d = {d}",
            m.len(),
            z.len()
        ));
    }
    if let Some(i) = m.iter().position(|v| !v.is_finite()) {
        return Err(format!("M[{i}] = {} is not finite", m[i]));
    }
    if let Some(i) = z.iter().position(|v| !v.is_finite()) {
        return Err(format!("z[{i}] = {} is not finite", z[i]));
    }
    let e = orthogonality_error(m, d);
    if e.is_nan() || e > STATE_TOL {
        return Err(format!("M is not orthonormal: max|MᵀM − I| = {e:e}"));
    }
    if let Some(i) = (1..d).find(|&i| z[i - 1] > z[i]) {
        return Err(format!("z not ascending at {i}: {z:?}"));
    }
    if z[d - 1] != 0.0 {
        return Err(format!("z[d−1] = {} ≠ 0", z[d - 1]));
    }
    Ok(())
}

/// Probabilities ω: finite, ≥ 0, Σ = 1 within `STATE_TOL`.
pub fn check_omega(w: &[f64]) -> Result<(), String> {
    check_omega_tol(w, STATE_TOL)
}

/// Probabilities ω: finite, ≥ 0, Σ = 1 within `tol`.
pub fn check_omega_tol(w: &[f64], tol: f64) -> Result<(), String> {
    if let Some(i) = w.iter().position(|v| !v.is_finite() || *v < 0.0) {
        return Err(format!("ω[{i}] = {} is not a probability", w[i]));
    }
    let s: f64 = w.iter().sum();
    if (s - 1.0).abs() > tol {
        return Err(format!("Σω = 1 + {:e}", s - 1.0));
    }
    Ok(())
}

/// A unit vector to `tol`.
pub fn check_unit(v: &[f64], tol: f64) -> Result<(), String> {
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(format!("entry {i} = {} is not finite", v[i]));
    }
    let n = norm(v);
    if (n - 1.0).abs() > tol {
        return Err(format!("norm 1 + {:e}", n - 1.0));
    }
    Ok(())
}

// ---- messages ---------------------------------------------------------------------------------

/// A string returned by the C convention of `bingham_last_error_message(buf, len, out_len)`:
/// `get(NULL, 0, &n)` asks for the length `n`, then `get(buf, n + 1, NULL)` copies it.
pub fn read_message(mut get: impl FnMut(*mut c_char, usize, *mut usize)) -> String {
    let mut n = 0usize;
    get(std::ptr::null_mut(), 0, &mut n);
    let mut buf = vec![0 as c_char; n + 1];
    get(buf.as_mut_ptr(), buf.len(), std::ptr::null_mut());
    let bytes: Vec<u8> = buf[..n].iter().map(|&c| c as u8).collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

// ---- configuration ----------------------------------------------------------------------------

/// An environment variable parsed as a number (accepts `1e7`, `10000000`, `1_000_000`).
pub fn env_count(name: &str, default: u64) -> u64 {
    match std::env::var(name) {
        Ok(s) => {
            let s = s.replace('_', "");
            s.parse::<u64>()
                .ok()
                .or_else(|| s.parse::<f64>().ok().map(|v| v as u64))
                .unwrap_or_else(|| panic!("{name}={s:?} is not a number"))
        }
        Err(_) => default,
    }
}
