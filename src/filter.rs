//! The recursive Bingham filter (Kurz, Gilitschenski, Julier & Hanebeck, JAIF 2014, Sec. 6) for
//! axes in the plane (`d = 2`, complex numbers `(re, im)`) and orientations in space (`d = 4`,
//! unit quaternions, **scalar first** `(w, x, y, z)`).
//!
//! System model `x_{k+1} = x_k ⊕ w_k`, measurement model `z_k = x_k ⊕ v_k`, with `w_k`, `v_k`
//! Bingham-distributed noise and `⊕` complex multiplication (`d = 2`) or the Hamilton product
//! (`d = 4`). The state is a Bingham distribution `(M, Z)`; it stays one:
//!
//! - **predict**: `A = E[x xᵀ]` of the state, `B = E[w wᵀ]` of the noise, the second moment of
//!   `x ⊕ w` is `C = Σ_ab A_ab L_a B L_bᵀ` (exact), and the new state is the Bingham
//!   distribution with second moment `C` (moment matching, the maximum-likelihood fit). With a
//!   known rotation `u` (e.g. a gyroscope increment), [`BinghamFilter::predict_rotation`]
//!   predicts `x ⊕ u ⊕ w`: the state is first rotated exactly, `x ⊕ u ~ Bingham(R(u) M, Z)`.
//! - **update** with a measurement `ẑ`: the likelihood `f_v(x⁻¹ ⊕ ẑ)` is a Bingham density in
//!   `x` with `M_L = L(ẑ) D M_v` (columns `ẑ ⊕ (D m_i)`, `D = diag(1, −1, …, −1)` the
//!   conjugation) and `Z_L = Z_v`; the posterior is the exact Bayes product, the
//!   eigendecomposition of `M Z Mᵀ + M_L Z_L M_Lᵀ`.
//!
//! Conventions as everywhere in the crate: `M` row-major `d×d` with orthonormal columns (the
//! principal directions, the **last column is the mode**), `z` of length `d` in any order and
//! shift on input, sorted ascending with `z[d−1] = 0` on output.
//!
//! # Speed and memory
//!
//! The filter calls the crate's core operations (the same functions [`Bingham`] uses: parameter
//! validation in `params`, moments and the eigendecomposition in `matrix`, the composed moment in
//! [`crate::quaternion`], the MLE in [`crate::mle`], the Bayes product in
//! [`crate::distribution`]), instantiated with the fixed-size nalgebra types `SMatrix<f64, d, d>`
//! for `d = 2, 4`, which live on the stack: after the first step with a given noise, a predict
//! or update performs **no heap allocation**. The noises' validation, normalization and moments
//! are cached, keyed on the bit patterns of the noise parameters, so passing the same arrays
//! every step costs nothing. The moment-matching solver is warm-started from the previous
//! prediction.
//!
//! # Concentration limits
//!
//! Repeated sharp updates can make the state arbitrarily concentrated; updates stay exact for any
//! finite concentration (tested to `|z| = 1e12` and beyond). The prediction needs the state's
//! second moment, which is singular to working precision for `|z| ≳ 1e13`: there, concentrations
//! below `−MAX_CONCENTRATION` (of the state and of the process noise) are raised to
//! `−MAX_CONCENTRATION` (an angular spread of about 7 µrad). The composed moment's smallest
//! eigenvalue is at least that of the state's moment, so the prediction never fails because the
//! state (or the noise) is sharp.

use nalgebra::{Const, Matrix4, SMatrix, SVector};
use std::sync::OnceLock;

use crate::deterministic::{for_each_point, for_each_probe, plan, Scheme};
use crate::distribution::{bayes_product, log_f_omega, omega, product_eigen_precision, Bingham};
use crate::error::{Error, Result};
use crate::matrix::{congruence, write_row_major};
use crate::mle::{cholesky_solve, fit_second_moment, Derivs};
use crate::params::{params_row_major, unit, UNIT_TOL};
use crate::quaternion::{compose_moments, left, right};

/// A `D×D` matrix on the stack.
type Mat<const D: usize> = SMatrix<f64, D, D>;
/// A vector of length `D` on the stack.
type Vect<const D: usize> = SVector<f64, D>;

/// The largest concentration `|z_i|` the prediction uses (see the module documentation,
/// "Concentration limits"): before the moments of the state and of the process noise are
/// formed, every `z_i < −MAX_CONCENTRATION` is replaced by `−MAX_CONCENTRATION`.
/// `z = −1e10` corresponds to an angular standard deviation of about `1/√(2·1e10) ≈ 7 µrad`.
pub const MAX_CONCENTRATION: f64 = 1e10;

/// The largest part of `log L` not captured by the fitted exponent (its largest residual over
/// the current deterministic samples) one tempering step of
/// [`BinghamFilter::update_nonlinear`] applies: a step applies `L^{Δβ}` with
/// `Δβ · residual ≤ TEMPERING_RESIDUAL`.
pub const TEMPERING_RESIDUAL: f64 = 1.0;

/// Importance-corrected moment matches at the end of [`BinghamFilter::update_nonlinear`].
pub const CORRECTION_PASSES: usize = 2;

/// The importance correction of [`BinghamFilter::update_nonlinear`] is skipped when its
/// weights' effective share `(Σ w r)² / (Σ w · Σ w r²)` falls below this (the approximation is
/// then too far from the posterior for the samples to correct it).
pub const MIN_CORRECTION_SHARE: f64 = 0.5;

/// The most tempering steps [`BinghamFilter::update_nonlinear`] takes.
pub const MAX_TEMPERING_STEPS: usize = 200;

/// The most deterministic samples a filter step uses (the Moments scheme for d = 4).
const MAX_SAMPLES: usize = 19; // also 7 + 12 probes (d = 4 fallback), 3 + 2 (d = 2)

/// Deterministic samples with their weights and log-likelihoods (on the stack).
struct Samples<const D: usize> {
    x: [Vect<D>; MAX_SAMPLES],
    /// Moment weights (fit weights for probes).
    w: [f64; MAX_SAMPLES],
    /// Fit-only points (no moment weight).
    probe: [bool; MAX_SAMPLES],
    l: [f64; MAX_SAMPLES],
    n: usize,
}

/// Unknowns of a symmetric `P` for d = 4.
const MAX_UNKNOWNS: usize = 10;

impl<const D: usize> Samples<D> {
    fn new() -> Self {
        Samples {
            x: [Vect::<D>::zeros(); MAX_SAMPLES],
            w: [0.0; MAX_SAMPLES],
            probe: [false; MAX_SAMPLES],
            l: [0.0; MAX_SAMPLES],
            n: 0,
        }
    }

    /// The largest residual `|l_k − c − x_kᵀ P x_k|` over the samples (fit-only points
    /// included), `c` the weighted mean offset (the fit's constant).
    #[allow(clippy::needless_range_loop)] // parallel arrays
    fn misfit(&self, p: &Mat<D>) -> f64 {
        // Relative to the largest log-likelihood, as in the fit (a huge constant cancels).
        let hi = self.l[..self.n]
            .iter()
            .fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        let mut r = [0.0; MAX_SAMPLES];
        let (mut sw, mut c) = (0.0, 0.0);
        for k in 0..self.n {
            let x = &self.x[k];
            r[k] = (self.l[k] - hi) - (x.transpose() * p * x)[(0, 0)];
            c += self.w[k] * r[k];
            sw += self.w[k];
        }
        let c = c / sw;
        r[..self.n]
            .iter()
            .fold(0.0, |a, &v| f64::max(a, (v - c).abs()))
    }

    /// The symmetric `P` minimizing `Σ_k w_k (l_k − c − x_kᵀ P x_k)²` (the constant `c` is
    /// absorbed in `P`'s trace, since `xᵀ x = 1`): the weighted least-squares fit of a Bingham
    /// exponent to the log-likelihood at the samples. Exact when `log L` is such an exponent.
    ///
    /// The fit is done in the scaled principal coordinates `u_i = (mᵀx)_i / s_i` of the
    /// distribution the samples come from (`s_i` the largest `|(mᵀx)_i|` over the samples), so
    /// the normal equations stay well conditioned however concentrated the samples are.
    #[allow(clippy::needless_range_loop)] // small dense normal equations
    fn fit_exponent(&self, m: &Mat<D>) -> Mat<D> {
        let nu = D * (D + 1) / 2;
        let hi = self.l[..self.n]
            .iter()
            .fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        let mut ys = [Vect::<D>::zeros(); MAX_SAMPLES];
        let mut scale = [0.0f64; D];
        for k in 0..self.n {
            ys[k] = m.transpose() * self.x[k];
            for i in 0..D {
                scale[i] = scale[i].max(ys[k][i].abs());
            }
        }
        for v in scale.iter_mut() {
            if v.is_nan() || *v <= 0.0 {
                *v = 1.0;
            }
        }
        let mut a = [0.0; MAX_UNKNOWNS * MAX_UNKNOWNS];
        let mut b = [0.0; MAX_UNKNOWNS];
        let mut phi = [0.0; MAX_UNKNOWNS];
        for k in 0..self.n {
            let y = &ys[k];
            let mut u = 0;
            for i in 0..D {
                for j in i..D {
                    let (ui, uj) = (y[i] / scale[i], y[j] / scale[j]);
                    phi[u] = if i == j { ui * ui } else { 2.0 * ui * uj };
                    u += 1;
                }
            }
            let (w, l) = (self.w[k], self.l[k] - hi);
            for r in 0..nu {
                b[r] += w * l * phi[r];
                for c in 0..nu {
                    a[r * nu + c] += w * phi[r] * phi[c];
                }
            }
        }
        // A tiny ridge keeps the normal equations definite.
        let tr: f64 = (0..nu).map(|r| a[r * nu + r]).sum();
        for r in 0..nu {
            a[r * nu + r] += 1e-12 * tr / nu as f64;
        }
        if !cholesky_solve(nu, &mut a[..nu * nu], &mut b[..nu]) {
            // Not numerically definite even with the ridge (no usable samples): no exponent.
            b.fill(0.0);
        }
        let mut py = Mat::<D>::zeros();
        let mut u = 0;
        for i in 0..D {
            for j in i..D {
                let v = b[u] / (scale[i] * scale[j]);
                py[(i, j)] = v;
                py[(j, i)] = v;
                u += 1;
            }
        }
        m * py * m.transpose()
    }
}

/// A recursive Bingham filter for `d = 2` (axes) or `d = 4` (unit quaternions).
///
/// Create it with [`BinghamFilter::new`] from the initial estimate, then alternate
/// [`predict`](BinghamFilter::predict) (or [`predict_rotation`](BinghamFilter::predict_rotation))
/// and [`update`](BinghamFilter::update). Every method either succeeds or returns an error and
/// leaves the filter exactly as it was (the new state is computed completely before it is
/// assigned).
///
/// The type is `Send` and `Sync`, holds no global state, and cloning gives an independent
/// filter.
#[derive(Debug, Clone)]
pub struct BinghamFilter {
    inner: Inner,
}

// Not boxed: the variants are plain arrays and boxing would add an indirection to every step.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
enum Inner {
    D2(Core<2>),
    D4(Core<4>),
}

/// Runs `$body` with `$c` bound to the dimension-specific core.
macro_rules! dispatch {
    ($self:expr, $c:ident => $body:expr) => {
        match $self {
            Inner::D2($c) => $body,
            Inner::D4($c) => $body,
        }
    };
}

impl BinghamFilter {
    /// A filter with the initial estimate `Bingham(M, Z)`.
    ///
    /// - `d`: 2 (axes, complex numbers `(re, im)`) or 4 (quaternions, scalar first).
    /// - `m`: `d×d` row-major, orthogonal within `ORTHOGONALITY_TOL` (it is re-orthonormalized).
    /// - `z`: `d` concentrations, column `i` of `M` belongs to `z[i]`; any order and shift.
    ///
    /// Errors: [`Error::InvalidDimension`] (d not 2 or 4, wrong lengths),
    /// [`Error::InvalidArgument`] (NaN/Inf, `M` not orthogonal).
    pub fn new(d: usize, m: &[f64], z: &[f64]) -> Result<BinghamFilter> {
        let inner = match d {
            2 => Inner::D2(Core::new(m, z)?),
            4 => Inner::D4(Core::new(m, z)?),
            _ => {
                return Err(Error::InvalidDimension(format!(
                    "the filter exists for d = 2 (axes) and d = 4 (quaternions), got d = {d}"
                )))
            }
        };
        Ok(BinghamFilter { inner })
    }

    /// A filter whose initial estimate is `b` (`b.dim()` must be 2 or 4).
    pub fn from_bingham(b: &Bingham) -> Result<BinghamFilter> {
        BinghamFilter::new(b.dim(), &b.m_row_major(), b.z().as_slice())
    }

    /// The dimension `d` (2 or 4).
    pub fn dim(&self) -> usize {
        match self.inner {
            Inner::D2(_) => 2,
            Inner::D4(_) => 4,
        }
    }

    /// The current estimate as a [`Bingham`] distribution (allocates; equal to
    /// [`BinghamFilter::state_into`]).
    pub fn state(&self) -> Bingham {
        dispatch!(&self.inner, c => Bingham::from_normalized_parts(&c.m, &c.z))
    }

    /// Copies the current estimate into `m` (`d×d` row-major, orthonormal columns, the last one
    /// the mode) and `z` (ascending, `z[d−1] = 0`). Errors: wrong lengths (nothing written).
    pub fn state_into(&self, m: &mut [f64], z: &mut [f64]) -> Result<()> {
        dispatch!(&self.inner, c => c.state_into(m, z))
    }

    /// Replaces the estimate by `Bingham(M, Z)` (validated as in [`BinghamFilter::new`]; the
    /// dimension stays). The noise caches are kept.
    pub fn set_state(&mut self, m: &[f64], z: &[f64]) -> Result<()> {
        dispatch!(&mut self.inner, c => c.set_state(m, z))
    }

    /// The mode of the estimate (the last column of `M`), a unit vector of length `d`. `−mode`
    /// is a mode as well (antipodal symmetry).
    pub fn mode(&self) -> Vec<f64> {
        let mut v = vec![0.0; self.dim()];
        self.mode_into(&mut v).expect("buffer has the right length");
        v
    }

    /// Copies the mode into `out` (length `d`). Errors: wrong length (nothing written).
    pub fn mode_into(&self, out: &mut [f64]) -> Result<()> {
        dispatch!(&self.inner, c => c.mode_into(out))
    }

    /// Prediction through `x_{k+1} = x_k ⊕ w_k`, `w_k ~ Bingham(M_w, Z_w)` (`m_w` row-major
    /// `d×d` orthogonal, `z_w` length `d`, any order and shift).
    ///
    /// The noise's mode may carry a known offset (a nominal rotation). Concentrations beyond
    /// [`MAX_CONCENTRATION`] are capped for the moment computation.
    ///
    /// Errors: [`Error::InvalidDimension`] (lengths), [`Error::InvalidArgument`] (NaN/Inf,
    /// `M_w` not orthogonal), [`Error::NotConverged`] / [`Error::Numerical`] (moment matching).
    pub fn predict(&mut self, m_w: &[f64], z_w: &[f64]) -> Result<()> {
        dispatch!(&mut self.inner, c => c.predict(None, m_w, z_w))
    }

    /// Prediction through `x_{k+1} = x_k ⊕ u ⊕ w_k` with a known unit `u` (length `d`, e.g. the
    /// rotation increment integrated from a gyroscope, quaternion scalar first; unit within
    /// `UNIT_TOL`, then normalized). The rotation is exact (`x ⊕ u ~ Bingham(R(u) M, Z)`), then
    /// the noise is composed as in [`BinghamFilter::predict`].
    pub fn predict_rotation(&mut self, u: &[f64], m_w: &[f64], z_w: &[f64]) -> Result<()> {
        dispatch!(&mut self.inner, c => c.predict(Some(u), m_w, z_w))
    }

    /// Measurement update with `measurement = x ⊕ v`, `v ~ Bingham(M_v, Z_v)`.
    ///
    /// `measurement`: length `d`, unit within `UNIT_TOL` (then normalized); its sign does not
    /// matter. The posterior is exact (Bayes' rule for Bingham densities).
    ///
    /// Errors: [`Error::InvalidDimension`] (lengths), [`Error::InvalidArgument`] (NaN/Inf,
    /// `M_v` not orthogonal, measurement not unit), [`Error::Numerical`] (overflow).
    pub fn update(&mut self, measurement: &[f64], m_v: &[f64], z_v: &[f64]) -> Result<()> {
        dispatch!(&mut self.inner, c => c.update(measurement, m_v, z_v))
    }

    /// The natural logarithm of the predictive density of `measurement` under the current
    /// estimate: `log ∫ f_state(x) f_v(x⁻¹ ⊕ ẑ) dx`, a density on the unit sphere with respect to
    /// the surface measure (antipodally symmetric). Use it for gating and for weighting filters
    /// in a bank. The filter is not changed.
    ///
    /// With `P = M Z Mᵀ + M_L Z_v M_Lᵀ` (as in the update) and its largest eigenvalue `λ`:
    /// `log p(ẑ) = log F(eig(P) − λ) + λ − log F(Z) − log F(Z_v)`.
    ///
    /// Arguments and errors as for [`BinghamFilter::update`].
    pub fn log_likelihood(&self, measurement: &[f64], m_v: &[f64], z_v: &[f64]) -> Result<f64> {
        dispatch!(&self.inner, c => c.log_likelihood(measurement, m_v, z_v))
    }

    /// Measurement update (d = 4) with a measured direction: `body` (sensor frame, unit) of the
    /// known `reference` (world frame, unit), von Mises–Fisher noise of concentration `kappa ≥ 0`
    /// on the measured direction. The likelihood `exp(κ rᵀ R(q) b)` is the Bingham density
    /// `exp(qᵀ κK q)` ([`crate::observation::davenport_matrix`]), so the posterior is exact; the
    /// rotation about `reference` is not observed and stays as uncertain as it was. Equal to
    /// [`BinghamFilter::update`]'s Bayes product with [`crate::observation::vector_observation`].
    ///
    /// Errors: [`Error::InvalidDimension`] (d = 2 filter, lengths not 3),
    /// [`Error::InvalidArgument`] (NaN/Inf, not unit within `UNIT_TOL`, bad `kappa`),
    /// [`Error::Numerical`] (overflow).
    pub fn update_vector(&mut self, body: &[f64], reference: &[f64], kappa: f64) -> Result<()> {
        let p = vector_exponent(body, reference, kappa)?;
        self.core4_mut()?.update_precision(&p)
    }

    /// The natural logarithm of the predictive density of the measured direction `body` (a
    /// density on the unit sphere S² of directions, surface measure) under the current estimate
    /// (d = 4): `log ∫ f(q) C(κ) exp(κ rᵀ R(q) b) dq` with `C(κ) = κ / (4π sinh κ)`. Use it for
    /// gating (an outlier has a small value) and to adapt `kappa`. The filter is not changed.
    /// Arguments and errors as for [`BinghamFilter::update_vector`].
    pub fn log_likelihood_vector(
        &self,
        body: &[f64],
        reference: &[f64],
        kappa: f64,
    ) -> Result<f64> {
        let p = vector_exponent(body, reference, kappa)?;
        let c = self.core4()?;
        Ok(c.log_likelihood_precision(&p)? + crate::observation::log_vmf_normalizer_s2(kappa))
    }

    /// Nonlinear prediction `x_{k+1} = a(x_k) ⊕ w_k` with `w_k ~ Bingham(m_w, z_w)`.
    ///
    /// `a` is called once per deterministic sample of the state (the
    /// [`Scheme::Moments`](crate::deterministic::Scheme::Moments) points: 3 for d = 2, 19 for
    /// d = 4, or 7 where that scheme falls back) with a unit vector `x` (length d) and must
    /// write the unit vector `a(x)` into its second argument (length d, unit within
    /// `UNIT_TOL`; it is then normalized). It returns `Err(message)` to signal failure. The
    /// sign of `a(x)` does not matter, and `a(−x) = ±a(x)` is the caller's contract (an
    /// orientation and its negative are the same rotation). The second moment of `a(x)` is
    /// formed from the weighted points, composed exactly with the noise's moment and refitted
    /// (moment matching), as in [`predict`](Self::predict). With `a` the identity this equals
    /// `predict` to rounding, since the points reproduce the state's second moment exactly.
    ///
    /// Errors: those of [`predict`](Self::predict), and [`Error::Callback`] if `a` fails or
    /// returns a non-finite or non-unit vector. On error the filter is unchanged. No heap
    /// allocation (beyond what `a` does) once the noise is cached.
    pub fn predict_nonlinear<F>(&mut self, mut a: F, m_w: &[f64], z_w: &[f64]) -> Result<()>
    where
        F: FnMut(&[f64], &mut [f64]) -> std::result::Result<(), String>,
    {
        dispatch!(&mut self.inner, c => c.predict_nonlinear(&mut a, m_w, z_w))
    }

    /// Nonlinear Bayes update: posterior `∝ prior(x) · L(x)`, with `log_l(x)` returning
    /// `Ok(log L(x))` for a unit vector `x` (length d; `L(−x) = L(x)` is the caller's
    /// contract) or `Err(message)` on failure. Log-likelihoods, so sharp likelihoods do not
    /// underflow.
    ///
    /// The algorithm (each round calls `log_l` at the deterministic samples of the current
    /// approximation, [`Scheme::Moments`](crate::deterministic::Scheme::Moments), plus a few
    /// fit-only points where those are too few to determine a quadratic form: 5 calls per round
    /// for d = 2, 19 for d = 4):
    ///
    /// 1. **Progressive (tempered) linearization.** Fit a Bingham exponent `xᵀ P x` to `log L`
    ///    at the samples (weighted least squares, in the approximation's scaled principal
    ///    coordinates) and multiply the current approximation by `exp(Δβ xᵀ P x)` (an exact
    ///    Bayes product), with `Δβ` chosen so that the part of `log L` the exponent does not
    ///    capture (the fit's largest residual over the samples) contributes at most
    ///    [`TEMPERING_RESIDUAL`] per step; repeat with the new approximation's samples until
    ///    `Σ Δβ = 1`. Where `log L` is a Bingham exponent the residual vanishes and the whole
    ///    likelihood is applied at once: the exact product. A likelihood far from log-quadratic
    ///    over the prior's spread is approached in several steps, each fitted where the
    ///    approximation now is, and never collapses onto one sample.
    /// 2. **Importance correction** ([`CORRECTION_PASSES`] rounds): reweight the samples of the
    ///    approximation by `prior · L / approximation` and fit the Bingham distribution to their
    ///    second moment (moment matching; the weights are constant when the approximation is the
    ///    posterior, so an exact result stays exact). Skipped where the weights would collapse
    ///    (effective share below [`MIN_CORRECTION_SHARE`]) or the approximation is sharper than
    ///    the moments can represent (`|z| > MAX_CONCENTRATION`).
    ///
    /// Reliable where the posterior is close to a Bingham distribution: measured in
    /// `tests/nonlinear.rs` against 10⁶-sample Monte Carlo references with a camera
    /// likelihood (figures in `docs/accuracy.md`), the posterior mode agrees within the
    /// references' standard errors for a prior of 0.14 rad spread and likelihoods of 1 to 0.1
    /// times that spread; for a broad prior (0.42 rad) the posterior is visibly non-Bingham and
    /// the fit's mode is off by up to 0.016 rad. A multimodal likelihood gets a single-mode fit.
    /// At most [`MAX_TEMPERING_STEPS`] steps; beyond that `Error::NotConverged`. Calls of
    /// `log_l`: `(steps + CORRECTION_PASSES) × samples`: 57 for a Bingham likelihood (d = 4),
    /// 57–190 for the camera likelihoods of the tests.
    ///
    /// Errors: [`Error::Callback`] (failure or a non-finite value), `NotConverged`, and the
    /// moment-matching errors. On error the filter is unchanged. No heap allocation.
    pub fn update_nonlinear<L>(&mut self, mut log_l: L) -> Result<()>
    where
        L: FnMut(&[f64]) -> std::result::Result<f64, String>,
    {
        dispatch!(&mut self.inner, c => c.update_nonlinear(&mut log_l))
    }

    /// The angular spread of the estimate (radians), see [`crate::observation::spread_from_omega`]:
    /// `out[i]` (i < d − 1) along principal direction `i` (column `i` of `M`), `out[d − 1]` the
    /// total (for d = 4 the RMS of `2 sin(θ/2)`, θ the rotation angle from the mode; ≈ RMS θ).
    /// Errors: `out` not of length `d` (nothing written).
    pub fn angular_spread_into(&self, out: &mut [f64]) -> Result<()> {
        dispatch!(&self.inner, c => c.angular_spread_into(out))
    }

    fn core4(&self) -> Result<&Core<4>> {
        match &self.inner {
            Inner::D4(c) => Ok(c),
            Inner::D2(_) => Err(not_quaternion()),
        }
    }

    fn core4_mut(&mut self) -> Result<&mut Core<4>> {
        match &mut self.inner {
            Inner::D4(c) => Ok(c),
            Inner::D2(_) => Err(not_quaternion()),
        }
    }

    /// Bayes update (d = 4) with the likelihood `exp(qᵀ P q)`, `P` symmetric (crate-internal:
    /// the AHRS's heading observation).
    pub(crate) fn update_exponent(&mut self, p: &Matrix4<f64>) -> Result<()> {
        self.core4_mut()?.update_precision(p)
    }

    /// The mode (d = 4) as an array.
    pub(crate) fn mode4(&self) -> Result<[f64; 4]> {
        let c = self.core4()?;
        let mode = c.m.column(3);
        Ok([mode[0], mode[1], mode[2], mode[3]])
    }
}

fn not_quaternion() -> Error {
    Error::InvalidDimension(
        "vector observations exist for d = 4 (quaternions, 3-D orientations); this filter has d = 2"
            .into(),
    )
}

/// Validates a vector observation and returns `κ K`.
fn vector_exponent(body: &[f64], reference: &[f64], kappa: f64) -> Result<Matrix4<f64>> {
    use crate::observation::{check_direction, check_kappa, observation_exponent};
    let b = check_direction("body", body)?;
    let r = check_direction("reference", reference)?;
    let kappa = check_kappa(kappa)?;
    Ok(observation_exponent(&b, &r, kappa))
}

/// A validated, normalized noise distribution with the quantities the filter needs.
#[derive(Debug, Clone, PartialEq)]
struct Noise<const D: usize> {
    m: Mat<D>,
    z: Vect<D>,
    /// Process noise: the second moment (of the capped concentrations). Measurement noise: unused.
    moment: Mat<D>,
    /// Measurement noise: `log F(z)`, evaluated on the first `log_likelihood` (NaN if it could
    /// not be evaluated; the update does not need it, so it neither pays for it nor fails on
    /// it). Process noise: unused.
    log_f: OnceLock<f64>,
}

/// Which quantities a noise entry carries.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Role {
    Process,
    Measurement,
}

/// Longest key: `d² + d` for `d = 4`.
const KEY_LEN: usize = 20;

/// One cached noise, keyed on the bit patterns of the caller's `m` and `z`.
#[derive(Debug, Clone, PartialEq)]
struct NoiseCache<const D: usize> {
    key: [u64; KEY_LEN],
    entry: Option<Noise<D>>,
}

fn key_of(m: &[f64], z: &[f64]) -> Option<[u64; KEY_LEN]> {
    if m.len() + z.len() > KEY_LEN {
        return None;
    }
    let mut k = [0u64; KEY_LEN];
    for (slot, v) in k.iter_mut().zip(m.iter().chain(z.iter())) {
        *slot = v.to_bits();
    }
    Some(k)
}

impl<const D: usize> NoiseCache<D> {
    fn empty() -> Self {
        NoiseCache {
            key: [0; KEY_LEN],
            entry: None,
        }
    }

    /// The cached entry if it was built from exactly these parameters (lengths D² and D).
    fn lookup(&self, m: &[f64], z: &[f64]) -> Option<&Noise<D>> {
        let e = self.entry.as_ref()?;
        let same = m.len() == D * D
            && z.len() == D
            && self
                .key
                .iter()
                .zip(m.iter().chain(z))
                .all(|(k, v)| *k == v.to_bits());
        same.then_some(e)
    }

    /// Validates and prepares a noise (no caching).
    fn build(role: Role, m: &[f64], z: &[f64]) -> Result<Noise<D>> {
        let (mm, zz) = match role {
            Role::Process => params_row_major(Const::<D>, "m_w", m, "z_w", z)?,
            Role::Measurement => params_row_major(Const::<D>, "m_v", m, "z_v", z)?,
        };
        let moment = match role {
            Role::Process => {
                let w = omega(&capped(&zz))?;
                congruence(&mm, &w)
            }
            Role::Measurement => Mat::<D>::zeros(),
        };
        Ok(Noise {
            m: mm,
            z: zz,
            moment,
            log_f: OnceLock::new(),
        })
    }

    /// The entry for these parameters, built and stored on a miss. On error the cache is
    /// unchanged.
    fn get(&mut self, role: Role, m: &[f64], z: &[f64]) -> Result<&Noise<D>> {
        if self.lookup(m, z).is_none() {
            let e = Self::build(role, m, z)?;
            self.key = key_of(m, z).expect("lengths were validated");
            self.entry = Some(e);
        }
        Ok(self.entry.as_ref().expect("just filled"))
    }
}

/// `z` with every entry below `−MAX_CONCENTRATION` raised to it.
fn capped<const D: usize>(z: &Vect<D>) -> Vect<D> {
    z.map(|v| v.max(-MAX_CONCENTRATION))
}

/// The filter for one dimension.
#[derive(Debug, Clone, PartialEq)]
struct Core<const D: usize> {
    /// Orthonormal, row-major; the last column is the mode.
    m: Mat<D>,
    /// Ascending, `z[D−1] = 0`.
    z: Vect<D>,
    /// The last prediction's moment-matching solution with its derivatives (warm start).
    predicted: Option<Derivs<Const<D>>>,
    process: NoiseCache<D>,
    measurement: NoiseCache<D>,
}

impl<const D: usize> Core<D> {
    fn new(m: &[f64], z: &[f64]) -> Result<Self> {
        let (m, z) = params_row_major(Const::<D>, "m", m, "z", z)?;
        Ok(Core {
            m,
            z,
            predicted: None,
            process: NoiseCache::empty(),
            measurement: NoiseCache::empty(),
        })
    }

    fn set_state(&mut self, m: &[f64], z: &[f64]) -> Result<()> {
        let (m, z) = params_row_major(Const::<D>, "m", m, "z", z)?;
        self.m = m;
        self.z = z;
        self.predicted = None;
        Ok(())
    }

    fn state_into(&self, m: &mut [f64], z: &mut [f64]) -> Result<()> {
        if m.len() != D * D || z.len() != D {
            return Err(Error::InvalidDimension(format!(
                "state buffers must have lengths {} and {D}, got {} and {}",
                D * D,
                m.len(),
                z.len()
            )));
        }
        write_row_major(&self.m, m);
        z.copy_from_slice(self.z.as_slice());
        Ok(())
    }

    fn mode_into(&self, out: &mut [f64]) -> Result<()> {
        if out.len() != D {
            return Err(Error::InvalidDimension(format!(
                "mode buffer must have length {D}, got {}",
                out.len()
            )));
        }
        out.copy_from_slice(self.m.column(D - 1).as_slice());
        Ok(())
    }

    fn predict(&mut self, u: Option<&[f64]>, m_w: &[f64], z_w: &[f64]) -> Result<()> {
        let u = u.map(|u| unit("u", Const::<D>, u)).transpose()?;
        let noise = self.process.get(Role::Process, m_w, z_w)?;
        let m = match u {
            Some(u) => right(Const::<D>, u.as_slice()) * self.m,
            None => self.m,
        };
        let w = omega(&capped(&self.z))?;
        let a = congruence(&m, &w);
        let c = compose_moments(&a, &noise.moment);
        let (m_new, z_new, solution) = fit_second_moment(&c, self.predicted.as_ref())?;
        self.m = m_new;
        self.z = z_new;
        self.predicted = Some(solution);
        Ok(())
    }

    /// Visits the deterministic samples (Moments scheme) of `Bingham(m, z)` with the
    /// concentrations capped as in the prediction.
    fn for_each_sample(
        m: &Mat<D>,
        z: &Vect<D>,
        visit: impl FnMut(&Vect<D>, f64) -> Result<()>,
    ) -> Result<()> {
        Self::for_each_sample_and_probe(m, z, false, visit)
    }

    /// [`Self::for_each_sample`], followed (if `probes`) by the fit-only probe points of
    /// [`for_each_probe`] (visited with a negative weight: `−w`).
    fn for_each_sample_and_probe(
        m: &Mat<D>,
        z: &Vect<D>,
        probes: bool,
        mut visit: impl FnMut(&Vect<D>, f64) -> Result<()>,
    ) -> Result<()> {
        let zc = capped(z);
        let mut grad = [0.0; D];
        let mut hess = [0.0; 16];
        let p = plan::<D>(
            zc.as_slice(),
            Scheme::Moments,
            &mut grad,
            &mut hess[..D * D],
        )?;
        for_each_point(m, &p, &grad, &hess[..D * D], &mut visit)?;
        if probes {
            for_each_probe(m, &p, |x, w| visit(x, -w))?;
        }
        Ok(())
    }

    fn predict_nonlinear<F>(&mut self, a: &mut F, m_w: &[f64], z_w: &[f64]) -> Result<()>
    where
        F: FnMut(&[f64], &mut [f64]) -> std::result::Result<(), String>,
    {
        let noise = self.process.get(Role::Process, m_w, z_w)?;
        let mut s = Mat::<D>::zeros();
        let mut k = 0usize;
        Self::for_each_sample(&self.m, &self.z, |x, wt| {
            let mut out = [0.0; D];
            a(x.as_slice(), &mut out).map_err(|msg| {
                Error::Callback(format!(
                    "transition failed at sample {k} {x:?}: {msg}",
                    x = x.as_slice()
                ))
            })?;
            let v = Vect::<D>::from_column_slice(&out);
            let n = v.norm();
            if !(n.is_finite() && (n - 1.0).abs() <= UNIT_TOL) {
                return Err(Error::Callback(format!(
                    "transition returned {out:?} at sample {k}: not a finite unit vector \
                     (norm {n}, tolerance {UNIT_TOL:e})"
                )));
            }
            let v = v / n;
            s.ger(wt, &v, &v, 1.0);
            k += 1;
            Ok(())
        })?;
        let c = compose_moments(&s, &noise.moment);
        let (m_new, z_new, solution) = fit_second_moment(&c, self.predicted.as_ref())?;
        self.m = m_new;
        self.z = z_new;
        self.predicted = Some(solution);
        Ok(())
    }

    /// The deterministic samples of `Bingham(m, z)` with the log-likelihood at each.
    fn samples_with_log_l<L>(
        m: &Mat<D>,
        z: &Vect<D>,
        log_l: &mut L,
        iteration: usize,
        out: &mut Samples<D>,
    ) -> Result<()>
    where
        L: FnMut(&[f64]) -> std::result::Result<f64, String>,
    {
        out.n = 0;
        Self::for_each_sample_and_probe(m, z, true, |x, wt| {
            let l = log_l(x.as_slice()).map_err(|msg| {
                Error::Callback(format!(
                    "log-likelihood failed at {x:?} (linearization {iteration}): {msg}",
                    x = x.as_slice()
                ))
            })?;
            if !l.is_finite() {
                return Err(Error::Callback(format!(
                    "log-likelihood returned {l} at {x:?}: not finite",
                    x = x.as_slice()
                )));
            }
            let k = out.n;
            out.x[k] = *x;
            out.w[k] = wt.abs();
            out.probe[k] = wt < 0.0;
            out.l[k] = l;
            out.n += 1;
            Ok(())
        })
    }

    /// The moment-matched posterior from the deterministic samples of its approximation
    /// `Bingham(m, z)`: the samples are reweighted by `prior(x) L(x) / approximation(x)` (close
    /// to constant when the approximation is good, and exactly constant when it is the
    /// posterior) and the Bingham distribution with their second moment is fitted.
    #[allow(clippy::needless_range_loop)] // parallel arrays
    fn importance_correction<L>(
        &self,
        m: &Mat<D>,
        z: &Vect<D>,
        log_l: &mut L,
        samples: &mut Samples<D>,
        step: usize,
    ) -> Result<(Mat<D>, Vect<D>)>
    where
        L: FnMut(&[f64]) -> std::result::Result<f64, String>,
    {
        if z[0] < -MAX_CONCENTRATION {
            // The samples would be those of the capped distribution, not of the approximation.
            return Ok((*m, *z));
        }
        Self::samples_with_log_l(m, z, log_l, step, samples)?;
        let prior = congruence(&self.m, &self.z);
        let approx = congruence(m, z);
        let mut lr = [0.0; MAX_SAMPLES];
        let mut top = f64::NEG_INFINITY;
        for k in 0..samples.n {
            let x = &samples.x[k];
            let e = (x.transpose() * (prior - approx) * x)[(0, 0)];
            lr[k] = samples.l[k] + e;
            if !samples.probe[k] {
                top = top.max(lr[k]);
            }
        }
        let mut s = Mat::<D>::zeros();
        // The weights' effective share: (Σ w r)² / (Σ w · Σ w r²), 1 for a constant ratio r.
        let (mut sw, mut swr, mut swr2) = (0.0, 0.0, 0.0);
        for k in 0..samples.n {
            if samples.probe[k] {
                continue;
            }
            let x = &samples.x[k];
            let r = (lr[k] - top).exp();
            s.ger(samples.w[k] * r, x, x, 1.0);
            sw += samples.w[k];
            swr += samples.w[k] * r;
            swr2 += samples.w[k] * r * r;
        }
        if swr * swr < MIN_CORRECTION_SHARE * sw * swr2 {
            // The approximation is too far from the posterior for the points to correct it
            // (their weights would collapse): keep it.
            return Ok((*m, *z));
        }
        // A moment too close to singular (an approximation sharper than the MLE can represent,
        // |z| ≳ 1e13) cannot be refitted: the approximation stands.
        match fit_second_moment(&s, None) {
            Ok((m_new, z_new, _)) => Ok((m_new, z_new)),
            Err(_) => Ok((*m, *z)),
        }
    }

    fn update_nonlinear<L>(&mut self, log_l: &mut L) -> Result<()>
    where
        L: FnMut(&[f64]) -> std::result::Result<f64, String>,
    {
        let mut samples = Samples::<D>::new();
        let (mut m, mut z) = (self.m, self.z);
        let mut remaining = 1.0f64;
        for step in 0..MAX_TEMPERING_STEPS {
            Self::samples_with_log_l(&m, &z, log_l, step, &mut samples)?;
            let p = samples.fit_exponent(&m);
            // The fitted exponent's spread over the samples decides the step.
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for k in 0..samples.n {
                let x = &samples.x[k];
                let q = (x.transpose() * p * x)[(0, 0)];
                lo = lo.min(q);
                hi = hi.max(q);
            }
            let spread = hi - lo;
            // Where the exponent fits log L at every sample (to rounding: log L is a Bingham
            // exponent there), the rest of the likelihood is applied at once.
            // The step is limited by the part of log L the exponent does not capture (the fit's
            // residual over the samples): a log-quadratic likelihood is applied at once.
            let misfit = samples.misfit(&p).max(1e-12 * spread);
            let last = misfit * remaining <= TEMPERING_RESIDUAL;
            let db = if last {
                remaining
            } else {
                TEMPERING_RESIDUAL / misfit
            };
            let (m_new, z_new) = bayes_product(&m, &z, &(p * db))?;
            m = m_new;
            z = z_new;
            if last {
                for pass in 0..CORRECTION_PASSES {
                    (m, z) =
                        self.importance_correction(&m, &z, log_l, &mut samples, step + 1 + pass)?;
                }
                self.m = m;
                self.z = z;
                return Ok(());
            }
            remaining -= db;
        }
        Err(Error::NotConverged(format!(
            "nonlinear update: the likelihood was not absorbed in {MAX_TEMPERING_STEPS} \
             tempering steps ({remaining:.3} of its exponent left); it is far sharper than \
             the prior or multimodal"
        )))
    }

    /// `M_L = L(ẑ) D M_v`: the likelihood's principal directions.
    fn likelihood_m(zhat: &Vect<D>, m_v: &Mat<D>) -> Mat<D> {
        let mut dm = *m_v;
        for mut row in dm.row_iter_mut().skip(1) {
            row.neg_mut();
        }
        left(Const::<D>, zhat.as_slice()) * dm
    }

    fn update(&mut self, measurement: &[f64], m_v: &[f64], z_v: &[f64]) -> Result<()> {
        let zhat = unit("measurement", Const::<D>, measurement)?;
        let noise = self.measurement.get(Role::Measurement, m_v, z_v)?;
        let ml = Self::likelihood_m(&zhat, &noise.m);
        let p = congruence(&ml, &noise.z);
        self.update_precision(&p)
    }

    /// Bayes product with the likelihood `exp(xᵀ P x)`; the state is assigned only on success.
    fn update_precision(&mut self, p: &Mat<D>) -> Result<()> {
        let (m_new, z_new) = bayes_product(&self.m, &self.z, p)?;
        self.m = m_new;
        self.z = z_new;
        Ok(())
    }

    fn log_likelihood(&self, measurement: &[f64], m_v: &[f64], z_v: &[f64]) -> Result<f64> {
        let zhat = unit("measurement", Const::<D>, measurement)?;
        let built;
        let noise = match self.measurement.lookup(m_v, z_v) {
            Some(n) => n,
            None => {
                built = NoiseCache::<D>::build(Role::Measurement, m_v, z_v)?;
                &built
            }
        };
        let log_f_noise = *noise
            .log_f
            .get_or_init(|| log_f_omega(&noise.z).map_or(f64::NAN, |r| r.0));
        if !log_f_noise.is_finite() {
            return Err(Error::Numerical(
                "log-likelihood: log F of the measurement noise is not finite".into(),
            ));
        }
        let ml = Self::likelihood_m(&zhat, &noise.m);
        let p = congruence(&ml, &noise.z);
        let value = self.log_likelihood_precision(&p)? - log_f_noise;
        if !value.is_finite() {
            return Err(Error::Numerical(format!(
                "log-likelihood is not finite ({value})"
            )));
        }
        Ok(value)
    }

    /// `log ∫ f_state(x) exp(xᵀ P x) dx` (surface measure): with `λ` the largest eigenvalue of
    /// `M Z Mᵀ + P`, `log F(eig − λ) + λ − log F(Z)`.
    fn log_likelihood_precision(&self, p: &Mat<D>) -> Result<f64> {
        let (_, l) = product_eigen_precision(&self.m, &self.z, p)?;
        let top = l[D - 1];
        let zp = l.map(|v| v - top);
        // As in the update: the posterior's concentrations may overflow (a state or noise near
        // the largest double); that is a numerical failure, not an invalid argument.
        if !zp.iter().all(|v| v.is_finite()) {
            return Err(Error::Numerical(
                "log-likelihood: the posterior concentrations are not finite".into(),
            ));
        }
        let (lf_post, _) = log_f_omega(&zp)?;
        let (lf_state, _) = log_f_omega(&self.z)?;
        let value = lf_post + top - lf_state;
        if !value.is_finite() {
            return Err(Error::Numerical(format!(
                "log-likelihood is not finite ({value})"
            )));
        }
        Ok(value)
    }

    fn angular_spread_into(&self, out: &mut [f64]) -> Result<()> {
        if out.len() != D {
            return Err(Error::InvalidDimension(format!(
                "spread buffer must have length {D}, got {}",
                out.len()
            )));
        }
        let w = omega(&self.z)?;
        crate::observation::spread_from_omega(w.as_slice(), out);
        Ok(())
    }
}
