//! Small dense symmetric positive definite solves (the MLE's Newton step, the nonlinear
//! update's exponent fit), in place on caller buffers; and the 3×3 Cholesky factor with its
//! forward substitution (the offline smoother's product, the AHRS's stated uncertainty).

use nalgebra::{Matrix3, Vector3};

/// Solves `A x = b` in place (`a` k×k row-major symmetric positive definite, destroyed;
/// `b` overwritten by `x`) by Cholesky; `false` if `A` is not numerically positive definite.
/// k = 2 and 3 (the Newton steps of d = 3 and 4) run the same arithmetic with the size known
/// at compile time (unrolled), so every k gives the same bits as the loop.
pub(crate) fn cholesky_solve(k: usize, a: &mut [f64], b: &mut [f64]) -> bool {
    match k {
        2 => solve::<2>(a, b),
        3 => solve::<3>(a, b),
        _ => solve_k(k, a, b),
    }
}

/// [`cholesky_solve`] for `k = K`.
#[inline(always)]
fn solve<const K: usize>(a: &mut [f64], b: &mut [f64]) -> bool {
    solve_k(K, &mut a[..K * K], &mut b[..K])
}

/// [`cholesky_solve`]'s loop.
#[inline(always)]
fn solve_k(k: usize, a: &mut [f64], b: &mut [f64]) -> bool {
    for j in 0..k {
        let mut s = a[j * k + j];
        for p in 0..j {
            s -= a[j * k + p] * a[j * k + p];
        }
        // (written to also reject NaN)
        if s.is_nan() || s <= 0.0 {
            return false;
        }
        let l = s.sqrt();
        a[j * k + j] = l;
        for i in j + 1..k {
            let mut t = a[i * k + j];
            for p in 0..j {
                t -= a[i * k + p] * a[j * k + p];
            }
            a[i * k + j] = t / l;
        }
    }
    for i in 0..k {
        let mut t = b[i];
        for p in 0..i {
            t -= a[i * k + p] * b[p];
        }
        b[i] = t / a[i * k + i];
    }
    for i in (0..k).rev() {
        let mut t = b[i];
        for p in i + 1..k {
            t -= a[p * k + i] * b[p];
        }
        b[i] = t / a[i * k + i];
    }
    true
}

/// The Cholesky factor `L` (lower, `S = L Lᵀ`) of a symmetric 3×3 `S` (its lower triangle
/// read), packed as `[l00, l10, l11, l20, l21, l22]`; `None` unless `S` is positive definite
/// (a pivot zero, negative or NaN).
pub(crate) fn cholesky3(s: &Matrix3<f64>) -> Option<[f64; 6]> {
    let pivot = |d: f64| (d > 0.0).then(|| d.sqrt());
    let l00 = pivot(s[(0, 0)])?;
    let l10 = s[(1, 0)] / l00;
    let l20 = s[(2, 0)] / l00;
    let l11 = pivot(s[(1, 1)] - l10 * l10)?;
    let l21 = (s[(2, 1)] - l20 * l10) / l11;
    let l22 = pivot(s[(2, 2)] - l20 * l20 - l21 * l21)?;
    Some([l00, l10, l11, l20, l21, l22])
}

/// `L⁻¹ b` for the packed factor `l` of [`cholesky3`] (forward substitution).
pub(crate) fn forward3(l: &[f64; 6], b: &Vector3<f64>) -> Vector3<f64> {
    let y0 = b.x / l[0];
    let y1 = (b.y - l[1] * y0) / l[2];
    let y2 = (b.z - l[3] * y0 - l[4] * y1) / l[5];
    Vector3::new(y0, y1, y2)
}
