//! The deterministic generators of the tests: SplitMix64 ([`Rng64`], [`mix`]), xorshift64
//! ([`XorShift64`], [`xorshift`], [`xorshift_uniform`]) and a 64-bit LCG ([`Lcg`]). Each gives the
//! same sequence on every platform, so a printed seed reproduces a case exactly.

use nalgebra::DMatrix;

use crate::norm;

/// The SplitMix64 increment (the golden ratio in 64-bit fixed point).
const GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// One SplitMix64 output step: the output for state `z` (incremented first), also used to derive
/// independent per-case seeds.
pub fn mix(z: u64) -> u64 {
    let mut z = z.wrapping_add(GAMMA);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// `(bits >> 11) / 2⁵³`: uniform in [0, 1) from the top 53 bits.
fn to_unit(bits: u64) -> f64 {
    (bits >> 11) as f64 / (1u64 << 53) as f64
}

/// SplitMix64 (Steele, Lea & Flood 2014): tiny, fast, and the same sequence on every platform.
/// The field is the state; `Rng64(seed)` and `Rng64::new(seed)` start at `seed`.
#[derive(Clone, Debug)]
pub struct Rng64(pub u64);

impl Rng64 {
    pub fn new(seed: u64) -> Rng64 {
        Rng64(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        let out = mix(self.0);
        self.0 = self.0.wrapping_add(GAMMA);
        out
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        to_unit(self.next_u64())
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// Uniform integer in 0..n (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        ((self.next_u64() as u128 * n as u128) >> 64) as usize
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.uniform() < p
    }

    /// Standard normal (Box–Muller, the cosine branch).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// `10^U(lo, hi)`.
    pub fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        10f64.powf(self.range(lo, hi))
    }

    /// One of `items`, uniformly.
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }

    /// A uniformly random unit vector of length `d` (normalized Gaussian; drawn again in the
    /// (practically never seen) case that its norm is below 1e-3).
    pub fn unit_vector(&mut self, d: usize) -> Vec<f64> {
        loop {
            let v: Vec<f64> = (0..d).map(|_| self.normal()).collect();
            let n = norm(&v);
            if n > 1e-3 {
                return v.iter().map(|x| x / n).collect();
            }
        }
    }

    /// [`Rng64::unit_vector`] as an array: `rng.unit_array::<3>()`.
    pub fn unit_array<const N: usize>(&mut self) -> [f64; N] {
        let v = self.unit_vector(N);
        std::array::from_fn(|i| v[i])
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

/// xorshift64 (Marsaglia 2003, shifts 13, 7, 17); the state must not be 0.
#[derive(Clone, Debug)]
pub struct XorShift64(pub u64);

impl XorShift64 {
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        to_unit(self.next_u64())
    }
}

/// Uniform draws in `[−½, ½)` from the xorshift64 sequence started at `seed` (non-zero).
pub fn xorshift(seed: u64) -> impl FnMut() -> f64 {
    let mut r = XorShift64(seed);
    move || r.uniform() - 0.5
}

/// Uniform draws in `[0, 1)` from the xorshift64 sequence started at `seed` (non-zero).
pub fn xorshift_uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut r = XorShift64(seed);
    move || r.uniform()
}

/// The 64-bit linear congruential generator of Knuth's MMIX (`s ← 6364136223846793005 s +
/// 1442695040888963407`); the field is the state.
#[derive(Clone, Debug)]
pub struct Lcg(pub u64);

impl Lcg {
    /// Steps the state, then: uniform in [0, 1) from its top 53 bits.
    pub fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        to_unit(self.0)
    }
}
