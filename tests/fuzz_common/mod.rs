//! Shared helpers of the reliability tests (`tests/fuzz_ffi.rs`, `tests/threads.rs`,
//! `tests/long_run.rs`): a deterministic PRNG, generators of valid and hostile inputs,
//! sentinel-guarded buffers, invariant checks, the last error message, and a crash reporter that
//! names the case that was running when a signal (SIGSEGV, SIGABRT, …) killed the process.
#![allow(dead_code)]

use std::os::raw::c_char;
use std::sync::atomic::{AtomicU64, Ordering};

use bingham::ffi::{bingham_last_error_message, bingham_mode, bingham_status};

// ---- PRNG -------------------------------------------------------------------------------------

/// SplitMix64 (Steele, Lea & Flood 2014): tiny, fast, and the same sequence on every platform,
/// so a printed seed reproduces a case exactly.
#[derive(Clone, Debug)]
pub struct Rng(u64);

/// One SplitMix64 output step, also used to derive independent per-case seeds.
pub fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Uniform integer in 0..n (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        ((self.next_u64() as u128 * n as u128) >> 64) as usize
    }

    pub fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }

    /// Standard normal (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.unit();
        let u2 = self.unit();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// `10^U(lo, hi)`.
    pub fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        10f64.powf(self.range(lo, hi))
    }

    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

// ---- values -----------------------------------------------------------------------------------

/// A non-finite value: NaNs with various payloads and signs, ±Inf.
pub fn non_finite(rng: &mut Rng) -> f64 {
    match rng.below(6) {
        0 => f64::NAN,
        1 => -f64::NAN,
        2 => f64::INFINITY,
        3 => f64::NEG_INFINITY,
        // signalling NaN, random payload
        4 => f64::from_bits(0x7FF0_0000_0000_0000 | (rng.next_u64() & 0x0007_FFFF_FFFF_FFFF) | 1),
        _ => f64::from_bits(0xFFF8_0000_0000_0000 | (rng.next_u64() & 0x0007_FFFF_FFFF_FFFF)),
    }
}

/// A finite but extreme value: ±0, subnormals, the smallest normal, huge magnitudes, random
/// finite bit patterns.
pub fn extreme(rng: &mut Rng) -> f64 {
    let sign = if rng.chance(0.5) { -1.0 } else { 1.0 };
    sign * match rng.below(8) {
        0 => 0.0,
        1 => f64::from_bits(1 + rng.next_u64() % ((1u64 << 52) - 1)), // subnormal
        2 => f64::MIN_POSITIVE,
        3 => f64::MAX,
        4 => rng.log_uniform(100.0, 308.0),
        5 => rng.log_uniform(-308.0, -100.0),
        6 => 5e-324,
        _ => loop {
            let v = f64::from_bits(rng.next_u64() & 0x7FFF_FFFF_FFFF_FFFF);
            if v.is_finite() {
                break v;
            }
        },
    }
}

/// A concentration as a caller might pass it (any sign and shift): mostly realistic values
/// (|z| up to 1e7 and a few beyond), sometimes extreme finite values.
pub fn concentration(rng: &mut Rng) -> f64 {
    match rng.below(20) {
        0 => 0.0,
        1 => -rng.unit(),
        2..=9 => -rng.log_uniform(-3.0, 3.0),
        10..=13 => -rng.log_uniform(3.0, 7.0),
        14 => -rng.log_uniform(7.0, 13.0),
        15 => rng.log_uniform(-3.0, 2.5), // positive (the shift is arbitrary)
        16 => rng.range(-5.0, 5.0),
        17 => -rng.log_uniform(-310.0, -3.0), // tiny, down to subnormal
        18 => -1e6,
        _ => extreme(rng),
    }
}

/// A concentration vector of length `d` with realistic structure: sometimes repeated entries,
/// sometimes all equal (uniform), sometimes one huge spread.
pub fn z_vector(rng: &mut Rng, d: usize) -> Vec<f64> {
    let mut z: Vec<f64> = (0..d).map(|_| concentration(rng)).collect();
    match rng.below(10) {
        0 => {
            // repeated values
            let v = z[0];
            for x in z.iter_mut() {
                if rng.chance(0.5) {
                    *x = v;
                }
            }
        }
        1 => {
            let v = z[0];
            z.iter_mut().for_each(|x| *x = v);
        }
        2 => {
            // moderate values only (the bread and butter)
            for x in z.iter_mut() {
                *x = -rng.log_uniform(-2.0, 2.5);
            }
        }
        3 => {
            // shifted by a large constant
            let c = rng.range(-1e3, 1e3);
            z.iter_mut().for_each(|x| *x += c);
        }
        _ => {}
    }
    z
}

/// Concentrations within the documented exact range: |z_i| ≤ 1e6 after the shift.
pub fn z_moderate(rng: &mut Rng, d: usize) -> Vec<f64> {
    (0..d)
        .map(|_| match rng.below(4) {
            0 => -rng.log_uniform(-3.0, 6.0),
            1 => -rng.log_uniform(-1.0, 2.0),
            2 => -rng.unit(),
            _ => 0.0,
        })
        .collect()
}

// ---- matrices and vectors (row-major) ---------------------------------------------------------

pub fn identity(d: usize) -> Vec<f64> {
    let mut m = vec![0.0; d * d];
    for i in 0..d {
        m[i * d + i] = 1.0;
    }
    m
}

pub fn unit_vector(rng: &mut Rng, d: usize) -> Vec<f64> {
    loop {
        let v: Vec<f64> = (0..d).map(|_| rng.normal()).collect();
        let n = norm(&v);
        if n > 1e-3 {
            return v.iter().map(|x| x / n).collect();
        }
    }
}

pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Applies the Householder reflection `I − 2 v vᵀ` (v unit) from the left to the row-major `m`.
fn reflect_left(m: &mut [f64], d: usize, v: &[f64]) {
    for c in 0..d {
        let dot: f64 = (0..d).map(|r| v[r] * m[r * d + c]).sum();
        for r in 0..d {
            m[r * d + c] -= 2.0 * v[r] * dot;
        }
    }
}

/// A random orthogonal matrix: a signed permutation times up to three Householder reflections
/// (orthonormal to rounding; not Haar-distributed, which does not matter here).
pub fn orthogonal(rng: &mut Rng, d: usize) -> Vec<f64> {
    let mut m = vec![0.0; d * d];
    let mut perm: Vec<usize> = (0..d).collect();
    for i in (1..d).rev() {
        perm.swap(i, rng.below(i + 1));
    }
    for (r, &c) in perm.iter().enumerate() {
        m[r * d + c] = if rng.chance(0.5) { 1.0 } else { -1.0 };
    }
    if rng.chance(0.1) {
        return m; // signed permutation: exactly orthogonal
    }
    for _ in 0..(1 + rng.below(3)) {
        let v = unit_vector(rng, d);
        reflect_left(&mut m, d, &v);
    }
    m
}

/// `M diag(w) Mᵀ` (row-major, exactly symmetric).
pub fn congruence(m: &[f64], w: &[f64], d: usize) -> Vec<f64> {
    let mut s = vec![0.0; d * d];
    for r in 0..d {
        for c in r..d {
            let v: f64 = (0..d).map(|k| m[r * d + k] * w[k] * m[c * d + k]).sum();
            s[r * d + c] = v;
            s[c * d + r] = v;
        }
    }
    s
}

/// max |MᵀM − I| for a row-major d×d matrix.
pub fn orthogonality_error(m: &[f64], d: usize) -> f64 {
    let mut worst = 0.0f64;
    for a in 0..d {
        for b in a..d {
            let v: f64 = (0..d).map(|r| m[r * d + a] * m[r * d + b]).sum();
            let target = if a == b { 1.0 } else { 0.0 };
            let e = (v - target).abs();
            if e.is_nan() {
                return f64::NAN;
            }
            worst = worst.max(e);
        }
    }
    worst
}

// ---- invariants -------------------------------------------------------------------------------

/// Tolerance of the "valid Bingham state" checks: orthonormality of M, Σω = 1.
pub const STATE_TOL: f64 = 1e-12;

/// A normalized Bingham parameter pair: finite, M orthonormal to 1e-12, z ascending with
/// z[d−1] = 0 exactly.
pub fn check_state(m: &[f64], z: &[f64], d: usize) -> Result<(), String> {
    if m.len() != d * d || z.len() != d {
        return Err(format!(
            "state lengths {} / {} for d = {d}",
            m.len(),
            z.len()
        ));
    }
    if let Some(i) = m.iter().position(|v| !v.is_finite()) {
        return Err(format!("M[{i}] = {} is not finite", m[i]));
    }
    if let Some(i) = z.iter().position(|v| !v.is_finite()) {
        return Err(format!("z[{i}] = {} is not finite", z[i]));
    }
    let e = orthogonality_error(m, d);
    if e.is_nan() || e > STATE_TOL {
        return Err(format!("M is not orthonormal: max|MᵀM − I| = {e:e}"));
    }
    if let Some(i) = (1..d).find(|&i| z[i - 1] > z[i]) {
        return Err(format!("z not ascending at {i}: {z:?}"));
    }
    if z[d - 1] != 0.0 {
        return Err(format!("z[d−1] = {} ≠ 0", z[d - 1]));
    }
    Ok(())
}

/// Probabilities ω: finite, ≥ 0, Σ = 1 within `STATE_TOL`.
pub fn check_omega(w: &[f64]) -> Result<(), String> {
    check_omega_tol(w, STATE_TOL)
}

/// Probabilities ω: finite, ≥ 0, Σ = 1 within `tol`.
pub fn check_omega_tol(w: &[f64], tol: f64) -> Result<(), String> {
    if let Some(i) = w.iter().position(|v| !v.is_finite() || *v < 0.0) {
        return Err(format!("ω[{i}] = {} is not a probability", w[i]));
    }
    let s: f64 = w.iter().sum();
    if (s - 1.0).abs() > tol {
        return Err(format!("Σω = 1 + {:e}", s - 1.0));
    }
    Ok(())
}

/// A unit vector to `tol`.
pub fn check_unit(v: &[f64], tol: f64) -> Result<(), String> {
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(format!("entry {i} = {} is not finite", v[i]));
    }
    let n = norm(v);
    if (n - 1.0).abs() > tol {
        return Err(format!("norm 1 + {:e}", n - 1.0));
    }
    Ok(())
}

// ---- sentinel-guarded buffers -----------------------------------------------------------------

/// Words of guard before and after each buffer: 4, or 0 with `BINGHAM_FUZZ_EXACT_BUFFERS=1`
/// (then every buffer is allocated with exactly its length, so that valgrind flags any access
/// beyond it; the guard-word checks are then vacuous).
pub fn guard_words() -> usize {
    static G: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *G.get_or_init(|| {
        if std::env::var_os("BINGHAM_FUZZ_EXACT_BUFFERS").is_some_and(|v| v != "0") {
            0
        } else {
            4
        }
    })
}

/// The fill pattern: a signalling NaN whose payload encodes the index, so a left-over sentinel
/// is never a valid (finite) output and shuffled words are noticed.
pub fn sentinel(i: usize) -> u64 {
    0x7FF4_DEAD_0000_0000 | (i as u64 & 0xFFFF_FFFF)
}

/// A caller buffer of `len` doubles with guard words on both sides (and one spare word, so a
/// deliberately misaligned pointer still points into owned memory).
pub struct Buf {
    words: Vec<u64>,
    guard: usize,
    pub len: usize,
}

impl Buf {
    /// Filled with the sentinel pattern (an output).
    pub fn sentinel(len: usize) -> Buf {
        let guard = guard_words();
        let spare = usize::from(guard > 0);
        let words = (0..len + 2 * guard + spare).map(sentinel).collect();
        Buf { words, guard, len }
    }

    /// Holding `data` (an input), guards filled with the sentinel pattern.
    pub fn from(data: &[f64]) -> Buf {
        let mut b = Buf::sentinel(data.len());
        let g = b.guard;
        for (w, v) in b.words[g..].iter_mut().zip(data) {
            *w = v.to_bits();
        }
        b
    }

    pub fn ptr(&mut self) -> *mut f64 {
        // SAFETY: guard <= words.len() (one past the end at most, for an empty exact buffer).
        unsafe { self.words.as_mut_ptr().add(self.guard).cast::<f64>() }
    }

    /// A pointer `offset` bytes (1..8) past the start: not aligned for `double`. Within the
    /// allocation when it holds at least one word; never dereferenced by a correct library.
    pub fn misaligned(&mut self, offset: usize) -> *mut f64 {
        self.ptr().cast::<u8>().wrapping_add(offset).cast::<f64>()
    }

    pub fn values(&self) -> Vec<f64> {
        self.words[self.guard..self.guard + self.len]
            .iter()
            .map(|&w| f64::from_bits(w))
            .collect()
    }

    pub fn bits(&self) -> Vec<u64> {
        self.words.clone()
    }

    /// The guard words are intact.
    pub fn guards_ok(&self) -> bool {
        let n = self.words.len();
        (0..self.guard)
            .chain(self.guard + self.len..n)
            .all(|i| self.words[i] == sentinel(i))
    }

    /// Every word (guards and body) still holds the sentinel pattern.
    pub fn untouched(&self) -> bool {
        self.words
            .iter()
            .enumerate()
            .all(|(i, &w)| w == sentinel(i))
    }

    /// Body words `from..to` still hold their sentinel pattern (not written).
    pub fn untouched_range(&self, from: usize, to: usize) -> bool {
        (self.guard + from..self.guard + to).all(|i| self.words[i] == sentinel(i))
    }

    /// No body word holds its sentinel any more (everything was written).
    pub fn fully_written(&self) -> bool {
        (self.guard..self.guard + self.len).all(|i| self.words[i] != sentinel(i))
    }
}

/// A non-NULL, aligned pointer to unmapped memory (address 8): any access crashes. Passed for
/// arrays that must not be touched (e.g. when `d` is invalid).
pub fn dangling() -> *mut f64 {
    std::ptr::NonNull::<f64>::dangling().as_ptr()
}

// ---- last error -------------------------------------------------------------------------------

/// This thread's last error message.
pub fn last_error() -> String {
    let mut n = 0usize;
    // SAFETY: len 0 with NULL buffer is the documented length query.
    unsafe { bingham_last_error_message(std::ptr::null_mut(), 0, &mut n) };
    let mut buf = vec![0 as c_char; n + 1];
    // SAFETY: buf has n + 1 writable bytes.
    unsafe { bingham_last_error_message(buf.as_mut_ptr(), buf.len(), std::ptr::null_mut()) };
    let bytes: Vec<u8> = buf[..n].iter().map(|&c| c as u8).collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

/// Sets this thread's last error to a known message (from a deliberately failing call) so that
/// a later check can tell whether a failing call replaced it. Returns the message.
pub fn prime_last_error(avoid: &str) -> &'static str {
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
pub fn check_error_message(name: &str) -> Result<(), String> {
    let msg = last_error();
    let prefix = format!("{name}: ");
    if !msg.starts_with(&prefix) || msg.len() <= prefix.len() + 3 {
        return Err(format!(
            "last error message {msg:?} does not describe a failing {name}"
        ));
    }
    Ok(())
}

pub fn status_name(s: bingham_status) -> &'static str {
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
pub fn status_code(s: bingham_status) -> i32 {
    // SAFETY: bingham_status is a fieldless repr(C) enum: reading its bits as an int is fine.
    unsafe { std::mem::transmute::<bingham_status, i32>(s) }
}

// ---- crash reporter ---------------------------------------------------------------------------

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

// ---- configuration ----------------------------------------------------------------------------

/// An environment variable parsed as a number (accepts `1e7`, `10000000`, `1_000_000`).
pub fn env_count(name: &str, default: u64) -> u64 {
    match std::env::var(name) {
        Ok(s) => {
            let s = s.replace('_', "");
            s.parse::<u64>()
                .ok()
                .or_else(|| s.parse::<f64>().ok().map(|v| v as u64))
                .unwrap_or_else(|| panic!("{name}={s:?} is not a number"))
        }
        Err(_) => default,
    }
}
