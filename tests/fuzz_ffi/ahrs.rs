//! The AHRS: random sample streams.
//!
//! One case is an AHRS (sample time, latencies, bias_std and gyro_scale_noise sometimes hostile;
//! valid values kept, so the compensation and the bias's uncertainty run on the hostile samples
//! too) fed a simulated IMU stream through bingham_ahrs_update, bingham_ahrs_update_dt (each
//! sample's own step: nominal, jittered, over dropped samples, the bounds 1e-6 and 10 s, or
//! hostile: 0, negative, NaN/Inf, below 1e-6, above 10, subnormal, huge) and the four batch
//! functions (`_update_batch`, `_spread`, `_health`, `_timed`; the optional outputs sometimes
//! NULL; the timed batch's timestamps nominal, jittered, over dropped samples, exactly uniform,
//! or with one hostile timestamp: NaN/Inf, equal to or before the previous one, a step beyond
//! 10 s or below 1e-6 s, or exactly 10 s), with hostile samples mixed in (NaN/Inf, zero and huge
//! vectors, subnormals, NULL and misaligned pointers, also for every argument of a batch, a NaN
//! or a huge gyroscope row in the middle of a batch, the magnetometer's input overlapping the
//! accelerometer's) and bingham_ahrs_set_state calls (valid starts near the truth, any
//! orthogonal M, huge / tiny / repeated z, z spanning more than a double, non-orthogonal M,
//! NaN/Inf), and a twin that receives only the calls that were accepted (a timed batch as timed
//! batches of one sample: split anywhere, the same). A NaN/Inf entry of any sensor means "no
//! sample" of that sensor and must be accepted (the gyroscope's a gap: afterwards the health
//! readout's gyr_missing_time has grown by the step, and is 0 after a usable rate), except the
//! accelerometer of the first sample (refused: no tilt to start from); a finite gyroscope turning
//! by more than 1e6 rad in its step, a step outside 1e-6..10 s and a bad timestamp are refused.
//! After every call: a refused call leaves the AHRS
//! bit-for-bit unchanged (quaternion, state, bias, spread, orientation covariance, health
//! readout, and the hidden state, through the twin) and the message names the function (and for
//! a batch the sample; for a bad step "dt"); a batch writes the rows of the samples before the
//! refused one only, and nothing on a NULL / misaligned argument; its quaternion, spread and
//! health rows equal, bit for bit, what the twin's getters give after it replays the same samples
//! one by one; bingham_ahrs_update_dt with the nominal step equals bingham_ahrs_update on a
//! clone, and a timed batch with uniformly spaced timestamps the untimed batch on a clone, bit
//! for bit; accepted calls leave a unit quaternion with w ≥ 0, a valid Bingham state, finite
//! bias and spread, an orientation covariance symmetric positive semi-definite with the squared
//! total spread as its trace; after set_state the state is the normalized Bingham(M, z) and the
//! quaternion ± its mode.

use bingham::ffi::bingham_status::*;
use bingham::ffi::*;
use testkit::fuzz::{check_unit, non_finite, Buf};
use testkit::Rng64;

use crate::ahrs_inputs::{
    ahrs_bits, ahrs_health, ahrs_sentinel, ahrs_state_args, ahrs_state_expected, check_set_state,
    gyro_kind, spoil_sample, Gyro, Imu, STEP_RANGE,
};
use crate::drivers::{cases_for, run_sequences, SHARE_AHRS};
use crate::status::{check_error_message, last_error, prime_last_error, status_name};
use crate::vectors::expect;

fn ahrs_sequence(seed: u64, verbose: bool) -> Result<u64, String> {
    let mut rng = Rng64::new(seed);
    let mut calls = 0u64;
    // --- parameters and creation, sometimes hostile (only sample_time is set by hand: the other
    // fields of bingham_ahrs_params may change)
    let dt = match rng.below(10) {
        0 => *rng.pick(&[0.0, -0.01, f64::NAN, f64::INFINITY, -f64::INFINITY]),
        1 => *rng.pick(&[
            1e-300,
            5e-324,
            1e-6,
            1.0,
            1.0000000000000002,
            10.0,
            100.0,
            1e10,
            f64::MAX,
        ]),
        _ => *rng.pick(&[0.01, 0.005, 1.0 / 400.0, 0.02]),
    };
    // above 1 s (BINGHAM_AHRS_MAX_SAMPLE_TIME) a sample time is refused as a likely rate in Hz
    let valid_dt = (1e-6..=1.0).contains(&dt);
    // the latencies (s): valid 0..=0.5, or hostile
    let latency = |rng: &mut Rng64| match rng.below(4) {
        0 => *rng.pick(&[
            -1e-9,
            -0.01,
            0.5 + 1e-9,
            11.0,
            f64::MAX,
            f64::NAN,
            f64::INFINITY,
        ]),
        1 => *rng.pick(&[0.0, -0.0, 5e-324, 1e-3, 0.011, 0.5, -1.0]),
        _ => 0.0,
    };
    let (mag_latency, acc_latency) = (latency(&mut rng), latency(&mut rng));
    let valid_latency = |v: f64| (0.0..=0.5).contains(&v);
    // −1 (BINGHAM_AHRS_LATENCY_ESTIMATE) is a valid magnetometer latency only
    let valid_mag_latency = |v: f64| v == -1.0 || valid_latency(v);
    // bias_std (rad/s, > 0) and gyro_scale_noise (√s, ≥ 0): hostile, valid, or the default
    let hostile = [-0.0, -1e-9, -1.0, f64::NAN, f64::INFINITY, -f64::INFINITY];
    let bias_std = match rng.below(6) {
        0 => Some(*rng.pick(&[&hostile[..], &[0.0]].concat())),
        1 => Some(*rng.pick(&[1e-6, 1e-3, 0.05, 1.0])),
        _ => None,
    };
    let gyro_scale_noise = match rng.below(6) {
        0 => Some(*rng.pick(&hostile[1..])),
        1 => Some(*rng.pick(&[0.0, -0.0, 1e-6, 0.1, 1.0])),
        _ => None,
    };
    let valid_bias_std = bias_std.is_none_or(|v| v.is_finite() && v > 0.0);
    let valid_scale = gyro_scale_noise.is_none_or(|v| v.is_finite() && v >= 0.0);
    // the field the message of bingham_ahrs_new must name, in the order of the validation: the
    // fields that must be > 0 (sample_time first, bias_std last), then sample_time's range,
    // gyro_scale_noise, the latencies
    let bad_field = if !(dt.is_finite() && dt > 0.0) {
        Some("sample_time")
    } else if !valid_bias_std {
        Some("bias_std")
    } else if !valid_dt {
        Some("sample_time")
    } else if !valid_scale {
        Some("gyro_scale_noise")
    } else if !valid_mag_latency(mag_latency) {
        Some("mag_latency")
    } else if !valid_latency(acc_latency) {
        Some("acc_latency")
    } else {
        None
    };
    // SAFETY (all calls below): live handles and buffers of the documented lengths, or NULL /
    // misaligned pointers that must be refused before any access.
    let mut p: bingham_ahrs_params = unsafe { std::mem::zeroed() };
    let raw = |p: &bingham_ahrs_params| -> Vec<u8> {
        // SAFETY: a plain struct of doubles.
        unsafe {
            std::slice::from_raw_parts(
                (p as *const bingham_ahrs_params).cast::<u8>(),
                std::mem::size_of::<bingham_ahrs_params>(),
            )
        }
        .to_vec()
    };
    let before = raw(&p);
    prime_last_error("bingham_ahrs_params_default");
    let st = unsafe { bingham_ahrs_params_default(dt, &mut p) };
    calls += 1;
    if valid_dt != (st == BINGHAM_OK) || (!valid_dt && st != BINGHAM_ERR_INVALID_ARGUMENT) {
        return Err(format!("params_default({dt:e}): {}", status_name(st)));
    }
    if st != BINGHAM_OK {
        if raw(&p) != before {
            return Err("params_default wrote on error".into());
        }
        check_error_message("bingham_ahrs_params_default")?;
        // defaults for another period, then the hostile sample_time by hand
        let st = unsafe { bingham_ahrs_params_default(0.01, &mut p) };
        if st != BINGHAM_OK {
            return Err(format!("params_default(0.01): {}", last_error()));
        }
        p.sample_time = dt;
    } else if p.sample_time != dt || p.mag_latency != -1.0 || p.acc_latency != 0.0 {
        return Err(format!(
            "params_default: sample_time {} ≠ {dt} or latencies {} {} ≠ −1, 0",
            p.sample_time, p.mag_latency, p.acc_latency
        ));
    }
    p.mag_latency = mag_latency;
    p.acc_latency = acc_latency;
    if let Some(v) = bias_std {
        p.bias_std = v;
    }
    if let Some(v) = gyro_scale_noise {
        p.gyro_scale_noise = v;
    }
    let mut out = [ahrs_sentinel()];
    let null_attack = rng.chance(0.05);
    prime_last_error("bingham_ahrs_new");
    let st = unsafe {
        if null_attack {
            if rng.chance(0.5) {
                bingham_ahrs_new(std::ptr::null(), out.as_mut_ptr())
            } else {
                bingham_ahrs_new(&p, std::ptr::null_mut())
            }
        } else {
            bingham_ahrs_new(&p, out.as_mut_ptr())
        }
    };
    calls += 1;
    let want = if null_attack {
        BINGHAM_ERR_NULL_ARGUMENT
    } else if bad_field.is_some() {
        BINGHAM_ERR_INVALID_ARGUMENT
    } else {
        BINGHAM_OK
    };
    if st != want {
        return Err(format!(
            "bingham_ahrs_new (sample_time {dt:e}, latencies {mag_latency:e} {acc_latency:e}, \
             bias_std {bias_std:?}, gyro_scale_noise {gyro_scale_noise:?}): {} instead of {} ({})",
            status_name(st),
            status_name(want),
            last_error()
        ));
    }
    if st != BINGHAM_OK {
        if out[0] != ahrs_sentinel() {
            return Err("bingham_ahrs_new wrote *out on error".into());
        }
        check_error_message("bingham_ahrs_new")?;
        if let Some(field) = bad_field.filter(|_| !null_attack) {
            if !last_error().contains(field) {
                return Err(format!("message does not name {field}: {}", last_error()));
            }
        }
        let st = unsafe { bingham_ahrs_params_default(0.01, &mut p) };
        assert_eq!(st, BINGHAM_OK);
        let st = unsafe { bingham_ahrs_new(&p, out.as_mut_ptr()) };
        if st != BINGHAM_OK {
            return Err(format!("bingham_ahrs_new with defaults: {}", last_error()));
        }
    }
    let mut a = out[0];
    let mut twin: *mut bingham_ahrs = std::ptr::null_mut();
    if unsafe { bingham_ahrs_new(&p, &mut twin) } != BINGHAM_OK {
        return Err(format!("twin: {}", last_error()));
    }
    let dt = p.sample_time;
    if verbose {
        eprintln!(
            "sample_time {dt:e}, latencies {:e} {:e}, bias_std {:e}, gyro_scale_noise {:e}",
            p.mag_latency, p.acc_latency, p.bias_std, p.gyro_scale_noise
        );
    }
    let mut imu = Imu {
        q: {
            let q = rng.unit_vector(4);
            if q[0] < 0.0 {
                [-q[0], -q[1], -q[2], -q[3]]
            } else {
                [q[0], q[1], q[2], q[3]]
            }
        },
        w: [0.0; 3],
    };
    let use_mag = rng.chance(0.8);
    let steps = 5 + rng.below(40);
    // whether a sample has been accepted (the first one must have a finite accelerometer)
    let mut initialized = false;
    // the last timestamp of the timed batches (None before one and after an untimed sample)
    let mut last_t: Option<f64> = None;
    let mut result = Ok(());
    for step in 0..steps {
        let before = match ahrs_bits(a) {
            Ok(b) => b,
            Err(e) => {
                result = Err(format!("step {step}: {e}"));
                break;
            }
        };
        let r = rng.below(11);
        let res: Result<(), String> = (|| {
            if r < 6 {
                // --- one sample: bingham_ahrs_update, or bingham_ahrs_update_dt with its own
                // time step (nominal, jittered, dropped samples, the bounds, or hostile)
                let timed = rng.chance(0.4);
                let h_dt = if timed { pick_step(&mut rng, dt) } else { dt };
                let step_ok = STEP_RANGE.contains(&h_dt);
                let mut s = imu.sample(&mut rng, if step_ok { h_dt } else { dt });
                let (mut non_finite_in, mut desc) = (None, String::new());
                if rng.chance(0.25) {
                    (non_finite_in, desc) = spoil_sample(&mut rng, &mut s);
                }
                let mag_null = !use_mag || rng.chance(0.1);
                // the gyroscope: a rate, a gap (NaN/Inf: "no sample"), or refused (a turn above
                // 1e6 rad in the step); NaN/Inf in the accelerometer refuses the first sample
                // only, in the magnetometer never ("no sample" of that sensor)
                let gyro = gyro_kind(&s[0], h_dt);
                let refuse =
                    !step_ok || gyro == Gyro::Refused || (non_finite_in == Some(1) && !initialized);
                let orig = s;
                let mut bufs: Vec<Buf> = s.iter().map(|v| Buf::from(v)).collect();
                let mut ptr: Vec<*mut f64> = bufs.iter_mut().map(|b| b.ptr()).collect();
                // overlapping inputs (valid: they are only read): the field read from the
                // accelerometer's buffer, one double on
                let mut shared = Buf::from(&[s[1][0], s[1][1], s[1][2], 25.0]);
                let overlap = !mag_null && rng.chance(0.05);
                if overlap {
                    s[2] = [s[1][1], s[1][2], 25.0];
                    ptr[1] = shared.ptr();
                    ptr[2] = shared.ptr().wrapping_add(1);
                    desc += " (mag overlapping acc)";
                }
                if mag_null {
                    ptr[2] = std::ptr::null_mut();
                }
                let mut ap = a;
                let mut null = false;
                if rng.chance(0.05) {
                    null = true;
                    match rng.below(4) {
                        0 => ap = std::ptr::null_mut(),
                        1 => ptr[0] = std::ptr::null_mut(),
                        2 => ptr[1] = std::ptr::null_mut(),
                        _ => ptr[rng.below(2)] = bufs[0].misaligned(3),
                    }
                }
                let name = if timed {
                    "bingham_ahrs_update_dt"
                } else {
                    "bingham_ahrs_update"
                };
                // update_dt(sample_time) is update, bit for bit: a clone takes the update
                let same_as_update = timed && h_dt == dt && !null && rng.chance(0.5);
                let mut plain: *mut bingham_ahrs = std::ptr::null_mut();
                if same_as_update && unsafe { bingham_ahrs_clone(a, &mut plain) } != BINGHAM_OK {
                    return Err(format!("clone: {}", last_error()));
                }
                let health_before = ahrs_health(a)?;
                prime_last_error(name);
                let st = unsafe {
                    if timed {
                        bingham_ahrs_update_dt(ap, h_dt, ptr[0], ptr[1], ptr[2])
                    } else {
                        bingham_ahrs_update(ap, ptr[0], ptr[1], ptr[2])
                    }
                };
                calls += 1;
                if verbose {
                    eprintln!(
                        "step {step}: {name} dt {:e} {s:?} mag {} {desc} null {null} -> {}",
                        h_dt,
                        !mag_null,
                        status_name(st)
                    );
                }
                if st == BINGHAM_ERR_PANIC {
                    return Err(format!("panic: {}", last_error()));
                }
                let kept = bufs.iter().zip(&orig).all(|(b, v)| {
                    b.guards_ok()
                        && b.values()
                            .iter()
                            .zip(v)
                            .all(|(x, y)| x.to_bits() == y.to_bits())
                }) && shared.guards_ok()
                    && shared
                        .values()
                        .iter()
                        .zip(orig[1].iter().chain(&[25.0]))
                        .all(|(x, y)| x.to_bits() == y.to_bits());
                if !kept {
                    return Err(format!("{name} modified an input"));
                }
                let want = if null {
                    Some(BINGHAM_ERR_NULL_ARGUMENT)
                } else if refuse {
                    Some(BINGHAM_ERR_INVALID_ARGUMENT)
                } else {
                    None
                };
                expect(st, want, &desc)?;
                if st != BINGHAM_OK {
                    check_error_message(name)?;
                    if !step_ok && !null && !last_error().contains("dt") {
                        return Err(format!("the message does not name dt: {}", last_error()));
                    }
                    if ahrs_bits(a)? != before {
                        return Err(format!(
                            "refused sample ({}) changed the AHRS",
                            status_name(st)
                        ));
                    }
                    // a sample whose gyroscope, accelerometer or magnetometer is missing (NaN) is
                    // as clean as any once the AHRS has started (the gyroscope's before that too)
                    let clean = desc.is_empty()
                        || non_finite_in == Some(0)
                        || (non_finite_in.is_some() && initialized);
                    if !refuse && !null && clean && gyro != Gyro::Ambiguous && valid_dt && dt <= 0.1
                    {
                        return Err(format!("a clean sample refused: {}", last_error()));
                    }
                    if !plain.is_null() {
                        unsafe { bingham_ahrs_free(plain) };
                    }
                    return Ok(());
                }
                // the twin gets the same values from separate buffers
                let mp = if mag_null {
                    std::ptr::null()
                } else {
                    s[2].as_ptr()
                };
                let st2 = unsafe {
                    if timed {
                        bingham_ahrs_update_dt(twin, h_dt, s[0].as_ptr(), s[1].as_ptr(), mp)
                    } else {
                        bingham_ahrs_update(twin, s[0].as_ptr(), s[1].as_ptr(), mp)
                    }
                };
                if st2 != BINGHAM_OK {
                    return Err(format!("twin refused an accepted sample: {}", last_error()));
                }
                if !plain.is_null() {
                    let st3 =
                        unsafe { bingham_ahrs_update(plain, s[0].as_ptr(), s[1].as_ptr(), mp) };
                    let same = st3 == BINGHAM_OK && ahrs_bits(plain)? == ahrs_bits(a)?;
                    unsafe { bingham_ahrs_free(plain) };
                    if !same {
                        return Err(format!(
                            "update_dt(sample_time) differs from update ({})",
                            status_name(st3)
                        ));
                    }
                }
                // the gyroscope's missing time: 0 after a rate, grown by the step after a gap
                let h = ahrs_health(a)?;
                let grown = health_before.gyr_missing_time + h_dt;
                let ok = match gyro {
                    Gyro::Usable => h.gyr_missing_time == 0.0,
                    Gyro::Gap if initialized => {
                        (h.gyr_missing_time - grown).abs() <= 1e-6 * h_dt + 1e-12 * grown
                    }
                    _ => true,
                };
                if !ok {
                    return Err(format!(
                        "gyr_missing_time {:e} after a {gyro:?} gyroscope sample (before {:e}, step {h_dt:e})",
                        h.gyr_missing_time, health_before.gyr_missing_time
                    ));
                }
                initialized = true;
                last_t = None;
                ahrs_bits(a)?;
            } else if r < 8 {
                // --- a batch: untimed (quaternions only, with the spread, with the spread and
                // the health score; each optional output sometimes NULL: not wanted) or timed
                // (with the spread and the health score), possibly with a NaN/Inf entry at
                // sample k, a gyroscope row turning too far, or a bad timestamp
                let variant = rng.below(4);
                let timed = variant == 3;
                let with_spread = variant >= 1;
                let with_health = variant >= 2;
                let n = rng.below(13);
                // the timestamps (timed): from the last one of the previous timed batch (its
                // step the first sample's) or any origin, the steps nominal, jittered or over
                // dropped samples, sometimes exactly uniform
                let uniform = rng.chance(0.3);
                let mut t = vec![0.0; n];
                let mut prev = last_t.unwrap_or(*rng.pick(&[0.0, -5.0, 1.0, 1e3, 12345.678, 1e9]));
                for tk in t.iter_mut() {
                    let h = if uniform {
                        dt
                    } else {
                        match rng.below(6) {
                            0..=2 => dt,
                            3 => dt * rng.range(0.7, 1.3),
                            4 => dt * (2 + rng.below(4)) as f64,
                            _ => dt * rng.range(0.2, 0.9),
                        }
                    };
                    *tk = prev + h;
                    prev = *tk;
                }
                // a hostile timestamp: not finite, not after the previous one, a step beyond
                // 10 s or below 1e-6 s, or exactly 10 s (valid)
                let mut t_desc = String::new();
                if timed && n > 0 && rng.chance(0.25) {
                    let k = rng.below(n);
                    let p = if k > 0 {
                        t[k - 1]
                    } else {
                        last_t.unwrap_or(t[0] - dt)
                    };
                    t[k] = match rng.below(8) {
                        0 => non_finite(&mut rng),
                        1 => p,
                        2 => p - dt * rng.range(0.0, 3.0),
                        3 => p + 10.0 + rng.range(1e-6, 5.0),
                        4 => p + 1e-7 * p.abs().max(1.0),
                        5 => p + 10.0,
                        6 => p + 1e-6,
                        _ => -p,
                    };
                    for j in k + 1..n {
                        t[j] = t[j - 1] + dt;
                    }
                    t_desc = format!("t[{k}] = {:e} (previous {p:e})", t[k]);
                }
                let mut g = vec![0.0; 3 * n];
                let mut ac = vec![0.0; 3 * n];
                let mut mg = vec![0.0; 3 * n];
                for k in 0..n {
                    let h = if timed {
                        let d = if k > 0 {
                            t[k] - t[k - 1]
                        } else {
                            last_t.map_or(dt, |l| t[0] - l)
                        };
                        if STEP_RANGE.contains(&d) {
                            d
                        } else {
                            dt
                        }
                    } else {
                        dt
                    };
                    let s = imu.sample(&mut rng, h);
                    g[3 * k..3 * k + 3].copy_from_slice(&s[0]);
                    ac[3 * k..3 * k + 3].copy_from_slice(&s[1]);
                    mg[3 * k..3 * k + 3].copy_from_slice(&s[2]);
                }
                let mag_null = !use_mag;
                // (sample, 0 gyroscope / 1 accelerometer / 2 magnetometer) with a NaN/Inf entry:
                // "no sample" of that sensor, except the accelerometer of the first sample of an
                // AHRS not yet started
                let spoiled = (n > 0 && rng.chance(0.4))
                    .then(|| (rng.below(n), rng.below(if mag_null { 2 } else { 3 })));
                if let Some((k, which)) = spoiled {
                    let arr = match which {
                        0 => &mut g,
                        1 => &mut ac,
                        _ => &mut mg,
                    };
                    arr[3 * k + rng.below(3)] = non_finite(&mut rng);
                }
                // a huge gyroscope row: refused if it turns by more than 1e6 rad (its norm
                // overflowing included), else used
                let mut huge = None;
                if n > 0 && rng.chance(0.1) {
                    let k = rng.below(n);
                    let v = *rng.pick(&[1e3, 1e7, 1e9, 1e12, 1e150, 1e200, f64::MAX]);
                    g[3 * k..3 * k + 3].copy_from_slice(&[v, -v, 0.5 * v]);
                    huge = Some((k, v));
                }
                // the sample that must stop the batch, in order: a bad timestamp or step, a
                // gyroscope turning too far, the first sample without an accelerometer
                let mut bad = None;
                let mut uncertain = false;
                {
                    let mut prev_t = last_t;
                    let mut started = initialized;
                    for k in 0..n {
                        let h = if timed {
                            let d = prev_t.map_or(dt, |l| t[k] - l);
                            if !t[k].is_finite() || d <= 0.0 || !STEP_RANGE.contains(&d) {
                                bad = Some(k);
                                break;
                            }
                            prev_t = Some(t[k]);
                            d
                        } else {
                            dt
                        };
                        match gyro_kind(&g[3 * k..3 * k + 3], h) {
                            Gyro::Refused => {
                                bad = Some(k);
                                break;
                            }
                            Gyro::Ambiguous => uncertain = true,
                            _ => {}
                        }
                        if !started && ac[3 * k..3 * k + 3].iter().any(|v| !v.is_finite()) {
                            bad = Some(k);
                            break;
                        }
                        started = true;
                    }
                }
                let spread_null = with_spread && rng.chance(0.3);
                let health_null = with_health && rng.chance(0.3);
                // overlapping inputs (valid: only read): the field read from the accelerometer's
                // rows, one double on
                let overlap = !mag_null && n > 0 && rng.chance(0.1);
                let mut ac_ext = ac.clone();
                ac_ext.push(25.0);
                if overlap {
                    mg = ac_ext[1..].to_vec();
                }
                let (mut bt, mut bg) = (Buf::from(&t), Buf::from(&g));
                let (mut ba, mut bm) = (Buf::from(&ac_ext), Buf::from(&mg));
                let mut bq = Buf::sentinel(4 * n);
                let mut bs = Buf::sentinel(n);
                let mut bh = Buf::sentinel(n);
                let mut ap = a;
                let mut tp = bt.ptr() as *const f64;
                let mut gp = bg.ptr() as *const f64;
                let mut acp = ba.ptr() as *const f64;
                let mut mp = if mag_null {
                    std::ptr::null()
                } else if overlap {
                    ba.ptr().wrapping_add(1) as *const f64
                } else {
                    bm.ptr() as *const f64
                };
                let mut qp = bq.ptr();
                let mut sp = if spread_null {
                    std::ptr::null_mut()
                } else {
                    bs.ptr()
                };
                let mut hp = if health_null {
                    std::ptr::null_mut()
                } else {
                    bh.ptr()
                };
                // a NULL / misaligned argument (the arrays only for n > 0: no array is read
                // for n = 0), refused before any sample; NULL means "none" for mag, spread and
                // health, so those are only misaligned
                let mut attack = String::new();
                if rng.chance(0.08) {
                    let which = rng.below(if n > 0 { 8 } else { 1 });
                    let null = (which < 4 || which == 7) && rng.chance(0.5);
                    let off = 1 + rng.below(7);
                    let passed = match which {
                        4 => !mag_null,
                        5 => with_spread && !spread_null,
                        6 => with_health && !health_null,
                        7 => timed,
                        _ => true,
                    };
                    if passed {
                        match (which, null) {
                            (0, true) => ap = std::ptr::null_mut(),
                            (0, false) => ap = a.cast::<u8>().wrapping_add(4).cast(),
                            (1, true) => gp = std::ptr::null(),
                            (1, false) => gp = bg.misaligned(off),
                            (2, true) => acp = std::ptr::null(),
                            (2, false) => acp = ba.misaligned(off),
                            (3, true) => qp = std::ptr::null_mut(),
                            (3, false) => qp = bq.misaligned(off),
                            (4, _) => mp = bm.misaligned(off),
                            (5, _) => sp = bs.misaligned(off),
                            (6, _) => hp = bh.misaligned(off),
                            (_, true) => tp = std::ptr::null(),
                            _ => tp = bt.misaligned(off),
                        }
                        let arg =
                            ["a", "gyr", "acc", "quat", "mag", "spread", "health", "t"][which];
                        attack = if null {
                            format!("{arg} NULL")
                        } else {
                            format!("{arg} misaligned")
                        };
                    }
                }
                let name = match variant {
                    0 => "bingham_ahrs_update_batch",
                    1 => "bingham_ahrs_update_batch_spread",
                    2 => "bingham_ahrs_update_batch_health",
                    _ => "bingham_ahrs_update_batch_timed",
                };
                // uniformly spaced timestamps: the timed batch is the untimed one, bit for bit
                // (an untimed batch on a clone compares). Not where a step rounds below 1e-6 s
                // (sample_time = 1e-6): the library checks the step's range before it takes a
                // step within a millionth of sample_time as sample_time, and refuses it
                // (reported, not fixed here).
                let comparable = timed
                    && attack.is_empty()
                    && t_desc.is_empty()
                    && (0..n).all(|k| {
                        let d = if k > 0 {
                            t[k] - t[k - 1]
                        } else {
                            last_t.map_or(dt, |l| t[0] - l)
                        };
                        (d - dt).abs() <= 1e-7 * dt && STEP_RANGE.contains(&d)
                    });
                let mut plain: *mut bingham_ahrs = std::ptr::null_mut();
                if comparable && unsafe { bingham_ahrs_clone(a, &mut plain) } != BINGHAM_OK {
                    return Err(format!("clone: {}", last_error()));
                }
                prime_last_error(name);
                let st = unsafe {
                    match variant {
                        0 => bingham_ahrs_update_batch(ap, n, gp, acp, mp, qp),
                        1 => bingham_ahrs_update_batch_spread(ap, n, gp, acp, mp, qp, sp),
                        2 => bingham_ahrs_update_batch_health(ap, n, gp, acp, mp, qp, sp, hp),
                        _ => bingham_ahrs_update_batch_timed(ap, n, tp, gp, acp, mp, qp, sp, hp),
                    }
                };
                calls += 1;
                if verbose {
                    eprintln!(
                        "step {step}: {name} n = {n}, spoiled {spoiled:?}, huge {huge:?}, {t_desc} \
                         t {t:?}, overlap {overlap}, bad {bad:?} {attack} -> {}",
                        status_name(st)
                    );
                }
                if st == BINGHAM_ERR_PANIC {
                    return Err(format!("panic: {}", last_error()));
                }
                let inputs_kept = |b: &Buf, v: &[f64]| {
                    b.guards_ok()
                        && b.values()
                            .iter()
                            .zip(v)
                            .all(|(x, y)| x.to_bits() == y.to_bits())
                };
                if !inputs_kept(&bt, &t)
                    || !inputs_kept(&bg, &g)
                    || !inputs_kept(&ba, &ac_ext)
                    || !inputs_kept(&bm, &mg)
                {
                    return Err(format!("{name} modified an input"));
                }
                if !attack.is_empty() {
                    expect(
                        st,
                        Some(BINGHAM_ERR_NULL_ARGUMENT),
                        &format!("{name} ({attack})"),
                    )?;
                    check_error_message(name)?;
                    if !bq.untouched() || !bs.untouched() || !bh.untouched() {
                        return Err(format!("{name} ({attack}) wrote an output"));
                    }
                    if ahrs_bits(a)? != before {
                        return Err(format!("{name} ({attack}) changed the AHRS"));
                    }
                    return Ok(());
                }
                if !uncertain {
                    expect(
                        st,
                        bad.map(|_| BINGHAM_ERR_INVALID_ARGUMENT),
                        &format!("bad sample {bad:?} ({t_desc})"),
                    )?;
                }
                // how many samples were processed
                let done = if st == BINGHAM_OK {
                    n
                } else {
                    check_error_message(name)?;
                    let msg = last_error();
                    let k = msg
                        .split("sample ")
                        .nth(1)
                        .and_then(|t| t.split(|c: char| !c.is_ascii_digit()).next())
                        .and_then(|t| t.parse::<usize>().ok())
                        .ok_or_else(|| format!("message does not name the sample: {msg}"))?;
                    if (!uncertain && bad.is_some_and(|b| b != k)) || k >= n {
                        return Err(format!(
                            "stopped at sample {k}, the bad one is {bad:?}: {msg}"
                        ));
                    }
                    // only the bad sample may stop a batch of simulated samples (a missing
                    // gyroscope, accelerometer or magnetometer does not)
                    if bad.is_none() && !uncertain && valid_dt && dt <= 0.1 {
                        return Err(format!(
                            "a batch stopped at sample {k} (spoiled {spoiled:?}, huge {huge:?}): {msg}"
                        ));
                    }
                    k
                };
                let q = bq.values();
                let s = bs.values();
                let h = bh.values();
                if !bq.guards_ok() || !bs.guards_ok() || !bh.guards_ok() {
                    return Err("guard words overwritten".into());
                }
                for k in 0..done {
                    let row = &q[4 * k..4 * k + 4];
                    check_unit(row, 1e-12).map_err(|e| format!("quat row {k}: {e}"))?;
                    if row[0] < 0.0 {
                        return Err(format!("quat row {k} with w < 0"));
                    }
                }
                if !bq.untouched_range(4 * done, 4 * n) {
                    return Err(format!(
                        "quat rows from the refused sample {done} on were written"
                    ));
                }
                for (wanted, null, b, what) in [
                    (with_spread, spread_null, &bs, "spread"),
                    (with_health, health_null, &bh, "health"),
                ] {
                    if (null || !wanted) && !b.untouched() {
                        return Err(format!("{what} written although not passed"));
                    }
                    if wanted && !null && !b.untouched_range(done, n) {
                        return Err(format!("{what} written from the refused sample on"));
                    }
                }
                // uniform timestamps: the untimed batch on the clone gives the same
                if !plain.is_null() {
                    let mut q2 = vec![0.0; 4 * n];
                    let (mut s2, mut h2) = (vec![0.0; n], vec![0.0; n]);
                    let st2 = unsafe {
                        bingham_ahrs_update_batch_health(
                            plain,
                            n,
                            g.as_ptr(),
                            ac.as_ptr(),
                            if mag_null {
                                std::ptr::null()
                            } else {
                                mg.as_ptr()
                            },
                            q2.as_mut_ptr(),
                            s2.as_mut_ptr(),
                            h2.as_mut_ptr(),
                        )
                    };
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    let same = st2 == st
                        && bits(&q[..4 * done]) == bits(&q2[..4 * done])
                        && (spread_null || bits(&s[..done]) == bits(&s2[..done]))
                        && (health_null || bits(&h[..done]) == bits(&h2[..done]))
                        && ahrs_bits(plain)? == ahrs_bits(a)?;
                    unsafe { bingham_ahrs_free(plain) };
                    if !same {
                        return Err(format!(
                            "timed batch with uniform timestamps differs from the untimed one ({} vs {})",
                            status_name(st),
                            status_name(st2)
                        ));
                    }
                }
                // the twin replays the processed samples one by one (a timed batch as batches of
                // one sample: split anywhere, the same): the same quaternion, total spread and
                // health score after each
                for k in 0..done {
                    let mp = if mag_null {
                        std::ptr::null()
                    } else {
                        mg[3 * k..].as_ptr()
                    };
                    let st = unsafe {
                        if timed {
                            let mut one = [0.0; 4];
                            bingham_ahrs_update_batch_timed(
                                twin,
                                1,
                                t[k..].as_ptr(),
                                g[3 * k..].as_ptr(),
                                ac[3 * k..].as_ptr(),
                                mp,
                                one.as_mut_ptr(),
                                std::ptr::null_mut(),
                                std::ptr::null_mut(),
                            )
                        } else {
                            bingham_ahrs_update(twin, g[3 * k..].as_ptr(), ac[3 * k..].as_ptr(), mp)
                        }
                    };
                    if st != BINGHAM_OK {
                        return Err(format!(
                            "twin refused sample {k} of an accepted batch: {}",
                            last_error()
                        ));
                    }
                    let (mut tq, mut ts) = ([0.0; 4], [0.0; 4]);
                    let sts = unsafe {
                        [
                            bingham_ahrs_quaternion(twin, tq.as_mut_ptr()),
                            bingham_ahrs_angular_spread(twin, ts.as_mut_ptr()),
                        ]
                    };
                    if sts.iter().any(|&st| st != BINGHAM_OK) {
                        return Err(format!("twin getters: {}", last_error()));
                    }
                    let th = ahrs_health(twin)?;
                    let same = |x: &[f64], y: &[f64]| {
                        x.iter().zip(y).all(|(a, b)| a.to_bits() == b.to_bits())
                    };
                    if !same(&q[4 * k..4 * k + 4], &tq) {
                        return Err(format!(
                            "quat row {k} {:?} differs from the twin's {tq:?}",
                            &q[4 * k..4 * k + 4]
                        ));
                    }
                    if with_spread && !spread_null && s[k].to_bits() != ts[3].to_bits() {
                        return Err(format!(
                            "spread[{k}] = {:e}, the twin's total spread {:e}",
                            s[k], ts[3]
                        ));
                    }
                    if with_health && !health_null && h[k].to_bits() != th.score.to_bits() {
                        return Err(format!(
                            "health[{k}] = {:e}, the twin's health score {:e}",
                            h[k], th.score
                        ));
                    }
                }
                if done == 0 && ahrs_bits(a)? != before {
                    return Err("a batch refused at sample 0 changed the AHRS".into());
                }
                initialized |= done > 0;
                if done > 0 {
                    last_t = if timed { Some(t[done - 1]) } else { None };
                }
            } else if r < 9 {
                // --- getters with NULL / misaligned arguments
                let which = rng.below(9);
                let null_handle = rng.chance(0.5);
                let mut buf = Buf::sentinel(16);
                let mut buf2 = Buf::sentinel(4);
                let op = if rng.chance(0.5) {
                    std::ptr::null_mut()
                } else {
                    buf.misaligned(4)
                };
                let (ap, o1, o2) = if null_handle {
                    (std::ptr::null(), buf.ptr(), buf2.ptr())
                } else if which == 1 && rng.chance(0.5) {
                    (a as *const _, buf.ptr(), op)
                } else {
                    (a as *const _, op, buf2.ptr())
                };
                let (name, st) = unsafe {
                    match which {
                        0 => ("bingham_ahrs_quaternion", bingham_ahrs_quaternion(ap, o1)),
                        1 => ("bingham_ahrs_state", bingham_ahrs_state(ap, o1, o2)),
                        2 => ("bingham_ahrs_gyro_bias", bingham_ahrs_gyro_bias(ap, o1)),
                        3 => (
                            "bingham_ahrs_gyro_bias_covariance",
                            bingham_ahrs_gyro_bias_covariance(ap, o1),
                        ),
                        4 => (
                            "bingham_ahrs_mag_latency_estimate",
                            bingham_ahrs_mag_latency_estimate(ap, o1),
                        ),
                        5 => ("bingham_ahrs_health", bingham_ahrs_health(ap, o1.cast())),
                        6 => (
                            "bingham_ahrs_orientation_covariance",
                            bingham_ahrs_orientation_covariance(ap, o1),
                        ),
                        7 => ("bingham_ahrs_gyro_scale", bingham_ahrs_gyro_scale(ap, o1)),
                        _ => (
                            "bingham_ahrs_angular_spread",
                            bingham_ahrs_angular_spread(ap, o1),
                        ),
                    }
                };
                calls += 1;
                expect(st, Some(BINGHAM_ERR_NULL_ARGUMENT), name)?;
                check_error_message(name)?;
                if !buf.untouched() || !buf2.untouched() {
                    return Err(format!("{name} wrote on error"));
                }
            } else if r < 10 {
                // --- clone (sometimes with NULL / misaligned arguments); continue with the copy
                let mut c = [ahrs_sentinel()];
                let attack = rng.below(8);
                let st = unsafe {
                    match attack {
                        0 => bingham_ahrs_clone(std::ptr::null(), c.as_mut_ptr()),
                        1 => bingham_ahrs_clone(a, std::ptr::null_mut()),
                        2 => bingham_ahrs_clone(
                            a,
                            c.as_mut_ptr().cast::<u8>().wrapping_add(3).cast(),
                        ),
                        _ => bingham_ahrs_clone(a, c.as_mut_ptr()),
                    }
                };
                calls += 1;
                if attack <= 2 {
                    expect(st, Some(BINGHAM_ERR_NULL_ARGUMENT), "clone")?;
                    check_error_message("bingham_ahrs_clone")?;
                    if c[0] != ahrs_sentinel() {
                        return Err("clone wrote *out on error".into());
                    }
                    return Ok(());
                }
                if st != BINGHAM_OK {
                    return Err(format!("clone: {}", last_error()));
                }
                if ahrs_bits(c[0])? != before {
                    unsafe { bingham_ahrs_free(c[0]) };
                    return Err("the clone differs from the original".into());
                }
                unsafe {
                    if rng.chance(0.5) {
                        bingham_ahrs_free(a);
                        a = c[0];
                    } else {
                        bingham_ahrs_free(c[0]);
                    }
                }
            } else {
                // --- set_state: a start / re-initialization Bingham(M, z), or hostile
                let (m, z, mut desc) = ahrs_state_args(&mut rng, &imu.q);
                let mut want = ahrs_state_expected(&m, &z);
                let (mut bm, mut bz) = (Buf::from(&m), Buf::from(&z));
                let (mut ap, mut mp, mut zp) = (a, bm.ptr() as *const f64, bz.ptr() as *const f64);
                if rng.chance(0.1) {
                    let null = rng.chance(0.5);
                    match rng.below(3) {
                        0 if null => ap = std::ptr::null_mut(),
                        0 => ap = a.cast::<u8>().wrapping_add(4).cast(),
                        1 if null => mp = std::ptr::null(),
                        1 => mp = bm.misaligned(1 + rng.below(7)),
                        _ if null => zp = std::ptr::null(),
                        _ => zp = bz.misaligned(1 + rng.below(7)),
                    }
                    desc = format!("{desc} (NULL / misaligned: a {ap:p} m {mp:p} z {zp:p})");
                    want = Some(BINGHAM_ERR_NULL_ARGUMENT);
                }
                prime_last_error("bingham_ahrs_set_state");
                let st = unsafe { bingham_ahrs_set_state(ap, mp, zp) };
                calls += 1;
                if verbose {
                    eprintln!(
                        "step {step}: set_state M {m:?} z {z:?} {desc} -> {}",
                        status_name(st)
                    );
                }
                if st == BINGHAM_ERR_PANIC {
                    return Err(format!("panic: {}", last_error()));
                }
                let same = |b: &Buf, v: &[f64]| {
                    b.guards_ok()
                        && b.values()
                            .iter()
                            .zip(v)
                            .all(|(x, y)| x.to_bits() == y.to_bits())
                };
                if !same(&bm, &m) || !same(&bz, &z) {
                    return Err(format!("set_state modified its input ({desc})"));
                }
                expect(st, want, &format!("bingham_ahrs_set_state ({desc})"))?;
                if st != BINGHAM_OK {
                    check_error_message("bingham_ahrs_set_state")?;
                    if ahrs_bits(a)? != before {
                        return Err(format!(
                            "refused set_state ({}, {desc}) changed the AHRS",
                            status_name(st)
                        ));
                    }
                    return Ok(());
                }
                let st2 = unsafe { bingham_ahrs_set_state(twin, m.as_ptr(), z.as_ptr()) };
                if st2 != BINGHAM_OK {
                    return Err(format!(
                        "twin refused an accepted set_state: {}",
                        last_error()
                    ));
                }
                ahrs_bits(a)?;
                check_set_state(a, &m, &z).map_err(|e| format!("set_state ({desc}): {e}"))?;
            }
            Ok(())
        })();
        if let Err(e) = res {
            result = Err(format!("step {step}: {e}"));
            break;
        }
        match (ahrs_bits(a), ahrs_bits(twin)) {
            (Ok(x), Ok(y)) if x == y => {}
            (Ok(_), Ok(_)) => {
                result = Err(format!(
                    "step {step}: the twin (fed only the accepted samples) differs: a refused sample changed hidden state"
                ));
                break;
            }
            (Err(e), _) | (_, Err(e)) => {
                result = Err(format!("step {step}: {e}"));
                break;
            }
        }
    }
    unsafe {
        bingham_ahrs_free(a);
        bingham_ahrs_free(twin);
        bingham_ahrs_free(std::ptr::null_mut());
    }
    result.map(|()| calls)
}

/// A sample's own time step for `bingham_ahrs_update_dt` (`dt` the nominal period): mostly the
/// nominal period, jittered or spanning dropped samples, sometimes the bounds of the valid
/// range, or hostile (0, negative, NaN/Inf, below 1e-6 s, above 10 s, subnormal, huge).
fn pick_step(rng: &mut Rng64, dt: f64) -> f64 {
    match rng.below(10) {
        0..=3 => dt,
        4 => dt * rng.range(0.7, 1.3),
        5 => dt * (2 + rng.below(5)) as f64,
        6 => *rng.pick(&[1e-6, 10.0, 0.5, 2.5, dt * (1.0 + 1e-9)]),
        _ => *rng.pick(&[
            0.0,
            -0.0,
            -dt,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            1e-7,
            9.99e-7,
            10.000001,
            11.0,
            1e300,
            5e-324,
            -1e-300,
            f64::MAX,
        ]),
    }
}

#[test]
fn fuzz_ahrs_sequences() {
    run_sequences(
        "bingham_ahrs",
        "ahrs",
        98,
        cases_for(1.0, 1.0, SHARE_AHRS),
        ahrs_sequence,
    );
}
