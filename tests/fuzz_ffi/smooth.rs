//! The offline smoother's exports (`bingham_ahrs_smooth`, `bingham_ahrs_smooth_ex`) with hostile
//! input: n = 0, 1, small and (rarely) a few hundred, NULL and misaligned pointers, NaN/Inf
//! rows and single entries, huge and subnormal values, zero and tiny accelerometer rows,
//! timestamps not increasing or too far apart, bad parameters. Checks: no panic, a known
//! status, NULL/misaligned → `NULL_ARGUMENT`, inputs unchanged, on an error every output
//! untouched (and the last error message names the function), on success every output written:
//! unit quaternions with w ≥ 0, finite spreads ≥ 0 equal to the square root of the covariance's
//! trace, symmetric covariances, finite biases.

use bingham::ffi::bingham_status::*;
use bingham::ffi::*;
use testkit::fuzz::{non_finite, Buf};
use testkit::Rng64;

use crate::drivers::{cases_for, run_sequences, SHARE_AHRS};
use crate::status::{check_error_message, prime_last_error, status_name};
use crate::vectors::expect;

/// A hostile value for one entry.
fn hostile(rng: &mut Rng64) -> f64 {
    match rng.below(4) {
        0 => non_finite(rng),
        1 => *rng.pick(&[1e300, -1e300, f64::MAX, 5e-324, -0.0, 1e-300]),
        2 => 0.0,
        _ => rng.range(-1e6, 1e6),
    }
}

fn smooth_case(seed: u64, verbose: bool) -> Result<u64, String> {
    let mut rng = Rng64::new(seed);
    let dt = if rng.chance(0.05) {
        *rng.pick(&[0.0, -0.01, f64::NAN, 1e-7, 2.0])
    } else {
        *rng.pick(&[0.01, 0.005, 1.0 / 286.0, 0.02])
    };
    let mut p: bingham_ahrs_params = unsafe { std::mem::zeroed() };
    // a bad period makes the default call fail: then keep the zeroed struct (itself invalid)
    let _ = unsafe { bingham_ahrs_params_default(dt, &mut p) };
    if rng.chance(0.05) {
        p.gyro_noise = hostile(&mut rng);
    }
    p.sample_time = dt;
    let n = match rng.below(10) {
        0 => 0,
        1 => 1,
        2 => 2,
        3 => 150 + rng.below(300),
        _ => 3 + rng.below(60),
    };
    // a plausible recording: a slow turn, gravity, a field; then spoiled here and there
    let mut g = Vec::with_capacity(3 * n);
    let mut a = Vec::with_capacity(3 * n);
    let mut m = Vec::with_capacity(3 * n);
    for k in 0..n {
        let t = k as f64 * 0.01;
        let c = (0.7 * t).cos();
        let s = (0.7 * t).sin();
        g.extend([
            0.1 * s + 0.01 * rng.normal(),
            0.2 * c,
            0.3 + 0.01 * rng.normal(),
        ]);
        a.extend([0.5 * s, 0.3 * c, 9.8 + 0.05 * rng.normal()]);
        m.extend([20.0 * c, 20.0 * s, -40.0 + rng.normal()]);
    }
    let mut t: Vec<f64> = (0..n)
        .map(|k| 3.0 + k as f64 * dt.abs().max(1e-6))
        .collect();
    let mut spoiled = Vec::new();
    if n > 0 {
        for _ in 0..rng.below(4) {
            let k = rng.below(n);
            let which = rng.below(5);
            let arr = match which {
                0 => &mut g,
                1 => &mut a,
                2 => &mut m,
                3 => &mut t,
                _ => &mut a,
            };
            if which == 3 {
                arr[k] = if rng.chance(0.5) {
                    hostile(&mut rng)
                } else {
                    arr[k.saturating_sub(1)]
                };
            } else if which == 4 || rng.chance(0.5) {
                // a whole row: no sample (or, for the accelerometer, no gravity)
                let v = if which == 4 { 0.0 } else { f64::NAN };
                arr[3 * k..3 * k + 3].fill(v);
            } else {
                arr[3 * k + rng.below(3)] = hostile(&mut rng);
            }
            spoiled.push((which, k));
        }
    }
    let extended = rng.chance(0.5);
    let with_mag = rng.chance(0.8);
    let with_spread = rng.chance(0.7);
    let with_t = extended && rng.chance(0.5);
    let with_bias = extended && rng.chance(0.5);
    let with_cov = extended && rng.chance(0.5);
    let (mut bt, mut bg, mut ba, mut bm) =
        (Buf::from(&t), Buf::from(&g), Buf::from(&a), Buf::from(&m));
    let (mut bq, mut bs, mut bb, mut bc) = (
        Buf::sentinel(4 * n),
        Buf::sentinel(n),
        Buf::sentinel(3 * n),
        Buf::sentinel(9 * n),
    );
    let mut pp: *const bingham_ahrs_params = &p;
    let tp = if with_t {
        bt.ptr() as *const f64
    } else {
        std::ptr::null()
    };
    let mut gp = bg.ptr() as *const f64;
    let mut ap = ba.ptr() as *const f64;
    let mp = if with_mag {
        bm.ptr() as *const f64
    } else {
        std::ptr::null()
    };
    let mut qp = bq.ptr();
    let mut sp = if with_spread {
        bs.ptr()
    } else {
        std::ptr::null_mut()
    };
    let bp = if with_bias {
        bb.ptr()
    } else {
        std::ptr::null_mut()
    };
    let cp = if with_cov {
        bc.ptr()
    } else {
        std::ptr::null_mut()
    };
    let mut attack = "";
    if rng.chance(0.1) {
        let off = 1 + rng.below(7);
        match rng.below(6) {
            0 => (pp, attack) = (std::ptr::null(), "p NULL"),
            1 => (gp, attack) = (std::ptr::null(), "gyr NULL"),
            2 => (ap, attack) = (ba.misaligned(off), "acc misaligned"),
            3 => (qp, attack) = (std::ptr::null_mut(), "quat NULL"),
            4 if with_spread => (sp, attack) = (bs.misaligned(off), "spread misaligned"),
            _ => (gp, attack) = (bg.misaligned(off), "gyr misaligned"),
        }
    }
    let name = if extended {
        "bingham_ahrs_smooth_ex"
    } else {
        "bingham_ahrs_smooth"
    };
    prime_last_error(name);
    let st = unsafe {
        if extended {
            bingham_ahrs_smooth_ex(pp, n, tp, gp, ap, mp, qp, sp, bp, cp)
        } else {
            bingham_ahrs_smooth(pp, n, gp, ap, mp, qp, sp)
        }
    };
    if verbose {
        eprintln!(
            "{name} n = {n}, dt = {dt}, spoiled {spoiled:?}, mag {with_mag}, t {with_t}, {attack} -> {}",
            status_name(st)
        );
    }
    if st == BINGHAM_ERR_PANIC {
        return Err(format!("{name} panicked"));
    }
    let kept = |b: &Buf, v: &[f64]| {
        b.guards_ok()
            && b.values()
                .iter()
                .zip(v)
                .all(|(x, y)| x.to_bits() == y.to_bits())
    };
    if !(kept(&bt, &t) && kept(&bg, &g) && kept(&ba, &a) && kept(&bm, &m)) {
        return Err(format!("{name} modified an input"));
    }
    if !attack.is_empty() {
        expect(
            st,
            Some(BINGHAM_ERR_NULL_ARGUMENT),
            &format!("{name} {attack}"),
        )?;
    }
    if st != BINGHAM_OK {
        if !(bq.untouched() && bs.untouched() && bb.untouched() && bc.untouched()) {
            return Err(format!(
                "{name} failed ({}) but wrote an output",
                status_name(st)
            ));
        }
        check_error_message(name)?;
        return Ok(1);
    }
    // success: every requested output written, and consistent
    if !(bq.guards_ok() && bs.guards_ok() && bb.guards_ok() && bc.guards_ok()) {
        return Err(format!("{name} wrote outside an output"));
    }
    if !bq.fully_written() {
        return Err(format!("{name}: quat not fully written"));
    }
    let q = bq.values();
    let s = bs.values();
    let b = bb.values();
    let c = bc.values();
    for k in 0..n {
        let r = &q[4 * k..4 * k + 4];
        let norm = r.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !((norm - 1.0).abs() < 1e-9 && r[0] >= 0.0) {
            return Err(format!(
                "{name}: quat row {k} = {r:?} not a unit quaternion with w ≥ 0"
            ));
        }
        if with_spread && !(s[k].is_finite() && s[k] >= 0.0) {
            return Err(format!("{name}: spread {k} = {}", s[k]));
        }
        if with_bias && !b[3 * k..3 * k + 3].iter().all(|x| x.is_finite()) {
            return Err(format!("{name}: bias row {k} not finite"));
        }
        if with_cov {
            let r = &c[9 * k..9 * k + 9];
            if !(r.iter().all(|x| x.is_finite()) && r[1] == r[3] && r[2] == r[6] && r[5] == r[7]) {
                return Err(format!("{name}: covariance row {k} = {r:?}"));
            }
            if with_spread {
                let tr = (r[0] + r[4] + r[8]).max(0.0).sqrt();
                if (tr - s[k]).abs() > 1e-6 * s[k].max(1e-300) {
                    return Err(format!("{name}: spread {} vs covariance trace {tr}", s[k]));
                }
            }
        }
    }
    Ok(1)
}

#[test]
fn fuzz_smooth() {
    run_sequences(
        "bingham_ahrs_smooth",
        "smooth",
        99,
        cases_for(0.2, 1.0, SHARE_AHRS),
        smooth_case,
    );
}
