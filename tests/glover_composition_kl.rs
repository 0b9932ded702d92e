//! Glover & Kaelbling (2013), Sec. 6 and App. A.9: the error of the moment-matched composition
//! (`Bingham::compose`) against the true density of `s = q ∘ r` (issue 22, "Reproduce the paper's
//! experiments", item 3). The paper: "We estimated the composition approximation error
//! (KL-divergence) for 9 of these signals [first-order QBF runs on synthetic signals], from all
//! combinations of (Λp, Λo) in {(−50)³, (−200)³, (−10, −10, −1)}. The mean composition error was
//! .0012, while the max was .0197, which occurred when Λp and Λo were both (−10, −10, −1)"; the
//! divergence is `D_KL(f_B ‖ f_true) = ∫ f_B log(f_B / f_true)` (App. A.9.3), by a finite-element
//! sum over a tetrahedral-octahedral subdivision of S³.
//!
//! **The true density.** For independent `q ~ Bingham(Λ, V)`, `r ~ Bingham(Σ, W)`, the density of
//! `s = q ∘ r` (surface measure on S³) is `f(s) = ∫ f_q(q) f_r(q⁻¹ ∘ s) dq`, and
//! `⟨w_i, q⁻¹ ∘ s⟩ = ⟨q ∘ w_i, s⟩ = ⟨q, s ∘ w_i⁻¹⟩`, so the integrand is `exp(qᵀ C(s) q)` with
//! `C(s) = Σ σ_i (s ∘ w_i⁻¹)(s ∘ w_i⁻¹)ᵀ + λ_i v_i v_iᵀ` and `f(s) = F(C(s)) / (F(Λ) F(Σ))`, `F`
//! of a symmetric matrix being `F` of its eigenvalues (our `F`: the integral over S³ with respect
//! to the surface measure, `F(0) = 2π²`; the paper's `1F1` differs by that factor, hence its
//! "2 ·" and the like). That `f` integrates to 1 is checked by the quadrature (to 1e-9), its second
//! moment against the exact composition moment `Σ_ab A_ab L(e_a) B L(e_b)ᵀ` (written out here),
//! and its shape by Monte Carlo (sampled `q ∘ r`: the second moment and `E[log f(s)]`).
//!
//! **The quadrature.** All integrands are even (`f(−s) = f(s)`). Two product rules, both in the
//! frame of `f_B` (mode `μ`, principal directions `v_i`, concentrations `z_i`):
//! - all `|z_i| ≥ 20` (concentrated): gnomonic coordinates on the hemisphere around `μ`,
//!   `s = (μ + Σ u_i v_i)/√(1 + |u|²)`, `dS = (1 + |u|²)⁻² du`, ∫_S³ = 2 ∫_R³, with
//!   `u_i = a_i sinh τ_i`, `a_i = 1/√(2|z_i|)` (the width of `f_B` along `v_i`), and the
//!   trapezoidal rule in `τ` (step `H` = 0.2; the integrand is analytic in a strip of half-width
//!   π/4 around the real axes, so the error falls like `exp(−π²/2h)`), the range cut where `f_B`
//!   is below e⁻³⁸ of its mode (`|z_i| ≥ 42`) or at `|u_i| = 4` (below `e^{0.94 z_i}`);
//! - a broad direction (`|z_i| < 20`): Hopf coordinates over the whole sphere,
//!   `s = cos η (cos ξ₁ μ + sin ξ₁ v₃) + sin η (cos ξ₂ v₁ + sin ξ₂ v₂)`,
//!   `dS = sin η cos η dη dξ₁ dξ₂`, Gauss–Legendre in `η` and the trapezoidal rule in the periodic
//!   `ξ₁, ξ₂`, `N ≥ 11 √max|z|` nodes in each (24 to 68 here).
//!
//! Each figure comes with an error estimate, the difference to a coarser rule (step 0.27, or
//! 3N/4 nodes), which bounds the step error of the finer rule (it converges faster); the
//! truncation of the range is checked by `∫ f_B = 1` and `∫ f = 1` (exact values) to 1e-9, and
//! the whole machinery by the closed-form KL divergence of two Binghams (App. A.8) to 1e-6
//! relative (`quadrature_kl_matches_the_closed_form_for_binghams`).
//!
//! The divergences are computed as `∫ (f_B log(f_B/f) − f_B + f)` and `∫ (f log(f/f_B) − f + f_B)`
//! (the same values, since both densities integrate to 1; the integrands are ≥ 0 pointwise).
//!
//! `cargo test --release --test glover_composition_kl -- --nocapture` prints the tables; figures
//! and the comparison with the paper: `docs/accuracy/filter.md`.

mod glover_common;

use bingham::filter::BinghamFilter;
use bingham::quaternion::{left_matrix, q4};
use bingham::{log_normalization, Bingham};
use glover_common::{mul, rmat, I4, Q};
use nalgebra::{DMatrix, DVector, Matrix4, Vector4};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::f64::consts::PI;

/// The paper's three concentration settings.
const SETTINGS: [(&str, [f64; 3]); 3] = [
    ("(-50)^3", [-50.0, -50.0, -50.0]),
    ("(-200)^3", [-200.0, -200.0, -200.0]),
    ("(-10,-10,-1)", [-10.0, -10.0, -1.0]),
];
/// The trapezoidal steps in the sinh coordinates: the rule, and the coarser one whose difference
/// to it is the error estimate.
const H: f64 = 0.2;
const H_COARSE: f64 = 0.27;

fn m4(m: &DMatrix<f64>) -> Matrix4<f64> {
    Matrix4::from_fn(|i, j| m[(i, j)])
}

fn random_rotation(rng: &mut StdRng) -> DMatrix<f64> {
    let g = DMatrix::from_fn(4, 4, |_, _| rng.gen::<f64>() - 0.5);
    g.qr().q()
}

fn bingham(m: DMatrix<f64>, l: &[f64; 3]) -> Bingham {
    Bingham::new(m, DVector::from_column_slice(&[l[0], l[1], l[2], 0.0])).unwrap()
}

/// The exact second moment of `q ∘ r`: `Σ_ab A_ab L(e_a) B L(e_b)ᵀ` (`q ∘ r = L(q) r`, `L`
/// linear in `q`).
fn composition_moment(a: &Matrix4<f64>, b: &Matrix4<f64>) -> Matrix4<f64> {
    let l: Vec<Matrix4<f64>> = (0..4)
        .map(|k| {
            let mut e = [0.0; 4];
            e[k] = 1.0;
            m4(&left_matrix(&e))
        })
        .collect();
    let mut s = Matrix4::zeros();
    for i in 0..4 {
        for j in 0..4 {
            s += a[(i, j)] * l[i] * b * l[j].transpose();
        }
    }
    s
}

/// The two components, their composition's moment-matched Bingham `f_B`, and the pieces of the
/// true density `f(s) = F(C(s)) / (F(Λ) F(Σ))`.
struct Pair {
    q: Bingham,
    r: Bingham,
    fb: Bingham,
    /// `Σ λ_i v_i v_iᵀ` of `q`
    a: Matrix4<f64>,
    /// `(σ_i, w_i⁻¹)` of `r` (the nonzero concentrations)
    w: Vec<(f64, Q)>,
    log_fq_fr: f64,
    log_fb: f64,
    /// instead of the composition, a Bingham density `exp(sᵀ P s − log F)` (`P`, `log F`): for
    /// checking the quadrature against the closed-form KL divergence of two Binghams
    known: Option<(Matrix4<f64>, f64)>,
}

impl Pair {
    /// `f_B = fb` against the Bingham `g` in place of the true composition.
    fn binghams(fb: Bingham, g: &Bingham) -> Pair {
        let mg = m4(g.m());
        let p = mg
            * Matrix4::from_diagonal(&Vector4::from_column_slice(g.z().as_slice()))
            * mg.transpose();
        let log_fb = fb.log_normalization().unwrap();
        Pair {
            q: fb.clone(),
            r: fb.clone(),
            fb,
            a: Matrix4::zeros(),
            w: Vec::new(),
            log_fq_fr: 0.0,
            log_fb,
            known: Some((p, g.log_normalization().unwrap())),
        }
    }

    fn new(q: Bingham, r: Bingham) -> Pair {
        let fb = q.compose(&r).unwrap();
        let mq = m4(q.m());
        let a = mq
            * Matrix4::from_diagonal(&Vector4::from_column_slice(q.z().as_slice()))
            * mq.transpose();
        let w = (0..4)
            .filter(|&i| r.z()[i] != 0.0)
            .map(|i| {
                let c = r.m().column(i);
                (r.z()[i], [c[0], -c[1], -c[2], -c[3]])
            })
            .collect();
        let log_fq_fr = q.log_normalization().unwrap() + r.log_normalization().unwrap();
        let log_fb = fb.log_normalization().unwrap();
        Pair {
            q,
            r,
            fb,
            a,
            w,
            log_fq_fr,
            log_fb,
            known: None,
        }
    }

    /// `log f(s)`, the true density of the composition.
    fn log_true(&self, s: &Q) -> f64 {
        if let Some((p, log_f)) = &self.known {
            let v = Vector4::from_column_slice(s);
            return (v.transpose() * p * v)[(0, 0)] - log_f;
        }
        let mut c = self.a;
        for (sigma, wi) in &self.w {
            let u = rmat(wi) * Vector4::from_column_slice(s);
            c += *sigma * u * u.transpose();
        }
        let e = c.symmetric_eigenvalues();
        log_normalization(e.as_slice()).unwrap() - self.log_fq_fr
    }
}

/// The integrals of one quadrature rule.
#[derive(Debug, Clone, Copy, Default)]
struct Integrals {
    fb: f64,
    ft: f64,
    /// `D(f_B ‖ f)`, the paper's direction
    kl_bt: f64,
    /// `D(f ‖ f_B)`, the one moment matching minimizes
    kl_tb: f64,
    /// `∫ f log f`
    neg_entropy: f64,
    moment: Matrix4<f64>,
    nodes: usize,
}

impl Integrals {
    fn add(&mut self, w: f64, s: &Q, lb: f64, lt: f64) {
        let (fb, ft) = (lb.exp(), lt.exp());
        self.fb += w * fb;
        self.ft += w * ft;
        self.kl_bt += w * (fb * (lb - lt) - fb + ft);
        self.kl_tb += w * (ft * (lt - lb) - ft + fb);
        self.neg_entropy += w * ft * lt;
        let v = Vector4::from_column_slice(s);
        self.moment += (w * ft) * v * v.transpose();
        self.nodes += 1;
    }
}

/// Gauss–Legendre nodes and weights on `[a, b]`: `testkit::gauss_legendre`'s rule on
/// `[−1, 1]`, mapped.
fn gauss_legendre(n: usize, a: f64, b: f64) -> Vec<(f64, f64)> {
    let (x, w) = testkit::gauss_legendre(n);
    x.iter()
        .zip(&w)
        .map(|(x, w)| (0.5 * (a + b) + 0.5 * (b - a) * x, 0.5 * (b - a) * w))
        .collect()
}

/// The quadrature rules (see the module documentation); each returns the fine and the coarse
/// rule's integrals, and the rule's name.
fn integrate(p: &Pair) -> (Integrals, Integrals, &'static str) {
    let z = p.fb.z();
    if -z[2] < 20.0 {
        // N ≥ 11 √|z|: the trapezoidal rule in ξ is exact below the harmonic N, and the
        // coefficients of exp(z sin² ξ) beyond it are below e⁻³⁰ of the mean (I_{N/2}(|z|/2))
        let n = (11.0 * (-z[0]).sqrt() / 4.0).ceil() as usize * 4;
        let n = n.max(24);
        assert!(n <= 100, "too sharp for the Hopf rule: z = {z:?}");
        (hopf(p, n, n), hopf(p, 3 * n / 4, 3 * n / 4), "Hopf")
    } else {
        (gnomonic(p, H), gnomonic(p, H_COARSE), "gnomonic")
    }
}

/// Gnomonic coordinates about the mode of `f_B`, `u_i = a_i sinh τ_i`, the trapezoidal rule in
/// `τ` with the step `h`. The range of `u_i`: where `z_i u²/(1 + u²) < −38` (with a margin) for
/// `|z_i| ≥ 42`; 4 for `20 ≤ |z_i| < 42` (beyond, the density is below e^{0.94 z_i}). For all
/// three directions with `|z_i| ≥ 20`.
fn gnomonic(p: &Pair, h: f64) -> Integrals {
    let m = p.fb.m();
    let z = p.fb.z();
    let mu: Q = [m[(0, 3)], m[(1, 3)], m[(2, 3)], m[(3, 3)]];
    let dirs: Vec<Q> = (0..3)
        .map(|i| [m[(0, i)], m[(1, i)], m[(2, i)], m[(3, i)]])
        .collect();
    let scale: Vec<f64> = (0..3).map(|i| 1.0 / (2.0 * -z[i]).sqrt()).collect();
    let axis = |i: usize| -> Vec<(f64, f64)> {
        let umax = if -z[i] >= 42.0 {
            let r = 38.0 / -z[i];
            1.5 * (r / (1.0 - r)).sqrt()
        } else {
            4.0
        };
        let k = ((umax / scale[i]).asinh() / h).ceil() as i64;
        (-k..=k)
            .map(|j| {
                let t = j as f64 * h;
                (scale[i] * t.sinh(), scale[i] * t.cosh() * h)
            })
            .collect()
    };
    let (a0, a1, a2) = (axis(0), axis(1), axis(2));
    let mut out = Integrals::default();
    for &(u0, d0) in &a0 {
        for &(u1, d1) in &a1 {
            for &(u2, d2) in &a2 {
                let r2 = 1.0 + u0 * u0 + u1 * u1 + u2 * u2;
                // 2 × hemisphere, dS = (1 + |u|²)⁻² du
                let w = 2.0 * d0 * d1 * d2 / (r2 * r2);
                let n = r2.sqrt().recip();
                let s: Q = std::array::from_fn(|c| {
                    n * (mu[c] + u0 * dirs[0][c] + u1 * dirs[1][c] + u2 * dirs[2][c])
                });
                let lb = (z[0] * u0 * u0 + z[1] * u1 * u1 + z[2] * u2 * u2) / r2 - p.log_fb;
                out.add(w, &s, lb, p.log_true(&s));
            }
        }
    }
    out
}

/// Hopf coordinates in the frame of `f_B`: `s = cos η (cos ξ₁ μ + sin ξ₁ v₃) + sin η (cos ξ₂ v₁ +
/// sin ξ₂ v₂)` (`v₃` the broadest direction), `dS = sin η cos η dη dξ₁ dξ₂` over the whole
/// sphere; Gauss–Legendre in `η ∈ [0, π/2]` (`n_eta` nodes), the trapezoidal rule in the periodic
/// `ξ₁, ξ₂` (`n_xi` nodes each). For a broad direction (|z| < 20) among the three.
fn hopf(p: &Pair, n_eta: usize, n_xi: usize) -> Integrals {
    let m = p.fb.m();
    let z = p.fb.z();
    let col =
        |i: usize| -> Vector4<f64> { Vector4::new(m[(0, i)], m[(1, i)], m[(2, i)], m[(3, i)]) };
    let (mu, v1, v2, v3) = (col(3), col(0), col(1), col(2));
    let mut out = Integrals::default();
    let dxi = 2.0 * PI / n_xi as f64;
    for (eta, weta) in gauss_legendre(n_eta, 0.0, 0.5 * PI) {
        let (se, ce) = eta.sin_cos();
        for i1 in 0..n_xi {
            let (s1, c1) = (i1 as f64 * dxi).sin_cos();
            let a = ce * (c1 * mu + s1 * v3);
            for i2 in 0..n_xi {
                let (s2, c2) = (i2 as f64 * dxi).sin_cos();
                let v = a + se * (c2 * v1 + s2 * v2);
                let s: Q = [v[0], v[1], v[2], v[3]];
                let w = weta * dxi * dxi * se * ce;
                let lb =
                    z[0] * (se * c2).powi(2) + z[1] * (se * s2).powi(2) + z[2] * (ce * s1).powi(2)
                        - p.log_fb;
                let lt = p.log_true(&s);
                out.add(w, &s, lb, lt);
            }
        }
    }
    out
}

/// One composition's figures, with the quadrature's error estimates, after the checks.
struct Outcome {
    kl_bt: f64,
    kl_tb: f64,
    kl_err: f64,
    norm_err: f64,
    nodes: usize,
    rule: &'static str,
}

fn check_pair(p: &Pair, what: &str) -> Outcome {
    let (f, c, rule) = integrate(p);
    // both densities integrate to 1 (the quadrature and the normalization of the true density)
    assert!((f.fb - 1.0).abs() < 1e-9, "{what}: ∫ f_B = {}", f.fb);
    assert!((f.ft - 1.0).abs() < 1e-9, "{what}: ∫ f_true = {}", f.ft);
    // the true density's second moment is the exact composition moment, which f_B matches
    let a = m4(&p.q.second_moment().unwrap());
    let b = m4(&p.r.second_moment().unwrap());
    let exact = composition_moment(&a, &b);
    let dm = (f.moment - exact).amax();
    assert!(dm < 1e-9, "{what}: E_true[ssᵀ] − exact moment {dm:e}");
    let db = (m4(&p.fb.second_moment().unwrap()) - exact).amax();
    assert!(db < 1e-8, "{what}: moment of f_B − exact {db:e}");
    let kl_err = (f.kl_bt - c.kl_bt).abs().max((f.kl_tb - c.kl_tb).abs());
    let norm_err = (f.fb - c.fb).abs().max((f.ft - c.ft).abs());
    assert!(
        kl_err < 1e-3 * f.kl_bt,
        "{what}: quadrature error estimate {kl_err:e} for KL {}",
        f.kl_bt
    );
    // the exact Bingham KL of f_B to itself through the same rule: 0 (a sanity check of the
    // sign conventions is the nonnegativity of both divergences)
    assert!(f.kl_bt >= 0.0 && f.kl_tb >= 0.0, "{what}: negative KL");
    Outcome {
        kl_bt: f.kl_bt,
        kl_tb: f.kl_tb,
        kl_err,
        norm_err,
        nodes: f.nodes,
        rule,
    }
}

fn print_outcome(what: &str, o: &Outcome, z: &[f64]) {
    println!(
        "  {what:<34} f_B z = ({:7.1}, {:7.1}, {:7.2})  KL(f_B‖f) = {:.3e}  KL(f‖f_B) = {:.3e}  \
         (error est. {:.0e}, ∫f − 1 est. {:.0e}, {} {} nodes)",
        z[0], z[1], z[2], o.kl_bt, o.kl_tb, o.kl_err, o.norm_err, o.nodes, o.rule
    );
}

fn summarize(name: &str, v: &[Outcome]) -> (f64, f64) {
    let mean = v.iter().map(|o| o.kl_bt).sum::<f64>() / v.len() as f64;
    let max = v.iter().map(|o| o.kl_bt).fold(0.0, f64::max);
    let mean_tb = v.iter().map(|o| o.kl_tb).sum::<f64>() / v.len() as f64;
    let max_tb = v.iter().map(|o| o.kl_tb).fold(0.0, f64::max);
    println!(
        "{name}: {} compositions, KL(f_B‖f) mean {mean:.2e}, max {max:.2e}; KL(f‖f_B) mean \
         {mean_tb:.2e}, max {max_tb:.2e}  (paper: mean 1.2e-3, max 1.97e-2)",
        v.len()
    );
    (mean, max)
}

/// Runs `work` on the items in two threads (the machine's two cores), keeping the order.
fn parallel<T: Sync, R: Send>(items: &[T], work: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let mid = items.len().div_ceil(2);
    std::thread::scope(|s| {
        let h = s.spawn(|| items[mid..].iter().map(&work).collect::<Vec<_>>());
        let mut out: Vec<R> = items[..mid].iter().map(&work).collect();
        out.extend(h.join().unwrap());
        out
    })
}

/// The nine ordered pairs of the paper's settings, the components at random orientations. An
/// isotropic component (`(−50)³`, `(−200)³`) is invariant under conjugation, so the divergence
/// of every pair with one does not depend on the orientations (checked: two draws agree to
/// 1e-9); `(−10, −10, −1) ∘ (−10, −10, −1)` does, and is run at 24 random relative orientations
/// and aligned (both `M = I`).
#[test]
fn composition_kl_for_the_paper_settings() {
    let mut rng = StdRng::seed_from_u64(2013);
    let mut pairs = Vec::new();
    for (nq, lq) in SETTINGS {
        for (nr, lr) in SETTINGS {
            let draws = if lq[2] == -1.0 && lr[2] == -1.0 {
                24
            } else {
                2
            };
            for draw in 0..draws {
                let q = bingham(random_rotation(&mut rng), &lq);
                let r = bingham(random_rotation(&mut rng), &lr);
                pairs.push((format!("{nq} ∘ {nr} #{draw}"), Pair::new(q, r)));
            }
        }
    }
    let aniso = SETTINGS[2].1;
    pairs.push((
        "(-10,-10,-1) ∘ (-10,-10,-1) aligned".to_string(),
        Pair::new(
            bingham(DMatrix::identity(4, 4), &aniso),
            bingham(DMatrix::identity(4, 4), &aniso),
        ),
    ));
    let out = parallel(&pairs, |(what, p)| check_pair(p, what));
    println!("random orientations, s = q ∘ r:");
    for ((what, p), o) in pairs.iter().zip(&out) {
        if what.ends_with("#0") || what.ends_with("#1") || what.ends_with("aligned") {
            print_outcome(what, o, p.fb.z().as_slice());
        }
    }
    // the nine settings: one value each (the draws of the orientation-free ones agree), the
    // anisotropic pair as the range over its orientations
    let mut nine = Vec::new();
    let mut sweep = Vec::new();
    for ((what, _), o) in pairs.iter().zip(&out) {
        if what.ends_with("aligned") {
            continue;
        }
        if what.starts_with("(-10,-10,-1) ∘ (-10,-10,-1)") {
            sweep.push(o.kl_bt);
        } else if what.ends_with("#0") {
            nine.push(o.kl_bt);
        } else {
            let first = nine.last().unwrap();
            assert!(
                (o.kl_bt - first).abs() < 1e-9 * first,
                "{what}: depends on the orientation"
            );
        }
    }
    sweep.sort_by(f64::total_cmp);
    let median = 0.5 * (sweep[11] + sweep[12]);
    let aligned = out.last().unwrap().kl_bt;
    println!(
        "(-10,-10,-1) ∘ (-10,-10,-1): KL(f_B‖f) from {:.2e} to {:.2e} over 24 random relative \
         orientations (median {:.2e}), {aligned:.2e} aligned",
        sweep[0], sweep[23], median
    );
    let all: Vec<f64> = nine.iter().copied().chain([median]).collect();
    let mean = all.iter().sum::<f64>() / all.len() as f64;
    let max = all.iter().copied().fold(0.0, f64::max);
    println!(
        "the nine settings (the anisotropic pair at its median): KL(f_B‖f) mean {mean:.2e}, max \
         {max:.2e}  (paper: mean 1.2e-3, max 1.97e-2)"
    );
    // measured: the eight with an isotropic component 2.5e-5 … 6.6e-4; the anisotropic pair
    // 1.3e-3 … 3.9e-2 (see docs/accuracy/filter.md); bounds a factor of about 2 from the measurement
    assert!(nine.iter().all(|&k| k < 1.5e-3), "{nine:?}");
    assert!(sweep[23] < 0.08 && sweep[0] > 1e-4, "{sweep:?}");
}

/// The quadrature against the closed form: `KL(f ‖ g)` of two Binghams (App. A.8,
/// `Bingham::kl_divergence`) by the same rules, in both directions, for the concentrations met
/// above (sharp, broad, mixed), at random relative orientations.
#[test]
fn quadrature_kl_matches_the_closed_form_for_binghams() {
    let mut rng = StdRng::seed_from_u64(99);
    let cases = [
        ([-100.0, -100.0, -100.0], [-80.0, -120.0, -60.0]),
        ([-40.0, -30.0, -25.0], [-45.0, -30.0, -20.0]),
        ([-8.0, -8.0, -1.0], [-10.0, -5.0, -2.0]),
        ([-37.0, -36.0, -4.3], [-30.0, -40.0, -6.0]),
        ([-2.6, -2.3, -0.43], [-2.0, -1.3, -0.72]),
    ];
    for (lf, lg) in cases {
        let f = bingham(random_rotation(&mut rng), &lf);
        // g: f's frame turned a little, so that the divergence is small as above
        let turn = m4(&left_matrix(&q4::from_rotation_vector(&[
            0.05, -0.03, 0.04,
        ])));
        let g = bingham(
            DMatrix::from_fn(4, 4, |i, j| (turn * m4(f.m()))[(i, j)]),
            &lg,
        );
        let p = Pair::binghams(f.clone(), &g);
        let (fine, coarse, rule) = integrate(&p);
        let exact_fg = f.kl_divergence(&g).unwrap();
        let exact_gf = g.kl_divergence(&f).unwrap();
        println!(
            "f {lf:?}, g {lg:?} ({rule}): KL(f‖g) {:.6e} (closed form {exact_fg:.6e}, difference \
             {:.0e}), KL(g‖f) {:.6e} (closed form {exact_gf:.6e}, difference {:.0e}), error \
             estimate {:.0e}",
            fine.kl_bt,
            (fine.kl_bt - exact_fg).abs(),
            fine.kl_tb,
            (fine.kl_tb - exact_gf).abs(),
            (fine.kl_bt - coarse.kl_bt).abs()
        );
        assert!(
            (fine.kl_bt - exact_fg).abs() < 1e-6 * exact_fg.max(1e-3),
            "{lf:?}"
        );
        assert!(
            (fine.kl_tb - exact_gf).abs() < 1e-6 * exact_gf.max(1e-3),
            "{lf:?}"
        );
    }
}

/// Monte Carlo check of the true density: samples of `q ∘ r` have its second moment and
/// `E[log f(s)]` equals the quadrature's `∫ f log f`.
#[test]
fn true_density_matches_sampled_compositions() {
    let mut rng = StdRng::seed_from_u64(7);
    for (i, (name, l)) in SETTINGS.iter().enumerate() {
        let (_, l2) = SETTINGS[(i + 2) % 3];
        let q = bingham(random_rotation(&mut rng), l);
        let r = bingham(random_rotation(&mut rng), &l2);
        let p = Pair::new(q, r);
        let (f, _, _) = integrate(&p);
        let n = 20_000;
        let qs = p.q.sample(&mut rng, n);
        let rs = p.r.sample(&mut rng, n);
        let mut moment = Matrix4::zeros();
        let mut sq = Matrix4::zeros();
        let (mut lsum, mut l2sum) = (0.0, 0.0);
        for (a, b) in qs.iter().zip(&rs) {
            let s = mul(&[a[0], a[1], a[2], a[3]], &[b[0], b[1], b[2], b[3]]);
            let v = Vector4::from_column_slice(&s);
            let o = v * v.transpose();
            moment += o;
            sq += o.component_mul(&o);
            let l = p.log_true(&s);
            lsum += l;
            l2sum += l * l;
        }
        let nf = n as f64;
        moment /= nf;
        let se_m = ((sq / nf - moment.component_mul(&moment)) / nf).map(|v| v.max(0.0).sqrt());
        let worst = (moment - f.moment)
            .zip_map(&se_m, |d, s| d.abs() / s.max(1e-12))
            .amax();
        let mean_l = lsum / nf;
        let se_l = ((l2sum / nf - mean_l * mean_l) / nf).sqrt();
        println!(
            "{name} ∘ {}: sampled moment within {worst:.2} standard errors of the quadrature's; \
             E[log f(s)] = {mean_l:.4} ± {se_l:.4} (sampled), ∫ f log f = {:.4} (quadrature)",
            SETTINGS[(i + 2) % 3].0,
            f.neg_entropy
        );
        assert!(
            worst < 5.0,
            "{name}: sampled moment {worst} standard errors off"
        );
        assert!(
            (mean_l - f.neg_entropy).abs() < 5.0 * se_l,
            "{name}: E[log f] {mean_l} ± {se_l} vs {}",
            f.neg_entropy
        );
    }
}

/// The paper's protocol: the compositions a first-order QBF performs (`w ∘ (u ∘ x)`: the
/// process noise `Bingham(I; Λp)` and the rotated posterior) while tracking a synthetic
/// quaternion Bingham process, for all nine (Λp, Λo), at a few steps of each signal.
#[test]
fn composition_kl_along_first_order_filter_runs() {
    const STEPS: [usize; 4] = [2, 5, 10, 20];
    let mut rng = StdRng::seed_from_u64(42);
    let mut pairs = Vec::new();
    for (np, lp) in SETTINGS {
        for (no, lo) in SETTINGS {
            let z = |l: &[f64; 3]| [0.0, l[0], l[1], l[2]];
            let (zp, zo) = (z(&lp), z(&lo));
            let noise_p = Bingham::from_row_major(4, &I4, &zp).unwrap();
            let noise_o = Bingham::from_row_major(4, &I4, &zo).unwrap();
            let mut f = BinghamFilter::new(4, &I4, &[0.0; 4]).unwrap();
            let phase: [f64; 3] = std::array::from_fn(|_| 2.0 * PI * rng.gen::<f64>());
            // the nominal orientation follows a sine wave in each Euler angle (paper, Sec. 6)
            let nominal = |t: f64| {
                let e: [f64; 3] = std::array::from_fn(|i| {
                    (0.6 + 0.3 * i as f64) * (0.05 * (i + 1) as f64 * t + phase[i]).sin()
                });
                let qx = q4::from_rotation_vector(&[e[0], 0.0, 0.0]);
                let qy = q4::from_rotation_vector(&[0.0, e[1], 0.0]);
                let qz = q4::from_rotation_vector(&[0.0, 0.0, e[2]]);
                mul(&qz, &mul(&qy, &qx))
            };
            let draw = |b: &Bingham, rng: &mut StdRng| {
                let s = &b.sample(rng, 1)[0];
                [s[0], s[1], s[2], s[3]]
            };
            let mut x = nominal(0.0);
            for n in 1..=*STEPS.last().unwrap() {
                let u = mul(&nominal(n as f64), &q4::conj(&nominal(n as f64 - 1.0)));
                if STEPS.contains(&n) {
                    let posterior = f.state().rotate_left(&u).unwrap();
                    pairs.push((
                        format!("Λp {np}, Λo {no}, step {n}"),
                        Pair::new(noise_p.clone(), posterior),
                    ));
                }
                f.predict_world(Some(&u), &I4, &zp).unwrap();
                x = mul(&draw(&noise_p, &mut rng), &mul(&u, &x));
                let y = mul(&draw(&noise_o, &mut rng), &x);
                f.update_world(&y, &I4, &zo).unwrap();
            }
        }
    }
    let out = parallel(&pairs, |(what, p)| check_pair(p, what));
    println!("first-order QBF runs, predict = w ∘ (u ∘ posterior):");
    for ((what, p), o) in pairs.iter().zip(&out) {
        print_outcome(what, o, p.fb.z().as_slice());
    }
    let (mean, max) = summarize("filter runs", &out);
    // the paper's figures, met: measured mean 6.5e-4, max 4.6e-3, the max where both are
    // (−10, −10, −1) as in the paper
    assert!(
        mean <= 1.2e-3 && max <= 1.97e-2,
        "mean {mean:e}, max {max:e}"
    );
    let (worst, _) = pairs
        .iter()
        .zip(&out)
        .max_by(|a, b| a.1.kl_bt.total_cmp(&b.1.kl_bt))
        .unwrap();
    assert!(
        worst.0.starts_with("Λp (-10,-10,-1), Λo (-10,-10,-1)"),
        "the largest divergence is at {}",
        worst.0
    );
}
