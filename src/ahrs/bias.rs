//! The gyroscope bias and scale error as a Gaussian coupled to the orientation error, and the
//! process noise they and the gyroscope put on the orientation.
//!
//! The gyroscope reads `ω_meas = (I + diag s) ω + b + noise`: a bias `b` (rad/s) and a scale
//! error `s` per axis (relative; misalignment is left to the process noise,
//! `gyro_scale_noise`). The rate turned by is `ω̂ = ω_meas − b̂ − diag(ŝ) ω_meas` (first order
//! in `s`, [`BiasState::rate`]). Errors are "truth relative to the estimate": the orientation
//! error `θ` is the body-frame rotation vector with `q_true = q̂ ⊗ exp(θ/2)`, the calibration
//! error `e = [b_true − b̂; s_true − ŝ]` (6: rad/s and relative, body frame). With the
//! body-frame increment `R` of a gyroscope sample (body k → body k+1), the sample time `dt` and
//! `G = [I, diag(ω)]` (3×6), `θ' = Rᵀ θ − dt·G e + n` (`n` the gyroscope's own noise): a scale
//! error turns the orientation in proportion to the rate about its axis. The AHRS keeps
//!
//! - the marginal of `θ` as the Bingham state (its concentrations give the precision `Λ` of `θ`
//!   at the mode: `Λ = Σ_i (−z_i/2) u_i u_iᵀ`, `u_i` the vector part of `q̂* ⊗ m_i`);
//! - `b̂`, `ŝ`, `P = Cov(e)` (6×6) and the cross-covariance `C = Cov(θ, e)` (3×6) here.
//!
//! `P` starts at `diag(bias_std² I, gyro_scale_std² I)`; the bias walks randomly, the scale does
//! not (a property of the sensor's calibration, changing with temperature far slower than the
//! bias). With `gyro_scale_std` 0 the scale's rows of `P` and columns of
//! `C` stay exactly zero and the filter is the bias's alone.
//!
//! Per sample `C ← RᵀC − dt·G P`, `P ← P + drift·dt` (the bias block), and the orientation's
//! covariance grows by `Q = q·dt·I − dt (RᵀC Gᵀ + G CᵀR) + dt² G P Gᵀ`: the gyroscope noise plus
//! what the bias's and the scale's uncertainty add. The growth is accumulated (turned into each new body frame) until the next correction,
//! where the Bingham state is composed with a noise of that covariance. After a Bayes update
//! that moved the mode by `μ` (body frame of the prior mode) the Gaussian conditioning on `θ`
//! gives, exactly for a Gaussian joint, `[b̂; ŝ] ← [b̂; ŝ] + CᵀΛ⁻μ`, `P ← P − CᵀΛ⁻C + KᵀΣ⁺K`
//! and `C ← Σ⁺K`, `K = Λ⁻C`, `Σ⁺` the (pseudo-)inverse of the posterior precision. This is a
//! Kalman filter of the bias and the scale driven by the same corrections the Bingham state
//! makes; its gain comes from the covariances, so a large bias is learned in seconds of motion,
//! the scale wherever the rate about an axis changes (a constant rate shows only `b + s·ω`),
//! and the orientation's spread includes what their uncertainty adds. At rest the gyroscope
//! measures the bias alone (`H = [I 0]`, [`BiasState::rest`]).

use nalgebra::allocator::Allocator;
use nalgebra::{
    DefaultAllocator, DimDiff, DimSub, Matrix3, Matrix4, Matrix6, OMatrix, SMatrix, SymmetricEigen,
    Vector3, Vector4, U1,
};

use crate::linalg::{cholesky3, forward3};
use crate::quaternion::q4;

/// The orientation error's cross-covariance with `[b; s]` (3×6).
pub(super) type Matrix3x6 = SMatrix<f64, 3, 6>;

/// The largest gyroscope scale error (per axis, relative) the estimate may reach: 5 %, above
/// the 0.5–3 % that consumer MEMS gyroscopes state at turn-on.
pub(super) const SCALE_MAX: f64 = 0.05;

/// The bias estimate with its covariance and its coupling to the orientation error.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct BiasState {
    /// `b̂` (rad/s, body frame).
    pub(super) b: Vector3<f64>,
    /// `ŝ`, the gyroscope's scale error per axis (relative: `ω_meas = (I + diag s) ω + b`).
    pub(super) s: Vector3<f64>,
    /// `P = Cov([b_true − b̂; s_true − ŝ])` (bias block (rad/s)², scale block relative²).
    pub(super) p: Matrix6<f64>,
    /// `C = Cov(θ, [b_true − b̂; s_true − ŝ])`, body frame of the current sample.
    pub(super) c: Matrix3x6,
    /// The orientation covariance added since the last correction (rad², current body frame).
    pub(super) pending: Matrix3<f64>,
}

impl BiasState {
    /// No bias, standard deviation `std` (rad/s) per axis; no scale error, standard deviation
    /// `scale_std` per axis (0: the scale is not estimated); no coupling.
    pub(super) fn new(std: f64, scale_std: f64) -> BiasState {
        let mut p = Matrix6::zeros();
        for i in 0..3 {
            p[(i, i)] = std * std;
            p[(i + 3, i + 3)] = scale_std * scale_std;
        }
        BiasState {
            b: Vector3::zeros(),
            s: Vector3::zeros(),
            p,
            c: Matrix3x6::zeros(),
            pending: Matrix3::zeros(),
        }
    }

    /// The rate `g` (rad/s) with the bias and the scale error taken out:
    /// `ω̂ = g − b̂ − diag(ŝ) g`.
    pub(super) fn rate(&self, g: &[f64; 3]) -> [f64; 3] {
        std::array::from_fn(|j| g[j] - self.b[j] - self.s[j] * g[j])
    }

    /// The bias covariance alone (the first 3×3 block of `P`).
    pub(super) fn bias_covariance(&self) -> Matrix3<f64> {
        self.p.fixed_view::<3, 3>(0, 0).into_owned()
    }

    /// The part of the orientation error's covariance (rad², body frame of the current sample)
    /// that the scale error explains, `C_s P_ss⁺ C_sᵀ` (`C_s = Cov(θ, s_true − ŝ)`, `P_ss` the
    /// scale error's covariance), as a root `X` with that part `XᵀX` (3×3: rows in the scale
    /// error's space, columns the body axes). A scale error is one constant of the sensor,
    /// whose prior (`gyro_scale_std`) the corrections barely narrow, so the heading drift it
    /// brings is as large as that prior says whatever the white noises are (module
    /// `uncertainty`). Zero without a scale prior.
    pub(super) fn scale_root(&self) -> Matrix3<f64> {
        let pss = self.p.fixed_view::<3, 3>(3, 3).into_owned();
        if pss.trace() <= 0.0 {
            return Matrix3::zeros();
        }
        let cs = self.c.fixed_view::<3, 3>(0, 3).into_owned();
        // P_ss = L Lᵀ: C_s P_ss⁻¹ C_sᵀ = XᵀX, X = L⁻¹ C_sᵀ (a triangular solve, no inverse);
        // a singular P_ss (a scale error learned exactly along a direction) by the
        // pseudo-inverse's square root
        lower_solve(&pss, &cs).unwrap_or_else(|| {
            let e = SymmetricEigen::new(pinv(&pss));
            let root = e.eigenvalues.map(|v| v.max(0.0).sqrt());
            Matrix3::from_diagonal(&root) * e.eigenvectors.transpose() * cs.transpose()
        })
    }

    /// One gyroscope sample: `r` the rotation matrix of the body increment, `w` the rate
    /// (rad/s; the scale error's effect on the orientation is `diag(w)` times it), `q` the
    /// gyroscope's own noise added to the orientation (rad², isotropic), `drift` the bias's
    /// random-walk variance added ((rad/s)²; the scale does not walk).
    pub(super) fn predict(&mut self, r: &Matrix3<f64>, w: &[f64; 3], dt: f64, q: f64, drift: f64) {
        let rt = r.transpose();
        let rc = rt * self.c;
        // G = [I, diag(w)]: θ' = Rᵀθ − dt·G e
        let p = &self.p;
        let gp = Matrix3x6::from_fn(|i, j| p[(i, j)] + w[i] * p[(i + 3, j)]);
        let rcg = Matrix3::from_fn(|i, j| rc[(i, j)] + w[j] * rc[(i, j + 3)]);
        let gpg = Matrix3::from_fn(|i, j| gp[(i, j)] + w[j] * gp[(i, j + 3)]);
        let coupling = -(rcg + rcg.transpose()) * dt + gpg * (dt * dt);
        self.pending = rt * self.pending * r + coupling + Matrix3::identity() * q;
        // beyond a few rad² the noise is uniform anyway (see `noise_moment`): keep it finite
        let tr = self.pending.trace();
        if tr > 3.0 {
            self.pending *= 3.0 / tr;
        }
        self.c = rc - gp * dt;
        for i in 0..3 {
            self.p[(i, i)] += drift;
        }
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
        let dx = k.transpose() * mu;
        self.b += dx.fixed_rows::<3>(0);
        self.s += dx.fixed_rows::<3>(3);
        let p = self.p - self.c.transpose() * k + k.transpose() * sigma_post * k;
        self.p = psd6(&p);
        self.c = sigma_post * k;
    }

    /// A direct measurement `y` of the bias at rest (rad/s) with variance `r` ((rad/s)² per
    /// axis), `H = [I 0]` (at rest the scale error has no rate to act on): the Kalman update
    /// `K = P Hᵀ (H P Hᵀ + r I)⁻¹`, `[b̂; ŝ] += K (y − b̂)`, `P ← (I − K H) P`,
    /// `C ← C (I − K H)ᵀ` (the error becomes `(I − K H) e − K v`).
    pub(super) fn rest(&mut self, y: &Vector3<f64>, r: f64) {
        let Some(s_inv) = (self.bias_covariance() + Matrix3::identity() * r).try_inverse() else {
            return;
        };
        // P Hᵀ: the first three columns of P
        let k = self.p.fixed_columns::<3>(0) * s_inv;
        let dx = k * (y - self.b);
        self.b += dx.fixed_rows::<3>(0);
        self.s += dx.fixed_rows::<3>(3);
        // (I − K H) P = P − K P[0..3, :]
        let p = self.p - k * self.p.fixed_rows::<3>(0);
        self.p = psd6(&p);
        // C (I − K H)ᵀ = C − C[:, 0..3] Kᵀ
        self.c -= self.c.fixed_columns::<3>(0) * k.transpose();
    }

    /// Forgets the coupling of the bias to the orientation error (`C = 0`): what a correction
    /// that did not teach the bias taught the orientation must not reach the bias through the
    /// next corrections (module `ahrs`, the recovery rule).
    pub(super) fn decouple(&mut self) {
        self.c = Matrix3x6::zeros();
    }

    /// The bias estimate clipped to `±max` per axis, the scale's to `±SCALE_MAX`.
    pub(super) fn clip(&mut self, max: f64) {
        for v in self.b.iter_mut() {
            *v = v.clamp(-max, max);
        }
        for v in self.s.iter_mut() {
            *v = v.clamp(-SCALE_MAX, SCALE_MAX);
        }
    }

    /// The bias block of `P` (and its coupling to the scale) scaled so that its trace is at
    /// most `cap`: rows and columns `0..3` times `√(cap/tr)`, which keeps `P` positive
    /// semi-definite.
    pub(super) fn cap_bias(&mut self, cap: f64) {
        let tr = self.p[(0, 0)] + self.p[(1, 1)] + self.p[(2, 2)];
        if tr > cap {
            let f = (cap / tr).sqrt();
            for i in 0..3 {
                self.p.row_mut(i).scale_mut(f);
                self.p.column_mut(i).scale_mut(f);
            }
        }
    }
}

/// [`psd`] for the 6×6 covariance of the bias and the scale: symmetrized, negative eigenvalues
/// raised to zero; a matrix with a Cholesky factor (the common case) without an eigensolve,
/// one without a scale part (the scale not estimated: its rows zero) as the bias block alone.
pub(super) fn psd6(a: &Matrix6<f64>) -> Matrix6<f64> {
    let s = (a + a.transpose()) * 0.5;
    if s.fixed_rows::<3>(3).iter().all(|&v| v == 0.0) {
        let mut out = Matrix6::zeros();
        out.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&psd(&s.fixed_view::<3, 3>(0, 0).into_owned()));
        return out;
    }
    if s.cholesky().is_some() {
        return s;
    }
    clip_negative(s)
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
    clip_negative(s)
}

/// The symmetric `s` with its negative eigenvalues raised to zero (`s` itself when there are
/// none), by an eigendecomposition: the path of [`psd`] and [`psd6`] when the cheap tests fail.
fn clip_negative<D>(s: OMatrix<f64, D, D>) -> OMatrix<f64, D, D>
where
    D: DimSub<U1>,
    DefaultAllocator: Allocator<D, D> + Allocator<DimDiff<D, U1>> + Allocator<D>,
    OMatrix<f64, D, D>: Copy,
{
    let e = SymmetricEigen::new(s);
    if e.eigenvalues.iter().all(|&v| v >= 0.0) {
        return s;
    }
    let l = e.eigenvalues.map(|v| v.max(0.0));
    e.eigenvectors * OMatrix::<f64, D, D>::from_diagonal(&l) * e.eigenvectors.transpose()
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

/// `X = L⁻¹ Cᵀ` (the columns `L⁻¹` times the rows of `c`), `L` the Cholesky factor of a
/// symmetric positive definite `a` ([`cholesky3`]): `c a⁻¹ cᵀ = XᵀX`. `None` unless `a` is
/// positive definite.
fn lower_solve(a: &Matrix3<f64>, c: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let l = cholesky3(a)?;
    let col = |i: usize| forward3(&l, &c.row(i).transpose());
    Some(Matrix3::from_columns(&[col(0), col(1), col(2)]))
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
        let mut s = BiasState::new(0.01, 0.0);
        let dt = 0.01;
        for _ in 0..100 {
            s.predict(&Matrix3::identity(), &[0.0; 3], dt, 1e-8, 0.0);
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
    fn a_scale_error_is_learned_from_the_corrections_it_causes() {
        // a constant rotation at w rad/s about x for t = 1 s: a scale error s turns θ_x by
        // −t·w·s; the rotation about x leaves θ_x's row apart from y and z, so the x-axis
        // algebra is scalar: C = −t·[σ_b², w σ_s²] (bias, scale), Var θ_x = q t + t²(σ_b² +
        // w² σ_s²), and a perfect measurement θ_x = μ moves [b̂, ŝ] by C/Var·μ
        let (sb, ss, w, dt) = (0.01, 0.01, 2.0, 0.01);
        let mut st = BiasState::new(sb, ss);
        let dq = q4::from_rotation_vector(&[w * dt, 0.0, 0.0]);
        let r = q4::to_matrix(&dq);
        let r = Matrix3::from_fn(|i, j| r[i][j]);
        for _ in 0..100 {
            st.predict(&r, &[w, 0.0, 0.0], dt, 1e-8, 0.0);
        }
        assert!((st.c[(0, 0)] + sb * sb).abs() < 1e-12, "{}", st.c);
        assert!((st.c[(0, 3)] + w * ss * ss).abs() < 1e-12, "{}", st.c);
        // the scale error explains (t w σ_s)² of θ_x's variance, and nothing else
        let x = st.scale_root();
        let m = x.transpose() * x;
        assert!((m[(0, 0)] - w * w * ss * ss).abs() < 1e-15, "{m}");
        assert!(
            m.iter().enumerate().all(|(k, v)| k == 0 || v.abs() < 1e-18),
            "{m}"
        );
        let n = st.take_pending();
        let var = 1e-6 + sb * sb + w * w * ss * ss;
        assert!((n[(0, 0)] - var).abs() < 1e-12, "{n}");
        // true scale error 0.5 %, no bias error: θ_x = −t·w·s
        let s_true = 0.005;
        let mu = Vector3::new(-w * s_true, 0.0, 0.0);
        st.correct(&pinv(&n), &mu, &(Matrix3::identity() * 1e-10), true);
        let want_s = w * w * ss * ss / var * s_true;
        let want_b = sb * sb / var * w * s_true;
        assert!((st.s[0] - want_s).abs() < 1e-9, "{} vs {want_s}", st.s[0]);
        assert!((st.b[0] - want_b).abs() < 1e-9, "{} vs {want_b}", st.b[0]);
        assert!(st.s[1].abs() < 1e-15 && st.s[2].abs() < 1e-15);
        // the rate then has the scale and the bias taken out: ω̂ = g − b̂ − ŝ g
        let g = [w * (1.0 + s_true), 0.0, 0.0];
        let got = st.rate(&g)[0];
        assert!((got - (g[0] - want_b - want_s * g[0])).abs() < 1e-15);
        // the variance of the scale error along x shrank by the share the correction explained
        let p_ss = ss * ss - (w * ss * ss) * (w * ss * ss) / var;
        assert!((st.p[(3, 3)] - p_ss).abs() < 1e-9, "{}", st.p[(3, 3)]);
    }

    /// The triangular solve gives the pseudo-inverse's quadratic form where `P_ss` is positive
    /// definite, and declines (for the pseudo-inverse to take over) where it is singular.
    #[test]
    fn the_scale_errors_part_by_triangular_solve_matches_the_inverse() {
        let cs = Matrix3::new(1e-5, -2e-6, 3e-7, 4e-6, 5e-5, -1e-6, -3e-6, 2e-6, 8e-5);
        for (i, a) in [
            Matrix3::new(4e-6, 1e-6, -5e-7, 1e-6, 3e-6, 2e-7, -5e-7, 2e-7, 1e-6),
            Matrix3::from_diagonal(&Vector3::new(1e-6, 1e-6, 1e-6)),
            Matrix3::new(1.0, 0.999, 0.0, 0.999, 1.0, 0.0, 0.0, 0.0, 1e-3) * 1e-6,
        ]
        .iter()
        .enumerate()
        {
            let x = lower_solve(a, &cs).expect("positive definite");
            let got = x.transpose() * x;
            let want = cs * a.try_inverse().unwrap() * cs.transpose();
            let err = (got - want).norm() / want.norm();
            assert!(err < 1e-12, "case {i}: {err:e}");
        }
        let singular = Matrix3::from_diagonal(&Vector3::new(1e-6, 0.0, 1e-6));
        assert!(lower_solve(&singular, &cs).is_none());
        // a singular P_ss: the root of the pseudo-inverse's form
        let mut st = BiasState::new(0.01, 0.01);
        st.p.fixed_view_mut::<3, 3>(3, 3).copy_from(&singular);
        st.c.fixed_view_mut::<3, 3>(0, 3).copy_from(&cs);
        let x = st.scale_root();
        let want = cs * pinv(&singular) * cs.transpose();
        assert!((x.transpose() * x - want).norm() < 1e-12 * want.norm());
        assert!(lower_solve(&Matrix3::from_element(f64::NAN), &cs).is_none());
    }

    #[test]
    fn without_a_scale_prior_the_scale_stays_zero_and_out_of_the_algebra() {
        let dt = 0.01;
        let dq = q4::from_rotation_vector(&[0.02, -0.01, 0.03]);
        let r = q4::to_matrix(&dq);
        let r = Matrix3::from_fn(|i, j| r[i][j]);
        let mut st = BiasState::new(0.01, 0.0);
        for _ in 0..50 {
            st.predict(&r, &[2.0, -1.0, 3.0], dt, 1e-8, 1e-9);
        }
        let n = st.take_pending();
        st.correct(
            &pinv(&n),
            &Vector3::new(0.001, -0.002, 0.0005),
            &(Matrix3::identity() * 1e-8),
            true,
        );
        st.rest(&Vector3::new(0.01, 0.0, 0.0), 1e-6);
        assert_eq!(st.s, Vector3::zeros());
        assert!(st.p.fixed_rows::<3>(3).iter().all(|&v| v == 0.0));
        assert!(st.c.fixed_columns::<3>(3).iter().all(|&v| v == 0.0));
        assert_eq!(st.scale_root(), Matrix3::zeros());
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
