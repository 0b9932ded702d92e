//! Long runs of the filter (`bingham::filter::BinghamFilter`) for d = 2 and d = 4 under
//! conditions a robot meets over hours:
//!
//! - (a) `sharp`: measurement noise so sharp that the concentrations grow to 1e6 and far
//!   beyond (updates only, and updates with a tiny process noise);
//! - (b) `near_uniform`: near-uniform states (z ≈ 0) with weak noises, and exactly uniform
//!   process noise (z_w = 0);
//! - (c) `antipodal_orthogonal`: measurements antipodal and orthogonal to the current mode;
//! - (d) `alternating`: huge and tiny noises alternating, random measurements and rotations.
//!
//! After every step: no NaN/Inf, M orthonormal to 1e-12, z finite, ascending, z[d−1] = 0 (a
//! valid Bingham state), and the scenario's own sanity checks. Every step must succeed (valid
//! inputs; the prediction caps concentrations at `MAX_CONCENTRATION`, documented in
//! src/filter/, and the update works for any finite concentration).
//!
//! Steps per scenario and dimension: `BINGHAM_LONG_STEPS` (default 10⁴ in `cargo test`;
//! `make long` runs 10⁶).

use std::time::Instant;

use bingham::filter::{BinghamFilter, MAX_CONCENTRATION};
use bingham::quaternion::compose;
use testkit::fuzz::{check_state, check_unit, env_count, identity};
use testkit::{norm, Rng64};

fn steps() -> u64 {
    env_count("BINGHAM_LONG_STEPS", 10_000)
}

/// Noise with the identity (1, 0, …) as its mode: M = I, z = (0, −k, …, −k).
fn noise(d: usize, k: f64) -> (Vec<f64>, Vec<f64>) {
    let mut z = vec![-k; d];
    z[0] = 0.0;
    (identity(d), z)
}

/// A unit vector within angle ~`s` of `x` (either sign).
fn near(rng: &mut Rng64, x: &[f64], s: f64) -> Vec<f64> {
    let v: Vec<f64> = x.iter().map(|c| c + s * rng.normal()).collect();
    let n = norm(&v);
    v.iter().map(|c| c / n).collect()
}

/// Angle between two axes (x and −x are the same).
fn axis_angle(a: &[f64], b: &[f64]) -> f64 {
    let dot: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    dot.abs().min(1.0).acos()
}

/// What one long run saw.
#[derive(Debug, Default)]
struct Report {
    steps: u64,
    max_concentration: f64,
    /// largest angle between the estimate and the truth (scenarios that track a truth)
    max_error: Option<f64>,
}

struct Run {
    label: String,
    f: BinghamFilter,
    d: usize,
    m: Vec<f64>,
    z: Vec<f64>,
    report: Report,
}

impl Run {
    fn new(label: &str, d: usize, m0: &[f64], z0: &[f64]) -> Run {
        let f = BinghamFilter::new(d, m0, z0).expect("initial state");
        let mut r = Run {
            label: label.to_string(),
            f,
            d,
            m: vec![0.0; d * d],
            z: vec![0.0; d],
            report: Report::default(),
        };
        r.check(0, "new");
        r
    }

    /// Reads the state and checks that it is a valid Bingham distribution.
    fn check(&mut self, step: u64, what: &str) {
        self.f.state_into(&mut self.m, &mut self.z).unwrap();
        if let Err(e) = check_state(&self.m, &self.z, self.d) {
            panic!(
                "{} step {step} ({what}): invalid state: {e}\n  M = {:?}\n  z = {:?}",
                self.label, self.m, self.z
            );
        }
        self.report.max_concentration = self.report.max_concentration.max(-self.z[0]);
    }

    fn mode(&self) -> Vec<f64> {
        (0..self.d)
            .map(|r| self.m[r * self.d + self.d - 1])
            .collect()
    }

    fn predict(&mut self, step: u64, w: &(Vec<f64>, Vec<f64>)) {
        if let Err(e) = self.f.predict(&w.0, &w.1) {
            panic!(
                "{} step {step}: predict failed: {e}\n  state z = {:?}, noise z = {:?}",
                self.label, self.z, w.1
            );
        }
        self.check(step, "predict");
    }

    fn predict_rotation(&mut self, step: u64, u: &[f64], w: &(Vec<f64>, Vec<f64>)) {
        if let Err(e) = self.f.predict_rotation(u, &w.0, &w.1) {
            panic!(
                "{} step {step}: predict_rotation failed: {e}\n  state z = {:?}, noise z = {:?}",
                self.label, self.z, w.1
            );
        }
        self.check(step, "predict_rotation");
    }

    fn update(&mut self, step: u64, y: &[f64], v: &(Vec<f64>, Vec<f64>)) {
        if let Err(e) = self.f.update(y, &v.0, &v.1) {
            panic!(
                "{} step {step}: update failed: {e}\n  state M = {:?} z = {:?}\n  measurement {y:?}, noise z = {:?}",
                self.label, self.m, self.z, v.1
            );
        }
        self.check(step, "update");
    }

    fn finish(self, start: Instant) -> Report {
        eprintln!(
            "{:<32} {:>8} steps {:>7.2} s  max concentration {:.3e}{}",
            self.label,
            self.report.steps,
            start.elapsed().as_secs_f64(),
            self.report.max_concentration,
            self.report
                .max_error
                .map(|e| format!("  max error {e:.2e} rad"))
                .unwrap_or_default()
        );
        self.report
    }
}

fn truth0(d: usize) -> Vec<f64> {
    let mut x = vec![0.0; d];
    x[d - 1] = 1.0;
    x
}

/// (a) Sharp measurements: concentrations grow to 1e6 and far beyond.
fn sharp(d: usize, with_predict: bool) {
    let start = Instant::now();
    let label = format!(
        "sharp d={d} {}",
        if with_predict {
            "predict+update"
        } else {
            "updates only"
        }
    );
    let mut rng = Rng64::new(1000 + d as u64 + 10 * u64::from(with_predict));
    let truth = rng.unit_vector(d);
    let mut run = Run::new(&label, d, &identity(d), &vec![-1.0; d]);
    let v = noise(d, 1e8); // angular sd ~ 7e-5
    let w = noise(d, 1e12); // tiny process noise
    let n = steps();
    for k in 0..n {
        if with_predict {
            run.predict(k, &w);
        }
        let y = near(&mut rng, &truth, 1e-5);
        run.update(k, &y, &v);
        let e = axis_angle(&run.mode(), &truth);
        if k > 10 {
            run.report.max_error = Some(run.report.max_error.unwrap_or(0.0).max(e));
        }
        run.report.steps += 1;
    }
    let r = run.finish(start);
    // the measurements pin the truth to ~1e-5 / sqrt(k): the estimate must stay there
    assert!(
        r.max_error.unwrap_or(0.0) < 1e-3,
        "{label}: estimate drifted: {r:?}"
    );
    if !with_predict && n >= 100 {
        assert!(
            r.max_concentration > 1e9,
            "{label}: concentrations did not grow: {r:?}"
        );
    }
}

/// (b) Near-uniform states and noises.
fn near_uniform(d: usize) {
    let start = Instant::now();
    let label = format!("near_uniform d={d}");
    let mut rng = Rng64::new(2000 + d as u64);
    let mut run = Run::new(&label, d, &identity(d), &vec![0.0; d]);
    let n = steps();
    for k in 0..n {
        let w = match k % 4 {
            0 => noise(d, 0.0), // exactly uniform process noise
            1 => noise(d, 1e-3),
            2 => noise(d, 1e-12),
            _ => noise(d, rng.log_uniform(-8.0, -1.0)),
        };
        run.predict(k, &w);
        let v = noise(d, rng.log_uniform(-9.0, -2.0));
        let y = rng.unit_vector(d);
        run.update(k, &y, &v);
        assert!(
            run.z[0] > -1.0,
            "{label} step {k}: a near-uniform run became concentrated: {:?}",
            run.z
        );
        run.report.steps += 1;
    }
    run.finish(start);
}

/// (c) Measurements antipodal and orthogonal to the mode.
fn antipodal_orthogonal(d: usize) {
    let start = Instant::now();
    let label = format!("antipodal_orthogonal d={d}");
    let mut rng = Rng64::new(3000 + d as u64);
    let mut run = Run::new(&label, d, &identity(d), &vec![-10.0; d]);
    let n = steps();
    for k in 0..n {
        let kv = *rng.pick(&[1e-2, 1.0, 1e2, 1e4, 1e6]);
        let kw = *rng.pick(&[1e-1, 1e2, 1e5, 1e9]);
        run.predict(k, &noise(d, kw));
        let mode = run.mode();
        let y: Vec<f64> = match k % 3 {
            0 => mode.iter().map(|x| -x).collect(), // antipodal: the same axis
            1 => (0..d).map(|r| run.m[r * d]).collect(), // orthogonal (least likely axis)
            _ => (0..d).map(|r| run.m[r * d + d - 2]).collect(), // orthogonal, second axis
        };
        run.update(k, &y, &noise(d, kv));
        if k % 3 == 0 {
            // an antipodal measurement confirms the mode
            let e = axis_angle(&run.mode(), &mode);
            assert!(
                e < 1e-6,
                "{label} step {k}: antipodal measurement moved the mode by {e}"
            );
        }
        run.report.steps += 1;
    }
    run.finish(start);
}

/// (d) Huge and tiny noises alternating, random measurements and known rotations.
fn alternating(d: usize) {
    let start = Instant::now();
    let label = format!("alternating d={d}");
    let mut rng = Rng64::new(4000 + d as u64);
    let mut truth = truth0(d);
    let mut run = Run::new(&label, d, &identity(d), &vec![-1.0; d]);
    let n = steps();
    for k in 0..n {
        let huge = k % 2 == 0;
        let (kw, kv) = if huge {
            (rng.log_uniform(9.0, 14.0), rng.log_uniform(8.0, 13.0))
        } else {
            (rng.log_uniform(-9.0, -3.0), rng.log_uniform(-12.0, -6.0))
        };
        if k % 5 == 0 {
            // a known rotation, as from a gyroscope
            let u1 = {
                let mut e = vec![0.0; d];
                e[0] = 1.0;
                near(&mut rng, &e, 0.05)
            };
            run.predict_rotation(k, &u1, &noise(d, kw));
            truth = compose(&truth, &u1).expect("d = 2 or 4");
            let nt = norm(&truth);
            truth.iter_mut().for_each(|x| *x /= nt);
        } else {
            run.predict(k, &noise(d, kw));
        }
        let y = if rng.chance(0.5) {
            near(&mut rng, &truth, 1e-3)
        } else {
            rng.unit_vector(d)
        };
        check_unit(&y, 1e-12).unwrap();
        run.update(k, &y, &noise(d, kv));
        run.report.steps += 1;
    }
    let r = run.finish(start);
    assert!(r.max_concentration <= 1e15 * n as f64, "{r:?}");
}

#[test]
fn long_sharp_d2() {
    sharp(2, false);
    sharp(2, true);
}

#[test]
fn long_sharp_d4() {
    sharp(4, false);
    sharp(4, true);
}

#[test]
fn long_near_uniform_d2() {
    near_uniform(2);
}

#[test]
fn long_near_uniform_d4() {
    near_uniform(4);
}

#[test]
fn long_antipodal_orthogonal_d2() {
    antipodal_orthogonal(2);
}

#[test]
fn long_antipodal_orthogonal_d4() {
    antipodal_orthogonal(4);
}

#[test]
fn long_alternating_d2() {
    alternating(2);
}

#[test]
fn long_alternating_d4() {
    alternating(4);
}

/// The cap the prediction applies is the documented one, and a state sharper than the cap
/// survives a prediction (capped) and an update (not capped).
#[test]
fn concentration_cap_is_the_documented_one() {
    assert_eq!(MAX_CONCENTRATION, 1e10);
    assert_eq!(
        bingham::ffi::BINGHAM_FILTER_MAX_CONCENTRATION,
        MAX_CONCENTRATION
    );
    for d in [2, 4] {
        let mut z = vec![-1e14; d];
        z[d - 1] = 0.0;
        let mut f = BinghamFilter::new(d, &identity(d), &z).unwrap();
        f.predict(&noise(d, 1e14).0, &noise(d, 1e14).1).unwrap();
        let s = f.state();
        let zs = s.z().as_slice().to_vec();
        assert!(zs[0] >= -1.01 * MAX_CONCENTRATION && zs[0] < 0.0, "{zs:?}");
        f.update(&truth0(d), &noise(d, 1e14).0, &noise(d, 1e14).1)
            .unwrap();
        let zs = f.state().z().as_slice().to_vec();
        assert!(zs[0] < -1e13, "the update is not capped: {zs:?}");
    }
}
