//! The C boundary's safety net: the panic guard around every export, pointer and length checks,
//! copying in and out of caller memory, and the thread-local last error message.
//!
//! The crate's `unsafe` lives in `src/ffi/` and in one other file,
//! `src/normalization/quadrature/simd.rs` (the call of the SIMD kernel compiled for the CPU
//! features detected at run time); `tests/layering.rs` keeps it so. The helpers here keep the
//! FFI's `unsafe` in a few small places.

use std::any::Any;
use std::cell::RefCell;
use std::os::raw::c_char;
use std::panic::{catch_unwind, AssertUnwindSafe};

use super::status::bingham_status;
use crate::error::{check_dim, Error};

/// The last error of a thread: the message callers read, and the first error since the message
/// was last read (so that a caller who does not check every status still finds the cause).
struct LastError {
    message: String,
    first_unread: Option<String>,
}

thread_local! {
    /// The most recent failed call on this thread (empty message: none yet).
    /// The only mutable state of the library; one per thread, so no locking.
    static LAST_ERROR: RefCell<LastError> = const {
        RefCell::new(LastError {
            message: String::new(),
            first_unread: None,
        })
    };
}

/// What follows the newest message when earlier errors were not read.
const FIRST_UNREAD: &str = " [the first error since the message was last read: ";

/// An error on its way to C: the status to return and the message to store.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Failure {
    pub(crate) status: bingham_status,
    pub(crate) message: String,
}

impl Failure {
    pub(crate) fn new(status: bingham_status, message: impl Into<String>) -> Failure {
        Failure {
            status,
            message: message.into(),
        }
    }

    pub(crate) fn null(name: &str) -> Failure {
        Failure::new(
            bingham_status::BINGHAM_ERR_NULL_ARGUMENT,
            format!("`{name}` is NULL"),
        )
    }

    pub(crate) fn argument(message: impl Into<String>) -> Failure {
        Failure::new(bingham_status::BINGHAM_ERR_INVALID_ARGUMENT, message)
    }

    pub(crate) fn dimension(message: impl Into<String>) -> Failure {
        Failure::new(bingham_status::BINGHAM_ERR_INVALID_DIMENSION, message)
    }

    /// Adds context (e.g. which argument or row) in front of the message.
    pub(crate) fn context(mut self, what: impl std::fmt::Display) -> Failure {
        self.message = format!("{what}: {}", self.message);
        self
    }
}

impl From<Error> for Failure {
    fn from(e: Error) -> Failure {
        Failure::new(bingham_status::from(&e), e.to_string())
    }
}

pub(crate) type FfiResult<T> = Result<T, Failure>;

fn set_last_error(message: String) {
    // `try_with`: during thread teardown the slot may be gone; then the message is dropped.
    let _ = LAST_ERROR.try_with(|slot| {
        if let Ok(mut s) = slot.try_borrow_mut() {
            match &s.first_unread {
                Some(first) => s.message = format!("{message}{FIRST_UNREAD}{first}]"),
                None => {
                    s.first_unread = Some(message.clone());
                    s.message = message;
                }
            }
        }
    });
}

fn panic_message(payload: &(dyn Any + Send)) -> &str {
    if let Some(s) = payload.downcast_ref::<&'static str>() {
        s
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.as_str()
    } else {
        "(no message)"
    }
}

/// Runs the body of the exported function `name`: catches panics, turns errors into a status and
/// stores their message (prefixed with `name`) as this thread's last error.
///
/// The success path is the body and a test of its result: `catch_unwind` costs nothing until a
/// panic unwinds, and the last-error slot is touched only on failure (in the cold functions
/// below, kept out of line so that the exports' fast path stays small; issue 35, `docs/speed.md`
/// row `c-call`).
#[inline]
pub(crate) fn guard(name: &'static str, body: impl FnOnce() -> FfiResult<()>) -> bingham_status {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => bingham_status::BINGHAM_OK,
        Ok(Err(failure)) => failed(name, failure),
        Err(payload) => panicked(name, payload),
    }
}

/// The error path of [`guard`]: stores the message, returns the status.
#[cold]
#[inline(never)]
fn failed(name: &'static str, failure: Failure) -> bingham_status {
    set_last_error(format!("{name}: {}", failure.message));
    failure.status
}

/// The panic path of [`guard`].
#[cold]
#[inline(never)]
fn panicked(name: &'static str, payload: Box<dyn Any + Send>) -> bingham_status {
    set_last_error(format!(
        "{name}: internal error (panic): {}",
        panic_message(payload.as_ref())
    ));
    bingham_status::BINGHAM_ERR_PANIC
}

/// `d` within `MIN_DIM..=MAX_DIM`; checked before any array is read, because array lengths
/// are derived from `d`.
pub(crate) fn dim(d: usize) -> FfiResult<()> {
    check_dim(d).map_err(Failure::from)
}

/// `a * b` as an array length (elements of `f64`), refusing overflow.
pub(crate) fn len2(what: &str, a: usize, b: usize) -> FfiResult<usize> {
    a.checked_mul(b)
        .filter(|&n| n <= isize::MAX as usize / std::mem::size_of::<f64>())
        .ok_or_else(|| Failure::dimension(format!("`{what}`: {a} * {b} elements overflow")))
}

/// A required pointer: not NULL and aligned for `T`.
#[inline]
pub(crate) fn need<T>(name: &str, p: *const T) -> FfiResult<()> {
    if p.is_null() || (p as usize) % std::mem::align_of::<T>() != 0 {
        Err(bad_pointer(name, p.is_null()))
    } else {
        Ok(())
    }
}

/// The failure of [`need`] (out of line: the checks' fast path stays small).
#[cold]
#[inline(never)]
fn bad_pointer(name: &str, null: bool) -> Failure {
    if null {
        Failure::null(name)
    } else {
        Failure::new(
            bingham_status::BINGHAM_ERR_NULL_ARGUMENT,
            format!("`{name}` is not aligned for its type"),
        )
    }
}

/// The failure of [`read`]: names the first entry that is not finite.
#[cold]
#[inline(never)]
fn not_finite(name: &str, s: &[f64]) -> Failure {
    let i = s.iter().position(|v| !v.is_finite()).unwrap_or(0);
    Failure::argument(format!("`{name}[{i}]` = {} is not finite", s[i]))
}

/// Borrows the caller's input array `p[0..len]` after checking the pointer and that every entry
/// is finite. `len == 0` accepts a NULL pointer and gives an empty slice.
///
/// # Safety
/// `p` must be NULL or point to `len` readable `double`s that stay valid and are not written
/// while the returned slice is used (the C caller's side of the contract in the header).
#[inline]
pub(crate) unsafe fn read<'a>(name: &str, p: *const f64, len: usize) -> FfiResult<&'a [f64]> {
    if len == 0 {
        return Ok(&[]);
    }
    need(name, p)?;
    // SAFETY: p is non-NULL and aligned (checked above); the caller guarantees `len` readable
    // doubles; `len * 8 <= isize::MAX` is guaranteed by the callers (`len2` or `len <= 64²`).
    let s = unsafe { std::slice::from_raw_parts(p, len) };
    // every entry tested (no early exit: a loop the compiler can vectorize), the message built
    // out of line
    if !s.iter().fold(true, |ok, v| ok & v.is_finite()) {
        return Err(not_finite(name, s));
    }
    Ok(s)
}

/// Borrows the caller's input array `p[0..len]` after checking the pointer, without checking
/// the values (for streams whose bad entries are refused one sample at a time).
///
/// # Safety
/// As for [`read`].
#[inline]
pub(crate) unsafe fn read_raw<'a>(name: &str, p: *const f64, len: usize) -> FfiResult<&'a [f64]> {
    if len == 0 {
        return Ok(&[]);
    }
    need(name, p)?;
    // a length given directly by the caller (`n` samples): refused before a slice that large
    // is formed, which would be undefined behaviour whatever memory is there
    if len > isize::MAX as usize / std::mem::size_of::<f64>() {
        return Err(Failure::dimension(format!(
            "`{name}`: {len} elements overflow"
        )));
    }
    // SAFETY: as in `read`; `len * 8 <= isize::MAX` checked above.
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

/// A caller's output array `p[0..len]` as a mutable slice (for outputs written progressively,
/// such as a batch's rows).
///
/// # Safety
/// `p` must be non-NULL, aligned, and point to `len` writable doubles not aliased by any input
/// slice in use.
pub(crate) unsafe fn output<'a>(name: &str, p: *mut f64, len: usize) -> FfiResult<&'a mut [f64]> {
    if len == 0 {
        return Ok(&mut []);
    }
    need(name, p)?;
    // SAFETY: caller contract.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

/// Copies a computed result into the caller's output array. Called only after every input has
/// been read and the whole computation has succeeded, so outputs may overlap inputs (in-place
/// use) and nothing is written on error.
///
/// # Safety
/// `p` must be non-NULL, aligned, and point to `src.len()` writable `double`s; no Rust reference
/// to that memory may be used afterwards.
#[inline]
pub(crate) unsafe fn write(p: *mut f64, src: &[f64]) {
    debug_assert!(!p.is_null());
    use std::ptr::copy_nonoverlapping as copy;
    // Short outputs (a value, a vector, a quaternion) are copied with a constant length: a few
    // moves instead of a call of `memcpy`.
    // SAFETY: the caller guarantees `src.len()` writable doubles at `p`; `src` is library-owned
    // memory, so the two ranges do not overlap.
    unsafe {
        match src.len() {
            1 => copy(src.as_ptr(), p, 1),
            2 => copy(src.as_ptr(), p, 2),
            3 => copy(src.as_ptr(), p, 3),
            4 => copy(src.as_ptr(), p, 4),
            n => copy(src.as_ptr(), p, n),
        }
    }
}

// ---- opaque handles (`bingham_filter *` and future ones) ---------------------------------------
//
// A handle is a `Box<T>` turned into a raw pointer for C: created by `*_new(…, T **out)` with
// [`write_handle`], borrowed by every other function with [`handle`] / [`handle_mut`], released by
// `*_free` with [`free_handle`] (NULL is a no-op). The handle functions validate like all others.

/// Borrows a handle passed as `const T *`.
///
/// # Safety
/// `p` must be NULL or a pointer obtained from [`write_handle`] and not yet freed, not mutated
/// concurrently (the header's "one handle per thread at a time").
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) unsafe fn handle<'a, T>(name: &str, p: *const T) -> FfiResult<&'a T> {
    need(name, p)?;
    // SAFETY: non-NULL, aligned, and per the contract a live Box<T> allocation.
    Ok(unsafe { &*p })
}

/// Borrows a handle passed as `T *` for modification.
///
/// # Safety
/// As for [`handle`], and no other reference to the handle may exist during the call.
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) unsafe fn handle_mut<'a, T>(name: &str, p: *mut T) -> FfiResult<&'a mut T> {
    need(name, p)?;
    // SAFETY: non-NULL, aligned, a live Box<T> allocation used by this call only (contract).
    Ok(unsafe { &mut *p })
}

/// Moves `value` to the heap and stores the new handle in `*out` (call last, after every check).
///
/// # Safety
/// `out` must be non-NULL (checked with [`need`] before) and point to a writable `T *`.
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) unsafe fn write_handle<T>(out: *mut *mut T, value: T) {
    // SAFETY: the caller checked `out`; the Box is released by `free_handle`.
    unsafe { *out = Box::into_raw(Box::new(value)) };
}

/// Releases a handle; NULL is a no-op.
///
/// # Safety
/// `p` must be NULL or a pointer from [`write_handle`] that has not been freed yet.
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) unsafe fn free_handle<T>(p: *mut T) {
    if !p.is_null() {
        // SAFETY: per the contract, p came from Box::into_raw and is freed exactly once.
        drop(unsafe { Box::from_raw(p) });
    }
}

/// Copies the calling thread's last error message into a caller buffer.
///
/// The message describes the most recent call **on this thread** that returned a status other
/// than `BINGHAM_OK`, e.g. `"bingham_pdf: x row 2: invalid argument: not a unit vector …"`
/// (UTF-8, no trailing newline). Successful calls do not clear it (like `errno`), so read it
/// right after the failing call. If no call has failed yet on this thread, the message is the
/// empty string. This function never changes the stored message. Each thread has its own
/// message; no locking is involved.
///
/// **The cause is not lost.** If calls failed since the message was last read (a read is a
/// call with `len > 0`), the message is the newest one followed by
/// `" [the first error since the message was last read: <its message>]"` — e.g. a failed
/// `bingham_ahrs_new` that went unchecked, then the next call's "`a` is NULL": the message
/// names both. Reading resets this: the next failure's message stands alone.
///
/// - `out_len` (may be `NULL`): receives the full length of the message in bytes, without the
///   terminating NUL, whether or not it fits.
/// - `buf`, `len`: when `len > 0`, at most `len - 1` bytes of the message are copied to `buf`
///   (cut at a UTF-8 character boundary, so the copy may be shorter) and a NUL is always
///   written after them. When `len == 0`, nothing is written and `buf` may be `NULL`: use this
///   to query the length, then call again with a buffer of `*out_len + 1` bytes.
/// - The message was truncated if and only if `*out_len >= len`.
///
/// Returns `BINGHAM_OK`, or `BINGHAM_ERR_NULL_ARGUMENT` if `buf` is `NULL` while `len > 0`
/// (nothing written).
///
/// # Safety
/// `buf` must be `NULL` or point to `len` writable bytes; `out_len` must be `NULL` or point to a
/// writable `size_t`.
#[no_mangle]
pub unsafe extern "C" fn bingham_last_error_message(
    buf: *mut c_char,
    len: usize,
    out_len: *mut usize,
) -> bingham_status {
    let result = catch_unwind(AssertUnwindSafe(|| {
        if len > 0 && buf.is_null() {
            return bingham_status::BINGHAM_ERR_NULL_ARGUMENT;
        }
        if !out_len.is_null() && (out_len as usize) % std::mem::align_of::<usize>() != 0 {
            return bingham_status::BINGHAM_ERR_NULL_ARGUMENT;
        }
        let copy = |message: &str| {
            if len > 0 {
                let mut n = message.len().min(len - 1);
                while !message.is_char_boundary(n) {
                    n -= 1;
                }
                // SAFETY: buf is non-NULL (checked) and has `len` writable bytes (caller
                // contract); we write n + 1 <= len bytes from library-owned memory.
                unsafe {
                    std::ptr::copy_nonoverlapping(message.as_ptr(), buf.cast::<u8>(), n);
                    *buf.add(n) = 0;
                }
            }
            if !out_len.is_null() {
                // SAFETY: out_len is non-NULL and aligned (checked) and writable (contract).
                unsafe { *out_len = message.len() };
            }
        };
        let read = LAST_ERROR.try_with(|slot| match slot.try_borrow_mut() {
            Ok(mut s) => {
                copy(&s.message);
                if len > 0 {
                    s.first_unread = None;
                }
            }
            Err(_) => copy(""),
        });
        if read.is_err() {
            copy("");
        }
        bingham_status::BINGHAM_OK
    }));
    result.unwrap_or(bingham_status::BINGHAM_ERR_PANIC)
}

#[cfg(test)]
mod tests {
    use super::*;
    use bingham_status::*;

    fn last() -> String {
        let mut n = 0usize;
        // SAFETY: len == 0 with a NULL buffer is the documented length query.
        let st = unsafe { bingham_last_error_message(std::ptr::null_mut(), 0, &mut n) };
        assert_eq!(st, BINGHAM_OK);
        let mut buf = vec![0 as c_char; n + 1];
        let mut n2 = 0usize;
        // SAFETY: buf has n + 1 writable bytes.
        let st = unsafe { bingham_last_error_message(buf.as_mut_ptr(), buf.len(), &mut n2) };
        assert_eq!(st, BINGHAM_OK);
        assert_eq!(n, n2);
        let bytes: Vec<u8> = buf[..n].iter().map(|&c| c as u8).collect();
        assert_eq!(buf[n], 0);
        String::from_utf8(bytes).unwrap()
    }

    #[test]
    fn panic_is_caught_and_reported() {
        let prev = std::panic::take_hook();
        std::panic::set_hook(Box::new(|_| {}));
        let st = guard("bingham_test", || panic!("boom {}", 42));
        let st2 = guard("bingham_test2", || -> FfiResult<()> {
            std::panic::panic_any(7u8)
        });
        std::panic::set_hook(prev);
        assert_eq!(st2, BINGHAM_ERR_PANIC);
        // two failures without a read in between: the newest, then the first
        assert_eq!(
            last(),
            "bingham_test2: internal error (panic): (no message) [the first error since the \
             message was last read: bingham_test: internal error (panic): boom 42]"
        );
        assert_eq!(st, BINGHAM_ERR_PANIC);
        let st = guard("bingham_test", || {
            std::panic::resume_unwind(Box::new("static boom"))
        });
        assert_eq!(st, BINGHAM_ERR_PANIC);
        assert_eq!(last(), "bingham_test: internal error (panic): static boom");
    }

    #[test]
    fn errors_are_stored_per_thread_and_not_cleared_by_success() {
        std::thread::spawn(|| assert_eq!(last(), ""))
            .join()
            .unwrap();
        let st = guard("bingham_f", || Err(Failure::argument("bad x")));
        assert_eq!(st, BINGHAM_ERR_INVALID_ARGUMENT);
        assert_eq!(last(), "bingham_f: bad x");
        assert_eq!(guard("bingham_g", || Ok(())), BINGHAM_OK);
        assert_eq!(last(), "bingham_f: bad x");
        std::thread::spawn(|| assert_eq!(last(), ""))
            .join()
            .unwrap();
        let st = guard("bingham_h", || {
            Err(Error::NotConverged("slow".into()).into())
        });
        assert_eq!(st, BINGHAM_ERR_NOT_CONVERGED);
        assert_eq!(last(), "bingham_h: not converged: slow");
    }

    #[test]
    fn the_first_unread_error_is_kept_with_the_newest() {
        let _ = guard("bingham_new", || {
            Err(Failure::argument("`gyro_noise` must be > 0"))
        });
        let _ = guard("bingham_use", || Err(Failure::null("a")));
        let _ = guard("bingham_use", || Err(Failure::null("b")));
        // the length query does not count as a read
        let mut n = 0usize;
        // SAFETY: len == 0 with a NULL buffer is the documented length query.
        let st = unsafe { bingham_last_error_message(std::ptr::null_mut(), 0, &mut n) };
        assert_eq!(st, BINGHAM_OK);
        let m = last();
        assert_eq!(m.len(), n);
        assert_eq!(
            m,
            "bingham_use: `b` is NULL [the first error since the message was last read: \
             bingham_new: `gyro_noise` must be > 0]"
        );
        // read: the next failure stands alone
        let _ = guard("bingham_use", || Err(Failure::null("c")));
        assert_eq!(last(), "bingham_use: `c` is NULL");
        assert_eq!(
            last(),
            "bingham_use: `c` is NULL",
            "reading never changes it"
        );
    }

    #[test]
    fn truncation_and_null_handling() {
        let _ = guard("bingham_é", || Err(Failure::argument("αβγ")));
        let full = last();
        assert_eq!(full, "bingham_é: αβγ");
        let mut n = 0usize;
        let mut buf = [1 as c_char; 64];
        for len in 1..=full.len() + 2 {
            buf.fill(1);
            // SAFETY: buf has 64 >= len writable bytes.
            let st = unsafe { bingham_last_error_message(buf.as_mut_ptr(), len, &mut n) };
            assert_eq!(st, BINGHAM_OK);
            assert_eq!(n, full.len());
            let got: Vec<u8> = buf
                .iter()
                .take_while(|&&c| c != 0)
                .map(|&c| c as u8)
                .collect();
            assert!(got.len() < len);
            let got = String::from_utf8(got).expect("cut at a char boundary");
            assert!(full.starts_with(&got));
            assert!(got.len() + 4 > len.min(full.len() + 1) - 1);
            assert_eq!(buf[len], 1, "nothing written past len");
        }
        // SAFETY: NULL buffer with len > 0 is refused without writing.
        let st = unsafe { bingham_last_error_message(std::ptr::null_mut(), 4, &mut n) };
        assert_eq!(st, BINGHAM_ERR_NULL_ARGUMENT);
        // SAFETY: out_len may be NULL.
        let st = unsafe { bingham_last_error_message(buf.as_mut_ptr(), 64, std::ptr::null_mut()) };
        assert_eq!(st, BINGHAM_OK);
        assert_eq!(last(), full, "querying never changes the message");
    }

    #[test]
    fn handles() {
        let mut out: *mut Vec<f64> = std::ptr::null_mut();
        // SAFETY: `out` is a valid `*mut *mut Vec<f64>`; the handle is freed once below.
        unsafe {
            write_handle(&mut out, vec![1.0, 2.0]);
            assert_eq!(handle("f", out).unwrap(), &vec![1.0, 2.0]);
            handle_mut("f", out).unwrap().push(3.0);
            assert_eq!(handle("f", out as *const Vec<f64>).unwrap().len(), 3);
            let e = handle::<Vec<f64>>("filter", std::ptr::null()).unwrap_err();
            assert_eq!(e.status, BINGHAM_ERR_NULL_ARGUMENT);
            assert_eq!(e.message, "`filter` is NULL");
            assert!(handle_mut::<Vec<f64>>("f", std::ptr::null_mut()).is_err());
            free_handle(out);
            free_handle::<Vec<f64>>(std::ptr::null_mut());
        }
    }

    #[test]
    fn helpers() {
        assert_eq!(dim(1).unwrap_err().status, BINGHAM_ERR_INVALID_DIMENSION);
        assert!(dim(2).is_ok() && dim(64).is_ok());
        assert_eq!(dim(65).unwrap_err().status, BINGHAM_ERR_INVALID_DIMENSION);
        assert_eq!(
            len2("x", usize::MAX, 2).unwrap_err().status,
            BINGHAM_ERR_INVALID_DIMENSION
        );
        assert_eq!(len2("x", 3, 4).unwrap(), 12);
        assert_eq!(
            need::<f64>("p", std::ptr::null()).unwrap_err().status,
            BINGHAM_ERR_NULL_ARGUMENT
        );
        let v = [1.0f64, 2.0];
        let misaligned = (v.as_ptr() as *const u8).wrapping_add(1) as *const f64;
        assert_eq!(
            need("p", misaligned).unwrap_err().status,
            BINGHAM_ERR_NULL_ARGUMENT
        );
        // SAFETY: v has 2 readable doubles; len 0 never reads.
        unsafe {
            assert_eq!(read("v", v.as_ptr(), 2).unwrap(), &v);
            assert!(read("v", std::ptr::null(), 0).unwrap().is_empty());
            let w = [1.0, f64::NAN];
            let e = read("w", w.as_ptr(), 2).unwrap_err();
            assert_eq!(e.status, BINGHAM_ERR_INVALID_ARGUMENT);
            assert_eq!(e.message, "`w[1]` = NaN is not finite");
        }
    }
}
