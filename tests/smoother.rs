//! The offline smoother (`bingham::smoother`, issue 36) against independent references: the
//! truth of a simulated IMU (3-D motion with gyroscope bias, linear-acceleration bursts and a
//! dipping field), and, for a rotation about the vertical, the optimal linear smoother (a
//! Rauch–Tung–Striebel smoother of the heading written here, exact for the linear-Gaussian model
//! the AHRS's parameters state) over Monte Carlo runs, compared to the reference's standard
//! error. Also the contract: lengths, timestamps, nothing written on error, `n` = 0 and 1, the
//! memory per sample.
//!
//! The bounds carry a margin over what was measured when the test was written (printed with
//! `--nocapture`).

use bingham::ahrs::{Ahrs, AhrsParams};
use bingham::smoother::{
    smooth, smooth_with, BiasMode, Fusion, SmoothInput, SmoothOptions, SmoothOutput,
    BIAS_BYTES_PER_SAMPLE, BYTES_PER_SAMPLE,
};
use std::f64::consts::PI;
use testkit::imu::{angle, normalize4, rms, to_sensor};
use testkit::{qexp, qmul, Rng64};

const G: f64 = 9.81;
const FIELD: [f64; 3] = [0.0, 20.0, -40.0];

struct Stream {
    dt: f64,
    truth: Vec<[f64; 4]>,
    gyr: Vec<[f64; 3]>,
    acc: Vec<[f64; 3]>,
    mag: Vec<[f64; 3]>,
    bias: [f64; 3],
}

/// The body rate (rad/s) at time `t`: a sum of sinusoids per axis.
fn body_rate(t: f64) -> [f64; 3] {
    let terms: [[(f64, f64, f64); 3]; 3] = [
        [(0.9, 0.11, 0.3), (0.5, 0.37, 1.1), (0.3, 0.83, 2.0)],
        [(0.7, 0.07, 1.7), (0.6, 0.29, 0.4), (0.25, 0.61, 2.9)],
        [(1.2, 0.05, 0.9), (0.4, 0.23, 2.3), (0.35, 0.71, 0.2)],
    ];
    std::array::from_fn(|i| {
        terms[i]
            .iter()
            .map(|&(a, f, p)| a * (2.0 * PI * f * t + p).sin())
            .sum()
    })
}

/// A simulated IMU at 100 Hz for `duration` s: the gyroscope sample `k` is the mean rate over
/// `(t_{k−1}, t_k]` plus a bias of 0.5 °/s per axis and noise, the accelerometer gravity with
/// bursts of linear acceleration, the magnetometer a dipping field, both with noise.
fn simulate(seed: u64, duration: f64) -> Stream {
    let dt = 0.01;
    let n = (duration / dt).round() as usize;
    let mut rng = Rng64(seed);
    let b = 0.5f64.to_radians();
    let bias = [b, -b, b];
    let (gyro_sd, acc_sd, mag_sd) = (0.3f64.to_radians(), 0.05, 0.5);
    let mut q = qmul(
        &qexp(&[0.0, 0.0, 40f64.to_radians()]),
        &qexp(&[10f64.to_radians(), -20f64.to_radians(), 0.0]),
    );
    let sub = 10;
    let h = dt / sub as f64;
    let mut s = Stream {
        dt,
        truth: Vec::new(),
        gyr: Vec::new(),
        acc: Vec::new(),
        mag: Vec::new(),
        bias,
    };
    for k in 0..n {
        let t = k as f64 * dt;
        let mut mean = [0.0; 3];
        if k > 0 {
            for j in 0..sub {
                let w = body_rate(t - dt + (j as f64 + 0.5) * h);
                q = normalize4(&qmul(&q, &qexp(&[w[0] * h, w[1] * h, w[2] * h])));
                for i in 0..3 {
                    mean[i] += w[i] / sub as f64;
                }
            }
        }
        let gyr = std::array::from_fn(|i| mean[i] + bias[i] + gyro_sd * rng.normal());
        let mut f = [0.0, 0.0, G];
        for (start, len) in [(12.0, 0.5), (27.0, 0.3), (41.0, 0.6)] {
            if t >= start && t < start + len {
                f[0] += 4.0 * (0.7 * t).cos();
                f[1] += 4.0 * (0.7 * t).sin();
            }
        }
        let a = to_sensor(&q, &f);
        let m = to_sensor(&q, &FIELD);
        s.truth.push(q);
        s.gyr.push(gyr);
        s.acc
            .push(std::array::from_fn(|i| a[i] + acc_sd * rng.normal()));
        s.mag
            .push(std::array::from_fn(|i| m[i] + mag_sd * rng.normal()));
    }
    s
}

struct Smoothed {
    quat: Vec<[f64; 4]>,
    spread: Vec<f64>,
    bias: Vec<[f64; 3]>,
    cov: Vec<[f64; 9]>,
}

fn run_smoother(p: &AhrsParams, s: &Stream, with_mag: bool, options: &SmoothOptions) -> Smoothed {
    let n = s.gyr.len();
    let mut r = Smoothed {
        quat: vec![[0.0; 4]; n],
        spread: vec![0.0; n],
        bias: vec![[0.0; 3]; n],
        cov: vec![[0.0; 9]; n],
    };
    let input = SmoothInput {
        time: None,
        gyr: &s.gyr,
        acc: &s.acc,
        mag: with_mag.then_some(&s.mag[..]),
    };
    let out = SmoothOutput {
        quat: &mut r.quat,
        spread: Some(&mut r.spread),
        bias: Some(&mut r.bias),
        covariance: Some(&mut r.cov),
    };
    smooth_with(p, options, &input, out).unwrap();
    r
}

/// The online AHRS: quaternions, spreads, bias estimates.
fn run_online(
    p: &AhrsParams,
    s: &Stream,
    with_mag: bool,
) -> (Vec<[f64; 4]>, Vec<f64>, Vec<[f64; 3]>) {
    let mut a = Ahrs::new(p).unwrap();
    let mut q = Vec::new();
    let mut sp = Vec::new();
    let mut b = Vec::new();
    for k in 0..s.gyr.len() {
        sp.push(
            a.update_spread(&s.gyr[k], &s.acc[k], with_mag.then_some(&s.mag[k]))
                .unwrap(),
        );
        q.push(a.quaternion());
        b.push(a.gyro_bias());
    }
    (q, sp, b)
}

#[test]
fn smooths_the_simulated_motion_better_than_the_online_ahrs_with_an_honest_spread() {
    // Sixteen seeds: the smoothed error is 0.56-0.65 of the online one on most of them and
    // 0.74-0.8 on a few, which ones moving with any change at the rounding level (seeds 4 and
    // 8 at a 20-ms correction period, 3 and 10 at 50 ms, 4, 8 and 16 with the scale state), so
    // each seed is held to being better and the mean ratio to the margin.
    let mut ratios = Vec::new();
    for seed in 1u64..=16 {
        let s = simulate(seed, 60.0);
        let p = AhrsParams::new(s.dt);
        let (qo, so, bo) = run_online(&p, &s, true);
        let r = run_smoother(&p, &s, true, &SmoothOptions::default());
        let eo: Vec<f64> = (0..qo.len()).map(|k| angle(&qo[k], &s.truth[k])).collect();
        let es: Vec<f64> = (0..qo.len())
            .map(|k| angle(&r.quat[k], &s.truth[k]))
            .collect();
        let (eo, es) = (rms(&eo), rms(&es));
        let calibration = es / rms(&r.spread);
        let bias_err = |b: &[[f64; 3]]| {
            rms(&b
                .iter()
                .map(|x| {
                    let d: [f64; 3] = std::array::from_fn(|i| x[i] - s.bias[i]);
                    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
                })
                .collect::<Vec<_>>())
        };
        let (bo_err, bs_err) = (bias_err(&bo), bias_err(&r.bias));
        println!(
            "seed {seed}: online {:.3}°, smoothed {:.3}° (error/spread {calibration:.2}; mean \
             spread online {:.3}°, smoothed {:.3}°); bias error online {:.4} °/s, smoothed {:.4} °/s",
            eo.to_degrees(),
            es.to_degrees(),
            rms(&so).to_degrees(),
            rms(&r.spread).to_degrees(),
            bo_err.to_degrees(),
            bs_err.to_degrees()
        );
        assert!(es < 0.9 * eo, "seed {seed}: smoothed {es} vs online {eo}");
        ratios.push(es / eo);
        assert!(
            (0.5..=2.0).contains(&calibration),
            "error/spread {calibration}"
        );
        assert!(rms(&r.spread) < rms(&so));
        assert!(bs_err < bo_err, "bias {bs_err} vs {bo_err}");
        // the covariance's trace is the spread², and it is symmetric positive definite
        for k in (0..r.cov.len()).step_by(97) {
            let c = &r.cov[k];
            let tr = c[0] + c[4] + c[8];
            assert!((tr.sqrt() - r.spread[k]).abs() <= 1e-6 * r.spread[k]);
            assert_eq!(c[1], c[3]);
            assert!(c[0] > 0.0 && c[0] * c[4] - c[1] * c[3] > 0.0);
        }
    }
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    assert!(mean < 0.7, "mean smoothed/online error {mean}: {ratios:?}");
}

/// Dropped samples (rows removed, timestamps given): the backward pass bridges an interval
/// as the forward pass does — the sample after the interval covers its end, the rest is turned
/// with the mean of the rates on both sides — so the smoother stays well ahead of the online
/// AHRS. (Bridged with the rate of the sample after next, and in the recorded order, the
/// backward pass drifted by the rate's change over every drop: with 5 % dropped the smoothed
/// error rose above the online one on the simulated suite.)
#[test]
fn dropped_samples_are_bridged_in_reverse_as_forward() {
    for seed in [11u64, 12] {
        let full = simulate(seed, 60.0);
        let mut rng = Rng64(seed + 100);
        let keep: Vec<usize> = (0..full.gyr.len())
            .filter(|&k| k < 10 || rng.uniform() >= 0.05)
            .collect();
        let pick3 = |v: &[[f64; 3]]| keep.iter().map(|&k| v[k]).collect::<Vec<_>>();
        let (gyr, acc, mag) = (pick3(&full.gyr), pick3(&full.acc), pick3(&full.mag));
        let truth: Vec<[f64; 4]> = keep.iter().map(|&k| full.truth[k]).collect();
        let time: Vec<f64> = keep.iter().map(|&k| k as f64 * full.dt).collect();
        let n = keep.len();
        let p = AhrsParams::new(full.dt);
        // the online AHRS with the same timestamps
        let mut a = Ahrs::new(&p).unwrap();
        let mut qo = vec![[0.0; 4]; n];
        a.update_batch_timed(&time, &gyr, &acc, Some(&mag), &mut qo, None, None)
            .unwrap();
        let mut qs = vec![[0.0; 4]; n];
        let input = SmoothInput {
            time: Some(&time),
            gyr: &gyr,
            acc: &acc,
            mag: Some(&mag),
        };
        let out = SmoothOutput {
            quat: &mut qs,
            spread: None,
            bias: None,
            covariance: None,
        };
        smooth_with(&p, &SmoothOptions::default(), &input, out).unwrap();
        let err =
            |q: &[[f64; 4]]| rms(&(0..n).map(|k| angle(&q[k], &truth[k])).collect::<Vec<_>>());
        let (eo, es) = (err(&qo), err(&qs));
        println!(
            "seed {seed}, {} of {} samples dropped: online {:.3}°, smoothed {:.3}°",
            full.gyr.len() - n,
            full.gyr.len(),
            eo.to_degrees(),
            es.to_degrees()
        );
        assert!(es < 0.7 * eo, "smoothed {es} vs online {eo}");
    }
}

#[test]
fn without_a_magnetometer_the_tilt_is_smoothed() {
    // Sixteen seeds, as in the test above: the smoothed tilt error is 0.64-0.74 of the online
    // one on most and 0.8-0.96 on a few, which ones moving with rounding-level changes (1 and 5
    // before the gyroscope's scale state, 12 and 16 with it), so each seed is held to being
    // better and the mean ratio to the margin (0.70 and 0.71).
    let mut ratios = Vec::new();
    for seed in 1u64..=16 {
        let s = simulate(seed, 60.0);
        let p = AhrsParams::new(s.dt);
        let (qo, _, _) = run_online(&p, &s, false);
        let r = run_smoother(&p, &s, false, &SmoothOptions::default());
        // the tilt error: the angle between the true and the estimated "up" in the sensor frame
        let tilt = |q: &[f64; 4], t: &[f64; 4]| {
            let a = to_sensor(q, &[0.0, 0.0, 1.0]);
            let b = to_sensor(t, &[0.0, 0.0, 1.0]);
            (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]).min(1.0).acos()
        };
        let eo = rms(&(0..qo.len())
            .map(|k| tilt(&qo[k], &s.truth[k]))
            .collect::<Vec<_>>());
        let es = rms(&(0..qo.len())
            .map(|k| tilt(&r.quat[k], &s.truth[k]))
            .collect::<Vec<_>>());
        println!(
            "6-D tilt: online {:.3}°, smoothed {:.3}°",
            eo.to_degrees(),
            es.to_degrees()
        );
        assert!(es < eo, "seed {seed}: smoothed {es} vs online {eo}");
        ratios.push(es / eo);
    }
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    assert!(
        mean < 0.75,
        "mean smoothed/online tilt error {mean}: {ratios:?}"
    );
}

#[test]
fn the_second_pass_and_the_exact_product_are_as_accurate() {
    let s = simulate(11, 60.0);
    let p = AhrsParams::new(s.dt);
    let (qo, _, _) = run_online(&p, &s, true);
    let eo = rms(&(0..qo.len())
        .map(|k| angle(&qo[k], &s.truth[k]))
        .collect::<Vec<_>>());
    for (bias, fusion) in [
        (BiasMode::Fused, Fusion::Tangent),
        (BiasMode::SecondPass, Fusion::Tangent),
        (BiasMode::Fused, Fusion::Bingham),
    ] {
        let r = run_smoother(
            &p,
            &s,
            true,
            &SmoothOptions {
                bias,
                fusion,
                ..SmoothOptions::default()
            },
        );
        let es = rms(&(0..qo.len())
            .map(|k| angle(&r.quat[k], &s.truth[k]))
            .collect::<Vec<_>>());
        println!(
            "{bias:?} {fusion:?}: {:.3}° (online {:.3}°)",
            es.to_degrees(),
            eo.to_degrees()
        );
        assert!(es < 0.8 * eo);
    }
}

// ---------------------------------------------------------------------------------------------
// A rotation about the vertical against the optimal linear smoother

/// A level sensor turning about the vertical: heading `ψ_k = ψ_{k−1} + ω_k dt`, the gyroscope
/// `ω_k` plus white noise of variance `q/dt` (`q` the heading's variance per sample), the
/// magnetometer a horizontal unit field at the heading with noise `σ_h` per component (the
/// heading's noise, radians), the accelerometer gravity with noise.
struct Heading {
    truth: Vec<f64>,
    gyr: Vec<[f64; 3]>,
    acc: Vec<[f64; 3]>,
    mag: Vec<[f64; 3]>,
}

fn simulate_heading(seed: u64, n: usize, dt: f64, q: f64, sigma_h: f64) -> Heading {
    let mut rng = Rng64(seed);
    let mut psi = rng.range(-PI, PI);
    let mut h = Heading {
        truth: Vec::new(),
        gyr: Vec::new(),
        acc: Vec::new(),
        mag: Vec::new(),
    };
    for k in 0..n {
        let t = k as f64 * dt;
        let w = 0.8 * (0.5 * t).sin() + 0.3 * (1.7 * t + 1.0).sin();
        if k > 0 {
            psi += w * dt;
        }
        // the sensor's y axis at heading ψ from north (ENU, turning about +z): the field
        // (0, 1, 0) in the world is (sin ψ, cos ψ, 0) in the sensor frame
        h.truth.push(psi);
        h.gyr.push([0.0, 0.0, w + q.sqrt() / dt * rng.normal()]);
        h.acc.push([
            0.02 * rng.normal(),
            0.02 * rng.normal(),
            G + 0.02 * rng.normal(),
        ]);
        h.mag.push([
            psi.sin() + sigma_h * rng.normal(),
            psi.cos() + sigma_h * rng.normal(),
            0.0,
        ]);
    }
    h
}

/// The heading (rad) of an orientation (sensor → ENU): the rotation about the vertical.
fn heading_of(q: &[f64; 4]) -> f64 {
    2.0 * q[3].atan2(q[0])
}

fn wrap(x: f64) -> f64 {
    (x + PI).rem_euclid(2.0 * PI) - PI
}

/// The optimal filter and smoother of the linear-Gaussian heading model: a Kalman filter on
/// the unwrapped heading with the magnetometer's heading `atan2(m_x, m_y)` (variance `r`) and a
/// Rauch–Tung–Striebel backward pass. Returns (filtered, smoothed) headings.
fn rts(h: &Heading, dt: f64, q: f64, r: f64, p0: f64) -> (Vec<f64>, Vec<f64>) {
    let n = h.gyr.len();
    let (mut xf, mut pf, mut xp, mut pp) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for k in 0..n {
        let y = h.mag[k][0].atan2(h.mag[k][1]);
        let (x, p) = if k == 0 {
            (y, p0)
        } else {
            (xf[k - 1] + h.gyr[k][2] * dt, pf[k - 1] + q)
        };
        xp[k] = x;
        pp[k] = p;
        let gain = p / (p + r);
        xf[k] = x + gain * wrap(y - x);
        pf[k] = (1.0 - gain) * p;
    }
    let mut xs = xf.clone();
    for k in (0..n - 1).rev() {
        let c = pf[k] / pp[k + 1];
        xs[k] = xf[k] + c * (xs[k + 1] - xp[k + 1]);
    }
    (xf, xs)
}

#[test]
fn heading_is_as_accurate_as_the_optimal_linear_smoother() {
    // the AHRS's heading evidence is per second: κ_m = T/(mag_noise²·mag_tau) for a period T,
    // the information of per-sample headings of variance σ_h² when mag_noise² mag_tau = σ_h² dt
    let dt = 0.01;
    let mut p = AhrsParams::new(dt);
    let sigma_h = 3f64.to_radians();
    p.mag_noise = sigma_h * (dt / p.mag_tau).sqrt();
    p.gyro_scale_noise = 1e-9;
    p.bias_std = 1e-6;
    let q = p.gyro_noise * p.gyro_noise * dt;
    let r = sigma_h * sigma_h;
    let n = 3000;
    let runs = 16;
    let skip = 300;
    let (mut kf, mut rts_s, mut on, mut sm) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for seed in 0..runs {
        let h = simulate_heading(100 + seed, n, dt, q, sigma_h);
        let (xf, xs) = rts(&h, dt, q, r, p.init_std * p.init_std);
        let mut a = Ahrs::new(&p).unwrap();
        let mut online = Vec::new();
        for k in 0..n {
            a.update(&h.gyr[k], &h.acc[k], Some(&h.mag[k])).unwrap();
            online.push(heading_of(&a.quaternion()));
        }
        let mut qs = vec![[0.0; 4]; n];
        let input = SmoothInput {
            time: None,
            gyr: &h.gyr,
            acc: &h.acc,
            mag: Some(&h.mag),
        };
        smooth(
            &p,
            &input,
            SmoothOutput {
                quat: &mut qs,
                spread: None,
                bias: None,
                covariance: None,
            },
        )
        .unwrap();
        let ms = |est: &dyn Fn(usize) -> f64| {
            (skip..n - skip)
                .map(|k| wrap(est(k) - h.truth[k]).powi(2))
                .sum::<f64>()
                / (n - 2 * skip) as f64
        };
        kf.push(ms(&|k| xf[k]));
        rts_s.push(ms(&|k| xs[k]));
        on.push(ms(&|k| online[k]));
        sm.push(ms(&|k| heading_of(&qs[k])));
    }
    // per run mean squares; the ratio of RMS errors and its standard error over the runs
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let se = |v: &[f64]| {
        let m = mean(v);
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() * (v.len() - 1)) as f64).sqrt()
    };
    let (kf_rms, rts_rms, on_rms, sm_rms) = (
        mean(&kf).sqrt(),
        mean(&rts_s).sqrt(),
        mean(&on).sqrt(),
        mean(&sm).sqrt(),
    );
    // the relative standard error of an RMS is half that of the mean square
    let rel = |v: &[f64]| 0.5 * se(v) / mean(v);
    println!(
        "heading RMS: Kalman filter {:.4}° (±{:.1} %), online AHRS {:.4}°; RTS smoother {:.4}° \
         (±{:.1} %), smoother {:.4}° (±{:.1} %)",
        kf_rms.to_degrees(),
        100.0 * rel(&kf),
        on_rms.to_degrees(),
        rts_rms.to_degrees(),
        100.0 * rel(&rts_s),
        sm_rms.to_degrees(),
        100.0 * rel(&sm)
    );
    // the smoother gains over the online AHRS what the optimal smoother gains over the optimal
    // filter, within three standard errors of the ratio (the relative errors add)
    let ratio_opt = rts_rms / kf_rms;
    let ratio = sm_rms / on_rms;
    let tol = 3.0 * (rel(&kf) + rel(&rts_s) + rel(&on) + rel(&sm));
    println!("gain: optimal {ratio_opt:.3}, AHRS {ratio:.3}, tolerance {tol:.3}");
    assert!(ratio <= ratio_opt * (1.0 + tol), "{ratio} vs {ratio_opt}");
    // and no smoother beats the optimal one beyond its standard error
    assert!(sm_rms >= rts_rms * (1.0 - 3.0 * (rel(&rts_s) + rel(&sm))));
}

// ---------------------------------------------------------------------------------------------
// The contract

#[test]
fn memory_per_sample_is_small() {
    // each pass's mode and covariance (the backward pass keeps its own to run concurrently)
    assert_eq!(BYTES_PER_SAMPLE, 112);
    assert_eq!(BIAS_BYTES_PER_SAMPLE, 72);
    // one hour at 1 kHz, with the bias output, well under 1 GiB (two thirds of it)
    let bytes = 3600 * 1000 * (BYTES_PER_SAMPLE + BIAS_BYTES_PER_SAMPLE);
    assert!(bytes < (1 << 30) / 3 * 2, "{bytes}");
}

#[test]
fn the_contract_lengths_timestamps_errors_and_short_recordings() {
    let s = simulate(5, 5.0);
    let p = AhrsParams::new(s.dt);
    let n = s.gyr.len();
    let input = SmoothInput {
        time: None,
        gyr: &s.gyr,
        acc: &s.acc,
        mag: Some(&s.mag),
    };
    let out = |q: &mut Vec<[f64; 4]>| {
        let mut r = Vec::new();
        std::mem::swap(q, &mut r);
        r
    };
    // n = 0: nothing to do
    let mut q0: Vec<[f64; 4]> = Vec::new();
    let empty = SmoothInput {
        time: None,
        gyr: &[],
        acc: &[],
        mag: None,
    };
    smooth(
        &p,
        &empty,
        SmoothOutput {
            quat: &mut q0,
            spread: None,
            bias: None,
            covariance: None,
        },
    )
    .unwrap();
    // n = 1: the online AHRS's first estimate
    let mut q1 = vec![[0.0; 4]; 1];
    let one = SmoothInput {
        time: None,
        gyr: &s.gyr[..1],
        acc: &s.acc[..1],
        mag: Some(&s.mag[..1]),
    };
    smooth(
        &p,
        &one,
        SmoothOutput {
            quat: &mut q1,
            spread: None,
            bias: None,
            covariance: None,
        },
    )
    .unwrap();
    let mut a = Ahrs::new(&p).unwrap();
    a.update(&s.gyr[0], &s.acc[0], Some(&s.mag[0])).unwrap();
    assert_eq!(q1[0], a.quaternion());
    // uniform timestamps give the untimed result bit for bit
    let mut qa = vec![[0.0; 4]; n];
    smooth(
        &p,
        &input,
        SmoothOutput {
            quat: &mut qa,
            spread: None,
            bias: None,
            covariance: None,
        },
    )
    .unwrap();
    let t: Vec<f64> = (0..n).map(|k| 100.0 + k as f64 * s.dt).collect();
    let mut qb = vec![[0.0; 4]; n];
    smooth(
        &p,
        &SmoothInput {
            time: Some(&t),
            ..input
        },
        SmoothOutput {
            quat: &mut qb,
            spread: None,
            bias: None,
            covariance: None,
        },
    )
    .unwrap();
    let (qa, qb) = (out(&mut qa), out(&mut qb));
    let first = (0..n).find(|&k| qa[k] != qb[k]);
    assert!(first.is_none(), "first difference at {first:?} of {n}");
    // errors leave the outputs untouched
    let sentinel = [7.0; 4];
    let mut qe = vec![sentinel; n];
    let mut se = vec![7.0; n];
    // a wrong length
    let r = smooth(
        &p,
        &SmoothInput {
            acc: &s.acc[1..],
            ..input
        },
        SmoothOutput {
            quat: &mut qe,
            spread: Some(&mut se),
            bias: None,
            covariance: None,
        },
    );
    assert!(matches!(r, Err(bingham::Error::InvalidDimension(_))));
    // timestamps not increasing
    let mut tb = t.clone();
    tb[n / 2] = tb[n / 2 - 1];
    let r = smooth(
        &p,
        &SmoothInput {
            time: Some(&tb),
            ..input
        },
        SmoothOutput {
            quat: &mut qe,
            spread: Some(&mut se),
            bias: None,
            covariance: None,
        },
    );
    assert!(matches!(r, Err(bingham::Error::InvalidArgument(_))));
    // a gyroscope sample late in the recording that turns too far: refused by the forward pass
    let mut gb = s.gyr.clone();
    gb[n - 3] = [1e300, 0.0, 0.0];
    let r = smooth(
        &p,
        &SmoothInput { gyr: &gb, ..input },
        SmoothOutput {
            quat: &mut qe,
            spread: Some(&mut se),
            bias: None,
            covariance: None,
        },
    );
    assert!(matches!(r, Err(bingham::Error::InvalidArgument(ref m)) if m.contains("sample")));
    // the first accelerometer sample missing: no tilt to start from
    let mut ab = s.acc.clone();
    ab[0] = [f64::NAN; 3];
    let r = smooth(
        &p,
        &SmoothInput { acc: &ab, ..input },
        SmoothOutput {
            quat: &mut qe,
            spread: Some(&mut se),
            bias: None,
            covariance: None,
        },
    );
    assert!(r.is_err());
    assert!(qe.iter().all(|q| *q == sentinel) && se.iter().all(|x| *x == 7.0));
    // NaN rows (no sample) anywhere else, and the last accelerometer samples missing: smoothed
    let mut gn = s.gyr.clone();
    let mut an = s.acc.clone();
    let mut mn = s.mag.clone();
    gn[100] = [f64::NAN; 3];
    an[200] = [f64::NAN; 3];
    mn[300] = [f64::NAN; 3];
    an[n - 1] = [f64::NAN; 3];
    an[n - 2] = [0.0; 3];
    smooth(
        &p,
        &SmoothInput {
            gyr: &gn,
            acc: &an,
            mag: Some(&mn),
            time: None,
        },
        SmoothOutput {
            quat: &mut qe,
            spread: Some(&mut se),
            bias: None,
            covariance: None,
        },
    )
    .unwrap();
    for k in 0..n {
        assert!(
            angle(&qe[k], &s.truth[k]) < 10f64.to_radians(),
            "sample {k}"
        );
        assert!(se[k].is_finite() && se[k] > 0.0);
    }
}
