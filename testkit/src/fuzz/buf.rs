//! Sentinel-guarded caller buffers: every word not written holds a signalling NaN that encodes
//! its index, with guard words on both sides.

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
