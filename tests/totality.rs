//! log F, ∇ log F and the Hessian are finite and valid for every finite z, from the smallest to
//! the largest doubles (issue 13), and accurate where concentrations are huge: the two-Gaussian
//! asymptote for all |z_i| ≥ 1e20, and high-precision references at |z| = 1e10, 1e100, 1e300
//! (`tests/data/normalization_extreme.csv`, written by `scripts/reference_normalization.py
//! --extreme`).

use bingham::error::Error;
use bingham::normalization::{evaluate, Method};
use testkit::{rel, Rng64};

/// A magnitude log-uniform in [1e-300, 1e308].
fn magnitude(rng: &mut Rng64) -> f64 {
    10f64.powf(-300.0 + 608.0 * rng.uniform()).min(f64::MAX)
}

/// Random z of dimension d mixing every hard case: log-uniform magnitudes over the whole
/// range, zeros, ties, one huge entry, all huge, the extreme doubles, positive entries.
fn random_z(rng: &mut Rng64, d: usize) -> Vec<f64> {
    let kind = rng.next_u64() % 8;
    let mut z: Vec<f64> = (0..d).map(|_| -magnitude(rng)).collect();
    match kind {
        // zeros and ties
        0 => {
            for i in 0..d {
                match rng.next_u64() % 3 {
                    0 => z[i] = 0.0,
                    1 => z[i] = z[(rng.next_u64() as usize) % d],
                    _ => {}
                }
            }
        }
        // a single huge entry, the rest moderate
        1 => {
            for v in z.iter_mut() {
                *v = -10f64.powf(-3.0 + 6.0 * rng.uniform());
            }
            z[(rng.next_u64() as usize) % d] = -magnitude(rng).max(1e100);
        }
        // all huge (ties likely)
        2 => {
            let base = 10f64.powf(200.0 + 108.0 * rng.uniform()).min(f64::MAX);
            for v in z.iter_mut() {
                *v = -base
                    * if rng.uniform() < 0.5 {
                        1.0
                    } else {
                        rng.uniform()
                    };
            }
        }
        // the extreme doubles
        3 => {
            for v in z.iter_mut() {
                *v = match rng.next_u64() % 5 {
                    0 => -f64::MAX,
                    1 => -f64::MIN_POSITIVE,
                    2 => -5e-324,
                    3 => 0.0,
                    _ => -magnitude(rng),
                };
            }
        }
        // mixed signs (some spans overflow: refused as documented)
        4 => {
            for v in z.iter_mut() {
                if rng.uniform() < 0.5 {
                    *v = -*v;
                }
            }
        }
        // all nearly equal (near-uniform after the shift)
        5 => {
            let c = -magnitude(rng);
            for v in z.iter_mut() {
                *v = c * (1.0 + 1e-12 * rng.uniform());
            }
        }
        _ => {}
    }
    z
}

/// Every call returns OK with finite outputs and Σω = 1, or — only when max z − min z
/// overflows — the documented InvalidArgument. Returns (calls, refused).
fn check_total(d: usize, n: usize, hessian: bool, seed: u64) -> (usize, usize) {
    let mut rng = Rng64(seed);
    let mut refused = 0;
    for _ in 0..n {
        let z = random_z(&mut rng, d);
        let lo = z.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = z.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let r = evaluate(&z, Method::Exact, hessian);
        if !(hi - lo).is_finite() {
            assert!(
                matches!(r, Err(Error::InvalidArgument(_))),
                "d={d} z={z:?}: span overflows, expected InvalidArgument, got {r:?}"
            );
            refused += 1;
            continue;
        }
        let e = r.unwrap_or_else(|err| panic!("d={d} z={z:?}: {err}"));
        assert!(e.log_f.is_finite(), "d={d} z={z:?}");
        assert!(
            e.grad.iter().all(|w| w.is_finite() && *w >= 0.0),
            "d={d} z={z:?}: {:?}",
            e.grad
        );
        assert!(e.hess.iter().all(|h| h.is_finite()), "d={d} z={z:?}");
        let s: f64 = e.grad.iter().sum();
        assert!(
            (s - 1.0).abs() <= 1e-12,
            "d={d} z={z:?}: Σω − 1 = {:e}",
            s - 1.0
        );
    }
    (n, refused)
}

#[test]
fn every_finite_z_gives_a_finite_answer_d2_to_4() {
    for d in 2..=4 {
        let (n, refused) = check_total(d, 20_000, true, 1300 + d as u64);
        println!("d = {d}: {n} calls ({refused} refused: span overflow), all others OK");
    }
}

#[test]
fn every_finite_z_gives_a_finite_answer_d5_to_64() {
    for (d, n) in [
        (5, 2000),
        (6, 1500),
        (7, 1000),
        (8, 1000),
        (16, 300),
        (64, 60),
    ] {
        let (_, refused) = check_total(d, n, d <= 8, 1400 + d as u64);
        println!("d = {d}: {n} calls ({refused} refused: span overflow), all others OK");
    }
}

/// The failing and wrong points, the extreme doubles, and the documented refusal.
#[test]
fn corner_cases() {
    let max = f64::MAX;
    for z in [
        vec![-1e300, -1e299, -1e298, 0.0],
        vec![-7.14e217, -8.88e214, -1.27e214, 0.0],
        vec![-1.26e198, -1.49e304, -2.36e141, 0.0],
        vec![-max, -max, -max, 0.0],
        vec![-max, -max, 0.0],
        vec![-max, 0.0],
        vec![-max, -5e-324, 0.0, -max],
        vec![-max, -1.0, -1e-300, 0.0],
        vec![max, max, 0.0, max],
        vec![-5e-324, 0.0, -5e-324],
    ] {
        let e = evaluate(&z, Method::Exact, true).unwrap_or_else(|err| panic!("{z:?}: {err}"));
        let s: f64 = e.grad.iter().sum();
        assert!(e.log_f.is_finite() && (s - 1.0).abs() <= 1e-12, "{z:?}");
        assert!(e.grad.iter().chain(&e.hess).all(|v| v.is_finite()), "{z:?}");
    }
    // (−1.26e198, −1.49e304, −2.36e141, 0): the 0.64-off point, log F = −738.6168…
    let e = evaluate(
        &[-1.26e198, -1.49e304, -2.36e141, 0.0],
        Method::Exact,
        false,
    )
    .unwrap();
    let want = 2f64.ln()
        + [1.26e198f64, 1.49e304, 2.36e141]
            .iter()
            .map(|v| 0.5 * (std::f64::consts::PI / v).ln())
            .sum::<f64>();
    assert!(
        (e.log_f - want).abs() <= 1e-14 * want.abs(),
        "{} vs {want}",
        e.log_f
    );
    for (i, v) in [1.26e198f64, 1.49e304, 2.36e141].iter().enumerate() {
        assert!(rel(e.grad[i], 0.5 / v, 0.0) <= 1e-13);
    }
    // spans beyond the largest double: the documented refusal
    for z in [vec![max, -max], vec![1e308, 0.0, -1e308, -1.0]] {
        assert!(
            matches!(
                evaluate(&z, Method::Exact, false),
                Err(Error::InvalidArgument(_))
            ),
            "{z:?}"
        );
    }
}

/// The two-Gaussian asymptote: with z_d = 0 and every other |z_i| ≥ 1e20,
/// `log F = log 2 + Σ_{i<d} ½ log(π/|z_i|)` and `ω_i = 1/(2|z_i|)`, both with a relative
/// correction O(1/min|z_i|) ≤ 1e-20.
#[test]
fn huge_concentrations_follow_the_two_gaussian_asymptote() {
    let mut rng = Rng64(2013);
    let (mut elf, mut ew, mut eh) = (0.0f64, 0.0f64, 0.0f64);
    for d in 2..=8 {
        for _ in 0..4000 / d {
            let mut z: Vec<f64> = (0..d - 1)
                .map(|_| -(10f64.powf(20.0 + 288.4 * rng.uniform()).min(f64::MAX)))
                .collect();
            // ties
            if rng.uniform() < 0.2 && d > 2 {
                z[1] = z[0];
            }
            z.push(0.0);
            let e = evaluate(&z, Method::Exact, true).unwrap();
            let want: f64 = 2f64.ln()
                + z[..d - 1]
                    .iter()
                    .map(|v| 0.5 * (std::f64::consts::PI / -v).ln())
                    .sum::<f64>();
            let errf = (e.log_f - want).abs() / want.abs().max(1.0);
            assert!(
                errf <= 1e-14,
                "d={d} z={z:?}: log F {} vs {want} ({errf:e})",
                e.log_f
            );
            elf = elf.max(errf);
            for i in 0..d - 1 {
                let w = 0.5 / -z[i];
                let err = rel(e.grad[i], w, 0.0);
                assert!(
                    err <= 1e-13,
                    "d={d} z={z:?}: ω{i} {} vs {w} ({err:e})",
                    e.grad[i]
                );
                ew = ew.max(err);
                // Var(x_i²) = 2ω_i² for a Gaussian coordinate (while it is a normal double)
                let h = e.hess[i * d + i];
                if w > 1e-150 {
                    let err = rel(h, 2.0 * w * w, 0.0);
                    assert!(
                        err <= 1e-9,
                        "d={d} z={z:?}: H{i}{i} {h:e} vs {:e}",
                        2.0 * w * w
                    );
                    eh = eh.max(err);
                }
            }
        }
    }
    println!("asymptote: max rel Δ log F {elf:e}, max rel Δω {ew:e}, max rel ΔH_ii {eh:e}");
}

/// `tests/data/normalization_extreme.csv`: rows `d, z1..zd, logF, omega1..omegad` at
/// |z| = 1e10, 1e100, 1e300 (65 digits; see `tests/data/README.md`).
#[test]
fn extreme_concentrations_match_high_precision_references() {
    let path = format!(
        "{}/tests/data/normalization_extreme.csv",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut worst = [(0.0f64, 0.0f64); 3]; // per magnitude class: (|Δ log F| rel, rel Δω)
    let mut rows = 0;
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
    {
        let v: Vec<f64> = line.split(',').map(|s| s.trim().parse().unwrap()).collect();
        let d = v[0] as usize;
        let z = &v[1..=d];
        let log_f = v[d + 1];
        let omega = &v[d + 2..2 * d + 2];
        let e = evaluate(z, Method::Exact, true).unwrap();
        let zmax = z.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let class = if zmax < 1e50 {
            0
        } else if zmax < 1e200 {
            1
        } else {
            2
        };
        // |Δ log F| is the relative error of F; log F itself is O(|log |z||), so allow its
        // rounding (1e-15 relative)
        let errf = (e.log_f - log_f).abs();
        assert!(
            errf <= 2e-14 * log_f.abs().max(1.0),
            "z={z:?}: log F {} vs {log_f} ({errf:e})",
            e.log_f
        );
        worst[class].0 = worst[class].0.max(errf / log_f.abs().max(1.0));
        for (i, (&got, &want)) in e.grad.iter().zip(omega).enumerate() {
            let err = rel(got, want, 0.0);
            assert!(err <= 1e-13, "z={z:?}: ω{i} {got} vs {want} ({err:e})");
            worst[class].1 = worst[class].1.max(err);
        }
        assert!(e.hess.iter().all(|h| h.is_finite()));
        rows += 1;
    }
    assert!(rows >= 30, "{rows} rows");
    for (c, name) in ["1e10", "1e100", "1e300"].iter().enumerate() {
        println!(
            "|z| ~ {name}: max rel Δ log F {:e}, max rel Δω {:e}",
            worst[c].0, worst[c].1
        );
    }
}

/// The filter's update with measurement noises out to 1e300 succeeds wherever the exact
/// Bayes product (`Bingham::multiply`) is representable, and agrees with it; the
/// log-likelihood is then finite too.
#[test]
fn updates_with_noises_out_to_1e300_succeed() {
    use bingham::filter::BinghamFilter;
    use bingham::quaternion::left_matrix;
    use bingham::Bingham;
    use nalgebra::{DMatrix, DVector};

    fn row_major(m: &DMatrix<f64>) -> Vec<f64> {
        let d = m.nrows();
        (0..d * d).map(|k| m[(k / d, k % d)]).collect()
    }
    fn likelihood(d: usize, zhat: &[f64], mv: &DMatrix<f64>, zv: &[f64]) -> Bingham {
        let mut dm = mv.clone();
        for i in 1..d {
            dm.row_mut(i).neg_mut();
        }
        Bingham::new(left_matrix(zhat) * dm, DVector::from_column_slice(zv)).unwrap()
    }

    let mut rng = Rng64(1300);
    let (mut updates, mut refused) = (0, 0);
    for d in [2usize, 4] {
        for trial in 0..200 {
            let m0 = rng.orthogonal(d);
            let mut z0: Vec<f64> = (0..d)
                .map(|_| -(10f64.powf(-2.0 + 8.0 * rng.uniform())))
                .collect();
            z0.sort_by(f64::total_cmp);
            z0[d - 1] = 0.0;
            let mut f = BinghamFilter::new(d, &row_major(&m0), &z0).unwrap();
            let mut state = Bingham::new(m0, DVector::from_column_slice(&z0)).unwrap();
            for step in 0..6 {
                let mv = rng.orthogonal(d);
                let mut zv: Vec<f64> = if trial == 0 && step == 0 && d == 4 {
                    // the example
                    vec![-1e300, -1e299, -1e298, 0.0]
                } else {
                    (0..d)
                        .map(|_| -(10f64.powf(-3.0 + 303.0 * rng.uniform())))
                        .collect()
                };
                zv.sort_by(f64::total_cmp);
                zv[d - 1] = 0.0;
                let zhat: Vec<f64> = {
                    let x: Vec<f64> = (0..d).map(|_| rng.normal()).collect();
                    let n = x.iter().map(|v| v * v).sum::<f64>().sqrt();
                    x.iter().map(|v| v / n).collect()
                };
                let expect = state.multiply(&likelihood(d, &zhat, &mv, &zv));
                let got = f.update(&zhat, &row_major(&mv), &zv);
                match expect {
                    Ok(b) => {
                        got.unwrap_or_else(|e| {
                            panic!("d={d} z_v={zv:?}: update failed ({e}) where multiply succeeds")
                        });
                        let zf = f.state().z().clone();
                        let scale = b.z().amax().max(1.0);
                        for i in 0..d {
                            assert!(
                                (zf[i] - b.z()[i]).abs() <= 1e-9 * scale,
                                "d={d} z_v={zv:?}: {zf:?} vs {:?}",
                                b.z()
                            );
                        }
                        let ll = f.log_likelihood(&zhat, &row_major(&mv), &zv);
                        assert!(
                            ll.as_ref().is_ok_and(|v| v.is_finite()),
                            "d={d} z_v={zv:?}: log-likelihood {ll:?}"
                        );
                        state = b;
                        updates += 1;
                    }
                    Err(_) => {
                        assert!(got.is_err(), "d={d} z_v={zv:?}");
                        refused += 1;
                    }
                }
            }
        }
    }
    println!(
        "{updates} updates with noises out to 1e300 ({refused} unrepresentable products refused)"
    );
    assert!(updates >= 2000);
}
