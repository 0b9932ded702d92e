//! Randomized quasi-Monte Carlo (RQMC) integration against a Bingham distribution: the error
//! estimate and the refinement of the nonlinear steps ([`super::sampled`]).
//!
//! Points: the first `n` points of a Sobol sequence (32-bit, Gray-code order, Joe & Kuo's
//! direction numbers for the first three dimensions), in [`REPLICATES`] copies, each XORed with
//! its own random digital shift (a fixed seed: results are reproducible). A shifted Sobol net is
//! uniform on the unit cube, so each replicate's estimate is unbiased (up to the ratio bias of
//! self-normalization, `O(1/n)`), and the replicates are independent: their spread is an honest
//! standard error of the pooled estimate, whatever the integrand.
//!
//! The cube is mapped to the sphere area-preservingly (Shoemake's map for d = 4, an angle for
//! d = 2) and from there to the **angular central Gaussian** (ACG) envelope of the Bingham
//! distribution `Bingham(M, Z)` (Kent, Ganeiber & Mardia 2013): `x = M y / ‖·‖`,
//! `y = Ω^{−1/2} u / ‖Ω^{−1/2} u‖` with `u` uniform, `Ω = I − 2Z/b`, `Σ_i 1/(b − 2z_i) = 1`.
//! The envelope's density with respect to the uniform measure is `∝ (yᵀ Ω y)^{−d/2}`; it has the
//! Bingham's principal axes and scales with heavier (polynomial) tails, so the ratio of a
//! Bingham-like target to it stays bounded: importance weights that cannot blow up.

#![allow(clippy::needless_range_loop)] // small dense sums over parallel arrays

use crate::error::{Error, Result};
use crate::filter::types::{Mat, Vect};

/// Independent randomizations of the point set (the error estimate's degrees of freedom + 1).
pub(crate) const REPLICATES: usize = 16;

/// The 32-bit Sobol sequence in three dimensions (Gray-code order).
pub(super) struct Sobol {
    v: [[u32; 32]; 3],
    x: [u32; 3],
    index: u32,
}

impl Sobol {
    pub(super) fn new() -> Self {
        let mut v = [[0u32; 32]; 3];
        for (k, e) in v[0].iter_mut().enumerate() {
            *e = 1u32 << (31 - k);
        }
        // Joe & Kuo: dimension 2 from x + 1 (s = 1, m = 1), dimension 3 from x² + x + 1
        // (s = 2, a = 1, m = 1, 3); m_k = ⊕_j a_j 2^j m_{k−j} ⊕ 2^s m_{k−s} ⊕ m_{k−s}.
        let polys: [(usize, u32, [u32; 2]); 2] = [(1, 0, [1, 0]), (2, 1, [1, 3])];
        for (dim, &(s, a, m0)) in polys.iter().enumerate() {
            let mut m = [0u32; 32];
            m[..s].copy_from_slice(&m0[..s]);
            for k in s..32 {
                let mut val = m[k - s] ^ (m[k - s] << s);
                for j in 1..s {
                    if (a >> (s - 1 - j)) & 1 == 1 {
                        val ^= m[k - j] << j;
                    }
                }
                m[k] = val;
            }
            for k in 0..32 {
                v[dim + 1][k] = m[k] << (31 - k);
            }
        }
        Sobol {
            v,
            x: [0; 3],
            index: 0,
        }
    }

    /// The next point's integer coordinates.
    pub(super) fn next_bits(&mut self) -> [u32; 3] {
        let out = self.x;
        let c = (!self.index).trailing_zeros() as usize;
        for j in 0..3 {
            self.x[j] ^= self.v[j][c.min(31)];
        }
        self.index = self.index.wrapping_add(1);
        out
    }
}

/// The replicates' digital shifts (SplitMix64 from a fixed seed: reproducible results).
pub(super) fn shifts() -> [[u32; 3]; REPLICATES] {
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (z ^ (z >> 31)) as u32
    };
    let mut out = [[0u32; 3]; REPLICATES];
    for r in out.iter_mut() {
        for e in r.iter_mut() {
            *e = next();
        }
    }
    out
}

fn unit_interval(bits: u32) -> f64 {
    (bits as f64 + 0.5) * (1.0 / 4_294_967_296.0)
}

/// The ACG envelope of a Bingham distribution, as a map from the cube to the sphere with the
/// log of its density (up to a constant) at the point.
pub(super) struct Acg<const D: usize> {
    m: Mat<D>,
    omega: [f64; D],
    scale: [f64; D],
}

impl<const D: usize> Acg<D> {
    /// The envelope of `Bingham(m, z)` (`z` ascending, `z[D−1] = 0`, finite).
    pub(super) fn new(m: &Mat<D>, z: &Vect<D>) -> Result<Self> {
        if D != 2 && D != 4 {
            return Err(Error::InvalidDimension(format!(
                "sampled nonlinear steps exist for d = 2 and 4, not {D}"
            )));
        }
        let lambda: [f64; D] = core::array::from_fn(|i| (-z[i]).clamp(0.0, 1e300));
        // h(b) = Σ 1/(b + 2λ_i) − 1 is decreasing on (0, D], h(0+) = +∞, h(D) ≤ 0.
        let h = |b: f64| lambda.iter().map(|l| 1.0 / (b + 2.0 * l)).sum::<f64>() - 1.0;
        let (mut lo, mut hi) = (1e-300f64.ln(), (D as f64).ln());
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if h(mid.exp()) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let b = hi.exp();
        let omega: [f64; D] = core::array::from_fn(|i| 1.0 + 2.0 * lambda[i] / b);
        let scale: [f64; D] = core::array::from_fn(|i| 1.0 / omega[i].sqrt());
        Ok(Acg {
            m: *m,
            omega,
            scale,
        })
    }

    /// The point for the cube coordinates `bits` (uniform bits, shifted), its principal
    /// coordinates `y`, and `log` of the envelope's density there (up to a constant).
    pub(super) fn point(&self, bits: [u32; 3], x: &mut Vect<D>, y: &mut Vect<D>) -> f64 {
        let mut u = [0.0; D];
        if D == 4 {
            let (u1, u2, u3) = (
                unit_interval(bits[0]),
                unit_interval(bits[1]),
                unit_interval(bits[2]),
            );
            let (r1, r2) = ((1.0 - u1).sqrt(), u1.sqrt());
            let (s1, c1) = (std::f64::consts::TAU * u2).sin_cos();
            let (s2, c2) = (std::f64::consts::TAU * u3).sin_cos();
            u[0] = r1 * s1;
            u[1] = r1 * c1;
            u[2] = r2 * s2;
            u[3] = r2 * c2;
        } else {
            let (s, c) = (std::f64::consts::PI * unit_interval(bits[0])).sin_cos();
            u[0] = c;
            u[1] = s;
        }
        // The largest scaled component sets the norm's scale (no underflow for huge Ω).
        let mut big = 0.0f64;
        for i in 0..D {
            u[i] *= self.scale[i];
            big = big.max(u[i].abs());
        }
        let mut n2 = 0.0;
        for v in u.iter() {
            n2 += (v / big) * (v / big);
        }
        let n = big * n2.sqrt();
        let mut q = 0.0;
        for i in 0..D {
            y[i] = u[i] / n;
            q += self.omega[i] * y[i] * y[i];
        }
        *x = self.m * *y;
        -(D as f64) * 0.5 * q.ln()
    }
}

/// The running largest log-weight of a weighted sum: weights `w = exp(lw)` are held relative
/// to it, `exp(lw − top)` ≤ 1, so that neither the weights nor the sums overflow; when a larger
/// `lw` arrives, the sums held so far are multiplied by `exp(top_old − top_new)`.
#[derive(Clone, Copy)]
pub(super) struct LogShift {
    top: f64,
}

impl LogShift {
    pub(super) fn new() -> Self {
        LogShift {
            top: f64::NEG_INFINITY,
        }
    }

    /// Admits the log-weight `lw`: returns the factor by which the sums held so far must be
    /// multiplied (`Some` when `lw` is a new maximum: 0 before the first value) and the
    /// relative weight `exp(lw − top)` of the new value.
    pub(super) fn admit(&mut self, lw: f64) -> (Option<f64>, f64) {
        let mut rescale = None;
        if lw > self.top {
            rescale = Some(if self.top == f64::NEG_INFINITY {
                0.0
            } else {
                (self.top - lw).exp()
            });
            self.top = lw;
        }
        (rescale, (lw - self.top).exp())
    }
}

/// Running sums of weighted values `Σ w g` and `Σ w` with `w = exp(lw)` held relative to the
/// largest `lw` seen ([`LogShift`]), so that neither overflows.
#[derive(Clone, Copy)]
pub(super) struct WeightedSums<const N: usize> {
    shift: LogShift,
    sw: f64,
    sw2: f64,
    swg: [f64; N],
    n: usize,
}

impl<const N: usize> WeightedSums<N> {
    pub(super) fn new() -> Self {
        WeightedSums {
            shift: LogShift::new(),
            sw: 0.0,
            sw2: 0.0,
            swg: [0.0; N],
            n: 0,
        }
    }

    pub(super) fn add(&mut self, lw: f64, g: &[f64; N]) {
        let (rescale, w) = self.shift.admit(lw);
        if let Some(s) = rescale {
            self.sw *= s;
            self.sw2 *= s * s;
            for v in self.swg.iter_mut() {
                *v *= s;
            }
        }
        self.sw += w;
        self.sw2 += w * w;
        for (acc, v) in self.swg.iter_mut().zip(g) {
            *acc += w * v;
        }
        self.n += 1;
    }

    /// The weighted mean `Σ w g / Σ w`.
    pub(super) fn mean(&self) -> [f64; N] {
        core::array::from_fn(|k| self.swg[k] / self.sw)
    }

    /// These sums and `other`'s pooled (same weight function).
    pub(super) fn pooled(&self, other: &Self) -> Self {
        let top = self.shift.top.max(other.shift.top);
        let (a, b) = (
            if self.n == 0 {
                0.0
            } else {
                (self.shift.top - top).exp()
            },
            if other.n == 0 {
                0.0
            } else {
                (other.shift.top - top).exp()
            },
        );
        WeightedSums {
            shift: LogShift { top },
            sw: a * self.sw + b * other.sw,
            sw2: a * a * self.sw2 + b * b * other.sw2,
            swg: core::array::from_fn(|k| a * self.swg[k] + b * other.swg[k]),
            n: self.n + other.n,
        }
    }

    /// The effective sample share `(Σ w)² / (n Σ w²)` (1 for equal weights).
    pub(super) fn share(&self) -> f64 {
        if self.n == 0 || self.sw2 <= 0.0 {
            return 0.0;
        }
        (self.sw * self.sw / (self.n as f64 * self.sw2)).min(1.0) // ≤ 1 by Cauchy–Schwarz
    }
}

/// The mean and standard error over the replicates of per-replicate estimates `e[r][k]`.
pub(super) fn mean_and_error<const N: usize>(e: &[[f64; N]; REPLICATES]) -> ([f64; N], [f64; N]) {
    let r = REPLICATES as f64;
    let mean: [f64; N] = core::array::from_fn(|k| e.iter().map(|v| v[k]).sum::<f64>() / r);
    let se: [f64; N] = core::array::from_fn(|k| {
        let ss: f64 = e.iter().map(|v| (v[k] - mean[k]).powi(2)).sum();
        (ss / (r - 1.0) / r).sqrt()
    });
    (mean, se)
}

/// Index of the symmetric-matrix entry `(i, j)`, `i ≤ j`, in the packed order used by the
/// sampled estimates (row by row of the upper triangle).
pub(super) fn packed<const D: usize>(i: usize, j: usize) -> usize {
    let (i, j) = if i <= j { (i, j) } else { (j, i) };
    i * D - i * (i + 1) / 2 + j
}

/// The packed upper triangle of `v vᵀ` (length `D(D+1)/2`, the rest of `out` zero).
pub(super) fn outer_packed<const D: usize>(v: &Vect<D>, out: &mut [f64; 10]) {
    out.fill(0.0);
    for i in 0..D {
        for j in i..D {
            out[packed::<D>(i, j)] = v[i] * v[j];
        }
    }
}

/// The symmetric matrix from its packed upper triangle.
pub(super) fn unpack<const D: usize>(p: &[f64; 10]) -> Mat<D> {
    Mat::<D>::from_fn(|i, j| p[packed::<D>(i, j)])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sobol_first_points_match_the_published_sequence() {
        // Joe & Kuo's new-joe-kuo-6.21201 first points, dimensions 1–3.
        let mut s = Sobol::new();
        let want = [
            [0.0, 0.0, 0.0],
            [0.5, 0.5, 0.5],
            [0.75, 0.25, 0.25],
            [0.25, 0.75, 0.75],
            [0.375, 0.375, 0.625],
            [0.875, 0.875, 0.125],
        ];
        for w in want {
            let b = s.next_bits();
            for j in 0..3 {
                assert_eq!(b[j] as f64 / 4_294_967_296.0, w[j], "{b:?} vs {w:?}");
            }
        }
    }

    #[test]
    fn a_shifted_net_integrates_a_polynomial_on_the_sphere() {
        // E[y_0² y_2²] over the uniform S³ is 1/24; E[y_0⁴] = 1/8.
        let acg = Acg::<4>::new(&Mat::<4>::identity(), &Vect::<4>::zeros()).unwrap();
        let sh = shifts();
        let mut s = Sobol::new();
        let (mut a, mut b) = (0.0, 0.0);
        let n = 1 << 12;
        for _ in 0..n {
            let bits = s.next_bits();
            for r in sh.iter() {
                let mut x = Vect::<4>::zeros();
                let mut y = Vect::<4>::zeros();
                let lq = acg.point(
                    [bits[0] ^ r[0], bits[1] ^ r[1], bits[2] ^ r[2]],
                    &mut x,
                    &mut y,
                );
                assert!(lq.abs() < 1e-12);
                a += y[0] * y[0] * y[2] * y[2];
                b += y[0].powi(4);
            }
        }
        let n = (n * REPLICATES) as f64;
        assert!((a / n - 1.0 / 24.0).abs() < 1e-5, "{}", a / n);
        assert!((b / n - 1.0 / 8.0).abs() < 1e-5, "{}", b / n);
    }
}
