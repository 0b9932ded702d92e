//! The shifted problem the contour method integrates ([`Contour`]: the distinct `λ_j` with
//! their multiplicities and the derivatives of `φ` at the saddle) and a point of its contour
//! ([`Node`]).

use super::complex::Cx;

/// A point of the contour: `w`, `s(w)` and its first three derivatives.
#[derive(Clone, Copy, Debug)]
pub(super) struct Node {
    pub(super) w: f64,
    pub(super) s: Cx,
    pub(super) ds: Cx,
    pub(super) dds: Cx,
    pub(super) d3s: Cx,
}

/// The shifted problem: distinct `λ_j = c − z_j` with multiplicities, `½ Σ m_j/λ_j ≈ 1`.
pub(super) struct Contour {
    pub(super) lam: Vec<f64>,
    pub(super) inv_lam: Vec<f64>,
    pub(super) mult: Vec<f64>,
    /// `m_j` as a count.
    pub(super) count: Vec<u32>,
    /// Whether some `m_j ≥ 2`.
    pub(super) tied: bool,
    /// `1/λ_j` of the untied values (`m_j = 1`).
    pub(super) single_il: Vec<f64>,
    /// `m_j/λ_j`.
    pub(super) mult_il: Vec<f64>,
    /// `1 − ½ Σ m_j/λ_j` (zero up to rounding), kept so that `φ'` is exact.
    pub(super) om: f64,
    /// `φ''(0) = ½ Σ m_j/λ_j²`.
    pub(super) a: f64,
    /// `φ'''(0) = −Σ m_j/λ_j³`.
    pub(super) b: f64,
    /// `φ''''(0) = 3 Σ m_j/λ_j⁴`.
    pub(super) c4: f64,
}
