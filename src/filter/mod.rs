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
//! # Memory and concentration limits
//!
//! The state lives on the stack (`d = 2, 4`, fixed-size nalgebra types, the `Core` in `state`):
//! after the first step with a given noise a predict or update performs **no heap allocation**;
//! noises are validated and prepared once and cached on their parameters' bit patterns
//! (`noise`); the moment matching is warm-started from the previous prediction, and the
//! eigendecompositions of the prediction (d = 4) and of the update from the state's principal
//! directions (`docs/design.md`, "Multiply (Bayes)"). Updates stay
//! exact for any finite concentration; the prediction needs the state's second moment, singular
//! to working precision for `|z| ≳ 1e13`, so concentrations below `−MAX_CONCENTRATION` (of the
//! state and of the process noise) are raised to it there (an angular spread of about 7 µrad).
//! The nonlinear steps are in `nonlinear`. Derivations: `docs/design.md` (§ "Filter"); speed:
//! `docs/speed.md`.

mod gate;
mod noise;
mod nonlinear;
mod spin;
mod state;
mod types;
mod world;

use nalgebra::Matrix4;

use crate::distribution::Bingham;
use crate::error::{Error, Result};

pub use gate::Gated;
pub use nonlinear::{
    NonlinearMethod, NonlinearOptions, NonlinearReport, CORRECTION_PASSES, DEFAULT_MAX_CALLS,
    DEFAULT_MODE_TOLERANCE, DEFAULT_PREDICT_TOLERANCE, DEFAULT_UPDATE_TOLERANCE,
    MAX_TEMPERING_STEPS, MIN_CORRECTION_SHARE, TEMPERING_RESIDUAL,
};
pub use spin::SpinFilter;
pub(crate) use state::Core;
pub use types::MAX_CONCENTRATION;

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

    /// The surprise of `measurement` (a health readout and the statistic of the gate):
    /// `s = 2 (log p(ŷ) − log p(measurement))` ≥ 0, `p` the predictive density of
    /// [`log_likelihood`](Self::log_likelihood) and `ŷ = x̂ ⊕ v̂` the predicted measurement
    /// (the modes of the state and of the noise). When the state and the noise are
    /// concentrated and the model holds, `s` is a χ² variable with `d − 1` degrees of freedom
    /// (mean 3 for quaternions; above 16.27 with probability 0.1 %, for d = 2 above 10.83); a
    /// measurement that does not fit the state — a quaternion given in (x, y, z, w) order, a
    /// fix in another frame — scores hundreds. Directions where the state or the noise is
    /// broad contribute little. The filter is not changed. Definition and derivation: module
    /// `gate`; measured in tests/filter_health.rs.
    ///
    /// Arguments and errors as for [`update`](Self::update).
    pub fn surprise(&self, measurement: &[f64], m_v: &[f64], z_v: &[f64]) -> Result<f64> {
        dispatch!(&self.inner, c => c.surprise(measurement, m_v, z_v))
    }

    /// The likelihood gate: [`update`](Self::update) if the measurement's
    /// [`surprise`](Self::surprise) is at most `max_surprise` (≥ 0; `f64::INFINITY` accepts
    /// every measurement), otherwise nothing changes. Returns the surprise and whether the
    /// update was applied; a gated-out measurement is not an error.
    ///
    /// Errors: those of [`update`](Self::update), [`Error::InvalidArgument`] for a NaN or
    /// negative `max_surprise`. On error the filter is unchanged.
    pub fn update_gated(
        &mut self,
        measurement: &[f64],
        m_v: &[f64],
        z_v: &[f64],
        max_surprise: f64,
    ) -> Result<Gated> {
        dispatch!(&mut self.inner, c => c.update_gated(measurement, m_v, z_v, max_surprise))
    }

    /// World-frame prediction (Glover & Kaelbling 2013): the state becomes the distribution of
    /// `w ∘ u ∘ x` (`q ∘ r` = the Hamilton product `q r`, rotate by `r`, then by `q`), with
    /// `w ~ Bingham(m_w, z_w)` and a known unit `u` (length `d`, or `None`: the identity) acting
    /// on the left, in the world frame — where [`predict_rotation`](Self::predict_rotation)
    /// composes on the right (`x ⊕ u ⊕ w`, body frame). The rotation is exact
    /// (`u ∘ x ~ Bingham(L(u) M, Z)`), the composition's second moment exact, the new state its
    /// moment-matching fit. For d = 2 (commutative) it equals `predict_rotation`; for d = 4 the
    /// two agree when the noise is isotropic.
    ///
    /// Arguments and errors as for [`predict_rotation`](Self::predict_rotation).
    pub fn predict_world(&mut self, u: Option<&[f64]>, m_w: &[f64], z_w: &[f64]) -> Result<()> {
        dispatch!(&mut self.inner, c => c.predict_world(u, m_w, z_w))
    }

    /// World-frame update: conditions on `y = v ∘ x`, `v ~ Bingham(m_v, z_v)` (the noise on the
    /// left, in the world frame; [`update`](Self::update) has `x ⊕ v`). The likelihood
    /// `f_v(y ∘ x⁻¹)` is the Bingham density in `x` with directions `m̄_i ∘ y` (`M_L = R(y) D
    /// M_v`), so the posterior is the exact Bayes product.
    ///
    /// Arguments (the measurement named `y`) and errors as for [`update`](Self::update).
    pub fn update_world(&mut self, y: &[f64], m_v: &[f64], z_v: &[f64]) -> Result<()> {
        dispatch!(&mut self.inner, c => c.update_world(y, m_v, z_v))
    }

    /// The natural logarithm of the predictive density of `y = v ∘ x` under the current
    /// estimate (surface measure on the sphere, as in [`log_likelihood`](Self::log_likelihood)),
    /// the world-frame counterpart of `log_likelihood`. The filter is not changed.
    pub fn log_likelihood_world(&self, y: &[f64], m_v: &[f64], z_v: &[f64]) -> Result<f64> {
        dispatch!(&self.inner, c => c.log_likelihood_world(y, m_v, z_v))
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
    /// `a` is called with a unit vector `x` (length d) and must write the unit vector `a(x)`
    /// into its second argument (length d, unit within `UNIT_TOL`; it is then normalized). It
    /// returns `Err(message)` to signal failure. The sign of `a(x)` does not matter, and
    /// `a(−x) = ±a(x)` is the caller's contract (an orientation and its negative are the same
    /// rotation). `a` is called at the state's deterministic points (the
    /// [`Scheme::Moments`](crate::deterministic::Scheme::Moments) points: 3 for d = 2, 19 for
    /// d = 4) and, where their error estimate asks, at sampled points.
    ///
    /// The new state is the Bingham distribution whose second moment is that of `a(x)` (`x` from
    /// the state) composed exactly with the noise's (moment matching), as in
    /// [`predict`](Self::predict); the second moment of `a(x)` meets the default tolerance
    /// ([`DEFAULT_PREDICT_TOLERANCE`], 5e-4 per entry) within [`DEFAULT_MAX_CALLS`] (20 000)
    /// calls of `a`, or the step is refused with `Error::NotConverged` (see
    /// [`predict_nonlinear_opts`](Self::predict_nonlinear_opts)). With `a` the identity this
    /// equals `predict` to rounding. The method: `docs/design.md`, section "Nonlinear steps".
    ///
    /// Errors: those of [`predict`](Self::predict), [`Error::Callback`] if `a` fails or
    /// returns a non-finite or non-unit vector, `Error::NotConverged` if the tolerance is not
    /// met within the budget. On error the filter is unchanged. No heap allocation (beyond what
    /// `a` does) once the noise is cached.
    pub fn predict_nonlinear<F>(&mut self, mut a: F, m_w: &[f64], z_w: &[f64]) -> Result<()>
    where
        F: FnMut(&[f64], &mut [f64]) -> std::result::Result<(), String>,
    {
        self.predict_nonlinear_opts(&mut a, m_w, z_w, &NonlinearOptions::default())
            .map(|_| ())
    }

    /// [`predict_nonlinear`](Self::predict_nonlinear) with the error controlled by `opts`: the
    /// second moment of `a(x)` under the state (before the noise is composed in) is computed
    /// with an error estimate of at most `opts.tolerance` in every entry (0: the default,
    /// [`DEFAULT_PREDICT_TOLERANCE`]; what the estimate means: [`NonlinearOptions::tolerance`]),
    /// or the step is refused with [`Error::NotConverged`] (the message gives the estimate
    /// reached) when that would take more than `opts.max_calls` calls of `a`. Returns what was
    /// measured. The method: `docs/design.md`, section "Nonlinear steps". Errors: those of
    /// `predict_nonlinear`, `InvalidArgument` for bad options. On error the filter is
    /// unchanged.
    pub fn predict_nonlinear_opts<F>(
        &mut self,
        mut a: F,
        m_w: &[f64],
        z_w: &[f64],
        opts: &NonlinearOptions,
    ) -> Result<NonlinearReport>
    where
        F: FnMut(&[f64], &mut [f64]) -> std::result::Result<(), String>,
    {
        dispatch!(&mut self.inner, c => c.predict_nonlinear(&mut a, m_w, z_w, opts))
    }

    /// Nonlinear Bayes update: posterior `∝ prior(x) · L(x)`, with `log_l(x)` returning
    /// `Ok(log L(x))` for a unit vector `x` (length d; `L(−x) = L(x)` is the caller's
    /// contract) or `Err(message)` on failure. Log-likelihoods, so sharp likelihoods do not
    /// underflow.
    ///
    /// The new state is the Bingham distribution that approximates the posterior: the
    /// likelihood is absorbed at the deterministic points of the current approximation
    /// ([`Scheme::Moments`](crate::deterministic::Scheme::Moments), plus fit-only points where
    /// those are too few: 5 calls of `log_l` per round for d = 2, 19 for d = 4) in tempered
    /// steps (at most [`MAX_TEMPERING_STEPS`], each applying at most [`TEMPERING_RESIDUAL`] of
    /// what the fitted exponent misses; then [`CORRECTION_PASSES`] importance corrections), and
    /// the result is checked and corrected by sampling around it until the error estimate of
    /// its second moment meets [`DEFAULT_UPDATE_TOLERANCE`] (2.5e-3 per entry) and that of its
    /// mode [`DEFAULT_MODE_TOLERANCE`] (0.05 spreads), within [`DEFAULT_MAX_CALLS`] (20 000)
    /// calls of `log_l` (see [`update_nonlinear_opts`](Self::update_nonlinear_opts)). A
    /// likelihood that is a Bingham density is applied exactly (the Bayes product). The method:
    /// `docs/design.md`, section "Nonlinear steps"; measured call counts: `docs/accuracy.md`
    /// (nonlinear models).
    ///
    /// Errors: [`Error::Callback`] (failure or a non-finite value), `NotConverged` (the
    /// likelihood not absorbed within [`MAX_TEMPERING_STEPS`], or the tolerance not met within
    /// the budget), and the moment-matching errors. On error the filter is unchanged. No heap
    /// allocation.
    pub fn update_nonlinear<L>(&mut self, mut log_l: L) -> Result<()>
    where
        L: FnMut(&[f64]) -> std::result::Result<f64, String>,
    {
        self.update_nonlinear_opts(&mut log_l, &NonlinearOptions::default())
            .map(|_| ())
    }

    /// [`update_nonlinear`](Self::update_nonlinear) with the error controlled by `opts`: the
    /// posterior's second moment is computed with an error estimate of at most `opts.tolerance`
    /// in every entry (0: the default, [`DEFAULT_UPDATE_TOLERANCE`]; what the estimate means:
    /// [`NonlinearOptions::tolerance`]) and its mode with one of at most `opts.mode_tolerance`
    /// spreads, or the update is refused with [`Error::NotConverged`] (the message gives the
    /// estimates reached) when that would take more than `opts.max_calls` calls of `log_l`.
    /// Where the deterministic approximation is already the posterior (a Bingham likelihood)
    /// the check leaves it exact. Returns what was measured. A posterior with several separated
    /// modes: the sampling sees the mode(s) near the deterministic approximation; see
    /// `docs/guide.md`. The method: `docs/design.md`, section "Nonlinear steps".
    pub fn update_nonlinear_opts<L>(
        &mut self,
        mut log_l: L,
        opts: &NonlinearOptions,
    ) -> Result<NonlinearReport>
    where
        L: FnMut(&[f64]) -> std::result::Result<f64, String>,
    {
        dispatch!(&mut self.inner, c => c.update_nonlinear(&mut log_l, opts))
    }

    /// The angular spread of the estimate (radians), see [`crate::observation::spread_from_omega`]:
    /// `out[i]` (i < d − 1) along principal direction `i` (column `i` of `M`), `out[d − 1]` the
    /// total (for d = 4 the RMS of `2 sin(θ/2)`, θ the rotation angle from the mode; ≈ RMS θ).
    /// Errors: `out` not of length `d` (nothing written).
    pub fn angular_spread_into(&self, out: &mut [f64]) -> Result<()> {
        dispatch!(&self.inner, c => c.angular_spread_into(out))
    }

    /// The d = 4 core (the typed door for in-crate callers such as the AHRS), or the error a
    /// d = 2 filter gives for a quaternion-only operation.
    pub(crate) fn core4(&self) -> Result<&Core<4>> {
        match &self.inner {
            Inner::D4(c) => Ok(c),
            Inner::D2(_) => Err(not_quaternion()),
        }
    }

    /// [`Self::core4`], mutable.
    pub(crate) fn core4_mut(&mut self) -> Result<&mut Core<4>> {
        match &mut self.inner {
            Inner::D4(c) => Ok(c),
            Inner::D2(_) => Err(not_quaternion()),
        }
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
