//! Small dense symmetric positive definite solves (the MLE's Newton step, the nonlinear
//! update's exponent fit), in place on caller buffers.

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
