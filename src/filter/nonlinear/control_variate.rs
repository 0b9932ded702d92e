//! Regression control variates for the sampled prediction ([`super::sampled`]): the second
//! moment of `a(x)` is estimated as `ḡ − βᵀ (h̄ − E h)`, where `h` are the fourth-degree
//! monomials of the state's principal coordinates `y` (their expectations are known exactly:
//! `E[y_i² y_j²] = H_ij + ω_i ω_j`, `E[y_i⁴]` likewise, every monomial with an index of odd
//! multiplicity 0 — the same moments the 19 deterministic points reproduce) and `β` the
//! weighted least-squares coefficients of `g = a aᵀ` on `h`. On the sphere the fourth-degree
//! monomials span the second-degree ones and the constant (`Σ y_i² = 1`), so the estimate is
//! exact for every `g` that is a polynomial of degree ≤ 4 in `y` — where the 19 points are —
//! and the sampling only has to integrate what is left: a near-polynomial model reaches a
//! tight tolerance with few points.

#![allow(clippy::needless_range_loop)] // small dense sums over parallel arrays

use super::rqmc::LogShift;

/// The most control features (the 35 fourth-degree monomials in 4 variables, one dropped).
pub(super) const MAX_FEATURES: usize = 34;

/// The fourth-degree monomials `y_a y_b y_c y_e` (`a ≤ b ≤ c ≤ e < d`, without `y_{d−1}⁴`)
/// and their exact expectations under a Bingham with `ω` and Hessian `hess` (row-major d×d).
pub(super) struct Features {
    index: [[usize; 4]; MAX_FEATURES],
    pub(super) mean: [f64; MAX_FEATURES],
    pub(super) n: usize,
}

impl Features {
    pub(super) fn new(d: usize, omega: &[f64], hess: &[f64]) -> Self {
        let mut f = Features {
            index: [[0; 4]; MAX_FEATURES],
            mean: [0.0; MAX_FEATURES],
            n: 0,
        };
        for a in 0..d {
            for b in a..d {
                for c in b..d {
                    for e in c..d {
                        if a == d - 1 {
                            continue; // y_{d−1}⁴: fixed by the others on the sphere
                        }
                        let q = [a, b, c, e];
                        // Even multiplicity of every index: (i,i,j,j) or (i,i,i,i).
                        let mean = if a == b && c == e {
                            hess[a * d + c] + omega[a] * omega[c]
                        } else {
                            0.0
                        };
                        f.index[f.n] = q;
                        f.mean[f.n] = mean;
                        f.n += 1;
                    }
                }
            }
        }
        if f.mean[..f.n].iter().any(|v| !v.is_finite()) {
            // The moments underflowed or overflowed (|z| beyond about 1e150): no control.
            f.n = 0;
        }
        f
    }

    /// The features at the principal coordinates `y`.
    pub(super) fn at(&self, y: &[f64], out: &mut [f64; MAX_FEATURES]) {
        for k in 0..self.n {
            let [a, b, c, e] = self.index[k];
            out[k] = y[a] * y[b] * y[c] * y[e];
        }
    }
}

/// Weighted sums of one replicate: `Σ w`, `Σ w h`, `Σ w g`, the weights `w = exp(lw)` held
/// relative to the largest `lw` seen.
#[derive(Clone, Copy)]
pub(super) struct ReplicateSums {
    shift: LogShift,
    sw: f64,
    sh: [f64; MAX_FEATURES],
    sg: [f64; 10],
}

impl ReplicateSums {
    pub(super) fn new() -> Self {
        ReplicateSums {
            shift: LogShift::new(),
            sw: 0.0,
            sh: [0.0; MAX_FEATURES],
            sg: [0.0; 10],
        }
    }

    pub(super) fn add(&mut self, lw: f64, h: &[f64; MAX_FEATURES], g: &[f64; 10]) {
        let (rescale, w) = self.shift.admit(lw);
        if let Some(s) = rescale {
            self.sw *= s;
            self.sh.iter_mut().for_each(|v| *v *= s);
            self.sg.iter_mut().for_each(|v| *v *= s);
        }
        self.sw += w;
        for (acc, v) in self.sh.iter_mut().zip(h) {
            *acc += w * v;
        }
        for (acc, v) in self.sg.iter_mut().zip(g) {
            *acc += w * v;
        }
    }

    /// The adjusted estimate `ḡ − βᵀ (h̄ − E h)` (first `ng` entries).
    pub(super) fn adjusted(&self, beta: &Beta, f: &Features, ng: usize) -> [f64; 10] {
        core::array::from_fn(|k| {
            if k >= ng {
                return 0.0;
            }
            let mut v = self.sg[k] / self.sw;
            for j in 0..f.n {
                v -= beta.0[j][k] * (self.sh[j] / self.sw - f.mean[j]);
            }
            v
        })
    }
}

/// The regression coefficients `β` (features × values).
pub(super) struct Beta(pub(super) [[f64; 10]; MAX_FEATURES]);

/// The pooled cross sums `Σ w h hᵀ`, `Σ w h gᵀ` (with `Σ w`, `Σ w²`, `Σ w h`, `Σ w g`) for the
/// regression, over every replicate, relative to one running maximum of `lw`.
pub(super) struct PooledSums {
    shift: LogShift,
    sw: f64,
    sw2: f64,
    n: usize,
    sh: [f64; MAX_FEATURES],
    sg: [f64; 10],
    shh: [[f64; MAX_FEATURES]; MAX_FEATURES],
    shg: [[f64; 10]; MAX_FEATURES],
}

impl PooledSums {
    pub(super) fn new() -> Self {
        PooledSums {
            shift: LogShift::new(),
            sw: 0.0,
            sw2: 0.0,
            n: 0,
            sh: [0.0; MAX_FEATURES],
            sg: [0.0; 10],
            shh: [[0.0; MAX_FEATURES]; MAX_FEATURES],
            shg: [[0.0; 10]; MAX_FEATURES],
        }
    }

    pub(super) fn add(&mut self, lw: f64, h: &[f64; MAX_FEATURES], nh: usize, g: &[f64; 10]) {
        let (rescale, w) = self.shift.admit(lw);
        if let Some(s) = rescale {
            self.sw *= s;
            self.sw2 *= s * s;
            self.sh.iter_mut().for_each(|v| *v *= s);
            self.sg.iter_mut().for_each(|v| *v *= s);
            for r in self.shh.iter_mut() {
                r.iter_mut().for_each(|v| *v *= s);
            }
            for r in self.shg.iter_mut() {
                r.iter_mut().for_each(|v| *v *= s);
            }
        }
        self.sw += w;
        self.sw2 += w * w;
        self.n += 1;
        for (acc, v) in self.sg.iter_mut().zip(g) {
            *acc += w * v;
        }
        for j in 0..nh {
            let wh = w * h[j];
            self.sh[j] += wh;
            for k in j..nh {
                self.shh[j][k] += wh * h[k];
            }
            for (acc, v) in self.shg[j].iter_mut().zip(g) {
                *acc += wh * v;
            }
        }
    }

    /// The effective sample share `(Σ w)² / (n Σ w²)`.
    pub(super) fn share(&self) -> f64 {
        if self.n == 0 || self.sw2 <= 0.0 {
            return 0.0;
        }
        (self.sw * self.sw / (self.n as f64 * self.sw2)).min(1.0) // ≤ 1 by Cauchy–Schwarz
    }

    /// The weighted least-squares coefficients of `g` (first `ng`) on the features (scaled to
    /// unit variance, a tiny ridge for the collinear ones), `g ≈ ḡ + βᵀ (h − h̄)`.
    pub(super) fn coefficients(&self, nh: usize, ng: usize) -> Beta {
        let mut beta = Beta([[0.0; 10]; MAX_FEATURES]);
        let hm: [f64; MAX_FEATURES] = core::array::from_fn(|j| self.sh[j] / self.sw);
        let gm: [f64; 10] = core::array::from_fn(|k| self.sg[k] / self.sw);
        let cov = |i: usize, j: usize| {
            let (i, j) = if i <= j { (i, j) } else { (j, i) };
            self.shh[i][j] / self.sw - hm[i] * hm[j]
        };
        let sd: [f64; MAX_FEATURES] = core::array::from_fn(|j| {
            let v = if j < nh { cov(j, j) } else { 0.0 };
            if v > 0.0 {
                v.sqrt()
            } else {
                0.0
            }
        });
        let mut a = [0.0; MAX_FEATURES * MAX_FEATURES];
        let mut b = [0.0; MAX_FEATURES];
        for k in 0..ng {
            for i in 0..nh {
                for j in 0..nh {
                    a[i * nh + j] = if sd[i] > 0.0 && sd[j] > 0.0 {
                        cov(i, j) / (sd[i] * sd[j])
                    } else if i == j {
                        1.0
                    } else {
                        0.0
                    };
                }
                a[i * nh + i] += 1e-9;
                b[i] = if sd[i] > 0.0 {
                    (self.shg[i][k] / self.sw - hm[i] * gm[k]) / sd[i]
                } else {
                    0.0
                };
            }
            if crate::linalg::cholesky_solve(nh, &mut a[..nh * nh], &mut b[..nh]) {
                for j in 0..nh {
                    beta.0[j][k] = if sd[j] > 0.0 { b[j] / sd[j] } else { 0.0 };
                }
            }
        }
        beta
    }
}
