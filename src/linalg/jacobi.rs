//! Symmetric eigendecomposition by the cyclic Jacobi method. It returns eigenvectors orthonormal
//! to machine precision and eigenvalues with small relative error, which the moment-matching and
//! the Bayes update need (the library's general-purpose QR-based solver left reconstruction
//! errors of ~1e-7 on close eigenvalues; Jacobi also keeps the high *relative* accuracy of small
//! eigenvalues of graded matrices).
//!
//! [`jacobi_in_place`] dispatches on the size: n = 2 is one rotation in closed form, n = 3 and
//! n = 4 (the filter's sizes) run a fully unrolled Jacobi on local arrays ([`jacobi_small`]),
//! larger n the general cyclic Jacobi ([`jacobi_general`]).
#![allow(clippy::needless_range_loop)]

use nalgebra::{DMatrix, DVector};

/// Eigenvalues and eigenvectors (as columns) of the symmetric matrix `a` (only its upper
/// triangle is read). Not sorted.
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) fn jacobi_eigen(a: &DMatrix<f64>) -> (DVector<f64>, DMatrix<f64>) {
    let n = a.nrows();
    // row-major scratch; `a` is symmetric so the layout does not matter for reading
    let mut m: Vec<f64> = a.transpose().as_slice().to_vec();
    let mut v = vec![0.0; n * n];
    let mut d = vec![0.0; n];
    let mut work = vec![0.0; 2 * n];
    jacobi_in_place(n, &mut m, &mut v, &mut d, &mut work);
    (DVector::from_vec(d), DMatrix::from_row_slice(n, n, &v))
}

/// Allocation-free Jacobi eigendecomposition on caller buffers: `m` (n×n row-major, upper
/// triangle read, destroyed), `v` (n×n row-major, receives the eigenvectors as columns), `d`
/// (n, the eigenvalues, not sorted), `work` (2n scratch; only n ≥ 5 uses it).
///
/// n = 2 is one rotation in closed form (the general path's rotation by the short-chain
/// formulas of n = 3, 4: the same eigenpairs within 2 ulps); n = 3, 4 go to `jacobi_small`, n ≥ 5 to [`jacobi_general`]. The paths have the same
/// accuracy: orthogonality and reconstruction to a few ulps of ‖A‖, eigenvalues of graded
/// matrices (`A = D·H·D`, H well conditioned) to a few ulps relative.
///
/// Range: every finite input with Frobenius norm ≤ 2^1021 (≈ 4.5e307) gives finite output (the
/// rotations preserve the norm, and no squares of entries are formed outside the range where
/// they cannot overflow or underflow), down to subnormal entries. Deterministic: the same input
/// gives bit-identical output. NaN input gives NaN output (after at most 100 sweeps).
pub fn jacobi_in_place(n: usize, m: &mut [f64], v: &mut [f64], d: &mut [f64], work: &mut [f64]) {
    match n {
        2 => jacobi_2x2(m, v, d),
        3 => jacobi_small::<3>(m, v, d, sweep3),
        4 => jacobi_small::<4>(m, v, d, sweep4),
        _ => jacobi_general(n, m, v, d, work),
    }
}

/// Numerical Recipes' rotation that annihilates `apq` in the block `[[d_p, apq], [apq, d_q]]`,
/// `h = d_q − d_p`, `apq ≠ 0`: `(t, s, tau)` = (tan φ, sin φ, tan(φ/2)), |φ| ≤ π/4. Scale-free
/// (no squares of entries), so it works over the whole range.
#[inline(always)]
fn rotation_nr(apq: f64, h: f64) -> (f64, f64, f64) {
    let g = 100.0 * apq.abs();
    let t = if h.abs() + g == h.abs() {
        apq / h
    } else {
        let theta = 0.5 * h / apq;
        let t = 1.0 / (theta.abs() + (1.0 + theta * theta).sqrt());
        if theta < 0.0 {
            -t
        } else {
            t
        }
    };
    // s = t·c and tau = s/(1 + c) with c = 1/r, r = √(1 + t²), as t/r and t/(1 + r): two
    // independent divisions instead of a chain of three
    let r = (1.0 + t * t).sqrt();
    (t, t / r, t / (1.0 + r))
}

/// Rutishauser's form of the plane rotation `(g, h) → (c·g − s·h, s·g + c·h)`, with
/// `tau = s/(1 + c)`: the small-angle update is a correction to `g` and `h`, which keeps the
/// accumulated eigenvectors orthonormal to a few ulps.
#[inline(always)]
fn rot(g: f64, h: f64, s: f64, tau: f64) -> (f64, f64) {
    (g - s * (h + g * tau), h + s * (g - h * tau))
}

/// n = 2: one rotation, in closed form, by [`rotation`] (the short-chain form the unrolled
/// n = 3, 4 paths use; a d = 2 filter step is a chain of two of these). The result agrees with
/// [`jacobi_general`]'s single rotation to an ulp or two and has the accuracy of the other paths
/// (tested against the double-double reference).
fn jacobi_2x2(m: &[f64], v: &mut [f64], d: &mut [f64]) {
    let (a00, a01, a11) = (m[0], m[1], m[3]);
    v[..4].copy_from_slice(&[1.0, 0.0, 0.0, 1.0]);
    d[0] = a00;
    d[1] = a11;
    if a01 == 0.0 {
        return;
    }
    let (ht, s, tau) = rotation(a01, a11 - a00);
    d[0] = a00 - ht;
    d[1] = a11 + ht;
    // the rotation of the rows of v = I, in Rutishauser's form: (1, 0) and (0, 1)
    let c = 1.0 - s * tau;
    v[0] = c;
    v[1] = s;
    v[2] = -s;
    v[3] = c;
}

/// Taylor coefficients in `y = x²` of `tan φ / x` for the Jacobi angle `tan 2φ = 2x` (the
/// Catalan numbers with alternating signs). With those of `sin φ / x` and `tan(φ/2) / x` below
/// they are dyadic, hence exact; for |x| ≤ [`SERIES_X`] the first omitted terms are below 2^-59
/// relative (the series alternate, so that bounds the truncation).
const SERIES_T: [f64; 7] = [1.0, -1.0, 2.0, -5.0, 14.0, -42.0, 132.0];
/// Taylor coefficients in `y` of `sin φ / x` (see [`SERIES_T`]).
const SERIES_S: [f64; 7] = [
    1.0,
    -1.5,
    3.875,
    -11.6875,
    37.9609375,
    -128.76953125,
    449.4482421875,
];
/// Taylor coefficients in `y` of `tan(φ/2) / x` (see [`SERIES_T`]).
const SERIES_TAU: [f64; 7] = [
    0.5,
    -0.625,
    1.4375,
    -3.9765625,
    12.05078125,
    -38.5712890625,
    128.04638671875,
];

/// Largest |x| = |a_pq / (d_q − d_p)| for which [`rotation`] uses the series.
const SERIES_X: f64 = 1.0 / 32.0;

/// Below this |x| (2^-28) the series reduce to their first terms exactly in floating point
/// (`t = s = x`, `tau = x/2`); [`rotation`] skips their evaluation.
const TINY_X: f64 = 3.725_290_298_461_914e-9;

/// Degree-6 polynomial in `y` (Estrin's scheme: short dependency chain).
#[inline(always)]
fn series(c: &[f64; 7], y: f64, y2: f64, y4: f64) -> f64 {
    let p01 = c[0] + c[1] * y;
    let p23 = c[2] + c[3] * y;
    let p46 = (c[4] + c[5] * y) + y2 * c[6];
    (p01 + y2 * p23) + y4 * p46
}

/// The Jacobi rotation of [`rotation_nr`] computed with a shorter dependency chain (a 4×4
/// eigendecomposition is a chain of about ten of them): `(t·apq, s, tau)` for `apq ≠ 0`,
/// `h = d_q − d_p`. Three regimes, each accurate to an ulp or two:
/// - |x| ≤ 1/32, `x = apq/h`: the Taylor series of t, s, tau in x (one division, no square
///   root; the late sweeps, and graded matrices);
/// - otherwise, for 3.2e-145 ≤ |apq| ≤ 3.1e144 (2^±480, so that no square below can over- or
///   underflow): `r = √(h² + 4apq²)`, `w = |h| + r`, `m = √(2rw)`, then `t = 2a/w`, `s = 2a/m`,
///   `tau = 2a/(w + m)` with `a = apq·sign(h)` (half-angle formulas without cancellation; one
///   division fewer on the chain than [`rotation_nr`]);
/// - else [`rotation_nr`].
#[inline(always)]
fn rotation(apq: f64, h: f64) -> (f64, f64, f64) {
    let aa = apq.abs();
    let ha = h.abs();
    if aa <= SERIES_X * ha {
        if aa <= TINY_X * ha {
            // what `rotation_series` gives, without evaluating the series
            let x = apq / h;
            return (x * apq, x, 0.5 * x);
        }
        return rotation_series(apq, h);
    }
    if (3.2e-145..=3.1e144).contains(&aa) {
        // |h| < 32·|apq|, so h² < 1e292 and 4apq² > 4e-289
        let a2 = if h < 0.0 { -2.0 * apq } else { 2.0 * apq };
        let r = (h * h + a2 * a2).sqrt();
        let w = ha + r;
        let m = (2.0 * r * w).sqrt();
        return (a2 * apq / w, a2 / m, a2 / (w + m));
    }
    let (t, s, tau) = rotation_nr(apq, h);
    (t * apq, s, tau)
}

/// The series regime of [`rotation`], |apq| ≤ |h|/32.
#[inline(always)]
fn rotation_series(apq: f64, h: f64) -> (f64, f64, f64) {
    let x = apq / h;
    let y = x * x;
    let y2 = y * y;
    let y4 = y2 * y2;
    let t = x * series(&SERIES_T, y, y2, y4);
    (
        t * apq,
        x * series(&SERIES_S, y, y2, y4),
        x * series(&SERIES_TAU, y, y2, y4),
    )
}

/// Working state of [`jacobi_small`]: the strict upper triangle `a`, the eigenvectors as rows
/// `vt` (row j is column j of V), the diagonal `d`, and the sum `z` of the diagonal updates of
/// the current sweep.
struct Block<const N: usize> {
    a: [[f64; N]; N],
    vt: [[f64; N]; N],
    d: [f64; N],
    z: [f64; N],
}

impl<const N: usize> Block<N> {
    /// Entry (i, j), i ≠ j, of the symmetric matrix (stored in the upper triangle).
    #[inline(always)]
    fn get(&self, i: usize, j: usize) -> f64 {
        if i < j {
            self.a[i][j]
        } else {
            self.a[j][i]
        }
    }

    #[inline(always)]
    fn set(&mut self, i: usize, j: usize, x: f64) {
        if i < j {
            self.a[i][j] = x
        } else {
            self.a[j][i] = x
        }
    }
}

/// `a_pq` is negligible next to both `d_p` and `d_q` (Numerical Recipes' test: `100·|a_pq|`
/// below half an ulp of each), a relative perturbation below 2^-59 of each diagonal.
#[inline(always)]
fn negligible(apq: f64, dp: f64, dq: f64) -> bool {
    let g = 100.0 * apq.abs();
    dp.abs() + g == dp.abs() && dq.abs() + g == dq.abs()
}

/// The Jacobi rotation `(s, tau)` in the plane (P, Q) of [`jacobi_small`], with its diagonal
/// update done and `a_pq` set to zero; `None` if `a_pq` is negligible (it is set to zero).
#[inline(always)]
fn prepare<const N: usize, const P: usize, const Q: usize>(s: &mut Block<N>) -> Option<(f64, f64)> {
    let apq = s.a[P][Q];
    s.a[P][Q] = 0.0;
    if negligible(apq, s.d[P], s.d[Q]) {
        return None;
    }
    let h = s.d[Q] - s.d[P];
    let (ta, sn, tau) = rotation(apq, h);
    s.z[P] -= ta;
    s.z[Q] += ta;
    s.d[P] -= ta;
    s.d[Q] += ta;
    Some((sn, tau))
}

/// Applies the rotation `(s, tau)` in the plane (P, Q) to the off-diagonals.
#[inline(always)]
fn apply<const N: usize, const P: usize, const Q: usize>(s: &mut Block<N>, sn: f64, tau: f64) {
    for j in 0..N {
        if j != P && j != Q {
            let (x, y) = rot(s.get(P, j), s.get(Q, j), sn, tau);
            s.set(P, j, x);
            s.set(Q, j, y);
        }
    }
}

/// Applies the rotation `(s, tau)` in the plane (P, Q) to the eigenvectors.
#[inline(always)]
fn apply_v<const N: usize, const P: usize, const Q: usize>(s: &mut Block<N>, sn: f64, tau: f64) {
    let (vp, vq) = (s.vt[P], s.vt[Q]);
    for j in 0..N {
        (s.vt[P][j], s.vt[Q][j]) = rot(vp[j], vq[j], sn, tau);
    }
}

/// One Jacobi rotation in the plane (P, Q). Returns whether it rotated.
#[inline(always)]
fn rotate<const N: usize, const P: usize, const Q: usize>(s: &mut Block<N>) -> bool {
    let Some((sn, tau)) = prepare::<N, P, Q>(s) else {
        return false;
    };
    apply::<N, P, Q>(s, sn, tau);
    apply_v::<N, P, Q>(s, sn, tau);
    true
}

/// Two rotations in disjoint planes (P1, Q1), (P2, Q2): both are prepared before either is
/// applied, and the off-diagonals (the dependency chain to the next pair) are updated before
/// the eigenvectors; the same result as one rotation after the other.
#[inline(always)]
fn rotate_pair<const P1: usize, const Q1: usize, const P2: usize, const Q2: usize>(
    s: &mut Block<4>,
) -> bool {
    let r1 = prepare::<4, P1, Q1>(s);
    let r2 = prepare::<4, P2, Q2>(s);
    if r1.is_none() && r2.is_none() {
        return false;
    }
    // a negligible one is the identity
    let (s1, tau1) = r1.unwrap_or((0.0, 0.0));
    let (s2, tau2) = r2.unwrap_or((0.0, 0.0));
    apply::<4, P1, Q1>(s, s1, tau1);
    apply::<4, P2, Q2>(s, s2, tau2);
    apply_v::<4, P1, Q1>(s, s1, tau1);
    apply_v::<4, P2, Q2>(s, s2, tau2);
    true
}

/// The 3×3 sweep: row-cyclic order.
#[inline(always)]
fn sweep3(s: &mut Block<3>) -> bool {
    let r01 = rotate::<3, 0, 1>(s);
    let r02 = rotate::<3, 0, 2>(s);
    let r12 = rotate::<3, 1, 2>(s);
    r01 | r02 | r12
}

/// The 4×4 sweep: the cyclic order that pairs disjoint planes, ((0,1), (2,3)), ((0,2), (1,3)),
/// ((0,3), (1,2)); the two rotations of a pair are independent, so their computations overlap.
#[inline(always)]
fn sweep4(s: &mut Block<4>) -> bool {
    let r0 = rotate_pair::<0, 1, 2, 3>(s);
    let r1 = rotate_pair::<0, 2, 1, 3>(s);
    let r2 = rotate_pair::<0, 3, 1, 2>(s);
    r0 | r1 | r2
}

/// Relative size 2^-28 of the off-diagonals below which [`finish`] ends the iteration.
const FINISH: f64 = 3.725_290_298_461_914e-9;

/// Ends the iteration with first-order perturbation theory when every off-diagonal is tiny,
/// `|a_pq| ≤ ε·|d_q − d_p|` and `|a_pq| ≤ ε·√|d_p·d_q|` (or zero), ε = 2^-28: the next sweep
/// would rotate by `t = a_pq/(d_q − d_p)` (|t| ≤ ε, so `c = 1` in floating point) and change
/// `d_p` by `a_pq²/(d_p − d_q)`. The step applies all of these at once, `V ← V·(I + K)` with
/// `K_qp = −K_pq = a_pq/(d_p − d_q)`, and the diagonal updates. What it leaves out is of second
/// order: `I + K` is orthogonal up to O(ε²), and the off-diagonals left are O(ε²·√|d_p·d_q|),
/// a perturbation of relative size a few times 2^-56 in the sense of Demmel and Veselić (the
/// second condition makes that hold for graded matrices too), so eigenvalues keep their
/// relative accuracy. Otherwise (or when an entry is outside 1e±150, where the squares of the test
/// could under- or overflow) it returns false and changes nothing; `s.z` must be zero.
#[inline(always)]
fn finish<const N: usize>(s: &mut Block<N>, b: &mut [f64; N]) -> bool {
    let mut x = [[0.0f64; N]; N];
    for p in 0..N {
        for q in p + 1..N {
            let apq = s.a[p][q];
            if apq == 0.0 {
                continue;
            }
            let h = s.d[q] - s.d[p];
            let aa = apq.abs();
            let small = aa <= FINISH * h.abs()
                && (1e-150..=1e150).contains(&aa)
                && aa * aa <= FINISH * FINISH * s.d[p].abs() * s.d[q].abs();
            if !small {
                return false;
            }
            x[p][q] = apq / h;
        }
    }
    let vt = s.vt;
    for p in 0..N {
        for q in p + 1..N {
            let t = x[p][q];
            let ta = t * s.a[p][q];
            s.z[p] -= ta;
            s.z[q] += ta;
            for j in 0..N {
                s.vt[p][j] -= t * vt[q][j];
                s.vt[q][j] += t * vt[p][j];
            }
            s.a[p][q] = 0.0;
        }
    }
    for i in 0..N {
        b[i] += s.z[i];
    }
    s.d = *b;
    true
}

/// Sweep limit of [`jacobi_small`] (it typically ends after three or four).
const MAX_SWEEPS: usize = 100;

/// Cyclic Jacobi for n = 3, 4 on local arrays, fully unrolled (`sweep` is a fixed sequence of
/// [`rotate`] / [`rotate_pair`] calls, so every index is a compile-time constant and the state
/// stays in registers). The iteration of [`jacobi_general`] (diagonal updates accumulated per
/// sweep, negligible off-diagonals set to zero, Rutishauser's rotation updates) with changes
/// that shorten it: no thresholds (every non-negligible entry is rotated), the negligible test
/// from the first sweep on, the rotation parameters by [`rotation`], for n = 4 an order that
/// pairs independent rotations, and the end by [`finish`] as soon as the off-diagonals are
/// tiny, instead of one or two more sweeps of rotations by angles below 2^-28 and a last sweep
/// that finds everything negligible.
#[inline(always)]
fn jacobi_small<const N: usize>(
    m: &[f64],
    v: &mut [f64],
    d: &mut [f64],
    sweep: impl Fn(&mut Block<N>) -> bool,
) {
    let mut s = Block {
        a: [[0.0; N]; N],
        vt: [[0.0; N]; N],
        d: [0.0; N],
        z: [0.0; N],
    };
    for i in 0..N {
        for j in i + 1..N {
            s.a[i][j] = m[i * N + j];
        }
        s.vt[i][i] = 1.0;
        s.d[i] = m[i * N + i];
    }
    let mut b = s.d;
    for _ in 0..MAX_SWEEPS {
        s.z = [0.0; N];
        if finish(&mut s, &mut b) {
            break;
        }
        let rotated = sweep(&mut s);
        for i in 0..N {
            b[i] += s.z[i];
        }
        s.d = b;
        if !rotated {
            break;
        }
    }
    for i in 0..N {
        d[i] = s.d[i];
        for j in 0..N {
            v[i * N + j] = s.vt[j][i];
        }
    }
}

/// The general-n path of [`jacobi_in_place`] (used for n ≥ 5): cyclic Jacobi in row order,
/// Rutishauser's variant as in Numerical Recipes (thresholds in the first three sweeps,
/// negligible off-diagonals set to zero from the fifth sweep on, diagonal updates accumulated
/// per sweep). Same buffers as [`jacobi_in_place`]; `work` holds 2n scratch values.
pub fn jacobi_general(n: usize, m: &mut [f64], v: &mut [f64], d: &mut [f64], work: &mut [f64]) {
    let (b, z) = work.split_at_mut(n);
    for i in 0..n {
        for j in 0..n {
            v[i * n + j] = if i == j { 1.0 } else { 0.0 };
        }
        d[i] = m[i * n + i];
        b[i] = d[i];
        z[i] = 0.0;
    }
    for sweep in 0..100 {
        let mut sm = 0.0;
        for p in 0..n {
            for q in p + 1..n {
                sm += m[p * n + q].abs();
            }
        }
        if sm == 0.0 {
            break;
        }
        let tresh = if sweep < 3 {
            0.2 * sm / (n * n) as f64
        } else {
            0.0
        };
        for p in 0..n {
            for q in p + 1..n {
                let apq = m[p * n + q];
                let g = 100.0 * apq.abs();
                if sweep > 3 && d[p].abs() + g == d[p].abs() && d[q].abs() + g == d[q].abs() {
                    m[p * n + q] = 0.0;
                } else if apq.abs() > tresh {
                    let (t, s, tau) = rotation_nr(apq, d[q] - d[p]);
                    let h = t * apq;
                    z[p] -= h;
                    z[q] += h;
                    d[p] -= h;
                    d[q] += h;
                    m[p * n + q] = 0.0;
                    let rot = |m: &mut [f64], i: usize, k: usize| {
                        let g = m[i];
                        let h = m[k];
                        m[i] = g - s * (h + g * tau);
                        m[k] = h + s * (g - h * tau);
                    };
                    for j in 0..p {
                        rot(m, j * n + p, j * n + q);
                    }
                    for j in p + 1..q {
                        rot(m, p * n + j, j * n + q);
                    }
                    for j in q + 1..n {
                        rot(m, p * n + j, q * n + j);
                    }
                    for j in 0..n {
                        rot(v, j * n + p, j * n + q);
                    }
                }
            }
        }
        for i in 0..n {
            b[i] += z[i];
            d[i] = b[i];
            z[i] = 0.0;
        }
    }
}

#[cfg(test)]
mod tests;
