//! d = 3, 4: `log F` and `ω = ∇ log F` of a concentrated Bingham by a series with a rigorous
//! error bound, used in place of the quadrature where that bound is below [`TOL`].
//!
//! # The series
//!
//! `z` canonical (ascending, `z_{d−1} = 0`), `n = d − 1`, `a_i = −z_i > 0` for `i < n`. On the
//! hemisphere `x_{d−1} > 0` take `y = (x_0, …, x_{n−1})` in the unit ball (`r = |y|`,
//! `x_{d−1} = √(1 − r²)`, surface element `dy/√(1 − r²)`); with both hemispheres
//!
//! `F(z) = 2 ∫_{r<1} exp(−Σ a_i y_i²) (1 − r²)^{−1/2} dy = G · T`,
//!
//! `G = 2 ∫_{Rⁿ} exp(−Σ a_i y_i²) dy = 2 π^{n/2} Π a_i^{−1/2}`, `T = E[h(ρ)]`,
//! `h(ρ) = (1 − ρ)^{−1/2} 1{ρ < 1}`, `ρ = Σ Y_i²` with independent `Y_i ~ N(0, s_i)`,
//! `s_i = 1/(2a_i)`. Likewise `ω_i = E[x_i²] = U_i/T` with `U_i = E[Y_i² h(ρ)]` (`i < n`), and
//! `ω_{d−1} = 1 − Σ_{i<n} ω_i`. (Equivalently `ω_i = s_i + 2 s_i² ∂ log T/∂s_i`: `∂/∂z_i` of
//! `−½ log a_i` is `s_i` and `∂s_i/∂z_i = 2 s_i²`; Stein's identity turns the derivative of
//! `T` into `U_i`.)
//!
//! Expand `(1 − ρ)^{−1/2} = Σ_k c_k ρ^k`, `c_k = C(2k, k)/4^k`, and integrate term by term over
//! all of `Rⁿ`: `T̂ = Σ_{k≤K} c_k m_k`, `Û_i = Σ_{k≤K} c_k m_{k,i}` with `m_k = E[ρ^k]`,
//! `m_{k,i} = E[Y_i² ρ^k]`. The moments come from generating functions:
//! `E[e^{tρ}] = Π (1 − 2t s_j)^{−1/2} = Σ μ_k t^k` (`m_k = k! μ_k`), whose logarithm is
//! `Σ_l q_l t^l/(2l)` with `q_l = Σ_j (2 s_j)^l`, so `μ_0 = 1`,
//! `μ_k = (1/2k) Σ_{l=1..k} q_l μ_{k−l}`; and `E[Y_i² e^{tρ}] = E[e^{tρ}] s_i/(1 − 2t s_i)`
//! (the tilted variance), so `ν_k = m_{k,i}/k!` obey `ν_0 = s_i`, `ν_k = s_i μ_k + 2 s_i ν_{k−1}`.
//! With `b_k = c_k k! = (2k − 1)!!/2^k` (`b_0 = 1`, `b_k = b_{k−1}(2k − 1)/2`):
//! `T̂ = Σ b_k μ_k`, `Û_i = Σ b_k ν_k`. Every term is positive (`T̂ ≥ 1`, `Û_i ≥ s_i`).
//!
//! # The error bound
//!
//! Write `P_K(ρ) = Σ_{k≤K} c_k ρ^k`. Then
//! `T − T̂ = X1 + X2 − X3` with (all three non-negative)
//!
//! * `X1 = E[(h − P_K)(ρ) 1{ρ ≤ ½}]`: there `h − P_K = ρ^{K+1} Σ_{k>K} c_k ρ^{k−K−1}` and, `c_k`
//!   non-increasing, the sum is at most `c_{K+1} Σ_j 2^{−j} = 2 c_{K+1}`: `X1 ≤ e1 = 2 b_{K+1}
//!   μ_{K+1}` (the truncation).
//! * `X2 = E[h(ρ) 1{½ < ρ < 1}]` (the integrable singularity at `r = 1`): in polar coordinates
//!   `y = rθ`, `Σ a_i y_i² = r² q(θ)`, `q ≥ a_min`; for `n ≥ 2`, `r^{n−1} ≤ r` and
//!   `e^{−r²q} ≤ e^{−q/2}` on the shell, so the radial integral is at most
//!   `e^{−q/2} ∫_{1/√2}^1 r (1 − r²)^{−1/2} dr = e^{−q/2}/√2`, against the whole Gaussian's
//!   `∫_0^∞ e^{−r²q} r^{n−1} dr = Γ(n/2)/(2 q^{n/2})`. Their ratio `√2 q^{n/2} e^{−q/2}/Γ(n/2)`
//!   decreases for `q > n`, so (integrating over θ) `X2 ≤ e2 = √2 a_min^{n/2} e^{−a_min/2}/Γ(n/2)`.
//! * `X3 = E[P_K(ρ) 1{ρ > ½}]` (the Gaussian mass the series counts beyond the ball): with
//!   `1{ρ > ½} ≤ e^{t(ρ − ½)}`, `t = θ a_min`, `E[ρ^k e^{tρ}] = Π(1 − 2t s_j)^{−1/2} m_k(s̃)`
//!   with the tilted variances `s̃_j = s_j/(1 − 2t s_j) ≤ s_j/(1 − θ)`; `m_k` is a polynomial
//!   with non-negative coefficients, homogeneous of degree k, so
//!   `X3 ≤ e3 = (1 − θ)^{−n/2} e^{−θ a_min/2} Σ_{k≤K} b_k (1 − θ)^{−k} μ_k`, here `θ = 7/8`.
//!
//! So `|T − T̂| ≤ e1 + e2 + e3 =: δ_T T̂`. For `U_i` the same three steps with the factor `y_i²`
//! give `e1 = 2 b_{K+1} ν_{K+1}`, `e2 = s_i √2 a_min^{n/2+1} e^{−a_min/2}/Γ(n/2 + 1)` (the
//! radial power is `r^{n+1}`; `y_i² = r² θ_i² ≤ θ_i²` on the shell; the ratio decreases for
//! `q > n + 2`) and `e3 = (1 − θ)^{−n/2} e^{−θ a_min/2} Σ b_k (1 − θ)^{−k−1} ν_k` (degree
//! `k + 1`): `|U_i − Û_i| ≤ δ_i Û_i`. Hence `|ω̂_i/ω_i − 1| ≤ (δ_T + δ_i)/(1 − δ_i)` for
//! `i < n`, `|ω̂_{d−1} − ω_{d−1}| ≤ Σ_{i<n} ω̂_i (δ_T + δ_i)/(1 − δ_i)` (relative: divided by
//! `ω̂_{d−1} ≥ ½`), and `|log T̂ − log T| ≤ δ_T/(1 − δ_T)`. [`evaluate`] returns the series only
//! where the largest of these is at most [`TOL`]; that is a bound on the mathematics, to which
//! the rounding of the evaluation adds a few ulp.
//!
//! The series is asymptotic (the terms `b_k μ_k ~ (2k s)^k` shrink while `k < a_min`), so the
//! truncation alone reaches [`TOL`] for `a_min` from about 50; the tails `e2, e3 ~ e^{−a_min/2}`
//! decide the switch-over: the series is used from `a_min = 96` (d = 3) and `99` (d = 4) on (`tests` locate it). Derivation also in
//! `docs/design.md` (§ "d = 3, 4: the concentrated series"). `src/mle/asymptotic.rs` holds the
//! series of `1/ω_i` to a fixed order (no bound) that steers the MLE's Newton steps.

/// The largest accepted error bound of the series (relative, on every `ω_i`; absolute on
/// `log F`). The quadrature it replaces is accurate to about 1e-15 (measured: max relative Δω
/// 1.3e-15 against a much finer rule over 40 000 z, 6e-16 against 65-digit references at
/// |z| ≥ 1e10; `docs/accuracy/normalization.md`), with a truncation of its own of 4e-18; the
/// series is used only where its bound is ten times below that.
pub(crate) const TOL: f64 = 1e-16;

/// Below this smallest concentration `a_min = −z_{d−2}` the tails alone exceed [`TOL`]
/// (`e2 > 1e-16` for `a_min < 90`), so the series is not tried.
const MIN_A: f64 = 80.0;

/// Above this largest concentration `s_i = 1/(2a_i)` would come near the subnormal range and
/// lose relative accuracy; the quadrature keeps it (down to `ω_i ≈ 3e-309`).
const MAX_A: f64 = 1e300;

/// The most terms summed; more are never needed once `a_min ≥ MIN_A` (the truncation meets
/// its share of [`TOL`] within about 30 terms at `a_min = 80`, fewer than 10 from 2000 up).
const MAX_TERMS: usize = 48;

/// `1/(2k)` for `k = 1..=MAX_TERMS` (entry 0 unused): the recursion of `μ_k` multiplies
/// instead of dividing (a division in its dependency chain per term).
const INV_2K: [f64; MAX_TERMS + 1] = {
    let mut t = [0.0; MAX_TERMS + 1];
    let mut k = 1;
    while k <= MAX_TERMS {
        t[k] = 1.0 / (2 * k) as f64;
        k += 1;
    }
    t
};

/// `1/(1 − θ)` of the tilt in the bound `e3` (θ = 7/8).
const TILT: f64 = 8.0;

/// The series' result: `log F`, `ω` (sorted order, length d) and the bound.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Series {
    /// `log F(z)`.
    pub log_f: f64,
    /// `ω_i = E[x_i²]`, `d` entries.
    pub omega: [f64; 4],
    /// The largest of the bounds on `|ω̂_i/ω_i − 1|` (every i) and on `|Δ log F|`.
    pub bound: f64,
    /// Terms summed (`K + 1`; read by the tests).
    #[cfg_attr(not(test), allow(dead_code))]
    pub terms: usize,
}

/// The series for canonical `z` of length 3 or 4, with its bound; `None` where it does not
/// apply (other d, `a_min < MIN_A`, `a_max > MAX_A`) or its bound exceeds [`TOL`]. `log F` only
/// `with_log_f` (otherwise 0: ω alone saves the logarithms).
pub(crate) fn evaluate(z: &[f64], with_log_f: bool) -> Option<Series> {
    let series = evaluate_unchecked(z, with_log_f)?;
    (series.bound <= TOL).then_some(series)
}

/// Beyond this `a_min` the tails `e2, e3` are below 1e-300 (`e^{−7a_min/16}` underflows) and
/// are not evaluated (two exponentials saved).
const TAILS_VANISH: f64 = 1800.0;

/// [`evaluate`] without the comparison of the bound with [`TOL`] (for the tests: the bound
/// where the series is refused).
pub(crate) fn evaluate_unchecked(z: &[f64], with_log_f: bool) -> Option<Series> {
    let d = z.len();
    if !(d == 3 || d == 4) {
        return None;
    }
    let n = d - 1;
    // ascending: a_0 is the largest, a_{n−1} the smallest concentration
    let (a_max, a_min) = (-z[0], -z[n - 1]);
    // (also refuses NaN)
    if !(a_min >= MIN_A && a_max <= MAX_A) {
        return None;
    }
    let mut s = [0.0f64; 3];
    let mut two_s = [0.0f64; 3];
    for i in 0..n {
        s[i] = 0.5 / -z[i];
        two_s[i] = 2.0 * s[i];
    }
    // q_l = Σ (2 s_j)^l, μ_k, ν_k (per i), accumulated with the terms b_k μ_k, b_k ν_k
    let mut q = [0.0f64; MAX_TERMS + 1];
    let mut mu = [0.0f64; MAX_TERMS + 1];
    let mut pw = two_s;
    mu[0] = 1.0;
    let mut nu = s;
    let mut b = 1.0f64;
    let mut t_minus_1 = 0.0f64; // T̂ − 1 (the k ≥ 1 terms)
    let mut u = s; // Û_i
    let mut tilt = 1.0f64; // 8^k
    let mut tail_t = 1.0f64; // Σ b_k 8^k μ_k
    let mut tail_u = s; // Σ b_k 8^k ν_k (times 8 at the end)
    let mut trunc_t;
    let mut trunc_u = [0.0f64; 3];
    let mut k = 0usize;
    loop {
        // the next orders: q_{k+1}, μ_{k+1}, ν_{k+1}, b_{k+1}
        let kn = k + 1;
        q[kn] = pw[..n].iter().sum();
        for p in pw[..n].iter_mut().zip(&two_s[..n]) {
            *p.0 *= p.1;
        }
        let mut acc = 0.0;
        for l in 1..=kn {
            acc += q[l] * mu[kn - l];
        }
        mu[kn] = acc * INV_2K[kn];
        let mut nu_next = [0.0f64; 3];
        for i in 0..n {
            nu_next[i] = s[i] * mu[kn] + two_s[i] * nu[i];
        }
        let b_next = b * (2 * kn - 1) as f64 * 0.5;
        // stop at K = k once the truncation bound e1 = 2 b_{K+1}(μ, ν)_{K+1} is below a
        // quarter of TOL relative to the partial sums (which only grow)
        trunc_t = 2.0 * b_next * mu[kn];
        let mut done = trunc_t <= 0.25 * TOL * (1.0 + t_minus_1);
        for i in 0..n {
            trunc_u[i] = 2.0 * b_next * nu_next[i];
            done &= trunc_u[i] <= 0.25 * TOL * u[i];
        }
        if done || kn == MAX_TERMS {
            break;
        }
        k = kn;
        b = b_next;
        tilt *= TILT;
        t_minus_1 += b * mu[k];
        tail_t += b * tilt * mu[k];
        nu = nu_next;
        for i in 0..n {
            u[i] += b * nu[i];
            tail_u[i] += b * tilt * nu[i];
        }
    }
    let t_hat = 1.0 + t_minus_1;
    let half_n = 0.5 * n as f64;
    // the tails e2, e3 (in log space: a_min^{n/2} overflows for a_min near 1e300); beyond
    // TAILS_VANISH e2 ≤ √2 a^{5/2} e^{−a/2} < 1e-380 and e3 ≤ 8^{5/2} e^{−7a/16} Σ… < 1e-330
    // (the sums Σ b_k 8^k μ_k are below 2 there): zero to every digit that TOL can see
    let (e2_t, e2_u, tilt_pref) = if a_min < TAILS_VANISH {
        let ln_a = a_min.ln();
        // ln(√2/Γ(n/2)): n = 2: ln √2; n = 3: ln(√2/(√π/2))
        let ln_c = if n == 2 {
            0.5 * std::f64::consts::LN_2
        } else {
            0.5 * std::f64::consts::LN_2 + std::f64::consts::LN_2 - 0.5 * std::f64::consts::PI.ln()
        };
        let e2_t = (half_n * ln_a - 0.5 * a_min + ln_c).exp();
        // the same with a_min^{n/2+1}/Γ(n/2+1): times a_min/(n/2)
        (
            e2_t,
            e2_t * a_min / half_n,
            (half_n * TILT.ln() - (1.0 - 1.0 / TILT) * 0.5 * a_min).exp(),
        )
    } else {
        (0.0, 0.0, 0.0)
    };
    // 1/(1 − δ) ≤ 1 + 2δ for δ ≤ ½ (no divisions but the two reciprocals); a δ above ½
    // makes the bound infinite
    let widen = |delta: f64| {
        if delta <= 0.5 {
            1.0 + 2.0 * delta
        } else {
            f64::INFINITY
        }
    };
    let inv_t = 1.0 / t_hat;
    let delta_t = (trunc_t + e2_t + tilt_pref * tail_t) * inv_t;
    let mut out = Series {
        log_f: 0.0,
        omega: [0.0; 4],
        bound: delta_t * widen(delta_t),
        terms: k + 1,
    };
    let mut sum = 0.0;
    let mut last_err = 0.0;
    for i in 0..n {
        let delta_u = (trunc_u[i] + e2_u * s[i] + tilt_pref * TILT * tail_u[i]) / u[i];
        let rel = (delta_t + delta_u) * widen(delta_u);
        let w = u[i] * inv_t;
        out.omega[i] = w;
        sum += w;
        last_err += w * rel;
        out.bound = out.bound.max(rel);
    }
    out.omega[n] = 1.0 - sum;
    // relative to ω_{d−1} ≥ 1 − Σ 1/(2 a_i) > 0.98 (a_i ≥ MIN_A): at most twice the error
    out.bound = out.bound.max(2.0 * last_err);
    if !with_log_f {
        return Some(out);
    }
    // log F = log 2 + (n/2) log π − ½ Σ log a_i + log T̂
    let mut log_f = std::f64::consts::LN_2 + half_n * std::f64::consts::PI.ln();
    for &zi in &z[..n] {
        log_f -= 0.5 * (-zi).ln();
    }
    out.log_f = log_f + t_minus_1.ln_1p();
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::normalization::quadrature::{log_f_sorted_fine, log_f_sorted_on, Path};
    use rand::{Rng, SeedableRng};

    /// The quadrature (production rule and kernel) on sorted `z`: `log F`, `ω`.
    fn quadrature(z: &[f64]) -> (f64, Vec<f64>) {
        let mut w = vec![0.0; z.len()];
        let lf = log_f_sorted_on(Path::detected(), z, Some(&mut w), None).unwrap();
        (lf, w)
    }

    /// The much finer rule (Gauss–Legendre 30, a ~4× denser layout, truncation at e^{−80}).
    fn fine(z: &[f64]) -> (f64, Vec<f64>) {
        let mut w = vec![0.0; z.len()];
        let lf = log_f_sorted_fine(z, &mut w, None).unwrap();
        (lf, w)
    }

    /// A random canonical z of dimension d whose concentrations lie between `lo` and `hi`
    /// (log-uniform), some of them tied or nearly so.
    fn random_z(rng: &mut impl Rng, d: usize, lo: f64, hi: f64) -> Vec<f64> {
        let mut a: Vec<f64> = (0..d - 1)
            .map(|_| (rng.gen_range(lo.ln()..hi.ln())).exp())
            .collect();
        match rng.gen_range(0..4) {
            0 => a[1] = a[0],                                   // tie
            1 => a[1] = a[0] * (1.0 + 1e-9 * rng.gen::<f64>()), // near tie
            2 => {
                // all near the largest
                let a0 = a[0];
                for v in a.iter_mut() {
                    *v = a0 * (1.0 + 1e-3 * rng.gen::<f64>());
                }
            }
            _ => {}
        }
        let mut z: Vec<f64> = a.iter().map(|v| -v).collect();
        z.sort_by(f64::total_cmp);
        z.push(0.0);
        z
    }

    /// The largest relative difference of ω and the absolute difference of log F.
    fn diff(s: &Series, lf: f64, w: &[f64]) -> (f64, f64) {
        let dw = w
            .iter()
            .zip(&s.omega)
            .map(|(a, b)| (b / a - 1.0).abs())
            .fold(0.0, f64::max);
        ((s.log_f - lf).abs() / lf.abs().max(1.0), dw)
    }

    /// Over the whole range where the series is used (random z, d = 3, 4, concentrations from
    /// the switch-over to 1e12, anisotropic, tied and near-tied): within its bound plus
    /// rounding of the quadrature (the quadrature's own measured error, about 1e-15, dominates)
    /// and the much finer rule.
    #[test]
    fn series_matches_the_quadrature_where_used() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(35);
        let (mut max_w, mut max_lf, mut max_w_fine, mut used, mut refused) =
            (0.0f64, 0.0f64, 0.0f64, 0, 0);
        for trial in 0..6000 {
            let d = 3 + trial % 2;
            let (lo, hi) = [
                (60.0, 200.0),
                (95.0, 1e3),
                (100.0, 1e4),
                (1e3, 1e6),
                (1e3, 1e12),
                (60.0, 1e12),
            ][(trial / 2) % 6];
            let z = random_z(&mut rng, d, lo, hi);
            let Some(s) = evaluate(&z, true) else {
                refused += 1;
                continue;
            };
            used += 1;
            assert!(s.bound <= TOL && s.terms <= MAX_TERMS);
            let (lf, w) = quadrature(&z);
            let (dl, dw) = diff(&s, lf, &w);
            assert!(
                dw <= 3e-15 && dl <= 2e-15,
                "z = {z:?}: Δω {dw:e}, Δlog F {dl:e}"
            );
            max_w = max_w.max(dw);
            max_lf = max_lf.max(dl);
            if trial % 10 == 0 {
                let (lf, w) = fine(&z);
                let (dl, dw) = diff(&s, lf, &w);
                assert!(
                    dw <= 3e-15 && dl <= 2e-15,
                    "z = {z:?}: Δω {dw:e}, Δlog F {dl:e}"
                );
                max_w_fine = max_w_fine.max(dw);
            }
            let sum: f64 = s.omega[..d].iter().sum();
            assert!((sum - 1.0).abs() <= 2.0 * f64::EPSILON, "Σω = {sum}");
        }
        println!(
            "used {used}, refused {refused}: max rel Δω {max_w:e} (fine rule {max_w_fine:e}), \
             max Δlog F {max_lf:e}"
        );
        assert!(used > 3000 && refused > 100);
    }

    /// The switch-over: the series is refused exactly where its bound exceeds TOL, which is
    /// below a_min ≈ 95 (the tails `e^{−a_min/2}`), and used above; the refused bound grows as
    /// a_min falls, and the series there still agrees with the quadrature within its bound
    /// (the bound is not vacuous).
    #[test]
    fn switch_over_falls_back_where_the_bound_fails() {
        for base in [
            &[-3.0, -1.0, 0.0][..],
            &[-1.0, -1.0, 0.0],
            &[-50.0, -2.0, -1.0, 0.0],
        ] {
            let mut switch = None;
            for a_min in (80..=140).rev() {
                let z: Vec<f64> = base.iter().map(|v| v * a_min as f64).collect();
                let s = evaluate_unchecked(&z, true).unwrap();
                assert_eq!(evaluate(&z, true).is_some(), s.bound <= TOL);
                // once refused, refused for every smaller a_min
                assert!(
                    switch.is_none() || s.bound > TOL,
                    "{z:?}: used below the switch"
                );
                if s.bound > TOL && switch.is_none() {
                    switch = Some(a_min);
                }
                let (lf, w) = fine(&z);
                let (dl, dw) = diff(&s, lf, &w);
                assert!(dw <= s.bound + 3e-15 && dl <= s.bound + 2e-15);
            }
            let switch = switch.expect("the bound fails somewhere above a_min = 80");
            println!("{base:?}: the series is refused from a_min = {switch} down");
            assert!((85..=110).contains(&switch), "{switch}");
        }
        // not below MIN_A, nor beyond MAX_A, nor for d = 2 or 5, nor with a tie at the mode
        assert!(evaluate_unchecked(&[-1e3, -79.0, 0.0], true).is_none());
        assert!(evaluate_unchecked(&[-1e301, -1e3, 0.0], true).is_none());
        assert!(evaluate_unchecked(&[-1e3, 0.0], true).is_none());
        assert!(evaluate_unchecked(&[-1e3, -1e3, -1e3, -1e3, 0.0], true).is_none());
        assert!(evaluate_unchecked(&[-1e3, 0.0, 0.0], true).is_none());
    }

    /// The terms fall off fast where the AHRS works (every concentration in the thousands); ω
    /// without log F is the same.
    #[test]
    fn few_terms_at_the_filters_concentrations() {
        let z = [-9000.0, -6500.0, -3000.0, 0.0];
        let s = evaluate(&z, true).unwrap();
        assert!(s.terms <= 8, "{}", s.terms);
        // ω alone is the same ω
        assert_eq!(evaluate(&z, false).unwrap().omega, s.omega);
        let s = evaluate(&[-1e12, -1e12, 0.0], true).unwrap();
        assert!(s.terms <= 3, "{}", s.terms);
    }
}
