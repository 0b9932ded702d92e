//! Status codes returned by every fallible C function, and their static descriptions.

use std::os::raw::{c_char, c_int};

use crate::error::Error;

/// The result of every fallible `bingham_*` function.
///
/// `BINGHAM_OK` (0) means success; every other value is an error, and then the function has
/// written nothing to its output arguments and has stored a human-readable description for the
/// calling thread, readable with `bingham_last_error_message()`.
///
/// The numeric values are part of the ABI: they are never renumbered, new codes are only
/// appended. Code that receives a status from elsewhere (e.g. as an `int`) should treat unknown
/// values as errors; `bingham_status_str()` accepts any `int`.
#[allow(non_camel_case_types)]
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum bingham_status {
    /// Success.
    BINGHAM_OK = 0,
    /// A required pointer argument was `NULL` (or not aligned for its type).
    BINGHAM_ERR_NULL_ARGUMENT = 1,
    /// The dimension `d` is outside `BINGHAM_MIN_DIM..BINGHAM_MAX_DIM` (2..64), or the operation
    /// does not exist for this `d` (composition and rotation: d = 2 and d = 4 only), or a count
    /// is unusable (e.g. `n * d` overflows).
    BINGHAM_ERR_INVALID_DIMENSION = 2,
    /// An argument value is not acceptable: NaN or infinite entries, `M` not orthogonal
    /// (max |MᵀM − I| > `BINGHAM_ORTHOGONALITY_TOL`), a vector that should be unit length but
    /// is not (|‖x‖ − 1| > `BINGHAM_UNIT_TOL`), a second-moment matrix that is not symmetric
    /// positive semi-definite, negative weights, no samples, …
    BINGHAM_ERR_INVALID_ARGUMENT = 3,
    /// An iterative method (e.g. the maximum-likelihood fit) did not reach its tolerance.
    BINGHAM_ERR_NOT_CONVERGED = 4,
    /// The result cannot be represented: e.g. F overflows a `double` (use the log version), or an
    /// intermediate result was not finite.
    BINGHAM_ERR_NUMERICAL = 5,
    /// An internal error (a Rust panic) was caught at the C boundary. This is a bug in the
    /// library; the message says where. The library stays usable.
    BINGHAM_ERR_PANIC = 6,
    /// A user-supplied callback (the transition or log-likelihood function of
    /// `bingham_filter_predict_nonlinear` / `bingham_filter_update_nonlinear`) returned a
    /// non-zero status, or a value that is not finite (or, for a transition, not unit length
    /// within `BINGHAM_UNIT_TOL`). The message names the point and the value.
    BINGHAM_ERR_CALLBACK = 7,
}

/// All codes, in numeric order.
pub(crate) const ALL_STATUS: [bingham_status; 8] = [
    bingham_status::BINGHAM_OK,
    bingham_status::BINGHAM_ERR_NULL_ARGUMENT,
    bingham_status::BINGHAM_ERR_INVALID_DIMENSION,
    bingham_status::BINGHAM_ERR_INVALID_ARGUMENT,
    bingham_status::BINGHAM_ERR_NOT_CONVERGED,
    bingham_status::BINGHAM_ERR_NUMERICAL,
    bingham_status::BINGHAM_ERR_PANIC,
    bingham_status::BINGHAM_ERR_CALLBACK,
];

impl bingham_status {
    /// The static, NUL-terminated description of this code.
    pub(crate) fn description(self) -> &'static [u8] {
        match self {
            bingham_status::BINGHAM_OK => b"ok\0",
            bingham_status::BINGHAM_ERR_NULL_ARGUMENT => b"null argument\0",
            bingham_status::BINGHAM_ERR_INVALID_DIMENSION => b"invalid dimension\0",
            bingham_status::BINGHAM_ERR_INVALID_ARGUMENT => b"invalid argument\0",
            bingham_status::BINGHAM_ERR_NOT_CONVERGED => b"not converged\0",
            bingham_status::BINGHAM_ERR_NUMERICAL => b"numerical failure\0",
            bingham_status::BINGHAM_ERR_PANIC => b"internal error (panic)\0",
            bingham_status::BINGHAM_ERR_CALLBACK => b"callback failed\0",
        }
    }
}

impl From<&Error> for bingham_status {
    fn from(e: &Error) -> Self {
        match e {
            Error::InvalidDimension(_) => bingham_status::BINGHAM_ERR_INVALID_DIMENSION,
            Error::InvalidArgument(_) => bingham_status::BINGHAM_ERR_INVALID_ARGUMENT,
            Error::NotConverged(_) => bingham_status::BINGHAM_ERR_NOT_CONVERGED,
            Error::Numerical(_) => bingham_status::BINGHAM_ERR_NUMERICAL,
            Error::Callback(_) => bingham_status::BINGHAM_ERR_CALLBACK,
        }
    }
}

const UNKNOWN_STATUS: &[u8] = b"unknown status\0";

/// A short, static, English description of a status code, e.g. `"invalid argument"`.
///
/// Takes any `int` (so codes added by later versions are safe to pass); values that are not a
/// known `bingham_status` give `"unknown status"`. Never returns `NULL`. The returned string is
/// owned by the library, valid for the lifetime of the program, and must not be freed or
/// modified. Thread-safe.
///
/// For the detailed message of the last failed call, use `bingham_last_error_message()`.
#[no_mangle]
pub extern "C" fn bingham_status_str(status: c_int) -> *const c_char {
    let bytes = ALL_STATUS
        .iter()
        .find(|s| **s as c_int == status)
        .map_or(UNKNOWN_STATUS, |s| s.description());
    bytes.as_ptr().cast()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::CStr;

    fn s(code: c_int) -> &'static str {
        // SAFETY: bingham_status_str returns a pointer to a static NUL-terminated string.
        unsafe { CStr::from_ptr(bingham_status_str(code)) }
            .to_str()
            .unwrap()
    }

    #[test]
    fn values_are_stable() {
        for (i, st) in ALL_STATUS.iter().enumerate() {
            assert_eq!(*st as c_int, i as c_int);
        }
    }

    #[test]
    fn strings() {
        assert_eq!(s(0), "ok");
        assert_eq!(s(3), "invalid argument");
        assert_eq!(s(6), "internal error (panic)");
        assert_eq!(s(7), "callback failed");
        assert_eq!(s(8), "unknown status");
        assert_eq!(s(-1), "unknown status");
        assert_eq!(s(c_int::MAX), "unknown status");
        for st in ALL_STATUS {
            let d = st.description();
            assert_eq!(d.iter().filter(|&&b| b == 0).count(), 1);
            assert_eq!(*d.last().unwrap(), 0);
        }
    }

    #[test]
    fn error_mapping() {
        use bingham_status::*;
        let m = String::new;
        assert_eq!(
            bingham_status::from(&Error::InvalidDimension(m())),
            BINGHAM_ERR_INVALID_DIMENSION
        );
        assert_eq!(
            bingham_status::from(&Error::InvalidArgument(m())),
            BINGHAM_ERR_INVALID_ARGUMENT
        );
        assert_eq!(
            bingham_status::from(&Error::NotConverged(m())),
            BINGHAM_ERR_NOT_CONVERGED
        );
        assert_eq!(
            bingham_status::from(&Error::Numerical(m())),
            BINGHAM_ERR_NUMERICAL
        );
        assert_eq!(
            bingham_status::from(&Error::Callback(m())),
            BINGHAM_ERR_CALLBACK
        );
    }
}
