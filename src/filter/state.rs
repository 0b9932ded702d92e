//! The filter for one dimension `D` (2 or 4) on the stack: the state, the warm start of the
//! moment matching, the noise caches, and the exact steps (prediction by composition and moment
//! matching, Bayes update, predictive likelihood, spread).

use nalgebra::Const;

use super::noise::{capped, Noise, NoiseCache, Role};
use super::types::{Mat, Vect};
use crate::canonical::{params_row_major, unit};
use crate::distribution::{bayes_product_in_basis, log_f_omega, omega, product_eigen_precision};
use crate::error::{Error, Result};
use crate::linalg::{congruence, write_row_major};
use crate::mle::{fit_second_moment, fit_second_moment_in_basis, Derivs};
use crate::quaternion::{compose_moments, left, right};

/// The filter for one dimension.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Core<const D: usize> {
    /// Orthonormal, row-major; the last column is the mode.
    pub(super) m: Mat<D>,
    /// Ascending, `z[D−1] = 0`.
    pub(super) z: Vect<D>,
    /// The last prediction's moment-matching solution with its derivatives (warm start).
    pub(super) predicted: Option<Derivs<Const<D>>>,
    pub(super) process: NoiseCache<D>,
    pub(super) measurement: NoiseCache<D>,
}

impl<const D: usize> Core<D> {
    pub(super) fn new(m: &[f64], z: &[f64]) -> Result<Self> {
        let (m, z) = params_row_major(Const::<D>, "m", m, "z", z)?;
        Ok(Core {
            m,
            z,
            predicted: None,
            process: NoiseCache::empty(),
            measurement: NoiseCache::empty(),
        })
    }

    pub(super) fn set_state(&mut self, m: &[f64], z: &[f64]) -> Result<()> {
        let (m, z) = params_row_major(Const::<D>, "m", m, "z", z)?;
        self.m = m;
        self.z = z;
        self.predicted = None;
        Ok(())
    }

    pub(super) fn state_into(&self, m: &mut [f64], z: &mut [f64]) -> Result<()> {
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

    pub(super) fn mode_into(&self, out: &mut [f64]) -> Result<()> {
        if out.len() != D {
            return Err(Error::InvalidDimension(format!(
                "mode buffer must have length {D}, got {}",
                out.len()
            )));
        }
        out.copy_from_slice(self.m.column(D - 1).as_slice());
        Ok(())
    }

    /// Prediction `x ⊕ u ⊕ w` from the caller's slices: `u` (unit within `UNIT_TOL`, or `None`
    /// for the identity) validated, the noise taken from the cache (built on a miss).
    pub(super) fn predict(&mut self, u: Option<&[f64]>, m_w: &[f64], z_w: &[f64]) -> Result<()> {
        let u = u.map(|u| unit("u", Const::<D>, u)).transpose()?;
        let noise = self.process.get(Role::Process, m_w, z_w)?;
        let (m, z, solution) = composed(&self.m, &self.z, self.predicted.as_ref(), u, noise)?;
        self.m = m;
        self.z = z;
        self.predicted = Some(solution);
        Ok(())
    }

    /// `M_L = L(ẑ) D M_v`: the likelihood's principal directions.
    pub(super) fn likelihood_m(zhat: &Vect<D>, m_v: &Mat<D>) -> Mat<D> {
        let mut dm = *m_v;
        for mut row in dm.row_iter_mut().skip(1) {
            row.neg_mut();
        }
        left(Const::<D>, zhat.as_slice()) * dm
    }

    pub(super) fn update(&mut self, measurement: &[f64], m_v: &[f64], z_v: &[f64]) -> Result<()> {
        let zhat = unit("measurement", Const::<D>, measurement)?;
        let noise = self.measurement.get(Role::Measurement, m_v, z_v)?;
        let ml = Self::likelihood_m(&zhat, &noise.m);
        let p = congruence(&ml, &noise.z);
        self.update_precision(&p)
    }

    /// Bayes product with the likelihood `exp(xᵀ P x)`; the state is assigned only on success.
    pub(crate) fn update_precision(&mut self, p: &Mat<D>) -> Result<()> {
        let (m_new, z_new) = bayes_product_in_basis(&self.m, &self.z, p)?;
        self.m = m_new;
        self.z = z_new;
        Ok(())
    }

    pub(super) fn log_likelihood(
        &self,
        measurement: &[f64],
        m_v: &[f64],
        z_v: &[f64],
    ) -> Result<f64> {
        let zhat = unit("measurement", Const::<D>, measurement)?;
        self.log_likelihood_with(m_v, z_v, |noise_m| Self::likelihood_m(&zhat, noise_m))
    }

    /// The predictive log density of an observation whose likelihood has the measurement
    /// noise's concentrations along the directions `likelihood_m(M_v)`: the noise taken from the
    /// cache if it is there (built, not stored, otherwise: `&self`), minus its `log F`.
    pub(super) fn log_likelihood_with(
        &self,
        m_v: &[f64],
        z_v: &[f64],
        likelihood_m: impl Fn(&Mat<D>) -> Mat<D>,
    ) -> Result<f64> {
        let noise = self
            .measurement
            .lookup_or_build(Role::Measurement, m_v, z_v)?;
        let log_f_noise = noise.log_f()?;
        let p = congruence(&likelihood_m(&noise.m), &noise.z);
        let value = self.log_likelihood_precision(&p)? - log_f_noise;
        if !value.is_finite() {
            return Err(Error::Numerical(format!(
                "log-likelihood is not finite ({value})"
            )));
        }
        Ok(value)
    }

    /// `log ∫ f_state(x) exp(xᵀ P x) dx` (surface measure), see [`log_evidence`].
    pub(super) fn log_likelihood_precision(&self, p: &Mat<D>) -> Result<f64> {
        log_evidence(&self.m, &self.z, p)
    }

    pub(super) fn angular_spread_into(&self, out: &mut [f64]) -> Result<()> {
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

impl Core<4> {
    /// The mode (the last column of `M`) as a quaternion, scalar first.
    pub(crate) fn mode(&self) -> [f64; 4] {
        let mode = self.m.column(3);
        [mode[0], mode[1], mode[2], mode[3]]
    }

    /// The principal directions (`M`, columns; the last is the mode) and concentrations (`z`,
    /// ascending, last 0).
    pub(crate) fn params(&self) -> (&Mat<4>, &Vect<4>) {
        (&self.m, &self.z)
    }

    /// The exact rotation `x ← x ⊕ u` (`u` unit): `M ← R(u) M`, `z` unchanged. No moment
    /// matching, no failure; the warm start of the next prediction stays valid (it depends on
    /// `z` only).
    pub(crate) fn rotate(&mut self, u: &[f64; 4]) {
        self.m = right(Const::<4>, u) * self.m;
    }

    /// Prediction `x ← x ⊕ w` by a noise `w` given by its second moment `s` (symmetric, trace
    /// 1), with `w_state = omega(z)` of the current state supplied by the caller (who caches it
    /// with the spread). The state is assigned only on success.
    pub(crate) fn compose_moment(&mut self, w_state: &Vect<4>, s: &Mat<4>) -> Result<()> {
        let a = congruence(&self.m, w_state);
        let c = compose_moments(&a, s);
        let (m, z, solution) = fit_second_moment_in_basis(&c, &self.m, self.predicted.as_ref())?;
        self.m = m;
        self.z = z;
        self.predicted = Some(solution);
        Ok(())
    }

    /// `omega(z)` (the second moments along the principal directions; concentrations capped
    /// as in the prediction): what [`Self::compose_moment`] and the spread need.
    pub(crate) fn omega(&self) -> Result<Vect<4>> {
        omega(&capped(&self.z))
    }

    /// The part of the state a failed multi-step sample must restore (`M`, `z`, warm start).
    pub(crate) fn save(&self) -> Saved4 {
        Saved4 {
            m: self.m,
            z: self.z,
            predicted: self.predicted.clone(),
        }
    }

    /// Restores what [`Self::save`] saved.
    pub(crate) fn restore(&mut self, s: Saved4) {
        self.m = s.m;
        self.z = s.z;
        self.predicted = s.predicted;
    }
}

/// A saved d = 4 state (see [`Core::save`]).
#[derive(Debug, Clone)]
pub(crate) struct Saved4 {
    m: Mat<4>,
    z: Vect<4>,
    predicted: Option<Derivs<Const<4>>>,
}

/// The state after `x ⊕ u ⊕ w`: the exact second moment of the composition (the state's moment
/// rotated by `u`, composed with the noise's) fitted by moment matching, warm-started from
/// `warm`.
fn composed<const D: usize>(
    m: &Mat<D>,
    z: &Vect<D>,
    warm: Option<&Derivs<Const<D>>>,
    u: Option<Vect<D>>,
    noise: &Noise<D>,
) -> Result<(Mat<D>, Vect<D>, Derivs<Const<D>>)> {
    let m = match u {
        Some(u) => right(Const::<D>, u.as_slice()) * m,
        None => *m,
    };
    let a = composed_moment(&m, z)?;
    let c = compose_moments(&a, &noise.moment);
    fit_second_moment(&c, warm)
}

/// The second moment `M diag(ω(z)) Mᵀ` a composition uses (concentrations capped at
/// `MAX_CONCENTRATION`, see the module documentation of `filter`).
pub(crate) fn composed_moment<const D: usize>(m: &Mat<D>, z: &Vect<D>) -> Result<Mat<D>> {
    Ok(congruence(m, &omega(&capped(z))?))
}

/// `log ∫ f(x) exp(xᵀ P x) dx` (surface measure) for `f = Bingham(M, Z)`: with `λ` the largest
/// eigenvalue of `M Z Mᵀ + P`, `log F(eig − λ) + λ − log F(Z)`.
pub(crate) fn log_evidence<const D: usize>(m: &Mat<D>, z: &Vect<D>, p: &Mat<D>) -> Result<f64> {
    let (lf_state, _) = log_f_omega(z)?;
    let value = log_joint_normalizer(m, z, p)? - lf_state;
    if !value.is_finite() {
        return Err(Error::Numerical(format!(
            "log-likelihood is not finite ({value})"
        )));
    }
    Ok(value)
}

/// `log ∫ exp(xᵀ (M Z Mᵀ + P) x) dx` (surface measure): `log F(eig − λ) + λ`, `λ` the largest
/// eigenvalue. [`log_evidence`] without the state's own normalizer, which cancels in a
/// difference of two evidences of the same state (the surprise).
pub(super) fn log_joint_normalizer<const D: usize>(
    m: &Mat<D>,
    z: &Vect<D>,
    p: &Mat<D>,
) -> Result<f64> {
    let (_, l) = product_eigen_precision(m, z, p)?;
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
    Ok(lf_post + top)
}
