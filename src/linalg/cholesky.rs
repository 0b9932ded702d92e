//! Small dense symmetric positive definite solves (the MLE's Newton step, the nonlinear
//! update's exponent fit), in place on caller buffers.

/// Solves `A x = b` in place (`a` k×k row-major symmetric positive definite, destroyed;
/// `b` overwritten by `x`) by Cholesky; `false` if `A` is not numerically positive definite.
pub(crate) fn cholesky_solve(k: usize, a: &mut [f64], b: &mut [f64]) -> bool {
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
