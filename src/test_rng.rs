//! A tiny deterministic generator for the unit tests (xorshift64; uniform in [−½, ½)).

/// Uniform draws in `[−½, ½)` from the xorshift64 sequence started at `seed` (non-zero).
pub(crate) fn xorshift(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}
