//! The kernel compiled per CPU path, and the run-time choice among them: the portable build
//! (SSE2 on x86-64, NEON on aarch64), AVX2 + FMA, and AVX-512. This is the crate's only `unsafe`
//! outside the C ABI (`src/ffi/`): calling a function compiled with `#[target_feature]` for CPU
//! features that run-time detection ([`Path::available`]) has found. `tests/layering.rs` keeps it
//! that way.

use super::groups::Group;
use super::kernel::{half, HalfSetup, Sums};
use super::kernel_path::Path;
use super::rule::Rule;
#[cfg(target_arch = "x86_64")]
use crate::special::lanes::Fused;
use crate::special::lanes::{Arith, Plain};

/// [`half`] for the group sizes and moments asked for, with arithmetic `A` on `L` lanes.
#[inline(always)]
pub(super) fn half_any<A: Arith, const L: usize, const L2: usize, const L4: usize>(
    rule: &Rule,
    g1: &Group,
    g2: &Group,
    near_first: bool,
    fourth: bool,
    setup: &HalfSetup,
) -> Sums {
    match (g1.size(), fourth) {
        (1, false) => half::<A, L, L2, L4, 1, false>(rule, g1, g2, near_first, setup),
        (1, true) => half::<A, L, L2, L4, 1, true>(rule, g1, g2, near_first, setup),
        (_, false) => half::<A, L, L2, L4, 2, false>(rule, g1, g2, near_first, setup),
        (_, true) => half::<A, L, L2, L4, 2, true>(rule, g1, g2, near_first, setup),
    }
}

/// The portable kernel: plain `a·b + c`, 4 lanes (two SSE2 or NEON registers per step).
pub(super) fn half_portable(
    rule: &Rule,
    g1: &Group,
    g2: &Group,
    near_first: bool,
    fourth: bool,
    setup: &HalfSetup,
) -> Sums {
    half_any::<Plain, 4, 8, 16>(rule, g1, g2, near_first, fourth, setup)
}

/// The kernel compiled for AVX2 and FMA: 4 lanes, one 256-bit register per step.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
pub(super) fn half_avx2(
    rule: &Rule,
    g1: &Group,
    g2: &Group,
    near_first: bool,
    fourth: bool,
    setup: &HalfSetup,
) -> Sums {
    half_any::<Fused, 4, 8, 16>(rule, g1, g2, near_first, fourth, setup)
}

/// The kernel compiled for AVX-512 (F, VL, DQ) and FMA: 8 lanes, one 512-bit register per step.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512dq,avx2,fma")]
pub(super) fn half_avx512(
    rule: &Rule,
    g1: &Group,
    g2: &Group,
    near_first: bool,
    fourth: bool,
    setup: &HalfSetup,
) -> Sums {
    half_any::<Fused, 8, 16, 32>(rule, g1, g2, near_first, fourth, setup)
}

/// One half with the kernel of `path` (which must be available, see [`Path::available`]).
pub(super) fn half_on(
    path: Path,
    rule: &Rule,
    g1: &Group,
    g2: &Group,
    near_first: bool,
    fourth: bool,
    setup: &HalfSetup,
) -> Sums {
    debug_assert!(path.available());
    match path {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `path` is only `Avx2` when the CPU has AVX2 and FMA (`Path::available`,
        // checked by every caller: `Path::detected` and `log_f_with_path`).
        Path::Avx2 => unsafe { half_avx2(rule, g1, g2, near_first, fourth, setup) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above, with AVX-512 F/VL/DQ, AVX2 and FMA.
        Path::Avx512 => unsafe { half_avx512(rule, g1, g2, near_first, fourth, setup) },
        _ => half_portable(rule, g1, g2, near_first, fourth, setup),
    }
}
