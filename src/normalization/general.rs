//! Exact `F(Z)` for any d: Laplace inversion along the steepest-descent contour.
//!
//! (docs: see the end of development)

use crate::error::{Error, Result};
use std::f64::consts::PI;
use std::ops::{Add, Mul, Sub};

/// A minimal complex number (only what the contour needs).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Cx {
    re: f64,
    im: f64,
}

impl Cx {
    const fn new(re: f64, im: f64) -> Self {
        Cx { re, im }
    }

    fn abs(self) -> f64 {
        self.re.hypot(self.im)
    }

    fn scale(self, k: f64) -> Self {
        Cx::new(self.re * k, self.im * k)
    }

    /// `1/self` by Smith's algorithm (no overflow in the intermediate squares).
    fn recip(self) -> Self {
        if self.re.abs() >= self.im.abs() {
            let t = self.im / self.re;
            let den = self.re + self.im * t;
            Cx::new(1.0 / den, -t / den)
        } else {
            let t = self.re / self.im;
            let den = self.re * t + self.im;
            Cx::new(t / den, -1.0 / den)
        }
    }

    fn is_finite(self) -> bool {
        self.re.is_finite() && self.im.is_finite()
    }
}

impl Add for Cx {
    type Output = Cx;
    fn add(self, o: Cx) -> Cx {
        Cx::new(self.re + o.re, self.im + o.im)
    }
}

impl Sub for Cx {
    type Output = Cx;
    fn sub(self, o: Cx) -> Cx {
        Cx::new(self.re - o.re, self.im - o.im)
    }
}

impl Mul for Cx {
    type Output = Cx;
    fn mul(self, o: Cx) -> Cx {
        Cx::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}

/// Principal `log(1 + u)`, accurate for small `|u|` and away from `u = −1`.
fn clog1p(u: Cx) -> Cx {
    let xp1 = 1.0 + u.re;
    // |1 + u|² − 1, without forming 1 + u first.
    let t = u.re * (2.0 + u.re) + u.im * u.im;
    let re = if t.abs() < 0.5 {
        0.5 * t.ln_1p()
    } else {
        xp1.hypot(u.im).ln()
    };
    Cx::new(re, u.im.atan2(xp1))
}

/// Step of the coarsest trapezoidal rule in `w`.
const H0: f64 = 0.5;
/// Number of coarsest steps: the rule covers `w ∈ [0, H0·N0] = [0, 7]`; `e^{−49} < 6e-22`.
const N0: usize = 14;
/// Maximum number of step halvings (finest step 0.5/2⁸, 1793 nodes).
const MAX_LEVEL: usize = 8;
/// Accept a level when every integral changed by at most this (relative) from the previous one.
const TOL: f64 = 1e-13;
/// Maximal recursion depth of the step subdivision in path following.
const MAX_DEPTH: u32 = 24;

/// A point of the contour: `w`, `s(w)`, `s'(w)`, `s''(w)`.
#[derive(Clone, Copy, Debug)]
struct Node {
    w: f64,
    s: Cx,
    ds: Cx,
    dds: Cx,
}

/// The shifted problem: distinct `λ_j = c − z_j` with multiplicities, `½ Σ m_j/λ_j ≈ 1`.
struct Contour {
    lam: Vec<f64>,
    inv_lam: Vec<f64>,
    mult: Vec<f64>,
    /// `1 − ½ Σ m_j/λ_j` (zero up to rounding), kept so that `φ'` is exact.
    om: f64,
    /// `φ''(0) = ½ Σ m_j/λ_j²`.
    a: f64,
    /// `φ'''(0) = −Σ m_j/λ_j³`.
    b: f64,
}

impl Contour {
    /// `φ(s) = s − ½ Σ m_j log(1 + s/λ_j)` and `φ'(s)` (the latter without cancellation near 0).
    fn phi_dphi(&self, s: Cx) -> (Cx, Cx) {
        let mut sum_log = Cx::new(0.0, 0.0);
        let mut sum_q = Cx::new(0.0, 0.0);
        for ((&l, &il), &m) in self.lam.iter().zip(&self.inv_lam).zip(&self.mult) {
            let u = s.scale(il);
            sum_log = sum_log + clog1p(u).scale(m);
            let r = Cx::new(l + s.re, s.im).recip();
            sum_q = sum_q + r.scale(m * il);
        }
        let phi = s - sum_log.scale(0.5);
        // φ'(s) = 1 − ½ Σ m/(λ+s) = (1 − ½ Σ m/λ) + (s/2) Σ m/(λ(λ+s)).
        let dphi = Cx::new(self.om, 0.0) + (s * sum_q).scale(0.5);
        (phi, dphi)
    }

    /// `φ'(s)` and `φ''(s)`.
    fn dphi_ddphi(&self, s: Cx) -> (Cx, Cx) {
        let mut sum_q = Cx::new(0.0, 0.0);
        let mut sum_r2 = Cx::new(0.0, 0.0);
        for ((&l, &il), &m) in self.lam.iter().zip(&self.inv_lam).zip(&self.mult) {
            let r = Cx::new(l + s.re, s.im).recip();
            sum_q = sum_q + r.scale(m * il);
            sum_r2 = sum_r2 + (r * r).scale(m);
        }
        let dphi = Cx::new(self.om, 0.0) + (s * sum_q).scale(0.5);
        (dphi, sum_r2.scale(0.5))
    }

    /// Newton's method for `φ(s) = −w²` in the open upper half plane, where the root is unique.
    fn newton(&self, w: f64, start: Cx) -> Option<Cx> {
        let target = -w * w;
        let mut s = start;
        let mut polishing = false;
        for _ in 0..50 {
            let (p, dp) = self.phi_dphi(s);
            let mut delta = (p - Cx::new(target, 0.0)) * dp.recip();
            if !delta.is_finite() {
                return None;
            }
            let size = delta.abs();
            let limit = 0.5 * (1.0 + s.abs());
            if size > limit {
                delta = delta.scale(limit / size);
            }
            s = s - delta;
            if s.im <= 0.0 {
                // The root is unique in the upper half plane and φ(s̄) = conj φ(s): reflect.
                s.im = if s.im < 0.0 {
                    -s.im
                } else {
                    1e-3 * (1.0 + s.abs())
                };
                polishing = false;
                continue;
            }
            let small = size <= 1e-9 * (1.0 + s.abs());
            if polishing {
                return small.then_some(s);
            }
            polishing = small;
        }
        None
    }

    /// Derivatives of the path at a solved point: `s' = −2w/φ'(s)`, `s'' = (−2 − φ'' s'²)/φ'`.
    fn node(&self, w: f64, s: Cx) -> Result<Node> {
        let (dp, ddp) = self.dphi_ddphi(s);
        let ip = dp.recip();
        let ds = ip.scale(-2.0 * w);
        let dds = (Cx::new(-2.0, 0.0) - ddp * ds * ds) * ip;
        if !(ds.is_finite() && dds.is_finite()) || ds.im <= 0.0 {
            return Err(Error::Numerical(format!(
                "steepest-descent path: bad tangent at w = {w}, s = ({}, {})",
                s.re, s.im
            )));
        }
        Ok(Node { w, s, ds, dds })
    }

    /// The saddle point `s = 0` at `w = 0`: `s' = i√(2/a)`, `s'' = 2b/(3a²)`.
    fn origin(&self) -> Node {
        Node {
            w: 0.0,
            s: Cx::new(0.0, 0.0),
            ds: Cx::new(0.0, (2.0 / self.a).sqrt()),
            dds: Cx::new(2.0 * self.b / (3.0 * self.a * self.a), 0.0),
        }
    }

    /// Follows the path from `from` to `w1`: Taylor predictor + Newton, halving on failure.
    fn march(&self, from: &Node, w1: f64, depth: u32) -> Result<Node> {
        let h = w1 - from.w;
        let pred = from.s + from.ds.scale(h) + from.dds.scale(0.5 * h * h);
        if let Some(s) = self.newton(w1, pred) {
            return self.node(w1, s);
        }
        if depth == 0 {
            return Err(Error::NotConverged(format!(
                "steepest-descent path: Newton failed near w = {w1}"
            )));
        }
        let mid = self.march(from, from.w + 0.5 * h, depth - 1)?;
        self.march(&mid, w1, depth - 1)
    }

    /// Adds `weight · e^{−w²} ·` the integrands at `node` to `sums`:
    /// `½ Im(s' r_j)` for each group (first `G` entries) and, with `hess`,
    /// `¼ Im(s' r_j r_k)` for `j ≤ k` (packed row by row). `r_j = 1/(λ_j + s)`.
    fn accumulate(&self, node: &Node, weight: f64, r: &mut [Cx], sums: &mut [f64], hess: bool) {
        let g = self.lam.len();
        let t = node.ds.scale(weight * (-node.w * node.w).exp());
        for (rj, &l) in r.iter_mut().zip(&self.lam) {
            *rj = Cx::new(l + node.s.re, node.s.im).recip();
        }
        for (sj, &rj) in sums.iter_mut().zip(r.iter()) {
            *sj += 0.5 * (t * rj).im;
        }
        if hess {
            let mut idx = g;
            for j in 0..g {
                let u = (t * r[j]).scale(0.25);
                for rk in &r[j..] {
                    sums[idx] += u.re * rk.im + u.im * rk.re;
                    idx += 1;
                }
            }
        }
    }
}

/// Solves `½ Σ m_j/(c − z_j) = 1` for `c > max z = 0` (`z` distinct, ascending, last 0).
///
/// `G(c) = 2/Σ m_j/(c − z_j) − 1` is a harmonic mean of linear functions minus one, hence
/// concave and increasing; Newton's method started at `c₀ = m_last/2` (where `G ≤ 0`) climbs
/// monotonically to the root. The root lies in `[m_last/2, d/2]`.
fn solve_shift(z: &[f64], mult: &[f64]) -> Result<f64> {
    let mut c = 0.5 * mult[mult.len() - 1];
    for _ in 0..200 {
        let (mut s1, mut s2) = (0.0, 0.0);
        for (&zj, &m) in z.iter().zip(mult) {
            let r = 1.0 / (c - zj);
            s1 += m * r;
            s2 += m * r * r;
        }
        let g = 2.0 / s1 - 1.0;
        let step = -g * s1 * s1 / (2.0 * s2);
        if !(step > 4.0 * f64::EPSILON * c) {
            if c.is_finite() && c > 0.0 {
                return Ok(c);
            }
            break;
        }
        c += step;
    }
    Err(Error::NotConverged("shift to the saddle point".into()))
}

/// Everything the general method computes (sorted order, as the input).
#[derive(Debug, Clone)]
pub(crate) struct GeneralEval {
    /// `log F(z)`.
    pub log_f: f64,
    /// `ω_i = ∂ log F/∂z_i` (empty unless requested).
    pub grad: Vec<f64>,
    /// `∂² log F/∂z_i∂z_j`, row-major (empty unless requested).
    pub hess: Vec<f64>,
    /// Number of contour points used.
    pub nodes: usize,
    /// Largest relative change of any integral between the last two trapezoidal levels.
    pub last_change: f64,
    /// The relative change at each refinement level.
    pub changes: Vec<f64>,
}

/// The quadrature schedule.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Rule {
    /// Accept a level when every integral changed by at most this (relative).
    pub tol: f64,
    /// Finest level (step `H0/2^level`).
    pub max_level: usize,
    /// Return the finest level's values even if `tol` was not met (for convergence studies).
    pub accept_at_max: bool,
}

/// The production schedule.
pub(crate) const RULE: Rule = Rule {
    tol: TOL,
    max_level: MAX_LEVEL,
    accept_at_max: false,
};

/// Evaluates `log F` and optionally ω and the Hessian for sorted (ascending), finite `z` of any
/// length `d ≥ 1` (the internal limit is only memory; the public one is `MAX_DIM`).
pub(crate) fn evaluate_sorted(z: &[f64], want_grad: bool, want_hess: bool) -> Result<GeneralEval> {
    evaluate_with(z, want_grad, want_hess, RULE)
}

/// [`evaluate_sorted`] with an explicit quadrature schedule.
pub(crate) fn evaluate_with(
    z: &[f64],
    want_grad: bool,
    want_hess: bool,
    rule: Rule,
) -> Result<GeneralEval> {
    let d = z.len();
    if d == 0 {
        return Err(Error::InvalidDimension("empty z".into()));
    }
    if z.iter().any(|v| !v.is_finite()) || z.windows(2).any(|p| p[0] > p[1]) {
        return Err(Error::InvalidArgument(
            "z must be finite and ascending".into(),
        ));
    }
    let zmax = z[d - 1];
    // Groups of equal values (ties), relative to the maximum.
    let mut zg: Vec<f64> = Vec::with_capacity(d);
    let mut mult: Vec<f64> = Vec::with_capacity(d);
    let mut group_of = Vec::with_capacity(d);
    for (i, &v) in z.iter().enumerate() {
        if i > 0 && v == z[i - 1] {
            *mult.last_mut().expect("nonempty") += 1.0;
        } else {
            zg.push(v - zmax);
            mult.push(1.0);
        }
        group_of.push(zg.len() - 1);
    }
    let g = zg.len();
    let c = solve_shift(&zg, &mult)?;
    let lam: Vec<f64> = zg.iter().map(|&v| c - v).collect();
    let inv_lam: Vec<f64> = lam.iter().map(|&l| 1.0 / l).collect();
    let kappa: f64 = 0.5 * inv_lam.iter().zip(&mult).map(|(il, m)| m * il).sum::<f64>();
    let a = 0.5
        * inv_lam
            .iter()
            .zip(&mult)
            .map(|(il, m)| m * il * il)
            .sum::<f64>();
    let b = -inv_lam
        .iter()
        .zip(&mult)
        .map(|(il, m)| m * il * il * il)
        .sum::<f64>();
    let ct = Contour {
        lam,
        inv_lam,
        mult,
        om: 1.0 - kappa,
        a,
        b,
    };

    let hess = want_hess;
    let nint = g + if hess { g * (g + 1) / 2 } else { 0 };
    let mut sums = vec![0.0; nint];
    let mut r = vec![Cx::new(0.0, 0.0); g];

    // Level 0: march out from the saddle point.
    let mut nodes: Vec<Node> = Vec::with_capacity(N0 + 1);
    nodes.push(ct.origin());
    ct.accumulate(&nodes[0], 0.5, &mut r, &mut sums, hess);
    for k in 1..=N0 {
        let next = ct.march(&nodes[k - 1], H0 * k as f64, MAX_DEPTH)?;
        ct.accumulate(&next, 1.0, &mut r, &mut sums, hess);
        nodes.push(next);
    }
    let mut h = H0;
    let mut prev: Vec<f64> = sums.iter().map(|v| v * h).collect();
    let mut change = f64::INFINITY;
    let mut changes = Vec::new();
    let mut result: Option<Vec<f64>> = None;
    if rule.max_level == 0 && rule.accept_at_max {
        result = Some(prev.clone());
    }
    for level in 1..=rule.max_level {
        h *= 0.5;
        let mut refined: Vec<Node> = Vec::with_capacity(2 * nodes.len() - 1);
        for pair in nodes.windows(2) {
            let (l, rt) = (&pair[0], &pair[1]);
            let wm = 0.5 * (l.w + rt.w);
            let step = rt.w - l.w;
            // Cubic Hermite predictor from both neighbours.
            let pred = (l.s + rt.s).scale(0.5) + (l.ds - rt.ds).scale(step / 8.0);
            let mid = match ct.newton(wm, pred) {
                Some(s) => ct.node(wm, s)?,
                None => ct.march(l, wm, MAX_DEPTH)?,
            };
            ct.accumulate(&mid, 1.0, &mut r, &mut sums, hess);
            refined.push(*l);
            refined.push(mid);
        }
        refined.push(*nodes.last().expect("nonempty"));
        nodes = refined;
        let cur: Vec<f64> = sums.iter().map(|v| v * h).collect();
        change = cur
            .iter()
            .zip(&prev)
            .map(|(c1, c0)| {
                let den = c1.abs().max(f64::MIN_POSITIVE);
                (c1 - c0).abs() / den
            })
            .fold(0.0, f64::max);
        changes.push(change);
        if change <= rule.tol || (rule.accept_at_max && level == rule.max_level) {
            result = Some(cur);
            break;
        }
        prev = cur;
    }
    let t = result.ok_or_else(|| {
        Error::NotConverged(format!(
            "contour quadrature: relative change {change:e} after {} nodes",
            nodes.len()
        ))
    })?;

    // I = ∫₀^∞ e^{−w²} y'(w) dw = Σ_j m_j T_j  (so that Σ ω = 1 up to rounding).
    let total: f64 = t[..g].iter().zip(&ct.mult).map(|(tj, m)| m * tj).sum();
    if !(total > 0.0 && total.is_finite()) {
        return Err(Error::Numerical("contour integral is not positive".into()));
    }
    let sum_log_lam: f64 = ct.lam.iter().zip(&ct.mult).map(|(l, m)| m * l.ln()).sum();
    let log_f = zmax + c + (2.0f64).ln() + 0.5 * d as f64 * PI.ln() - 0.5 * sum_log_lam
        + total.ln()
        - PI.ln();
    if !log_f.is_finite() {
        return Err(Error::Numerical("log F is not finite".into()));
    }
    let omega_g: Vec<f64> = t[..g].iter().map(|tj| tj / total).collect();
    let grad = if want_grad || want_hess {
        group_of.iter().map(|&j| omega_g[j]).collect()
    } else {
        Vec::new()
    };
    let mut hmat = Vec::new();
    if want_hess {
        hmat = vec![0.0; d * d];
        // Offsets of the packed rows (j, j..g).
        let mut offs = vec![0usize; g];
        let mut o = g;
        for (j, off) in offs.iter_mut().enumerate() {
            *off = o;
            o += g - j;
        }
        for i in 0..d {
            for k in 0..d {
                let (gi, gk) = (group_of[i], group_of[k]);
                let (j0, j1) = if gi <= gk { (gi, gk) } else { (gk, gi) };
                let e = t[offs[j0] + (j1 - j0)] / total * if i == k { 3.0 } else { 1.0 };
                hmat[i * d + k] = e - grad[i] * grad[k];
            }
        }
        // The last row/column from the zero row sums (Σ_k ∂ω_i/∂z_k = 0), which avoids the
        // cancellation in E[x_i² x_d²] − ω_i ω_d when the mode carries almost all the mass.
        let l = d - 1;
        for i in 0..l {
            let s: f64 = (0..l).map(|k| hmat[i * d + k]).sum();
            hmat[i * d + l] = -s;
            hmat[l * d + i] = -s;
        }
        let s: f64 = (0..l).map(|i| hmat[i * d + l]).sum();
        hmat[l * d + l] = -s;
        if hmat.iter().any(|v| !v.is_finite()) {
            return Err(Error::Numerical("Hessian is not finite".into()));
        }
    }
    Ok(GeneralEval {
        log_f,
        grad: if want_grad { grad } else { Vec::new() },
        hess: hmat,
        nodes: nodes.len(),
        last_change: change,
        changes,
    })
}

/// Sorted evaluation (see `SortedEval`).
pub(crate) fn log_f_sorted(
    z: &[f64],
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<f64> {
    let ev = evaluate_sorted(z, grad.is_some(), hess.is_some())?;
    if let Some(gr) = grad {
        gr.copy_from_slice(&ev.grad);
    }
    if let Some(hs) = hess {
        hs.copy_from_slice(&ev.hess);
    }
    Ok(ev.log_f)
}
