//! The Bingham distribution `f(x) = exp(xᵀ M Z Mᵀ x) / F(Z)` on S^{d−1}: the type [`Bingham`]
//! with its validation and normalization, density, moments, entropy, KL divergence, and the
//! Bayes product (multiply) and rotations the filter uses. The composition
//! ([`Bingham::compose`]) is moment matching and lives in [`crate::mle`], sampling
//! ([`Bingham::sample`]) in the sampler's module.
//!
//! The operations are generic over the dimension type (see the `matrix` module): [`Bingham`]
//! instantiates them with `Dyn`, the filter with `Const<2>` and `Const<4>` (on the stack).

use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, Dim, Dyn};

use crate::canonical::{check_normalize, normalize_eigen, params_row_major, unit};
pub use crate::canonical::{ORTHOGONALITY_TOL, UNIT_TOL};
use crate::error::{check_dim, check_finite, Error, Result};
use crate::linalg::{
    congruence, in_basis, sym_eigen, sym_eigen_in_basis, warm_basis, Square, Vector,
};
use crate::normalization::{log_f_canonical, omega_canonical};
use crate::quaternion::{left, right};

/// A Bingham distribution with `M` orthonormal (columns = principal directions, the last one
/// the mode) and `z` ascending with `z[d−1] = 0`.
#[derive(Debug, Clone, PartialEq)]
pub struct Bingham {
    m: DMatrix<f64>,
    z: DVector<f64>,
}

impl Bingham {
    /// Validates and normalizes parameters: `d` in 2..=64, all entries finite,
    /// `max |MᵀM − I| ≤ ORTHOGONALITY_TOL`. Sorts `z` ascending (moving the columns of `M`
    /// along), subtracts the largest entry (`z_d = 0`), and re-orthonormalizes `M`.
    pub fn new(m: DMatrix<f64>, z: DVector<f64>) -> Result<Bingham> {
        let d = z.len();
        check_dim(d)?;
        if m.nrows() != d || m.ncols() != d {
            return Err(Error::InvalidDimension(format!(
                "M is {}x{}, expected {d}x{d}",
                m.nrows(),
                m.ncols()
            )));
        }
        check_finite("z", z.as_slice())?;
        check_finite("M", m.as_slice())?;
        let (m, z) = check_normalize("M", &m, "z", &z)?;
        Ok(Bingham { m, z })
    }

    /// Like [`Bingham::new`] with `M` given row-major (`m.len() == d*d`) and `z.len() == d`.
    pub fn from_row_major(d: usize, m: &[f64], z: &[f64]) -> Result<Bingham> {
        check_dim(d)?;
        let (m, z) = params_row_major(Dyn(d), "M", m, "z", z)?;
        Ok(Bingham { m, z })
    }

    /// Wraps (copies) parameters of any dimension type that are already normalized (z
    /// ascending, `z_d = 0`, M orthonormal).
    pub(crate) fn from_normalized_parts<D: Dim>(m: &Square<D>, z: &Vector<D>) -> Bingham
    where
        DefaultAllocator: Allocator<D, D> + Allocator<D>,
    {
        let d = z.len();
        Bingham {
            m: DMatrix::from_column_slice(d, d, m.as_slice()),
            z: DVector::from_column_slice(z.as_slice()),
        }
    }

    /// The dimension `d` (the sphere is S^{d−1} ⊂ R^d).
    pub fn dim(&self) -> usize {
        self.z.len()
    }

    /// The orthonormal matrix `M` (columns are the principal directions, last = mode).
    pub fn m(&self) -> &DMatrix<f64> {
        &self.m
    }

    /// The concentrations, ascending, `z[d−1] = 0`.
    pub fn z(&self) -> &DVector<f64> {
        &self.z
    }

    /// `M` as a row-major array of length d².
    pub fn m_row_major(&self) -> Vec<f64> {
        self.m.transpose().as_slice().to_vec()
    }

    /// The mode (last column of `M`); `−mode` is a mode too (antipodal symmetry).
    pub fn mode(&self) -> DVector<f64> {
        self.m.column(self.dim() - 1).into_owned()
    }

    /// `log F(Z)` (surface measure, exact method).
    pub fn log_normalization(&self) -> Result<f64> {
        log_f_canonical(self.z.as_slice(), None, None)
    }

    /// `ω_i = E[(m_iᵀ x)²] = ∂ log F/∂z_i`, in the order of `z`.
    pub fn omega(&self) -> Result<DVector<f64>> {
        omega(&self.z)
    }

    /// `log F` and `ω` together.
    pub fn log_normalization_and_omega(&self) -> Result<(f64, DVector<f64>)> {
        log_f_omega(&self.z)
    }

    /// The second moment `S = E[x xᵀ] = M diag(ω) Mᵀ` (symmetric, trace 1).
    pub fn second_moment(&self) -> Result<DMatrix<f64>> {
        let w = self.omega()?;
        Ok(congruence(&self.m, &w))
    }

    /// `log f(x)` for a unit vector `x` (length d, `|‖x‖ − 1| ≤ UNIT_TOL`; normalized first).
    pub fn log_pdf(&self, x: &[f64]) -> Result<f64> {
        self.log_pdf_given(x, self.log_normalization()?)
    }

    /// `log f(x)` with `log F` already known (`log_f` = [`Bingham::log_normalization`]): for
    /// evaluating many points with one normalization.
    pub fn log_pdf_given(&self, x: &[f64], log_f: f64) -> Result<f64> {
        let x = unit("x", Dyn(self.dim()), x)?;
        Ok(self.exponent(&x) - log_f)
    }

    /// `f(x)`, see [`Bingham::log_pdf`].
    pub fn pdf(&self, x: &[f64]) -> Result<f64> {
        Ok(self.log_pdf(x)?.exp())
    }

    /// `xᵀ M Z Mᵀ x` (≤ 0).
    pub(crate) fn exponent(&self, x: &DVector<f64>) -> f64 {
        let c = self.m.tr_mul(x);
        c.iter().zip(self.z.iter()).map(|(c, z)| z * c * c).sum()
    }

    /// Differential entropy `−E[log f] = log F − Σ z_i ω_i` (nats, w.r.t. surface measure).
    pub fn entropy(&self) -> Result<f64> {
        let (lf, w) = self.log_normalization_and_omega()?;
        Ok(lf - self.z.dot(&w))
    }

    /// Kullback–Leibler divergence `KL(self ‖ other) = E_self[log self − log other]`
    /// (Glover 2013, App. A.8), exact. Both must have the same `d`.
    pub fn kl_divergence(&self, other: &Bingham) -> Result<f64> {
        if other.dim() != self.dim() {
            return Err(Error::InvalidDimension(format!(
                "KL divergence needs equal dimensions, got {} and {}",
                self.dim(),
                other.dim()
            )));
        }
        let (lf, w) = self.log_normalization_and_omega()?;
        let s = congruence(&self.m, &w);
        let lg = other.log_normalization()?;
        let c = other.m.transpose() * s * &other.m;
        let cross: f64 = (0..self.dim()).map(|i| other.z[i] * c[(i, i)]).sum();
        let kl = self.z.dot(&w) - lf - cross + lg;
        Ok(kl.max(0.0))
    }

    /// Bayes' product: the density proportional to `f_self · f_other` is Bingham with
    /// `C = M1 Z1 M1ᵀ + M2 Z2 M2ᵀ = V Λ Vᵀ`, `M = V`, `z = Λ − max Λ`.
    pub fn multiply(&self, other: &Bingham) -> Result<Bingham> {
        if other.dim() != self.dim() {
            return Err(Error::InvalidDimension(format!(
                "multiply needs equal dimensions, got {} and {}",
                self.dim(),
                other.dim()
            )));
        }
        let (m, z) = bayes_product(&self.m, &self.z, &other.precision())?;
        Ok(Bingham { m, z })
    }

    /// `M Z Mᵀ` (symmetric).
    pub(crate) fn precision(&self) -> DMatrix<f64> {
        congruence(&self.m, &self.z)
    }

    /// Distribution of `u ⊕ x` for a fixed unit `u` (d = 2: complex, d = 4: quaternion,
    /// scalar first): `M ← L(u) M`.
    pub fn rotate_left(&self, u: &[f64]) -> Result<Bingham> {
        let u = self.rotation_arg(u)?;
        Ok(Bingham {
            m: left(Dyn(self.dim()), u.as_slice()) * &self.m,
            z: self.z.clone(),
        })
    }

    /// Distribution of `x ⊕ u` for a fixed unit `u`: `M ← R(u) M` with `x ⊕ u = R(u) x`.
    pub fn rotate_right(&self, u: &[f64]) -> Result<Bingham> {
        let u = self.rotation_arg(u)?;
        Ok(Bingham {
            m: right(Dyn(self.dim()), u.as_slice()) * &self.m,
            z: self.z.clone(),
        })
    }

    fn rotation_arg(&self, u: &[f64]) -> Result<DVector<f64>> {
        let d = self.dim();
        if !(d == 2 || d == 4) {
            return Err(Error::InvalidDimension(format!(
                "rotation is defined for d = 2 and d = 4, got {d}"
            )));
        }
        unit("u", Dyn(d), u)
    }
}

/// `log F(z)` and `ω = ∇ log F(z)` (exact method; allocation-free for fixed sizes up to 4).
pub(crate) fn log_f_omega<D: Dim>(z: &Vector<D>) -> Result<(f64, Vector<D>)>
where
    DefaultAllocator: Allocator<D>,
{
    let (d, _) = z.shape_generic();
    let mut w = Vector::zeros_generic(d, nalgebra::U1);
    let lf = log_f_canonical(z.as_slice(), Some(w.as_mut_slice()), None)?;
    Ok((lf, w))
}

/// `ω = ∇ log F(z)` alone (exact method; allocation-free for fixed sizes up to 4; for d = 2
/// without the logarithm of `F`).
pub(crate) fn omega<D: Dim>(z: &Vector<D>) -> Result<Vector<D>>
where
    DefaultAllocator: Allocator<D>,
{
    let (d, _) = z.shape_generic();
    let mut w = Vector::zeros_generic(d, nalgebra::U1);
    omega_canonical(z.as_slice(), w.as_mut_slice())?;
    Ok(w)
}

/// The eigendecomposition `M1 Z1 M1ᵀ + P2 = V Λ Vᵀ` (Λ ascending, unshifted) behind Bayes'
/// product of `Bingham(m1, z1)` and the density `∝ exp(xᵀ P2 x)` (`P2` symmetric: a Bingham's
/// `M2 Z2 M2ᵀ`, or a vector observation's `κ K`). The caller can use `max Λ` (the log of the
/// normalization's shift). To keep the Jacobi iteration away from overflow for huge
/// concentrations the matrix is scaled by a power of two first (exact, and the Jacobi rotations
/// are invariant under it).
pub(crate) fn product_eigen_precision<D: Dim>(
    m1: &Square<D>,
    z1: &Vector<D>,
    p2: &Square<D>,
) -> Result<(Square<D>, Vector<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let mut c = congruence(m1, z1);
    for (v, p) in c.iter_mut().zip(p2.iter()) {
        *v += p;
    }
    scaled_eigen(c, sym_eigen)
}

/// [`product_eigen_precision`] with the eigendecomposition warm-started from the prior's
/// principal directions `m1` (when they are orthonormal enough, [`warm_basis`]; cold
/// otherwise): in that basis the matrix is `Z1 + M1ᵀ P2 M1`, nearly diagonal when the
/// likelihood moves the prior little (the filter's updates), and Jacobi converges in fewer
/// sweeps ([`sym_eigen_in_basis`]). The same eigenpairs as [`product_eigen_precision`] up to
/// rounding. Cold for d = 2 and when the decomposition in that basis fails (e.g. a
/// non-finite entry there).
pub(crate) fn product_eigen_precision_in_basis<D: Dim>(
    m1: &Square<D>,
    z1: &Vector<D>,
    p2: &Square<D>,
) -> Result<(Square<D>, Vector<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    // (n = 2 is one closed-form rotation either way: nothing to save)
    if z1.len() < 3 || !warm_basis(m1) {
        return product_eigen_precision(m1, z1, p2);
    }
    let mut b = in_basis(p2, m1);
    for i in 0..z1.len() {
        b[(i, i)] += z1[i];
    }
    // (a product that overflows in this basis, or any other failure there, is left to the
    // cold path and its scaling)
    scaled_eigen(b, |b| sym_eigen_in_basis(b, m1)).or_else(|_| product_eigen_precision(m1, z1, p2))
}

/// The eigendecomposition `eigen(c)` of the symmetric `c` with `c` scaled by a power of two
/// first when its largest entry is beyond 1e±100 (exact; the eigenvalues are scaled back, the
/// Jacobi rotations are invariant under it), which keeps the iteration away from overflow for
/// huge concentrations. Errors if an entry or an eigenvalue overflows.
fn scaled_eigen<D: Dim>(
    mut c: Square<D>,
    eigen: impl FnOnce(&Square<D>) -> Result<(Square<D>, Vector<D>)>,
) -> Result<(Square<D>, Vector<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let big = c.iter().fold(0.0f64, |big, v| big.max(v.abs()));
    if !big.is_finite() {
        return Err(Error::Numerical(
            "Bayes product: the concentrations overflow".into(),
        ));
    }
    let scale = if big > 1e100 || (big > 0.0 && big < 1e-100) {
        Some(big.log2().floor() as i32)
    } else {
        None
    };
    if let Some(e) = scale {
        let f = 2f64.powi(-e);
        c.iter_mut().for_each(|v| *v *= f);
    }
    let (v, mut l) = eigen(&c)?;
    if let Some(e) = scale {
        let f = 2f64.powi(e);
        l.iter_mut().for_each(|v| *v *= f);
        if !l.iter().all(|v| v.is_finite()) {
            return Err(Error::Numerical(
                "Bayes product: the concentrations overflow".into(),
            ));
        }
    }
    Ok((v, l))
}

/// Bayes' product of `Bingham(m1, z1)` and the density `∝ exp(xᵀ P2 x)`: the normalized
/// parameters of the posterior ([`product_eigen_precision`], then sorted, shifted and
/// re-orthonormalized).
pub(crate) fn bayes_product<D: Dim>(
    m1: &Square<D>,
    z1: &Vector<D>,
    p2: &Square<D>,
) -> Result<(Square<D>, Vector<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    normalized_product(product_eigen_precision(m1, z1, p2)?)
}

/// [`bayes_product`] with the eigendecomposition warm-started from the prior's principal
/// directions ([`product_eigen_precision_in_basis`]; the filter's update, where the posterior's
/// directions are near the prior's). The same result up to rounding.
pub(crate) fn bayes_product_in_basis<D: Dim>(
    m1: &Square<D>,
    z1: &Vector<D>,
    p2: &Square<D>,
) -> Result<(Square<D>, Vector<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    normalized_product(product_eigen_precision_in_basis(m1, z1, p2)?)
}

/// The normalized posterior parameters from the eigendecomposition `(V, Λ)` of its exponent.
fn normalized_product<D: Dim>((v, l): (Square<D>, Vector<D>)) -> Result<(Square<D>, Vector<D>)>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let (m, z) = normalize_eigen(&v, &l);
    if !z.iter().all(|v| v.is_finite()) {
        return Err(Error::Numerical(
            "Bayes product: the posterior concentrations overflow a double".into(),
        ));
    }
    Ok((m, z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::orthogonality_error;
    use crate::quaternion::{left, q4};
    use nalgebra::{Const, Matrix4, SMatrix, Vector4};
    use testkit::xorshift;

    /// A state like the AHRS's (`M` a Jacobi eigenbasis, concentrations −1e3 … −1e5, the
    /// first two nearly equal) and the evidence of a correction (a likelihood whose mode is a
    /// small rotation away, concentrations −1e2 … −1e4).
    fn state_and_evidence(
        r: &mut impl FnMut() -> f64,
    ) -> (Matrix4<f64>, Vector4<f64>, Matrix4<f64>) {
        let g = Matrix4::from_fn(|_, _| r());
        let (m, _) = sym_eigen(&(g + g.transpose())).unwrap();
        let z1 = -(10f64.powf(3.0 + 2.0 * (r() + 0.5)));
        let z = Vector4::new(
            z1,
            z1 * (1.0 - 1e-3 * (r() + 0.5)),
            -(10f64.powf(3.0 + 2.0 * (r() + 0.5))),
            0.0,
        );
        let u = q4::from_rotation_vector(&[1e-2 * r(), 1e-2 * r(), 1e-2 * r()]);
        let ml = left(Const::<4>, &u) * m;
        let zl = Vector4::new(
            -(10f64.powf(3.0 + 2.0 * r())),
            -(10f64.powf(3.0 + 2.0 * r())),
            -(10f64.powf(3.0 + 2.0 * r())),
            0.0,
        );
        (m, z, congruence(&ml, &zl))
    }

    /// The warm-started Bayes product against the cold one and against nalgebra's
    /// `SymmetricEigen` of the same exponent (its eigenvalues are accurate to a few ulps of
    /// ‖C‖, enough for concentrations ≥ 1e2): the same posterior up to rounding, orthonormal
    /// to a few ulps.
    #[test]
    fn warm_bayes_product_agrees_with_the_cold_one() {
        let mut r = xorshift(17);
        let eps = f64::EPSILON;
        let (mut worst_z, mut worst_na, mut worst_mode, mut worst_ortho) =
            (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for k in 0..300 {
            let (m, z, p) = state_and_evidence(&mut r);
            assert!(warm_basis(&m), "k = {k}");
            let (mw, zw) = bayes_product_in_basis(&m, &z, &p).unwrap();
            let (mc, zc) = bayes_product(&m, &z, &p).unwrap();
            let c = congruence(&m, &z) + p;
            let na = nalgebra::SymmetricEigen::new(c);
            let mut l: Vec<f64> = na.eigenvalues.iter().copied().collect();
            l.sort_by(f64::total_cmp);
            for i in 0..3 {
                worst_z = worst_z.max(((zw[i] - zc[i]) / zc[i]).abs());
                worst_na = worst_na.max(((zw[i] - (l[i] - l[3])) / zc[i]).abs());
            }
            assert_eq!(zw[3], 0.0);
            // the mode is separated by ≥ 1e2: within a few ulps · ‖C‖/gap of the cold one
            let s = if mw.column(3).dot(&mc.column(3)) < 0.0 {
                -1.0
            } else {
                1.0
            };
            worst_mode = worst_mode.max((mw.column(3) - mc.column(3) * s).amax());
            worst_ortho = worst_ortho.max(orthogonality_error(&mw));
        }
        // measured: 3.8e-15, 9.1e-15, 2.8e-15 and 4 ulps
        assert!(
            worst_z <= 1e-13 && worst_na <= 1e-13,
            "{worst_z:e} {worst_na:e}"
        );
        assert!(worst_mode <= 1e-14, "{worst_mode:e}");
        assert!(worst_ortho <= 6.0 * eps, "{worst_ortho:e}");
    }

    /// d = 2, a basis that is not orthonormal enough and a non-finite exponent take the cold
    /// path: bit for bit the cold result.
    #[test]
    fn warm_bayes_product_falls_back_to_the_cold_one() {
        let mut r = xorshift(19);
        let (m, z, p) = state_and_evidence(&mut r);
        let drifted = m * (1.0 + 8.0 * f64::EPSILON);
        assert_eq!(
            bayes_product_in_basis(&drifted, &z, &p).unwrap(),
            bayes_product(&drifted, &z, &p).unwrap()
        );
        let m2 = SMatrix::<f64, 2, 2>::new(0.6, -0.8, 0.8, 0.6);
        let z2 = nalgebra::Vector2::new(-50.0, 0.0);
        let p2 = SMatrix::<f64, 2, 2>::new(-3.0, 1.0, 1.0, -7.0);
        assert_eq!(
            bayes_product_in_basis(&m2, &z2, &p2).unwrap(),
            bayes_product(&m2, &z2, &p2).unwrap()
        );
        let huge = p * 1e306;
        assert!(bayes_product_in_basis(&m, &z, &huge).is_err());
        assert!(bayes_product(&m, &z, &huge).is_err());
    }
}
