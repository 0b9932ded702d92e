//! The gyroscope bias as a Gaussian coupled to the orientation error, and the process noise it
//! and the gyroscope put on the orientation.
//!
//! Errors are "truth relative to the estimate": the orientation error `θ` is the body-frame
//! rotation vector with `q_true = q̂ ⊗ exp(θ/2)`, the bias error `e = b_true − b̂` (rad/s, body
//! frame). With the body-frame increment `R` of a gyroscope sample (body k → body k+1) and the
//! sample time `dt`, `θ' = Rᵀ θ − dt·e + n` (`n` the gyroscope's own noise). The AHRS keeps
//!
//! - the marginal of `θ` as the Bingham state (its concentrations give the precision `Λ` of `θ`
//!   at the mode: `Λ = Σ_i (−z_i/2) u_i u_iᵀ`, `u_i` the vector part of `q̂* ⊗ m_i`);
//! - `b̂`, `P = Cov(e)` and the cross-covariance `C = Cov(θ, e)` here.
//!
//! Per sample `C ← RᵀC − dt·P`, `P ← P + drift·dt`, and the orientation's covariance grows by
//! `Q = q·dt·I − dt (RᵀC + CᵀR) + dt² P`: the gyroscope noise plus what the bias's uncertainty
//! adds. The growth is accumulated (turned into each new body frame) until the next correction,
//! where the Bingham state is composed with a noise of that covariance. After a Bayes update
//! that moved the mode by `μ` (body frame of the prior mode) the Gaussian conditioning on `θ`
//! gives, exactly for a Gaussian joint, `b̂ ← b̂ + CᵀΛ⁻μ`, `P ← P − CᵀΛ⁻C + KᵀΣ⁺K` and
//! `C ← Σ⁺K`, `K = Λ⁻C`, `Σ⁺` the (pseudo-)inverse of the posterior precision. This is a
//! Kalman filter of the bias driven by the same corrections the Bingham state makes; its gain
//! comes from the covariances, so a large bias is learned in seconds of motion and the
//! orientation's spread includes what the bias's uncertainty adds.

use nalgebra::{Matrix3, Matrix4, SymmetricEigen, Vector3, Vector4};

use crate::quaternion::q4;

/// The bias estimate with its covariance and its coupling to the orientation error.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct BiasState {
    /// `b̂` (rad/s, body frame).
    pub(super) b: Vector3<f64>,
    /// `P = Cov(b_true − b̂)` ((rad/s)²).
    pub(super) p: Matrix3<f64>,
    /// `C = Cov(θ, b_true − b̂)` (rad²/s), body frame of the current sample.
    pub(super) c: Matrix3<f64>,
    /// The orientation covariance added since the last correction (rad², current body frame).
    pub(super) pending: Matrix3<f64>,
}

impl BiasState {
    /// No bias, standard deviation `std` (rad/s) per axis, no coupling.
    pub(super) fn new(std: f64) -> BiasState {
        BiasState {
            b: Vector3::zeros(),
            p: Matrix3::identity() * (std * std),
            c: Matrix3::zeros(),
            pending: Matrix3::zeros(),
        }
    }

    /// One gyroscope sample: `r` the rotation matrix of the body increment, `q` the gyroscope's
    /// own noise added to the orientation (rad², isotropic), `drift` the bias's random-walk
    /// variance added ((rad/s)²).
    pub(super) fn predict(&mut self, r: &Matrix3<f64>, dt: f64, q: f64, drift: f64) {
        let rt = r.transpose();
        let rc = rt * self.c;
        let coupling = -(rc + rc.transpose()) * dt + self.p * (dt * dt);
        self.pending = rt * self.pending * r + coupling + Matrix3::identity() * q;
        // beyond a few rad² the noise is uniform anyway (see `noise_moment`): keep it finite
        let tr = self.pending.trace();
        if tr > 3.0 {
            self.pending *= 3.0 / tr;
        }
        self.c = rc - self.p * dt;
        self.p += Matrix3::identity() * drift;
    }

    /// The pending covariance made positive semi-definite (negative parts, which the coupling
    /// term can have under fast rotation, dropped: the conservative side) and reset to zero.
    pub(super) fn take_pending(&mut self) -> Matrix3<f64> {
        let n = psd(&self.pending);
        self.pending = Matrix3::zeros();
        n
    }

    /// The Gaussian conditioning after a Bayes update (see the module documentation).
    /// `lam_prior` the prior precision of `θ`, `mu` the move of the mode, `sigma_post` the
    /// posterior covariance (pseudo-inverse of its precision); `learn`: whether the estimate
    /// moves (false: the bias is estimated at rest only, the coupling still widens the state).
    pub(super) fn correct(
        &mut self,
        lam_prior: &Matrix3<f64>,
        mu: &Vector3<f64>,
        sigma_post: &Matrix3<f64>,
        learn: bool,
    ) {
        if !learn {
            return;
        }
        let k = lam_prior * self.c;
        self.b += k.transpose() * mu;
        let p = self.p - self.c.transpose() * k + k.transpose() * sigma_post * k;
        self.p = psd(&p);
        self.c = sigma_post * k;
    }

    /// A direct measurement `y` of the bias at rest (rad/s) with variance `r` ((rad/s)² per
    /// axis): the Kalman update `K = P (P + r I)⁻¹`, `b̂ ← b̂ + K (y − b̂)`, `P ← (I − K) P`,
    /// `C ← C (I − K)ᵀ` (the bias error becomes `(I − K) e − K v`).
    pub(super) fn rest(&mut self, y: &Vector3<f64>, r: f64) {
        let Some(s_inv) = (self.p + Matrix3::identity() * r).try_inverse() else {
            return;
        };
        let k = self.p * s_inv;
        self.b += k * (y - self.b);
        let ik = Matrix3::identity() - k;
        self.p = psd(&(ik * self.p));
        self.c *= ik.transpose();
    }

    /// Forgets the coupling of the bias to the orientation error (`C = 0`): what a correction
    /// that did not teach the bias taught the orientation must not reach the bias through the
    /// next corrections (module `ahrs`, the recovery rule).
    pub(super) fn decouple(&mut self) {
        self.c = Matrix3::zeros();
    }

    /// The estimate clipped to `±max` per axis.
    pub(super) fn clip(&mut self, max: f64) {
        for v in self.b.iter_mut() {
            *v = v.clamp(-max, max);
        }
    }
}

/// `a` symmetrized with negative eigenvalues raised to zero. A positive definite `a` (all
/// leading principal minors positive, the common case) is returned without an eigensolve.
pub(super) fn psd(a: &Matrix3<f64>) -> Matrix3<f64> {
    let s = (a + a.transpose()) * 0.5;
    let m1 = s[(0, 0)];
    let m2 = s[(0, 0)] * s[(1, 1)] - s[(0, 1)] * s[(1, 0)];
    if m1 > 0.0 && m2 > 0.0 && s.determinant() > 0.0 {
        return s;
    }
    let e = SymmetricEigen::new(s);
    if e.eigenvalues.iter().all(|&v| v >= 0.0) {
        return s;
    }
    let l = e.eigenvalues.map(|v| v.max(0.0));
    e.eigenvectors * Matrix3::from_diagonal(&l) * e.eigenvectors.transpose()
}

/// The body-frame precision `Λ` of the orientation error at the mode of `Bingham(M, z)`
/// (Laplace: `Λ = Σ_i (−z_i/2) u_i u_iᵀ`).
pub(super) fn precision(m: &Matrix4<f64>, z: &Vector4<f64>) -> Matrix3<f64> {
    let mode = m.column(3);
    let mut lam = Matrix3::zeros();
    for (i, u) in principal_directions(m, &[mode[0], mode[1], mode[2], mode[3]])
        .iter()
        .enumerate()
    {
        lam += u * u.transpose() * (-(z[i] - z[3]) / 2.0).max(0.0);
    }
    lam
}

/// The body-frame directions of the first three columns of `m` at the orientation `q` (the
/// mode): `u_i` the vector part of `q* ⊗ m_i`, orthonormal when `m` is orthogonal and `q` its
/// last column.
pub(super) fn principal_directions(m: &Matrix4<f64>, q: &[f64; 4]) -> [Vector3<f64>; 3] {
    let qc = q4::conj(q);
    std::array::from_fn(|i| {
        let c = m.column(i);
        let v = q4::mul(&qc, &[c[0], c[1], c[2], c[3]]);
        Vector3::new(v[1], v[2], v[3])
    })
}

/// The body-frame precision `H` that the likelihood `exp(qᵀ E q)` puts on the orientation
/// error at `q` (its Hessian in `θ`, `q ⊗ exp(θ/2)`): with `A = L(q)ᵀ E L(q)`,
/// `H = −½ (A_vv − A_00 I)`, symmetrized (a measurement far from the mode can make it
/// indefinite; [`pinv`] of the sum with the prior's precision drops such directions).
pub(super) fn evidence_precision(q: &[f64; 4], e: &Matrix4<f64>) -> Matrix3<f64> {
    let (w, x, y, z) = (q[0], q[1], q[2], q[3]);
    let l = Matrix4::new(w, -x, -y, -z, x, w, -z, y, y, z, w, -x, z, -y, x, w);
    let a = l.transpose() * e * l;
    let h = -(a.fixed_view::<3, 3>(1, 1).into_owned() - Matrix3::identity() * a[(0, 0)]) * 0.5;
    (h + h.transpose()) * 0.5
}

/// The pseudo-inverse of a symmetric `a` restricted to its positive part (eigenvalues below
/// `1e-9` of the largest, and negative ones, count as zero: unobserved directions).
pub(super) fn pinv(a: &Matrix3<f64>) -> Matrix3<f64> {
    let s = (a + a.transpose()) * 0.5;
    if let Some(inv) = well_conditioned_inverse(&s) {
        return inv;
    }
    let e = SymmetricEigen::new(s);
    let top = e.eigenvalues.iter().fold(0.0f64, |m, &v| m.max(v));
    let l = e.eigenvalues.map(|v| {
        if v > 1e-9 * top && v > 0.0 {
            1.0 / v
        } else {
            0.0
        }
    });
    e.eigenvectors * Matrix3::from_diagonal(&l) * e.eigenvectors.transpose()
}

/// Below this bound on the condition number `tr(A)·tr(A⁻¹)` a positive definite `A` has no
/// eigenvalue under `1e-9` of its largest (with a factor 10 to spare for the rounding of the
/// traces), so [`pinv`] is its inverse.
const PINV_DIRECT: f64 = 1e8;

/// The inverse of a symmetric `s` by Cholesky when `s` is positive definite and
/// `tr(s)·tr(s⁻¹) < PINV_DIRECT`: then every eigenvalue `λ_i ≥ 1/tr(s⁻¹) > 1e-9·tr(s) ≥
/// 1e-9·λ_max`, so the pseudo-inverse of [`pinv`] keeps every direction and is the inverse
/// (the same matrix to rounding, without the eigendecomposition: a correction's commonest
/// case, every direction observed). `None` otherwise (not positive definite, nearly singular
/// or non-finite): [`pinv`] then takes the eigendecomposition.
fn well_conditioned_inverse(s: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    // s = L Lᵀ
    let l00 = s[(0, 0)];
    if l00.is_nan() || l00 <= 0.0 {
        return None;
    }
    let l00 = l00.sqrt();
    let l10 = s[(1, 0)] / l00;
    let l20 = s[(2, 0)] / l00;
    let d1 = s[(1, 1)] - l10 * l10;
    if d1.is_nan() || d1 <= 0.0 {
        return None;
    }
    let l11 = d1.sqrt();
    let l21 = (s[(2, 1)] - l20 * l10) / l11;
    let d2 = s[(2, 2)] - l20 * l20 - l21 * l21;
    if d2.is_nan() || d2 <= 0.0 {
        return None;
    }
    let l22 = d2.sqrt();
    // W = L⁻¹ (lower triangular), s⁻¹ = Wᵀ W
    let w00 = 1.0 / l00;
    let w11 = 1.0 / l11;
    let w22 = 1.0 / l22;
    let w10 = -l10 * w00 * w11;
    let w21 = -l21 * w11 * w22;
    let w20 = -(l20 * w00 + l21 * w10) * w22;
    let i00 = w00 * w00 + w10 * w10 + w20 * w20;
    let i11 = w11 * w11 + w21 * w21;
    let i22 = w22 * w22;
    let i10 = w10 * w11 + w20 * w21;
    let i20 = w20 * w22;
    let i21 = w21 * w22;
    let cond = s.trace() * (i00 + i11 + i22);
    if cond.is_nan() || cond >= PINV_DIRECT {
        return None;
    }
    Some(Matrix3::new(
        i00, i10, i20, //
        i10, i11, i21, //
        i20, i21, i22,
    ))
}

/// The second moment of a rotation noise `exp(θ/2)` whose rotation vector has the covariance
/// `n` (rad², positive semi-definite): `[[1 − tr n/4, 0], [0, n/4]]` — the moment of
/// `exp(θ/2)`, `θ ~ N(0, n)`, to second order in `θ`, and the definition of the process noise
/// (a Bingham distribution with this moment). Eigenvalues of `n` above 1 rad² are lowered to 1
/// (a noise that wide is near uniform anyway), so the moment stays positive definite.
pub(super) fn noise_moment(n: &Matrix3<f64>) -> Matrix4<f64> {
    // a positive semi-definite n with trace ≤ 1 has every eigenvalue ≤ 1: no eigensolve
    let n = if n.trace() <= 1.0 {
        *n
    } else {
        let e = SymmetricEigen::new(*n);
        let l = e.eigenvalues.map(|v| v.clamp(0.0, 1.0));
        e.eigenvectors * Matrix3::from_diagonal(&l) * e.eigenvectors.transpose()
    };
    let mut s = Matrix4::zeros();
    s[(0, 0)] = 1.0 - n.trace() / 4.0;
    for i in 0..3 {
        for j in 0..3 {
            s[(i + 1, j + 1)] = n[(i, j)] / 4.0;
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn precision_of_a_known_state_matches_its_concentrations() {
        // Bingham with mode q̂ and concentrations −2/σ² along body axes x, y, z.
        let qh = q4::from_rotation_vector(&[0.3, -0.2, 0.5]);
        let sig = [0.1, 0.2, 0.05];
        let mut m = Matrix4::zeros();
        for i in 0..3 {
            let mut e = [0.0; 4];
            e[i + 1] = 1.0;
            let col = q4::mul(&qh, &e);
            for r in 0..4 {
                m[(r, i)] = col[r];
            }
        }
        for r in 0..4 {
            m[(r, 3)] = qh[r];
        }
        let z = Vector4::new(
            -2.0 / (sig[0] * sig[0]),
            -2.0 / (sig[1] * sig[1]),
            -2.0 / (sig[2] * sig[2]),
            0.0,
        );
        let lam = precision(&m, &z);
        let cov = pinv(&lam);
        for i in 0..3 {
            assert!((lam[(i, i)] - 1.0 / (sig[i] * sig[i])).abs() < 1e-9 * lam[(i, i)]);
            assert!((cov[(i, i)] - sig[i] * sig[i]).abs() < 1e-12);
        }
        assert!((lam * cov - Matrix3::identity()).norm() < 1e-9);
        // The likelihood exp(qᵀ E q) with E = this state's exponent has the same precision.
        let e = m * Matrix4::from_diagonal(&z) * m.transpose();
        let h = evidence_precision(&qh, &e);
        assert!((h - lam).norm() < 1e-9 * lam.norm(), "{h} vs {lam}");
    }

    #[test]
    fn pinv_direct_path_matches_the_constructed_inverse() {
        // random orthogonal bases, eigenvalues spread over 1 to 12 decades, some directions
        // zero or negative (the eigendecomposition's cases), the rest positive definite
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut direct, mut by_eigen) = (0, 0);
        for k in 0..3000 {
            let q = q4::from_rotation_vector(&[
                6.0 * uniform() - 3.0,
                6.0 * uniform() - 3.0,
                6.0 * uniform() - 3.0,
            ]);
            let r = q4::to_matrix(&q);
            let r = Matrix3::from_fn(|i, j| r[i][j]);
            let decades = 1.0 + 11.0 * uniform();
            let top = 10f64.powf(8.0 * uniform() - 2.0);
            let mut l = Vector3::from_fn(|_, _| top * 10f64.powf(-decades * uniform()));
            l[0] = top;
            match k % 10 {
                0 => l[2] = 0.0,
                1 => l[1] = -1e-3 * top,
                _ => {}
            }
            let a = r * Matrix3::from_diagonal(&l) * r.transpose();
            // the pseudo-inverse from the construction (eigenvalues below 1e-9 of the largest,
            // and negative ones, dropped)
            let inv = l.map(|v| if v > 1e-9 * top { 1.0 / v } else { 0.0 });
            let want = r * Matrix3::from_diagonal(&inv) * r.transpose();
            let got = pinv(&a);
            // the direct path (the one this test is about) within a few ulps times the
            // condition number, and only where every direction is kept; the rest goes to the
            // eigendecomposition as before
            if well_conditioned_inverse(&((a + a.transpose()) * 0.5)).is_none() {
                by_eigen += 1;
                continue;
            }
            direct += 1;
            assert!(l.iter().all(|&v| v > 1e-9 * top), "{l}");
            let cond = l.iter().fold(0.0, |m: f64, &v| m.max(v))
                / l.iter().fold(f64::INFINITY, |m: f64, &v| m.min(v));
            let err = (got - want).norm() / want.norm();
            assert!(err < 1e-14 * cond, "eigenvalues {l}: error {err:e}");
        }
        assert!(
            direct > 1000 && by_eigen > 600,
            "{direct} direct, {by_eigen} by eigen"
        );
    }

    #[test]
    fn a_bias_error_is_learned_from_the_corrections_it_causes() {
        // 1-axis check through the 3-D algebra: a constant bias error drifts θ; a perfect
        // measurement of θ then moves b̂ by CᵀΛμ.
        let mut s = BiasState::new(0.01);
        let dt = 0.01;
        for _ in 0..100 {
            s.predict(&Matrix3::identity(), dt, 1e-8, 0.0);
        }
        // C = −t·P after t = 1 s without rotation
        assert!((s.c[(0, 0)] + 1.0 * 1e-4).abs() < 1e-9);
        let n = s.take_pending();
        // variance t²P + q t
        assert!((n[(0, 0)] - (1e-4 + 1e-6)).abs() < 1e-9);
        // θ observed as −0.005 rad (true bias error +0.005 rad/s) with a precise measurement
        let lam_prior = Matrix3::identity() / n[(0, 0)];
        let sigma_post = Matrix3::identity() * 1e-10;
        s.correct(
            &lam_prior,
            &Vector3::new(-0.005, 0.0, 0.0),
            &sigma_post,
            true,
        );
        // b̂ = Cov(e,θ)/Var(θ)·θ = (−1e-4/1.01e-4)·(−0.005)
        assert!((s.b[0] - 0.005 / 1.01).abs() < 1e-9);
        assert!(s.p[(0, 0)] < 1e-4 * 0.02);
    }

    #[test]
    fn noise_moment_has_unit_trace_and_the_rotation_moments() {
        let n = Matrix3::new(0.01, 0.002, 0.0, 0.002, 0.02, 0.0, 0.0, 0.0, 0.005);
        let s = noise_moment(&n);
        assert!((s.trace() - 1.0).abs() < 1e-15);
        assert!((s[(1, 2)] - 0.0005).abs() < 1e-15);
        let big = noise_moment(&(Matrix3::identity() * 50.0));
        assert!((big[(0, 0)] - 0.25).abs() < 1e-12);
    }
}
