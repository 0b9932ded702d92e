//! Deterministic samples of a Bingham distribution: weighted points on one hemisphere whose
//! weighted moments are those of the distribution, for propagating it through nonlinear
//! functions (the "unscented" idea on the sphere).
//!
//! Every point set here is built in the principal coordinates `y = Mᵀ x` (the Bingham density
//! is `∝ exp(Σ z_i y_i²)`, `z` ascending with `z[d−1] = 0`, so `e_{d−1}` is the mode) and mapped
//! back by `x = M y`. With `ω = ∇ log F(z)` and `H = ∇² log F(z)` the distribution's moments in
//! these coordinates are
//!
//! - `E[y_i²] = ω_i` and `E[y_i y_j] = 0` (i ≠ j): the second moment is `M diag(ω) Mᵀ`;
//! - `E[y_i² y_j²] = H_ij + ω_i ω_j`, and every other fourth moment `E[y_i y_j y_k y_l]` with an
//!   index of odd multiplicity is zero (the density is even in each `y_i`).
//!
//! Two schemes (see [`Scheme`]):
//!
//! - **`Tac2016 { lambda }`** (Gilitschenski, Kurz, Julier, Hanebeck, "Unscented Orientation
//!   Estimation Based on the Bingham Distribution", IEEE TAC 2016; libDirectional's
//!   `sampleDeterministic`): `2d − 1` points, the mode and, for each other principal axis `i`,
//!   the pair `cos α_i e_{d−1} ± sin α_i e_i` with weight `w_i / 2` each, where
//!   `w_i = ω_i + (1 − λ) ω_{d−1} / (d − 1)` and `sin² α_i = ω_i / w_i`; the mode gets
//!   `1 − Σ w_i`. It reproduces the second moment exactly when `ω` is exact (here it is, to
//!   rounding; libDirectional's refit errors of up to 15 % come from its saddlepoint
//!   approximation of `ω`, not from the scheme). Its fourth moments are not those of the
//!   distribution: `E[y_i⁴] = ω_i² / w_i`, `E[y_i² y_j²] = 0` for two non-mode axes.
//! - **`Moments`**: the mode, the pairs `(e_{d−1} ± t_i e_i)/‖·‖` and the quadruples
//!   `(e_{d−1} ± t_i e_i ± t_j e_j)/‖·‖` for every two non-mode axes `i < j`, with
//!   `t_i² = E[y_i⁴] / E[y_i² y_{d−1}²]` and weights solved in closed form so that **every
//!   second and fourth moment** (all `E[y_i² y_j²]`, `E[y_i⁴]`, and the vanishing odd ones) is
//!   reproduced exactly (to rounding): `1 + 2(d − 1) + 2(d − 1)(d − 2)` points (3, 9, 19 for
//!   d = 2, 3, 4). For a concentrated distribution it is the degree-5 Gaussian cubature with
//!   points at `±√3 σ` on the principal axes and `(±√3 σ_i, ±√3 σ_j)` on their pairs, which it
//!   tends to.
//!
//!   Where a weight of that set would be negative — a "girdle": two directions much sharper
//!   than a third, broad one, e.g. every predicted state of the JAIF d = 4 scenario,
//!   `z ≈ (−150, −150, −2, 0)` — the broad axis `b = d − 2` joins the mode in a three-point
//!   circle rule: centers `e_{d−1}` and `(e_{d−1} ± τ e_b)/‖·‖` with `τ² = E[y_b⁴] / E[y_b² y_{d−1}²]`,
//!   pairs `(c ± t_i e_i)/‖·‖` around each center `c` for the other axes, quadruples around
//!   `e_{d−1}`; again every second and fourth moment in closed form, with the same count.
//!   Over random `z` (`tests/deterministic.rs`: `z_i = −10^u`, `u` uniform in `[−1, 7]`) one of
//!   the two sets is positive for every `z` with d = 2 and 3 and for 95 % with d = 4 (the
//!   JAIF states included). In the remaining cases (a very broad axis next to a moderately
//!   sharp one, e.g. `z = (−25.6, −6.8, −0.017, 0)`) and wherever a quantity underflows
//!   (|z| beyond about 1e150) the scheme returns the `2d − 1` points of `Tac2016` with
//!   `λ = 1/2` instead, which reproduce the second moment only, and says so
//!   ([`Reproduced::SecondMoment`]).
//!
//! Points are returned as unit vectors, each in one hemisphere (the mode's component is
//! positive); a Bingham is antipodally symmetric, so `−x` stands for the same point.

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, U1};

use crate::distribution::Bingham;
use crate::error::{Error, Result};
use crate::linalg::{Square, Vector};
use crate::normalization::log_f_canonical;

/// A deterministic sampling scheme (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scheme {
    /// The TAC 2016 scheme with its weighting parameter `lambda` in `[0, 1]` (libDirectional's
    /// default is 0.5): `2d − 1` points, exact second moment.
    Tac2016 {
        /// Weighting parameter in `[0, 1]`: the mode's weight is `λ ω_{d−1}` (λ = 0: no point
        /// at the mode; λ = 1: the pairs lie on the principal axes themselves).
        lambda: f64,
    },
    /// The moment-matched scheme: `2d² − 4d + 3` points reproducing every second and fourth
    /// moment, or (where no positive set of either shape exists) the `2d − 1` points of
    /// `Tac2016 { lambda: 0.5 }`.
    Moments,
}

/// What a point set reproduces exactly (to rounding).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reproduced {
    /// The second moment `E[x xᵀ]`.
    SecondMoment,
    /// The second moment and every fourth moment `E[x_i x_j x_k x_l]`.
    FourthMoments,
}

/// Weighted points of a Bingham distribution in `d` dimensions.
#[derive(Debug, Clone, PartialEq)]
pub struct DeterministicSamples {
    /// Dimension.
    pub d: usize,
    /// `count × d`, row-major: one unit vector per row.
    pub points: Vec<f64>,
    /// `count` positive weights summing to 1.
    pub weights: Vec<f64>,
    /// What the weighted points reproduce.
    pub reproduced: Reproduced,
}

impl DeterministicSamples {
    /// Number of points.
    pub fn count(&self) -> usize {
        self.weights.len()
    }
}

/// The largest number of points `scheme` returns in dimension `d`: `2d − 1` for `Tac2016`,
/// `2d² − 4d + 3` for `Moments` (the fallback returns fewer).
pub fn max_count(d: usize, scheme: Scheme) -> usize {
    match scheme {
        Scheme::Tac2016 { .. } => 2 * d - 1,
        Scheme::Moments => moments_count(d),
    }
}

fn moments_count(d: usize) -> usize {
    1 + 2 * (d - 1) + 2 * (d - 1) * (d - 2)
}

/// The point set in principal coordinates: the mode (weight `w0`), pairs with gnomonic offset
/// `t[i]` (`t2` holds `t²`) and weight `w1[i]` each, and (if `quads`) the quadruples of axes
/// `i < j` whose weights are computed from `q` on the fly.
#[derive(Debug, Clone)]
pub(crate) struct Plan<const N: usize> {
    d: usize,
    w0: f64,
    t2: [f64; N],
    w1: [f64; N],
    quads: bool,
    /// The girdle variant: three centers `e_{d−1}` (weight `w0`) and
    /// `(e_{d−1} ± τ e_{d−2})/‖·‖` (weight `center_w` each), pairs around each center.
    girdle: Option<Girdle<N>>,
    reproduced: Reproduced,
}

/// The girdle variant's extra parameters (see [`Plan::girdle`]).
#[derive(Debug, Clone)]
struct Girdle<const N: usize> {
    /// `τ²`.
    tau2: f64,
    /// Weight of each of the two outer centers.
    center_w: f64,
    /// Weight of each pair point around each outer center, per sharp axis.
    outer_w: [f64; N],
    /// The pairs' squared gnomonic offsets `t_i²`, per sharp axis (the plan's `t2` holds the
    /// quadruples' geometry).
    pair_t2: [f64; N],
}

impl<const N: usize> Plan<N> {
    /// Number of points.
    pub(crate) fn count(&self) -> usize {
        if self.quads {
            moments_count(self.d)
        } else {
            2 * self.d - 1
        }
    }

    pub(crate) fn reproduced(&self) -> Reproduced {
        self.reproduced
    }
}

/// `E[y_i² y_j²]` from the Hessian (row-major, d×d) and `ω`.
fn fourth(hess: &[f64], w: &[f64], d: usize, i: usize, j: usize) -> f64 {
    hess[i * d + j] + w[i] * w[j]
}

/// Builds the plan for normalized `z` (ascending, `z[d−1] = 0`, `d ≤ N`). `grad` (length d) and
/// `hess` (d² ) are scratch buffers that receive `ω` and `H`; they are needed again to
/// enumerate the points.
pub(crate) fn plan<const N: usize>(
    z: &[f64],
    scheme: Scheme,
    grad: &mut [f64],
    hess: &mut [f64],
) -> Result<Plan<N>> {
    let d = z.len();
    debug_assert!(d <= N && d >= 2);
    match scheme {
        Scheme::Tac2016 { lambda } => {
            if !(0.0..=1.0).contains(&lambda) {
                return Err(Error::InvalidArgument(format!(
                    "lambda must be in [0, 1], got {lambda}"
                )));
            }
            log_f_canonical(z, Some(grad), None)?;
            Ok(tac_plan(grad, lambda))
        }
        Scheme::Moments => {
            log_f_canonical(z, Some(&mut *grad), Some(&mut *hess))?;
            Ok(moments_plan(grad, hess)
                .or_else(|| girdle_plan(grad, hess))
                .unwrap_or_else(|| tac_plan(grad, 0.5)))
        }
    }
}

/// The TAC 2016 weights and offsets (`t² = tan² α = ω_i / (w_i − ω_i)`).
#[allow(clippy::needless_range_loop)] // three arrays indexed together
fn tac_plan<const N: usize>(w: &[f64], lambda: f64) -> Plan<N> {
    let d = w.len();
    let mut p = Plan {
        d,
        w0: 0.0,
        t2: [0.0; N],
        w1: [0.0; N],
        quads: false,
        girdle: None,
        reproduced: Reproduced::SecondMoment,
    };
    let spread = (1.0 - lambda) * w[d - 1] / (d - 1) as f64;
    let mut sum = 0.0;
    for i in 0..d - 1 {
        let wi = w[i] + spread;
        // sin² α = ω_i / w_i, cos² α = spread / w_i; with λ = 1 and ω_i > 0 the pair lies on
        // the axis itself (t = ∞): represent it by a huge offset, which normalizes to e_i.
        p.t2[i] = if spread > 0.0 {
            w[i] / spread
        } else {
            f64::INFINITY
        };
        p.w1[i] = wi / 2.0;
        sum += wi;
    }
    p.w0 = (1.0 - sum).max(0.0);
    p
}

/// The moment-matched plan, or `None` where a weight would be negative or not finite.
fn moments_plan<const N: usize>(w: &[f64], hess: &[f64]) -> Option<Plan<N>> {
    let d = w.len();
    let md = d - 1;
    let mut p = Plan {
        d,
        w0: 0.0,
        t2: [0.0; N],
        w1: [0.0; N],
        quads: true,
        girdle: None,
        reproduced: Reproduced::FourthMoments,
    };
    // t_i² = E[y_i⁴] / E[y_i² y_d²] (E[y_i⁴] = H_ii + ω_i² directly: the equivalent
    // ω_i − Σ_{j≠i} E[y_i² y_j²] cancels badly for concentrated distributions).
    for i in 0..md {
        let e4 = fourth(hess, w, d, i, i);
        let qd = fourth(hess, w, d, i, md);
        let t2 = e4 / qd;
        if !(t2.is_finite() && t2 > 0.0) {
            return None;
        }
        p.t2[i] = t2;
    }
    // Residual second and mixed-mode fourth moments after the quadruples.
    let mut r2 = [0.0; N];
    let mut r4 = [0.0; N];
    for i in 0..md {
        r2[i] = w[i];
        r4[i] = fourth(hess, w, d, i, md);
    }
    let mut total = 0.0;
    for i in 0..md {
        for j in i + 1..md {
            let (wq, yi2, yj2, yd2) = quad_weight(hess, w, &p.t2, d, i, j);
            if !(wq.is_finite() && wq >= 0.0) {
                return None;
            }
            r2[i] -= 4.0 * wq * yi2;
            r2[j] -= 4.0 * wq * yj2;
            r4[i] -= 4.0 * wq * yi2 * yd2;
            r4[j] -= 4.0 * wq * yj2 * yd2;
            total += 4.0 * wq;
        }
    }
    for i in 0..md {
        // Pair weight from the mixed-mode moment; with t² = E[y_i⁴]/E[y_i² y_d²] the second
        // moment r2 is then matched identically (no separate axis point is needed).
        let t2 = p.t2[i];
        let w1 = r4[i] * (1.0 + t2) * (1.0 + t2) / (2.0 * t2);
        if !(w1.is_finite() && w1 >= 0.0 && r2[i] >= 0.0) {
            return None;
        }
        p.w1[i] = w1;
        total += 2.0 * w1;
    }
    let w0 = 1.0 - total;
    if !(w0.is_finite() && w0 >= 0.0) {
        return None;
    }
    p.w0 = w0;
    Some(p)
}

/// The girdle variant of the moment-matched plan for `d ≥ 3`: the broad axis `b = d − 2` joins
/// the mode in a three-point circle rule (centers `e_d` and `(e_d ± τ e_b)/‖·‖`), the other
/// ("sharp") axes get pairs around each center and quadruples around `e_d`. With
/// `τ² = E[y_b⁴] / E[y_b² y_d²]` and, per sharp axis, `t_i² = E[y_i²] / (E[y_i² y_b²] +
/// E[y_i² y_d²]) − 1` (after the quadruples) every second and fourth moment is matched in
/// closed form. `None` where a weight would be negative or not finite.
#[allow(clippy::needless_range_loop)] // several arrays indexed together
fn girdle_plan<const N: usize>(w: &[f64], hess: &[f64]) -> Option<Plan<N>> {
    let d = w.len();
    if d < 3 {
        return None;
    }
    let (md, b) = (d - 1, d - 2);
    let tau2 = fourth(hess, w, d, b, b) / fourth(hess, w, d, b, md);
    if !(tau2.is_finite() && tau2 > 0.0) {
        return None;
    }
    let (c3, c4) = (tau2 / (1.0 + tau2), 1.0 / (1.0 + tau2));
    let mut p = Plan {
        d,
        w0: 0.0,
        t2: [0.0; N],
        w1: [0.0; N],
        quads: true,
        girdle: Some(Girdle {
            tau2,
            center_w: 0.0,
            outer_w: [0.0; N],
            pair_t2: [0.0; N],
        }),
        reproduced: Reproduced::FourthMoments,
    };
    // Quadruple geometry from the single-center estimate t_i² = E[y_i⁴] / E[y_i² (y_b² + y_d²)].
    for i in 0..b {
        let t2 = fourth(hess, w, d, i, i) / (fourth(hess, w, d, i, b) + fourth(hess, w, d, i, md));
        if !(t2.is_finite() && t2 > 0.0) {
            return None;
        }
        p.t2[i] = t2;
    }
    // Per sharp axis: E[y_i² (y_i² + Σ_{sharp j ≠ i} y_j²)] (= E[y_i²] − E[y_i² (y_b² + y_d²)],
    // formed without that cancellation), E[y_i² y_b²] and E[y_i² y_d²], minus what the
    // quadruples carry.
    let mut r2 = [0.0; N];
    let mut r4b = [0.0; N];
    let mut r4d = [0.0; N];
    for i in 0..b {
        r2[i] = (0..b).map(|j| fourth(hess, w, d, i, j)).sum();
        r4b[i] = fourth(hess, w, d, i, b);
        r4d[i] = fourth(hess, w, d, i, md);
    }
    let mut total = 0.0;
    // Broad-axis moments carried by the points other than the centers.
    let (mut carried2, mut carried4) = (0.0, 0.0);
    for i in 0..b {
        for j in i + 1..b {
            let (wq, yi2, yj2, yd2) = quad_weight(hess, w, &p.t2, d, i, j);
            if !(wq.is_finite() && wq >= 0.0) {
                return None;
            }
            r2[i] -= 4.0 * wq * yi2 * (yi2 + yj2);
            r2[j] -= 4.0 * wq * yj2 * (yi2 + yj2);
            r4d[i] -= 4.0 * wq * yi2 * yd2;
            r4d[j] -= 4.0 * wq * yj2 * yd2;
            total += 4.0 * wq;
        }
    }
    let g = p.girdle.as_mut().expect("set above");
    for i in 0..b {
        // Pairs (c_k ± t e_i)/√(1 + t²): their y_i² y_b² and y_i² y_d² add up to y_i² / (1 + t²).
        let t2 = r2[i] / (r4b[i] + r4d[i]);
        let outer = r4b[i] * (1.0 + t2) * (1.0 + t2) / (4.0 * t2 * c3);
        let inner = r4d[i] * (1.0 + t2) * (1.0 + t2) / (2.0 * t2) - 2.0 * outer * c4;
        if !(t2.is_finite() && t2 > 0.0 && outer >= 0.0 && inner >= 0.0 && outer.is_finite()) {
            return None;
        }
        g.pair_t2[i] = t2;
        p.w1[i] = inner;
        g.outer_w[i] = outer;
        total += 2.0 * inner + 4.0 * outer;
        // The outer pairs' share of y_b² and y_b² y_d².
        let y_b2 = c3 / (1.0 + t2);
        carried2 += 4.0 * outer * y_b2;
        carried4 += 4.0 * outer * y_b2 * c4 / (1.0 + t2);
    }
    // The outer centers carry the rest of E[y_b²] (and with τ² as chosen, E[y_b² y_d²]).
    let rest2 = w[b] - carried2;
    let rest4 = fourth(hess, w, d, b, md) - carried4;
    let center_w = rest2 / (2.0 * c3);
    if !(center_w.is_finite() && center_w >= 0.0 && rest4 >= 0.0) {
        return None;
    }
    g.center_w = center_w;
    total += 2.0 * center_w;
    let w0 = 1.0 - total;
    if !(w0.is_finite() && w0 >= 0.0) {
        return None;
    }
    p.w0 = w0;
    Some(p)
}

/// The weight of each of the four quadruple points of axes `i < j` and their squared
/// principal coordinates `(w, y_i², y_j², y_d²)`.
fn quad_weight(
    hess: &[f64],
    w: &[f64],
    t2: &[f64],
    d: usize,
    i: usize,
    j: usize,
) -> (f64, f64, f64, f64) {
    let n = 1.0 + t2[i] + t2[j];
    let (yi2, yj2, yd2) = (t2[i] / n, t2[j] / n, 1.0 / n);
    let q = fourth(hess, w, d, i, j);
    (q / (4.0 * yi2 * yj2), yi2, yj2, yd2)
}

/// Calls `visit(y, weight)` for every point of `plan` in principal coordinates (`y` of length
/// d, unit, mode component positive), in the documented order: the mode; for each non-mode
/// axis `i` the points `+t_i`, `−t_i`; then (Moments) for each `i < j` the signs
/// `(+,+), (+,−), (−,+), (−,−)`. `grad`, `hess` as filled by [`plan`].
pub(crate) fn for_each_principal<const N: usize>(
    plan: &Plan<N>,
    grad: &[f64],
    hess: &[f64],
    mut visit: impl FnMut(&[f64], f64) -> Result<()>,
) -> Result<()> {
    let d = plan.d;
    let md = d - 1;
    let mut y = [0.0; N];
    y[md] = 1.0;
    visit(&y[..d], plan.w0)?;
    // Sharp axes (with quadruples) are 0..last; the girdle's broad axis d − 2 is a center axis.
    let last = match &plan.girdle {
        None => {
            for i in 0..md {
                pair(&mut y, d, plan.t2[i], None, i, plan.w1[i], &mut visit)?;
            }
            md
        }
        Some(g) => {
            let b = d - 2;
            let (cb, cd) = (
                (g.tau2 / (1.0 + g.tau2)).sqrt(),
                (1.0 / (1.0 + g.tau2)).sqrt(),
            );
            for sign in [1.0, -1.0] {
                y.fill(0.0);
                y[md] = cd;
                y[b] = sign * cb;
                visit(&y[..d], g.center_w)?;
            }
            for i in 0..b {
                let t2 = g.pair_t2[i];
                pair(&mut y, d, t2, None, i, plan.w1[i], &mut visit)?;
                pair(&mut y, d, t2, Some((cb, cd)), i, g.outer_w[i], &mut visit)?;
                pair(&mut y, d, t2, Some((-cb, cd)), i, g.outer_w[i], &mut visit)?;
            }
            b
        }
    };
    if plan.quads {
        for i in 0..last {
            for j in i + 1..last {
                let (wq, yi2, yj2, yd2) = quad_weight(hess, grad, &plan.t2, d, i, j);
                let (a, b, c) = (yi2.sqrt(), yj2.sqrt(), yd2.sqrt());
                for (si, sj) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                    y.fill(0.0);
                    y[md] = c;
                    y[i] = si * a;
                    y[j] = sj * b;
                    visit(&y[..d], wq)?;
                }
            }
        }
    }
    Ok(())
}

/// Visits the two points `(c ± t e_i)/√(1 + t²)` (weight `w` each) around the center `c`:
/// `e_{d−1}`, or (`center = Some((c_b, c_d))`) `c_b e_{d−2} + c_d e_{d−1}`. `t² = ∞` puts them
/// on `±e_i`.
fn pair(
    y: &mut [f64],
    d: usize,
    t2: f64,
    center: Option<(f64, f64)>,
    i: usize,
    w: f64,
    visit: &mut impl FnMut(&[f64], f64) -> Result<()>,
) -> Result<()> {
    let (c, s) = if t2.is_infinite() {
        (0.0, 1.0)
    } else {
        let n = (1.0 + t2).sqrt();
        (1.0 / n, t2.sqrt() / n)
    };
    let (cb, cd) = center.unwrap_or((0.0, 1.0));
    for sign in [1.0, -1.0] {
        y.fill(0.0);
        y[d - 1] = c * cd;
        if d >= 3 {
            y[d - 2] = c * cb;
        }
        y[i] = sign * s;
        visit(&y[..d], w)?;
    }
    Ok(())
}

/// Extra points for fitting a quadratic form `xᵀ P x` where `plan` has no more points than `P`
/// has free entries: for d = 2 the pair at twice the offset; for the `2d − 1` fallback (d ≥ 4)
/// the quadruples
/// `(e_{d−1} ± t_i e_i ± t_j e_j)/‖·‖` with the plan's offsets, mapped by `M`, each with a
/// quarter of the smallest pair weight. They carry no moment: callers use them for the fit
/// only. Nothing is visited when the plan has its own quadruples.
pub(crate) fn for_each_probe<D: Dim, const N: usize>(
    m: &Square<D>,
    plan: &Plan<N>,
    mut visit: impl FnMut(&Vector<D>, f64) -> Result<()>,
) -> Result<()>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let d = plan.d;
    let (dd, _) = m.shape_generic();
    if d == 2 {
        // Three points determine a 2×2 quadratic form exactly: two more, at twice the offset,
        // make the fit's residual meaningful.
        let t = 2.0 * plan.t2[0].min(1e300).sqrt();
        for sign in [1.0, -1.0] {
            let mut x = Vector::<D>::zeros_generic(dd, U1);
            x.axpy(1.0, &m.column(1), 1.0);
            x.axpy(sign * t, &m.column(0), 1.0);
            let n = x.norm();
            x /= n;
            visit(&x, 0.5 * plan.w1[0])?;
        }
        return Ok(());
    }
    if plan.quads || d < 4 {
        return Ok(());
    }
    let md = d - 1;
    let wt = 0.25 * plan.w1[..md].iter().fold(f64::INFINITY, |a, &b| a.min(b));
    for i in 0..md {
        for j in i + 1..md {
            let (ti, tj) = (plan.t2[i].min(1e300).sqrt(), plan.t2[j].min(1e300).sqrt());
            for (si, sj) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                let mut x = Vector::<D>::zeros_generic(dd, U1);
                x.axpy(1.0, &m.column(md), 1.0);
                x.axpy(si * ti, &m.column(i), 1.0);
                x.axpy(sj * tj, &m.column(j), 1.0);
                let n = x.norm();
                x /= n;
                visit(&x, wt)?;
            }
        }
    }
    Ok(())
}

/// Calls `visit(x, weight)` for every point `x = M y` of `plan` (see [`for_each_principal`]).
pub(crate) fn for_each_point<D: Dim, const N: usize>(
    m: &Square<D>,
    plan: &Plan<N>,
    grad: &[f64],
    hess: &[f64],
    mut visit: impl FnMut(&Vector<D>, f64) -> Result<()>,
) -> Result<()>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let (dd, _) = m.shape_generic();
    for_each_principal(plan, grad, hess, |y, wt| {
        let mut x = Vector::<D>::zeros_generic(dd, U1);
        for (k, &yk) in y.iter().enumerate() {
            if yk != 0.0 {
                x.axpy(yk, &m.column(k), 1.0);
            }
        }
        let n = x.norm();
        x /= n;
        visit(&x, wt)
    })
}

impl Bingham {
    /// Deterministic samples of this distribution (see the module documentation for the
    /// schemes, the point layout and what each reproduces).
    ///
    /// Errors: `InvalidArgument` (`lambda` outside `[0, 1]`), `Numerical` (log F failed).
    pub fn deterministic_samples(&self, scheme: Scheme) -> Result<DeterministicSamples> {
        let d = self.dim();
        let mut grad = vec![0.0; d];
        let mut hess = vec![0.0; d * d];
        let z = self.z().as_slice();
        let plan = plan::<{ crate::error::MAX_DIM }>(z, scheme, &mut grad, &mut hess)?;
        let mut points = Vec::with_capacity(plan.count() * d);
        let mut weights = Vec::with_capacity(plan.count());
        for_each_point(self.m(), &plan, &grad, &hess, |x, wt| {
            points.extend_from_slice(x.as_slice());
            weights.push(wt);
            Ok(())
        })?;
        Ok(DeterministicSamples {
            d,
            points,
            weights,
            reproduced: plan.reproduced(),
        })
    }
}
