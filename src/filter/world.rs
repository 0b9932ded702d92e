//! World-frame (left-acting) steps of the first-order filter: the model of Glover & Kaelbling
//! (2013), `x_n = w_n ∘ u_n ∘ x_{n−1}`, `y_n = v_n ∘ x_n`, where `q ∘ r` (the Hamilton product
//! `q r`) rotates by `r`, then by `q`. The control and the noises act on the left, in the world
//! frame; the filter's other steps compose on the right (`x ⊕ u ⊕ w`, body frame). For d = 2
//! (complex multiplication, commutative) both are the same.
//!
//! - predict: `u ∘ x ~ Bingham(L(u) M, Z)` exactly; the second moment of `w ∘ (u ∘ x)` is
//!   `compose_moments(B, A)` (the noise's moment `B` is the left factor) — exact — and the new
//!   state is its moment-matching fit, as in the body-frame prediction.
//! - update: `f(y | x) = f_v(y ∘ x⁻¹)`, and `⟨y x̄, m⟩ = ⟨x, m̄ y⟩`, so the likelihood is the
//!   Bingham density in `x` with directions `m̄_i ∘ y` (paper: `V_o⁻¹ ∘ y`), `M_L = R(y) D M_v`
//!   (`D` the conjugation), and the posterior the exact Bayes product.
//!
//! Derivation: `docs/design.md` (§ "World-frame steps and the spin filter").

use nalgebra::Const;

use super::noise::Role;
use super::state::{composed_moment, Core};
use super::types::{Mat, Vect};
use crate::canonical::unit;
use crate::error::Result;
use crate::linalg::congruence;
use crate::quaternion::{compose_moments, left, right};

/// `D = diag(1, −1, …, −1)`: `D x` is the conjugate (the inverse of a unit `x`).
pub(crate) fn conjugation<const D: usize>() -> Mat<D> {
    Mat::<D>::from_fn(|i, j| match (i, j) {
        (0, 0) => 1.0,
        (i, j) if i == j => -1.0,
        _ => 0.0,
    })
}

/// `M_L = R(y) D M_v`: the principal directions, in `x`, of the likelihood of `y = v ∘ x` with
/// `v ~ Bingham(M_v, ·)`.
pub(crate) fn world_likelihood_m<const D: usize>(y: &Vect<D>, m_v: &Mat<D>) -> Mat<D> {
    right(Const::<D>, y.as_slice()) * conjugation::<D>() * m_v
}

impl<const D: usize> Core<D> {
    /// Prediction `x ← w ∘ u ∘ x` (`u` unit within `UNIT_TOL`, or `None` for the identity).
    pub(super) fn predict_world(
        &mut self,
        u: Option<&[f64]>,
        m_w: &[f64],
        z_w: &[f64],
    ) -> Result<()> {
        let u = u.map(|u| unit("u", Const::<D>, u)).transpose()?;
        let noise = self.process.get(Role::Process, m_w, z_w)?;
        let m = match u {
            Some(u) => left(Const::<D>, u.as_slice()) * self.m,
            None => self.m,
        };
        let a = composed_moment(&m, &self.z)?;
        let c = compose_moments(&noise.moment, &a);
        let (m, z, solution) = crate::mle::fit_second_moment(&c, self.predicted.as_ref())?;
        self.m = m;
        self.z = z;
        self.predicted = Some(solution);
        Ok(())
    }

    /// The likelihood exponent `P = M_L Z_v M_Lᵀ` of `y = v ∘ x`, with the cached noise.
    fn world_precision(&mut self, y: &[f64], m_v: &[f64], z_v: &[f64]) -> Result<Mat<D>> {
        let y = unit("y", Const::<D>, y)?;
        let noise = self.measurement.get(Role::Measurement, m_v, z_v)?;
        Ok(congruence(&world_likelihood_m(&y, &noise.m), &noise.z))
    }

    /// Update with `y = v ∘ x`, `v ~ Bingham(M_v, Z_v)`: the exact Bayes product.
    pub(super) fn update_world(&mut self, y: &[f64], m_v: &[f64], z_v: &[f64]) -> Result<()> {
        let p = self.world_precision(y, m_v, z_v)?;
        self.update_precision(&p)
    }

    /// `log p(y)` under the current estimate (surface measure on the sphere).
    pub(super) fn log_likelihood_world(&self, y: &[f64], m_v: &[f64], z_v: &[f64]) -> Result<f64> {
        let y = unit("y", Const::<D>, y)?;
        self.log_likelihood_with(m_v, z_v, |noise_m| world_likelihood_m(&y, noise_m))
    }
}
