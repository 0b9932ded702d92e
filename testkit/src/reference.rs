//! The reference tables `tests/data/normalization_d{d}.csv` of the bingham crate (log F, ω and
//! the Hessian of log F at high precision), read by its integration tests and its unit tests.

use std::path::PathBuf;

/// One row of a reference file `tests/data/normalization_d{d}.csv`.
pub struct RefRow {
    pub z: Vec<f64>,
    pub log_f: f64,
    pub omega: Vec<f64>,
    /// row-major d×d Hessian of log F, empty if the file has none
    pub hess: Vec<f64>,
}

/// The bingham crate's `tests/data/` (this crate lives in its `testkit/`).
fn data_dir() -> PathBuf {
    let here = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    here.parent()
        .expect("testkit/ has a parent")
        .join("tests")
        .join("data")
}

/// Reads `tests/data/normalization_d{d}.csv` (header `d,z1..zd,logF,omega1..omegad[,H11..Hdd]`).
pub fn read_reference(d: usize) -> Vec<RefRow> {
    let path = data_dir().join(format!("normalization_d{d}.csv"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'));
    let header: Vec<&str> = lines
        .next()
        .expect("header")
        .split(',')
        .map(|s| s.trim())
        .collect();
    let col = |name: &str| header.iter().position(|h| h.eq_ignore_ascii_case(name));
    let lf = col("logF").expect("logF column");
    let mut rows = Vec::new();
    for line in lines {
        let v: Vec<f64> = line
            .split(',')
            .map(|s| s.trim().parse::<f64>().expect("number"))
            .collect();
        let z: Vec<f64> = (1..=d)
            .map(|i| v[col(&format!("z{i}")).expect("z col")])
            .collect();
        let omega: Vec<f64> = (1..=d)
            .map(|i| v[col(&format!("omega{i}")).expect("omega col")])
            .collect();
        let hess = if col("H11").is_some() {
            let mut h = Vec::with_capacity(d * d);
            for i in 1..=d {
                for j in 1..=d {
                    h.push(
                        v[col(&format!("H{i}{j}"))
                            .or_else(|| col(&format!("H{i}_{j}")))
                            .expect("H col")],
                    );
                }
            }
            h
        } else {
            Vec::new()
        };
        rows.push(RefRow {
            z,
            log_f: v[lf],
            omega,
            hess,
        });
    }
    assert!(!rows.is_empty(), "{} has no rows", path.display());
    rows
}
