//! The evaluation scenarios of JAIF Sec. 7 (`tests/filter*.rs`, `tests/deterministic.rs`,
//! `benches/filter.rs`): the initial estimate, the noises and the true initial state, the seeds
//! of each Monte Carlo run (the same as in `examples/c/*_tracking.c`), and the simulation of the
//! truth and the measurements given the library's sampler and composition.

use crate::fuzz::identity;
use crate::norm;

/// Time steps per run.
pub const STEPS: usize = 100;

/// One scenario: initial estimate, noises (row-major `M`, `z`) and the true initial state.
#[derive(Clone, Debug)]
pub struct Scenario {
    pub d: usize,
    pub m0: Vec<f64>,
    pub z0: Vec<f64>,
    pub mw: Vec<f64>,
    pub zw: Vec<f64>,
    pub mv: Vec<f64>,
    pub zv: Vec<f64>,
    pub x0: Vec<f64>,
}

fn anti_diagonal(d: usize) -> Vec<f64> {
    (0..d * d)
        .map(|k| if k / d + k % d == d - 1 { 1.0 } else { 0.0 })
        .collect()
}

/// JAIF Sec. 7.1: axis estimation, d = 2.
pub fn scenario_2d() -> Scenario {
    Scenario {
        d: 2,
        m0: identity(2),
        z0: vec![-1.0, 0.0],
        mw: anti_diagonal(2),
        zw: vec![-200.0, 0.0],
        mv: anti_diagonal(2),
        zv: vec![-2.0, 0.0],
        x0: vec![1.0, 0.0],
    }
}

/// JAIF Sec. 7.2: quaternions, d = 4.
pub fn scenario_4d() -> Scenario {
    Scenario {
        d: 4,
        m0: identity(4),
        z0: vec![-1.0, -1.0, -1.0, 0.0],
        mw: anti_diagonal(4),
        zw: vec![-200.0, -200.0, -2.0, 0.0],
        mv: anti_diagonal(4),
        zv: vec![-500.0, -500.0, -500.0, 0.0],
        x0: vec![0.0, 1.0, 0.0, 0.0],
    }
}

/// Seeds of run `r` (the same in the C examples).
pub fn seed_w(r: u64) -> u64 {
    1000 + 2 * r
}
pub fn seed_v(r: u64) -> u64 {
    1001 + 2 * r
}

/// One run: the true states `x_1..x_STEPS` and measurements `z_k = x_k ⊕ v_k`, where
/// `x_k = x_{k−1} ⊕ w_{k−1}`. `draw(m, z, seed, n)` gives `n` samples of `Bingham(m, z)` (of
/// dimension `sc.d`) as `bingham_sample(d, m, z, seed, n, …)` draws them; `compose(x, y)` is
/// `x ⊕ y`.
pub fn simulate_with(
    sc: &Scenario,
    run: u64,
    mut draw: impl FnMut(&[f64], &[f64], u64, usize) -> Vec<Vec<f64>>,
    compose: impl Fn(&[f64], &[f64]) -> Vec<f64>,
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let w = draw(&sc.mw, &sc.zw, seed_w(run), STEPS);
    let v = draw(&sc.mv, &sc.zv, seed_v(run), STEPS);
    let mut x = sc.x0.clone();
    let mut truth = Vec::with_capacity(STEPS);
    let mut meas = Vec::with_capacity(STEPS);
    for k in 0..STEPS {
        x = normalized(&compose(&x, &w[k]));
        meas.push(normalized(&compose(&x, &v[k])));
        truth.push(x.clone());
    }
    (truth, meas)
}

/// `x / |x|`.
pub fn normalized(x: &[f64]) -> Vec<f64> {
    let n = norm(x);
    x.iter().map(|v| v / n).collect()
}

/// A transition for the nonlinear prediction: a fixed turn by 0.1 rad, `x ⊕ (cos 0.05, sin 0.05)`
/// for d = 2 and `x ⊗ (cos 0.05, 0, 0, sin 0.05)` for d = 4, written out (no allocation).
pub fn turn(x: &[f64], out: &mut [f64]) -> Result<(), String> {
    let (c, s) = (0.05f64.cos(), 0.05f64.sin());
    if x.len() == 2 {
        out[0] = x[0] * c - x[1] * s;
        out[1] = x[0] * s + x[1] * c;
    } else {
        out[0] = x[0] * c - x[3] * s;
        out[1] = x[1] * c + x[2] * s;
        out[2] = x[2] * c - x[1] * s;
        out[3] = x[3] * c + x[0] * s;
    }
    Ok(())
}
