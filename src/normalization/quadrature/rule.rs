//! The composite rule of the quadrature: the Gauss–Legendre nodes of a panel ([`Rule`]), the
//! panel layout ([`Layout`], the production [`LAYOUT`]) and the panels of one half
//! ([`Panels`]).

use crate::normalization::gauss::gauss_legendre_unit;

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
    pub(super) x: &'static [f64],
    pub(super) w: &'static [f64],
    /// the rule's order (nodes per panel without the padding)
    pub(super) n: usize,
}

/// The `N`-point rule padded to `P` nodes (`P ≥ N` a multiple of 8; padding: node ½, weight 0).
pub(super) const fn padded<const N: usize, const P: usize>() -> ([f64; P], [f64; P]) {
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
pub(super) const N: usize = 20;
static RULE_NODES: ([f64; 24], [f64; 24]) = padded::<N, 24>();
pub(super) static RULE: Rule = Rule {
    x: &RULE_NODES.0,
    w: &RULE_NODES.1,
    n: N,
};
/// The production layout, chosen by measurement against the fine rule
/// ([`log_f_sorted_fine`](super::log_f_sorted_fine);
/// `log_f_sorted_tuned` runs other layouts): over 40 000 random z (d = 3, 4; |z_i| from 1e-3 to
/// 1e6, uniform in [−1e6, 0], ties, zeros) max |Δ log F| 3.6e-15, relative Δω 1.3e-15, ΔH
/// 7.8e-15 (relative to `√(H_ii H_jj)`), 58.6 nodes on average for d = 4 and 42.6 for d = 3 (the
/// layout before: 82 and 76 nodes, Δω 5.0e-15, ΔH 2.3e-13); over 30 000 z with |z_i| up to
/// 1e306, relative Δω 1.8e-15. The grading ratio starts at 3 and grows by 1.4 per panel: the
/// Bessel factor's departure from its asymptote, the part that limits a panel's ratio, falls
/// off like `(s_min/t)²`. Neighbouring layouts pass too (first 2–3, rho 2.5–3.5, grow 1.2–1.6);
/// ratios from 4 up, a first breakpoint beyond 3 scales, or panels wider than 5 Gaussian
/// scales (when the grading starts far below them, `FLOOR`) lose accuracy (up to 1e-13).
pub(super) const LAYOUT: Layout = Layout {
    first: 2.5,
    rho: 3.0,
    w_max: 0.71,
    trunc: 40.0,
    kappa: 4.0,
    grow: 1.4,
};
/// Most breakpoints a half can need.
const MAX_BREAKS: usize = 200;

/// The panels `[b_i, b_{i+1}]` of one half, `0 = b0 < b1 < … = t_max`: the first breakpoint
/// at `first·s_min` (the smallest feature scale), then graded geometrically by `rho`, with
/// widths capped by `w_max` and by `kappa` Gaussian scales; at most `MAX_BREAKS` breakpoints.
#[derive(Clone, Copy, Debug)]
pub(super) struct Panels {
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
    pub(super) fn new(lay: &Layout, t_max: f64, s_min: f64, gauss: f64) -> Self {
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
