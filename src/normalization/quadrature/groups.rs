//! The two coordinate groups of the integrand (a single axis or a circle, [`Group`]), their
//! exact power-of-two scalings in one half ([`Scaling`]) and their values and moment factors at
//! a batch of nodes.

use crate::special::lanes::{self, Arith, Span, F};
use crate::special::pow2_floor;

/// One group of coordinates: a single axis or a circle.
#[derive(Clone, Copy, Debug)]
pub(super) enum Group {
    /// One coordinate with concentration `z ≤ 0`.
    Single { z: f64 },
    /// Two coordinates `z_lo ≤ z_hi ≤ 0`; `beta = (z_hi − z_lo)/2`.
    Circle { zhi: f64, beta: f64 },
}

/// A group's scaled value and second moment factors at radius² `r` (see [`Scaling`]).
#[derive(Clone, Copy, Default)]
pub(super) struct GroupEval {
    /// `C·g` (near position: `C·√r·g`)
    pub(super) g: f64,
}

/// A group's scaled value and moment factors at a batch of `L` radii² (see [`Scaling`]).
#[derive(Clone, Copy)]
pub(super) struct GroupLanes<const L: usize> {
    /// `C·g` (near position: `C·√r·g`)
    pub(super) g: F<L>,
    /// second moments `D_k·r·E[x_k²]·g` (times the same factor as `g`) of the group's
    /// coordinates (lo, hi)
    pub(super) m: [F<L>; 2],
    /// fourth moments (lo lo, lo hi, hi hi), each times `D_k D_l` and the factor of `g`
    pub(super) q: [F<L>; 3],
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
pub(super) struct Scaling {
    pub(super) c: f64,
    pub(super) inv_r: f64,
    pub(super) wide: bool,
    /// `D` of the group's coordinates (lo, hi)
    pub(super) d: [f64; 2],
    pub(super) near: bool,
}

impl Group {
    pub(super) fn size(&self) -> usize {
        match self {
            Group::Single { .. } => 1,
            Group::Circle { .. } => 2,
        }
    }

    /// Rate of the exponential factor (`|z|` of the exponent), ≥ 0.
    pub(super) fn rate(&self) -> f64 {
        match *self {
            Group::Single { z } => -z,
            Group::Circle { zhi, .. } => -zhi,
        }
    }

    pub(super) fn beta(&self) -> f64 {
        match *self {
            Group::Single { .. } => 0.0,
            Group::Circle { beta, .. } => beta,
        }
    }

    /// The group's scaling in a half where its largest radius² is `r_max` (`≤ 1`).
    pub(super) fn scaling(&self, r_max: f64, near: bool) -> Scaling {
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
    pub(super) fn span(&self, ra: f64, rb: f64) -> Span {
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
    pub(super) fn eval_far(&self, sc: &Scaling, r: f64, root: f64) -> GroupEval {
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
    pub(super) fn eval_lanes<
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

/// The `D` factors of the d coordinates (group 1's, then group 2's).
pub(super) fn d_factors(g1: &Group, sc1: &Scaling, sc2: &Scaling) -> [f64; 4] {
    if g1.size() == 1 {
        [sc1.d[0], sc2.d[0], sc2.d[1], 1.0]
    } else {
        [sc1.d[0], sc1.d[1], sc2.d[0], sc2.d[1]]
    }
}
