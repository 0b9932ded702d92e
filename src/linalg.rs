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
/// formulas of n = 3, 4: the same eigenpairs within 2 ulps); n = 3, 4 go to [`jacobi_small`], n ≥ 5 to [`jacobi_general`]. The paths have the same
/// accuracy: orthogonality and reconstruction to a few ulps of ‖A‖, eigenvalues of graded
/// matrices (`A = D·H·D`, H well conditioned) to a few ulps relative.
///
/// Range: every finite input with Frobenius norm ≤ 2^1021 (≈ 4.5e307) gives finite output (the
/// rotations preserve the norm, and no squares of entries are formed outside the range where
/// they cannot overflow or underflow), down to subnormal entries. Deterministic: the same input
/// gives bit-identical output. NaN input gives NaN output (after at most 100 sweeps).
pub(crate) fn jacobi_in_place(
    n: usize,
    m: &mut [f64],
    v: &mut [f64],
    d: &mut [f64],
    work: &mut [f64],
) {
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
pub(crate) fn jacobi_general(
    n: usize,
    m: &mut [f64],
    v: &mut [f64],
    d: &mut [f64],
    work: &mut [f64],
) {
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
mod tests {
    use super::*;

    // (its own copy: benches/eigen.rs includes this file outside the crate)
    fn xorshift(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    /// Random orthogonal n×n matrix.
    fn orthogonal(n: usize, r: &mut impl FnMut() -> f64) -> DMatrix<f64> {
        DMatrix::from_fn(n, n, |_, _| r()).qr().q()
    }

    /// `Q·diag(λ)·Qᵀ`, symmetrised.
    fn rotated(lambda: &[f64], r: &mut impl FnMut() -> f64) -> DMatrix<f64> {
        let n = lambda.len();
        let q = orthogonal(n, r);
        let a = &q * DMatrix::from_diagonal(&DVector::from_column_slice(lambda)) * q.transpose();
        (&a + a.transpose()) * 0.5
    }

    /// The signature of `jacobi_in_place` and `jacobi_general`.
    type Solver = fn(usize, &mut [f64], &mut [f64], &mut [f64], &mut [f64]);

    /// Eigenvalues (sorted) and eigenvectors (unsorted columns) by `solver`.
    fn solve(a: &DMatrix<f64>, solver: Solver) -> (Vec<f64>, DVector<f64>, DMatrix<f64>) {
        let n = a.nrows();
        let mut m: Vec<f64> = a.transpose().as_slice().to_vec();
        let (mut v, mut d, mut w) = (vec![0.0; n * n], vec![0.0; n], vec![0.0; 2 * n]);
        solver(n, &mut m, &mut v, &mut d, &mut w);
        let mut sorted = d.clone();
        sorted.sort_by(f64::total_cmp);
        (
            sorted,
            DVector::from_vec(d),
            DMatrix::from_row_slice(n, n, &v),
        )
    }

    /// Largest |VΛVᵀ − A|_ij / √(|a_ii·a_jj|) (the componentwise backward error that gives
    /// graded matrices relative accuracy) and largest |VᵀV − I|.
    fn graded_residual(a: &DMatrix<f64>, d: &DVector<f64>, v: &DMatrix<f64>) -> (f64, f64) {
        let n = a.nrows();
        let rec = v * DMatrix::from_diagonal(d) * v.transpose();
        let mut worst: f64 = 0.0;
        for i in 0..n {
            for j in 0..n {
                let scale = (a[(i, i)].abs() * a[(j, j)].abs()).sqrt();
                worst = worst.max((rec[(i, j)] - a[(i, j)]).abs() / scale);
            }
        }
        let ortho = (v.transpose() * v - DMatrix::identity(n, n)).amax();
        (worst, ortho)
    }

    /// Double-double numbers (about 106 bits) for an independent reference.
    #[derive(Clone, Copy, Debug)]
    struct Dd(f64, f64);

    impl Dd {
        fn two_sum(a: f64, b: f64) -> Dd {
            let s = a + b;
            let bb = s - a;
            Dd(s, (a - (s - bb)) + (b - bb))
        }
        fn norm(self) -> Dd {
            let s = self.0 + self.1;
            Dd(s, self.1 - (s - self.0))
        }
        fn add(self, o: Dd) -> Dd {
            let s = Dd::two_sum(self.0, o.0);
            let t = Dd::two_sum(self.1, o.1);
            let s = Dd(s.0, s.1 + t.0).norm();
            Dd(s.0, s.1 + t.1).norm()
        }
        fn neg(self) -> Dd {
            Dd(-self.0, -self.1)
        }
        fn sub(self, o: Dd) -> Dd {
            self.add(o.neg())
        }
        fn mul(self, o: Dd) -> Dd {
            let p = self.0 * o.0;
            let e = self.0.mul_add(o.0, -p);
            Dd(p, e + (self.0 * o.1 + self.1 * o.0)).norm()
        }
        fn div(self, o: Dd) -> Dd {
            let q1 = self.0 / o.0;
            let r = self.sub(o.mul(Dd(q1, 0.0)));
            let q2 = r.0 / o.0;
            let r = r.sub(o.mul(Dd(q2, 0.0)));
            let q3 = r.0 / o.0;
            Dd(q1, q2).norm().add(Dd(q3, 0.0))
        }
        fn sqrt(self) -> Dd {
            if self.0 <= 0.0 {
                return Dd(0.0, 0.0);
            }
            let s = Dd(self.0.sqrt(), 0.0);
            s.add(self.sub(s.mul(s)).div(s.add(s)))
        }
        fn abs(self) -> Dd {
            if self.0 < 0.0 {
                self.neg()
            } else {
                self
            }
        }
    }

    /// Eigenvalues (sorted) of `a` by cyclic Jacobi in double-double arithmetic (rotations
    /// as in `jacobi_general`, so graded matrices get relative accuracy ~1e-31).
    fn reference_eigenvalues(a: &DMatrix<f64>) -> Vec<f64> {
        let n = a.nrows();
        let mut m: Vec<Vec<Dd>> = (0..n)
            .map(|i| (0..n).map(|j| Dd(a[(i, j)], 0.0)).collect())
            .collect();
        let one = Dd(1.0, 0.0);
        for _ in 0..60 {
            let mut done = true;
            for p in 0..n {
                for q in p + 1..n {
                    let apq = m[p][q];
                    let scale = (m[p][p].0 * m[q][q].0).abs().sqrt();
                    if apq.0 == 0.0 || apq.0.abs() <= 1e-40 * scale {
                        continue;
                    }
                    done = false;
                    let theta = m[q][q].sub(m[p][p]).div(apq.add(apq));
                    let t = one.div(theta.abs().add(one.add(theta.mul(theta)).sqrt()));
                    let t = if theta.0 < 0.0 { t.neg() } else { t };
                    let c = one.div(one.add(t.mul(t)).sqrt());
                    let s = t.mul(c);
                    let ta = t.mul(apq);
                    m[p][p] = m[p][p].sub(ta);
                    m[q][q] = m[q][q].add(ta);
                    m[p][q] = Dd(0.0, 0.0);
                    m[q][p] = Dd(0.0, 0.0);
                    for j in 0..n {
                        if j != p && j != q {
                            let (g, h) = (m[j][p], m[j][q]);
                            let gp = c.mul(g).sub(s.mul(h));
                            let hp = s.mul(g).add(c.mul(h));
                            m[j][p] = gp;
                            m[p][j] = gp;
                            m[j][q] = hp;
                            m[q][j] = hp;
                        }
                    }
                }
            }
            if done {
                break;
            }
        }
        let mut d: Vec<f64> = (0..n).map(|i| m[i][i].0).collect();
        d.sort_by(f64::total_cmp);
        d
    }

    #[test]
    fn reconstructs_close_eigenvalues() {
        let mut worst: f64 = 0.0;
        let mut ortho: f64 = 0.0;
        let mut s: u64 = 88172645463325252;
        let mut r = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for n in [2usize, 3, 4, 7] {
            for _ in 0..300 {
                let g = DMatrix::from_fn(n, n, |_, _| r());
                let q = g.qr().q();
                let w = DVector::from_fn(n, |i, _| {
                    0.5 + 1e-3 * i as f64 + if i == 0 { -0.499 } else { 0.0 }
                });
                let a = &q * DMatrix::from_diagonal(&w) * q.transpose();
                let a = (&a + a.transpose()) * 0.5;
                let (vals, vecs) = jacobi_eigen(&a);
                let rec = &vecs * DMatrix::from_diagonal(&vals) * vecs.transpose();
                worst = worst.max((rec - &a).amax());
                ortho = ortho.max((vecs.transpose() * &vecs - DMatrix::identity(n, n)).amax());
            }
        }
        assert!(worst < 1e-15, "reconstruction {worst:e}");
        assert!(ortho < 4e-15, "orthogonality {ortho:e}");
    }

    /// n = 2 (closed form) against the general path over 600 decades of scale and 24 of
    /// off-diagonal size: the same eigenpairs, eigenvalues within 2 ulps of ‖A‖, eigenvectors
    /// within 2 ulps (the same rotation, formed by a shorter chain).
    #[test]
    fn two_by_two_agrees_with_the_general_path() {
        let mut r = xorshift(3);
        let mut cases = vec![
            [1.0, 0.0, 2.0],
            [1.0, 1e-300, 1.0],
            [2.0, 3.0, 2.0],
            [-1e12, 5.0, 0.0],
            [0.0, -0.0, -0.0],
            [1e300, 1e-300, -1e300],
            [5e-324, 5e-324, 0.0],
            [3.0, -2.0, 3.0],
        ];
        for _ in 0..2000 {
            let s = 10f64.powf(600.0 * r() - 300.0);
            let t = 10f64.powf(24.0 * r() - 12.0);
            cases.push([s * r(), s * t * r(), s * r()]);
        }
        for [a, b, c] in cases {
            let (mut v, mut d, mut w) = ([0.0; 4], [0.0; 2], [0.0; 4]);
            jacobi_in_place(2, &mut [a, b, b, c], &mut v, &mut d, &mut w);
            let (mut v2, mut d2) = ([0.0; 4], [0.0; 2]);
            jacobi_general(2, &mut [a, b, b, c], &mut v2, &mut d2, &mut w);
            // the same eigenpairs: sorted, eigenvectors up to sign (for a zero gap either
            // rotation by ±45° is the decomposition)
            let norm = a.abs().max(b.abs()).max(c.abs());
            let pairs = |v: [f64; 4], d: [f64; 2]| {
                let mut p = [(d[0], [v[0], v[2]]), (d[1], [v[1], v[3]])];
                p.sort_by(|x, y| x.0.total_cmp(&y.0));
                p
            };
            // (subnormal entries carry fewer bits: there the two chains may differ in the
            // eigenvectors by the entries' own relative precision, so only the eigenvalues are
            // compared, to a few subnormal steps)
            let subnormal = [a, b, c].iter().any(|x| *x != 0.0 && !x.is_normal());
            for ((l, x), (l2, x2)) in pairs(v, d).into_iter().zip(pairs(v2, d2)) {
                assert!(
                    (l - l2).abs() <= 2.0 * f64::EPSILON * norm + 4.0 * 5e-324,
                    "{a} {b} {c}: {d:?} {d2:?}"
                );
                if subnormal {
                    continue;
                }
                let sign = if x[0] * x2[0] + x[1] * x2[1] < 0.0 {
                    -1.0
                } else {
                    1.0
                };
                for k in 0..2 {
                    assert!(
                        (x[k] - sign * x2[k]).abs() <= 2.0 * f64::EPSILON,
                        "{a} {b} {c}: {v:?} {v2:?}"
                    );
                }
            }
        }
    }

    /// Rotated spectra with eigenvalues from 1e-12 to 1e12 relative (the filter's precisions
    /// and second moments): the eigenvalues agree with the extended-precision reference to a few
    /// ulps of ‖A‖ (all a rotated matrix determines), as the general path does.
    #[test]
    fn wide_range_matches_reference() {
        let mut r = xorshift(11);
        for n in [2usize, 3, 4] {
            let (mut worst, mut worst_general, mut worst_rec, mut worst_ortho) =
                (0.0f64, 0.0f64, 0.0f64, 0.0f64);
            for k in 0..600 {
                let lambda: Vec<f64> = (0..n)
                    .map(|i| match k % 3 {
                        // Bingham-like: 0, −1, −1e6, −1e12 (spread by random exponents)
                        0 if i == n - 1 => 0.0,
                        0 => -(10f64.powf(24.0 * (r() + 0.5))),
                        // second moment: positive, spread up to 1e24
                        1 => 10f64.powf(24.0 * (r() + 0.5)),
                        // indefinite
                        _ => 10f64.powf(24.0 * (r() + 0.5)) * r().signum(),
                    })
                    .collect();
                let a = rotated(&lambda, &mut r);
                let norm = a.norm();
                let reference = reference_eigenvalues(&a);
                let (fast, d, v) = solve(&a, jacobi_in_place);
                let (general, _, _) = solve(&a, jacobi_general);
                for i in 0..n {
                    worst = worst.max((fast[i] - reference[i]).abs() / norm);
                    worst_general = worst_general.max((general[i] - reference[i]).abs() / norm);
                }
                let rec = &v * DMatrix::from_diagonal(&d) * v.transpose();
                worst_rec = worst_rec.max((rec - &a).amax() / norm);
                worst_ortho =
                    worst_ortho.max((v.transpose() * &v - DMatrix::identity(n, n)).amax());
            }
            let eps = f64::EPSILON;
            // measured: eigenvalues ≤ 1.2 eps (general path ≤ 1.6), reconstruction ≤ 2.8 eps,
            // orthogonality ≤ 3 eps
            assert!(
                worst < 3.0 * eps,
                "n = {n}: eigenvalues {:.2} eps",
                worst / eps
            );
            assert!(
                worst_general < 3.0 * eps,
                "n = {n}: general {:.2} eps",
                worst_general / eps
            );
            assert!(
                worst_rec < 5.0 * eps,
                "n = {n}: rec {:.2} eps",
                worst_rec / eps
            );
            assert!(
                worst_ortho < 6.0 * eps,
                "n = {n}: ortho {:.2} eps",
                worst_ortho / eps
            );
        }
    }

    /// Graded matrices `A = ±D·H·D` (H well conditioned with unit diagonal, definite or
    /// indefinite; D from 1e-6 to 1e6 in random order: eigenvalues from 1e-12 to 1e12
    /// relative): every eigenvalue to a few ulps *relative* against the extended-precision
    /// reference, and a componentwise backward error of a few ulps of √(|a_ii·a_jj|).
    #[test]
    fn graded_matrices_keep_relative_accuracy() {
        let mut r = xorshift(29);
        for n in [2usize, 3, 4] {
            let (mut worst, mut worst_general, mut worst_res, mut worst_ortho) =
                (0.0f64, 0.0f64, 0.0f64, 0.0f64);
            for k in 0..900 {
                // H: unit diagonal; definite (eigenvalues in [0.5, 2] before the scaling) or,
                // every third, indefinite (diagonal ±1, off-diagonals below 0.3)
                let h = if k % 3 == 2 {
                    DMatrix::from_fn(n, n, |i, j| match (i, j) {
                        _ if i == j => [1.0, -1.0][i % 2],
                        _ => 0.0,
                    })
                } else {
                    let lambda: Vec<f64> = (0..n).map(|_| 1.25 + 1.5 * r()).collect();
                    let h = rotated(&lambda, &mut r);
                    DMatrix::from_fn(n, n, |i, j| h[(i, j)] / (h[(i, i)] * h[(j, j)]).sqrt())
                };
                let mut off = DMatrix::from_fn(n, n, |_, _| 0.6 * r());
                off = (&off + off.transpose()) * 0.5;
                let sign = if k % 3 == 1 { -1.0 } else { 1.0 };
                let dg: Vec<f64> = (0..n).map(|_| 10f64.powf(12.0 * r())).collect();
                let a = DMatrix::from_fn(n, n, |i, j| {
                    let hij = if k % 3 == 2 && i != j {
                        off[(i, j)]
                    } else {
                        h[(i, j)]
                    };
                    sign * dg[i] * hij * dg[j]
                });
                let reference = reference_eigenvalues(&a);
                let (fast, d, v) = solve(&a, jacobi_in_place);
                let (general, _, _) = solve(&a, jacobi_general);
                for i in 0..n {
                    let rel = |x: f64| (x - reference[i]).abs() / reference[i].abs();
                    worst = worst.max(rel(fast[i]));
                    worst_general = worst_general.max(rel(general[i]));
                }
                let (res, ortho) = graded_residual(&a, &d, &v);
                worst_res = worst_res.max(res);
                worst_ortho = worst_ortho.max(ortho);
            }
            let eps = f64::EPSILON;
            // measured: relative ≤ 1.5 eps (general path ≤ 1.9), residual ≤ 2.9 eps,
            // orthogonality ≤ 2.5 eps
            assert!(
                worst < 4.0 * eps,
                "n = {n}: relative {:.2} eps",
                worst / eps
            );
            assert!(
                worst_general < 4.0 * eps,
                "n = {n}: general {:.2} eps",
                worst_general / eps
            );
            assert!(
                worst_res < 6.0 * eps,
                "n = {n}: residual {:.2} eps",
                worst_res / eps
            );
            assert!(
                worst_ortho < 6.0 * eps,
                "n = {n}: ortho {:.2} eps",
                worst_ortho / eps
            );
        }
    }

    /// Diagonal and block-diagonal inputs, repeated eigenvalues, signed zeros.
    #[test]
    fn special_structures() {
        for n in [2usize, 3, 4] {
            // diagonal (with ±0): returned as is, V = I exactly
            let diag = [3.0, -0.0, 0.0, -2.5];
            let a = DMatrix::from_fn(n, n, |i, j| if i == j { diag[i] } else { 0.0 });
            let (_, d, v) = solve(&a, jacobi_in_place);
            for i in 0..n {
                // (−0 comes back as +0: d = b + z, as on the general path)
                assert_eq!(d[i], diag[i]);
            }
            assert_eq!(v, DMatrix::identity(n, n));
            // all zeros, both signs
            for z in [0.0, -0.0] {
                let (_, d, v) = solve(&DMatrix::from_element(n, n, z), jacobi_in_place);
                assert!(d.iter().all(|x| *x == 0.0));
                assert_eq!(v, DMatrix::identity(n, n));
            }
        }
        // block diagonal: the uncoupled rows and columns stay exact
        let a = DMatrix::from_row_slice(
            4,
            4,
            &[
                2.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.5, 0.0, 0.0, 0.5, 3.0, 0.0, 0.0, 0.0, 0.0, -7.0,
            ],
        );
        let (_, d, v) = solve(&a, jacobi_in_place);
        assert_eq!((d[0], d[3]), (2.0, -7.0));
        for i in 0..4 {
            for j in [0, 3] {
                assert_eq!(v[(i, j)], if i == j { 1.0 } else { 0.0 });
                assert_eq!(v[(j, i)], if i == j { 1.0 } else { 0.0 });
            }
        }
        // repeated eigenvalues
        let mut r = xorshift(7);
        let eps = f64::EPSILON;
        for n in [2usize, 3, 4] {
            for lambda in [
                vec![1.0; 4],
                vec![1.0, 1.0, 1.0, 2.0],
                vec![-1.0, 3.0, -1.0, 3.0],
                vec![0.0, 0.0, -1e6, -1e6],
            ] {
                for _ in 0..50 {
                    let a = rotated(&lambda[..n], &mut r);
                    let (sorted, d, v) = solve(&a, jacobi_in_place);
                    let reference = reference_eigenvalues(&a);
                    let norm = a.norm();
                    for i in 0..n {
                        assert!((sorted[i] - reference[i]).abs() <= 2.0 * eps * norm);
                    }
                    let rec = &v * DMatrix::from_diagonal(&d) * v.transpose();
                    assert!((rec - &a).amax() <= 4.0 * eps * norm);
                    assert!((v.transpose() * &v - DMatrix::identity(n, n)).amax() <= 6.0 * eps);
                }
            }
        }
    }

    /// Scales from the subnormals to 1e307 and mixed magnitudes: finite output, the same
    /// relative accuracy; scaling by a power of two (away from the range limits) scales the
    /// result exactly. NaN input terminates.
    #[test]
    fn extreme_scales() {
        let mut r = xorshift(17);
        let eps = f64::EPSILON;
        for n in [2usize, 3, 4] {
            for _ in 0..200 {
                let g = DMatrix::from_fn(n, n, |_, _| r());
                let base = (&g + g.transpose()) * 0.5;
                let (unit, _, _) = solve(&base, jacobi_in_place);
                for k in [
                    -1070, -1040, -1000, -600, -480, -300, 0, 300, 480, 600, 1000, 1020,
                ] {
                    let scale = 2f64.powi(k);
                    let a = &base * scale;
                    let (sorted, d, v) = solve(&a, jacobi_in_place);
                    assert!(d.iter().chain(v.iter()).all(|x| x.is_finite()), "2^{k}");
                    // (a.norm() would under- or overflow)
                    let norm = base.norm() * scale;
                    let rec = &v * DMatrix::from_diagonal(&d) * v.transpose();
                    let ortho = (v.transpose() * &v - DMatrix::identity(n, n)).amax();
                    assert!(ortho <= 6.0 * eps, "2^{k}: {ortho:e}");
                    if k > -1000 {
                        assert!((rec - &a).amax() <= 5.0 * eps * norm, "2^{k}");
                    }
                    if (-900..=900).contains(&k) {
                        for i in 0..n {
                            let x = sorted[i] / scale;
                            assert!(
                                (x - unit[i]).abs() <= 4.0 * eps * base.norm(),
                                "2^{k}: {x:e} vs {:e} (n = {n}, {i})",
                                unit[i]
                            );
                        }
                    }
                }
            }
            // mixed magnitudes: diagonal 1e300 / 1e-300, off-diagonals from 1e-320 to 1e150
            for _ in 0..200 {
                let a = DMatrix::from_fn(n, n, |i, j| {
                    let (i, j) = (i.min(j), i.max(j));
                    let e = [300.0, -300.0, 150.0, -320.0][(i + 2 * j) % 4];
                    10f64.powf(e + r()) * (r() + 0.01)
                });
                let a = DMatrix::from_fn(n, n, |i, j| a[(i.min(j), i.max(j))]);
                let (_, d, v) = solve(&a, jacobi_in_place);
                assert!(d.iter().chain(v.iter()).all(|x| x.is_finite()));
                let rec = &v * DMatrix::from_diagonal(&d) * v.transpose();
                assert!((rec - &a).amax() <= 5.0 * eps * a.amax() * n as f64);
                assert!((v.transpose() * &v - DMatrix::identity(n, n)).amax() <= 6.0 * eps);
            }
            // the largest norm of the documented range
            let a = DMatrix::from_fn(
                n,
                n,
                |i, j| if i == j { 0.3 } else { -0.2 } * 2f64.powi(1020),
            );
            let (_, d, v) = solve(&a, jacobi_in_place);
            assert!(d.iter().chain(v.iter()).all(|x| x.is_finite()));
            // NaN: terminates (callers check for finite output)
            let mut a = DMatrix::from_element(n, n, 1.0);
            a[(0, n - 1)] = f64::NAN;
            let (_, d, _) = solve(&a, jacobi_in_place);
            assert!(d.iter().any(|x| x.is_nan()));
        }
    }

    /// Nearly diagonal inputs (the iteration ends in the first-order step at once), graded and
    /// with close diagonals, against the extended-precision reference; repeated runs give
    /// bit-identical output.
    #[test]
    fn nearly_diagonal_and_deterministic() {
        let mut r = xorshift(41);
        let eps = f64::EPSILON;
        for n in [3usize, 4] {
            for k in 0..400 {
                let dg: Vec<f64> = (0..n)
                    .map(|i| match k % 4 {
                        0 => 10f64.powf(12.0 * r()),
                        1 => 1.0 + 1e-6 * i as f64 + 1e-9 * r(),
                        2 => -(10f64.powf(6.0 * r())),
                        _ => r(),
                    })
                    .collect();
                let off = 10f64.powf(-9.0 - 6.0 * (r() + 0.5));
                let a = DMatrix::from_fn(n, n, |i, j| {
                    if i == j {
                        dg[i]
                    } else {
                        let (i, j) = (i.min(j), i.max(j));
                        off * (dg[i] * dg[j]).abs().sqrt() * ((i * 7 + j * 3) as f64 * 0.37).sin()
                    }
                });
                let reference = reference_eigenvalues(&a);
                let (sorted, d, v) = solve(&a, jacobi_in_place);
                for i in 0..n {
                    let rel = (sorted[i] - reference[i]).abs() / reference[i].abs();
                    assert!(rel <= 2.0 * eps, "k = {k}: {:.2} eps", rel / eps);
                }
                let (res, ortho) = graded_residual(&a, &d, &v);
                assert!(res <= 4.0 * eps && ortho <= 4.0 * eps, "k = {k}");
                let (sorted2, d2, v2) = solve(&a, jacobi_in_place);
                assert_eq!(sorted, sorted2);
                assert_eq!((d, v), (d2, v2));
            }
        }
    }

    /// The regimes of `rotation` and Numerical Recipes' formulas against the exact rotation
    /// (double-double), and the shortcut for tiny angles against the series (bit for bit).
    #[test]
    fn rotation_regimes() {
        let mut r = xorshift(5);
        let one = Dd(1.0, 0.0);
        let ulps = |x: f64, y: Dd| (Dd(x, 0.0).sub(y)).0.abs() / (f64::EPSILON * y.0.abs());
        let (mut worst, mut worst_nr) = ([0.0f64; 3], [0.0f64; 3]);
        for k in 0..100_000 {
            let apq = r() * 10f64.powf(40.0 * r());
            let x = match k % 3 {
                0 => 10f64.powf(-30.0 * (r() + 0.5)),
                1 => 10f64.powf(-3.0 * (r() + 0.5)),
                _ => 10f64.powf(8.0 * r()),
            } * r().signum();
            let h = apq / x;
            // exact: θ = h/(2apq), t = sign(θ)/(|θ| + √(1 + θ²)), c = 1/√(1 + t²)
            let a = Dd(apq, 0.0);
            let theta = Dd(h, 0.0).div(a.add(a));
            let t = one.div(theta.abs().add(one.add(theta.mul(theta)).sqrt()));
            let t = if theta.0 < 0.0 { t.neg() } else { t };
            let c = one.div(one.add(t.mul(t)).sqrt());
            let exact = [t.mul(a), t.mul(c), t.mul(c).div(one.add(c))];
            let (ta, s, tau) = rotation(apq, h);
            let (t0, s0, tau0) = rotation_nr(apq, h);
            for (i, (got, nr)) in [(ta, t0 * apq), (s, s0), (tau, tau0)]
                .into_iter()
                .enumerate()
            {
                worst[i] = worst[i].max(ulps(got, exact[i]));
                worst_nr[i] = worst_nr[i].max(ulps(nr, exact[i]));
            }
            if apq.abs() <= TINY_X * h.abs() {
                let (ta1, s1, tau1) = rotation_series(apq, h);
                assert_eq!((ta.to_bits(), s.to_bits()), (ta1.to_bits(), s1.to_bits()));
                assert_eq!(tau.to_bits(), tau1.to_bits());
            }
        }
        // measured: ≤ 1.9 ulps (Numerical Recipes' formulas: ≤ 2.2)
        assert!(worst.iter().all(|w| *w <= 2.5), "{worst:?}");
    }
}
