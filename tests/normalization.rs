//! The normalization constant against independent references: 65-digit values computed
//! offline (`scripts/reference_normalization.py`), brute-force sphere quadrature, and identities.

use bingham::normalization::{evaluate, log_normalization_into, Method};
use bingham::Bingham;
use testkit::{gauss_legendre, read_reference, rel, Rng64};

/// Checks every reference row of dimension d; returns (max rel err of F, max rel err of ω).
fn check_reference(d: usize) -> (f64, f64) {
    let rows = read_reference(d);
    let (mut ef, mut ew, mut eh) = (0.0f64, 0.0f64, 0.0f64);
    for r in &rows {
        let zmax = r.z.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        // acceptance: ≤ 1e-12 (F) and ≤ 1e-11 (ω) for |z| ≤ 1e5, ≤ 1e-10 for both beyond
        let (tf, tw) = if zmax <= 1e5 {
            (1e-12, 1e-11)
        } else {
            (1e-10, 1e-10)
        };
        let e = evaluate(&r.z, Method::Exact, !r.hess.is_empty()).unwrap();
        // relative error of F = |exp(Δ log F) − 1| ≈ |Δ log F|
        let errf = (e.log_f - r.log_f).abs();
        assert!(
            errf <= tf,
            "d={d} z={:?}: log F {} vs {} (err {errf:e})",
            r.z,
            e.log_f,
            r.log_f
        );
        ef = ef.max(errf);
        for i in 0..d {
            let errw = rel(e.grad[i], r.omega[i], 1e-300);
            assert!(
                errw <= tw,
                "d={d} z={:?}: omega[{i}] {} vs {} (rel err {errw:e})",
                r.z,
                e.grad[i],
                r.omega[i]
            );
            ew = ew.max(errw);
        }
        if !r.hess.is_empty() {
            // Hessian: relative to the scale of its row (diagonal entries are variances)
            for i in 0..d {
                let scale = (0..d).map(|j| r.hess[i * d + j].abs()).fold(0.0, f64::max);
                for j in 0..d {
                    let err = (e.hess[i * d + j] - r.hess[i * d + j]).abs() / scale.max(1e-300);
                    assert!(
                        err <= 1e-9,
                        "d={d} z={:?}: H[{i}][{j}] {} vs {} ({err:e})",
                        r.z,
                        e.hess[i * d + j],
                        r.hess[i * d + j]
                    );
                    eh = eh.max(err);
                }
            }
        }
    }
    println!(
        "d = {d}: {} rows, max |Δ log F| = {ef:e}, max rel Δω = {ew:e}, max rel ΔH = {eh:e}",
        rows.len()
    );
    (ef, ew)
}

#[test]
fn d2_matches_reference() {
    check_reference(2);
}

#[test]
fn d3_matches_reference() {
    check_reference(3);
}

#[test]
fn d4_matches_reference() {
    check_reference(4);
}

#[test]
fn uniform_sphere_values() {
    let pi = std::f64::consts::PI;
    for (d, area) in [(2usize, 2.0 * pi), (3, 4.0 * pi), (4, 2.0 * pi * pi)] {
        let e = evaluate(&vec![0.0; d], Method::Exact, true).unwrap();
        assert!((e.log_f - area.ln()).abs() < 1e-15, "d={d}");
        for i in 0..d {
            assert!((e.grad[i] - 1.0 / d as f64).abs() < 1e-15);
            for j in 0..d {
                let dd = d as f64;
                let want = if i == j {
                    3.0 / (dd * (dd + 2.0))
                } else {
                    1.0 / (dd * (dd + 2.0))
                } - 1.0 / (dd * dd);
                assert!(
                    (e.hess[i * d + j] - want).abs() < 1e-14,
                    "d={d} H[{i}][{j}] = {} want {want}",
                    e.hess[i * d + j]
                );
            }
        }
    }
}

fn random_z(rng: &mut Rng64, d: usize) -> Vec<f64> {
    (0..d)
        .map(|_| {
            // log-uniform magnitudes in [1e-3, 1e6], some exact zeros and ties
            let u = rng.uniform();
            if u < 0.1 {
                0.0
            } else {
                -(10f64).powf(-3.0 + 9.0 * rng.uniform())
            }
        })
        .collect()
}

#[test]
fn omega_sums_to_one_and_identities_hold() {
    let mut rng = Rng64(7);
    let mut worst = 0.0f64;
    for d in 2..=4 {
        for _ in 0..400 {
            let z = random_z(&mut rng, d);
            let e = evaluate(&z, Method::Exact, false).unwrap();
            let s: f64 = e.grad.iter().sum();
            worst = worst.max((s - 1.0).abs());
            assert!((s - 1.0).abs() <= 1e-14, "z={z:?}: Σω − 1 = {:e}", s - 1.0);
            assert!(e.grad.iter().all(|w| *w > 0.0 && w.is_finite()));
            // shift: F(Z + cI) = e^c F(Z)
            let c = 1000.0 * (rng.uniform() - 0.5);
            let zs: Vec<f64> = z.iter().map(|v| v + c).collect();
            let es = evaluate(&zs, Method::Exact, false).unwrap();
            assert!(
                (es.log_f - e.log_f - c).abs() <= 1e-12 * (1.0 + c.abs()),
                "shift"
            );
            for i in 0..d {
                assert!(rel(es.grad[i], e.grad[i], 1e-300) <= 1e-9);
            }
            // permutation: reversed order gives reversed gradient
            let zr: Vec<f64> = z.iter().rev().cloned().collect();
            let er = evaluate(&zr, Method::Exact, false).unwrap();
            // (ties may be visited in another order: equal up to rounding)
            assert!((er.log_f - e.log_f).abs() <= 1e-15 * e.log_f.abs().max(1.0));
            for i in 0..d {
                assert!(rel(er.grad[d - 1 - i], e.grad[i], 1e-300) <= 1e-14);
            }
        }
    }
    println!("max |Σω − 1| = {worst:e}");
}

#[test]
fn hessian_matches_finite_differences_of_gradient() {
    let mut rng = Rng64(11);
    for d in 2..=4 {
        for _ in 0..40 {
            let z: Vec<f64> = (0..d)
                .map(|_| -(10f64).powf(-1.0 + 4.0 * rng.uniform()))
                .collect();
            let e = evaluate(&z, Method::Exact, true).unwrap();
            for j in 0..d {
                let h = 1e-5 * z[j].abs().max(1.0);
                let mut zp = z.clone();
                zp[j] += h;
                let mut zm = z.clone();
                zm[j] -= h;
                let gp = evaluate(&zp, Method::Exact, false).unwrap().grad;
                let gm = evaluate(&zm, Method::Exact, false).unwrap().grad;
                for i in 0..d {
                    let fd = (gp[i] - gm[i]) / (2.0 * h);
                    let scale = e.hess[i * d + i].abs().max(e.hess[j * d + j].abs()).sqrt()
                        * e.hess[i * d + i].abs().max(e.hess[j * d + j].abs()).sqrt();
                    // truncation O(h²) plus rounding of the differenced gradients (~eps·|ω|/h)
                    let rounding = 8.0 * f64::EPSILON * gp[i].abs().max(gm[i].abs()) / h;
                    assert!(
                        (fd - e.hess[i * d + j]).abs() <= 1e-6 * scale + rounding,
                        "d={d} z={z:?} H[{i}][{j}] = {} fd {fd}",
                        e.hess[i * d + j]
                    );
                }
            }
        }
    }
}

/// Brute force for d = 3: tensor Gauss–Legendre in (cos θ, φ) over the sphere, independent of
/// every 1-D formula. Returns (F, E[x_i²]).
#[allow(clippy::needless_range_loop)]
fn brute_force_d3(z: &[f64]) -> (f64, [f64; 3]) {
    let n = 400;
    let (xs, ws) = gauss_legendre(n);
    let mut f = 0.0;
    let mut m = [0.0; 3];
    for a in 0..n {
        let t = xs[a]; // cos θ in [-1, 1]
        let st = (1.0 - t * t).sqrt();
        for b in 0..n {
            let phi = std::f64::consts::PI * (xs[b] + 1.0);
            let x = [st * phi.cos(), st * phi.sin(), t];
            let e = (z[0] * x[0] * x[0] + z[1] * x[1] * x[1] + z[2] * x[2] * x[2]).exp();
            let w = ws[a] * ws[b] * std::f64::consts::PI * e;
            f += w;
            for i in 0..3 {
                m[i] += w * x[i] * x[i];
            }
        }
    }
    (f, [m[0] / f, m[1] / f, m[2] / f])
}

#[test]
#[allow(clippy::needless_range_loop)]
fn d3_matches_brute_force_sphere_quadrature() {
    for z in [
        [-1.0, -0.5, 0.0],
        [-10.0, -3.0, 0.0],
        [-30.0, -30.0, 0.0],
        [-20.0, -1.0, 0.0],
        [-5.0, 0.0, 0.0],
        [-0.0, 0.0, 0.0],
    ] {
        let (f, m) = brute_force_d3(&z);
        let e = evaluate(&z, Method::Exact, false).unwrap();
        assert!(
            rel(e.log_f.exp(), f, 0.0) < 1e-12,
            "z={z:?}: {} vs {f}",
            e.log_f.exp()
        );
        for i in 0..3 {
            assert!(
                rel(e.grad[i], m[i], 0.0) < 1e-11,
                "z={z:?} ω{i}: {} vs {}",
                e.grad[i],
                m[i]
            );
        }
    }
}

#[test]
fn extreme_inputs_are_finite() {
    for z in [
        vec![-1e6, -10.0, -1.0, 0.0],
        vec![-5e4, -5e4, 0.0, 0.0],
        vec![-1e6, -1e6, -1e6, 0.0],
        vec![-1e9, -1e8, -1e7, 0.0],
        vec![1e6, 0.0, -1e6, 5.0],
        vec![-1e-300, 0.0, -5e-324, 0.0],
        vec![-1e6, -1e6, 0.0],
        vec![-1e12, 0.0],
        vec![1e300, -1e300],
    ] {
        let e = evaluate(&z, Method::Exact, true).unwrap();
        assert!(e.log_f.is_finite(), "{z:?}");
        assert!(
            e.grad.iter().chain(e.hess.iter()).all(|v| v.is_finite()),
            "{z:?}"
        );
        let s: f64 = e.grad.iter().sum();
        assert!((s - 1.0).abs() < 1e-14, "{z:?}: {s}");
    }
}

#[test]
fn bad_input_is_an_error() {
    assert!(evaluate(&[0.0], Method::Exact, false).is_err());
    assert!(evaluate(&vec![0.0; 65], Method::Exact, false).is_err());
    assert!(evaluate(&[f64::NAN, 0.0], Method::Exact, false).is_err());
    assert!(evaluate(&[f64::INFINITY, 0.0, 1.0], Method::Exact, false).is_err());
    let mut g = [0.0; 2];
    assert!(log_normalization_into(&[0.0, 0.0, 0.0], Method::Exact, Some(&mut g), None).is_err());
}

/// `log F` (of `z`, unshifted) and `ω` (in the order of `z` sorted ascending) through the
/// distribution, i.e. the crate's own callers (`log_f_canonical`).
fn through_bingham(z: &[f64]) -> (f64, Vec<f64>) {
    let d = z.len();
    let mut m = vec![0.0; d * d];
    for i in 0..d {
        m[i * d + i] = 1.0;
    }
    let b = Bingham::from_row_major(d, &m, z).unwrap();
    let (lf, w) = b.log_normalization_and_omega().unwrap();
    let zmax = z.iter().fold(f64::NEG_INFINITY, |a, &v| a.max(v));
    (lf + zmax, w.as_slice().to_vec())
}

/// The crate's own callers take `log F` and `ω` of a concentrated d = 3, 4 Bingham from the
/// series of `normalization::concentrated` where its error bound is below 1e-16 (every
/// concentration below the mode from about 100): against the 65-digit references (the rows of
/// `normalization_d{3,4}.csv` and `normalization_extreme.csv` with every concentration below the
/// mode at least 100) and against the public path (always the quadrature) over random
/// concentrated z, 100 to 1e12, with ties.
#[test]
fn concentrated_binghams_match_references_and_the_quadrature() {
    // (z, log F, ω) of every reference row of d = 3, 4
    let mut refs: Vec<(Vec<f64>, f64, Vec<f64>)> = Vec::new();
    for d in [3, 4] {
        for r in read_reference(d) {
            refs.push((r.z, r.log_f, r.omega));
        }
    }
    let path = format!(
        "{}/tests/data/normalization_extreme.csv",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
    {
        let v: Vec<f64> = line.split(',').map(|s| s.trim().parse().unwrap()).collect();
        let d = v[0] as usize;
        if d == 3 || d == 4 {
            refs.push((v[1..=d].to_vec(), v[d + 1], v[d + 2..2 * d + 2].to_vec()));
        }
    }
    let (mut rows, mut ew, mut ef) = (0, 0.0f64, 0.0f64);
    for (z, log_f, omega) in &refs {
        let d = z.len();
        let mut idx: Vec<usize> = (0..d).collect();
        idx.sort_by(|&a, &b| z[a].total_cmp(&z[b]));
        let a_min = z[idx[d - 1]] - z[idx[d - 2]];
        let a_max = z[idx[d - 1]] - z[idx[0]];
        if !(a_min >= 100.0 && a_max <= 1e300) {
            continue;
        }
        rows += 1;
        let (lf, w) = through_bingham(z);
        let errf = (lf - log_f).abs() / log_f.abs().max(1.0);
        assert!(errf <= 2e-15, "z={z:?}: log F {lf} vs {log_f} ({errf:e})");
        ef = ef.max(errf);
        for (k, &i) in idx.iter().enumerate() {
            let err = rel(w[k], omega[i], 0.0);
            assert!(
                err <= 2e-15,
                "z={z:?}: ω{i} {} vs {} ({err:e})",
                w[k],
                omega[i]
            );
            ew = ew.max(err);
        }
    }
    println!("{rows} reference rows: max rel Δ log F {ef:e}, max rel Δω {ew:e}");
    assert!(rows >= 15, "{rows} rows");
    let mut rng = Rng64(35);
    let (mut ew, mut ef, mut es) = (0.0f64, 0.0f64, 0.0f64);
    for trial in 0..2000 {
        let d = 3 + trial % 2;
        let mut z: Vec<f64> = (0..d - 1)
            .map(|_| -(10f64).powf(2.0 + 10.0 * rng.uniform()))
            .collect();
        if trial % 5 == 0 {
            z[1] = z[0]; // a tie
        }
        z.push(0.0);
        let (lf, w) = through_bingham(&z);
        let e = evaluate(&z, Method::Exact, false).unwrap();
        let mut sorted: Vec<(f64, f64)> = z.iter().copied().zip(e.grad.iter().copied()).collect();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        let errf = (lf - e.log_f).abs() / e.log_f.abs().max(1.0);
        assert!(
            errf <= 3e-15,
            "z={z:?}: log F {lf} vs {} ({errf:e})",
            e.log_f
        );
        ef = ef.max(errf);
        for (k, (_, want)) in sorted.iter().enumerate() {
            let err = rel(w[k], *want, 0.0);
            assert!(err <= 3e-15, "z={z:?}: ω{k} {} vs {want} ({err:e})", w[k]);
            ew = ew.max(err);
        }
        let sum: f64 = w.iter().sum();
        es = es.max((sum - 1.0).abs());
        assert!((sum - 1.0).abs() <= 2.0 * f64::EPSILON, "Σω = {sum}");
    }
    println!("random: max rel Δ log F {ef:e}, max rel Δω {ew:e}, max |Σω − 1| {es:e}");
}
