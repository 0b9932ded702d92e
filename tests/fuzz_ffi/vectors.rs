//! Vector observations, rotation noise, angular spread.
//!
//! Scalar arguments (kappa, sigma) do not fit the table above: each function has its own case
//! generator. Every case checks the status the header prescribes where the arguments determine
//! it, that errors write nothing and name the function, that inputs stay unchanged, and the
//! invariants of a successful result.

use bingham::ffi::bingham_status::*;
use bingham::ffi::*;
use testkit::fuzz::{
    check_state, dangling, extreme, non_finite, orthogonal, orthogonality_error, z_moderate,
    z_vector, Buf, STATE_TOL,
};
use testkit::{norm, rot, Rng64};

use crate::case::spoil;
use crate::drivers::{cases_for, drive, SHARE_VECTOR};
use crate::filter::{direction, vector_kappa};
use crate::kinds::Kind::*;
use crate::status::{check_error_message, last_error, prime_last_error, status_code, status_name};

/// `R(q) v` for a unit quaternion q (scalar first), with the tests' textbook `R(q)`.
pub(crate) fn rotate(q: &[f64], v: &[f64]) -> [f64; 3] {
    let r = rot(&[q[0], q[1], q[2], q[3]]);
    [0, 1, 2].map(|i| r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2])
}

/// Calls `call` with input buffers (optionally NULL / misaligned) and sentinel outputs; checks
/// the generic contract and returns the status and the outputs' values.
struct Pointers {
    /// per input: None = valid, Some(0) = NULL, Some(k) = misaligned by k bytes
    inputs: Vec<Option<usize>>,
    outputs: Vec<Option<usize>>,
    /// all array pointers dangling (an invalid d must be refused first)
    dangling: bool,
}

fn run_arrays(
    name: &str,
    inputs: &[Vec<f64>],
    out_lens: &[usize],
    ptrs: &Pointers,
    call: impl FnOnce(&[*const f64], &[*mut f64]) -> bingham_status,
) -> Result<(bingham_status, Vec<Vec<f64>>), String> {
    let mut ib: Vec<Buf> = inputs.iter().map(|v| Buf::from(v)).collect();
    let mut ob: Vec<Buf> = out_lens.iter().map(|&n| Buf::sentinel(n)).collect();
    let before: Vec<Vec<u64>> = ib.iter().map(Buf::bits).collect();
    let pick = |b: &mut Buf, how: Option<usize>| match how {
        _ if ptrs.dangling => dangling(),
        None => b.ptr(),
        Some(0) => std::ptr::null_mut(),
        Some(k) => b.misaligned(k),
    };
    let ip: Vec<*const f64> = ib
        .iter_mut()
        .zip(&ptrs.inputs)
        .map(|(b, &h)| pick(b, h) as *const f64)
        .collect();
    let op: Vec<*mut f64> = ob
        .iter_mut()
        .zip(&ptrs.outputs)
        .map(|(b, &h)| pick(b, h))
        .collect();
    prime_last_error(name);
    let st = call(&ip, &op);
    let code = status_code(st);
    if !(0..=7).contains(&code) || st == BINGHAM_ERR_PANIC || st == BINGHAM_ERR_CALLBACK {
        return Err(format!("status {code}: {}", last_error()));
    }
    for (i, b) in ib.iter().enumerate() {
        if b.bits() != before[i] {
            return Err(format!("input {i} was modified"));
        }
    }
    if st != BINGHAM_OK {
        if ob.iter().any(|b| !b.untouched()) {
            return Err(format!("{} but an output was written", status_name(st)));
        }
        check_error_message(name)?;
        return Ok((st, vec![]));
    }
    for (i, b) in ob.iter().enumerate() {
        if !b.guards_ok() || !b.fully_written() {
            return Err(format!("output {i}: not exactly its length written"));
        }
        if let Some(v) = b.values().iter().find(|v| !v.is_finite()) {
            return Err(format!("output {i} holds {v}"));
        }
    }
    Ok((st, ob.iter().map(Buf::values).collect()))
}

/// NULL (Some(0)) or misaligned (Some(1..8)) for one of `n` pointers, else all valid.
fn pointer_attack(rng: &mut Rng64, n: usize, p: f64) -> (Vec<Option<usize>>, bool) {
    let mut v = vec![None; n];
    if rng.chance(p) {
        v[rng.below(n)] = Some(if rng.chance(0.6) { 0 } else { 1 + rng.below(7) });
        return (v, true);
    }
    (v, false)
}

pub(crate) fn expect(
    st: bingham_status,
    want: Option<bingham_status>,
    what: &str,
) -> Result<(), String> {
    match want {
        Some(w) if w != st => Err(format!(
            "{what}: status {} where the header prescribes {} ({})",
            status_name(st),
            status_name(w),
            if st == BINGHAM_OK {
                String::new()
            } else {
                last_error()
            }
        )),
        _ => Ok(()),
    }
}

fn vector_observation_case(seed: u64, verbose: bool) -> Result<&'static str, String> {
    let mut rng = Rng64::new(seed);
    let mut body = direction(&mut rng);
    let mut reference = if rng.chance(0.2) {
        body.iter()
            .map(|v| if rng.chance(0.5) { *v } else { -*v })
            .collect()
    } else {
        direction(&mut rng)
    };
    let mut kappa = vector_kappa(&mut rng);
    let (pins, mut pa) = pointer_attack(&mut rng, 4, 0.1);
    let mut want = pa.then_some(BINGHAM_ERR_NULL_ARGUMENT);
    let mut clean = !pa;
    let mut what = format!("pointers {pins:?}");
    if !pa {
        match rng.below(8) {
            0 => {
                let v = if rng.chance(0.5) {
                    &mut body
                } else {
                    &mut reference
                };
                v[rng.below(3)] = non_finite(&mut rng);
                want = Some(BINGHAM_ERR_INVALID_ARGUMENT);
                what = "non-finite vector".into();
            }
            1 => {
                kappa = if rng.chance(0.5) {
                    non_finite(&mut rng)
                } else {
                    -rng.log_uniform(-320.0, 308.0)
                };
                want = Some(BINGHAM_ERR_INVALID_ARGUMENT);
                what = format!("kappa = {kappa:e}");
            }
            2 => {
                let v = if rng.chance(0.5) {
                    &mut body
                } else {
                    &mut reference
                };
                what = spoil(&mut rng, U, v, 3);
                clean = false;
            }
            3 => {
                kappa = extreme(&mut rng);
                if !(0.0..=f64::MAX / 2.0).contains(&kappa) {
                    want = Some(BINGHAM_ERR_INVALID_ARGUMENT);
                }
                clean = false;
                what = format!("kappa = {kappa:e}");
            }
            _ => {}
        }
    }
    pa = pa || want.is_some();
    if verbose {
        eprintln!("body {body:?} reference {reference:?} kappa {kappa:e} {what}");
    }
    let ptrs = Pointers {
        inputs: pins[..2].to_vec(),
        outputs: pins[2..].to_vec(),
        dangling: false,
    };
    let name = "bingham_vector_observation";
    let r = run_arrays(
        name,
        &[body.clone(), reference.clone()],
        &[16, 4],
        &ptrs,
        |i, o| {
            // SAFETY: 3 readable doubles each (or NULL / misaligned), 16 and 4 writable doubles.
            unsafe { bingham_vector_observation(i[0], i[1], kappa, o[0], o[1]) }
        },
    );
    let (st, outs) = r?;
    expect(st, want, &what)?;
    if st != BINGHAM_OK {
        if clean && !pa && kappa <= 1e300 {
            return Err(format!("valid arguments refused: {}", last_error()));
        }
        return Ok(status_name(st));
    }
    let (m, z) = (&outs[0], &outs[1]);
    let e = orthogonality_error(m, 4);
    if e.is_nan() || e > STATE_TOL {
        return Err(format!("M not orthogonal: {e:e}"));
    }
    if z != &[-2.0 * kappa, -2.0 * kappa, 0.0, 0.0] {
        return Err(format!("z = {z:?} for kappa = {kappa:e}"));
    }
    // the exponent: qᵀ M Z Mᵀ q = kappa (rᵀ R(q) b − 1) for (normalized) b, r
    let (nb, nr) = (norm(&body), norm(&reference));
    let b: Vec<f64> = body.iter().map(|v| v / nb).collect();
    let r: Vec<f64> = reference.iter().map(|v| v / nr).collect();
    for _ in 0..3 {
        let q = rng.unit_vector(4);
        let lhs: f64 = (0..4)
            .map(|c| {
                let p: f64 = (0..4).map(|k| m[k * 4 + c] * q[k]).sum();
                z[c] * p * p
            })
            .sum();
        let rb = rotate(&q, &b);
        let rhs = kappa * (rb[0] * r[0] + rb[1] * r[1] + rb[2] * r[2] - 1.0);
        if (lhs - rhs).abs() > 1e-11 * kappa.max(1e-300) {
            return Err(format!("exponent {lhs:e} vs kappa (rᵀRb − 1) = {rhs:e}"));
        }
    }
    Ok("OK")
}

fn noise_case(seed: u64, verbose: bool) -> Result<&'static str, String> {
    let mut rng = Rng64::new(seed);
    let d = if rng.chance(0.1) {
        *rng.pick(&[0usize, 1, 3, 5, 64, 65, usize::MAX])
    } else if rng.chance(0.5) {
        2
    } else {
        4
    };
    let bad_d = d != 2 && d != 4;
    let (sigma, mut want, mut must) = match rng.below(8) {
        0 => (rng.log_uniform(-6.0, 0.5), None, true),
        1 => (rng.log_uniform(-9.0, -6.0), None, false), // near the documented limit
        2 => (rng.log_uniform(0.5, 300.0), None, true),
        3 => (
            non_finite(&mut rng),
            Some(BINGHAM_ERR_INVALID_ARGUMENT),
            false,
        ),
        4 => (
            -rng.log_uniform(-320.0, 300.0) * f64::from(u8::from(rng.chance(0.9))),
            Some(BINGHAM_ERR_INVALID_ARGUMENT),
            false,
        ),
        5 => {
            let s = extreme(&mut rng);
            let want = (s <= 0.0).then_some(BINGHAM_ERR_INVALID_ARGUMENT);
            (s, want, s >= 1e-6)
        }
        _ => (rng.range(1e-3, 3.0), None, true),
    };
    let (pouts, pa) = pointer_attack(&mut rng, 2, 0.1);
    if pa {
        want = Some(BINGHAM_ERR_NULL_ARGUMENT);
        must = false;
    }
    if bad_d {
        want = Some(BINGHAM_ERR_INVALID_DIMENSION);
    }
    if verbose {
        eprintln!("d = {d}, sigma = {sigma:e}, pointers {pouts:?}");
    }
    let len = if bad_d { 1 } else { d };
    let ptrs = Pointers {
        inputs: vec![],
        outputs: pouts,
        dangling: bad_d && rng.chance(0.5),
    };
    let name = "bingham_noise_from_angle_std";
    let (st, outs) = run_arrays(name, &[], &[len * len, len], &ptrs, |_, o| {
        // SAFETY: d*d and d writable doubles, or dangling with an invalid d (refused first).
        unsafe { bingham_noise_from_angle_std(d, sigma, o[0], o[1]) }
    })?;
    expect(st, want, &format!("d = {d}, sigma = {sigma:e}"))?;
    if st != BINGHAM_OK {
        if must && !bad_d {
            return Err(format!(
                "sigma = {sigma:e} (d = {d}) refused: {}",
                last_error()
            ));
        }
        return Ok(status_name(st));
    }
    let (m, z) = (&outs[0], &outs[1]);
    check_state(m, z, d)?;
    // (a uniform result, z = 0, e.g. d = 2 with sigma > 4, has no distinguished mode)
    if z[0] != 0.0 && (0..d).any(|r| m[r * d + d - 1] != if r == 0 { 1.0 } else { 0.0 }) {
        return Err(format!("the mode is not the identity: M = {m:?}"));
    }
    // the second moment: E[x_0²] = (1 + E cos θ)/2, E cos θ = (1 − σ²) e^{−σ²/2} (d = 4),
    // e^{−2σ²} (d = 2)
    if (1e-4..=100.0).contains(&sigma) {
        let s2 = sigma * sigma;
        let c = if d == 4 {
            0.5 * (1.0 + (1.0 - s2) * (-0.5 * s2).exp())
        } else {
            0.5 * (1.0 + (-2.0 * s2).exp())
        };
        let mut s = vec![0.0; d * d];
        // SAFETY: valid buffers.
        let st = unsafe { bingham_second_moment(d, m.as_ptr(), z.as_ptr(), s.as_mut_ptr()) };
        if st != BINGHAM_OK {
            return Err(format!("second moment of the result: {}", last_error()));
        }
        if (s[0] - c).abs() > 1e-9 {
            return Err(format!("E[x_0²] = {} instead of {c}", s[0]));
        }
    }
    Ok("OK")
}

fn angular_spread_case(seed: u64, verbose: bool) -> Result<&'static str, String> {
    let mut rng = Rng64::new(seed);
    let d = if rng.chance(0.08) {
        *rng.pick(&[0usize, 1, 3, 5, 64, 65, usize::MAX])
    } else if rng.chance(0.5) {
        2
    } else {
        4
    };
    let bad_d = d != 2 && d != 4;
    let dl = if bad_d { 2 } else { d };
    let moderate = rng.chance(0.5);
    let mut m = orthogonal(&mut rng, dl);
    let mut z = if moderate {
        z_moderate(&mut rng, dl)
    } else {
        z_vector(&mut rng, dl)
    };
    let (pins, pa) = pointer_attack(&mut rng, 3, 0.1);
    let mut want = pa.then_some(BINGHAM_ERR_NULL_ARGUMENT);
    let mut clean = moderate && !pa;
    if !pa {
        match rng.below(8) {
            0 => {
                let v = if rng.chance(0.5) { &mut m } else { &mut z };
                let i = rng.below(v.len());
                v[i] = non_finite(&mut rng);
                want = Some(BINGHAM_ERR_INVALID_ARGUMENT);
                clean = false;
            }
            1 => {
                spoil(&mut rng, M, &mut m, dl);
                clean = false;
            }
            2 => {
                spoil(&mut rng, Z, &mut z, dl);
                clean = false;
            }
            _ => {}
        }
    }
    if bad_d {
        want = Some(BINGHAM_ERR_INVALID_DIMENSION);
    }
    if verbose {
        eprintln!("d = {d}, m = {m:?}, z = {z:?}, pointers {pins:?}");
    }
    let ptrs = Pointers {
        inputs: pins[..2].to_vec(),
        outputs: pins[2..].to_vec(),
        dangling: bad_d && rng.chance(0.5),
    };
    let name = "bingham_angular_spread";
    let (st, outs) = run_arrays(name, &[m, z], &[dl], &ptrs, |i, o| {
        // SAFETY: d*d and d readable, d writable doubles (dangling only with an invalid d).
        unsafe { bingham_angular_spread(d, i[0], i[1], o[0]) }
    })?;
    expect(st, want, &format!("d = {d}"))?;
    if st != BINGHAM_OK {
        if clean && !bad_d {
            return Err(format!("valid arguments refused: {}", last_error()));
        }
        return Ok(status_name(st));
    }
    let v = &outs[0];
    let k = if d == 4 { 2.0 } else { 1.0 };
    let parts: f64 = v[..d - 1].iter().map(|x| x * x).sum();
    let total = v[d - 1] * v[d - 1];
    // all ≥ 0; at most the uniform distribution's total k √(1 − 1/d)
    if v.iter().any(|x| *x < 0.0) || v[d - 1] > k * (1.0 - 1.0 / d as f64).sqrt() * (1.0 + 1e-12) {
        return Err(format!("spread {v:?} out of range"));
    }
    if (parts - total).abs() > 1e-9 * total + 1e-300 {
        return Err(format!("Σ per-axis² = {parts:e} ≠ total² = {total:e}"));
    }
    Ok("OK")
}

#[test]
fn fuzz_vector_observation() {
    let n = cases_for(1.0, 3.0, SHARE_VECTOR);
    drive("bingham_vector_observation", 40, n, vector_observation_case);
}

#[test]
fn fuzz_noise_from_angle_std() {
    let n = cases_for(1.0, 3.0, SHARE_VECTOR);
    drive("bingham_noise_from_angle_std", 41, n, noise_case);
}

#[test]
fn fuzz_angular_spread() {
    let n = cases_for(1.0, 3.0, SHARE_VECTOR);
    drive("bingham_angular_spread", 42, n, angular_spread_case);
}
