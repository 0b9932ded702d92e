//! The normalization constant `F(Z) = ∫_{S^{d-1}} exp(xᵀ Z x) dx` (surface measure), its
//! logarithm, gradient and Hessian.
//!
//! The public functions accept `z` in any order and with any shift; they sort and shift
//! internally (`F(Z + cI) = e^c F(Z)`) and return derivatives in the order of the input.
//! The gradient of `log F` is `ω_i = ∂ log F / ∂z_i = E[x_i²]` (so `Σ ω_i = 1`), the Hessian of
//! `log F` is `∂ω_i/∂z_j = Cov(x_i², x_j²)`.

mod concentrated;
mod contour;
pub(crate) mod d2;
mod gauss;
mod quadrature;
#[doc(hidden)]
pub use quadrature::{log_f_sorted_fine, log_f_sorted_tuned, Path, KERNEL_ENV};
mod saddlepoint;

use crate::error::{check_dim, check_finite, Error, Result, MAX_DIM};

/// How to evaluate the normalization constant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// Exact to near machine precision: closed form (d = 2), 1-D Bessel quadrature (d = 3, 4),
    /// Laplace inversion along the steepest-descent contour (d ≥ 5); finite for every finite z.
    /// Measured against 65-digit references, for |z| up to 1e300: see `docs/accuracy.md`.
    #[default]
    Exact,
    /// The third-order saddlepoint approximation of Kume & Wood (2005). **Approximate**:
    /// relative errors of F up to several percent (measured: `docs/accuracy.md`); ω do not sum to
    /// exactly 1. Any d. Provided for comparison with other libraries.
    Saddlepoint,
}

/// Result of [`evaluate`]: `log F`, and on request its gradient and Hessian (input order).
#[derive(Debug, Clone, PartialEq)]
pub struct LogNormalization {
    /// `log F(Z)` (natural logarithm).
    pub log_f: f64,
    /// `ω_i = ∂ log F/∂z_i`, length d, empty unless requested.
    pub grad: Vec<f64>,
    /// `∂² log F/∂z_i∂z_j`, row-major d×d, empty unless requested.
    pub hess: Vec<f64>,
}

/// The evaluation of `method` on sorted, shifted input (`z` ascending, `z[d-1] = 0`, all
/// finite), with the d = 3, 4 quadrature on the kernel `path`. Writes the gradient / Hessian
/// (sorted order) when the slices are given; every `log_f_sorted*` below has this contract.
fn sorted_eval(
    method: Method,
    path: Path,
    z: &[f64],
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<f64> {
    match (method, z.len()) {
        (Method::Saddlepoint, _) => saddlepoint::log_f_sorted(z, grad, hess),
        (Method::Exact, 2) => d2::log_f_sorted(z, grad, hess),
        (Method::Exact, 3 | 4) => quadrature::log_f_sorted_on(path, z, grad, hess),
        (Method::Exact, _) => contour::log_f_sorted(z, grad, hess),
    }
}

/// Evaluates `log F(z)` and optionally its gradient (length d) and Hessian (d×d row-major)
/// into caller-provided slices, without heap allocation for d ≤ 4 with the exact method.
///
/// `z` may be in any order and shift. Errors: d outside 2..=64, non-finite `z`, slices of the
/// wrong length.
pub fn log_normalization_into(
    z: &[f64],
    method: Method,
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<f64> {
    log_normalization_on(z, method, Path::detected(), grad, hess)
}

/// Whether `z` is in the canonical form of a normalized distribution: finite, ascending,
/// `z[d−1] = 0`, `2 ≤ d ≤ MAX_DIM`.
pub(crate) fn is_canonical(z: &[f64]) -> bool {
    (2..=crate::error::MAX_DIM).contains(&z.len())
        && z.iter().all(|v| v.is_finite())
        && z.windows(2).all(|w| w[0] <= w[1])
        && z[z.len() - 1] == 0.0
}

/// `log F(z)` and on request `ω` (length d) and the Hessian (d×d row-major) with the exact
/// method, for `z` already in canonical form ([`is_canonical`]: what every normalized
/// distribution, the filter's state and noises and the deterministic points' plan hold).
///
/// The crate-private door for those callers: no validation, no sorting and no write-back
/// through a permutation (debug builds assert the form). The public door,
/// [`log_normalization_into`], validates and sorts. Errors: `NotConverged` / `Numerical` from
/// the evaluation, and `Numerical` if `log F` is not finite.
///
/// For d = 3, 4 without the Hessian, where every concentration below the mode is large
/// enough that the series of [`concentrated`] has an error bound below
/// `concentrated::TOL` = 1e-16 (about 95 and up), the series replaces the quadrature (same
/// accuracy, a fraction of the cost: the AHRS's posteriors all lie there).
pub(crate) fn log_f_canonical(
    z: &[f64],
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<f64> {
    debug_assert!(is_canonical(z), "not canonical: {z:?}");
    // d = 3, 4 concentrated (every concentration below the mode ≳ 95): the series, where its
    // error bound is below `concentrated::TOL`; otherwise (and for the Hessian) the exact path
    if hess.is_none() && (z.len() == 3 || z.len() == 4) {
        if let Some(series) = concentrated::evaluate(z, true) {
            if let Some(g) = grad {
                g.copy_from_slice(&series.omega[..z.len()]);
            }
            return Ok(series.log_f);
        }
    }
    let log_f = sorted_eval(Method::Exact, Path::detected(), z, grad, hess)?;
    if !log_f.is_finite() {
        return Err(Error::Numerical(format!(
            "log F is not finite for z = {z:?}"
        )));
    }
    Ok(log_f)
}

/// `ω = ∇ log F(z)` alone (exact method) into `grad` (length d) for canonical `z` (see
/// [`log_f_canonical`]). For d = 2 the closed form without `log F` (a logarithm); for d = 3, 4
/// concentrated, the series of `concentrated` where its bound is below `concentrated::TOL`.
pub(crate) fn omega_canonical(z: &[f64], grad: &mut [f64]) -> Result<()> {
    if z.len() == 2 {
        debug_assert!(is_canonical(z) && grad.len() == 2);
        let (w1, w2, _) = d2::pair_moments(z[0]);
        grad[0] = w1;
        grad[1] = w2;
        return Ok(());
    }
    if z.len() == 3 || z.len() == 4 {
        debug_assert!(is_canonical(z) && grad.len() == z.len());
        if let Some(series) = concentrated::evaluate(z, false) {
            grad.copy_from_slice(&series.omega[..z.len()]);
            return Ok(());
        }
    }
    log_f_canonical(z, Some(grad), None).map(|_| ())
}

/// `ω = ∇ log F(z)` by the series of `concentrated` into `grad` (length d) for canonical `z`
/// ([`is_canonical`]) of d = 3, 4 where the series' error bound is below `concentrated::TOL`
/// (every concentration below the mode ≳ 95); `false`, `grad` untouched, elsewhere (other d,
/// `z` not canonical, the bound not met). The MLE's Newton iteration asks for it to know
/// whether the series served (it then takes the Hessian from the series too).
pub(crate) fn omega_series(z: &[f64], grad: &mut [f64]) -> bool {
    if !((z.len() == 3 || z.len() == 4) && grad.len() == z.len() && is_canonical(z)) {
        return false;
    }
    match concentrated::evaluate(z, false) {
        Some(series) => {
            grad.copy_from_slice(&series.omega[..z.len()]);
            true
        }
        None => false,
    }
}

/// [`log_normalization_into`] with the exact method and the d = 3, 4 quadrature on the given
/// kernel (for tests and benchmarks; other d ignore `path`). Errors as
/// [`log_normalization_into`], and `InvalidArgument` if the CPU cannot run `path`.
#[doc(hidden)]
pub fn log_f_with_path(
    z: &[f64],
    path: Path,
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<f64> {
    if !path.available() {
        return Err(Error::InvalidArgument(format!(
            "path {path:?} is not available on this CPU"
        )));
    }
    log_normalization_on(z, Method::Exact, path, grad, hess)
}

/// [`log_normalization_into`] with the d = 3, 4 kernel `path` (available on this CPU).
fn log_normalization_on(
    z: &[f64],
    method: Method,
    path: Path,
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<f64> {
    let d = z.len();
    check_dim(d)?;
    check_finite("z", z)?;
    if grad.as_ref().is_some_and(|g| g.len() != d) {
        return Err(Error::InvalidDimension(
            "gradient buffer length must be d".into(),
        ));
    }
    if hess.as_ref().is_some_and(|h| h.len() != d * d) {
        return Err(Error::InvalidDimension(
            "Hessian buffer length must be d*d".into(),
        ));
    }
    // small d (the filter's hot path) on small stack arrays, without heap allocation
    if d <= 4 {
        sorted_call::<4>(z, method, path, grad, hess)
    } else {
        sorted_call::<MAX_DIM>(z, method, path, grad, hess)
    }
}

/// Sorts and shifts `z` (`d ≤ N`, validated), evaluates, and writes the derivatives back in
/// input order.
#[inline(always)]
fn sorted_call<const N: usize>(
    z: &[f64],
    method: Method,
    path: Path,
    grad: Option<&mut [f64]>,
    hess: Option<&mut [f64]>,
) -> Result<f64> {
    let d = z.len();
    // Sort ascending (stable), remembering where each sorted entry came from.
    let mut perm = [0usize; N];
    for (i, p) in perm.iter_mut().enumerate().take(d) {
        *p = i;
    }
    let perm = &mut perm[..d];
    if N <= 4 {
        // insertion sort: a handful of comparisons, the order of `sort_by`
        for i in 1..d {
            let mut k = i;
            while k > 0 && z[perm[k]].total_cmp(&z[perm[k - 1]]).is_lt() {
                perm.swap(k, k - 1);
                k -= 1;
            }
        }
    } else {
        perm.sort_by(|&a, &b| z[a].total_cmp(&z[b]));
    }
    let shift = z[perm[d - 1]];
    let mut zs = [0.0f64; N];
    for (k, &p) in perm.iter().enumerate() {
        zs[k] = z[p] - shift;
    }
    zs[d - 1] = 0.0;
    let zs = &zs[..d];
    // The shift z − max z overflows when the entries span more than the largest double
    // (e.g. z = (MAX, −MAX)): refused, like the distribution constructors do.
    if !zs[0].is_finite() {
        return Err(Error::InvalidArgument(
            "z: max z − min z overflows a double; the concentrations must span less than \
             about 1.8e308"
                .into(),
        ));
    }
    let eval = |zs: &[f64], g: Option<&mut [f64]>, h: Option<&mut [f64]>| {
        sorted_eval(method, path, zs, g, h)
    };
    let mut gs = [0.0f64; N];
    let want_grad = grad.is_some();
    let log_f = match hess {
        None => eval(zs, want_grad.then_some(&mut gs[..d]), None)?,
        Some(h) => {
            let mut small = [0.0f64; 16];
            let mut big = Vec::new();
            let hs: &mut [f64] = if d <= 4 {
                &mut small[..d * d]
            } else {
                big.resize(d * d, 0.0);
                &mut big
            };
            let lf = eval(zs, Some(&mut gs[..d]), Some(&mut *hs))?;
            for a in 0..d {
                for b in 0..d {
                    h[perm[a] * d + perm[b]] = hs[a * d + b];
                }
            }
            lf
        }
    };
    if let Some(g) = grad {
        for (k, &p) in perm.iter().enumerate() {
            g[p] = gs[k];
        }
    }
    let log_f = log_f + shift;
    if !log_f.is_finite() {
        return Err(Error::Numerical(format!(
            "log F is not finite for z = {z:?}"
        )));
    }
    Ok(log_f)
}

/// `log F(z)` with the exact method. See [`log_normalization_into`].
pub fn log_normalization(z: &[f64]) -> Result<f64> {
    log_normalization_into(z, Method::Exact, None, None)
}

/// `log F`, gradient and (if `hessian`) Hessian of `log F`, allocated. See [`log_normalization_into`].
pub fn evaluate(z: &[f64], method: Method, hessian: bool) -> Result<LogNormalization> {
    let d = z.len();
    check_dim(d)?;
    let mut grad = vec![0.0; d];
    let mut hess = if hessian {
        vec![0.0; d * d]
    } else {
        Vec::new()
    };
    let log_f = log_normalization_into(
        z,
        method,
        Some(&mut grad),
        if hessian { Some(&mut hess) } else { None },
    )?;
    Ok(LogNormalization { log_f, grad, hess })
}
