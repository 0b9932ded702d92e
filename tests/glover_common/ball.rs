//! The simulated ping-pong balls of Glover & Kaelbling (2013), Sec. 6, and the QBF-2 that
//! tracks them: shared by `tests/glover_spin.rs` (the experiment, described there) and
//! `tests/glover_spin_failures.rs` (what sets the spin error).
// each test binary uses a part
#![allow(dead_code)]

use crate::glover_common::{draw, m_with_mode, mul, normalized, I4, Q};
use bingham::filter::SpinFilter;
use bingham::quaternion::q4;
use bingham::Bingham;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::f64::consts::PI;

pub const IDENTITY: Q = [1.0, 0.0, 0.0, 0.0];
pub const FRAMES: usize = 40;
pub const PER_TYPE: usize = 20;
pub const TYPES: usize = 12;
pub const MIN_DETECTIONS: usize = 8;
pub const SEED: u64 = 2013;

/// Noises with the identity as mode, `m = I`: concentrations on `(1, i, j, k)`.
pub const Z_PROCESS: [f64; 4] = [0.0, -400.0, -400.0, -400.0];
pub const Z_DETECT: [f64; 4] = [0.0, -40.0, -40.0, -10.0];
pub const Z_DARK: [f64; 4] = [0.0, -3.6, -3.6, 0.0];
pub const Z_JITTER: [f64; 4] = [0.0, -4000.0, -4000.0, -4000.0];
/// Spin priors, with `m_with_mode` (the mode last).
pub const Z_SPIN_PRIOR: [f64; 4] = [-3.0, -3.0, -3.0, 0.0];
pub const Z_BANK_PRIOR: [f64; 4] = [-10.0, -10.0, -10.0, 0.0];

pub const TOWARD_CAMERA: [f64; 3] = [0.0, 0.0, 1.0];
/// The logo's normal in the body frame.
pub const LOGO: [f64; 3] = [0.0, 0.0, 1.0];
/// 180° about the logo's normal: `y` and `y ∘ FLIP` look the same.
pub const FLIP: Q = [0.0, 0.0, 0.0, 1.0];
/// The orientation with the logo in the centre of the back side (180° about x: body z → −z).
pub const Y_DARK: Q = [0.0, 1.0, 0.0, 0.0];
pub const FPS: f64 = 200.0;
pub const REV_PER_S: [f64; 3] = [25.0, 37.5, 50.0];
pub const AXES: [(&str, [f64; 3]); 4] = [
    ("top-spin", [0.0, 1.0, 0.0]),
    ("under-spin", [0.0, -1.0, 0.0]),
    ("left side-spin", [0.0, 0.0, 1.0]),
    ("right side-spin", [0.0, 0.0, -1.0]),
];

// ---------------------------------------------------------------------------------------------
// the logo and the spin types

pub fn logo_faces_camera(x: &Q) -> bool {
    let d = q4::rotate(x, &LOGO);
    d.iter()
        .zip(&TOWARD_CAMERA)
        .map(|(a, b)| a * b)
        .sum::<f64>()
        > 0.0
}

/// The mean spin (rotation per frame) of spin type `k` (axis `k / 3`, speed `k % 3`).
pub fn type_mean(k: usize) -> Q {
    let a = AXES[k / 3].1;
    let rate = 2.0 * PI * REV_PER_S[k % 3] / FPS;
    q4::from_rotation_vector(&[a[0] * rate, a[1] * rate, a[2] * rate])
}

pub fn log_mean_exp(a: f64, b: f64) -> f64 {
    let m = a.max(b);
    m + (0.5 * ((a - m).exp() + (b - m).exp())).ln()
}

// ---------------------------------------------------------------------------------------------
// the simulation

#[derive(Debug, Clone, Copy)]
pub enum Obs {
    Logo(Q),
    Dark,
}

pub struct Trajectory {
    pub kind: usize,
    pub spin: Q,
    pub x: Vec<Q>,
    pub obs: Vec<Obs>,
    pub redrawn: usize,
}

pub struct Noises {
    pub uniform: Bingham,
    pub process: Bingham,
    pub detect: Bingham,
    pub jitter: Bingham,
}

pub fn simulate(kind: usize, index: usize, n: &Noises) -> Trajectory {
    let mut rng = StdRng::seed_from_u64(SEED * 1_000_003 + (kind * 1000 + index) as u64);
    let spin = normalized(&mul(&draw(&n.process, &mut rng), &type_mean(kind)));
    let mut redrawn = 0;
    loop {
        let mut x = draw(&n.uniform, &mut rng);
        let (mut xs, mut obs) = (Vec::with_capacity(FRAMES), Vec::with_capacity(FRAMES));
        let mut detections = 0;
        for _ in 0..FRAMES {
            x = normalized(&mul(&mul(&draw(&n.jitter, &mut rng), &spin), &x));
            xs.push(x);
            if logo_faces_camera(&x) {
                detections += 1;
                let mut y = normalized(&mul(&draw(&n.detect, &mut rng), &x));
                if rng.gen_bool(0.5) {
                    y = mul(&y, &FLIP);
                }
                obs.push(Obs::Logo(y));
            } else {
                obs.push(Obs::Dark);
            }
        }
        if detections >= MIN_DETECTIONS {
            return Trajectory {
                kind,
                spin,
                x: xs,
                obs,
                redrawn,
            };
        }
        redrawn += 1;
    }
}

// ---------------------------------------------------------------------------------------------
// the Bingham filters

/// The type whose mean spin has the highest density under `b` (the normalization is common).
pub fn classify(b: &Bingham, means: &[Q]) -> usize {
    let mut best = (f64::NEG_INFINITY, 0);
    for (k, m) in means.iter().enumerate() {
        let e = b.log_pdf_given(m, 0.0).expect("exponent");
        if e > best.0 {
            best = (e, k);
        }
    }
    best.1
}

/// QBF-2: the spin filter with the noises it assumes.
#[derive(Clone)]
pub struct Qbf2 {
    pub f: SpinFilter,
    pub total: f64,
    pub z_process: [f64; 4],
    pub z_detect: [f64; 4],
}

impl Qbf2 {
    pub fn new(spin_mode: &Q, z_v: &[f64; 4]) -> Qbf2 {
        Qbf2::with_noises(spin_mode, z_v, Z_PROCESS, Z_DETECT)
    }

    pub fn with_noises(
        spin_mode: &Q,
        z_v: &[f64; 4],
        z_process: [f64; 4],
        z_detect: [f64; 4],
    ) -> Qbf2 {
        Qbf2 {
            f: SpinFilter::new(&I4, &[0.0; 4], &m_with_mode(spin_mode), z_v).expect("spin filter"),
            total: 0.0,
            z_process,
            z_detect,
        }
    }

    pub fn frame(&mut self, obs: &Obs, what: &str) {
        let ll = |y: &Q, z: &[f64]| {
            self.f
                .log_likelihood(y, &I4, z)
                .unwrap_or_else(|e| panic!("{what}: log_likelihood: {e}"))
        };
        let (y, z) = match obs {
            Obs::Logo(y) => {
                let y2 = mul(y, &FLIP);
                let (a, b) = (ll(y, &self.z_detect), ll(&y2, &self.z_detect));
                self.total += log_mean_exp(a, b);
                (if a >= b { *y } else { y2 }, self.z_detect)
            }
            Obs::Dark => {
                self.total += ll(&Y_DARK, &Z_DARK);
                (Y_DARK, Z_DARK)
            }
        };
        self.f
            .step(None, &I4, &self.z_process, Some(&y), &I4, &z)
            .unwrap_or_else(|e| panic!("{what}: step: {e}"));
    }
}

pub fn noises(z_detect: &[f64; 4]) -> Noises {
    let b = |z: &[f64; 4]| Bingham::from_row_major(4, &I4, z).unwrap();
    Noises {
        uniform: b(&[0.0; 4]),
        process: b(&Z_PROCESS),
        detect: b(z_detect),
        jitter: b(&Z_JITTER),
    }
}
