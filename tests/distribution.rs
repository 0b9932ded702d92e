//! Density, moments, entropy, KL, multiply, compose, rotate and the sampler, checked against
//! Monte Carlo (with tolerances derived from n), pointwise density identities and invariants.

use bingham::quaternion::compose as qmul;
use bingham::Bingham;
use nalgebra::{DMatrix, DVector};
use rand::rngs::StdRng;
use rand::SeedableRng;
use testkit::{rel, Rng64};

fn bingham(rng: &mut Rng64, z: &[f64]) -> Bingham {
    Bingham::new(rng.orthogonal(z.len()), DVector::from_column_slice(z)).unwrap()
}

/// Asserts that the empirical second moment of `xs` matches `s` within 5 standard errors
/// (estimated per entry from the samples). Returns the largest |error|/σ.
fn assert_moment_matches(xs: &[DVector<f64>], s: &DMatrix<f64>, what: &str) -> f64 {
    let d = s.nrows();
    let n = xs.len() as f64;
    let mut worst = 0.0f64;
    for i in 0..d {
        for j in i..d {
            let mut m1 = 0.0;
            let mut m2 = 0.0;
            for x in xs {
                let p = x[i] * x[j];
                m1 += p;
                m2 += p * p;
            }
            m1 /= n;
            m2 /= n;
            let sigma = ((m2 - m1 * m1).max(0.0) / n).sqrt();
            let err = (m1 - s[(i, j)]).abs();
            assert!(
                err <= 5.0 * sigma + 1e-12,
                "{what}: S[{i}][{j}] empirical {m1} vs {} (err {err:e}, σ {sigma:e})",
                s[(i, j)]
            );
            worst = worst.max(err / sigma.max(1e-300));
        }
    }
    worst
}

#[test]
fn sampler_matches_second_moment() {
    let mut rng = Rng64(1);
    let mut srng = StdRng::seed_from_u64(42);
    for d in [2usize, 3, 4] {
        for c in [0.0, -1.0, -10.0, -100.0, -1e3, -1e4] {
            let mut z = vec![c; d];
            z[d - 1] = 0.0;
            if d > 2 {
                z[0] = 2.0 * c; // anisotropic
            }
            let b = bingham(&mut rng, &z);
            let xs = b.sample(&mut srng, 1_000_000);
            assert!(xs.iter().all(|x| (x.norm() - 1.0).abs() < 1e-12));
            let w =
                assert_moment_matches(&xs, &b.second_moment().unwrap(), &format!("d={d} z={z:?}"));
            println!("d={d} z={z:?}: max |error|/σ = {w:.2}");
        }
    }
}

#[test]
fn sampler_is_deterministic_for_a_seed() {
    let mut rng = Rng64(3);
    let b = bingham(&mut rng, &[-5.0, -1.0, 0.0, 0.0]);
    let a = b.sample(&mut StdRng::seed_from_u64(7), 100);
    let c = b.sample(&mut StdRng::seed_from_u64(7), 100);
    assert_eq!(a, c);
}

#[test]
fn pdf_integrates_to_one_d2_and_log_pdf_is_consistent() {
    let mut rng = Rng64(4);
    for z in [[-0.0, 0.0], [-3.0, 0.0], [-400.0, 0.0]] {
        let b = bingham(&mut rng, &z);
        // trapezoid on the circle is spectrally accurate for periodic integrands
        let n = 20000;
        let mut s = 0.0;
        for k in 0..n {
            let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            s += b.pdf(&[t.cos(), t.sin()]).unwrap();
        }
        s *= 2.0 * std::f64::consts::PI / n as f64;
        assert!((s - 1.0).abs() < 1e-12, "z={z:?}: ∫pdf = {s}");
    }
    let b = bingham(&mut rng, &[-2.0, -1.0, 0.0]);
    assert!(b.pdf(&[1.0, 0.0]).is_err());
    assert!(b.pdf(&[2.0, 0.0, 0.0]).is_err());
    assert!(b.pdf(&[f64::NAN, 0.0, 1.0]).is_err());
}

#[test]
fn multiply_is_the_pointwise_product() {
    let mut rng = Rng64(5);
    for d in [2usize, 3, 4, 6] {
        let mut z1: Vec<f64> = (0..d).map(|_| -50.0 * rng.uniform()).collect();
        let mut z2: Vec<f64> = (0..d).map(|_| -1e4 * rng.uniform()).collect();
        z1[0] = 0.0;
        z2[1] = 0.0;
        let a = bingham(&mut rng, &z1);
        let b = bingham(&mut rng, &z2);
        let p = a.multiply(&b).unwrap();
        // the exponent of the product equals the sum of exponents up to a constant
        let x0 = DVector::from_fn(d, |_, _| rng.normal()).normalize();
        let base = expo(&a, &x0) + expo(&b, &x0) - expo(&p, &x0);
        for _ in 0..20 {
            let x = DVector::from_fn(d, |_, _| rng.normal()).normalize();
            let c = expo(&a, &x) + expo(&b, &x) - expo(&p, &x);
            assert!((c - base).abs() < 1e-9 * 1e4, "d={d}: {c} vs {base}");
        }
        assert!(p.z()[d - 1] == 0.0 && p.z().iter().zip(p.z().iter().skip(1)).all(|(a, b)| a <= b));
    }
}

fn expo(b: &Bingham, x: &DVector<f64>) -> f64 {
    let c = b.m().tr_mul(x);
    c.iter().zip(b.z().iter()).map(|(c, z)| z * c * c).sum()
}

#[test]
fn multiply_aligned_adds_concentrations_and_keeps_mode() {
    let mut rng = Rng64(6);
    let m = rng.orthogonal(4);
    let a = Bingham::new(m.clone(), DVector::from_vec(vec![-3.0, -2.0, -1.0, 0.0])).unwrap();
    let b = Bingham::new(m.clone(), DVector::from_vec(vec![-30.0, -20.0, -10.0, 0.0])).unwrap();
    let p = a.multiply(&b).unwrap();
    for (i, want) in [-33.0, -22.0, -11.0, 0.0].iter().enumerate() {
        assert!((p.z()[i] - want).abs() < 1e-12, "{:?}", p.z());
    }
    let mode_err = 1.0 - p.mode().dot(&a.mode()).abs();
    assert!(mode_err < 1e-14);
}

#[test]
fn compose_matches_sampled_composition() {
    let mut rng = Rng64(8);
    let mut srng = StdRng::seed_from_u64(8);
    for (za, zb) in [
        (vec![-5.0, 0.0], vec![-50.0, 0.0]),
        (vec![-1.0, 0.0], vec![-200.0, 0.0]),
        (
            vec![-10.0, -5.0, -1.0, 0.0],
            vec![-200.0, -200.0, -2.0, 0.0],
        ),
        (
            vec![-100.0, -100.0, -100.0, 0.0],
            vec![-500.0, -50.0, -5.0, 0.0],
        ),
    ] {
        let a = bingham(&mut rng, &za);
        let b = bingham(&mut rng, &zb);
        let c = a.compose(&b).unwrap();
        let n = 400_000;
        let xa = a.sample(&mut srng, n);
        let xb = b.sample(&mut srng, n);
        let xs: Vec<DVector<f64>> = xa
            .iter()
            .zip(xb.iter())
            .map(|(x, y)| DVector::from_vec(qmul(x.as_slice(), y.as_slice()).unwrap()))
            .collect();
        assert_moment_matches(
            &xs,
            &c.second_moment().unwrap(),
            &format!("compose {za:?} ⊕ {zb:?}"),
        );
    }
    let a = bingham(&mut rng, &[-1.0, 0.0, 0.0]);
    assert!(a.compose(&a).is_err(), "d = 3 has no composition");
}

#[test]
fn compose_with_identity_mode_noise_keeps_m_and_lowers_concentration() {
    let mut rng = Rng64(9);
    let a = bingham(&mut rng, &[-100.0, -50.0, -20.0, 0.0]);
    // noise with mode at the identity quaternion (1,0,0,0): last column e1
    let mut mn = DMatrix::zeros(4, 4);
    mn[(1, 0)] = 1.0;
    mn[(2, 1)] = 1.0;
    mn[(3, 2)] = 1.0;
    mn[(0, 3)] = 1.0;
    let w = Bingham::new(mn, DVector::from_vec(vec![-300.0, -300.0, -300.0, 0.0])).unwrap();
    let c = a.compose(&w).unwrap();
    for i in 0..3 {
        assert!(
            c.z()[i] > a.z()[i],
            "concentration must drop: {:?} vs {:?}",
            c.z(),
            a.z()
        );
    }
    assert!(1.0 - c.mode().dot(&a.mode()).abs() < 1e-12);
}

#[test]
fn rotation_moves_the_density() {
    let mut rng = Rng64(10);
    for d in [2usize, 4] {
        let mut z: Vec<f64> = (0..d).map(|_| -20.0 * rng.uniform()).collect();
        z[d - 1] = 0.0;
        let b = bingham(&mut rng, &z);
        let u = DVector::from_fn(d, |_, _| rng.normal()).normalize();
        let l = b.rotate_left(u.as_slice()).unwrap();
        let r = b.rotate_right(u.as_slice()).unwrap();
        for _ in 0..10 {
            let x = DVector::from_fn(d, |_, _| rng.normal()).normalize();
            let ux = qmul(u.as_slice(), x.as_slice()).unwrap();
            let xu = qmul(x.as_slice(), u.as_slice()).unwrap();
            let p = b.log_pdf(x.as_slice()).unwrap();
            assert!((l.log_pdf(&ux).unwrap() - p).abs() < 1e-12);
            assert!((r.log_pdf(&xu).unwrap() - p).abs() < 1e-12);
        }
        assert!(b.rotate_left(&vec![2.0; d]).is_err());
    }
}

#[test]
fn entropy_and_kl_match_monte_carlo() {
    let mut rng = Rng64(12);
    let mut srng = StdRng::seed_from_u64(12);
    for (za, zb) in [
        (vec![-3.0, -1.0, 0.0], vec![-10.0, -0.5, 0.0]),
        (vec![-30.0, -20.0, -1.0, 0.0], vec![-5.0, -5.0, -5.0, 0.0]),
    ] {
        let a = bingham(&mut rng, &za);
        let b = bingham(&mut rng, &zb);
        let n = 200_000;
        let xs = a.sample(&mut srng, n);
        let (mut h1, mut h2, mut k1, mut k2) = (0.0, 0.0, 0.0, 0.0);
        for x in &xs {
            let la = a.log_pdf(x.as_slice()).unwrap();
            let lb = b.log_pdf(x.as_slice()).unwrap();
            h1 += -la;
            h2 += la * la;
            k1 += la - lb;
            k2 += (la - lb) * (la - lb);
        }
        let nf = n as f64;
        let (hm, km) = (h1 / nf, k1 / nf);
        let hs = ((h2 / nf - hm * hm) / nf).sqrt();
        let ks = ((k2 / nf - km * km) / nf).sqrt();
        let h = a.entropy().unwrap();
        let k = a.kl_divergence(&b).unwrap();
        assert!((h - hm).abs() < 5.0 * hs, "entropy {h} vs MC {hm} ± {hs}");
        assert!((k - km).abs() < 5.0 * ks, "KL {k} vs MC {km} ± {ks}");
        assert!(a.kl_divergence(&a).unwrap().abs() < 1e-12);
        assert!(rel(b.entropy().unwrap(), b.entropy().unwrap(), 1.0) == 0.0);
    }
    // uniform: entropy = log |S^{d-1}|
    let u = bingham(&mut rng, &[0.0, 0.0, 0.0]);
    assert!((u.entropy().unwrap() - (4.0 * std::f64::consts::PI).ln()).abs() < 1e-14);
}

#[test]
fn constructor_validates() {
    let id = DMatrix::<f64>::identity(3, 3);
    assert!(Bingham::new(id.clone(), DVector::from_vec(vec![0.0, -1.0, f64::NAN])).is_err());
    let mut bad = id.clone();
    bad[(0, 1)] = 1e-3;
    assert!(Bingham::new(bad, DVector::from_vec(vec![0.0, -1.0, -2.0])).is_err());
    assert!(Bingham::new(id.clone(), DVector::from_vec(vec![0.0, -1.0])).is_err());
    // unsorted, shifted input is normalized, and M's columns follow
    let b = Bingham::new(id, DVector::from_vec(vec![5.0, 3.0, 4.0])).unwrap();
    assert_eq!(b.z().as_slice(), &[-2.0, -1.0, 0.0]);
    assert_eq!(b.mode().as_slice(), &[1.0, 0.0, 0.0]);
    assert_eq!(b.m()[(1, 0)], 1.0);
}
