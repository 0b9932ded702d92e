//! The small types and the constant the files of `filter` share: the stack matrix and vector of
//! one dimension, and the prediction's concentration cap.

use nalgebra::{SMatrix, SVector};

/// A `D×D` matrix on the stack.
pub(super) type Mat<const D: usize> = SMatrix<f64, D, D>;
/// A vector of length `D` on the stack.
pub(super) type Vect<const D: usize> = SVector<f64, D>;

/// The largest concentration `|z_i|` the prediction uses (see the documentation of module
/// `filter`, "Memory and concentration limits"): before the moments of the state and of the
/// process noise are formed, every `z_i < −MAX_CONCENTRATION` is replaced by
/// `−MAX_CONCENTRATION`. `z = −1e10` corresponds to an angular standard deviation of about
/// `1/√(2·1e10) ≈ 7 µrad`.
pub const MAX_CONCENTRATION: f64 = 1e10;
