//! The exact normalization constant for d ≥ 5 (steepest-descent Laplace inversion), through the
//! public API, against references that do not use the method under test:
//!
//! * `z = 0`: `F = |S^{d−1}| = 2π^{d/2}/Γ(d/2)`, `ω = 1/d`, and the exact fourth moments;
//! * nested sphere quadrature: split the coordinates into blocks ("atoms") of equal values or
//!   pairs, `x = (√u·a, √(1−u)·b)` with `a`, `b` on the smaller spheres, which gives
//!   `F(blocks) = ½ ∫₀¹ F_A(u z_A) F_B((1−u) z_B) u^{p/2−1} (1−u)^{q/2−1} du` recursively, with
//!   `F = |S^{p−1}| e^{v}` for a block of `p` equal values `v` and the closed form
//!   `2π e^{(a+b)/2} I0((a−b)/2)` for a pair (I0, I1 by their power series here). Tanh–sinh
//!   panels, split at the boundary layers, and a convergence check of the reference itself;
//!   ω from the derivatives of the same integrals;
//! * the high-precision files `tests/data/normalization_d{5..8}.csv`, when present;
//! * identities: `Σ ω = 1`, permutation and shift invariance, symmetric Hessian with zero row sums.

use bingham::normalization::{evaluate, log_normalization_into, Method};
use std::f64::consts::PI;
use testkit::{read_reference, xorshift_uniform};

/// `log |S^{d−1}|` by the recursion `|S^{d−1}| = 2π/(d−2)·|S^{d−3}|`.
fn log_sphere_area(d: usize) -> f64 {
    let mut area: f64 = if d % 2 == 1 { 2.0 } else { 2.0 * PI };
    let mut k = if d % 2 == 1 { 1 } else { 2 };
    while k < d {
        area *= 2.0 * PI / k as f64;
        k += 2;
    }
    area.ln()
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

#[test]
fn zero_matrix_gives_the_sphere_area_and_uniform_moments() {
    for d in 5..=64 {
        let z = vec![0.0; d];
        let e = evaluate(&z, Method::Exact, d <= 12).unwrap();
        let exact = log_sphere_area(d);
        assert!(
            (e.log_f - exact).abs() < 4e-15 * exact.abs().max(1.0),
            "d = {d}: {} vs {exact}",
            e.log_f
        );
        for &w in &e.grad {
            assert!(rel(w, 1.0 / d as f64) < 1e-14, "d = {d}: ω = {w}");
        }
        if d <= 12 {
            let df = d as f64;
            for i in 0..d {
                for k in 0..d {
                    let e4 = if i == k { 3.0 } else { 1.0 } / (df * (df + 2.0));
                    assert!((e.hess[i * d + k] - (e4 - 1.0 / (df * df))).abs() < 1e-15);
                }
            }
        }
    }
}

/// A block of the nested reference: `p` equal values, or a pair of values.
#[derive(Clone, Copy, Debug)]
enum Atom {
    Equal(f64, usize),
    Pair(f64, f64),
}

impl Atom {
    fn dim(self) -> usize {
        match self {
            Atom::Equal(_, p) => p,
            Atom::Pair(..) => 2,
        }
    }
    fn params(self) -> usize {
        match self {
            Atom::Equal(..) => 1,
            Atom::Pair(..) => 2,
        }
    }
    fn scaled(self, t: f64) -> Atom {
        match self {
            Atom::Equal(v, p) => Atom::Equal(v * t, p),
            Atom::Pair(a, b) => Atom::Pair(a * t, b * t),
        }
    }
    fn magnitudes(self) -> Vec<f64> {
        match self {
            Atom::Equal(v, _) => vec![v.abs()],
            Atom::Pair(a, b) => vec![a.abs(), b.abs(), (a - b).abs()],
        }
    }
}

/// `I0(x)e^{−x}` and `I1(x)e^{−x}` for `0 ≤ x ≤ 40` by the power series (all terms positive).
fn i01e_series(x: f64) -> (f64, f64) {
    assert!((0.0..=40.0).contains(&x));
    let q = 0.25 * x * x;
    let (mut t0, mut t1) = (1.0, 1.0);
    let (mut s0, mut s1) = (1.0, 1.0);
    let mut k = 1.0;
    while t0 > 1e-18 * s0 || t1 > 1e-18 * s1 {
        t0 *= q / (k * k);
        t1 *= q / (k * (k + 1.0));
        s0 += t0;
        s1 += t1;
        k += 1.0;
    }
    let e = (-x).exp();
    (s0 * e, 0.5 * x * s1 * e)
}

/// `|S^{p−1}|`.
fn sphere_area(p: usize) -> f64 {
    log_sphere_area(p).exp()
}

/// `F` of one atom and its derivatives with respect to the atom's values.
fn atom_f(atom: Atom) -> (f64, Vec<f64>) {
    match atom {
        Atom::Equal(v, p) => {
            let f = sphere_area(p) * v.exp();
            (f, vec![f])
        }
        Atom::Pair(a, b) => {
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            let (i0, i1) = i01e_series(0.5 * (hi - lo));
            let f = 2.0 * PI * hi.exp() * i0;
            let (w_lo, w_hi) = ((i0 - i1) / (2.0 * i0), (i0 + i1) / (2.0 * i0));
            if a <= b {
                (f, vec![f * w_lo, f * w_hi])
            } else {
                (f, vec![f * w_hi, f * w_lo])
            }
        }
    }
}

/// Tanh–sinh nodes on [0, 1]: `(u, 1 − u, weight)`.
fn tanh_sinh_unit(h: f64) -> Vec<(f64, f64, f64)> {
    let n = (4.2 / h).ceil() as i64;
    (-n..=n)
        .filter_map(|k| {
            let t = k as f64 * h;
            let v = 0.5 * PI * t.sinh();
            let (u, um) = (
                1.0 / (1.0 + (-2.0 * v).exp()),
                1.0 / (1.0 + (2.0 * v).exp()),
            );
            let w = h * 0.5 * PI * t.cosh() * 2.0 * u * um;
            (w > 1e-300).then_some((u, um, w))
        })
        .collect()
}

/// The nested reference: `F` and its derivatives with respect to every atom value.
fn nested(atoms: &[Atom], h: f64) -> (f64, Vec<f64>) {
    if atoms.len() == 1 {
        return atom_f(atoms[0]);
    }
    let (first, rest) = (atoms[0], &atoms[1..]);
    let p = first.dim() as f64;
    let q: f64 = rest.iter().map(|a| a.dim() as f64).sum();
    // Panels split at the boundary layers of large values: u ~ 1/|v| near 0 for the first
    // atom, 1 − u ~ 1/|v| near 1 for the rest (tanh–sinh copes with milder ones by itself).
    let mut cuts = vec![0.0, 1.0];
    for (m, near_one) in first
        .magnitudes()
        .into_iter()
        .map(|m| (m, false))
        .chain(rest.iter().flat_map(|a| a.magnitudes()).map(|m| (m, true)))
    {
        if m > 30.0 {
            for c in [1.0, 8.0, 64.0] {
                if c < m {
                    cuts.push(if near_one { 1.0 - c / m } else { c / m });
                }
            }
        }
    }
    cuts.sort_by(f64::total_cmp);
    cuts.dedup_by(|a, b| (*a - *b).abs() < 1e-12 * b.abs().max(1e-300));
    let rule = tanh_sinh_unit(h);
    let np = first.params();
    let nr: usize = rest.iter().map(|a| a.params()).sum();
    let mut f = 0.0;
    let mut grad = vec![0.0; np + nr];
    for panel in cuts.windows(2) {
        let (a, b) = (panel[0], panel[1]);
        for &(x, xm, w) in &rule {
            let u = a + (b - a) * x;
            let um = (1.0 - b) + (b - a) * xm; // 1 − u without cancellation
            let jac = 0.5 * w * (b - a) * u.powf(0.5 * p - 1.0) * um.powf(0.5 * q - 1.0);
            let (f0, g0) = atom_f(first.scaled(u));
            let scaled: Vec<Atom> = rest.iter().map(|a| a.scaled(um)).collect();
            let (fr, gr) = nested(&scaled, h);
            f += jac * f0 * fr;
            for (k, g) in g0.iter().enumerate() {
                grad[k] += jac * u * g * fr;
            }
            for (k, g) in gr.iter().enumerate() {
                grad[np + k] += jac * um * f0 * g;
            }
        }
    }
    (f, grad)
}

/// `(z, log F, ω)` of the nested reference, with its own convergence checked.
fn reference(atoms: &[Atom], h: f64) -> (Vec<f64>, f64, Vec<f64>) {
    let (f, g) = nested(atoms, h);
    let (f2, _) = nested(atoms, h * 1.25);
    assert!(
        rel(f2, f) < 1e-14,
        "reference not converged: {:e}",
        rel(f2, f)
    );
    let mut z = Vec::new();
    let mut omega = Vec::new();
    let mut k = 0;
    for atom in atoms {
        match *atom {
            Atom::Equal(v, p) => {
                for _ in 0..p {
                    z.push(v);
                    omega.push(g[k] / (p as f64 * f));
                }
                k += 1;
            }
            Atom::Pair(a, b) => {
                z.extend([a, b]);
                omega.extend([g[k] / f, g[k + 1] / f]);
                k += 2;
            }
        }
    }
    (z, f.ln(), omega)
}

fn check_against_nested(atoms: &[Atom], h: f64, tol: f64) -> (f64, f64) {
    let (z, lf, om) = reference(atoms, h);
    let e = evaluate(&z, Method::Exact, false).unwrap();
    let ef = (e.log_f - lf).abs();
    let ew = e
        .grad
        .iter()
        .zip(&om)
        .map(|(a, b)| rel(*a, *b))
        .fold(0.0, f64::max);
    println!(
        "d = {} z = {z:?}: |Δ log F| = {ef:.1e}, max rel Δω = {ew:.1e}",
        z.len()
    );
    assert!(ef < tol && ew < tol, "z = {z:?}: {ef:e} {ew:e}");
    (ef, ew)
}

#[test]
fn moderate_generic_z_against_nested_sphere_quadrature() {
    use Atom::{Equal, Pair};
    let cases: Vec<Vec<Atom>> = vec![
        // d = 5
        vec![Pair(-7.5, -1.25), Pair(-3.0, -0.4), Equal(0.0, 1)],
        vec![Pair(-30.0, -12.0), Pair(-25.0, -0.5), Equal(0.0, 1)],
        // d = 6
        vec![Pair(-9.0, -2.0), Pair(-5.5, -4.5), Pair(-1.0, 0.0)],
        vec![Pair(-0.01, -0.003), Pair(-0.02, -0.007), Pair(-0.001, 0.0)],
        // d = 7
        vec![Pair(-20.0, -11.0), Pair(-6.0, -0.3), Equal(0.0, 3)],
    ];
    for atoms in cases {
        check_against_nested(&atoms, 1.0 / 16.0, 1e-13);
    }
}

#[test]
fn d8_three_dimensional_references() {
    use Atom::{Equal, Pair};
    check_against_nested(
        &[
            Pair(-18.0, -3.0),
            Pair(-14.0, -6.0),
            Equal(-1.5, 3),
            Equal(0.0, 1),
        ],
        1.0 / 12.0,
        1e-13,
    );
    check_against_nested(
        &[
            Pair(-6.0, -4.0),
            Pair(-3.5, -2.0),
            Pair(-1.2, -0.9),
            Pair(-0.5, 0.0),
        ],
        1.0 / 8.0,
        1e-13,
    );
}

/// The ladder `z_i = −10(d − 1 − i)`, d = 8 and 5, of `benches/general.rs` (the slowest quadrature
/// convergence among its cases: the image of the saddle between the two smallest `λ` lies 0.26
/// from the real `w` axis).
#[test]
fn benchmark_ladders_against_nested_sphere_quadrature() {
    use Atom::{Equal, Pair};
    let cases: Vec<Vec<Atom>> = vec![
        vec![
            Pair(-70.0, -60.0),
            Pair(-50.0, -40.0),
            Pair(-30.0, -20.0),
            Pair(-10.0, 0.0),
        ],
        vec![Pair(-40.0, -30.0), Pair(-20.0, -10.0), Equal(0.0, 1)],
    ];
    for atoms in cases {
        check_against_nested(&atoms, 1.0 / 12.0, 1e-13);
    }
}

#[test]
fn huge_and_mixed_scales_against_nested_sphere_quadrature() {
    use Atom::{Equal, Pair};
    let cases: Vec<Vec<Atom>> = vec![
        vec![Equal(-1e6, 2), Pair(-3.0, -1e-3), Equal(0.0, 1)],
        vec![Equal(-1e6, 4), Equal(0.0, 1)],
        vec![Equal(-1e6, 3), Equal(0.0, 2)],
        vec![Equal(-2.5e5, 3), Equal(-40.0, 2), Equal(0.0, 1)],
        vec![Equal(-1e6, 5), Equal(-1e3, 2), Equal(0.0, 1)],
        vec![Equal(-3e4, 4), Pair(-12.0, -2.0), Equal(0.0, 2)],
        vec![Equal(-1e6, 7), Equal(0.0, 1)],
    ];
    for atoms in cases {
        check_against_nested(&atoms, 1.0 / 20.0, 1e-13);
    }
}

#[test]
fn omega_sums_to_one_and_invariances() {
    let mut rnd = xorshift_uniform(0x2545_F491_4F6C_DD1D);
    for d in [5, 6, 7, 8, 11, 16, 31, 64] {
        for _ in 0..4 {
            let z: Vec<f64> = (0..d)
                .map(|_| -(10f64).powf(-3.0 + 9.0 * rnd()) + 2.0)
                .collect();
            let e = evaluate(&z, Method::Exact, d <= 16).unwrap();
            let s: f64 = e.grad.iter().sum();
            assert!((s - 1.0).abs() < 1e-14, "d = {d}: Σω − 1 = {:e}", s - 1.0);
            // Reversed order: same value, permuted gradient.
            let zr: Vec<f64> = z.iter().rev().copied().collect();
            let mut gr = vec![0.0; d];
            let lr = log_normalization_into(&zr, Method::Exact, Some(&mut gr), None).unwrap();
            assert!((lr - e.log_f).abs() < 1e-14 * e.log_f.abs().max(1.0));
            for i in 0..d {
                assert!(rel(gr[d - 1 - i], e.grad[i]) < 1e-14);
            }
            if d <= 16 {
                for i in 0..d {
                    let row: f64 = (0..d).map(|k| e.hess[i * d + k]).sum();
                    assert!(row.abs() < 1e-14, "row sum {row:e}");
                    for k in 0..d {
                        assert_eq!(e.hess[i * d + k], e.hess[k * d + i]);
                    }
                }
            }
        }
    }
}

#[test]
fn high_precision_reference_files_d5_to_d8() {
    for d in 5..=8 {
        let rows = read_reference(d);
        let (mut ef, mut ew, mut eh) = (0.0f64, 0.0f64, 0.0f64);
        for r in &rows {
            let e = evaluate(&r.z, Method::Exact, !r.hess.is_empty()).unwrap();
            ef = ef.max((e.log_f - r.log_f).abs());
            for (a, b) in e.grad.iter().zip(&r.omega) {
                ew = ew.max(rel(*a, *b));
            }
            for (k, (got, want)) in e.hess.iter().zip(&r.hess).enumerate() {
                // Relative to the natural scale √(H_ii H_jj) ≥ |H_ij|.
                let (i, j) = (k / d, k % d);
                let scale = (r.hess[i * d + i] * r.hess[j * d + j]).sqrt();
                eh = eh.max((got - want).abs() / scale);
            }
        }
        println!(
            "d = {d}: {} rows, max |Δ log F| = {ef:.1e}, max rel Δω = {ew:.1e}, \
             max |ΔH_ij|/√(H_ii H_jj) = {eh:.1e}",
            rows.len()
        );
        // Acceptance is 1e-10; the method reaches ~1e-14.
        assert!(ef < 1e-12 && ew < 1e-12, "d = {d}: {ef:e} {ew:e}");
        assert!(eh < 1e-12, "d = {d}: Hessian {eh:e}");
    }
}
