//! The crash and hang reporter: each running test records the case it is in ([`CaseSlot`]); a
//! fatal signal prints the running cases before the process dies, and a watchdog aborts the
//! process (so that the reporter names the case) when a case runs too long.

use std::sync::atomic::{AtomicU64, Ordering};

use super::env_count;

/// Slots naming the case each running test is in: `[label id + 1, case seed]` pairs.
const SLOTS: usize = 32;
static RUNNING: [AtomicU64; 2 * SLOTS] = [const { AtomicU64::new(0) }; 2 * SLOTS];
static LABELS: std::sync::Mutex<Vec<&'static str>> = std::sync::Mutex::new(Vec::new());
/// Copies of the labels readable from a signal handler (pointer, length), set once per label.
static LABEL_PTRS: [AtomicU64; 2 * SLOTS] = [const { AtomicU64::new(0) }; 2 * SLOTS];

/// When each slot's current case started (milliseconds since `epoch()`), for the watchdog.
static STARTED_MS: [AtomicU64; SLOTS] = [const { AtomicU64::new(0) }; SLOTS];

fn epoch() -> std::time::Instant {
    static EPOCH: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
    *EPOCH.get_or_init(std::time::Instant::now)
}

fn now_ms() -> u64 {
    epoch().elapsed().as_millis() as u64
}

/// Seconds a single case may run before the watchdog declares a hang and aborts the process
/// (printing the case): `BINGHAM_FUZZ_TIMEOUT`, default 120 (generous: the machine may be busy).
pub fn case_timeout_s() -> u64 {
    env_count("BINGHAM_FUZZ_TIMEOUT", 120)
}

/// Starts (once) a thread that aborts the process when a case runs longer than
/// [`case_timeout_s`]: a hang is a failure like a crash, and the abort makes the crash reporter
/// name the case.
fn start_watchdog() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = epoch();
        std::thread::spawn(|| loop {
            std::thread::sleep(std::time::Duration::from_millis(500));
            let limit = case_timeout_s() * 1000;
            for s in 0..SLOTS {
                if RUNNING[2 * s].load(Ordering::Acquire) == 0 {
                    continue;
                }
                let t0 = STARTED_MS[s].load(Ordering::Relaxed);
                if now_ms().saturating_sub(t0) > limit {
                    write_fd2(b"\n*** watchdog: a case has been running for more than ");
                    write_u64(limit / 1000);
                    write_fd2(b" s (BINGHAM_FUZZ_TIMEOUT): treating it as a hang\n");
                    std::process::abort();
                }
            }
        });
    });
}

/// The crash reporter's record of what one test is doing; cheap to update per case.
pub struct CaseSlot {
    slot: usize,
}

impl CaseSlot {
    /// Claims a slot for the test labelled `label`.
    pub fn new(label: &'static str) -> CaseSlot {
        install_crash_reporter();
        start_watchdog();
        let mut labels = LABELS.lock().unwrap();
        let id = labels.len();
        assert!(id < SLOTS, "too many case slots");
        labels.push(label);
        LABEL_PTRS[2 * id].store(label.as_ptr() as u64, Ordering::SeqCst);
        LABEL_PTRS[2 * id + 1].store(label.len() as u64, Ordering::SeqCst);
        CaseSlot { slot: id }
    }

    /// Marks `seed` as the case now running.
    pub fn enter(&self, seed: u64) {
        STARTED_MS[self.slot].store(now_ms(), Ordering::Relaxed);
        RUNNING[2 * self.slot + 1].store(seed, Ordering::Relaxed);
        RUNNING[2 * self.slot].store(self.slot as u64 + 1, Ordering::Release);
    }

    pub fn leave(&self) {
        RUNNING[2 * self.slot].store(0, Ordering::Release);
    }
}

fn write_fd2(bytes: &[u8]) {
    // SAFETY: write(2) is async-signal-safe; the buffer is valid.
    unsafe {
        libc::write(2, bytes.as_ptr().cast(), bytes.len());
    }
}

fn write_u64(mut v: u64) {
    let mut buf = [0u8; 20];
    let mut i = buf.len();
    loop {
        i -= 1;
        buf[i] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 {
            break;
        }
    }
    write_fd2(&buf[i..]);
}

extern "C" fn on_fatal_signal(sig: libc::c_int) {
    write_fd2(b"\n*** fatal signal ");
    write_u64(sig as u64);
    write_fd2(b" while running:\n");
    for s in 0..SLOTS {
        let id = RUNNING[2 * s].load(Ordering::Acquire);
        if id == 0 {
            continue;
        }
        let ptr = LABEL_PTRS[2 * s].load(Ordering::SeqCst) as *const u8;
        let len = LABEL_PTRS[2 * s + 1].load(Ordering::SeqCst) as usize;
        write_fd2(b"    ");
        if !ptr.is_null() {
            // SAFETY: a &'static str stored by CaseSlot::new.
            write_fd2(unsafe { std::slice::from_raw_parts(ptr, len) });
        }
        write_fd2(b" case seed ");
        write_u64(RUNNING[2 * s + 1].load(Ordering::Relaxed));
        write_fd2(b"\n");
    }
    write_fd2(b"    (reproduce with BINGHAM_FUZZ_REPRO=<label>:<seed>)\n");
    // SAFETY: restore the default action and re-raise: the process dies with the same signal.
    unsafe {
        libc::signal(sig, libc::SIG_DFL);
        libc::raise(sig);
    }
}

/// Installs (once) handlers for SIGSEGV, SIGBUS, SIGILL, SIGFPE and SIGABRT that print the
/// running cases before the process dies.
pub fn install_crash_reporter() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        for sig in [
            libc::SIGSEGV,
            libc::SIGBUS,
            libc::SIGILL,
            libc::SIGFPE,
            libc::SIGABRT,
        ] {
            // SAFETY: installing a handler that only calls async-signal-safe functions; an
            // alternate stack is not needed for the faults we expect (not stack overflows).
            unsafe {
                let mut sa: libc::sigaction = std::mem::zeroed();
                sa.sa_sigaction = on_fatal_signal as *const () as usize;
                libc::sigemptyset(&mut sa.sa_mask);
                sa.sa_flags = libc::SA_NODEFER | libc::SA_RESETHAND;
                libc::sigaction(sig, &sa, std::ptr::null_mut());
            }
        }
    });
}
