//! d = 3 and d = 4: the normalization constant as an exact 1-D integral of Bessel functions.
//!
//! Split the coordinates into two groups whose squared norms are `u` and `1 − u`
//! (`docs/design.md`, § "d = 3, 4: one-dimensional Bessel integrals"). With `z` sorted
//! ascending and `z_d = 0`:
//!
//! * d = 4: two circles, `(z1, z2)` of radius² `u` and `(z3, z4)` of radius² `1 − u`:
//!   `F = 2π² ∫₀¹ A(u) B(1−u) du`, `A(r) = e^{r z2} I0e(r (z2−z1)/2)`, `B(r) = I0e(r (z4−z3)/2)`.
//! * d = 3: the single coordinate `x1` (`x1² = u`) and the circle `(z2, z3)`:
//!   `F = 2π ∫₀¹ A(u) B(1−u) du`, `A(r) = r^{−1/2} e^{r z1}`, `B(r) = I0e(r (z3−z2)/2)`.
//!
//! Moments come from the same integrals (the circle moments `E[x_lo²] = r (I0e − I1e)/2`, …, in
//! `docs/design.md`); every integrand is positive, so `ω_i = E[x_i²]` carries no cancellation.
//!
//! Contract: for every finite sorted `z` with `z_d = 0`, `log F` and every `ω_i` to near machine
//! precision (down to `ω_i ≈ 1/(2|z_i|)` at |z| = 1e300); the Hessian less accurately (a
//! covariance of nearly independent coordinates cancels digits; it only steers the MLE). How: the halves `u ∈ [0, ½]`, `[½, 1]` in `√u`, `√(1−u)`, graded 20-point
//! Gauss–Legendre panels (`LAYOUT`), power-of-two scalings per group and half (`Scaling`), the
//! kernel (`kernel`) compiled per CPU path (`simd`, the crate's only `unsafe` outside the FFI).
//! Derivation and numerics: `docs/design.md` (§ "Numerical notes": d = 3, 4 quadrature, kernel
//! paths, range); measured accuracy `docs/accuracy.md`, speed `docs/speed.md`.

use super::gauss::gauss_legendre_unit;
use super::Path;
use crate::error::Result;
use crate::special::lanes::{self, Arith, Fused, Plain, Span, F};
use crate::special::pow2_floor;

mod kernel;
mod simd;

use kernel::half_setup;
use simd::half_on;

/// Panel layout of the composite rule.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Layout {
    /// First breakpoint, in units of the smallest feature scale.
    pub first: f64,
    /// Ratio of consecutive breakpoints in the graded part.
    pub rho: f64,
    /// Largest panel width in `v` or `s` (the half-range is 1/√2).
    pub w_max: f64,
    /// Truncation: the exponential factor `e^{u z}` is dropped past `u |z| = trunc`.
    pub trunc: f64,
    /// Largest panel width in units of the Gaussian scale `1/√|z|` of `e^{u z} = e^{v² z}`.
    pub kappa: f64,
    /// Growth of the grading ratio from one panel to the next (1: constant `rho`).
    pub grow: f64,
}

/// A Gauss–Legendre rule on `[0, 1]`, its nodes and weights padded with zero-weight nodes to a
/// multiple of 8 (the most lanes a batch has), so that a panel is a whole number of batches.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rule {
    x: &'static [f64],
    w: &'static [f64],
    /// the rule's order (nodes per panel without the padding)
    n: usize,
}

/// The `N`-point rule padded to `P` nodes (`P ≥ N` a multiple of 8; padding: node ½, weight 0).
const fn padded<const N: usize, const P: usize>() -> ([f64; P], [f64; P]) {
    assert!(P >= N && P % 8 == 0);
    let (x, w) = gauss_legendre_unit::<N>();
    let mut px = [0.5; P];
    let mut pw = [0.0; P];
    let mut i = 0;
    while i < N {
        px[i] = x[i];
        pw[i] = w[i];
        i += 1;
    }
    (px, pw)
}

/// Gauss–Legendre order per panel of the production rule.
const N: usize = 20;
static RULE_NODES: ([f64; 24], [f64; 24]) = padded::<N, 24>();
static RULE: Rule = Rule {
    x: &RULE_NODES.0,
    w: &RULE_NODES.1,
    n: N,
};
/// The production layout, chosen by measurement against the fine rule ([`log_f_sorted_fine`];
/// `log_f_sorted_tuned` runs other layouts): over 40 000 random z (d = 3, 4; |z_i| from 1e-3 to
/// 1e6, uniform in [−1e6, 0], ties, zeros) max |Δ log F| 3.6e-15, relative Δω 1.3e-15, ΔH
/// 7.8e-15 (relative to `√(H_ii H_jj)`), 58.6 nodes on average for d = 4 and 42.6 for d = 3 (the
/// layout before: 82 and 76 nodes, Δω 5.0e-15, ΔH 2.3e-13); over 30 000 z with |z_i| up to
/// 1e306, relative Δω 1.8e-15. The grading ratio starts at 3 and grows by 1.4 per panel: the
/// Bessel factor's departure from its asymptote, the part that limits a panel's ratio, falls
/// off like `(s_min/t)²`. Neighbouring layouts pass too (first 2–3, rho 2.5–3.5, grow 1.2–1.6);
/// ratios from 4 up, a first breakpoint beyond 3 scales, or panels wider than 5 Gaussian
/// scales (when the grading starts far below them, `FLOOR`) lose accuracy (up to 1e-13).
const LAYOUT: Layout = Layout {
    first: 2.5,
    rho: 3.0,
    w_max: 0.71,
    trunc: 40.0,
    kappa: 4.0,
    grow: 1.4,
};
/// Most breakpoints a half can need.
const MAX_BREAKS: usize = 200;

/// One group of coordinates: a single axis or a circle.
#[derive(Clone, Copy, Debug)]
enum Group {
    /// One coordinate with concentration `z ≤ 0`.
    Single { z: f64 },
    /// Two coordinates `z_lo ≤ z_hi ≤ 0`; `beta = (z_hi − z_lo)/2`.
    Circle { zhi: f64, beta: f64 },
}

/// A group's scaled value and second moment factors at radius² `r` (see [`Scaling`]).
#[derive(Clone, Copy, Default)]
struct GroupEval {
    /// `C·g` (near position: `C·√r·g`)
    g: f64,
}

/// A group's scaled value and moment factors at a batch of `L` radii² (see [`Scaling`]).
#[derive(Clone, Copy)]
struct GroupLanes<const L: usize> {
    /// `C·g` (near position: `C·√r·g`)
    g: F<L>,
    /// second moments `D_k·r·E[x_k²]·g` (times the same factor as `g`) of the group's
    /// coordinates (lo, hi)
    m: [F<L>; 2],
    /// fourth moments (lo lo, lo hi, hi hi), each times `D_k D_l` and the factor of `g`
    q: [F<L>; 3],
}

/// A group's exact scale factors in one half of the integral.
///
/// In the near position (the group's radius² is the integration variable `r = t²`,
/// `t ∈ [0, T]`) the group contributes `√r·g(r)·C` per node and the weight loses its factor
/// `2t` (`2t·g = 2·(√r g)`); in the far position (`r = 1 − t² ∈ [½, 1]`) it contributes
/// `C·g(r)`. `C` makes that O(1) in the region that dominates: `√β` for a circle whose Bessel
/// argument `rβ` exceeds 1 there ("wide": `I0e(rβ) ≈ (2π rβ)^{−1/2}`), `1/√R` otherwise, 1 for
/// a single axis (`√r·e^{rz}/√r = e^{rz}`). The moment factors are scaled by `D = 1/R`
/// (`R = T²` near, 1 far: `E[x²] ≤ r ≤ R`), except the lo coordinate of a wide circle, whose
/// `r E[x_lo²] ≈ 1/(2β)` is scaled by `β`. `C` and `1/R` are powers of two.
#[derive(Clone, Copy, Debug)]
struct Scaling {
    c: f64,
    inv_r: f64,
    wide: bool,
    /// `D` of the group's coordinates (lo, hi)
    d: [f64; 2],
    near: bool,
}

impl Group {
    fn size(&self) -> usize {
        match self {
            Group::Single { .. } => 1,
            Group::Circle { .. } => 2,
        }
    }

    /// Rate of the exponential factor (`|z|` of the exponent), ≥ 0.
    fn rate(&self) -> f64 {
        match *self {
            Group::Single { z } => -z,
            Group::Circle { zhi, .. } => -zhi,
        }
    }

    fn beta(&self) -> f64 {
        match *self {
            Group::Single { .. } => 0.0,
            Group::Circle { beta, .. } => beta,
        }
    }

    /// The group's scaling in a half where its largest radius² is `r_max` (`≤ 1`).
    fn scaling(&self, r_max: f64, near: bool) -> Scaling {
        let inv_r = pow2_floor(1.0 / r_max);
        match *self {
            Group::Single { .. } => Scaling {
                c: 1.0,
                inv_r,
                wide: false,
                d: [inv_r, inv_r],
                near,
            },
            Group::Circle { beta, .. } => {
                let wide = beta * r_max >= 1.0;
                Scaling {
                    c: pow2_floor(if wide {
                        beta.sqrt()
                    } else {
                        r_max.sqrt().recip()
                    }),
                    inv_r,
                    wide,
                    d: [if wide { beta } else { inv_r }, inv_r],
                    near,
                }
            }
        }
    }

    /// What the Bessel arguments `rβ` of a batch share when its radii² lie between `ra` and
    /// `rb` (either order); [`Span::Mixed`] for a single axis (no Bessel function).
    fn span(&self, ra: f64, rb: f64) -> Span {
        match *self {
            Group::Single { .. } => Span::Mixed,
            Group::Circle { beta, .. } => {
                let (xa, xb) = (ra * beta, rb * beta);
                Span::of(xa.min(xb), xa.max(xb))
            }
        }
    }

    /// The scaled value `C·g` alone at one far radius² `r = root²` (for the bound that decides
    /// whether the far half is needed).
    fn eval_far(&self, sc: &Scaling, r: f64, root: f64) -> GroupEval {
        match *self {
            Group::Single { z } => GroupEval {
                g: (r * z).exp() / root,
            },
            Group::Circle { zhi, beta } => {
                let (i0, _, _, _) = crate::special::i01e_times(r * beta, sc.c);
                GroupEval {
                    g: (r * zhi).exp() * i0,
                }
            }
        }
    }

    /// Evaluates at the radii² `r = root²` of a batch (the roots are passed to avoid square
    /// roots; unused in the far position of a circle), scaled by `sc`; `span` is what the
    /// Bessel arguments share ([`Group::span`]).
    #[inline(always)]
    fn eval_lanes<
        A: Arith,
        const L: usize,
        const L2: usize,
        const L4: usize,
        const FOURTH: bool,
    >(
        &self,
        sc: &Scaling,
        r: F<L>,
        root: F<L>,
        span: Span,
    ) -> GroupLanes<L> {
        let rr = r * sc.inv_r;
        let zero = F::splat(0.0);
        match *self {
            Group::Single { z } => {
                let ex = lanes::exp::<A, L>(r * z);
                let g = if sc.near {
                    ex
                } else {
                    ex.zip(root, |e, s| e / s)
                };
                let mut e = GroupLanes {
                    g,
                    m: [rr * g, zero],
                    q: [zero; 3],
                };
                if FOURTH {
                    e.q[0] = rr * rr * g;
                }
                e
            }
            Group::Circle { zhi, beta } => {
                let x = r * beta;
                let k = if sc.near { root * sc.c } else { F::splat(sc.c) };
                let b = lanes::bessel::<A, L, L2, L4, FOURTH>(x, k, span);
                // e^{r zhi}; exactly 1 for zhi = 0 (always so for the far-right group)
                let ex = if zhi == 0.0 {
                    F::splat(1.0)
                } else {
                    lanes::exp::<A, L>(r * zhi)
                };
                let g = ex * b.i0;
                let h = ex * 0.5;
                let mut e = GroupLanes {
                    g,
                    m: [
                        if sc.wide { h * b.xdm } else { h * rr * b.dm },
                        h * rr * (b.i0 + b.i1),
                    ],
                    q: [zero; 3],
                };
                if FOURTH {
                    let i2 = b.i0 - b.i1x * 2.0;
                    let rr2 = rr * rr * ex;
                    e.q = if sc.wide {
                        [ex * b.x2q * 0.125, rr * ex * b.i1 * 0.25, zero]
                    } else {
                        [rr2 * b.q * 0.125, rr2 * b.i1x * 0.25, zero]
                    };
                    e.q[2] = rr2 * (b.i0 * 3.0 + b.i1 * 4.0 + i2) * 0.125;
                }
                e
            }
        }
    }
}

/// The panels `[b_i, b_{i+1}]` of one half, `0 = b0 < b1 < … = t_max`: the first breakpoint
/// at `first·s_min` (the smallest feature scale), then graded geometrically by `rho`, with
/// widths capped by `w_max` and by `kappa` Gaussian scales; at most `MAX_BREAKS` breakpoints.
#[derive(Clone, Copy, Debug)]
struct Panels {
    lo: f64,
    hi: f64,
    /// breakpoints so far, `lo` included
    count: usize,
    done: bool,
    t_max: f64,
    rho: f64,
    grow: f64,
    /// largest width: `min(w_max, kappa·gauss)`
    step: f64,
}

impl Panels {
    fn new(lay: &Layout, t_max: f64, s_min: f64, gauss: f64) -> Self {
        Panels {
            lo: 0.0,
            hi: (lay.first * s_min).min(t_max),
            count: 1,
            done: false,
            t_max,
            rho: lay.rho,
            grow: lay.grow,
            step: lay.w_max.min(lay.kappa * gauss),
        }
    }
}

impl Iterator for Panels {
    type Item = (f64, f64);

    #[inline(always)]
    fn next(&mut self) -> Option<(f64, f64)> {
        if self.done {
            return None;
        }
        let panel = (self.lo, self.hi);
        self.count += 1;
        let x = self.hi;
        if x >= self.t_max {
            self.done = true;
        } else {
            self.lo = x;
            self.hi = if self.count == MAX_BREAKS - 1 {
                self.t_max
            } else {
                (x * self.rho).min(x + self.step).min(self.t_max)
            };
            self.rho *= self.grow;
        }
        Some(panel)
    }
}

/// The `D` factors of the d coordinates (group 1's, then group 2's).
fn d_factors(g1: &Group, sc1: &Scaling, sc2: &Scaling) -> [f64; 4] {
    if g1.size() == 1 {
        [sc1.d[0], sc2.d[0], sc2.d[1], 1.0]
    } else {
        [sc1.d[0], sc1.d[1], sc2.d[0], sc2.d[1]]
    }
}

/// `log F`, `ω` and (with `fourth`) the Hessian in sorted order, and the node count.
struct Integral {
    log_f: f64,
    omega: [f64; 4],
    hess: [f64; 16],
    nodes: usize,
}

#[allow(clippy::too_many_arguments)]
fn integrate_counted(
    path: Path,
    rule: &Rule,
    lay: &Layout,
    log_c: f64,
    g1: Group,
    g2: Group,
    d: usize,
    fourth: bool,
) -> Integral {
    let left = half_setup(lay, &g1, &g2, true);
    let (sc1, sc2) = (left.sc1, left.sc2);
    let mut sums = half_on(path, rule, &g1, &g2, true, fourth, &left);
    let dl = d_factors(&g1, &sc1, &sc2);
    // The far half u ∈ [½, 1]: A(u) decreases and B(1−u) ≤ 1, so its integral is at most
    // A(½)/2 (times the moment factors, ≤ 1). Skip it when that bound is negligible against
    // F and against every moment integral (all in the left half's scaled units:
    // f_true = f/(C1 C2), m_true = m/(C1 C2 D)).
    let at_half = g1.eval_far(&sc1, 0.5, std::f64::consts::FRAC_1_SQRT_2);
    let bound = 0.5 * at_half.g * sc2.c;
    let smallest = sums.m[..d]
        .iter()
        .zip(dl.iter())
        .fold(sums.f, |acc, (&m, &dk)| acc.min(m / dk));
    if bound > 1e-18 * smallest {
        let setup = half_setup(lay, &g1, &g2, false);
        let right = half_on(path, rule, &g1, &g2, false, fourth, &setup);
        let (rc1, rc2) = (setup.sc1, setup.sc2);
        let dr = d_factors(&g1, &rc1, &rc2);
        // right-half sums in the left half's units (modest ratios: this half only runs
        // when group 1's rate is below a few thousand)
        let cf = (sc1.c / rc1.c) * (sc2.c / rc2.c);
        let mut ratio = [0.0; 4];
        for ((r, l), rr) in ratio.iter_mut().zip(&dl).zip(&dr).take(d) {
            *r = cf * (l / rr);
        }
        sums.nodes += right.nodes;
        sums.f += cf * right.f;
        for ((s, r), m) in sums.m.iter_mut().zip(&ratio).zip(&right.m).take(d) {
            *s += r * m;
        }
        if fourth {
            for (i, (row, rrow)) in sums.q.iter_mut().zip(&right.q).enumerate().take(d) {
                for j in i..d {
                    row[j] += (ratio[i] * (dl[j] / dr[j])) * rrow[j];
                }
            }
        }
    }
    // f / (C1 C2) by exact power-of-two divisions; its logarithm directly while it is a
    // normal double, else log f minus the scale's exponent times ln 2
    let f_true = sums.f / sc1.c / sc2.c;
    let log_f = if f_true >= f64::MIN_POSITIVE {
        log_c + f_true.ln()
    } else {
        let exponent = |v: f64| ((v.to_bits() >> 52) as i64 - 1023) as f64;
        log_c + sums.f.ln() - (exponent(sc1.c) + exponent(sc2.c)) * std::f64::consts::LN_2
    };
    let mut out = Integral {
        log_f,
        omega: [0.0; 4],
        hess: [0.0; 16],
        nodes: sums.nodes,
    };
    for ((w, m), dk) in out.omega.iter_mut().zip(&sums.m).zip(&dl).take(d) {
        *w = m / sums.f / dk;
    }
    if fourth {
        let (omega, h) = (&out.omega, &mut out.hess);
        // Cov(x_i², x_j²) for i, j < d; the last row and column from Σ_i ∂ω_i/∂z_j = 0,
        // which avoids the cancellation E[x_d⁴] − ω_d² when x_d² ≈ 1.
        for i in 0..d - 1 {
            for j in i..d - 1 {
                let v = sums.q[i][j] / sums.f / dl[i] / dl[j] - omega[i] * omega[j];
                h[i * d + j] = v;
                h[j * d + i] = v;
            }
        }
        let mut last_sum = 0.0;
        for i in 0..d - 1 {
            let s: f64 = (0..d - 1).map(|j| h[i * d + j]).sum();
            h[i * d + d - 1] = -s;
            h[(d - 1) * d + i] = -s;
            last_sum += s;
        }
        h[d * d - 1] = last_sum;
    }
    out
}

/// Evaluates with the given rule, layout and kernel; writes the outputs in sorted order.
fn integrate(
    path: Path,
    rule: &Rule,
    lay: &Layout,
    z: &[f64],
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<(f64, usize)> {
    let d = z.len();
    let (log_c, g1, g2) = groups(z);
    let out = integrate_counted(path, rule, lay, log_c, g1, g2, d, hess.is_some());
    if let Some(g) = grad {
        g.copy_from_slice(&out.omega[..d]);
    }
    if let Some(h) = hess {
        h.copy_from_slice(&out.hess[..d * d]);
    }
    Ok((out.log_f, out.nodes))
}

/// `log c` and the two groups of sorted `z` (d = 3 or 4), `F = c ∫ A B` (module documentation).
fn groups(z: &[f64]) -> (f64, Group, Group) {
    /// ln(2π) and ln(2π²), as `f64::ln` rounds them
    const LN_2PI: f64 = 1.8378770664093453;
    const LN_2PI2: f64 = 2.9826069522587457;
    if z.len() == 3 {
        (
            LN_2PI,
            Group::Single { z: z[0] },
            Group::Circle {
                zhi: z[2],
                beta: 0.5 * (z[2] - z[1]),
            },
        )
    } else {
        (
            LN_2PI2,
            Group::Circle {
                zhi: z[1],
                beta: 0.5 * (z[1] - z[0]),
            },
            Group::Circle {
                zhi: z[3],
                beta: 0.5 * (z[3] - z[2]),
            },
        )
    }
}

/// The same integral with a much finer rule (Gauss–Legendre 30 on a layout ~4× denser,
/// truncation at e^{−80}): the convergence check used by the tests. Sorted `z`; writes `ω`
/// and, if given, the Hessian (sorted order).
#[doc(hidden)]
pub fn log_f_sorted_fine(z: &[f64], grad: &mut [f64], hess: Option<&mut [f64]>) -> Result<f64> {
    static R30: ([f64; 32], [f64; 32]) = padded::<30, 32>();
    let fine = Layout {
        first: 0.25,
        rho: 1.6,
        w_max: 0.08,
        trunc: 80.0,
        kappa: 0.5,
        grow: 1.0,
    };
    let rule = Rule {
        x: &R30.0,
        w: &R30.1,
        n: 30,
    };
    integrate(Path::detected(), &rule, &fine, z, Some(grad), hess).map(|r| r.0)
}

/// Evaluation with a chosen Gauss–Legendre order and layout `[first, rho, w_max, trunc, kappa,
/// grow]` (`grow` optional, default 1) for tuning experiments; returns `log F` and the node count.
#[doc(hidden)]
pub fn log_f_sorted_tuned(
    z: &[f64],
    grad: &mut [f64],
    hess: Option<&mut [f64]>,
    n: usize,
    lay: &[f64],
) -> Result<(f64, usize)> {
    let lay = Layout {
        first: lay[0],
        rho: lay[1],
        w_max: lay[2],
        trunc: lay[3],
        kappa: lay[4],
        grow: lay.get(5).copied().unwrap_or(1.0),
    };
    macro_rules! go {
        ($n:literal, $p:literal) => {{
            static R: ([f64; $p], [f64; $p]) = padded::<$n, $p>();
            let rule = Rule {
                x: &R.0,
                w: &R.1,
                n: $n,
            };
            integrate(Path::detected(), &rule, &lay, z, Some(grad), hess)
        }};
    }
    match n {
        6 => go!(6, 8),
        8 => go!(8, 8),
        10 => go!(10, 16),
        12 => go!(12, 16),
        14 => go!(14, 16),
        16 => go!(16, 16),
        18 => go!(18, 24),
        24 => go!(24, 24),
        32 => go!(32, 32),
        _ => go!(20, 24),
    }
}

/// d = 3 or 4 with a chosen kernel (see [`Path`]); sorted `z`, outputs in sorted order.
pub(crate) fn log_f_sorted_on(
    path: Path,
    z: &[f64],
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<f64> {
    integrate(path, &RULE, &LAYOUT, z, grad, hess).map(|r| r.0)
}
