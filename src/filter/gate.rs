//! The normalized surprise of a measurement and the likelihood gate on the update: a readout
//! that says whether a measurement fits the state, on a scale that does not depend on how
//! concentrated the state or the noise is.
//!
//! The predictive density `p(y)` of a measurement `y = x ⊕ v` ([`Core::log_likelihood`]) is
//! largest near the predicted measurement `ŷ = x̂ ⊕ v̂` (the modes of the state and of the
//! noise). The surprise is `s(y) = 2 (log p(ŷ) − log p(y))`, clamped at 0. When the state and
//! the noise are concentrated, `p` is close to a Gaussian in the tangent space at `ŷ` with
//! covariance `Σ_x + Σ_v`, and `s` is the squared Mahalanobis distance of `y` from `ŷ`: a χ²
//! variable with `d − 1` degrees of freedom (3 for quaternions, 1 for axes) when the model
//! holds — mean `d − 1`, `P(s > 16.27) = 0.1 %` for d = 4, `P(s > 10.83) = 0.1 %` for d = 2.
//! Directions in which the state or the noise is broad contribute little (a uniform heading
//! cannot make a heading surprising). Both densities are exact (Bayes normalizers), so `s` is
//! exact for the model; only its χ² reading is the Gaussian approximation.

use nalgebra::Const;

use super::noise::Role;
use super::state::{log_joint_normalizer, Core};
use super::types::Vect;
use crate::canonical::unit;
use crate::error::{Error, Result};
use crate::linalg::congruence;
use crate::quaternion::left;

/// The outcome of [`crate::filter::BinghamFilter::update_gated`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gated {
    /// The measurement's surprise `s ≥ 0` (see [`crate::filter::BinghamFilter::surprise`]).
    pub surprise: f64,
    /// Whether the update was applied (`surprise ≤ max_surprise`).
    pub accepted: bool,
}

impl<const D: usize> Core<D> {
    /// `2 (log p(ŷ) − log p(y))`, clamped at 0 (module documentation).
    pub(super) fn surprise(&self, measurement: &[f64], m_v: &[f64], z_v: &[f64]) -> Result<f64> {
        let y = unit("measurement", Const::<D>, measurement)?;
        let noise = self
            .measurement
            .lookup_or_build(Role::Measurement, m_v, z_v)?;
        // the noise's mode: the direction of its largest concentration
        let top = (0..D).fold(0, |b, i| if noise.z[i] > noise.z[b] { i } else { b });
        let v_hat: Vect<D> = noise.m.column(top).into_owned();
        let x_hat: Vect<D> = self.m.column(D - 1).into_owned();
        let y_hat: Vect<D> = left(Const::<D>, x_hat.as_slice()) * v_hat;
        // The two predictive densities share the state's and the noise's normalizers, which
        // cancel in the difference: only the two joint normalizers are evaluated.
        let at = |y: &Vect<D>| {
            let p = congruence(&Self::likelihood_m(y, &noise.m), &noise.z);
            log_joint_normalizer(&self.m, &self.z, &p)
        };
        let s = 2.0 * (at(&y_hat)? - at(&y)?);
        if !s.is_finite() {
            return Err(Error::Numerical(format!(
                "the surprise is not finite ({s})"
            )));
        }
        Ok(s.max(0.0))
    }

    /// The update if the surprise is at most `max_surprise`; the state unchanged otherwise.
    pub(super) fn update_gated(
        &mut self,
        measurement: &[f64],
        m_v: &[f64],
        z_v: &[f64],
        max_surprise: f64,
    ) -> Result<Gated> {
        if max_surprise.is_nan() || max_surprise < 0.0 {
            return Err(Error::InvalidArgument(format!(
                "`max_surprise` must be ≥ 0 (or +Inf: no gate), got {max_surprise}"
            )));
        }
        let surprise = self.surprise(measurement, m_v, z_v)?;
        let accepted = surprise <= max_surprise;
        if accepted {
            self.update(measurement, m_v, z_v)?;
        }
        Ok(Gated { surprise, accepted })
    }
}
