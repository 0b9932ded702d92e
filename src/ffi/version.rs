//! Version information and the library's limits and tolerances, as C constants.

use std::os::raw::c_char;

/// Major version of the header. Compare with `bingham_version()` at run time to detect a
/// header/library mismatch.
pub const BINGHAM_VERSION_MAJOR: u32 = 0;
/// Minor version of the header.
pub const BINGHAM_VERSION_MINOR: u32 = 5;
/// Patch version of the header.
pub const BINGHAM_VERSION_PATCH: u32 = 0;

/// Smallest supported dimension `d` (the circle S¹ ⊂ R²).
pub const BINGHAM_MIN_DIM: usize = 2;
/// Largest supported dimension `d`.
pub const BINGHAM_MAX_DIM: usize = 64;
/// Tolerance on max |MᵀM − I| (largest absolute entry) when an orthogonal `M` is expected;
/// accepted matrices are re-orthonormalized internally (kept as given if already orthonormal to
/// 8 ulps, as every matrix the library returns, so a returned state handed back reproduces itself
/// bit for bit).
pub const BINGHAM_ORTHOGONALITY_TOL: f64 = 1e-6;
/// Tolerance on |‖x‖ − 1| when a unit vector is expected (points of the sphere, quaternions):
/// within it the vector is normalized (a quaternion rounded to 4 or 5 decimals is accepted),
/// beyond it refused with `BINGHAM_ERR_INVALID_ARGUMENT` ("normalize it first").
pub const BINGHAM_UNIT_TOL: f64 = 1e-3;

static VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), "\0");

/// The library version as `"MAJOR.MINOR.PATCH"`, e.g. `"0.2.0"`: the version of the library
/// actually loaded, to compare with the `BINGHAM_VERSION_*` macros of the header compiled in.
///
/// Never returns `NULL`. The string is static: do not free or modify it. Thread-safe.
#[no_mangle]
pub extern "C" fn bingham_version() -> *const c_char {
    VERSION.as_ptr().cast()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn macros_match_cargo_version() {
        let v = |s: &str| s.parse::<u32>().unwrap();
        assert_eq!(
            BINGHAM_VERSION_MAJOR,
            v(env!("CARGO_PKG_VERSION_MAJOR")),
            "edit src/ffi/version.rs, then `make header`"
        );
        assert_eq!(
            BINGHAM_VERSION_MINOR,
            v(env!("CARGO_PKG_VERSION_MINOR")),
            "edit src/ffi/version.rs, then `make header`"
        );
        assert_eq!(
            BINGHAM_VERSION_PATCH,
            v(env!("CARGO_PKG_VERSION_PATCH")),
            "edit src/ffi/version.rs, then `make header`"
        );
        // SAFETY: static NUL-terminated string.
        let s = unsafe { std::ffi::CStr::from_ptr(bingham_version()) };
        assert_eq!(
            s.to_str().unwrap(),
            format!("{BINGHAM_VERSION_MAJOR}.{BINGHAM_VERSION_MINOR}.{BINGHAM_VERSION_PATCH}")
        );
    }

    #[test]
    fn limits_match_core() {
        assert_eq!(BINGHAM_MIN_DIM, crate::error::MIN_DIM);
        assert_eq!(BINGHAM_MAX_DIM, crate::error::MAX_DIM);
        assert_eq!(
            BINGHAM_ORTHOGONALITY_TOL,
            crate::distribution::ORTHOGONALITY_TOL
        );
        assert_eq!(BINGHAM_UNIT_TOL, crate::distribution::UNIT_TOL);
    }
}
