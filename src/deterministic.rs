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
//!   tends to. The weights are positive for every `z` tried with d = 2 and 3; for d = 4 they are
//!   positive unless two directions are much sharper than a third, broad one (e.g.
//!   `z = (−1e4, −400, −0.5, 0)`: a "girdle" with two sharp axes), where no positive set of this
//!   shape exists. There, and wherever a weight would be negative or a quantity underflows
//!   (|z| beyond about 1e150), the scheme returns the `2d − 1` points of `Tac2016` with
//!   `λ = 1/2` instead, which reproduce the second moment only, and says so
//!   ([`Reproduced::SecondMoment`]).
//!
//! Points are returned as unit vectors, each in one hemisphere (the mode's component is
//! positive); a Bingham is antipodally symmetric, so `−x` stands for the same point.

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, U1};

use crate::distribution::Bingham;
use crate::error::{Error, Result};
use crate::matrix::{Square, Vector};
use crate::normalization::{log_normalization_into, Method};

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
    /// moment, or (where no positive set of that shape exists) the `2d − 1` points of
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
    reproduced: Reproduced,
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
            log_normalization_into(z, Method::Exact, Some(grad), None)?;
            Ok(tac_plan(grad, lambda))
        }
        Scheme::Moments => {
            log_normalization_into(z, Method::Exact, Some(&mut *grad), Some(&mut *hess))?;
            Ok(moments_plan(grad, hess).unwrap_or_else(|| tac_plan(grad, 0.5)))
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
    for i in 0..md {
        let t2 = plan.t2[i];
        let (c, s) = if t2.is_infinite() {
            (0.0, 1.0)
        } else {
            let n = (1.0 + t2).sqrt();
            (1.0 / n, t2.sqrt() / n)
        };
        for sign in [1.0, -1.0] {
            y.fill(0.0);
            y[md] = c;
            y[i] = sign * s;
            visit(&y[..d], plan.w1[i])?;
        }
    }
    if plan.quads {
        for i in 0..md {
            for j in i + 1..md {
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
