//! The moment map of a concentrated Bingham as a series, and the curvature correction it gives
//! Newton's step (d = 3, 4).
//!
//! With `z` sorted, `z_d = 0` and every other `z_j` far below it, `x` stays near `±e_d` and its
//! other coordinates are nearly independent Gaussians of variances `s_j = 1/(2|z_j|)`. Expanding
//! the sphere's measure in them (`(1 − r²)^{−1/2} = Σ_k C(2k, k) r^{2k}/4^k`, the Gaussian
//! moments, exponentially small tails dropped) gives, for `i < d`, with sums over the other
//! `j < d`, `j ≠ i` (`S = Σ s_j`, `Q = Σ s_j²`, `C = Σ s_j³`, `P = Σ_{j<l} s_j s_l`,
//! `M = Σ_{j≠l} s_j² s_l`):
//!
//! `1/ω_i = 1/s_i − 1 − (3s_i + S) − 2(9s_i² + 3s_i S + 2Q + P)
//!          − (153s_i³ + 54s_i² S + 36s_i Q + 18s_i P + 25C + 12M) + O(s⁴)`.
//!
//! Derived symbolically (series of the ratio of the two Gaussian expectations) for one and two
//! other coordinates, i.e. d = 3 and 4; with three or more a term in their triple products
//! appears at the last order, which is not derived, so larger d do not use it. The first two
//! orders are those of the known start `1/ω_i ≈ 2|z_i| − 1 − Σ_j 1/(2|z_j|) − 1/|z_i|`.
//!
//! The MLE's Newton iteration solves `G(z) = 1/ω(z) − 1/ω̂ = 0`, where `G` is `2|z|` plus the
//! series' lower terms: nearly linear, so one step from a warm start at a residual of 1e-2
//! lands near 1e-6 (the spin filter's fits), just short of finishing in one more step. The
//! series knows most of the curvature that is left: [`correct_step`] adds to Newton's step `Δ`
//! (from the exact Hessian) the solution of `J δ = −N(Δ)`, `N` the series' departure from its
//! tangent along `Δ`, so the step follows the curvature to second order. It only moves the
//! point Newton evaluates next; the line search and the convergence test are unchanged, so the
//! solution meets the same tolerance.

/// The series is used where every concentration below the mode is at least this large
/// (`s_j ≤ 1/16`) at both ends of the step. Chosen by counting evaluations over random d = 3, 4
/// problems (|z_i| from 1 to 1e4, warm starts 1–20 % off): from 8 up the correction never costs
/// an evaluation; from 3 to 5 it sometimes does (the terms stop decreasing fast enough to
/// describe the curvature), and it gains little there.
const MIN_CONCENTRATION: f64 = 8.0;

/// A value with its derivative along one direction (forward-mode differentiation of the series).
#[derive(Debug, Clone, Copy)]
struct Jet {
    v: f64,
    d: f64,
}

/// What the series' terms are evaluated on: plain values, or [`Jet`]s.
trait Term: Copy + std::ops::Add<Output = Self> + std::ops::Mul<Output = Self> {
    const ZERO: Self;
    /// `c · self`.
    fn scale(self, c: f64) -> Self;
}

impl Term for f64 {
    const ZERO: f64 = 0.0;
    fn scale(self, c: f64) -> f64 {
        c * self
    }
}

impl Term for Jet {
    const ZERO: Jet = Jet { v: 0.0, d: 0.0 };
    fn scale(self, c: f64) -> Jet {
        Jet {
            v: c * self.v,
            d: c * self.d,
        }
    }
}

impl std::ops::Add for Jet {
    type Output = Jet;
    fn add(self, o: Jet) -> Jet {
        Jet {
            v: self.v + o.v,
            d: self.d + o.d,
        }
    }
}

impl std::ops::Mul for Jet {
    type Output = Jet;
    fn mul(self, o: Jet) -> Jet {
        Jet {
            v: self.v * o.v,
            d: self.d * o.v + self.v * o.d,
        }
    }
}

const ZERO: Jet = Jet::ZERO;

/// The series' terms beyond `1/s_i − 1` for coordinate `i` of `s` (`s.len() ≤ 3`).
fn higher_terms<T: Term>(s: &[T], i: usize) -> T {
    let si = s[i];
    let (mut sum, mut sq, mut cube, mut pairs, mut mixed) =
        (T::ZERO, T::ZERO, T::ZERO, T::ZERO, T::ZERO);
    for (j, &sj) in s.iter().enumerate() {
        if j == i {
            continue;
        }
        sum = sum + sj;
        sq = sq + sj * sj;
        cube = cube + sj * sj * sj;
        for (l, &sl) in s.iter().enumerate() {
            if l != i && l != j {
                mixed = mixed + sj * sj * sl;
                if l > j {
                    pairs = pairs + sj * sl;
                }
            }
        }
    }
    let second = si.scale(3.0) + sum;
    let third = (si * si).scale(9.0) + (si * sum).scale(3.0) + sq.scale(2.0) + pairs;
    let fourth = (si * si * si).scale(153.0)
        + (si * si * sum).scale(54.0)
        + (si * sq).scale(36.0)
        + (si * pairs).scale(18.0)
        + cube.scale(25.0)
        + mixed.scale(12.0);
    (second + third.scale(2.0) + fourth).scale(-1.0)
}

/// [`higher_terms`] of every coordinate of `s` (`s.len() ≤ 3`) with its gradient in `s`
/// (`grad[i][m] = ∂T_i/∂s_m`; entries past `s.len()` zero), written out on the (at most two)
/// other coordinates `o₁, o₂` of each `i`: one pass instead of one forward-mode evaluation per
/// coordinate and direction (the tests compare the two).
fn terms_and_gradients(s: &[f64]) -> ([f64; 3], [[f64; 3]; 3]) {
    let k = s.len();
    let (mut value, mut grad) = ([0.0; 3], [[0.0; 3]; 3]);
    for i in 0..k {
        let si = s[i];
        // the other coordinates (o₂ = 0 for k = 2: its terms vanish)
        let (m1, m2) = match i {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        let o1 = if m1 < k { s[m1] } else { 0.0 };
        let o2 = if m2 < k { s[m2] } else { 0.0 };
        let sum = o1 + o2;
        let sq = o1 * o1 + o2 * o2;
        let cube = o1 * o1 * o1 + o2 * o2 * o2;
        let pairs = o1 * o2;
        let mixed = o1 * o1 * o2 + o2 * o2 * o1;
        let second = 3.0 * si + sum;
        let third = 9.0 * (si * si) + 3.0 * (si * sum) + 2.0 * sq + pairs;
        let fourth = 153.0 * (si * si * si)
            + 54.0 * (si * si * sum)
            + 36.0 * (si * sq)
            + 18.0 * (si * pairs)
            + 25.0 * cube
            + 12.0 * mixed;
        value[i] = -(second + 2.0 * third + fourth);
        let (d2, d3, d4) = (
            3.0,
            18.0 * si + 3.0 * sum,
            459.0 * si * si + 108.0 * si * sum + 36.0 * sq + 18.0 * pairs,
        );
        grad[i][i] = -(d2 + 2.0 * d3 + d4);
        for m in [m1, m2] {
            if m >= k {
                continue;
            }
            let sm = s[m];
            // the sums' derivatives in s_m: sum 1, sq 2s_m, cube 3s_m², pairs (sum − s_m),
            // mixed 2s_m(sum − s_m) + (sq − s_m²)
            let rest = sum - sm;
            let (d2, d3, d4) = (
                1.0,
                3.0 * si + 4.0 * sm + rest,
                54.0 * si * si
                    + 72.0 * si * sm
                    + 18.0 * si * rest
                    + 75.0 * sm * sm
                    + 12.0 * (2.0 * sm * rest + sq - sm * sm),
            );
            grad[i][m] = -(d2 + 2.0 * d3 + d4);
        }
    }
    (value, grad)
}

/// `1/ω_i` of the series at `z` (sorted, `z_d = 0`, d = 3 or 4), for the tests.
#[cfg(test)]
pub(super) fn inverse_omega(z: &[f64], i: usize) -> f64 {
    let k = z.len() - 1;
    let mut s = [ZERO; 3];
    for j in 0..k {
        s[j] = Jet {
            v: -0.5 / z[j],
            d: 0.0,
        };
    }
    1.0 / s[i].v - 1.0 + higher_terms(&s[..k], i).v
}

/// Below this concentration `series_hessian` declines (the series of `1/ω` is used there only
/// where the concentrated series of ω itself holds, from about 95 up).
const SERIES_HESSIAN_MIN: f64 = 80.0;

/// The Hessian of `log F` at `z` (sorted, `z_d = 0`, d = 3 or 4, every concentration below the
/// mode at least `SERIES_HESSIAN_MIN`) into `hess` (d×d row-major) from the series of `1/ω_i`:
/// `H_ij = ∂ω_i/∂z_j = −ω_i² ∂(1/ω_i)/∂z_j` with `ω` = `grad` (exact) and the derivative of the
/// series, `−2δ_ij + 2 s_j² ∂T_i/∂s_j` (`T_i` its higher terms), symmetrized; the last row and
/// column from `Σ_j H_ij = 0` (ω does not change when every `z_j` moves alike). The omitted
/// order of the series, `O(s⁵)` relative in `∂(1/ω_i)/∂z_j` (`s ≤ 1/160` here), and the
/// exponentially small tails make it an approximation of the exact Hessian to about 1e-7
/// relative or better (`tests`); the Newton iteration uses it only for its steps, whose
/// convergence it barely slows (a step with a Jacobian off by ε leaves a residual ε times the
/// last), never for the convergence test. Returns `false`, `hess` untouched, where it does not
/// apply or the result is not finite.
pub(super) fn series_hessian(z: &[f64], grad: &[f64], hess: &mut [f64]) -> bool {
    let d = z.len();
    if !(d == 3 || d == 4) || grad.len() != d || hess.len() != d * d {
        return false;
    }
    let k = d - 1;
    if !(0..k).all(|i| z[i] <= -SERIES_HESSIAN_MIN) {
        return false;
    }
    let mut s = [0.0; 3];
    for j in 0..k {
        s[j] = -0.5 / z[j];
    }
    let mut dinv = [[0.0; 3]; 3];
    let (_, grads) = terms_and_gradients(&s[..k]);
    for (i, row) in dinv.iter_mut().enumerate().take(k) {
        // ∂(1/ω_i)/∂z_j = −2δ_ij + ∂T_i/∂s_j · ds_j/dz_j, ds_j/dz_j = 2 s_j²
        let dt = grads[i];
        for j in 0..k {
            row[j] = if i == j { -2.0 } else { 0.0 } + dt[j] * 2.0 * s[j] * s[j];
        }
    }
    hessian_from(&dinv, grad, hess)
}

/// The Hessian of `log F` into `hess` (d×d row-major, d = `grad.len()` ≤ 4) from `ω` = `grad`
/// and `dinv[i][j] = ∂(1/ω_i)/∂z_j` (i, j < d − 1): `H_ij = −ω_i² dinv[i][j]`, symmetrized; the
/// last row and column from `Σ_j H_ij = 0`. Returns `false`, `hess` untouched, if the result
/// is not finite.
pub(super) fn hessian_from(dinv: &[[f64; 3]; 3], grad: &[f64], hess: &mut [f64]) -> bool {
    let d = grad.len();
    let k = d - 1;
    let mut h = [0.0; 16];
    for i in 0..k {
        for j in 0..k {
            h[i * d + j] = -grad[i] * grad[i] * dinv[i][j];
        }
    }
    for i in 0..k {
        for j in i + 1..k {
            let m = 0.5 * (h[i * d + j] + h[j * d + i]);
            h[i * d + j] = m;
            h[j * d + i] = m;
        }
    }
    let mut corner = 0.0;
    for i in 0..k {
        let row: f64 = (0..k).map(|j| h[i * d + j]).sum();
        h[i * d + k] = -row;
        h[k * d + i] = -row;
        corner += row;
    }
    h[k * d + k] = corner;
    if !h[..d * d].iter().all(|v| v.is_finite()) {
        return false;
    }
    hess.copy_from_slice(&h[..d * d]);
    true
}

/// [`series_root`] is tried where every concentration below the mode of the start is at least
/// this large (`s_j ≤ 2.5e-4`). The series' omitted order leaves its root a relative residual
/// in the exact `ω` of about `5.6e3 s_max⁵` (measured from 100 to 1600 over the test's
/// problems: 1.9e-8 at 100, 5.3e-13 at 800, 1.7e-14 at 1600), 5e-15 here: six times below a
/// third of [`MLE_TOL`](super::solution::MLE_TOL), so the root meets the tolerance on the
/// exact `ω` (the AHRS's states: every `|z_j|` in the thousands). Below it the root may miss,
/// and the check that refuses it would cost an evaluation for nothing.
const ROOT_MIN: f64 = 2000.0;

/// The root of the series' moment equation `1/ω_i(z) = 1/t_i` (i < d − 1; `t` ascending,
/// normalized, d = 3 or 4), by Newton's method on the series alone: `1/ω_i = 2a_i − 1 + T_i(s)`
/// with `a = −z`, `s_j = 1/(2a_j)`, whose Jacobian in `a` is `2δ_ij − 2s_j² ∂T_i/∂s_j` (nearly
/// `2I`, inverted by its Neumann series; two steps reach the rounding of `a`: [`SETTLED`]).
/// From `z` (the start, `z[d−1] = 0`, every other entry at most `−ROOT_MIN`), which receives
/// the root. `dinv` receives
/// `∂(1/ω_i)/∂z_j` of the series at the last iterate (for [`hessian_from`]). The root is the
/// series', not the exact equation's: the caller checks it on the exact `ω` (the series'
/// truncation is below `MLE_TOL/3` here, see [`ROOT_MIN`]). Returns `false`, `z` untouched,
/// where it does not apply, or if the iteration leaves the range or does not settle.
pub(super) fn series_root(t: &[f64], z: &mut [f64], dinv: &mut [[f64; 3]; 3]) -> bool {
    let d = z.len();
    if !(d == 3 || d == 4) || t.len() != d {
        return false;
    }
    let k = d - 1;
    if !(0..k).all(|i| z[i] <= -ROOT_MIN) {
        return false;
    }
    let (mut a, mut inv_t) = ([0.0; 3], [0.0; 3]);
    for i in 0..k {
        a[i] = -z[i];
        inv_t[i] = 1.0 / t[i];
    }
    for _ in 0..8 {
        let mut s = [0.0; 3];
        for j in 0..k {
            s[j] = 0.5 / a[j];
        }
        // the Jacobian 2(I − E), E_ij = s_j² ∂T_i/∂s_j (|E| ≲ 1e-6 for s ≤ 5e-4: a ≥ ROOT_MIN/2),
        // inverted by its Neumann series ½(I + E + E²): the omitted E³ is below 1e-17
        let mut e = [[0.0; 3]; 3];
        let mut f = [0.0; 3];
        let (value, grads) = terms_and_gradients(&s[..k]);
        for i in 0..k {
            f[i] = (2.0 * a[i] - 1.0 + value[i]) - inv_t[i];
            for j in 0..k {
                e[i][j] = grads[i][j] * s[j] * s[j];
                dinv[i][j] = if i == j { -2.0 } else { 0.0 } + 2.0 * e[i][j];
            }
        }
        let ef = mat_vec(&e, &f, k);
        let eef = mat_vec(&e, &ef, k);
        let mut settled = true;
        for i in 0..k {
            let step = 0.5 * (f[i] + ef[i] + eef[i]);
            a[i] -= step;
            settled &= step.abs() <= SETTLED * a[i];
        }
        if !(0..k).all(|i| a[i].is_finite() && a[i] >= 0.5 * ROOT_MIN) {
            return false;
        }
        if settled {
            for i in 0..k {
                z[i] = -a[i];
            }
            return true;
        }
    }
    false
}

/// [`series_root`] stops after a step of at most this relative size in every `a_i`. Its
/// Jacobian `2I + O(s²)` changes by `O(s²) ≤ 1e-7` relative across a step (`s ≤ 2.5e-4`), so a
/// step of relative size `δ` leaves an error of about `1e-7 δ` (Newton's quadratic term): below
/// the rounding of `a` after a step of 1e-9. On the AHRS's fits the second step is that small
/// (1 323 steps for 666 fits on the 50 Hz bench stream; the test's starts 1–30 % off as well).
const SETTLED: f64 = 1e-9;

/// `E f` for the leading `k × k` block of `e` (k ≤ 3).
fn mat_vec(e: &[[f64; 3]; 3], f: &[f64; 3], k: usize) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (o, row) in out.iter_mut().zip(e).take(k) {
        *o = row[..k].iter().zip(&f[..k]).map(|(x, y)| x * y).sum();
    }
    out
}

/// Adds to Newton's step `step` (its first `d − 1` entries; `H Δ = ω² ∘ G` from `z` with
/// gradient `grad` and Hessian `hess`, d×d row-major) the series' curvature correction `δ`,
/// `H δ = ω² ∘ N(Δ)` with `N(Δ) = T(z + Δ) − T(z) − T′(z) Δ` for the series' higher terms `T`.
/// Only for d = 3, 4 and where the series holds at both ends of the step
/// (`MIN_CONCENTRATION`); otherwise, or if the correction is not finite, `step` is left as it
/// is. Returns whether it was corrected.
pub(super) fn correct_step(z: &[f64], grad: &[f64], hess: &[f64], step: &mut [f64]) -> bool {
    let d = z.len();
    if !(d == 3 || d == 4) {
        return false;
    }
    let k = d - 1;
    if !(0..k).all(|i| z[i] <= -MIN_CONCENTRATION && z[i] + step[i] <= -MIN_CONCENTRATION) {
        return false;
    }
    // s_j = −1/(2 z_j) at both ends; at z its derivative along Δ, ds_j/dz_j Δ_j = 2 s_j² Δ_j
    let (mut s0, mut s1) = ([ZERO; 3], [ZERO; 3]);
    for j in 0..k {
        let v = -0.5 / z[j];
        s0[j] = Jet {
            v,
            d: 2.0 * v * v * step[j],
        };
        s1[j] = Jet {
            v: -0.5 / (z[j] + step[j]),
            d: 0.0,
        };
    }
    let mut jac = [0.0; 9];
    let mut corr = [0.0; 3];
    for a in 0..k {
        for b in 0..k {
            jac[a * k + b] = hess[a * d + b];
        }
        let at_z = higher_terms(&s0[..k], a);
        let n = higher_terms(&s1[..k], a).v - at_z.v - at_z.d;
        corr[a] = grad[a] * grad[a] * n;
    }
    if !crate::linalg::cholesky_solve(k, &mut jac[..k * k], &mut corr[..k])
        || !corr[..k].iter().all(|c| c.is_finite())
    {
        return false;
    }
    for (s, c) in step.iter_mut().zip(&corr[..k]) {
        *s += c;
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::cholesky_solve;
    use crate::normalization::{log_normalization_into, Method};

    fn omega(z: &[f64]) -> Vec<f64> {
        let mut w = vec![0.0; z.len()];
        log_normalization_into(z, Method::Exact, Some(&mut w), None).unwrap();
        w
    }

    /// The series against the exact moments (d = 3, 4): its error in `1/ω_i` falls like the
    /// first omitted order, `s⁵` relative, as the concentrations grow.
    #[test]
    fn series_matches_the_exact_moments_of_concentrated_binghams() {
        for base in [&[-5.0, -3.0, -1.0, 0.0][..], &[-4.0, -1.5, 0.0][..]] {
            let mut last = f64::INFINITY;
            for c in [20.0, 40.0, 80.0, 160.0, 320.0] {
                let z: Vec<f64> = base.iter().map(|v| v * c).collect();
                let w = omega(&z);
                let s_max = 0.5 / c;
                let err = (0..z.len() - 1)
                    .map(|i| (inverse_omega(&z, i) * w[i] - 1.0).abs())
                    .fold(0.0, f64::max);
                println!(
                    "z = {z:?}: relative error {err:e}, s_max⁵ = {:e}",
                    s_max.powi(5)
                );
                assert!(err <= 3e4 * s_max.powi(5) + 1e-14, "z = {z:?}: {err:e}");
                assert!(
                    err < last || err < 1e-14,
                    "z = {z:?}: {err:e} after {last:e}"
                );
                last = err;
            }
        }
    }

    /// The written-out terms and gradients against the loops and forward-mode differentiation
    /// of [`higher_terms`].
    #[test]
    fn written_out_terms_match_forward_mode() {
        for s in [
            &[1e-3, 2e-3, 5e-3][..],
            &[3e-4, 3e-4, 3e-4][..],
            &[1e-2, 4e-3][..],
            &[2e-5, 7e-3, 1e-4][..],
        ] {
            let k = s.len();
            let (values, grads) = terms_and_gradients(s);
            for i in 0..k {
                let plain = higher_terms(s, i);
                assert!(
                    (values[i] - plain).abs() <= 1e-15 * plain.abs(),
                    "s = {s:?}, i = {i}: {} vs {plain}",
                    values[i]
                );
                let g = grads[i];
                for (m, &gm) in g[..k].iter().enumerate() {
                    let jets: Vec<Jet> = s
                        .iter()
                        .enumerate()
                        .map(|(l, &v)| Jet {
                            v,
                            d: if l == m { 1.0 } else { 0.0 },
                        })
                        .collect();
                    let want = higher_terms(&jets, i).d;
                    assert!(
                        (gm - want).abs() <= 1e-14 * want.abs().max(1.0),
                        "s = {s:?}, i = {i}, m = {m}: {gm} vs {want}"
                    );
                }
            }
        }
    }

    /// Shapes of `z` (d = 4 and 3; scaled by the concentration): distinct, equal, and far
    /// apart concentrations.
    const SHAPES: [&[f64]; 5] = [
        &[-5.0, -3.0, -1.0, 0.0],
        &[-1.0, -1.0, -1.0, 0.0],
        &[-1e4, -30.0, -1.0, 0.0],
        &[-4.0, -1.5, 0.0],
        &[-1.0, -1.0, 0.0],
    ];

    /// The series' Hessian against the exact one (the quadrature) where the Newton iteration
    /// uses it (every concentration below the mode from 80 up, d = 3, 4): within 1e-6 of the
    /// diagonal's scale, and closer as the concentrations grow.
    #[test]
    fn series_hessian_matches_the_exact_hessian() {
        let mut worst_at_min: f64 = 0.0;
        for base in SHAPES {
            for c in [80.0, 200.0, 1e3, 1e4, 1e6] {
                let z: Vec<f64> = base.iter().map(|v| v * c).collect();
                let d = z.len();
                let (mut g, mut h) = (vec![0.0; d], vec![0.0; d * d]);
                log_normalization_into(&z, Method::Exact, Some(&mut g), Some(&mut h)).unwrap();
                let mut hs = vec![0.0; d * d];
                assert!(series_hessian(&z, &g, &mut hs), "z = {z:?}");
                let scale = (0..d).map(|i| h[i * d + i].abs()).fold(0.0, f64::max);
                let err = (0..d * d)
                    .map(|k| (hs[k] - h[k]).abs() / scale)
                    .fold(0.0, f64::max);
                println!("z = {z:?}: max error {err:e} of the diagonal's scale");
                assert!(err < 1e-6, "z = {z:?}: {err:e}\n{hs:?}\n{h:?}");
                if c == 80.0 {
                    worst_at_min = worst_at_min.max(err);
                }
            }
        }
        // declined below the threshold, for other d, and with the buffer untouched
        let mut hs = [7.0; 16];
        assert!(!series_hessian(
            &[-79.0, -100.0, -100.0, 0.0],
            &[0.0; 4],
            &mut hs
        ));
        assert!(!series_hessian(&[-100.0, 0.0], &[0.0; 2], &mut hs[..4]));
        assert_eq!(hs, [7.0; 16]);
        println!("worst at the threshold: {worst_at_min:e}");
    }

    /// The series' root against the exact moment equation (d = 3, 4) from starts 1–30 % off:
    /// from [`ROOT_MIN`] up it meets a third of `MLE_TOL` on the exact ω (the quadrature), and
    /// it declines below [`ROOT_MIN`], for other d, and where the iteration would leave the range.
    #[test]
    fn series_root_solves_the_exact_moment_equation() {
        use crate::mle::solution::MLE_TOL;
        let (mut worst, mut tried): (f64, usize) = (0.0, 0);
        for base in SHAPES {
            for c in [ROOT_MIN, 3e3, 1e4, 1e5, 1e8] {
                for off in [1.01f64, 0.97, 1.3, 0.8] {
                    let z: Vec<f64> = base.iter().map(|v| v * c).collect();
                    let d = z.len();
                    let t = omega(&z);
                    let mut zr: Vec<f64> = z.iter().map(|v| v * off).collect();
                    if zr[..d - 1].iter().any(|&v| v > -ROOT_MIN) {
                        // (a start below ROOT_MIN is declined: tested below)
                        continue;
                    }
                    tried += 1;
                    let mut dinv = [[0.0; 3]; 3];
                    assert!(series_root(&t, &mut zr, &mut dinv), "z = {z:?}, off {off}");
                    let w = omega(&zr);
                    let r = (0..d - 1)
                        .map(|i| (w[i] / t[i] - 1.0).abs())
                        .fold(0.0, f64::max);
                    worst = worst.max(r);
                    assert!(r <= MLE_TOL / 3.0, "z = {z:?}, off {off}: residual {r:e}");
                }
            }
        }
        println!("worst residual on the exact ω: {worst:e} ({tried} problems)");
        assert!(tried >= 80, "{tried}");
        let mut dinv = [[0.0; 3]; 3];
        let mut z = [-1999.0, -3000.0, -4000.0, 0.0];
        assert!(!series_root(&[0.1, 0.2, 0.3, 0.4], &mut z, &mut dinv));
        assert_eq!(z, [-1999.0, -3000.0, -4000.0, 0.0]);
        let mut z2 = [-3000.0, 0.0];
        assert!(!series_root(&[0.1, 0.9], &mut z2, &mut dinv));
        // a target far outside the series' range (ω of a concentration near 5): the iteration
        // leaves it and declines
        let mut z3 = [-3000.0, -3000.0, -3000.0, 0.0];
        assert!(!series_root(&[0.1, 0.1, 0.1, 0.7], &mut z3, &mut dinv));
        assert_eq!(z3, [-3000.0, -3000.0, -3000.0, 0.0]);
    }

    /// One Newton step from a start 1–3 % off (the spin filter's warm starts): corrected, its
    /// residual is several times smaller than the plain step's.
    #[test]
    fn corrected_step_lands_closer() {
        for (zs, off) in [
            ([-60.0, -45.0, -12.0, 0.0], [1.02, 0.985, 1.03]),
            ([-27.0, -21.0, -9.0, 0.0], [0.99, 1.015, 0.98]),
            ([-400.0, -90.0, -40.0, 0.0], [1.03, 1.01, 0.97]),
        ] {
            let t = omega(&zs);
            let z0 = [zs[0] * off[0], zs[1] * off[1], zs[2] * off[2], 0.0];
            let (mut g, mut h) = ([0.0; 4], [0.0; 16]);
            log_normalization_into(&z0, Method::Exact, Some(&mut g), Some(&mut h)).unwrap();
            let mut step = [0.0; 4];
            let mut jac = [0.0; 9];
            for a in 0..3 {
                for b in 0..3 {
                    jac[a * 3 + b] = h[a * 4 + b];
                }
                step[a] = g[a] * g[a] * (1.0 / g[a] - 1.0 / t[a]);
            }
            assert!(cholesky_solve(3, &mut jac, &mut step[..3]));
            let resid = |step: &[f64]| {
                let z: Vec<f64> = (0..4).map(|i| z0[i] + step[i]).collect();
                let w = omega(&z);
                (0..3)
                    .map(|i| (w[i] / t[i] - 1.0).abs())
                    .fold(0.0, f64::max)
            };
            let plain = resid(&step);
            assert!(correct_step(&z0, &g, &h, &mut step[..3]));
            let corrected = resid(&step);
            println!("z = {zs:?}: plain {plain:e}, corrected {corrected:e}");
            assert!(
                corrected * 2.0 < plain,
                "z = {zs:?}: {plain:e} → {corrected:e}"
            );
        }
        // not below MIN_CONCENTRATION, nor for d = 2 or d ≥ 5
        let mut step = [0.1; 3];
        assert!(!correct_step(
            &[-7.0, -20.0, -30.0, 0.0],
            &[0.0; 4],
            &[0.0; 16],
            &mut step
        ));
        assert!(!correct_step(
            &[-70.0, 0.0],
            &[0.0; 2],
            &[0.0; 4],
            &mut step[..1]
        ));
        assert_eq!(step, [0.1; 3]);
    }
}
