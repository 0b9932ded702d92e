//! Which compiled kernel evaluates the quadrature's nodes ([`Path`]): the ones this CPU can
//! run, and the one chosen once per process at run time.

use std::sync::OnceLock;

/// The compiled kernel that evaluates the d = 3, 4 quadrature nodes (several at a time, see
/// `quadrature/`). [`Path::detected`] picks the one every evaluation uses, once per process; the
/// others exist for tests and benchmarks
/// ([`log_f_with_path`](crate::normalization::log_f_with_path)). All paths agree to rounding
/// (they differ only in fused versus separate multiply-adds, `tests/dispatch.rs`); each is
/// deterministic: the same input gives the same bits on every call and thread.
#[doc(hidden)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Path {
    /// Plain arithmetic on the target's baseline instruction set (SSE2 on x86-64, NEON on
    /// aarch64), 4 lanes.
    Portable,
    /// x86-64 with AVX2 and FMA, 4 lanes.
    Avx2,
    /// x86-64 with AVX-512 (F, VL, DQ), AVX2 and FMA, 8 lanes. Chosen by [`Path::detected`]
    /// where available: on the AMD Zen 4 development machine (512-bit operations in two 256-bit
    /// passes) it is faster than `Avx2` on every d = 3, 4 benchmark case (criterion, group
    /// `d4_path` of `benches/normalization.rs`; figures in `docs/speed.md`, row `d4-path`).
    /// The kernel is limited by its instruction count, which 8 lanes halve.
    Avx512,
}

impl Path {
    /// Every path, available or not.
    pub const ALL: [Path; 3] = [Path::Portable, Path::Avx2, Path::Avx512];

    /// Whether this CPU can run the path.
    pub fn available(self) -> bool {
        match self {
            Path::Portable => true,
            #[cfg(target_arch = "x86_64")]
            Path::Avx2 => is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"),
            #[cfg(target_arch = "x86_64")]
            Path::Avx512 => {
                Path::Avx2.available()
                    && is_x86_feature_detected!("avx512f")
                    && is_x86_feature_detected!("avx512vl")
                    && is_x86_feature_detected!("avx512dq")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The path every evaluation uses, detected on first use: `Avx512` where the CPU has
    /// AVX-512 F/VL/DQ, AVX2 and FMA, else `Avx2` where it has AVX2 and FMA, else `Portable`.
    pub fn detected() -> Path {
        static BEST: OnceLock<Path> = OnceLock::new();
        *BEST.get_or_init(|| {
            if Path::Avx512.available() {
                Path::Avx512
            } else if Path::Avx2.available() {
                Path::Avx2
            } else {
                Path::Portable
            }
        })
    }
}
