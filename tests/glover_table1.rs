//! Table 1 of Glover & Kaelbling (2013), "Tracking the spin on a ping pong ball with the
//! quaternion Bingham filter" (`../shared/papers/glover2013-quaternion-bingham-filter.txt`,
//! Sec. 6): the first-order quaternion Bingham filter (QBF) against an extended Kalman filter
//! (EKF) on simulated projected-Gaussian processes (issue 22, "Reproduce the paper's
//! experiments", item 1).
//!
//! **Process.** The paper's world-frame model `x_n = w_n ∘ u_n ∘ x_{n−1}`, `y_n = v_n ∘ x_n`
//! (`q ∘ r` the Hamilton product `q r`). The controls `u_n = x̄_n ∘ x̄_{n−1}⁻¹` make the nominal
//! orientation `x̄_n` (before noise) follow a sine wave in each Euler angle (yaw, pitch, roll;
//! amplitudes π, π/3, π; periods in [200, 400) steps and phases drawn per run). The noises `w_n`,
//! `v_n` are **projected Gaussians** whose second moment `E[w wᵀ]` equals that of the Bingham noise
//! the filters are told, `Bingham(I, (0, Λ))` — the paper's "matching second moments from the
//! Bingham to the projected Gaussian". The paper does not say where its Gaussian is centred, so
//! both readings are run:
//!
//! - `Central` (the mapping of issue 22): `w = g/|g|`, `g ~ N(0, Σ)` — the angular central
//!   Gaussian. `E[g_i²/|g|²] = ∫₀^∞ σ_i² (1 + 2tσ_i²)⁻¹ Πⱼ (1 + 2tσ_j²)^(−1/2) dt` (write
//!   `1/|g|² = ∫₀^∞ e^(−t|g|²) dt`), evaluated by the trapezoidal rule in `log t`, and a
//!   multiplicative fixed point `σ_i² ← σ_i² S_ii / E[g_i²/|g|²]` gives the diagonal `Σ` (scale
//!   fixed by `Σ_00 = 1`, since `g/|g|` does not depend on it). With the moment matched, this noise
//!   has a narrow core and heavy tails (for Λ = (−50)³: `σ_i = 0.016` against the Bingham's 0.1,
//!   3 % of the draws beyond 60°): the true orientation moves 4.9°, 5.9°, 12° per step for
//!   Λp = −400, −200, −50, where the paper reports 7°, 9°, 18°.
//! - `Tangent`: `w = g/|g|`, `g = (1, δ)`, `δ ~ N(0, diag(τ²))` — a Gaussian about the identity,
//!   the EKF's own noise model ("in order to match the EKF dynamics model"); the same integral
//!   with `e^(−t)` for the first factor, the same fixed point on `τ²`. Its motion, 7.5°, 9.9°,
//!   19°, matches the paper's.
//!
//! `projected_gaussian_matches_the_bingham_moment` checks both mappings against samples.
//!
//! **Settings.** `Λp ∈ {(−50)³, (−200)³, (−400)³} × Λo ∈ {(−400, −400, −10), (−400)³, (−50)³}`,
//! in the paper's column order (observation noise outer, process noise inner), 30 runs of 1000
//! steps each, one seed per run (`SEED + 100·setting + run`); both filters see the same data and
//! start from the same prior (mode at the true `x_0`, the process noise's spread).
//!
//! **QBF.** `BinghamFilter::predict_world(u, I, (0, Λp))` then `update_world(y, I, (0, Λo))`.
//! Its prediction is exact in the second moment for these data too (the composed moment depends on
//! the noise only through its second moment, which the projected Gaussian shares); its update
//! uses the Bingham likelihood, not the projected Gaussian's.
//!
//! **EKF.** LaViola's quaternion EKF as the paper adapted it (discrete time), in this file, not
//! in the library: state `x ∈ R⁴` with a 4×4 covariance `P`, Gaussian noise in R⁴, measurement
//! function `h(x) = x/|x|`, state renormalized after every update. Given its best chance:
//! `w ∘ (u ∘ x) = R(u ∘ x) w` is linear in `w`, so with `w ≈ e + δ` (`e` the identity),
//! `P⁻ = L(u) P L(u)ᵀ + R(u∘x̂) Q_w R(u∘x̂)ᵀ`; likewise the observation noise enters as
//! `R(h) Q_v R(h)ᵀ`. `Q = diag(q_r, S_11, S_22, S_33)`: the tangent variances are the Bingham's
//! (= the projected Gaussian's) second moments, so the EKF's noise is exactly matched and rotated
//! into the state's frame; `q_r = E[(1 − |w_0|)²]`, the radial part, does not affect the estimate
//! (`H = (I − hhᵀ)/|x|` removes it). The observation's sign is chosen nearest the prediction, the
//! covariance update is in Joseph form, and after the update the covariance is projected with the
//! Jacobian of the normalization.
//!
//! **Measured.** The angular error `2 acos |⟨x̂, x⟩|` after each update, its mean over the 1000
//! steps of a run, and per setting the mean over the 30 runs of the per-run decrease
//! `100 (1 − e_QBF/e_EKF)` with its standard error — the paper's "average % mean error decrease"
//! (Table 1: 37.3, 45.6, 54.3, 19.9, 3.33, 1.52, 3.42, 0.72, 0.47; QBF better on 268/270 runs).
//! What each test asserts, and why, is in its doc comment. Printed with `--nocapture`; the report
//! is in `docs/accuracy/filter.md`. The test `table1_ekf_variants` (with `BINGHAM_TABLE1_VARIANTS=1`) runs weaker EKFs (noise not
//! rotated into the state's frame, anisotropy averaged away) to show where the paper's larger
//! margins can come from.
//!
//! Run: `cargo test --release --test glover_table1 -- --nocapture`
//! (variants: `BINGHAM_TABLE1_VARIANTS=1 cargo test --release --test glover_table1 -- --nocapture`).

mod glover_common;

use bingham::filter::BinghamFilter;
use bingham::quaternion::{left_matrix, q4, right_matrix};
use bingham::Bingham;
use glover_common::{angle, lmat, rmat, to_q, I4};
use nalgebra::{Matrix4, Vector4};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::f64::consts::PI;

const SEED: u64 = 0x7AB1_E001;
const RUNS: usize = 30;
const STEPS: usize = 1000;

/// Process concentrations, the paper's inner loop.
const PROCESS: [f64; 3] = [-50.0, -200.0, -400.0];
/// Observation concentrations, the paper's outer loop.
const OBSERVATION: [[f64; 3]; 3] = [
    [-400.0, -400.0, -10.0],
    [-400.0, -400.0, -400.0],
    [-50.0, -50.0, -50.0],
];
/// Table 1's row, in the same order (process inner, observation outer).
const PAPER: [(f64, f64); 9] = [
    (37.3, 5.1),
    (45.6, 5.0),
    (54.3, 6.4),
    (19.9, 1.8),
    (3.33, 0.53),
    (1.52, 0.44),
    (3.42, 0.88),
    (0.72, 0.40),
    (0.47, 0.27),
];

// ---------------------------------------------------------------------------------------------
// The nominal trajectory

/// `qz(yaw) ∘ qy(pitch) ∘ qx(roll)`.
fn euler(yaw: f64, pitch: f64, roll: f64) -> [f64; 4] {
    let qz = [(0.5 * yaw).cos(), 0.0, 0.0, (0.5 * yaw).sin()];
    let qy = [(0.5 * pitch).cos(), 0.0, (0.5 * pitch).sin(), 0.0];
    let qx = [(0.5 * roll).cos(), (0.5 * roll).sin(), 0.0, 0.0];
    q4::mul(&qz, &q4::mul(&qy, &qx))
}

/// The nominal orientation: a sine wave in each Euler angle, with per-run periods and phases.
struct Nominal {
    amplitude: [f64; 3],
    period: [f64; 3],
    phase: [f64; 3],
}

impl Nominal {
    fn draw(rng: &mut StdRng) -> Nominal {
        Nominal {
            amplitude: [PI, PI / 3.0, PI],
            period: [0; 3].map(|_| rng.gen_range(200.0..400.0)),
            phase: [0; 3].map(|_| rng.gen_range(0.0..2.0 * PI)),
        }
    }

    fn at(&self, n: usize) -> [f64; 4] {
        let a: [f64; 3] = std::array::from_fn(|k| {
            self.amplitude[k] * (2.0 * PI * n as f64 / self.period[k] + self.phase[k]).sin()
        });
        euler(a[0], a[1], a[2])
    }
}

// ---------------------------------------------------------------------------------------------
// The projected-Gaussian noise

/// How a noise quaternion is drawn from a Gaussian in R⁴.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// `w = g/|g|`, `g ~ N(0, diag(σ²))` (`σ_0 = 1`): the angular central Gaussian.
    Central,
    /// `w = g/|g|`, `g = (1, δ)`, `δ ~ N(0, diag(τ_1², τ_2², τ_3²))`: a Gaussian about the
    /// identity, as an EKF models its noise.
    Tangent,
}

/// For `w` of the given kind with variances `s` (`s_0` unused for `Tangent`): the diagonal of
/// `E[w wᵀ]` and `E|w_0|`. With `1/|g|² = ∫₀^∞ e^(−t|g|²) dt`,
/// `E[g_i²/|g|²] = ∫₀^∞ s_i (1 + 2t s_i)⁻¹ c_0(t) Πⱼ≥1 (1 + 2t s_j)^(−1/2) dt`, and with
/// `1/|g| = π^(−1/2) ∫₀^∞ t^(−1/2) e^(−t|g|²) dt`,
/// `E|g_0|/|g| = π^(−1/2) ∫₀^∞ t^(−1/2) a_0(t) Πⱼ≥1 (1 + 2t s_j)^(−1/2) dt`, where
/// `c_0 = (1 + 2t s_0)^(−1/2)`, `a_0 = √(2 s_0/π) (1 + 2t s_0)⁻¹` (central) or
/// `c_0 = a_0 = e^(−t)` (tangent: `g_0 = 1`). Trapezoidal rule in `u = log t` (the integrands
/// decay exponentially in `u` at both ends, where the rule converges geometrically).
fn pg_moments(kind: Kind, s: &[f64; 4]) -> ([f64; 4], f64) {
    let first = if kind == Kind::Central { 0 } else { 1 };
    let smax = s[first..].iter().cloned().fold(0.0, f64::max);
    let smin = s[first..].iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = match kind {
        Kind::Central => (1e24 / smin).ln(),
        Kind::Tangent => 800f64.ln(),
    };
    let (lo, h) = ((1e-40 / smax).ln(), 0.02);
    let n = ((hi - lo) / h).ceil() as usize;
    let (mut m, mut a) = ([0.0; 4], 0.0);
    for k in 0..=n {
        let t = (lo + k as f64 * h).exp();
        let f: [f64; 4] = std::array::from_fn(|j| 1.0 + 2.0 * t * s[j]);
        let rest = f[1..].iter().map(|f| f.sqrt()).product::<f64>();
        let (c0, a0) = match kind {
            Kind::Central => (1.0 / f[0].sqrt(), (2.0 * s[0] / PI).sqrt() / f[0]),
            Kind::Tangent => ((-t).exp(), (-t).exp()),
        };
        let w = if k == 0 || k == n { 0.5 * h } else { h } * t / rest;
        for i in first..4 {
            m[i] += w * c0 * s[i] / f[i];
        }
        a += w * t.powf(-0.5) * a0 / PI.sqrt();
    }
    if kind == Kind::Tangent {
        m[0] = 1.0 - m[1] - m[2] - m[3];
    }
    (m, a)
}

/// A noise `Bingham(I, (0, λ1, λ2, λ3))` and the projected Gaussian that shares its second moment.
#[derive(Clone, Copy)]
struct Noise {
    kind: Kind,
    /// The Bingham concentrations `(0, λ1, λ2, λ3)`, as the QBF is told.
    z: [f64; 4],
    /// The Bingham's second moment (diagonal).
    moment: [f64; 4],
    /// Standard deviations of the Gaussian in R⁴ (`σ_0 = 1` for `Central`, unused for `Tangent`).
    sigma: [f64; 4],
    /// `E[(1 − |w_0|)²]`: the radial variance about the identity.
    radial: f64,
}

impl Noise {
    fn new(kind: Kind, lambda: [f64; 3]) -> Noise {
        let z = [0.0, lambda[0], lambda[1], lambda[2]];
        let s = Bingham::from_row_major(4, &I4, &z)
            .unwrap()
            .second_moment()
            .unwrap();
        for i in 0..4 {
            for j in 0..4 {
                if i != j {
                    assert!(s[(i, j)].abs() < 1e-14, "moment not diagonal: {s}");
                }
            }
        }
        let moment: [f64; 4] = std::array::from_fn(|i| s[(i, i)]);
        // multiplicative fixed point on the variances (central: the scale fixed by Σ_00 = 1)
        let mut var = moment.map(|m| m / moment[0]);
        let mut converged = false;
        for _ in 0..200 {
            let (m, _) = pg_moments(kind, &var);
            let err = (0..4)
                .map(|i| (m[i] / moment[i] - 1.0).abs())
                .fold(0.0, f64::max);
            if err < 1e-12 {
                converged = true;
                break;
            }
            match kind {
                Kind::Central => {
                    (0..4).for_each(|i| var[i] *= moment[i] / m[i]);
                    let v0 = var[0];
                    var.iter_mut().for_each(|v| *v /= v0);
                }
                Kind::Tangent => (1..4).for_each(|i| var[i] *= moment[i] / m[i]),
            }
        }
        assert!(
            converged,
            "the moment mapping did not converge for {kind:?} {lambda:?}"
        );
        let (_, abs0) = pg_moments(kind, &var);
        Noise {
            kind,
            z,
            moment,
            sigma: var.map(f64::sqrt),
            radial: 1.0 - 2.0 * abs0 + moment[0],
        }
    }

    /// One draw of `w`.
    fn sample(&self, rng: &mut StdRng) -> [f64; 4] {
        let mut g = [0.0; 4];
        for k in 0..2 {
            let (u1, u2): (f64, f64) = (1.0 - rng.gen::<f64>(), rng.gen());
            let r = (-2.0 * u1.ln()).sqrt();
            g[2 * k] = r * (2.0 * PI * u2).cos();
            g[2 * k + 1] = r * (2.0 * PI * u2).sin();
        }
        let mut g: [f64; 4] = std::array::from_fn(|i| g[i] * self.sigma[i]);
        if self.kind == Kind::Tangent {
            g[0] = 1.0;
        }
        let n = g.iter().map(|a| a * a).sum::<f64>().sqrt();
        g.map(|a| a / n)
    }

    /// The EKF's covariance of `w − e` in the noise's own frame: `diag(q_r, S_11, S_22, S_33)`,
    /// the tangent part averaged for `RotatedIsotropic`, `q_r` the mean tangent variance for
    /// `FixedTangentRadial`.
    fn covariance(&self, how: EkfNoise) -> Matrix4<f64> {
        let mut t = [self.moment[1], self.moment[2], self.moment[3]];
        let mean = t.iter().sum::<f64>() / 3.0;
        if how == EkfNoise::RotatedIsotropic {
            t = [mean; 3];
        }
        let r = if how == EkfNoise::FixedTangentRadial {
            mean
        } else {
            self.radial
        };
        Matrix4::from_diagonal(&Vector4::new(r, t[0], t[1], t[2]))
    }
}

// ---------------------------------------------------------------------------------------------
// The EKF (LaViola, discrete time, as adapted by Glover & Kaelbling)

/// How the EKF is told the noise.
#[derive(Clone, Copy, Debug, PartialEq)]
enum EkfNoise {
    /// Matched second moments, rotated into the state's frame (`R(u∘x̂) Q R(u∘x̂)ᵀ`): the best.
    Rotated,
    /// Matched second moments, anisotropy averaged away, rotated.
    RotatedIsotropic,
    /// Matched second moments as an additive covariance in fixed R⁴ coordinates, not rotated.
    Fixed,
    /// As `Fixed`, with the radial variance set to the mean tangent one (for isotropic noise,
    /// `s I`, which needs no rotation).
    FixedTangentRadial,
}

struct Ekf {
    x: Vector4<f64>,
    p: Matrix4<f64>,
    q_w: Matrix4<f64>,
    q_v: Matrix4<f64>,
    rotated: bool,
}

impl Ekf {
    fn new(x0: &[f64; 4], process: &Noise, observation: &Noise, how: EkfNoise) -> Ekf {
        let l = lmat(x0);
        Ekf {
            x: Vector4::from(*x0),
            p: l * process.covariance(EkfNoise::Rotated) * l.transpose(),
            q_w: process.covariance(how),
            q_v: observation.covariance(how),
            rotated: matches!(how, EkfNoise::Rotated | EkfNoise::RotatedIsotropic),
        }
    }

    /// `x ← w ∘ u ∘ x`: `F = L(u)`, the noise Jacobian `R(u ∘ x̂)`.
    fn predict(&mut self, u: &[f64; 4]) {
        let f = lmat(u);
        self.x = f * self.x;
        let g = if self.rotated {
            rmat(&to_q(&self.x))
        } else {
            Matrix4::identity()
        };
        self.p = f * self.p * f.transpose() + g * self.q_w * g.transpose();
    }

    /// `y = v ∘ h(x)`, `h(x) = x/|x|`; then renormalize.
    fn update(&mut self, y: &[f64; 4]) {
        let n = self.x.norm();
        let h = self.x / n;
        let mut y = Vector4::from(*y);
        if y.dot(&h) < 0.0 {
            y = -y;
        }
        let jac = (Matrix4::identity() - h * h.transpose()) / n;
        let g = if self.rotated {
            rmat(&to_q(&h))
        } else {
            Matrix4::identity()
        };
        let s = jac * self.p * jac.transpose() + g * self.q_v * g.transpose();
        let k = self.p * jac.transpose() * s.try_inverse().expect("innovation covariance");
        self.x += k * (y - h);
        let a = Matrix4::identity() - k * jac;
        // Joseph form
        self.p = a * self.p * a.transpose() + k * g * self.q_v * g.transpose() * k.transpose();
        let n = self.x.norm();
        self.x /= n;
        let jn = (Matrix4::identity() - self.x * self.x.transpose()) / n;
        self.p = jn * self.p * jn.transpose();
    }
}

// ---------------------------------------------------------------------------------------------
// The experiment

/// Per-run mean errors (radians) of the QBF and of each EKF variant.
struct Run {
    qbf: f64,
    ekf: Vec<f64>,
    /// Mean angle between successive true orientations.
    motion: f64,
    /// Mean angle of the control `u`.
    control: f64,
}

fn row_major(m: &Matrix4<f64>) -> Vec<f64> {
    (0..16).map(|k| m[(k / 4, k % 4)]).collect()
}

fn run(process: &Noise, observation: &Noise, seed: u64, variants: &[EkfNoise]) -> Run {
    let mut rng = StdRng::seed_from_u64(seed);
    let nominal = Nominal::draw(&mut rng);
    let mut x = nominal.at(0);
    let mut qbf = BinghamFilter::new(4, &row_major(&lmat(&x)), &process.z).unwrap();
    let mut ekfs: Vec<Ekf> = variants
        .iter()
        .map(|&v| Ekf::new(&x, process, observation, v))
        .collect();
    let (mut e_qbf, mut e_ekf) = (0.0, vec![0.0; variants.len()]);
    let (mut motion, mut control) = (0.0, 0.0);
    let mut prev = x;
    for n in 1..=STEPS {
        let now = nominal.at(n);
        let u = q4::mul(&now, &q4::conj(&prev));
        prev = now;
        control += angle(&u, &[1.0, 0.0, 0.0, 0.0]);
        let w = process.sample(&mut rng);
        let next = q4::mul(&w, &q4::mul(&u, &x));
        motion += angle(&next, &x);
        x = next;
        let y = q4::mul(&observation.sample(&mut rng), &x);

        qbf.predict_world(Some(&u), &I4, &process.z).unwrap();
        qbf.update_world(&y, &I4, &observation.z).unwrap();
        e_qbf += angle(&qbf.mode(), &x);
        for (ekf, e) in ekfs.iter_mut().zip(e_ekf.iter_mut()) {
            ekf.predict(&u);
            ekf.update(&y);
            *e += angle(ekf.x.as_slice(), &x);
        }
    }
    let steps = STEPS as f64;
    Run {
        qbf: e_qbf / steps,
        ekf: e_ekf.iter().map(|e| e / steps).collect(),
        motion: motion / steps,
        control: control / steps,
    }
}

/// One setting's summary against one EKF variant.
struct Row {
    qbf: f64,
    ekf: f64,
    /// Mean and standard error over the runs of `100 (1 − e_QBF/e_EKF)`.
    decrease: (f64, f64),
    wins: usize,
}

fn summarize(runs: &[Run], variant: usize) -> Row {
    let r = runs.len() as f64;
    let d: Vec<f64> = runs
        .iter()
        .map(|x| 100.0 * (1.0 - x.qbf / x.ekf[variant]))
        .collect();
    let mean = d.iter().sum::<f64>() / r;
    let var = d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (r - 1.0);
    Row {
        qbf: runs.iter().map(|x| x.qbf).sum::<f64>() / r,
        ekf: runs.iter().map(|x| x.ekf[variant]).sum::<f64>() / r,
        decrease: (mean, (var / r).sqrt()),
        wins: runs.iter().filter(|x| x.qbf < x.ekf[variant]).count(),
    }
}

fn fmt3(l: &[f64; 3]) -> String {
    if l[0] == l[1] && l[1] == l[2] {
        format!("({})³", l[0])
    } else {
        format!("({}, {}, {})", l[0], l[1], l[2])
    }
}

/// The nine settings in the paper's order; for each, the runs.
fn table(kind: Kind, variants: &[EkfNoise]) -> Vec<(String, Vec<Run>)> {
    let mut out = Vec::new();
    for (o, lo) in OBSERVATION.iter().enumerate() {
        let obs = Noise::new(kind, *lo);
        for (p, &lp) in PROCESS.iter().enumerate() {
            let proc_ = Noise::new(kind, [lp; 3]);
            let setting = 3 * o + p;
            let runs: Vec<Run> = (0..RUNS)
                .map(|r| {
                    run(
                        &proc_,
                        &obs,
                        SEED + 100 * setting as u64 + r as u64,
                        variants,
                    )
                })
                .collect();
            out.push((
                format!("Λp = {:<6} Λo = {}", fmt3(&[lp; 3]), fmt3(lo)),
                runs,
            ));
        }
    }
    out
}

fn print_table(title: &str, settings: &[(String, Vec<Run>)], variant: usize) -> Vec<Row> {
    println!("\n{title}");
    println!(
        "{:<42} {:>9} {:>9} {:>16} {:>14} {:>6}",
        "setting", "QBF (°)", "EKF (°)", "% decrease ± SE", "paper", "wins"
    );
    let deg = 180.0 / PI;
    let mut rows = Vec::new();
    for (k, (name, runs)) in settings.iter().enumerate() {
        let row = summarize(runs, variant);
        println!(
            "{:<42} {:>9.3} {:>9.3} {:>9.2} ± {:<5.2} {:>6.2} ± {:<5.2} {:>3}/{}",
            name,
            row.qbf * deg,
            row.ekf * deg,
            row.decrease.0,
            row.decrease.1,
            PAPER[k].0,
            PAPER[k].1,
            row.wins,
            runs.len()
        );
        rows.push(row);
    }
    let wins: usize = rows.iter().map(|r| r.wins).sum();
    println!(
        "QBF better on {wins}/{} runs (paper: 268/270)",
        RUNS * settings.len()
    );
    rows
}

fn print_motion(settings: &[(String, Vec<Run>)]) {
    // mean angular change of the true state per step, per process noise (paper: 18°, 9°, 7°)
    for (p, lp) in PROCESS.iter().enumerate() {
        let runs: Vec<&Run> = settings
            .iter()
            .enumerate()
            .filter(|(k, _)| k % 3 == p)
            .flat_map(|(_, (_, r))| r)
            .collect();
        let mean = |f: fn(&Run) -> f64| runs.iter().map(|r| f(r)).sum::<f64>() / runs.len() as f64;
        println!(
            "Λp = ({lp})³: mean angular change of the true orientation per step {:.1}° \
             (of the control alone {:.1}°)",
            mean(|r| r.motion).to_degrees(),
            mean(|r| r.control).to_degrees()
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Tests

/// The shared helpers (`tests/glover_common`) agree with the library's quaternion matrices.
#[test]
fn quaternion_matrices_match_the_library() {
    let mut rng = StdRng::seed_from_u64(SEED);
    for _ in 0..10 {
        let q = Noise::new(Kind::Central, [-1.0; 3]).sample(&mut rng);
        let (l, r) = (left_matrix(&q), right_matrix(&q));
        let (lm, rm) = (lmat(&q), rmat(&q));
        for i in 0..4 {
            for j in 0..4 {
                assert!((l[(i, j)] - lm[(i, j)]).abs() < 1e-15);
                assert!((r[(i, j)] - rm[(i, j)]).abs() < 1e-15);
            }
        }
    }
}

/// For both kinds of projected Gaussian, the sample second moment of `w` equals the Bingham's
/// within a few standard errors (every entry, 4·10⁵ samples per noise), and so does the radial
/// moment `E[(1 − |w_0|)²]` the EKF is given; the naive mapping (the Gaussian's own variances
/// set to the Bingham's moments) is detectably wrong where the noise is broad, so the check has
/// the power to fail.
#[test]
fn projected_gaussian_matches_the_bingham_moment() {
    const N: usize = 400_000;
    let mut rng = StdRng::seed_from_u64(SEED ^ 0xA5A5);
    for kind in [Kind::Central, Kind::Tangent] {
        for lambda in [
            [-50.0; 3],
            [-200.0; 3],
            [-400.0; 3],
            [-400.0, -400.0, -10.0],
        ] {
            let noise = Noise::new(kind, lambda);
            let mut naive = noise;
            naive.sigma = match kind {
                Kind::Central => noise.moment.map(|m| (m / noise.moment[0]).sqrt()),
                Kind::Tangent => noise.moment.map(f64::sqrt),
            };
            for (which, nz) in [("matched", &noise), ("naive", &naive)] {
                let (mut s1, mut s2) = ([[0.0; 4]; 4], [[0.0; 4]; 4]);
                let (mut r1, mut r2) = (0.0, 0.0);
                for _ in 0..N {
                    let w = nz.sample(&mut rng);
                    let r = (1.0 - w[0].abs()).powi(2);
                    r1 += r;
                    r2 += r * r;
                    for i in 0..4 {
                        for j in 0..4 {
                            let v = w[i] * w[j];
                            s1[i][j] += v;
                            s2[i][j] += v * v;
                        }
                    }
                }
                let n = N as f64;
                let z_score = |sum: f64, sum2: f64, target: f64| {
                    let mean = sum / n;
                    (mean - target).abs() / ((sum2 / n - mean * mean) / n).sqrt()
                };
                let mut max_z: f64 = 0.0;
                for i in 0..4 {
                    for j in 0..4 {
                        let target = if i == j { noise.moment[i] } else { 0.0 };
                        max_z = max_z.max(z_score(s1[i][j], s2[i][j], target));
                    }
                }
                let z_radial = z_score(r1, r2, noise.radial);
                println!(
                    "{kind:?} Λ = {:<22} {which:<7}: worst |sample − Bingham| entry {max_z:6.2} SE, \
                     E[(1−|w0|)²] {:.3e} (sample {:.3e}, {z_radial:.2} SE)",
                    fmt3(&lambda),
                    noise.radial,
                    r1 / n
                );
                if which == "matched" {
                    assert!(max_z < 4.5, "{kind:?} {lambda:?}: off by {max_z} SE");
                    assert!(
                        z_radial < 4.5,
                        "{kind:?} {lambda:?}: radial moment off by {z_radial} SE"
                    );
                } else if lambda[0] == -50.0 || lambda[2] == -10.0 {
                    assert!(
                        max_z > 10.0,
                        "{kind:?} {lambda:?}: the naive mapping went unnoticed"
                    );
                }
            }
        }
    }
}

/// Runs the nine settings against the best EKF and prints the table.
fn measure(kind: Kind) -> (Vec<String>, Vec<Row>) {
    let settings = table(kind, &[EkfNoise::Rotated]);
    let rows = print_table(
        &format!(
            "Table 1 (Glover & Kaelbling 2013), {kind:?} projected-Gaussian noise: QBF vs EKF \
             (noise matched, rotated into the state's frame); mean angular error, 30 runs × 1000 steps"
        ),
        &settings,
        0,
    );
    print_motion(&settings);
    (settings.into_iter().map(|(n, _)| n).collect(), rows)
}

/// Table 1 with the angular central Gaussian noise (`g ~ N(0, Σ)`, the mapping of issue 22).
/// The QBF is ahead on every setting, on average by more than 2 standard errors (measured: 3.0 SE
/// at (−400)³/(−400)³, 8 SE and more elsewhere) and on most runs of each setting (measured: 20/30
/// at (−400)³/(−400)³, 28–30/30 on the others, 258/270 in all; with two other seeds 22–24/30
/// there and 258–264/270). Asserted: ≥ 16/30 per setting, ≥ 240/270 in all — a few runs of slack
/// below the lowest measured figure, since single runs may flip on another platform's rounding.
/// The margin comes from the heavy tails of this noise (see the report), which the Bingham update
/// resists and the Kalman update does not.
#[test]
fn table1_central_qbf_beats_the_ekf() {
    let (names, rows) = measure(Kind::Central);
    for (name, row) in names.iter().zip(&rows) {
        assert!(
            row.qbf < row.ekf,
            "{name}: QBF {} not below EKF {}",
            row.qbf,
            row.ekf
        );
        let (d, se) = row.decrease;
        assert!(
            d > 2.0 * se,
            "{name}: mean per-run decrease {d:.3} ± {se:.3} %"
        );
        assert!(
            row.wins >= 18,
            "{name}: QBF better on only {}/30 runs",
            row.wins
        );
    }
    let total: usize = rows.iter().map(|r| r.wins).sum();
    assert!(total >= 240, "QBF better on only {total}/270 runs");
}

/// Table 1 with the Gaussian about the identity (`g = (1, δ)`), the noise whose mean angular
/// motion matches the paper's (7°, 9°, 18°). Against the best EKF, the QBF is ahead where the
/// observation noise is anisotropic (measured 1.6–3.4 %, ≥ 13 SE; 30/30 runs, 28–30 with other
/// seeds; asserted: > 4 SE, ≥ 25/30) and where the process noise is broad ((−50)³: 0.20–0.37 %,
/// ≥ 6 SE; asserted > 4 SE); on the four other isotropic settings both filters are the same to
/// within 0.05 % (0.00 ± 0.00 % to 0.02 ± 0.01 %; −0.01 ± 0.01 % with other seeds), and the test
/// asserts only that the QBF is not worse there by more than 0.1 %. In all ≥ 180/270 runs
/// (measured 215, 212–213 with other seeds).
#[test]
fn table1_tangent_qbf_beats_the_ekf() {
    let (names, rows) = measure(Kind::Tangent);
    for (k, (name, row)) in names.iter().zip(&rows).enumerate() {
        let (d, se) = row.decrease;
        let anisotropic = k < 3;
        let broad_process = k % 3 == 0;
        if anisotropic || broad_process {
            assert!(
                row.qbf < row.ekf,
                "{name}: QBF {} not below EKF {}",
                row.qbf,
                row.ekf
            );
            assert!(
                d > 4.0 * se,
                "{name}: mean per-run decrease {d:.3} ± {se:.3} %"
            );
        } else {
            assert!(
                d > -0.1,
                "{name}: QBF worse than the EKF by {:.3} ± {se:.3} %",
                -d
            );
        }
        if anisotropic {
            assert!(
                row.wins >= 25,
                "{name}: QBF better on only {}/30 runs",
                row.wins
            );
        }
    }
    let total: usize = rows.iter().map(|r| r.wins).sum();
    assert!(total >= 180, "QBF better on only {total}/270 runs");
}

/// Weaker EKFs: the noise not rotated into the state's frame, the anisotropy averaged away —
/// how much of the paper's margin they explain. Runs only with `BINGHAM_TABLE1_VARIANTS=1` (four
/// EKFs on both noise models, too long for every CI run); it asserts that every weaker variant
/// leaves the QBF a larger mean margin than the best-chance EKF of the CI tests.
#[test]
fn table1_ekf_variants() {
    if std::env::var_os("BINGHAM_TABLE1_VARIANTS").is_none() {
        return;
    }
    let variants = [
        EkfNoise::Rotated,
        EkfNoise::RotatedIsotropic,
        EkfNoise::Fixed,
        EkfNoise::FixedTangentRadial,
    ];
    for kind in [Kind::Central, Kind::Tangent] {
        let settings = table(kind, &variants);
        let mut means = vec![];
        for (k, v) in variants.iter().enumerate() {
            let rows = print_table(&format!("{kind:?} noise, EKF variant {v:?}"), &settings, k);
            means.push(rows.iter().map(|r| r.decrease.0).sum::<f64>() / rows.len() as f64);
        }
        for (k, m) in means.iter().enumerate().skip(1) {
            assert!(
                *m > means[0],
                "{kind:?}: variant {:?} leaves a mean margin {m:.2} % ≤ the best EKF's {:.2} %",
                variants[k],
                means[0]
            );
        }
    }
}
