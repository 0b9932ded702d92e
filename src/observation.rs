//! Vector observations of an orientation and the helpers a user of the quaternion filter needs
//! around them: the Bingham likelihood of a measured direction (Davenport's matrix), isotropic
//! rotation noise from an angular standard deviation, and the angular spread of a Bingham state.
//!
//! Conventions: the orientation `q = (w, x, y, z)` (scalar first, unit) maps the sensor frame to
//! the world frame, `v_world = q ⊗ v_sensor ⊗ q*`, with rotation matrix `R(q)`.

use nalgebra::{Const, DMatrix, Matrix4, SVector};

use crate::canonical::{normalize_eigen, unit};
use crate::distribution::Bingham;
#[allow(unused_imports)] // doc links
use crate::distribution::UNIT_TOL;
use crate::error::{Error, Result};
use crate::linalg::sym_eigen;
use crate::mle::mle_from_second_moment;

/// Davenport's matrix of a direction pair: the symmetric, traceless 4×4 matrix `K` with
/// `qᵀ K q = rᵀ R(q) b` for every unit quaternion `q` (scalar first). With `B = b rᵀ`,
/// `S = B + Bᵀ`, `σ = tr B = b·r` and `c = b × r`: `K = [[σ, cᵀ], [c, S − σ I₃]]`. For unit
/// `b`, `r` its eigenvalues are `−1, −1, +1, +1`; the `+1` eigenspace holds the rotations that
/// map `b` onto `r`.
pub fn davenport_matrix(body: &[f64; 3], reference: &[f64; 3]) -> [[f64; 4]; 4] {
    let (b, r) = (body, reference);
    let sigma = b[0] * r[0] + b[1] * r[1] + b[2] * r[2];
    let c = [
        b[1] * r[2] - b[2] * r[1],
        b[2] * r[0] - b[0] * r[2],
        b[0] * r[1] - b[1] * r[0],
    ];
    let mut k = [[0.0; 4]; 4];
    k[0][0] = sigma;
    for i in 0..3 {
        k[0][i + 1] = c[i];
        k[i + 1][0] = c[i];
        for j in 0..3 {
            k[i + 1][j + 1] = b[i] * r[j] + b[j] * r[i];
        }
        k[i + 1][i + 1] -= sigma;
    }
    k
}

/// Checks that `v` has length 3, is finite and has unit norm within [`UNIT_TOL`]; returns it
/// normalized.
pub fn check_direction(what: &str, v: &[f64]) -> Result<[f64; 3]> {
    Ok(unit(what, Const::<3>, v)?.into())
}

/// Checks a von Mises–Fisher concentration: finite, `≥ 0`, and `2κ` finite.
pub fn check_kappa(kappa: f64) -> Result<f64> {
    // 2κ is the likelihood's concentration: it must be a finite double as well.
    if kappa.is_finite() && kappa >= 0.0 && (2.0 * kappa).is_finite() {
        Ok(kappa)
    } else {
        Err(Error::InvalidArgument(format!(
            "`kappa` must be finite, >= 0 and at most half the largest double, got {kappa}"
        )))
    }
}

/// `κ K` for a validated pair: the exponent matrix of the likelihood `exp(qᵀ κK q)`.
pub(crate) fn observation_exponent(
    body: &[f64; 3],
    reference: &[f64; 3],
    kappa: f64,
) -> Matrix4<f64> {
    let k = davenport_matrix(body, reference);
    Matrix4::from_fn(|i, j| k[i][j] * kappa)
}

/// The likelihood of a measured direction as a Bingham density in the orientation.
///
/// A sensor measures the unit direction `body` (sensor frame) of the known unit direction
/// `reference` (world frame) with von Mises–Fisher noise of concentration `kappa ≥ 0`:
/// `p(b | q) ∝ exp(κ rᵀ R(q) b) = exp(qᵀ κK q)` ([`davenport_matrix`]). Returned normalized:
/// `z = (−2κ, −2κ, 0, 0)`, the columns of `M` the eigenvectors of `K` (the last two span the
/// rotations that map `body` onto `reference`; the rotation about `reference` is unobserved).
///
/// Errors: [`Error::InvalidDimension`] (lengths not 3), [`Error::InvalidArgument`] (NaN/Inf,
/// not unit within [`UNIT_TOL`], `kappa` negative or not finite).
pub fn vector_observation(body: &[f64], reference: &[f64], kappa: f64) -> Result<Bingham> {
    let b = check_direction("body", body)?;
    let r = check_direction("reference", reference)?;
    let kappa = check_kappa(kappa)?;
    // Ascending eigenvalues: −1, −1, 1, 1 exactly (the decomposition only rounds them).
    let k = davenport_matrix(&b, &r);
    let (v, _) = sym_eigen(&Matrix4::from_fn(|i, j| k[i][j]))?;
    let z = SVector::<f64, 4>::new(-2.0 * kappa, -2.0 * kappa, 0.0, 0.0);
    let (m, z) = normalize_eigen(&v, &z);
    Ok(Bingham::from_normalized_parts(&m, &z))
}

/// `log C(κ)` of the von Mises–Fisher density on the unit sphere S² (surface measure):
/// `C(κ) = κ / (4π sinh κ)`, `C(0) = 1/(4π)`. Exact for every `κ ≥ 0` (no overflow).
pub fn log_vmf_normalizer_s2(kappa: f64) -> f64 {
    let four_pi = 4.0 * std::f64::consts::PI;
    // log(sinh κ / κ): series below 1e-3 (error below 1e-19), else κ + log((1 − e^{−2κ}) / (2κ)).
    let log_sinhc = if kappa < 1e-3 {
        let k2 = kappa * kappa;
        k2 / 6.0 - k2 * k2 / 180.0
    } else {
        kappa + (-(-2.0 * kappa).exp_m1()).ln() - (2.0 * kappa).ln()
    };
    -four_pi.ln() - log_sinhc
}

/// Isotropic rotation noise with angular standard deviation `sigma` (radians) as a Bingham
/// distribution, mode at the identity.
///
/// - `d = 4`: the rotation by a Gaussian rotation vector `v ~ N(0, σ² I₃)`, as a unit quaternion
///   `q = (cos(|v|/2), sin(|v|/2) v/|v|)`. Its second moment is exactly
///   `diag(a, (1−a)/3, (1−a)/3, (1−a)/3)` with `a = (1 + E[cos|v|])/2`,
///   `E[cos|v|] = (1 − σ²) e^{−σ²/2}`.
/// - `d = 2`: the unit complex number `(cos φ, sin φ)` with a Gaussian angle `φ ~ N(0, σ²)`:
///   second moment `diag((1 + e^{−2σ²})/2, (1 − e^{−2σ²})/2)`.
///
/// The result is the Bingham distribution with exactly that second moment (the MLE, moment
/// matching). For small `σ`, `z ≈ −2/σ²` (d = 4) and `z ≈ −1/(2σ²)` (d = 2).
///
/// Errors: [`Error::InvalidDimension`] (d not 2 or 4), [`Error::InvalidArgument`] (`sigma` not
/// finite or `≤ 0`, or so small that the concentration exceeds the MLE's range: the smallest
/// moment below `1e-13`, about `σ < 6e-7` rad).
pub fn noise_from_angle_std(d: usize, sigma: f64) -> Result<Bingham> {
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(Error::InvalidArgument(format!(
            "`sigma` must be finite and > 0, got {sigma}"
        )));
    }
    let s2 = sigma * sigma;
    // The moments of the identity's direction (first coordinate) and of each other coordinate,
    // the latter without cancellation for small σ.
    let (small, count) = match d {
        4 => {
            // 1 − a = (1 − E cos)/2, 1 − E cos = −expm1(−σ²/2) + σ² e^{−σ²/2}.
            // σ² e^{−σ²/2} → 0 as σ → ∞ (written so that σ² = ∞ gives 0, not ∞·0).
            let e = (-0.5 * s2).exp();
            let tail = if e == 0.0 { 0.0 } else { s2 * e };
            let one_minus_a = 0.5 * (-(-0.5 * s2).exp_m1() + tail);
            (one_minus_a / 3.0, 3)
        }
        2 => (-0.5 * (-2.0 * s2).exp_m1(), 1),
        _ => {
            return Err(Error::InvalidDimension(format!(
                "rotation noise exists for d = 2 and d = 4, got d = {d}"
            )))
        }
    };
    if small < crate::mle::OMEGA_MIN {
        return Err(Error::InvalidArgument(format!(
            "`sigma` = {sigma:e} rad is below the smallest supported angular standard deviation \
             (about 6e-7 rad for d = 4, 3e-7 rad for d = 2): the concentration would exceed the \
             MLE's range"
        )));
    }
    let big = 1.0 - small * count as f64;
    let mut s = DMatrix::zeros(d, d);
    s[(0, 0)] = big;
    for i in 1..d {
        s[(i, i)] = small;
    }
    mle_from_second_moment(&s)
}

/// The angular spread of a Bingham distribution on S¹ (d = 2) or S³ (d = 4, quaternions) from
/// its moments `ω` (ascending, as [`Bingham::omega`]), written to `out` (length `d`, radians):
///
/// - `[i]` for `i < d − 1`: the spread along principal direction `i` (column `i` of `M`),
///   `k·√ω_i`;
/// - `[d − 1]`: the total spread `k·√(1 − ω_{d−1})`.
///
/// `k = 2` for quaternions, `k = 1` for d = 2. Exact meaning: with `α` the angle between the
/// random `x` and the mode (`cos α = |xᵀ m_d|`), the total is `k·√E[sin² α]`; for d = 4 this is
/// the RMS of `2 sin(θ/2)` with `θ` the rotation angle from the mode, for d = 2 the RMS of
/// `sin α` with `α` the angle between the axes. Both equal the RMS angle to second order in
/// the angle (a state with RMS angle 5° reads 5.0°); per axis, the squares add up to the
/// total's square.
pub fn spread_from_omega(omega: &[f64], out: &mut [f64]) {
    let d = omega.len();
    let k = if d == 4 { 2.0 } else { 1.0 };
    let mut rest = 0.0;
    for (o, w) in out.iter_mut().zip(&omega[..d - 1]) {
        *o = k * w.max(0.0).sqrt();
        rest += w.max(0.0);
    }
    out[d - 1] = k * rest.sqrt();
}

/// [`spread_from_omega`] of a distribution. Errors: d not 2 or 4 ([`Error::InvalidDimension`]),
/// and those of [`Bingham::omega`].
pub fn angular_spread(b: &Bingham) -> Result<Vec<f64>> {
    if b.dim() != 2 && b.dim() != 4 {
        return Err(Error::InvalidDimension(format!(
            "the angular spread exists for d = 2 (axes) and d = 4 (quaternions), got d = {}",
            b.dim()
        )));
    }
    let mut out = vec![0.0; b.dim()];
    spread_from_omega(b.omega()?.as_slice(), &mut out);
    Ok(out)
}
