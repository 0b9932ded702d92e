//! The kernel of the quadrature: one half of the integral (the panels on one side of the
//! integrand's peak) for two coordinate groups, evaluated a batch of lanes at a time, with the
//! lane sums of `F`, ω and (on request) the fourth moments. Generic over the arithmetic
//! (plain or fused multiply-add) and the lane count; `simd` instantiates it per CPU path.

use super::groups::{Group, Scaling};
use super::rule::{Layout, Panels, Rule};
use crate::special::lanes::{Arith, F};

/// Accumulated scaled integrals: `f = ∫ g1 g2`, `m[k] = ∫ g·E[x_k²]`,
/// `q[k][l] = ∫ g·E[x_k² x_l²]`, each times the half's factors (`C1 C2`, and `D_k`, `D_k D_l`).
#[derive(Default)]
pub(super) struct Sums {
    pub(super) nodes: usize,
    pub(super) f: f64,
    pub(super) m: [f64; 4],
    pub(super) q: [[f64; 4]; 4],
}

/// [`Sums`] per lane, reduced at the end of a half.
pub(super) struct LaneSums<const L: usize> {
    pub(super) f: F<L>,
    pub(super) m: [F<L>; 4],
    pub(super) q: [[F<L>; 4]; 4],
}

/// The smallest first breakpoint relative to `t_max`: the near group contributes at most
/// `O(t)` per unit `t` below its dominant region, so `[0, 1e-20·t_max]` holds at most about
/// `1e-20` of every integral and needs no grading (this caps the panel count when the
/// Bessel scale `1/√β` is far below `t_max`, e.g. `β = 1e300`, `t_max = 1/√2`).
const FLOOR: f64 = 1e-20;

/// The panels and both groups' scalings of one half (see [`half`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct HalfSetup {
    pub(super) panels: Panels,
    pub(super) sc1: Scaling,
    pub(super) sc2: Scaling,
}

pub(super) fn half_setup(lay: &Layout, g1: &Group, g2: &Group, near_first: bool) -> HalfSetup {
    let a = g1.rate();
    let (t_max, scales) = if near_first {
        let t_max = if a > 0.0 {
            (lay.trunc / a).sqrt().min(std::f64::consts::FRAC_1_SQRT_2)
        } else {
            std::f64::consts::FRAC_1_SQRT_2
        };
        (t_max, [a, g1.beta()])
    } else {
        // In the far half group 1's factor e^{(1−s²) z} grows away from s = 0 (no boundary
        // layer there); its Gaussian scale only caps the panel width (`kappa`). Grading from
        // s = 0 follows group 2's Bessel factor alone.
        (std::f64::consts::FRAC_1_SQRT_2, [0.0, g2.beta()])
    };
    let (sc1, sc2) = if near_first {
        (g1.scaling(t_max * t_max, true), g2.scaling(1.0, false))
    } else {
        (g1.scaling(1.0, false), g2.scaling(t_max * t_max, true))
    };
    let big = scales[0].max(scales[1]);
    let s_min = if big > 0.0 {
        (1.0 / big.sqrt()).max(FLOOR * t_max)
    } else {
        f64::INFINITY
    };
    let gauss = if a > 0.0 {
        1.0 / a.sqrt()
    } else {
        f64::INFINITY
    };
    HalfSetup {
        panels: Panels::new(lay, t_max, s_min, gauss),
        sc1,
        sc2,
    }
}

/// Integrates one half, `L` nodes at a time. `near_first`: the integration variable is √r of
/// group 1 (left half); otherwise √r of group 2 (right half). `N1` is group 1's size, `FOURTH`
/// asks for the fourth moments. Returns the scaled sums.
///
/// The batch kernel: every step below is the same operation on all lanes (the compiler emits
/// SIMD instructions for the instruction set of the function it is inlined into, see
/// [`half_on`]); the lane sums are reduced in lane order at the end, so the result does not
/// depend on anything but the input.
#[inline(always)]
pub(super) fn half<
    A: Arith,
    const L: usize,
    const L2: usize,
    const L4: usize,
    const N1: usize,
    const FOURTH: bool,
>(
    rule: &Rule,
    g1: &Group,
    g2: &Group,
    near_first: bool,
    setup: &HalfSetup,
) -> Sums {
    let zero = F::<L>::splat(0.0);
    let mut acc = LaneSums {
        f: zero,
        m: [zero; 4],
        q: [[zero; 4]; 4],
    };
    // The accumulators stay in memory (one load and store per batch and sum): left to itself
    // the optimizer vectorizes the gradient kernel across the sums instead of across the lanes
    // and spends ~60 shuffles per batch transposing the products (measured with callgrind on
    // z = (−1e6, −10, −1, 0): 15 100 → 13 300 instructions per call; values unchanged).
    std::hint::black_box(&mut acc);
    let (sc1, sc2) = (&setup.sc1, &setup.sc2);
    // the far group needs √r only if it is a single axis
    let far_root = if near_first { g2.size() == 1 } else { N1 == 1 };
    // the rule's nodes and weights, padded to whole batches of L
    let m = rule.n.div_ceil(L) * L;
    let (rx, rw) = (&rule.x[..m], &rule.w[..m]);
    let mut panels = 0;
    for (lo, hi) in setup.panels {
        panels += 1;
        let width = hi - lo;
        // The Bessel arguments of the panel's nodes (padding included) lie between those of
        // its first and last node, computed as in the batches below: if they share a piece of
        // the fits, or all take the asymptotic series, the batches skip the per-lane search.
        let (ta, tb) = (lo + width * rx[0], lo + width * rx[rule.n - 1]);
        let (ra, rb) = (ta * ta, tb * tb);
        let (oa, ob) = (1.0 - ra, 1.0 - rb);
        let (span1, span2) = if near_first {
            (g1.span(ra, rb), g2.span(oa, ob))
        } else {
            (g1.span(oa, ob), g2.span(ra, rb))
        };
        for (xs, ws) in rx.chunks_exact(L).zip(rw.chunks_exact(L)) {
            let mut t = zero;
            let mut w = zero;
            for l in 0..L {
                t.0[l] = lo + width * xs[l];
                // 2t dt, the 2t absorbed by the near group's √r
                w.0[l] = width * ws[l] * 2.0;
            }
            let t2 = t * t;
            let other = F::splat(1.0) - t2;
            let other_root = if far_root { other.sqrt() } else { other };
            let (r1, root1, r2, root2) = if near_first {
                (t2, t, other, other_root)
            } else {
                (other, other_root, t2, t)
            };
            let e1 = g1.eval_lanes::<A, L, L2, L4, FOURTH>(sc1, r1, root1, span1);
            let e2 = g2.eval_lanes::<A, L, L2, L4, FOURTH>(sc2, r2, root2, span2);
            let wg1 = w * e1.g;
            let wg2 = w * e2.g;
            acc.f = A::madd(wg1, e2.g, acc.f);
            for i in 0..N1 {
                acc.m[i] = A::madd(e1.m[i], wg2, acc.m[i]);
            }
            for j in 0..2 {
                acc.m[N1 + j] = A::madd(wg1, e2.m[j], acc.m[N1 + j]);
            }
            if FOURTH {
                // within group 1
                acc.q[0][0] = A::madd(e1.q[0], wg2, acc.q[0][0]);
                if N1 == 2 {
                    acc.q[0][1] = A::madd(e1.q[1], wg2, acc.q[0][1]);
                    acc.q[1][1] = A::madd(e1.q[2], wg2, acc.q[1][1]);
                }
                // within group 2
                acc.q[N1][N1] = A::madd(wg1, e2.q[0], acc.q[N1][N1]);
                acc.q[N1][N1 + 1] = A::madd(wg1, e2.q[1], acc.q[N1][N1 + 1]);
                acc.q[N1 + 1][N1 + 1] = A::madd(wg1, e2.q[2], acc.q[N1 + 1][N1 + 1]);
                // across groups
                for i in 0..N1 {
                    let wm = w * e1.m[i];
                    for j in 0..2 {
                        acc.q[i][N1 + j] = A::madd(wm, e2.m[j], acc.q[i][N1 + j]);
                    }
                }
            }
        }
    }
    let mut sums = Sums {
        nodes: panels * rule.n,
        f: acc.f.sum(),
        ..Sums::default()
    };
    for (s, a) in sums.m.iter_mut().zip(&acc.m).take(N1 + 2) {
        *s = a.sum();
    }
    if FOURTH {
        for (i, (srow, arow)) in sums.q.iter_mut().zip(&acc.q).enumerate().take(N1 + 2) {
            for (s, a) in srow.iter_mut().zip(arow).skip(i).take(N1 + 2 - i) {
                *s = a.sum();
            }
        }
    }
    sums
}
