//! Which compiled kernel evaluates the quadrature's nodes ([`Path`]): the ones this CPU can
//! run, and the one chosen once per process at run time (the fastest, or the one the
//! environment variable [`KERNEL_ENV`], `BINGHAM_KERNEL`, names).

use std::sync::OnceLock;

/// The compiled kernel that evaluates the d = 3, 4 quadrature nodes (several at a time, see
/// `quadrature/`). [`Path::detected`] picks the one every evaluation uses, once per process (the
/// fastest this CPU runs, unless `BINGHAM_KERNEL` names another: [`KERNEL_ENV`]); the others
/// exist for tests and benchmarks
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

/// The environment variable that forces the kernel path: `BINGHAM_KERNEL=portable`, `avx2` or
/// `avx512` (ASCII case ignored, surrounding white space ignored). Read once per process, on the
/// first evaluation of a normalization constant ([`Path::detected`]); changing it afterwards has
/// no effect. A value
/// naming no path, or a path this CPU cannot run, is ignored: the fastest available path is used
/// (so an AVX path never runs on a CPU without those instructions, whatever the variable says).
pub const KERNEL_ENV: &str = "BINGHAM_KERNEL";

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

    /// The path's name, as [`KERNEL_ENV`] spells it: `portable`, `avx2`, `avx512`.
    pub fn name(self) -> &'static str {
        match self {
            Path::Portable => "portable",
            Path::Avx2 => "avx2",
            Path::Avx512 => "avx512",
        }
    }

    /// The path a name spells ([`Path::name`]; ASCII case and surrounding white space ignored),
    /// available or not; `None` for any other string.
    pub fn from_name(name: &str) -> Option<Path> {
        let name = name.trim();
        Path::ALL
            .into_iter()
            .find(|p| p.name().eq_ignore_ascii_case(name))
    }

    /// The fastest path this CPU runs: `Avx512` where the CPU has AVX-512 F/VL/DQ, AVX2 and FMA,
    /// else `Avx2` where it has AVX2 and FMA, else `Portable`.
    pub fn fastest() -> Path {
        if Path::Avx512.available() {
            Path::Avx512
        } else if Path::Avx2.available() {
            Path::Avx2
        } else {
            Path::Portable
        }
    }

    /// The path for a value of [`KERNEL_ENV`] (`None`: the variable is unset or not UTF-8): the
    /// path it names if this CPU can run it, else [`Path::fastest`]. Never an unavailable path.
    pub fn requested(value: Option<&str>) -> Path {
        match value.and_then(Path::from_name) {
            Some(path) if path.available() => path,
            _ => Path::fastest(),
        }
    }

    /// The path every evaluation uses, chosen on first use and kept for the life of the
    /// process: [`Path::requested`] with the value of [`KERNEL_ENV`] (`BINGHAM_KERNEL`), i.e.
    /// the fastest path this CPU runs ([`Path::fastest`]) unless the variable names another
    /// available one. Always [`available`](Path::available).
    pub fn detected() -> Path {
        static CHOSEN: OnceLock<Path> = OnceLock::new();
        *CHOSEN.get_or_init(|| {
            let value = std::env::var_os(KERNEL_ENV);
            Path::requested(value.as_ref().and_then(|v| v.to_str()))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_values_fall_back() {
        for path in Path::ALL {
            assert_eq!(Path::from_name(path.name()), Some(path));
            assert_eq!(
                Path::from_name(&format!(" {} ", path.name().to_uppercase())),
                Some(path)
            );
            let chosen = Path::requested(Some(path.name()));
            assert!(chosen.available());
            if path.available() {
                assert_eq!(chosen, path);
            } else {
                assert_eq!(chosen, Path::fastest());
            }
        }
        for value in [
            None,
            Some(""),
            Some("sse2"),
            Some("avx"),
            Some("avx-512"),
            Some("x"),
        ] {
            assert_eq!(value.and_then(Path::from_name), None, "{value:?}");
            assert_eq!(Path::requested(value), Path::fastest(), "{value:?}");
        }
        assert!(Path::fastest().available());
        assert!(Path::detected().available());
    }
}
