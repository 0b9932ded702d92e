//! Statuses and the last error message (bingham's C ABI; the generic helpers are in
//! `testkit::fuzz`).

use bingham::ffi::*;
use testkit::fuzz::read_message;

/// This thread's last error message.
pub(crate) fn last_error() -> String {
    // SAFETY: the length query (NULL buffer, len 0), then a buffer of the length it gave.
    read_message(|buf, len, n| unsafe {
        bingham_last_error_message(buf, len, n);
    })
}

/// Sets this thread's last error to a known message (from a deliberately failing call) so that
/// a later check can tell whether a failing call replaced it. Returns the message.
pub(crate) fn prime_last_error(avoid: &str) -> &'static str {
    // SAFETY: d = 0 fails before any pointer is used.
    if avoid != "bingham_mode" {
        let st =
            unsafe { bingham_mode(0, std::ptr::null(), std::ptr::null(), std::ptr::null_mut()) };
        assert_eq!(st, bingham_status::BINGHAM_ERR_INVALID_DIMENSION);
        "bingham_mode: "
    } else {
        // SAFETY: as above.
        let st = unsafe {
            bingham::ffi::bingham_entropy(
                0,
                std::ptr::null(),
                std::ptr::null(),
                std::ptr::null_mut(),
            )
        };
        assert_eq!(st, bingham_status::BINGHAM_ERR_INVALID_DIMENSION);
        "bingham_entropy: "
    }
}

/// The last error was set by a failing call of `name`: it starts with `"<name>: "` and says
/// more than that.
pub(crate) fn check_error_message(name: &str) -> Result<(), String> {
    let msg = last_error();
    let prefix = format!("{name}: ");
    if !msg.starts_with(&prefix) || msg.len() <= prefix.len() + 3 {
        return Err(format!(
            "last error message {msg:?} does not describe a failing {name}"
        ));
    }
    Ok(())
}

pub(crate) fn status_name(s: bingham_status) -> &'static str {
    use bingham_status::*;
    match s {
        BINGHAM_OK => "OK",
        BINGHAM_ERR_NULL_ARGUMENT => "NULL_ARGUMENT",
        BINGHAM_ERR_INVALID_DIMENSION => "INVALID_DIMENSION",
        BINGHAM_ERR_INVALID_ARGUMENT => "INVALID_ARGUMENT",
        BINGHAM_ERR_NOT_CONVERGED => "NOT_CONVERGED",
        BINGHAM_ERR_NUMERICAL => "NUMERICAL",
        BINGHAM_ERR_PANIC => "PANIC",
        BINGHAM_ERR_CALLBACK => "CALLBACK",
    }
}

/// The status as its integer code (also for values outside the enum, which would be a bug).
pub(crate) fn status_code(s: bingham_status) -> i32 {
    // SAFETY: bingham_status is a fieldless repr(C) enum: reading its bits as an int is fine.
    unsafe { std::mem::transmute::<bingham_status, i32>(s) }
}
