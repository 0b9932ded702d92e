//! The pieces of `[0, 128)` the Bessel fits are made of: the coefficient layout of a piece
//! ([`Piece`], [`Poly`]; the tables in `tables` are made of them) and the piece that holds an
//! argument ([`piece_index`]).

/// Number of coefficients of each piece's divided-difference polynomial (degree 9, the degree
/// the Estrin evaluations are written for; `NT` in `scripts/bessel_reference.py`, which writes
/// `tables`: a table of another length does not compile).
pub(super) const NT: usize = 10;

/// Coefficients of one function on one piece: `f(c + t) = hi + (lo + t·g(t))`, `g(t) = Σ q[k] t^k`.
#[derive(Clone, Copy)]
pub(super) struct Poly {
    pub(super) hi: f64,
    pub(super) lo: f64,
    pub(super) q: [f64; NT],
}

/// Two values evaluated together by the same sequence of operations.
pub(super) type Lanes = [f64; 2];

/// One piece of `[0, 128)`: midpoint `c` and, as lane pairs `[i1, d]`, the coefficients of
/// `e^{-x} I1(x)` (on the first piece `e^{-x} I1(x) / x`) and of `e^{-x} (I0(x) − I1(x))`:
/// `f(c + t) = hi + (lo + t·Σ q[k] t^k)` in each lane.
#[derive(Clone, Copy)]
#[repr(C, align(16))]
pub(super) struct Piece {
    pub(super) q: [Lanes; NT],
    pub(super) hi: Lanes,
    pub(super) lo: Lanes,
    pub(super) c: f64,
}

/// Index of a piece containing `x`, `0 ≤ x < 128` (branch-free; no float-to-int conversion).
///
/// `[0, 8)`: 32 pieces of width 1/4; `x + 8 ∈ [8, 16)` has the piece number in its top five
/// mantissa bits. Where `x + 8` rounds up across a boundary the next piece is chosen, whose
/// polynomial is then used at most half an ulp of 8 outside its interval — harmless (this includes
/// `x` just below 8, where `x + 8` may round to 16 and select piece 32, the first one of `[8, 8.5)`).
/// `[8, 128)`: 16 pieces per octave, numbered by the biased exponent (1026..=1029) and the top four
/// mantissa bits of `x` itself.
#[inline(always)]
pub(super) fn piece_index(x: f64) -> usize {
    let small = (((x + 8.0).to_bits() >> 47) as usize).wrapping_sub(1026 << 5);
    let large = ((x.to_bits() >> 48) as usize).wrapping_sub((1026 << 4) - 32);
    if x < 8.0 {
        small
    } else {
        large
    }
}
