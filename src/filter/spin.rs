//! The second-order quaternion Bingham filter of Glover & Kaelbling (2013, Sec. 4): the
//! orientation `x` and the spin `v` (the rotation per step) of an object observed without a
//! gyroscope, e.g. by a camera.
//!
//! Process and observation (`q ∘ r` = Hamilton product `q r`: rotate by `r`, then by `q`):
//! `v_n = w_n ∘ u_n ∘ v_{n−1}`, `x_n = v_{n−1} ∘ x_{n−1}`, `y_n = o_n ∘ x_n`, with Bingham
//! noises `w_n` (process, on the spin) and `o_n` (observation). The joint posterior is carried as
//! the product of two Bingham marginals `B_x · B_v` (the paper's assumption: `x` and `v`
//! independent given the data). One step, from the marginals of step `n − 1`:
//!
//! 1. orientation: prior `B_v ∘ B_x` (the composition's exact second moment, moment matched),
//!    times `f(y | x) = Bingham(x; Z_o, R(y) D M_o)` (exact Bayes product);
//! 2. spin: the observation's evidence about `v_{n−1}` is `g(v) = ∫ f(y | x) B_x(v⁻¹ ∘ x) dx`,
//!    the density of `a ∘ b⁻¹` with `a ~ Bingham(Z_o, R(y) D M_o)` and `b ~ B_x`: a composition,
//!    moment matched (the paper's `f_{y|x} ∘ B_x⁻¹`); `B_v · g` (exact Bayes product), rotated by
//!    `u` on the left (exact) and composed with `w` (exact second moment, moment matched).
//!
//! Approximations: the product of marginals, and the three moment matchings (each keeps the
//! exact second moment of the composition it replaces). Derivation and measurements:
//! `docs/design.md` (§ "World-frame steps and the spin filter"), `docs/accuracy.md`
//! (§ "Glover & Kaelbling reproduced").

use std::sync::OnceLock;

use nalgebra::Const;

use super::noise::{NoiseCache, Role};
use super::state::{composed_moment, log_joint_normalizer};
use super::types::{Mat, Vect, MAX_CONCENTRATION};
use super::world::{conjugation, world_likelihood_m};
use crate::canonical::{params_row_major, unit};
use crate::distribution::{bayes_product, log_f_omega, omega, Bingham};
use crate::error::{Error, Result};
use crate::linalg::{congruence, write_row_major};
use crate::mle::{fit_second_moment_nearest, Derivs};
use crate::observation::spread_from_omega;
use crate::quaternion::{compose_moments, left, right};

/// One Bingham marginal: `M` (orthonormal columns, the last the mode) and `z` (ascending,
/// `z[3] = 0`).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Marginal {
    m: Mat<4>,
    z: Vect<4>,
}

impl Marginal {
    fn from_slices(what_m: &str, m: &[f64], what_z: &str, z: &[f64]) -> Result<Self> {
        let (m, z) = params_row_major(Const::<4>, what_m, m, what_z, z)?;
        Ok(Marginal { m, z })
    }

    fn write(&self, m: &mut [f64], z: &mut [f64]) {
        write_row_major(&self.m, m);
        z.copy_from_slice(self.z.as_slice());
    }

    fn mode(&self) -> [f64; 4] {
        let c = self.m.column(3);
        [c[0], c[1], c[2], c[3]]
    }
}

/// How many previous solutions of each moment matching are kept as warm starts. The targets
/// change shape from step to step as the object turns against the observation's world-frame
/// axes, and come back to earlier shapes as it keeps turning: starting Newton from the nearest of
/// the last 16 solutions rather than the last one saves about 0.6 evaluations of ∇ log F per
/// step in the `spin_step` benchmark's scenario (`docs/speed.md`, row `spin-step`).
const STARTS: usize = 16;

/// The last `STARTS` solutions of one moment matching (a ring), with their derivatives.
#[derive(Debug, Clone)]
struct Starts {
    slots: [Option<Derivs<Const<4>>>; STARTS],
    next: usize,
}

impl Default for Starts {
    fn default() -> Self {
        Starts {
            slots: std::array::from_fn(|_| None),
            next: 0,
        }
    }
}

impl Starts {
    fn iter(&self) -> impl Iterator<Item = &Derivs<Const<4>>> {
        self.slots.iter().flatten()
    }

    fn push(&mut self, solution: Derivs<Const<4>>) {
        self.slots[self.next] = Some(solution);
        self.next = (self.next + 1) % STARTS;
    }
}

/// The moment-matching warm starts of the three compositions of a step.
#[derive(Debug, Clone, Default)]
struct Warm {
    orientation: Starts,
    evidence: Starts,
    spin: Starts,
}

/// The orientation's prediction `B_v ∘ B_x` for the next step, which depends on the state
/// only: the moments of `x` and `v` (the spin evidence and the spin's prediction need them
/// too), the moment-matched parameters, the solver's solution (the next warm start) and, once
/// [`SpinFilter::log_likelihood`] has needed it, its `log F`. Computed by whichever of `step` and `log_likelihood` comes first
/// and shared by the others until the state changes: a caller that weighs two interpretations
/// of an observation and then steps pays for one prediction, not three. The same bits either
/// way (the solver starts from the same warm starts).
#[derive(Debug, Clone)]
struct Prediction {
    ax: Mat<4>,
    av: Mat<4>,
    m: Mat<4>,
    z: Vect<4>,
    sol: Derivs<Const<4>>,
    log_f: OnceLock<f64>,
}

/// The second-order quaternion Bingham filter (orientation and spin, d = 4, quaternions scalar
/// first), see the module documentation for the model.
///
/// Every method either succeeds or returns an error and leaves the filter as it was. The state
/// lives on the stack (about 10 KB, most of it the moment matchings' warm starts); after the
/// first step with given noises a step performs no heap allocation (the noises are validated
/// once and cached on their parameters' bit patterns).
/// `Send` and `Sync`; cloning gives an independent filter.
#[derive(Debug, Clone)]
pub struct SpinFilter {
    x: Marginal,
    v: Marginal,
    /// The second moment of `v` when it is known without evaluating `ω(z_v)`: after a step,
    /// the composition's moment that `v` was fitted to (moment matching reproduces it), which
    /// saves one evaluation of the normalization's derivatives per step.
    v_moment: Option<Mat<4>>,
    warm: Warm,
    /// The prediction of the current state, once computed (see [`Prediction`]).
    predicted: OnceLock<Prediction>,
    process: NoiseCache<4>,
    observation: NoiseCache<4>,
}

/// The observation's precision in `x` and the second moment of `a ~ Bingham(Z_o, R(y) D M_o)`.
struct ObservationTerms {
    precision: Mat<4>,
    moment: Mat<4>,
}

impl SpinFilter {
    /// A filter with the orientation prior `Bingham(m_x, z_x)` and the spin prior
    /// `Bingham(m_v, z_v)` (each `m` 4×4 row-major orthogonal, `z` 4 concentrations in any order
    /// and shift, as for [`super::BinghamFilter::new`]). `z_x = 0` (all equal) is the uniform
    /// orientation prior: nothing known about the orientation.
    ///
    /// Errors: [`Error::InvalidDimension`] (lengths), [`Error::InvalidArgument`] (NaN/Inf, `m`
    /// not orthogonal).
    pub fn new(m_x: &[f64], z_x: &[f64], m_v: &[f64], z_v: &[f64]) -> Result<SpinFilter> {
        Ok(SpinFilter {
            x: Marginal::from_slices("m_x", m_x, "z_x", z_x)?,
            v: Marginal::from_slices("m_v", m_v, "z_v", z_v)?,
            v_moment: None,
            warm: Warm::default(),
            predicted: OnceLock::new(),
            process: NoiseCache::empty(),
            observation: NoiseCache::empty(),
        })
    }

    /// Replaces both marginals (validated as in [`SpinFilter::new`]); the noise caches are kept.
    pub fn set_state(&mut self, m_x: &[f64], z_x: &[f64], m_v: &[f64], z_v: &[f64]) -> Result<()> {
        let x = Marginal::from_slices("m_x", m_x, "z_x", z_x)?;
        let v = Marginal::from_slices("m_v", m_v, "z_v", z_v)?;
        self.x = x;
        self.v = v;
        self.v_moment = None;
        self.warm = Warm::default();
        self.predicted = OnceLock::new();
        Ok(())
    }

    /// Copies the orientation marginal into `m_x` (16, row-major, the last column the mode),
    /// `z_x` (4, ascending, last 0) and the spin marginal into `m_v`, `z_v`. Errors: wrong
    /// lengths (nothing written).
    pub fn state_into(
        &self,
        m_x: &mut [f64],
        z_x: &mut [f64],
        m_v: &mut [f64],
        z_v: &mut [f64],
    ) -> Result<()> {
        for (name, len, want) in [
            ("m_x", m_x.len(), 16),
            ("z_x", z_x.len(), 4),
            ("m_v", m_v.len(), 16),
            ("z_v", z_v.len(), 4),
        ] {
            if len != want {
                return Err(Error::InvalidDimension(format!(
                    "`{name}` must have length {want}, got {len}"
                )));
            }
        }
        self.x.write(m_x, z_x);
        self.v.write(m_v, z_v);
        Ok(())
    }

    /// The orientation marginal.
    pub fn orientation(&self) -> Bingham {
        Bingham::from_normalized_parts(&self.x.m, &self.x.z)
    }

    /// The spin marginal (the rotation per step, `x_{n+1} = v ∘ x_n`).
    pub fn spin(&self) -> Bingham {
        Bingham::from_normalized_parts(&self.v.m, &self.v.z)
    }

    /// The orientation's mode, a unit quaternion (scalar first; `−q` is the same rotation).
    pub fn orientation_mode(&self) -> [f64; 4] {
        self.x.mode()
    }

    /// The spin's mode: the most probable rotation per step, a unit quaternion (scalar first).
    pub fn spin_mode(&self) -> [f64; 4] {
        self.v.mode()
    }

    /// The angular spreads (radians) of the orientation (`x_out`) and of the spin (`v_out`,
    /// radians per step), each as [`super::BinghamFilter::angular_spread_into`]: entries 0–2
    /// along the principal directions (columns 0–2 of the marginal's `M`), entry 3 the total
    /// (the RMS of `2 sin(θ/2)`, θ the rotation angle from the mode). A uniform marginal gives
    /// the spread of uniform rotations. Errors: lengths not 4 (nothing written),
    /// [`Error::Numerical`] (moments of an extremely concentrated marginal).
    pub fn angular_spread_into(&self, x_out: &mut [f64], v_out: &mut [f64]) -> Result<()> {
        if x_out.len() != 4 || v_out.len() != 4 {
            return Err(Error::InvalidDimension(format!(
                "spread buffers must have length 4, got {} and {}",
                x_out.len(),
                v_out.len()
            )));
        }
        let wx = omega(&self.x.z)?;
        let wv = omega(&self.v.z)?;
        spread_from_omega(wx.as_slice(), x_out);
        spread_from_omega(wv.as_slice(), v_out);
        Ok(())
    }

    /// One time step: `v ← w ∘ u ∘ v`, `x ← v ∘ x` with the process noise `w ~ Bingham(m_w,
    /// z_w)` and the control `u` (unit within `UNIT_TOL`, or `None`: identity), and, when `y` is
    /// `Some`, the observation `y = o ∘ x` with `o ~ Bingham(m_o, z_o)` (`m_o`, `z_o` are
    /// ignored without `y`). See the module documentation for the algorithm.
    ///
    /// Errors: [`Error::InvalidDimension`] (lengths), [`Error::InvalidArgument`] (NaN/Inf,
    /// non-orthogonal `m`, `u` or `y` not unit), [`Error::NotConverged`] /
    /// [`Error::Numerical`] (moment matching, overflow). On error the filter is unchanged.
    pub fn step(
        &mut self,
        u: Option<&[f64]>,
        m_w: &[f64],
        z_w: &[f64],
        y: Option<&[f64]>,
        m_o: &[f64],
        z_o: &[f64],
    ) -> Result<()> {
        let u = u.map(|u| unit("u", Const::<4>, u)).transpose()?;
        let y = y.map(|y| unit("y", Const::<4>, y)).transpose()?;
        let w_moment = self.process.get(Role::Process, m_w, z_w)?.moment;
        let obs = match y {
            Some(y) => {
                let o = self.observation.get(Role::Observation, m_o, z_o)?;
                Some(observation_terms(&y, &o.m, &o.z, &o.moment))
            }
            None => None,
        };

        // Orientation: x_n = v_{n−1} ∘ x_{n−1}, then the observation.
        let (ax, av, mxp, zxp, warm_x) = {
            let p = self.prediction()?;
            (p.ax, p.av, p.m, p.z, p.sol.clone())
        };
        let x = match &obs {
            Some(o) => {
                let (m, z) = bayes_product(&mxp, &zxp, &o.precision)?;
                Marginal { m, z }
            }
            None => Marginal { m: mxp, z: zxp },
        };

        // Spin: B_v · (f_{y|x} ∘ B_x⁻¹), then rotated by u and composed with w.
        let (v_post, warm_g) = match &obs {
            Some(o) => {
                let d = conjugation::<4>();
                let b_inv = d * ax * d;
                let (mg, zg, warm_g) = fit_second_moment_nearest(
                    &compose_moments(&o.moment, &b_inv),
                    self.warm.evidence.iter(),
                )?;
                let (m, z) = bayes_product(&self.v.m, &self.v.z, &congruence(&mg, &zg))?;
                (Marginal { m, z }, Some(warm_g))
            }
            None => (self.v, None),
        };
        let lu = u.map(|u| left(Const::<4>, u.as_slice()));
        let a_post = match (&obs, lu) {
            // the spin unchanged by an observation: its moment is known, `L(u) A_v L(u)ᵀ`
            (None, Some(l)) => l * av * l.transpose(),
            (None, None) => av,
            (Some(_), Some(l)) => composed_moment(&(l * v_post.m), &v_post.z)?,
            (Some(_), None) => composed_moment(&v_post.m, &v_post.z)?,
        };
        let (mvn, zvn, warm_v) =
            fit_second_moment_nearest(&compose_moments(&w_moment, &a_post), self.warm.spin.iter())?;
        let v_moment = fitted_moment(&mvn, &zvn, &warm_v);

        self.x = x;
        self.v = Marginal { m: mvn, z: zvn };
        self.v_moment = v_moment;
        self.predicted = OnceLock::new();
        self.warm.orientation.push(warm_x);
        if let Some(g) = warm_g {
            self.warm.evidence.push(g);
        }
        self.warm.spin.push(warm_v);
        Ok(())
    }

    /// The orientation's prediction of the current state (see [`Prediction`]), computed now if
    /// no call has since the state last changed.
    fn prediction(&self) -> Result<&Prediction> {
        if let Some(p) = self.predicted.get() {
            return Ok(p);
        }
        let ax = composed_moment(&self.x.m, &self.x.z)?;
        let av = self.spin_moment()?;
        let (m, z, sol) =
            fit_second_moment_nearest(&compose_moments(&av, &ax), self.warm.orientation.iter())?;
        // Another thread may have set it meanwhile: the same value (same state, same starts).
        let _ = self.predicted.set(Prediction {
            ax,
            av,
            m,
            z,
            sol,
            log_f: OnceLock::new(),
        });
        self.predicted
            .get()
            .ok_or_else(|| Error::Numerical("spin filter: the prediction was not kept".into()))
    }

    /// The spin marginal's second moment (see [`SpinFilter::v_moment`]).
    fn spin_moment(&self) -> Result<Mat<4>> {
        match self.v_moment {
            Some(a) => Ok(a),
            None => composed_moment(&self.v.m, &self.v.z),
        }
    }

    /// The natural logarithm of the predictive density of the observation `y = o ∘ x_n`,
    /// `o ~ Bingham(m_o, z_o)`, before the step that would take it: `log ∫ f(y | x) (B_v ∘
    /// B_x)(x) dx`, a density on the unit sphere S³ (surface measure, antipodally symmetric),
    /// the quantity a bank of filters sums over time, and what picks between two
    /// interpretations of an ambiguous observation. The filter's state is not changed; the
    /// orientation's prediction this computes is kept until the state changes, so further
    /// calls and the next [`SpinFilter::step`] reuse it (the same bits as without it).
    ///
    /// Errors: as for [`SpinFilter::step`]'s observation.
    pub fn log_likelihood(&self, y: &[f64], m_o: &[f64], z_o: &[f64]) -> Result<f64> {
        let y = unit("y", Const::<4>, y)?;
        let o = self
            .observation
            .lookup_or_build(Role::Observation, m_o, z_o)?;
        let log_f_o = o.log_f()?;
        let pred = self.prediction()?;
        let log_f_x = match pred.log_f.get() {
            Some(v) => *v,
            None => {
                let v = log_f_omega(&pred.z)?.0;
                let _ = pred.log_f.set(v);
                v
            }
        };
        let p = congruence(&world_likelihood_m(&y, &o.m), &o.z);
        let value = log_joint_normalizer(&pred.m, &pred.z, &p)? - log_f_x - log_f_o;
        if !value.is_finite() {
            return Err(Error::Numerical(format!(
                "log-likelihood is not finite ({value})"
            )));
        }
        Ok(value)
    }
}

/// The second moment of the fitted `Bingham(m, z)` (the output of [`fit_second_moment_nearest`] with its
/// solution `sol`) without evaluating `ω(z)`: `M diag(ω) Mᵀ` with the `ω` the solver evaluated
/// at its last point, the same bits [`composed_moment`] computes when that point is `z` itself
/// (the solver's `z` already canonical, and within `MAX_CONCENTRATION`); `None` otherwise.
fn fitted_moment(m: &Mat<4>, z: &Vect<4>, sol: &Derivs<Const<4>>) -> Option<Mat<4>> {
    let same = z
        .iter()
        .zip(sol.z.iter())
        .all(|(a, b)| a.to_bits() == b.to_bits() && *a >= -MAX_CONCENTRATION);
    same.then(|| congruence(m, &sol.grad))
}

/// The observation's exponent in `x` (`M_L Z_o M_Lᵀ`, `M_L = R(y) D M_o`) and the second moment
/// of `Bingham(Z_o, M_L)` (`R(y) D S_o D R(y)ᵀ` from the noise's moment `S_o`).
fn observation_terms(y: &Vect<4>, m_o: &Mat<4>, z_o: &Vect<4>, s_o: &Mat<4>) -> ObservationTerms {
    let ml = world_likelihood_m(y, m_o);
    let r = right(Const::<4>, y.as_slice()) * conjugation::<4>();
    ObservationTerms {
        precision: congruence(&ml, z_o),
        moment: r * s_o * r.transpose(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quaternion::q4;

    /// The spin marginal's moment kept after a step is, bit for bit, the one evaluated from its
    /// parameters: a filter that keeps it and one that re-evaluates it run the same.
    #[test]
    fn kept_spin_moment_is_the_evaluated_one() {
        let id = [
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        let (z_w, z_o) = ([0.0, -400.0, -400.0, -400.0], [0.0, -40.0, -40.0, -10.0]);
        let spin = q4::from_rotation_vector(&[0.6, -0.5, 0.62]);
        let mut f = SpinFilter::new(&id, &[0.0; 4], &id, &[0.0, -3.0, -3.0, -3.0]).unwrap();
        let mut x = [0.5, 0.5, 0.5, 0.5];
        let mut kept = 0;
        for k in 0..120 {
            x = q4::mul(&spin, &x);
            // a small observation error, and every 7th step without an observation
            let o = q4::from_rotation_vector(&[0.01 * (k % 5) as f64, -0.02, 0.005]);
            let y = q4::mul(&o, &x);
            let u = (k % 3 == 0).then_some(spin);
            let obs = (k % 7 != 3).then_some(&y[..]);
            f.step(u.as_ref().map(|u| &u[..]), &id, &z_w, obs, &id, &z_o)
                .unwrap();
            if let Some(a) = f.v_moment {
                let b = composed_moment(&f.v.m, &f.v.z).unwrap();
                let bits = |m: &Mat<4>| m.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&a), bits(&b), "step {k}");
                kept += 1;
            }
        }
        assert!(kept >= 110, "kept {kept} of 120");
    }

    /// Weighing observations with `log_likelihood` before a step changes nothing: the shared
    /// prediction gives the same states bit for bit as steps alone, the same log-likelihoods
    /// on every call, and those are the predictive density computed from scratch (the
    /// orientation prediction fitted anew, `log_evidence` minus the noise's `log F`) to
    /// rounding.
    #[test]
    fn the_shared_prediction_changes_no_bit() {
        use crate::filter::state::log_evidence;
        let id = [
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        let (z_w, z_o) = ([0.0, -400.0, -400.0, -400.0], [0.0, -40.0, -40.0, -10.0]);
        let spin = q4::from_rotation_vector(&[0.9, 0.3, -0.4]);
        let new = || SpinFilter::new(&id, &[0.0; 4], &id, &[0.0, -3.0, -3.0, -3.0]).unwrap();
        let (mut weighed, mut plain) = (new(), new());
        let mut x = [0.6, -0.2, 0.5, 0.59].map(|v: f64| v / 0.9981f64.sqrt());
        let bits = |m: &[f64]| m.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        for k in 0..60 {
            x = q4::mul(&spin, &x);
            let o = q4::from_rotation_vector(&[0.02 * (k % 3) as f64, -0.03, 0.01]);
            let y = q4::mul(&o, &x);
            let y_flip = q4::mul(&y, &[0.0, 0.0, 0.0, 1.0]);
            let obs = (k % 5 != 2).then_some(&y[..]);
            let a = weighed.log_likelihood(&y, &id, &z_o).unwrap();
            let b = weighed.log_likelihood(&y_flip, &id, &z_o).unwrap();
            assert_eq!(
                a.to_bits(),
                weighed.log_likelihood(&y, &id, &z_o).unwrap().to_bits()
            );
            // from scratch, as before the prediction was shared
            let ax = composed_moment(&weighed.x.m, &weighed.x.z).unwrap();
            let av = weighed.spin_moment().unwrap();
            let (mxp, zxp, _) = fit_second_moment_nearest(
                &compose_moments(&av, &ax),
                weighed.warm.orientation.iter(),
            )
            .unwrap();
            let yv = Vect::<4>::from_column_slice(&y);
            let o = weighed
                .observation
                .lookup_or_build(Role::Observation, &id, &z_o)
                .unwrap();
            let p = congruence(&world_likelihood_m(&yv, &o.m), &o.z);
            let scratch = log_evidence(&mxp, &zxp, &p).unwrap() - o.log_f().unwrap();
            // (y is normalized on the way in; the test's is unit to rounding)
            assert!(
                (a - scratch).abs() <= 1e-12 * (1.0 + a.abs()),
                "step {k}: {a} vs {scratch}"
            );
            assert!(a.is_finite() && b.is_finite());
            weighed.step(None, &id, &z_w, obs, &id, &z_o).unwrap();
            plain.step(None, &id, &z_w, obs, &id, &z_o).unwrap();
            let state = |f: &SpinFilter| {
                let parts = [
                    f.x.m.as_slice(),
                    f.x.z.as_slice(),
                    f.v.m.as_slice(),
                    f.v.z.as_slice(),
                ];
                bits(&parts.concat())
            };
            assert_eq!(state(&weighed), state(&plain), "step {k}");
        }
    }
}
