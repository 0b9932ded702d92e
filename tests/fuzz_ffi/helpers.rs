//! The small helpers: `bingham_status_str`, `bingham_last_error_message` and `bingham_version`
//! (the crate's version, the same static string at every call, the last error left alone).

use bingham::ffi::bingham_status::*;
use bingham::ffi::*;
use testkit::fuzz::{identity, CaseSlot};
use testkit::{mix, Rng64};

use crate::drivers::{base_seed, cases_for, repro, SHARE_DISTRIBUTION, SHARE_FILTER};
use crate::status::last_error;

#[test]
fn fuzz_status_str_and_last_error_message() {
    let count = cases_for(1.0, 1.0, 1.0 - SHARE_DISTRIBUTION - SHARE_FILTER);
    if repro().is_some() {
        return; // reproducing a case of another test
    }
    let slot = CaseSlot::new("helpers");
    let version = bingham_version();
    assert!(!version.is_null(), "bingham_version returned NULL");
    let known: Vec<String> = (0..=7)
        .map(|c| {
            // SAFETY: any int is accepted; the result is a static C string.
            let p = bingham_status_str(c);
            assert!(!p.is_null());
            // SAFETY: NUL-terminated static string.
            unsafe { std::ffi::CStr::from_ptr(p) }
                .to_str()
                .unwrap()
                .to_string()
        })
        .collect();
    assert!(
        known.iter().all(|s| !s.is_empty() && s != "unknown status"),
        "{known:?}"
    );
    for i in 0..count {
        let seed = mix(base_seed() ^ (77 << 48) ^ i);
        slot.enter(seed);
        let mut rng = Rng64::new(seed);
        // status_str with any int
        let code = match rng.below(4) {
            0 => rng.below(10) as i32 - 2,
            1 => i32::MIN + rng.below(3) as i32,
            2 => i32::MAX - rng.below(3) as i32,
            _ => rng.next_u64() as i32,
        };
        let p = bingham_status_str(code);
        assert!(!p.is_null(), "status_str({code}) is NULL");
        // SAFETY: NUL-terminated static string.
        let s = unsafe { std::ffi::CStr::from_ptr(p) }
            .to_str()
            .expect("UTF-8");
        if (0..=7).contains(&code) {
            assert_eq!(s, known[code as usize]);
        } else {
            assert_eq!(s, "unknown status", "status_str({code})");
        }
        // a failing call with a message of varying length (the row number varies; "‖" and
        // other non-ASCII characters appear in some messages), then reads with random buffers
        let d = 2 + rng.below(4);
        let n = 1 + rng.below(300);
        let mut x = vec![0.0; n * d];
        for r in 0..n {
            x[r * d] = 1.0;
        }
        let bad = rng.below(n);
        x[bad * d] = 1.5;
        let (m, z) = (identity(d), vec![0.0; d]);
        let mut p_out = vec![0.0; n];
        // SAFETY: valid buffers.
        let st = unsafe {
            bingham_log_pdf(d, m.as_ptr(), z.as_ptr(), n, x.as_ptr(), p_out.as_mut_ptr())
        };
        assert_eq!(st, BINGHAM_ERR_INVALID_ARGUMENT);
        let full = last_error();
        assert!(full.contains(&format!("row {bad}")), "{full}");
        // bingham_version between a failure and the reading of its message
        let v = bingham_version();
        assert_eq!(v, version, "bingham_version: not the same static string");
        // SAFETY: NUL-terminated static string.
        let text = unsafe { std::ffi::CStr::from_ptr(v) }.to_str();
        assert_eq!(text, Ok(env!("CARGO_PKG_VERSION")), "bingham_version");
        assert_eq!(last_error(), full, "bingham_version changed the last error");
        let len = match rng.below(4) {
            0 => 0,
            1 => rng.below(full.len() + 3),
            2 => full.len() + rng.below(3),
            _ => 1 + rng.below(8),
        };
        let mut buf = vec![0xA5u8; len + 16];
        let mut out_len = [usize::MAX; 2];
        let buf_null = len > 0 && rng.chance(0.05);
        let len_null = rng.chance(0.2);
        let len_misaligned = !len_null && rng.chance(0.05);
        let bp = if buf_null || (len == 0 && rng.chance(0.5)) {
            std::ptr::null_mut()
        } else {
            // SAFETY: within buf.
            unsafe { buf.as_mut_ptr().add(8) }.cast::<std::os::raw::c_char>()
        };
        let lp = if len_null {
            std::ptr::null_mut()
        } else if len_misaligned {
            out_len
                .as_mut_ptr()
                .cast::<u8>()
                .wrapping_add(1)
                .cast::<usize>()
        } else {
            out_len.as_mut_ptr()
        };
        // SAFETY: bp is NULL or has len writable bytes (8 guard bytes on each side); lp NULL,
        // valid, or misaligned (refused).
        let st = unsafe { bingham_last_error_message(bp, len, lp) };
        let ctx = format!("seed {seed}: len {len}, buf NULL {buf_null}, out_len NULL {len_null}, misaligned {len_misaligned}, message {full:?}");
        assert!(
            buf[..8].iter().all(|&b| b == 0xA5) && buf[8 + len..].iter().all(|&b| b == 0xA5),
            "wrote outside the buffer: {ctx}"
        );
        assert_eq!(last_error(), full, "reading changed the message: {ctx}");
        if buf_null || len_misaligned {
            assert_eq!(st, BINGHAM_ERR_NULL_ARGUMENT, "{ctx}");
            assert!(
                buf.iter().all(|&b| b == 0xA5) && out_len == [usize::MAX; 2],
                "wrote on error: {ctx}"
            );
            continue;
        }
        assert_eq!(st, BINGHAM_OK, "{ctx}");
        if !len_null {
            assert_eq!(out_len, [full.len(), usize::MAX], "{ctx}");
        }
        if len > 0 && !bp.is_null() {
            let got = &buf[8..8 + len];
            let nul = got.iter().position(|&b| b == 0).expect("NUL-terminated");
            let s = std::str::from_utf8(&got[..nul]).expect("cut at a character boundary");
            assert!(full.starts_with(s), "{ctx}");
            assert!(nul < len, "{ctx}");
            // as long as fits, but possibly shorter to stay on a character boundary
            assert!(
                nul == full.len().min(len - 1) || (full.len() >= len && nul + 4 > len - 1),
                "{ctx}: copied {nul}"
            );
        } else {
            assert!(buf.iter().all(|&b| b == 0xA5), "{ctx}");
        }
        slot.leave();
    }
}
