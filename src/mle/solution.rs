//! What the solvers of the moment equation share: the solution with its derivatives
//! ([`Derivs`]), the convergence tolerance ([`MLE_TOL`]) and where a Newton iteration starts
//! ([`NewtonStart`]).

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim};

use crate::linalg::{Square, Vector};

/// Convergence tolerance: `max_i |ω_i(z) − ω̂_i| / ω̂_i`.
pub const MLE_TOL: f64 = 1e-13;

/// `log F`'s gradient `ω` and Hessian at a point `z` (as the solver sees it: `z[d−1] = 0`).
/// In a solution returned by [`solve_z`](super::newton::solve_z) the Hessian may be that of the
/// previous iterate (see [`newton::newton`](super::newton::newton)). `hess` holds the Hessian
/// row-major in its storage (`hess.as_slice()`, as [`newton::newton`](super::newton::newton)
/// reads and writes it).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Derivs<D: Dim>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    pub(crate) z: Vector<D>,
    pub(crate) grad: Vector<D>,
    pub(crate) hess: Square<D>,
}

/// Where [`newton`](super::newton::newton) starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum NewtonStart {
    /// From [`initial_guess`](super::newton::initial_guess).
    Guess,
    /// From the point in `z` whose gradient and Hessian are already in `grad` and `hess`.
    Evaluated,
}
