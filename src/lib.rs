//! # bingham
//!
//! Exact Bingham distribution math and the recursive Bingham filter of Kurz et al.
//!
//! A Bingham distribution on the unit sphere S^{d-1} ⊂ R^d has the density
//! `f(x) = exp(xᵀ M Z Mᵀ x) / F(Z)` with respect to the **surface measure**, so that
//! `F(0) = |S^{d-1}|` (2π for d = 2, 4π for d = 3, 2π² for d = 4).
//! `M` is orthogonal with the principal directions as columns, the **last column is the mode**;
//! `Z = diag(z)` with `z` sorted ascending and `z_d = 0` (other orders and shifts are normalized:
//! adding `c·I` to `Z` does not change the distribution).
//! Quaternions are scalar first, `(w, x, y, z)`.

pub mod ahrs;
mod canonical;
pub mod deterministic;
pub mod distribution;
pub mod error;
pub mod ffi;
pub mod filter;
mod linalg;
pub mod mle;
pub mod normalization;
pub mod observation;
pub mod quaternion;
mod sampler;
pub mod smoother;
pub mod special;

pub use distribution::Bingham;
pub use error::{Error, Result, MAX_DIM, MIN_DIM};
pub use mle::{mle_from_samples, mle_from_second_moment};
pub use normalization::{log_normalization, Method};

/// Internals exposed for the benchmarks only (`benches/eigen.rs`); not part of the API, may
/// change without notice.
#[doc(hidden)]
pub mod internals {
    pub use crate::linalg::{jacobi_general, jacobi_in_place};
}
