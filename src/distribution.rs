//! The Bingham distribution `f(x) = exp(xᵀ M Z Mᵀ x) / F(Z)` on S^{d−1}: validation and
//! normalization of parameters, density, moments, entropy, KL divergence, and the operations
//! of the filter (multiply, compose, rotate).

use nalgebra::{DMatrix, DVector};

use crate::error::{check_dim, check_finite, Error, Result};
use crate::normalization::{log_normalization_into, Method};
use crate::quaternion::{left_matrix, right_matrix};

/// Largest accepted `max |MᵀM − I|` for a user-supplied `M`; `M` is then re-orthonormalized.
pub const ORTHOGONALITY_TOL: f64 = 1e-6;
/// Largest accepted `|‖x‖ − 1|` for a user-supplied unit vector; it is then normalized.
pub const UNIT_TOL: f64 = 1e-6;

/// A Bingham distribution with `M` orthonormal (columns = principal directions, the last one
/// the mode) and `z` ascending with `z[d−1] = 0`.
#[derive(Debug, Clone, PartialEq)]
pub struct Bingham {
    m: DMatrix<f64>,
    z: DVector<f64>,
}

/// Max-abs deviation of `MᵀM` from the identity.
pub(crate) fn orthogonality_error(m: &DMatrix<f64>) -> f64 {
    let g = m.transpose() * m;
    let mut e: f64 = 0.0;
    for i in 0..g.nrows() {
        for j in 0..g.ncols() {
            let t = if i == j { 1.0 } else { 0.0 };
            e = e.max((g[(i, j)] - t).abs());
        }
    }
    e
}

/// Modified Gram–Schmidt (twice), from the last column (the mode) to the first, so the mode's
/// direction is kept exactly up to rounding.
pub(crate) fn reorthonormalize(m: &mut DMatrix<f64>) {
    let d = m.ncols();
    for _pass in 0..2 {
        for j in (0..d).rev() {
            for k in (j + 1)..d {
                let dot = m.column(j).dot(&m.column(k));
                let ck = m.column(k).into_owned();
                m.column_mut(j).axpy(-dot, &ck, 1.0);
            }
            let n = m.column(j).norm();
            m.column_mut(j).scale_mut(1.0 / n);
        }
    }
}

/// Checks that `x` has length `d`, is finite and has unit norm within [`UNIT_TOL`]; returns it normalized.
pub(crate) fn unit_vector(what: &str, d: usize, x: &[f64]) -> Result<DVector<f64>> {
    if x.len() != d {
        return Err(Error::InvalidDimension(format!(
            "{what} has length {}, expected d = {d}",
            x.len()
        )));
    }
    check_finite(what, x)?;
    let v = DVector::from_column_slice(x);
    let n = v.norm();
    if (n - 1.0).abs() > UNIT_TOL {
        return Err(Error::InvalidArgument(format!(
            "{what} must be a unit vector: its norm is {n} (tolerance {UNIT_TOL})"
        )));
    }
    Ok(v / n)
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
        let err = orthogonality_error(&m);
        if err.is_nan() || err > ORTHOGONALITY_TOL {
            return Err(Error::InvalidArgument(format!(
                "M is not orthogonal: max |MᵀM − I| = {err:e} exceeds {ORTHOGONALITY_TOL:e}"
            )));
        }
        let b = Self::from_parts_unchecked(m, z);
        // The shift z − max z overflows when the entries span more than the largest double
        // (e.g. z = (MAX, −MAX)): refuse instead of returning a −Inf concentration.
        if !b.z.iter().all(|v| v.is_finite()) {
            return Err(Error::InvalidArgument(
                "z: max z − min z overflows a double; the concentrations must span less than \
                 about 1.8e308"
                    .into(),
            ));
        }
        Ok(b)
    }

    /// Like [`Bingham::new`] with `M` given row-major (`m.len() == d*d`) and `z.len() == d`.
    pub fn from_row_major(d: usize, m: &[f64], z: &[f64]) -> Result<Bingham> {
        check_dim(d)?;
        if m.len() != d * d || z.len() != d {
            return Err(Error::InvalidDimension(format!(
                "expected M of length {} and z of length {d}, got {} and {}",
                d * d,
                m.len(),
                z.len()
            )));
        }
        Self::new(
            DMatrix::from_row_slice(d, d, m),
            DVector::from_column_slice(z),
        )
    }

    /// Sort, shift and re-orthonormalize without validation (for internally produced,
    /// finite, orthonormal-to-rounding parameters).
    pub(crate) fn from_parts_unchecked(m: DMatrix<f64>, z: DVector<f64>) -> Bingham {
        let d = z.len();
        let mut idx: Vec<usize> = (0..d).collect();
        idx.sort_by(|&a, &b| z[a].total_cmp(&z[b]));
        let zmax = z[idx[d - 1]];
        let zs = DVector::from_iterator(d, idx.iter().map(|&i| z[i] - zmax));
        let mut ms = DMatrix::zeros(d, d);
        for (k, &i) in idx.iter().enumerate() {
            ms.set_column(k, &m.column(i));
        }
        reorthonormalize(&mut ms);
        let mut zs = zs;
        zs[d - 1] = 0.0;
        Bingham { m: ms, z: zs }
    }

    /// Wraps parameters that are already normalized (z ascending, `z_d = 0`, M orthonormal).
    pub(crate) fn from_normalized_unchecked(m: DMatrix<f64>, z: DVector<f64>) -> Bingham {
        Bingham { m, z }
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
        log_normalization_into(self.z.as_slice(), Method::Exact, None, None)
    }

    /// `ω_i = E[(m_iᵀ x)²] = ∂ log F/∂z_i`, in the order of `z`.
    pub fn omega(&self) -> Result<DVector<f64>> {
        let mut w = DVector::zeros(self.dim());
        log_normalization_into(
            self.z.as_slice(),
            Method::Exact,
            Some(w.as_mut_slice()),
            None,
        )?;
        Ok(w)
    }

    /// `log F` and `ω` together.
    pub fn log_normalization_and_omega(&self) -> Result<(f64, DVector<f64>)> {
        let mut w = DVector::zeros(self.dim());
        let lf = log_normalization_into(
            self.z.as_slice(),
            Method::Exact,
            Some(w.as_mut_slice()),
            None,
        )?;
        Ok((lf, w))
    }

    /// The second moment `S = E[x xᵀ] = M diag(ω) Mᵀ` (symmetric, trace 1).
    pub fn second_moment(&self) -> Result<DMatrix<f64>> {
        let w = self.omega()?;
        Ok(moment_from_parts(&self.m, &w))
    }

    /// `log f(x)` for a unit vector `x` (length d, `|‖x‖ − 1| ≤ UNIT_TOL`; normalized first).
    pub fn log_pdf(&self, x: &[f64]) -> Result<f64> {
        self.log_pdf_given(x, self.log_normalization()?)
    }

    /// `log f(x)` with `log F` already known (`log_f` = [`Bingham::log_normalization`]): for
    /// evaluating many points with one normalization.
    pub fn log_pdf_given(&self, x: &[f64], log_f: f64) -> Result<f64> {
        let x = unit_vector("x", self.dim(), x)?;
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
        let s = moment_from_parts(&self.m, &w);
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
        let c = self.precision() + other.precision();
        from_symmetric(c)
    }

    /// `M Z Mᵀ` (symmetric).
    pub(crate) fn precision(&self) -> DMatrix<f64> {
        let mz = &self.m * DMatrix::from_diagonal(&self.z);
        let c = mz * self.m.transpose();
        (&c + c.transpose()) * 0.5
    }

    /// Composition `x ⊕ y` of independent `x ~ self`, `y ~ other` (complex multiplication for
    /// d = 2, Hamilton product for d = 4), approximated by the Bingham with the same second
    /// moment (exact moment matching: `E[(x⊕y)(x⊕y)ᵀ] = Σ_ab A_ab L_a B L_bᵀ`, then the MLE).
    pub fn compose(&self, other: &Bingham) -> Result<Bingham> {
        let d = self.dim();
        if other.dim() != d || !(d == 2 || d == 4) {
            return Err(Error::InvalidDimension(format!(
                "composition is defined for d = 2 (complex) and d = 4 (quaternions) with equal \
                 dimensions, got {} and {}",
                d,
                other.dim()
            )));
        }
        let a = self.second_moment()?;
        let b = other.second_moment()?;
        let c = compose_moments(&a, &b);
        crate::mle::mle_from_second_moment(&c)
    }

    /// Distribution of `u ⊕ x` for a fixed unit `u` (d = 2: complex, d = 4: quaternion,
    /// scalar first): `M ← L(u) M`.
    pub fn rotate_left(&self, u: &[f64]) -> Result<Bingham> {
        let u = self.rotation_arg(u)?;
        Ok(Bingham {
            m: left_matrix(u.as_slice()) * &self.m,
            z: self.z.clone(),
        })
    }

    /// Distribution of `x ⊕ u` for a fixed unit `u`: `M ← R(u) M` with `x ⊕ u = R(u) x`.
    pub fn rotate_right(&self, u: &[f64]) -> Result<Bingham> {
        let u = self.rotation_arg(u)?;
        Ok(Bingham {
            m: right_matrix(u.as_slice()) * &self.m,
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
        unit_vector("u", d, u)
    }

    /// Draws `n` independent samples (unit vectors) by exact rejection sampling from an angular
    /// central Gaussian envelope (Kent, Ganeiber & Mardia 2013). Deterministic for a seeded `rng`.
    pub fn sample<R: rand::Rng + ?Sized>(&self, rng: &mut R, n: usize) -> Vec<DVector<f64>> {
        crate::sample::Sampler::new(self).sample(rng, n)
    }
}

/// `M diag(w) Mᵀ`, symmetrized.
pub(crate) fn moment_from_parts(m: &DMatrix<f64>, w: &DVector<f64>) -> DMatrix<f64> {
    let s = m * DMatrix::from_diagonal(w) * m.transpose();
    (&s + s.transpose()) * 0.5
}

/// Eigendecomposition of a symmetric matrix, ascending eigenvalues with matching columns;
/// each column's sign chosen so its largest-magnitude entry is positive (deterministic output).
pub(crate) fn sym_eigen_ascending(c: DMatrix<f64>) -> Result<(DMatrix<f64>, DVector<f64>)> {
    let d = c.nrows();
    if !c.iter().all(|v| v.is_finite()) {
        return Err(Error::Numerical(
            "eigendecomposition of a non-finite matrix".into(),
        ));
    }
    let (eigenvalues, eigenvectors) = crate::linalg::jacobi_eigen(&c);
    let mut idx: Vec<usize> = (0..d).collect();
    idx.sort_by(|&a, &b| eigenvalues[a].total_cmp(&eigenvalues[b]));
    let vals = DVector::from_iterator(d, idx.iter().map(|&i| eigenvalues[i]));
    let mut vecs = DMatrix::zeros(d, d);
    for (k, &i) in idx.iter().enumerate() {
        let mut col = eigenvectors.column(i).into_owned();
        let big = col
            .iter()
            .cloned()
            .fold(0.0f64, |acc, v| if v.abs() > acc.abs() { v } else { acc });
        if big < 0.0 {
            col.neg_mut();
        }
        vecs.set_column(k, &col);
    }
    if !vals.iter().all(|v| v.is_finite()) || !vecs.iter().all(|v| v.is_finite()) {
        return Err(Error::Numerical(
            "eigendecomposition produced non-finite values".into(),
        ));
    }
    Ok((vecs, vals))
}

/// The Bingham with precision matrix `C` (symmetric): eigenvectors and shifted eigenvalues.
pub(crate) fn from_symmetric(c: DMatrix<f64>) -> Result<Bingham> {
    let (v, l) = sym_eigen_ascending(c)?;
    let b = Bingham::from_parts_unchecked(v, l);
    if !b.z.iter().all(|v| v.is_finite()) {
        return Err(Error::Numerical(
            "the resulting concentrations overflow a double".into(),
        ));
    }
    Ok(b)
}

/// `Σ_ab A_ab L_a B L_bᵀ`: the second moment of `x ⊕ y` (d = 2 or 4).
pub(crate) fn compose_moments(a: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    let d = a.nrows();
    let basis: Vec<DMatrix<f64>> = (0..d)
        .map(|k| {
            let mut e = vec![0.0; d];
            e[k] = 1.0;
            left_matrix(&e)
        })
        .collect();
    let lb: Vec<DMatrix<f64>> = basis.iter().map(|l| l * b).collect();
    let mut c = DMatrix::zeros(d, d);
    for i in 0..d {
        for j in 0..d {
            if a[(i, j)] != 0.0 {
                c += (&lb[i] * basis[j].transpose()) * a[(i, j)];
            }
        }
    }
    (&c + c.transpose()) * 0.5
}
