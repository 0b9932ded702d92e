//! The noises of the filter steps: validated and normalized once, with the quantities a step
//! needs (the process noise's second moment, the measurement noise's `log F`), cached per filter
//! on the bit patterns of the caller's parameters.

use nalgebra::Const;
use std::sync::OnceLock;

use super::types::{Mat, Vect, MAX_CONCENTRATION};
use crate::canonical::params_row_major;
use std::borrow::Cow;

use crate::distribution::{log_f_omega, omega};
use crate::error::{Error, Result};
use crate::linalg::congruence;

/// A validated, normalized noise distribution with the quantities the filter needs.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Noise<const D: usize> {
    pub(super) m: Mat<D>,
    pub(super) z: Vect<D>,
    /// Process and observation noise: the second moment (of the capped concentrations).
    /// Measurement noise: unused.
    pub(super) moment: Mat<D>,
    /// Measurement noise: `log F(z)`, evaluated on the first `log_likelihood` (NaN if it could
    /// not be evaluated; the update does not need it, so it neither pays for it nor fails on
    /// it). Process noise: unused.
    pub(super) log_f: OnceLock<f64>,
}

/// Which quantities a noise entry carries.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Role {
    Process,
    Measurement,
    /// The spin filter's observation noise: named `m_o`, `z_o`; it needs the second moment
    /// (for the spin's likelihood) and `log F` (for the predictive density).
    Observation,
}

/// Longest key: `d² + d` for `d = 4`.
const KEY_LEN: usize = 20;

impl<const D: usize> Noise<D> {
    /// `log F(z)`, evaluated once (see [`Noise::log_f`]); an error if it is not finite.
    pub(super) fn log_f(&self) -> Result<f64> {
        let v = *self
            .log_f
            .get_or_init(|| log_f_omega(&self.z).map_or(f64::NAN, |r| r.0));
        if v.is_finite() {
            Ok(v)
        } else {
            Err(Error::Numerical(
                "log-likelihood: log F of the measurement noise is not finite".into(),
            ))
        }
    }
}

/// One cached noise, keyed on the bit patterns of the caller's `m` and `z`.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct NoiseCache<const D: usize> {
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
    pub(super) fn empty() -> Self {
        NoiseCache {
            key: [0; KEY_LEN],
            entry: None,
        }
    }

    /// The cached entry if it was built from exactly these parameters (lengths D² and D).
    pub(super) fn lookup(&self, m: &[f64], z: &[f64]) -> Option<&Noise<D>> {
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

    /// The cached entry for these parameters, or one built for this call only (not stored:
    /// for the `&self` readouts, which must not change the filter).
    pub(super) fn lookup_or_build(
        &self,
        role: Role,
        m: &[f64],
        z: &[f64],
    ) -> Result<Cow<'_, Noise<D>>> {
        match self.lookup(m, z) {
            Some(n) => Ok(Cow::Borrowed(n)),
            None => Ok(Cow::Owned(Self::build(role, m, z)?)),
        }
    }

    /// Validates and prepares a noise (no caching).
    pub(super) fn build(role: Role, m: &[f64], z: &[f64]) -> Result<Noise<D>> {
        let (mm, zz) = match role {
            Role::Process => params_row_major(Const::<D>, "m_w", m, "z_w", z)?,
            Role::Measurement => params_row_major(Const::<D>, "m_v", m, "z_v", z)?,
            Role::Observation => params_row_major(Const::<D>, "m_o", m, "z_o", z)?,
        };
        let moment = match role {
            Role::Process | Role::Observation => {
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
    pub(super) fn get(&mut self, role: Role, m: &[f64], z: &[f64]) -> Result<&Noise<D>> {
        if self.lookup(m, z).is_none() {
            let e = Self::build(role, m, z)?;
            self.key = key_of(m, z).expect("lengths were validated");
            self.entry = Some(e);
        }
        Ok(self.entry.as_ref().expect("just filled"))
    }
}

/// `z` with every entry below `−MAX_CONCENTRATION` raised to it.
pub(super) fn capped<const D: usize>(z: &Vect<D>) -> Vect<D> {
    z.map(|v| v.max(-MAX_CONCENTRATION))
}
