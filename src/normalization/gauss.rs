//! Gauss–Legendre rules computed at compile time (no tables to mistype).

/// cos(x) for |x| ≤ π by a Taylor series (const context; only seeds Newton's method).
const fn cos_seed(x: f64) -> f64 {
    let x2 = x * x;
    let mut term = 1.0;
    let mut sum = 1.0;
    let mut k = 1;
    while k < 30 {
        term = -term * x2 / ((2 * k - 1) as f64 * (2 * k) as f64);
        sum += term;
        k += 1;
    }
    sum
}

/// Legendre polynomial P_n(x) and its derivative.
const fn legendre(n: usize, x: f64) -> (f64, f64) {
    let mut p0 = 1.0;
    let mut p1 = x;
    let mut k = 2;
    while k <= n {
        let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
        p0 = p1;
        p1 = p2;
        k += 1;
    }
    let dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
    (p1, dp)
}

/// An N-point Gauss–Legendre rule on [0, 1]: `(nodes, weights)`, nodes ascending.
pub(crate) const fn gauss_legendre_unit<const N: usize>() -> ([f64; N], [f64; N]) {
    let mut nodes = [0.0; N];
    let mut weights = [0.0; N];
    let mut i = 0;
    while i < N {
        // i-th root of P_N, descending in x; Newton from the Tricomi-type seed.
        let mut x = cos_seed(std::f64::consts::PI * (i as f64 + 0.75) / (N as f64 + 0.5));
        let mut it = 0;
        while it < 100 {
            let (p, dp) = legendre(N, x);
            let dx = p / dp;
            x -= dx;
            it += 1;
            if dx < 1e-17 && dx > -1e-17 {
                break;
            }
        }
        let (_, dp) = legendre(N, x);
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        // map [-1, 1] -> [0, 1], ascending order
        nodes[N - 1 - i] = 0.5 * (1.0 + x);
        weights[N - 1 - i] = 0.5 * w;
        i += 1;
    }
    (nodes, weights)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_polynomials_exactly() {
        const R: ([f64; 12], [f64; 12]) = gauss_legendre_unit::<12>();
        for p in 0..24 {
            let s: f64 = R.0.iter().zip(R.1.iter()).map(|(x, w)| w * x.powi(p)).sum();
            let exact = 1.0 / (p as f64 + 1.0);
            assert!((s - exact).abs() < 2e-16 * 4.0, "p = {p}: {s} vs {exact}");
        }
        let sw: f64 = R.1.iter().sum();
        assert!((sw - 1.0).abs() < 4e-16);
    }
}
