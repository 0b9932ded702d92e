//! Deterministic samples.
//!
//! bingham_deterministic_sample_count / bingham_deterministic_samples: random and hostile d, scheme
//! codes, lambda, capacity (zero, short, exact, larger, SIZE_MAX), NULL and misaligned pointers (also
//! the size_t and int outputs), NaN/Inf and spoiled M and z, one fault at a time. An error has the
//! prescribed status and writes nothing (sentinels, including the spare rows); success writes exactly
//! `count` rows and weights (the rows beyond stay untouched) that satisfy the invariants.

use std::os::raw::c_int;

use bingham::ffi::bingham_status::*;
use bingham::ffi::*;
use testkit::fuzz::{check_unit, dangling, non_finite, orthogonal, z_moderate, z_vector, Buf};
use testkit::Rng64;

use crate::case::spoil;
use crate::drivers::{cases_for, drive, SHARE_NONLINEAR};
use crate::kinds::Kind::*;
use crate::status::{check_error_message, last_error, prime_last_error, status_code, status_name};
use crate::vectors::expect;

fn max_samples(d: usize, scheme: c_int) -> usize {
    if scheme == BINGHAM_SAMPLES_TAC2016 {
        2 * d - 1
    } else {
        2 * d * d - 4 * d + 3
    }
}

/// A scheme code: mostly valid, sometimes not; and whether it is valid.
fn scheme_code(rng: &mut Rng64) -> (c_int, bool) {
    if rng.chance(0.9) {
        (
            *rng.pick(&[BINGHAM_SAMPLES_TAC2016, BINGHAM_SAMPLES_MOMENTS]),
            true,
        )
    } else {
        let random = rng.next_u64() as c_int;
        let c = *rng.pick(&[-1, 2, 3, c_int::MIN, c_int::MAX, random]);
        (c, c == 0 || c == 1)
    }
}

fn dim_for_samples(rng: &mut Rng64) -> usize {
    if rng.chance(0.06) {
        *rng.pick(&[0usize, 1, 65, 1000, usize::MAX])
    } else if rng.chance(0.06) {
        *rng.pick(&[5usize, 6, 8, 13, 64])
    } else {
        2 + rng.below(3)
    }
}

fn sample_count_case(seed: u64, verbose: bool) -> Result<&'static str, String> {
    let mut rng = Rng64::new(seed);
    let d = dim_for_samples(&mut rng);
    let (scheme, scheme_ok) = scheme_code(&mut rng);
    let attack = if rng.chance(0.15) {
        Some(rng.below(8))
    } else {
        None
    };
    if verbose {
        eprintln!("d = {d}, scheme = {scheme}, pointer attack {attack:?}");
    }
    let mut out = [usize::MAX; 3];
    let p = match attack {
        Some(0) => std::ptr::null_mut(),
        Some(k) => out
            .as_mut_ptr()
            .cast::<u8>()
            .wrapping_add(k)
            .cast::<usize>(),
        None => out.as_mut_ptr(),
    };
    prime_last_error("bingham_deterministic_sample_count");
    // SAFETY: p is NULL, misaligned (refused) or points to a writable size_t.
    let st = unsafe { bingham_deterministic_sample_count(d, scheme, p) };
    let want = if !(2..=64).contains(&d) {
        BINGHAM_ERR_INVALID_DIMENSION
    } else if !scheme_ok {
        BINGHAM_ERR_INVALID_ARGUMENT
    } else if attack.is_some() {
        BINGHAM_ERR_NULL_ARGUMENT
    } else {
        BINGHAM_OK
    };
    expect(st, Some(want), &format!("d = {d}, scheme = {scheme}"))?;
    if st != BINGHAM_OK {
        if out != [usize::MAX; 3] {
            return Err(format!("{} but wrote {out:?}", status_name(st)));
        }
        check_error_message("bingham_deterministic_sample_count")?;
        return Ok(status_name(st));
    }
    if out != [max_samples(d, scheme), usize::MAX, usize::MAX] {
        return Err(format!("count {out:?} for d = {d}, scheme {scheme}"));
    }
    Ok("OK")
}

/// One fault of a `bingham_deterministic_samples` case.
#[derive(Debug, Clone, Copy, PartialEq)]
enum SampleFault {
    None,
    /// argument 0..6 (m, z, points, weights, count, reproduced): NULL (0) or misaligned by k
    Pointer(usize, usize),
    NonFinite,
    Lambda,
    SpoilM,
    SpoilZ,
    Scheme,
    Capacity,
}

const REPRODUCED_SENTINEL: c_int = 0x5A5A_5A5A;

fn deterministic_samples_case(seed: u64, verbose: bool) -> Result<&'static str, String> {
    let mut rng = Rng64::new(seed);
    let d = dim_for_samples(&mut rng);
    let bad_d = !(2..=64).contains(&d);
    let dl = if bad_d { 2 } else { d };
    let mut fault = match rng.below(20) {
        0..=9 => SampleFault::None,
        10 | 11 => {
            let i = rng.below(6);
            // misaligned by k bytes (k = 4 would be aligned for the int `reproduced`)
            let k = if rng.chance(0.6) {
                0
            } else {
                *rng.pick(&[1usize, 2, 3, 5, 6, 7])
            };
            SampleFault::Pointer(i, k)
        }
        12 => SampleFault::NonFinite,
        13 => SampleFault::Lambda,
        14 => SampleFault::SpoilM,
        15 | 16 => SampleFault::SpoilZ,
        17 => SampleFault::Scheme,
        _ => SampleFault::Capacity,
    };
    let (mut scheme, scheme_ok) = scheme_code(&mut rng);
    if fault == SampleFault::Scheme {
        if scheme_ok {
            scheme = *rng.pick(&[-1, 2, c_int::MIN, c_int::MAX]);
        }
    } else if !scheme_ok {
        if fault == SampleFault::None {
            fault = SampleFault::Scheme;
        } else {
            scheme = BINGHAM_SAMPLES_MOMENTS;
        }
    }
    let len_scheme = if fault == SampleFault::Scheme {
        BINGHAM_SAMPLES_MOMENTS
    } else {
        scheme
    };
    let needed = max_samples(dl, len_scheme);
    let moderate = rng.chance(0.7) && fault != SampleFault::SpoilZ;
    let mut m = orthogonal(&mut rng, dl);
    let mut z = if moderate {
        z_moderate(&mut rng, dl)
    } else {
        z_vector(&mut rng, dl)
    };
    let mut lambda = match rng.below(6) {
        0 => 0.0,
        1 => 1.0,
        _ => rng.uniform(),
    };
    let mut capacity = match rng.below(10) {
        0 => needed + 1 + rng.below(5),
        // the library writes at most the needed count: a capacity beyond the buffers is never
        // used (the buffers hold needed + 5 rows), and must not overflow anything
        1 => usize::MAX,
        _ => needed,
    };
    let mut desc = format!("{fault:?}");
    match fault {
        SampleFault::NonFinite => {
            let v = if rng.chance(0.5) { &mut m } else { &mut z };
            let i = rng.below(v.len());
            v[i] = non_finite(&mut rng);
        }
        SampleFault::Lambda => {
            lambda = match rng.below(3) {
                0 => non_finite(&mut rng),
                1 => -rng.log_uniform(-320.0, 300.0),
                _ => 1.0 + rng.log_uniform(-15.0, 300.0),
            };
            desc = format!("lambda = {lambda:e}");
        }
        SampleFault::SpoilM => desc = spoil(&mut rng, M, &mut m, dl),
        SampleFault::SpoilZ => desc = spoil(&mut rng, Z, &mut z, dl),
        SampleFault::Capacity => {
            capacity = if rng.chance(0.3) {
                0
            } else {
                needed - 1 - rng.below(needed.min(3))
            };
            desc = format!("capacity {capacity} < {needed}");
        }
        _ => {}
    }
    if verbose {
        eprintln!(
            "d = {d}, scheme {scheme}, lambda {lambda:e}, capacity {capacity}, {desc}\n m = {m:?}\n z = {z:?}"
        );
    }
    let rows = capacity.min(needed + 5);
    let mut mb = Buf::from(&m);
    let mut zb = Buf::from(&z);
    let (m_bits, z_bits) = (mb.bits(), zb.bits());
    let mut pb = Buf::sentinel(rows * dl);
    let mut wb = Buf::sentinel(rows);
    let mut count = [usize::MAX; 3];
    let mut reproduced = [REPRODUCED_SENTINEL; 3];
    let dang = bad_d && rng.chance(0.5);
    let mut ptrs: [*mut u8; 6] = [
        mb.ptr().cast(),
        zb.ptr().cast(),
        pb.ptr().cast(),
        wb.ptr().cast(),
        count.as_mut_ptr().cast(),
        reproduced.as_mut_ptr().cast(),
    ];
    if let SampleFault::Pointer(i, k) = fault {
        ptrs[i] = if k == 0 {
            std::ptr::null_mut()
        } else {
            ptrs[i].wrapping_add(k)
        };
    }
    if dang {
        ptrs = [dangling().cast(); 6];
    }
    prime_last_error("bingham_deterministic_samples");
    // SAFETY: m: d*d and z: d readable doubles, points: rows*d and weights: rows writable doubles
    // with rows >= the count the library may write, count and reproduced one element each; or
    // NULL / misaligned (refused) / dangling with an invalid d (refused before any access).
    let st = unsafe {
        bingham_deterministic_samples(
            d,
            ptrs[0] as *const f64,
            ptrs[1] as *const f64,
            scheme,
            lambda,
            capacity,
            ptrs[2].cast(),
            ptrs[3].cast(),
            ptrs[4].cast(),
            ptrs[5].cast(),
        )
    };
    let code = status_code(st);
    if !(0..=7).contains(&code) || st == BINGHAM_ERR_PANIC || st == BINGHAM_ERR_CALLBACK {
        return Err(format!("status {code}: {}", last_error()));
    }
    if mb.bits() != m_bits || zb.bits() != z_bits {
        return Err("an input was modified".into());
    }
    let tac = scheme == BINGHAM_SAMPLES_TAC2016;
    let (zmax, zmin) = z
        .iter()
        .fold((f64::NEG_INFINITY, f64::INFINITY), |(a, b), &v| {
            (a.max(v), b.min(v))
        });
    let span_overflows = !(zmax - zmin).is_finite();
    let want = if bad_d {
        Some(BINGHAM_ERR_INVALID_DIMENSION)
    } else {
        match fault {
            SampleFault::Scheme | SampleFault::NonFinite => Some(BINGHAM_ERR_INVALID_ARGUMENT),
            SampleFault::Lambda if tac => Some(BINGHAM_ERR_INVALID_ARGUMENT),
            // (`reproduced` may be NULL)
            SampleFault::Pointer(i, k) if i != 5 || k != 0 => Some(BINGHAM_ERR_NULL_ARGUMENT),
            SampleFault::Capacity => Some(BINGHAM_ERR_INVALID_DIMENSION),
            // (z spanning more than a double is refused like everywhere)
            _ if span_overflows => Some(BINGHAM_ERR_INVALID_ARGUMENT),
            SampleFault::None | SampleFault::Lambda | SampleFault::Pointer(..) if moderate => {
                Some(BINGHAM_OK)
            }
            _ => None,
        }
    };
    expect(st, want, &desc)?;
    let untouched = pb.untouched()
        && wb.untouched()
        && count == [usize::MAX; 3]
        && reproduced == [REPRODUCED_SENTINEL; 3];
    if st != BINGHAM_OK {
        if !untouched {
            return Err(format!("{} but an output was written", status_name(st)));
        }
        check_error_message("bingham_deterministic_samples")?;
        if !bad_d
            && fault == SampleFault::Capacity
            && !last_error().contains(&format!("the {needed} points"))
        {
            return Err(format!("message does not give the count: {}", last_error()));
        }
        // extreme z may fail (log F's moments); every other failure was expected
        let tolerated = fault == SampleFault::SpoilM
            || (!moderate && matches!(st, BINGHAM_ERR_NUMERICAL | BINGHAM_ERR_NOT_CONVERGED));
        if want.is_none() && !tolerated {
            return Err(format!("unexpected {}: {}", status_name(st), last_error()));
        }
        return Ok(status_name(st));
    }
    // success
    let n = count[0];
    if count[1..] != [usize::MAX; 2] || reproduced[1..] != [REPRODUCED_SENTINEL; 2] {
        return Err("wrote past count / reproduced".into());
    }
    let rep = reproduced[0];
    let no_rep = fault == SampleFault::Pointer(5, 0);
    if no_rep != (rep == REPRODUCED_SENTINEL) {
        return Err(format!("reproduced = {rep:#x} (NULL passed: {no_rep})"));
    }
    let expect_n = |r: c_int| {
        if r == 4 {
            max_samples(d, BINGHAM_SAMPLES_MOMENTS)
        } else {
            2 * d - 1
        }
    };
    // 2 (second moment) or, for MOMENTS only, 4 (fourth moments too)
    let rep_ok = rep == 2 || (rep == 4 && !tac);
    if !no_rep && (!rep_ok || n != expect_n(rep)) {
        return Err(format!(
            "count {n}, reproduced {rep} (scheme {scheme}, d = {d})"
        ));
    }
    if n > needed || (n != 2 * d - 1 && n != max_samples(d, BINGHAM_SAMPLES_MOMENTS)) {
        return Err(format!("count {n} (needed {needed})"));
    }
    if !pb.guards_ok() || !wb.guards_ok() {
        return Err("wrote outside the buffers".into());
    }
    if !pb.untouched_range(n * d, rows * d) || !wb.untouched_range(n, rows) {
        return Err("wrote rows beyond count".into());
    }
    let pts = pb.values();
    let ws = wb.values();
    let mut sum = 0.0;
    for k in 0..n {
        check_unit(&pts[k * d..(k + 1) * d], 1e-12).map_err(|e| format!("point {k}: {e}"))?;
        if !(ws[k].is_finite() && ws[k] >= 0.0) {
            return Err(format!("weight {k} = {}", ws[k]));
        }
        sum += ws[k];
    }
    if (sum - 1.0).abs() > 1e-12 {
        return Err(format!("weights sum to 1 + {:e}", sum - 1.0));
    }
    // the weighted second moment is the distribution's (moderate z, d <= 8)
    if moderate && d <= 8 {
        let mut s = vec![0.0; d * d];
        // SAFETY: valid buffers of lengths d*d, d, d*d.
        let st = unsafe { bingham_second_moment(d, m.as_ptr(), z.as_ptr(), s.as_mut_ptr()) };
        if st != BINGHAM_OK {
            return Err(format!("second moment: {}", last_error()));
        }
        for r in 0..d {
            for c in 0..d {
                let v: f64 = (0..n)
                    .map(|k| ws[k] * pts[k * d + r] * pts[k * d + c])
                    .sum();
                if (v - s[r * d + c]).abs() > 1e-11 {
                    return Err(format!(
                        "E[x xᵀ][{r}][{c}] = {v} from the points, {} exact",
                        s[r * d + c]
                    ));
                }
            }
        }
    }
    Ok("OK")
}

#[test]
fn fuzz_deterministic_sample_count() {
    let n = cases_for(1.0, 10.0, SHARE_NONLINEAR);
    drive(
        "bingham_deterministic_sample_count",
        50,
        n,
        sample_count_case,
    );
}

#[test]
fn fuzz_deterministic_samples() {
    let n = cases_for(5.0, 10.0, SHARE_NONLINEAR);
    drive(
        "bingham_deterministic_samples",
        51,
        n,
        deterministic_samples_case,
    );
}
