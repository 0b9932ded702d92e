//! The AHRS on a simulated IMU: a known smooth motion (body rate a sum of sinusoids, integrated
//! finely), gyroscope with bias and white noise, accelerometer (gravity, noise and bursts of
//! linear acceleration), magnetometer (a dipping field with noise). Checks accuracy, bias
//! estimation, heading observability, initialization, and that refused samples change nothing.
//!
//! Parameters are `AhrsParams::new(dt)` defaults throughout; the bounds carry a margin of at
//! least 2× over what was measured when the test was written (printed with `--nocapture`).

use bingham::ahrs::{Ahrs, AhrsParams};
use bingham::Error;
use std::f64::consts::PI;
use testkit::imu::{angle, normalize4, rms, to_sensor};
use testkit::{qexp, qmul, Rng64};

const G: f64 = 9.81;
/// The magnetic field in the world frame (ENU, µT): north and down.
const FIELD: [f64; 3] = [0.0, 20.0, -40.0];
const BIAS_DEG: f64 = 0.5;

// ---------------------------------------------------------------------------------------------
// Quaternion helpers independent of the crate's `q4` (qmul, qexp, rot: testkit).

/// The angle between the two estimates of "up" in the sensor frame (the tilt error).
fn tilt_error(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    let (ua, ub) = (
        to_sensor(a, &[0.0, 0.0, 1.0]),
        to_sensor(b, &[0.0, 0.0, 1.0]),
    );
    let c = ua[0] * ub[0] + ua[1] * ub[1] + ua[2] * ub[2];
    c.clamp(-1.0, 1.0).acos()
}

// ---------------------------------------------------------------------------------------------
// The simulated IMU

struct Config {
    /// Sample rate (Hz).
    rate: f64,
    /// Total duration (s).
    duration: f64,
    /// The sensor is still until this time (s); the motion ramps in over 2 s after it.
    rest: f64,
    /// Windows `(start, length)` (s) of horizontal linear acceleration (4 m/s²).
    bursts: Vec<(f64, f64)>,
    /// A window `(start, length)` (s) of free fall (specific force zero, noise only).
    free_fall: Option<(f64, f64)>,
    seed: u64,
}

impl Config {
    fn standard(seed: u64) -> Config {
        Config {
            rate: 100.0,
            duration: 70.0,
            rest: 10.0,
            bursts: vec![(22.0, 0.5), (37.0, 0.3), (51.0, 0.6)],
            free_fall: None,
            seed,
        }
    }
}

struct Stream {
    dt: f64,
    truth: Vec<[f64; 4]>,
    gyr: Vec<[f64; 3]>,
    acc: Vec<[f64; 3]>,
    mag: Vec<[f64; 3]>,
    bias: [f64; 3],
}

/// The true body rate (rad/s) at time `t`: zero during the rest phase, then a sum of
/// sinusoids per axis ramped in smoothly.
fn body_rate(t: f64, rest: f64) -> [f64; 3] {
    if t <= rest {
        return [0.0; 3];
    }
    let s = ((t - rest) / 2.0).min(1.0);
    let ramp = s * s * (3.0 - 2.0 * s);
    let terms: [[(f64, f64, f64); 3]; 3] = [
        [(0.9, 0.11, 0.3), (0.5, 0.37, 1.1), (0.3, 0.83, 2.0)],
        [(0.7, 0.07, 1.7), (0.6, 0.29, 0.4), (0.25, 0.61, 2.9)],
        [(1.2, 0.05, 0.9), (0.4, 0.23, 2.3), (0.35, 0.71, 0.2)],
    ];
    let mut w = [0.0; 3];
    for (i, axis) in terms.iter().enumerate() {
        for &(a, f, p) in axis {
            w[i] += a * (2.0 * PI * f * (t - rest) + p).sin();
        }
        w[i] *= ramp;
    }
    w
}

fn simulate(c: &Config) -> Stream {
    let dt = 1.0 / c.rate;
    let n = (c.duration * c.rate).round() as usize;
    let mut rng = Rng64(c.seed);
    let bias = [
        BIAS_DEG.to_radians(),
        -BIAS_DEG.to_radians(),
        BIAS_DEG.to_radians(),
    ];
    let (gyro_sd, acc_sd, mag_sd) = (0.3f64.to_radians(), 0.05, 0.5);
    // Roll 10°, pitch −20°, yaw 40° (world from sensor).
    let mut q = qmul(
        &qexp(&[0.0, 0.0, 40f64.to_radians()]),
        &qmul(
            &qexp(&[0.0, -20f64.to_radians(), 0.0]),
            &qexp(&[10f64.to_radians(), 0.0, 0.0]),
        ),
    );
    let sub = 10;
    let h = dt / sub as f64;
    let mut s = Stream {
        dt,
        truth: Vec::with_capacity(n),
        gyr: Vec::with_capacity(n),
        acc: Vec::with_capacity(n),
        mag: Vec::with_capacity(n),
        bias,
    };
    for k in 0..n {
        let t = k as f64 * dt;
        if k > 0 {
            // The interval (t − dt, t], integrated in body-frame substeps at their midpoints.
            for j in 0..sub {
                let tm = t - dt + (j as f64 + 0.5) * h;
                let w = body_rate(tm, c.rest);
                q = normalize4(&qmul(&q, &qexp(&[w[0] * h, w[1] * h, w[2] * h])));
            }
        }
        let w = if k > 0 {
            body_rate(t - 0.5 * dt, c.rest)
        } else {
            [0.0; 3]
        };
        let gyr = [
            w[0] + bias[0] + gyro_sd * rng.normal(),
            w[1] + bias[1] + gyro_sd * rng.normal(),
            w[2] + bias[2] + gyro_sd * rng.normal(),
        ];
        let mut f_world = [0.0, 0.0, G];
        for &(start, len) in &c.bursts {
            if t >= start && t < start + len {
                f_world[0] += 4.0 * (0.7 * t).cos();
                f_world[1] += 4.0 * (0.7 * t).sin();
            }
        }
        if let Some((start, len)) = c.free_fall {
            if t >= start && t < start + len {
                f_world = [0.0; 3];
            }
        }
        let a = to_sensor(&q, &f_world);
        let acc = [
            a[0] + acc_sd * rng.normal(),
            a[1] + acc_sd * rng.normal(),
            a[2] + acc_sd * rng.normal(),
        ];
        let m = to_sensor(&q, &FIELD);
        let mag = [
            m[0] + mag_sd * rng.normal(),
            m[1] + mag_sd * rng.normal(),
            m[2] + mag_sd * rng.normal(),
        ];
        s.truth.push(q);
        s.gyr.push(gyr);
        s.acc.push(acc);
        s.mag.push(mag);
    }
    s
}

struct Run {
    est: Vec<[f64; 4]>,
    spread: Vec<f64>,
    ahrs: Ahrs,
}

fn run(s: &Stream, with_mag: bool) -> Run {
    let mut ahrs = Ahrs::new(&AhrsParams::new(s.dt)).unwrap();
    let mut est = Vec::with_capacity(s.truth.len());
    let mut spread = Vec::with_capacity(s.truth.len());
    for k in 0..s.truth.len() {
        let mag = with_mag.then_some(&s.mag[k]);
        ahrs.update(&s.gyr[k], &s.acc[k], mag).unwrap();
        est.push(ahrs.quaternion());
        let mut out = [0.0; 4];
        ahrs.angular_spread(&mut out).unwrap();
        spread.push(out[3]);
    }
    Run { est, spread, ahrs }
}

/// Errors (rad) from sample `from` on: total angle and tilt.
fn errors(s: &Stream, r: &Run, from: usize) -> (Vec<f64>, Vec<f64>) {
    let total = (from..s.truth.len())
        .map(|k| angle(&r.est[k], &s.truth[k]))
        .collect();
    let tilt = (from..s.truth.len())
        .map(|k| tilt_error(&r.est[k], &s.truth[k]))
        .collect();
    (total, tilt)
}

fn is_invalid_argument(r: &Result<(), Error>) -> bool {
    matches!(r, Err(Error::InvalidArgument(_)))
}

/// Everything observable of an AHRS, as bits.
fn snapshot(a: &Ahrs) -> Vec<u64> {
    let (mut m, mut z) = ([0.0; 16], [0.0; 4]);
    a.state_into(&mut m, &mut z).unwrap();
    let mut spread = [0.0; 4];
    a.angular_spread(&mut spread).unwrap();
    a.quaternion()
        .iter()
        .chain(&m)
        .chain(&z)
        .chain(&a.gyro_bias())
        .chain(&spread)
        .map(|v| v.to_bits())
        .chain([a.samples(), a.is_initialized() as u64])
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Accuracy

#[test]
fn tracks_the_simulated_motion() {
    let s = simulate(&Config::standard(1));
    let r = run(&s, true);
    let settle = (15.0 / s.dt) as usize;
    let (total, tilt) = errors(&s, &r, settle);
    let (e_rms, e_max) = (rms(&total), total.iter().fold(0.0f64, |a, &b| a.max(b)));
    let t_rms = rms(&tilt);
    let spread_rms = rms(&r.spread[settle..]);
    println!(
        "with magnetometer (t > 15 s): angle error RMS {:.3}°, max {:.3}°; tilt RMS {:.3}°; \
         reported spread RMS {:.3}°",
        e_rms.to_degrees(),
        e_max.to_degrees(),
        t_rms.to_degrees(),
        spread_rms.to_degrees()
    );
    assert!(e_rms.to_degrees() < 2.0, "RMS {}°", e_rms.to_degrees());
    assert!(e_max.to_degrees() < 5.0, "max {}°", e_max.to_degrees());
    assert!(t_rms.to_degrees() < 1.5, "tilt RMS {}°", t_rms.to_degrees());
    // With a magnetometer the heading is observed: the reported spread is small.
    assert!(
        spread_rms.to_degrees() < 10.0,
        "spread {}°",
        spread_rms.to_degrees()
    );
    // During the rest phase the estimate is steady and accurate.
    let (rest_err, _) = errors(&s, &r, (5.0 / s.dt) as usize);
    let rest_rms = rms(&rest_err[..(5.0 / s.dt) as usize]);
    println!(
        "rest phase 5–10 s: angle error RMS {:.3}°",
        rest_rms.to_degrees()
    );
    assert!(rest_rms.to_degrees() < 3.0);
}

#[test]
fn initializes_from_the_first_sample() {
    for seed in 0..5 {
        let s = simulate(&Config::standard(100 + seed));
        let mut a = Ahrs::new(&AhrsParams::new(s.dt)).unwrap();
        assert!(!a.is_initialized());
        assert_eq!(a.quaternion(), [1.0, 0.0, 0.0, 0.0]);
        a.update(&s.gyr[0], &s.acc[0], Some(&s.mag[0])).unwrap();
        assert!(a.is_initialized());
        assert_eq!(a.samples(), 1);
        let e = angle(&a.quaternion(), &s.truth[0]).to_degrees();
        let mut spread = [0.0; 4];
        a.angular_spread(&mut spread).unwrap();
        println!(
            "seed {seed}: first-sample error {e:.3}°, reported spread {:.2}°",
            spread[3].to_degrees()
        );
        assert!(e < 5.0, "{e}°");
        // Without a magnetometer: the tilt is right, the heading unknown.
        let mut b = Ahrs::new(&AhrsParams::new(s.dt)).unwrap();
        b.update(&s.gyr[0], &s.acc[0], None).unwrap();
        let t = tilt_error(&b.quaternion(), &s.truth[0]).to_degrees();
        b.angular_spread(&mut spread).unwrap();
        println!("seed {seed}: first-sample tilt error without magnetometer {t:.3}°");
        assert!(t < 3.0, "tilt {t}°");
        assert!(spread[3].to_degrees() > 30.0, "{:?}", spread);
    }
}

#[test]
fn estimates_the_gyro_bias() {
    let s = simulate(&Config::standard(2));
    let r = run(&s, true);
    let est = r.ahrs.gyro_bias();
    let err: Vec<f64> = (0..3).map(|i| (est[i] - s.bias[i]).to_degrees()).collect();
    println!(
        "true bias {:.3?}°/s, estimate {:.3?}°/s, error {:.4?}°/s",
        s.bias.map(f64::to_degrees),
        est.map(f64::to_degrees),
        err
    );
    for e in &err {
        assert!(e.abs() < 0.5 * BIAS_DEG, "bias error {e}°/s");
    }
    // After the rest phase alone (10 s), the bias is already known.
    let mut a = Ahrs::new(&AhrsParams::new(s.dt)).unwrap();
    for k in 0..(10.0 / s.dt) as usize {
        a.update(&s.gyr[k], &s.acc[k], Some(&s.mag[k])).unwrap();
    }
    let b = a.gyro_bias();
    let err: Vec<f64> = (0..3).map(|i| (b[i] - s.bias[i]).to_degrees()).collect();
    let cov = a.gyro_bias_covariance();
    let std: Vec<f64> = (0..3).map(|i| cov[4 * i].sqrt().to_degrees()).collect();
    println!("after the 10 s rest: error {err:.4?}°/s, reported std {std:.4?}°/s");
    // The rest's samples (0.3°/s noise each, about 850 of them used) measure the bias to
    // 0.01°/s (the bias's random walk is held over a rest): the reported standard deviation,
    // which covers the error (measured 2026-11-27: errors 2.2, 0.4 and 1.5 of it).
    for (e, sd) in err.iter().zip(&std) {
        assert!(*sd < 0.05, "reported std at rest {sd}°/s");
        assert!(
            e.abs() < 3.0 * sd,
            "bias error at rest {e}°/s, reported std {sd}°/s"
        );
    }
}

#[test]
fn learns_the_gyro_bias_in_motion_without_rest() {
    // No rest at all: the bias (0.5°/s per axis) is learned from the corrections during motion
    // (issue 20: within 10 % after 60 s), its reported covariance covers the error it has, and
    // the orientation's spread follows the orientation's error while the bias is learned.
    // Without the standard stream's linear-acceleration bursts: the low-passed accelerometer
    // takes a burst for tilt, and the corrections it causes move the bias estimate (measured:
    // about 50 % off with the three bursts, against 9 % without; a known limit).
    let s = simulate(&Config {
        rest: 0.0,
        bursts: Vec::new(),
        ..Config::standard(7)
    });
    let mut a = Ahrs::new(&AhrsParams::new(s.dt)).unwrap();
    let (mut early, mut late) = (Vec::new(), Vec::new());
    let (mut early_err, mut late_err) = (Vec::new(), Vec::new());
    for k in 0..s.truth.len() {
        let spread = a
            .update_spread(&s.gyr[k], &s.acc[k], Some(&s.mag[k]))
            .unwrap();
        let e = angle(&a.quaternion(), &s.truth[k]);
        let t = k as f64 * s.dt;
        if (1.0..3.0).contains(&t) {
            early.push(spread);
            early_err.push(e);
        } else if t >= 40.0 {
            late.push(spread);
            late_err.push(e);
        }
    }
    let est = a.gyro_bias();
    let cov = a.gyro_bias_covariance();
    let err: Vec<f64> = (0..3).map(|i| est[i] - s.bias[i]).collect();
    let rel = err.iter().map(|e| e * e).sum::<f64>().sqrt()
        / s.bias.iter().map(|b| b * b).sum::<f64>().sqrt();
    let std: Vec<f64> = (0..3).map(|i| cov[4 * i].sqrt()).collect();
    println!(
        "no rest: bias error {:.4?}°/s ({:.1} %), reported std {:.4?}°/s; spread early {:.2}° \
         (error {:.2}°), late {:.2}° (error {:.2}°)",
        err.iter().map(|e| e.to_degrees()).collect::<Vec<_>>(),
        100.0 * rel,
        std.iter().map(|e| e.to_degrees()).collect::<Vec<_>>(),
        rms(&early).to_degrees(),
        rms(&early_err).to_degrees(),
        rms(&late).to_degrees(),
        rms(&late_err).to_degrees()
    );
    assert!(rel < 0.10, "bias error {:.1} %", 100.0 * rel);
    for i in 0..3 {
        assert!(err[i].abs() < 3.0 * std[i], "axis {i}: error beyond 3σ");
        assert!(
            std[i] < 0.5 * AhrsParams::new(s.dt).bias_std,
            "axis {i}: not learned"
        );
        assert!((cov[3 * i + (i + 1) % 3] - cov[3 * ((i + 1) % 3) + i]).abs() < 1e-18);
    }
    // The stated spread is scaled by what the innovations show (module `uncertainty`): while
    // the bias is being learned and once it is, it stays within a factor of two of the RMS
    // error against the truth (measured 2026-11-28: error/spread 0.58 in 1–3 s, 0.37 from
    // 40 s on, with the spread 0.42° and 0.61°).
    for (what, e, sp) in [("early", &early_err, &early), ("late", &late_err, &late)] {
        let ratio = rms(e) / rms(sp);
        assert!(
            (0.25..=2.0).contains(&ratio),
            "{what}: RMS error / RMS spread {ratio:.2}"
        );
    }
}

#[test]
fn learns_the_gyro_scale_error_in_motion() {
    // The standard stream's gyroscope (without its linear-acceleration bursts, which the
    // corrections read as tilt) with a scale error per axis (ω_meas = (1 + s) ω + b + noise:
    // the rate part scaled), estimated with a prior of its size: the estimate approaches the
    // truth and the orientation gets better than without the scale state.
    let mut s = simulate(&Config {
        bursts: Vec::new(),
        duration: 300.0,
        ..Config::standard(11)
    });
    let scale = [0.005, -0.003, 0.004];
    for g in s.gyr.iter_mut() {
        for i in 0..3 {
            g[i] += scale[i] * (g[i] - s.bias[i]);
        }
    }
    let from = (15.0 / s.dt) as usize;
    let mut rms_err = Vec::new();
    let mut est = [0.0; 3];
    for std in [0.0, 0.005] {
        let mut p = AhrsParams::new(s.dt);
        p.gyro_scale_std = std;
        let mut a = Ahrs::new(&p).unwrap();
        let mut e = Vec::new();
        for k in 0..s.truth.len() {
            a.update(&s.gyr[k], &s.acc[k], Some(&s.mag[k])).unwrap();
            if k >= from {
                e.push(angle(&a.quaternion(), &s.truth[k]));
            }
        }
        rms_err.push(rms(&e));
        est = a.gyro_scale();
        if std == 0.0 {
            assert_eq!(est, [0.0; 3]);
        }
    }
    println!(
        "scale {scale:?}: estimate {est:.5?}; RMS error {:.3}° without the scale state, {:.3}° with",
        rms_err[0].to_degrees(),
        rms_err[1].to_degrees()
    );
    // measured 2026-11-29: [0.0037, −0.0009, 0.0034] after 300 s (the scale is learned
    // slowly: the gyroscope's noise here, 0.3°/s per sample, hides a 0.3 % error at 1 rad/s for
    // many corrections), RMS error 0.83° → 0.34°
    let off = (0..3)
        .map(|i| (est[i] - scale[i]).powi(2))
        .sum::<f64>()
        .sqrt();
    let size = scale.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!(off < 0.5 * size, "estimate {est:?} for {scale:?}");
    for i in 0..3 {
        assert!(
            est[i] * scale[i] > 0.0 && (est[i] - scale[i]).abs() < scale[i].abs(),
            "axis {i}: {} for {}",
            est[i],
            scale[i]
        );
    }
    assert!(rms_err[1] < 0.6 * rms_err[0], "{rms_err:?}");
}

#[test]
fn without_magnetometer_the_heading_is_uncertain() {
    let s = simulate(&Config::standard(3));
    let r = run(&s, false);
    let settle = (15.0 / s.dt) as usize;
    let (_, tilt) = errors(&s, &r, settle);
    let t_rms = rms(&tilt);
    let min_spread = r.spread[settle..]
        .iter()
        .fold(f64::INFINITY, |a, &b| a.min(b));
    println!(
        "without magnetometer: tilt error RMS {:.3}°, max {:.3}°; smallest reported spread {:.1}°",
        t_rms.to_degrees(),
        tilt.iter().fold(0.0f64, |a, &b| a.max(b)).to_degrees(),
        min_spread.to_degrees()
    );
    // The heading is unobserved, the tilt is not: the bias is learned from the tilt
    // corrections alone (slowly: measured 0.19–0.34°/s left of 0.5°/s after the run), and the
    // estimate must not absorb the mode's slides along the unobserved rotation about the
    // vertical (which would throw it far off).
    let est = r.ahrs.gyro_bias();
    let err: Vec<f64> = (0..3).map(|i| (est[i] - s.bias[i]).to_degrees()).collect();
    println!("without magnetometer: bias error {err:.4?}°/s");
    for e in &err {
        assert!(e.abs() < 0.8 * BIAS_DEG, "bias error {e}°/s");
    }
    assert!(t_rms.to_degrees() < 1.5, "tilt RMS {}°", t_rms.to_degrees());
    assert!(
        min_spread.to_degrees() > 30.0,
        "spread {}°",
        min_spread.to_degrees()
    );
    let with = run(&s, true);
    let max_with = with.spread[settle..].iter().fold(0.0f64, |a, &b| a.max(b));
    assert!(max_with.to_degrees() < 10.0, "{}°", max_with.to_degrees());
}

#[test]
fn free_fall_is_skipped() {
    let mut c = Config::standard(4);
    c.free_fall = Some((30.0, 0.5));
    c.duration = 40.0;
    let s = simulate(&c);
    let r = run(&s, true); // no sample refused
    let k0 = (30.0 / s.dt) as usize;
    let (total, _) = errors(&s, &r, k0);
    let worst = total.iter().fold(0.0f64, |a, &b| a.max(b)).to_degrees();
    println!("free fall at 30 s: largest angle error after it {worst:.3}°");
    assert!(worst < 5.0, "{worst}°");
    assert_eq!(r.ahrs.samples(), s.truth.len() as u64);
}

// ---------------------------------------------------------------------------------------------
// Refused samples and the batch interface

#[test]
fn refused_samples_change_nothing() {
    let s = simulate(&Config::standard(5));
    let mut a = Ahrs::new(&AhrsParams::new(s.dt)).unwrap();
    // Before initialization, too: a rate that turns more than MAX_TURN in a sample.
    let fresh = snapshot(&a);
    assert!(is_invalid_argument(&a.update(
        &[1e9, 0.0, 0.0],
        &s.acc[0],
        None
    )));
    assert_eq!(snapshot(&a), fresh);
    for k in 0..1500 {
        a.update(&s.gyr[k], &s.acc[k], Some(&s.mag[k])).unwrap();
    }
    let reference = a.clone();
    let before = snapshot(&a);
    let (g, ac, m) = (s.gyr[1500], s.acc[1500], s.mag[1500]);
    for bad in [1e9, -1e9, 1e12] {
        for i in 0..3 {
            let mut gb = g;
            gb[i] = bad;
            assert!(is_invalid_argument(&a.update(&gb, &ac, Some(&m))));
            assert!(is_invalid_argument(&a.update(&gb, &ac, None)));
            assert_eq!(snapshot(&a), before, "a refused sample changed the AHRS");
        }
    }
    // A time step that is not one: refused, nothing changed.
    for dt in [0.0, -0.01, 1e-9, 10.5, f64::NAN, f64::INFINITY] {
        assert!(
            is_invalid_argument(&a.update_dt(dt, &g, &ac, Some(&m))),
            "{dt}"
        );
        assert_eq!(snapshot(&a), before, "a refused time step changed the AHRS");
    }
    // Hidden state (filters, rest timer, magnetic reference) unchanged too: the refused
    // samples leave no trace in what follows.
    let mut b = reference;
    for k in 1500..2000 {
        a.update(&s.gyr[k], &s.acc[k], Some(&s.mag[k])).unwrap();
        b.update(&s.gyr[k], &s.acc[k], Some(&s.mag[k])).unwrap();
        assert_eq!(snapshot(&a), snapshot(&b), "diverged at sample {k}");
    }
}

#[test]
fn a_non_finite_accelerometer_or_magnetometer_drops_that_channel_only() {
    let s = simulate(&Config::standard(5));
    let mut a = Ahrs::new(&AhrsParams::new(s.dt)).unwrap();
    for k in 0..1500 {
        a.update(&s.gyr[k], &s.acc[k], Some(&s.mag[k])).unwrap();
    }
    let (g, ac, m) = (s.gyr[1500], s.acc[1500], s.mag[1500]);
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for i in 0..3 {
            // A non-finite field sample is the same as no field sample, bit for bit.
            let mut mb = m;
            mb[i] = bad;
            let (mut x, mut y) = (a.clone(), a.clone());
            x.update(&g, &ac, Some(&mb)).unwrap();
            y.update(&g, &ac, None).unwrap();
            assert_eq!(snapshot(&x), snapshot(&y));
            // A non-finite accelerometer sample: accepted, the gyroscope increment applied
            // (the estimate turns with it), and every non-finite value means the same.
            let mut abad = ac;
            abad[i] = bad;
            let mut u = a.clone();
            u.update(&g, &abad, Some(&m)).unwrap();
            let mut v = a.clone();
            v.update(&g, &[f64::NAN; 3], Some(&m)).unwrap();
            assert_eq!(snapshot(&u), snapshot(&v));
            assert_eq!(u.samples(), a.samples() + 1);
            let turned = angle(&u.quaternion(), &a.quaternion());
            let expected = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt() * s.dt;
            assert!(
                (turned - expected).abs() < 0.2 * expected + 2e-3,
                "turned {turned}, gyroscope {expected}"
            );
        }
    }
    // A stream with every tenth accelerometer and magnetometer row missing still tracks.
    let mut b = Ahrs::new(&AhrsParams::new(s.dt)).unwrap();
    let mut err = Vec::new();
    for k in 0..s.truth.len() {
        let acc = if k % 10 == 5 { [f64::NAN; 3] } else { s.acc[k] };
        let mag = if k % 10 == 7 { [f64::NAN; 3] } else { s.mag[k] };
        b.update(&s.gyr[k], &acc, Some(&mag)).unwrap();
        if k * 2 > s.truth.len() {
            err.push(angle(&b.quaternion(), &s.truth[k]));
        }
    }
    assert!(rms(&err).to_degrees() < 3.0, "{}", rms(&err).to_degrees());
}

#[test]
fn first_sample_needs_gravity() {
    let p = AhrsParams::new(0.01);
    let mut a = Ahrs::new(&p).unwrap();
    let fresh = snapshot(&a);
    for acc in [[0.0; 3], [0.1, -0.2, 0.3], [0.0, 0.0, 0.2 * G]] {
        assert!(is_invalid_argument(&a.update(&[0.0; 3], &acc, None)));
        assert!(is_invalid_argument(&a.update(
            &[0.0; 3],
            &acc,
            Some(&[0.0, 20.0, -40.0])
        )));
        assert_eq!(snapshot(&a), fresh);
        assert!(!a.is_initialized());
        assert_eq!(a.samples(), 0);
    }
    // Before the first sample: identity and the uniform state.
    let (mut m, mut z) = ([9.0; 16], [9.0; 4]);
    a.state_into(&mut m, &mut z).unwrap();
    for (k, v) in m.iter().enumerate() {
        assert_eq!(*v, if k % 5 == 0 { 1.0 } else { 0.0 });
    }
    assert_eq!(z, [0.0; 4]);
    assert!(matches!(
        a.state_into(&mut [0.0; 15], &mut z),
        Err(Error::InvalidDimension(_))
    ));
    // A usable sample then initializes it (a zero magnetometer is ignored).
    a.update(&[0.0; 3], &[0.0, 0.0, G], Some(&[0.0; 3]))
        .unwrap();
    assert!(a.is_initialized());
    assert_eq!(a.samples(), 1);
}

#[test]
fn batch_stops_at_the_first_refused_sample() {
    let s = simulate(&Config {
        duration: 3.0,
        ..Config::standard(6)
    });
    let n = s.truth.len();
    let bad_at = 120;
    let acc = s.acc.clone();
    let mut gyr = s.gyr.clone();
    // a rate turning more than MAX_TURN in a sample (a NaN row is a gap, not an error)
    gyr[bad_at][1] = 1e9;
    let mut a = Ahrs::new(&AhrsParams::new(s.dt)).unwrap();
    let mut quat = vec![[7.0; 4]; n];
    let mut spread = vec![7.0; n];
    let r = a.update_batch(&gyr, &acc, Some(&s.mag), &mut quat, Some(&mut spread));
    match r {
        Err(Error::InvalidArgument(msg)) => {
            assert!(msg.contains(&format!("sample {bad_at}")), "message: {msg}")
        }
        other => panic!("expected InvalidArgument, got {other:?}"),
    }
    assert_eq!(a.samples(), bad_at as u64);
    // The rows before it equal one-by-one updates, bit for bit; the rest are untouched.
    let mut b = Ahrs::new(&AhrsParams::new(s.dt)).unwrap();
    for k in 0..bad_at {
        b.update(&s.gyr[k], &acc[k], Some(&s.mag[k])).unwrap();
        assert_eq!(quat[k].map(f64::to_bits), b.quaternion().map(f64::to_bits));
        let mut out = [0.0; 4];
        b.angular_spread(&mut out).unwrap();
        assert_eq!(spread[k].to_bits(), out[3].to_bits());
    }
    assert_eq!(snapshot(&a), snapshot(&b));
    assert!(quat[bad_at..].iter().all(|q| *q == [7.0; 4]));
    assert!(spread[bad_at..].iter().all(|v| *v == 7.0));

    // A whole batch without magnetometer and spread equals one-by-one updates.
    let mut c = Ahrs::new(&AhrsParams::new(s.dt)).unwrap();
    let mut d = c.clone();
    c.update_batch(&s.gyr, &s.acc, None, &mut quat, None)
        .unwrap();
    for (k, row) in quat.iter().enumerate() {
        d.update(&s.gyr[k], &s.acc[k], None).unwrap();
        assert_eq!(row.map(f64::to_bits), d.quaternion().map(f64::to_bits));
    }

    // Lengths that disagree: refused before any sample.
    let mut e = Ahrs::new(&AhrsParams::new(s.dt)).unwrap();
    let short = &s.acc[..n - 1];
    for r in [
        e.update_batch(&s.gyr, short, None, &mut quat, None),
        e.update_batch(&s.gyr, &s.acc, Some(&s.mag[..5]), &mut quat, None),
        e.update_batch(&s.gyr, &s.acc, None, &mut quat[..n - 1], None),
        e.update_batch(&s.gyr, &s.acc, None, &mut quat, Some(&mut spread[..3])),
    ] {
        assert!(matches!(r, Err(Error::InvalidDimension(_))), "{r:?}");
    }
    assert_eq!(e.samples(), 0);
    // A first sample without gravity: refused at index 0.
    let mut zero = s.acc.clone();
    zero[0] = [0.0; 3];
    match e.update_batch(&s.gyr, &zero, None, &mut quat, None) {
        Err(Error::InvalidArgument(msg)) => assert!(msg.contains("sample 0"), "{msg}"),
        other => panic!("{other:?}"),
    }
    assert!(!e.is_initialized());
}

#[test]
fn parameters_are_validated() {
    let good = AhrsParams::new(0.01);
    assert!(Ahrs::new(&good).is_ok());
    assert_eq!(Ahrs::new(&good).unwrap().params(), &good);
    type Setter = fn(&mut AhrsParams, f64);
    let positive: [(&str, Setter); 10] = [
        ("sample_time", |p, v| p.sample_time = v),
        ("gyro_noise", |p, v| p.gyro_noise = v),
        ("acc_noise", |p, v| p.acc_noise = v),
        ("acc_reject", |p, v| p.acc_reject = v),
        ("gravity", |p, v| p.gravity = v),
        ("mag_noise", |p, v| p.mag_noise = v),
        ("mag_norm_tol", |p, v| p.mag_norm_tol = v),
        ("bias_max", |p, v| p.bias_max = v),
        ("rest_time", |p, v| p.rest_time = v),
        ("init_std", |p, v| p.init_std = v),
    ];
    for (name, set) in positive {
        for v in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let mut p = good;
            set(&mut p, v);
            let r = Ahrs::new(&p);
            assert!(
                matches!(r, Err(Error::InvalidArgument(ref m)) if m.contains(name)),
                "{name} = {v}: {r:?}"
            );
            assert!(p.validate().is_err());
        }
    }
    // bias_time: 0 disables the estimation, negative or NaN is refused.
    let mut p = good;
    p.bias_time = 0.0;
    assert!(Ahrs::new(&p).is_ok());
    for v in [-1.0, f64::NAN, f64::INFINITY] {
        p.bias_time = v;
        assert!(
            matches!(Ahrs::new(&p), Err(Error::InvalidArgument(_))),
            "{v}"
        );
    }
}

/// A rate in Hz passed where the period is expected is refused with a hint (issue 23), and
/// `from_rate` takes the rate.
#[test]
fn a_rate_passed_as_the_sample_time_is_refused_and_from_rate_takes_it() {
    use bingham::ahrs::{MAX_SAMPLE_TIME, MIN_SAMPLE_TIME};
    assert_eq!(MAX_SAMPLE_TIME, 1.0);
    for hz in [100.0, 1000.0, 1.5, 1e3 + 1.0] {
        let p = AhrsParams::new(hz);
        for r in [p.validate(), Ahrs::new(&p).map(|_| ())] {
            match r {
                Err(Error::InvalidArgument(m)) => {
                    assert!(m.contains("did you pass a rate in Hz?"), "{m}");
                    assert!(m.contains(&format!("for {hz} Hz pass {}", 1.0 / hz)), "{m}");
                    assert!(m.contains(&format!("AhrsParams::from_rate({hz})")), "{m}");
                    assert!(
                        m.contains(&format!("bingham_ahrs_params_from_rate({hz}, &p)")),
                        "{m}"
                    );
                }
                other => panic!("sample_time = {hz}: {other:?}"),
            }
        }
    }
    // the bound itself is accepted
    assert!(Ahrs::new(&AhrsParams::new(MAX_SAMPLE_TIME)).is_ok());
    assert!(Ahrs::new(&AhrsParams::new(MIN_SAMPLE_TIME)).is_ok());

    // from_rate: the defaults for the period 1/hz, bit for bit
    assert_eq!(AhrsParams::from_rate(100.0).unwrap(), AhrsParams::new(0.01));
    assert_eq!(AhrsParams::from_rate(100.0).unwrap().sample_time, 0.01);
    assert_eq!(AhrsParams::from_rate(400.0).unwrap().sample_time, 0.0025);
    assert_eq!(AhrsParams::from_rate(1.0).unwrap(), AhrsParams::new(1.0));
    assert_eq!(AhrsParams::from_rate(1e6).unwrap().sample_time, 1e-6);
    for (hz, needle) in [
        (0.5, "below 1 Hz"),
        (0.999, "below 1 Hz"),
        (0.0, "finite and > 0"),
        (-0.0, "finite and > 0"),
        (-1.0, "finite and > 0"),
        (-100.0, "finite and > 0"),
        (f64::NAN, "finite and > 0"),
        (f64::INFINITY, "finite and > 0"),
        (f64::NEG_INFINITY, "finite and > 0"),
        (2e6, "above 1000000 Hz"),
    ] {
        match AhrsParams::from_rate(hz) {
            Err(Error::InvalidArgument(m)) => {
                assert!(m.contains("`hz`") && m.contains(needle), "{hz}: {m}")
            }
            other => panic!("from_rate({hz}): {other:?}"),
        }
    }
}

#[test]
fn ahrs_is_send_and_sync() {
    fn check<T: Send + Sync + Clone>() {}
    check::<Ahrs>();
    check::<AhrsParams>();
}

#[test]
fn a_start_180_degrees_wrong_is_corrected() {
    // The truth turned upside down about the east axis, told with a confident 10° spread.
    let s = simulate(&Config::standard(5));
    let flip = [0.0, 1.0, 0.0, 0.0];
    let wrong = qmul(&flip, &s.truth[0]);
    let noise = bingham::observation::noise_from_angle_std(4, 10f64.to_radians()).unwrap();
    let start = noise.rotate_left(&wrong).unwrap();
    let mut ahrs = Ahrs::new(&AhrsParams::new(s.dt)).unwrap();
    ahrs.set_state(&start.m_row_major(), start.z().as_slice())
        .unwrap();
    assert!(ahrs.is_initialized());
    assert!(angle(&ahrs.quaternion(), &s.truth[0]).to_degrees() > 179.0);
    // the first sample keeps the given start (it only primes the low-pass filters)
    ahrs.update(&s.gyr[0], &s.acc[0], Some(&s.mag[0])).unwrap();
    assert!(angle(&ahrs.quaternion(), &s.truth[0]).to_degrees() > 170.0);
    let mut last_bad = 0;
    for k in 1..s.truth.len() {
        ahrs.update(&s.gyr[k], &s.acc[k], Some(&s.mag[k])).unwrap();
        if angle(&ahrs.quaternion(), &s.truth[k]).to_degrees() >= 5.0 {
            last_bad = k;
        }
    }
    let t = last_bad as f64 * s.dt;
    println!("180° wrong start: within 5° for good from t = {t:.2} s");
    assert!(t < 20.0, "still off at t = {t} s");
    // a bad state is refused and changes nothing
    let before = snapshot(&ahrs);
    let mut m = start.m_row_major();
    m[0] += 0.1;
    assert!(ahrs.set_state(&m, start.z().as_slice()).is_err());
    assert!(ahrs
        .set_state(&start.m_row_major(), &[f64::NAN, 0.0, 0.0, 0.0])
        .is_err());
    assert_eq!(before, snapshot(&ahrs));
}
