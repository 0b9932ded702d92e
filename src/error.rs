//! Error values of the core API.

use std::fmt;

/// Smallest supported dimension `d` (the circle S¹).
pub const MIN_DIM: usize = 2;
/// Largest supported dimension `d`.
pub const MAX_DIM: usize = 64;

/// Everything that can go wrong in the core; the C layer maps each variant to a `bingham_status`.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// The dimension is outside `MIN_DIM..=MAX_DIM`, or not supported by the operation
    /// (composition and the filter exist for d = 2 and d = 4 only), or array lengths disagree.
    InvalidDimension(String),
    /// An argument is not acceptable (NaN/Inf, non-orthogonal `M`, non-unit vector, …).
    InvalidArgument(String),
    /// An iterative method did not reach its tolerance.
    NotConverged(String),
    /// A computation produced a non-finite or otherwise unusable intermediate result.
    Numerical(String),
    /// A user-supplied function (the transition or log-likelihood of the nonlinear filter
    /// steps) reported failure or returned an unusable value (not finite, not unit length).
    Callback(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::InvalidDimension(m) => write!(f, "invalid dimension: {m}"),
            Error::InvalidArgument(m) => write!(f, "invalid argument: {m}"),
            Error::NotConverged(m) => write!(f, "not converged: {m}"),
            Error::Numerical(m) => write!(f, "numerical failure: {m}"),
            Error::Callback(m) => write!(f, "callback failed: {m}"),
        }
    }
}

impl std::error::Error for Error {}

impl Error {
    /// The same error with `what` and ": " in front of its message (e.g. "sample 12"), for a
    /// call that fails on one item of many.
    pub(crate) fn prefixed(self, what: &str) -> Error {
        match self {
            Error::InvalidDimension(m) => Error::InvalidDimension(format!("{what}: {m}")),
            Error::InvalidArgument(m) => Error::InvalidArgument(format!("{what}: {m}")),
            Error::NotConverged(m) => Error::NotConverged(format!("{what}: {m}")),
            Error::Numerical(m) => Error::Numerical(format!("{what}: {m}")),
            Error::Callback(m) => Error::Callback(format!("{what}: {m}")),
        }
    }
}

/// Result type of the core API.
pub type Result<T> = std::result::Result<T, Error>;

/// Checks `MIN_DIM <= d <= MAX_DIM`.
pub fn check_dim(d: usize) -> Result<()> {
    if (MIN_DIM..=MAX_DIM).contains(&d) {
        Ok(())
    } else {
        Err(Error::InvalidDimension(format!(
            "d = {d} is outside the supported range {MIN_DIM}..={MAX_DIM}"
        )))
    }
}

/// Checks that every value is finite; `what` names the argument in the message.
pub fn check_finite(what: &str, values: &[f64]) -> Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(Error::InvalidArgument(format!(
            "{what}[{i}] = {} is not finite",
            values[i]
        ))),
    }
}
