//! The d = 3, 4 quadrature kernels (`Path`: portable, AVX2 + FMA, AVX-512): every path this CPU
//! runs agrees with the portable one to 1e-14 relative (log F, ω, and the Hessian relative to
//! `√(H_ii H_jj)`), over random z in [−1e6, 0]^d, ties, zeros and extremes up to the largest
//! doubles; each path gives bit-identical results on repeated calls and on other threads; and
//! the default evaluation uses the detected path; `BINGHAM_KERNEL` forces the path of a process
//! (this binary run again as a child process with the variable set), and a value naming no path
//! or a path the CPU lacks falls back to the fastest available one.

use bingham::normalization::{log_f_with_path, log_normalization_into, Method, Path, KERNEL_ENV};
use testkit::Rng64;

/// log F, ω and H (input order) on one path.
fn eval(z: &[f64], path: Path) -> (f64, Vec<f64>, Vec<f64>) {
    let d = z.len();
    let mut g = vec![0.0; d];
    let mut h = vec![0.0; d * d];
    let lf = log_f_with_path(z, path, Some(&mut g), Some(&mut h)).unwrap();
    (lf, g, h)
}

/// Random z of dimension 3 or 4: uniform in [−1e6, 0], log-uniform magnitudes from 1e-3 to
/// 1e6 or (rarely) up to 1e300, with zeros and ties.
fn random_z(rng: &mut Rng64, d: usize) -> Vec<f64> {
    let kind = rng.next_u64() % 4;
    let mut z: Vec<f64> = (0..d)
        .map(|_| match kind {
            0 => -1e6 * rng.uniform(),
            1 | 2 => -(10f64).powf(-3.0 + 9.0 * rng.uniform()),
            _ => -(10f64).powf(-3.0 + 303.0 * rng.uniform()),
        })
        .collect();
    for i in 0..d {
        match rng.next_u64() % 10 {
            0 => z[i] = 0.0,
            1 => z[i] = z[(rng.next_u64() as usize) % d],
            _ => {}
        }
    }
    z
}

/// The test inputs: fixed corner cases, then random ones.
fn inputs() -> Vec<Vec<f64>> {
    let max = f64::MAX;
    let mut zs = vec![
        vec![0.0, 0.0, 0.0],
        vec![0.0, 0.0, 0.0, 0.0],
        vec![-1.0, -1.0, -1.0, 0.0],
        vec![-200.0, -200.0, -2.0, 0.0],
        vec![-1e4, -1e3, -1e2, 0.0],
        vec![-5e4, -5e4, 0.0, 0.0],
        vec![-1e6, -10.0, -1.0, 0.0],
        vec![-1e6, -1e6, -1e6, 0.0],
        vec![-10.0, -1.0, 0.0],
        vec![-1e6, -10.0, 0.0],
        vec![-1e6, -1e6, 0.0],
        vec![-1e300, -1e299, -1e298, 0.0],
        vec![-max, -max, -max, 0.0],
        vec![-max, -1.0, -1e-300, 0.0],
        vec![-5e-324, 0.0, -5e-324],
        vec![-128.0, -0.0, -256.0, -64.0],
    ];
    let mut rng = Rng64(20240607);
    for k in 0..3000 {
        zs.push(random_z(&mut rng, 3 + k % 2));
    }
    zs
}

/// Largest difference between two evaluations: |Δ log F| / max(1, |log F|), relative Δω,
/// ΔH relative to `√(H_ii H_jj)`.
fn difference(a: &(f64, Vec<f64>, Vec<f64>), b: &(f64, Vec<f64>, Vec<f64>)) -> [f64; 3] {
    let d = a.1.len();
    let ef = (a.0 - b.0).abs() / b.0.abs().max(1.0);
    let ew =
        a.1.iter()
            .zip(&b.1)
            .map(|(x, y)| (x - y).abs() / y.abs())
            .fold(0.0, f64::max);
    let mut eh = 0.0f64;
    for i in 0..d {
        for j in 0..d {
            let scale = (b.2[i * d + i] * b.2[j * d + j]).abs().sqrt();
            if scale > 0.0 {
                eh = eh.max((a.2[i * d + j] - b.2[i * d + j]).abs() / scale);
            }
        }
    }
    [ef, ew, eh]
}

#[test]
fn every_available_path_agrees_with_the_portable_one() {
    let paths: Vec<Path> = Path::ALL.into_iter().filter(|p| p.available()).collect();
    assert!(paths.contains(&Path::Portable));
    let zs = inputs();
    for &path in &paths {
        let mut worst = [0.0f64; 3];
        for z in &zs {
            let p = eval(z, Path::Portable);
            let e = eval(z, path);
            assert!(e.0.is_finite() && e.1.iter().chain(&e.2).all(|v| v.is_finite()));
            let diff = difference(&e, &p);
            for (w, v) in worst.iter_mut().zip(diff) {
                *w = w.max(v);
            }
            assert!(
                diff.iter().all(|&v| v <= 1e-14),
                "{path:?} vs portable at z = {z:?}: {diff:?}"
            );
        }
        println!(
            "{path:?}: {} inputs, max |Δ log F| {:.1e}, rel Δω {:.1e}, ΔH {:.1e}",
            zs.len(),
            worst[0],
            worst[1],
            worst[2]
        );
    }
    println!("paths run: {paths:?}; detected: {:?}", Path::detected());
}

#[test]
fn unavailable_paths_are_refused() {
    for path in Path::ALL {
        let r = log_f_with_path(&[-1.0, -0.5, 0.0], path, None, None);
        assert_eq!(r.is_ok(), path.available(), "{path:?}");
    }
}

#[test]
fn the_default_evaluation_uses_the_detected_path() {
    assert!(Path::detected().available());
    for z in inputs().iter().take(200) {
        let d = z.len();
        let mut g = vec![0.0; d];
        let mut h = vec![0.0; d * d];
        let lf = log_normalization_into(z, Method::Exact, Some(&mut g), Some(&mut h)).unwrap();
        let e = eval(z, Path::detected());
        assert_eq!(lf.to_bits(), e.0.to_bits(), "{z:?}");
        assert!(g.iter().zip(&e.1).all(|(a, b)| a.to_bits() == b.to_bits()));
        assert!(h.iter().zip(&e.2).all(|(a, b)| a.to_bits() == b.to_bits()));
    }
}

/// Bit patterns of every output for every input on one path.
fn transcript(path: Path, zs: &[Vec<f64>]) -> Vec<u64> {
    let mut out = Vec::new();
    for z in zs {
        let (lf, g, h) = eval(z, path);
        out.push(lf.to_bits());
        out.extend(g.iter().chain(&h).map(|v| v.to_bits()));
        // gradient only (a kernel without fourth moments)
        let mut g2 = vec![0.0; z.len()];
        let lf2 = log_f_with_path(z, path, Some(&mut g2), None).unwrap();
        out.push(lf2.to_bits());
        out.extend(g2.iter().map(|v| v.to_bits()));
    }
    out
}

#[test]
fn results_are_bit_identical_across_calls_and_threads() {
    let zs: Vec<Vec<f64>> = inputs().into_iter().take(600).collect();
    for path in Path::ALL.into_iter().filter(|p| p.available()) {
        let first = transcript(path, &zs);
        assert_eq!(first, transcript(path, &zs), "{path:?}: second run differs");
        let threads: Vec<_> = (0..4)
            .map(|_| {
                let zs = zs.clone();
                std::thread::spawn(move || transcript(path, &zs))
            })
            .collect();
        for t in threads {
            assert_eq!(first, t.join().unwrap(), "{path:?}: another thread differs");
        }
    }
}

/// Set in the child process of [`the_environment_variable_forces_the_path`].
const CHILD: &str = "BINGHAM_DISPATCH_CHILD";

/// The z the child evaluates (d = 3 and 4, gradient and Hessian).
fn child_inputs() -> Vec<Vec<f64>> {
    inputs().into_iter().step_by(50).collect()
}

/// One line per input: the bits of log F, ω and H of the default evaluation (hex).
fn default_transcript(zs: &[Vec<f64>]) -> Vec<String> {
    zs.iter()
        .map(|z| {
            let d = z.len();
            let mut g = vec![0.0; d];
            let mut h = vec![0.0; d * d];
            let lf = log_normalization_into(z, Method::Exact, Some(&mut g), Some(&mut h)).unwrap();
            std::iter::once(lf)
                .chain(g)
                .chain(h)
                .map(|v| format!("{:016x}", v.to_bits()))
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect()
}

/// The child's side: does nothing unless started by the test below; then prints the chosen
/// path and the transcript of the default evaluation.
#[test]
fn child_reports_its_path() {
    if std::env::var_os(CHILD).is_none() {
        return;
    }
    // own lines (the test harness prints the test's name without a line break before it)
    println!("\nKERNEL-PATH {}", Path::detected().name());
    for line in default_transcript(&child_inputs()) {
        println!("KERNEL-BITS {line}");
    }
}

#[test]
fn the_environment_variable_forces_the_path() {
    let exe = std::env::current_exe().unwrap();
    let zs = child_inputs();
    let values: [Option<&str>; 8] = [
        None,
        Some("portable"),
        Some("avx2"),
        Some("avx512"),
        Some(" AVX2 "),
        Some("sse4"),
        Some(""),
        Some("avx512-please"),
    ];
    for value in values {
        let mut cmd = std::process::Command::new(&exe);
        cmd.args([
            "--exact",
            "child_reports_its_path",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD, "1");
        match value {
            Some(v) => cmd.env(KERNEL_ENV, v),
            None => cmd.env_remove(KERNEL_ENV),
        };
        let out = cmd.output().unwrap();
        assert!(out.status.success(), "{value:?}: the child failed: {out:?}");
        let stdout = String::from_utf8(out.stdout).unwrap();
        let name = stdout
            .lines()
            .find_map(|l| l.strip_prefix("KERNEL-PATH "))
            .unwrap_or_else(|| panic!("{value:?}: no path in {stdout}"));
        let chosen = Path::from_name(name).unwrap();
        // the named path where this CPU runs it, else the fastest one; never an unavailable one
        let expected = match value.and_then(Path::from_name) {
            Some(p) if p.available() => p,
            _ => Path::fastest(),
        };
        assert_eq!(chosen, expected, "{KERNEL_ENV}={value:?}");
        assert!(chosen.available());
        // the child's default evaluation ran on that path: the same bits as the path here
        let bits: Vec<&str> = stdout
            .lines()
            .filter_map(|l| l.strip_prefix("KERNEL-BITS "))
            .collect();
        assert_eq!(bits.len(), zs.len(), "{value:?}");
        for (z, line) in zs.iter().zip(bits) {
            let (lf, g, h) = eval(z, chosen);
            let want: Vec<String> = std::iter::once(lf)
                .chain(g)
                .chain(h)
                .map(|v| format!("{:016x}", v.to_bits()))
                .collect();
            assert_eq!(line, want.join(" "), "{KERNEL_ENV}={value:?}, z = {z:?}");
        }
        println!("{KERNEL_ENV}={value:?}: {name}");
    }
}
