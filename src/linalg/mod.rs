//! The linear algebra of the crate, in one place: the fixed- and dynamic-size matrix types and
//! helpers generic over the dimension (`matrix`: row-major conversion, congruences, orthogonality,
//! sorting, the sorted symmetric eigendecomposition), the Jacobi eigendecomposition underneath it
//! (`jacobi`), and small Cholesky solves (`cholesky`).

mod cholesky;
mod jacobi;
mod matrix;

pub(crate) use cholesky::{cholesky3, cholesky_solve, forward3};
pub use jacobi::{jacobi_general, jacobi_in_place};
pub(crate) use matrix::*;
