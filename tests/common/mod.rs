//! Shared helpers for the integration tests.
#![allow(dead_code)]

use nalgebra::DMatrix;

/// One row of a reference file `tests/data/normalization_d{d}.csv`.
pub struct RefRow {
    pub z: Vec<f64>,
    pub log_f: f64,
    pub omega: Vec<f64>,
    /// row-major d×d Hessian of log F, empty if the file has none
    pub hess: Vec<f64>,
}

/// Reads `tests/data/normalization_d{d}.csv` (header `d,z1..zd,logF,omega1..omegad[,H11..Hdd]`).
pub fn read_reference(d: usize) -> Vec<RefRow> {
    let path = format!(
        "{}/tests/data/normalization_d{d}.csv",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
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
    assert!(!rows.is_empty(), "{path} has no rows");
    rows
}

/// A deterministic pseudo-random generator for tests (SplitMix64).
pub struct Rng64(pub u64);

impl Rng64 {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E3779B97F4A7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
        z ^ (z >> 31)
    }
    /// uniform in [0, 1)
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
    /// A Haar-random orthogonal d×d matrix (QR of a Gaussian matrix with sign fix).
    pub fn orthogonal(&mut self, d: usize) -> DMatrix<f64> {
        let g = DMatrix::from_fn(d, d, |_, _| self.normal());
        let qr = g.qr();
        let mut q = qr.q();
        let r = qr.r();
        for j in 0..d {
            if r[(j, j)] < 0.0 {
                for i in 0..d {
                    q[(i, j)] = -q[(i, j)];
                }
            }
        }
        q
    }
}

/// Relative error |a − b| / |b| (absolute when |b| < floor).
pub fn rel(a: f64, b: f64, floor: f64) -> f64 {
    (a - b).abs() / b.abs().max(floor)
}

/// `R(q)` of a unit quaternion (scalar first, `v_world = q v q*`), the textbook formula.
pub fn rot(q: &[f64; 4]) -> [[f64; 3]; 3] {
    let (w, x, y, z) = (q[0], q[1], q[2], q[3]);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}
