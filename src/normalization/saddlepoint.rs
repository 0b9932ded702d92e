//! (being written)
use crate::error::{Error, Result};

/// Sorted evaluation (see `SortedEval`).
pub(crate) fn log_f_sorted(
    _z: &[f64],
    _grad: Option<&mut [f64]>,
    _hess: Option<&mut [f64]>,
) -> Result<f64> {
    Err(Error::Numerical("not yet available".into()))
}
