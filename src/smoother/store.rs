//! What the smoother stores per sample: each pass's mode, covariance, bias and exponent, packed,
//! and the memory they take.

use nalgebra::{Matrix3, Matrix4};

use crate::error::{Error, Result};

/// The bytes the smoother allocates per sample, besides the caller's inputs and outputs: each
/// pass's mode as 4 `f64` and stated covariance as 6 `f32` (the backward pass keeps its own, so
/// that it can run while the forward pass does, module documentation "Threads").
pub const BYTES_PER_SAMPLE: usize = 2 * std::mem::size_of::<Forward>();

/// The bytes the smoother allocates per sample in addition to [`BYTES_PER_SAMPLE`] when the
/// smoothed gyroscope bias is requested (each pass's bias estimate as 3 `f32` and its
/// covariance as 6 `f32`).
pub const BIAS_BYTES_PER_SAMPLE: usize = 2 * std::mem::size_of::<ForwardBias>();

/// What the forward pass keeps per sample; the backward pass replaces it by the smoothed
/// values in place.
#[derive(Debug, Clone, Copy)]
pub(super) struct Forward {
    pub(super) q: [f64; 4],
    /// The covariance's upper triangle: xx, xy, xz, yy, yz, zz.
    pub(super) c: [f32; 6],
}

/// The forward bias estimate and its covariance (upper triangle), per sample.
#[derive(Debug, Clone, Copy)]
pub(super) struct ForwardBias {
    pub(super) b: [f32; 3],
    pub(super) p: [f32; 6],
}

pub(super) fn pack(c: &Matrix3<f64>) -> [f32; 6] {
    [
        c[(0, 0)] as f32,
        (0.5 * (c[(0, 1)] + c[(1, 0)])) as f32,
        (0.5 * (c[(0, 2)] + c[(2, 0)])) as f32,
        c[(1, 1)] as f32,
        (0.5 * (c[(1, 2)] + c[(2, 1)])) as f32,
        c[(2, 2)] as f32,
    ]
}

/// [`pack`] of a row-major 3×3.
pub(super) fn pack9(c: &[f64; 9]) -> [f32; 6] {
    [
        c[0] as f32,
        (0.5 * (c[1] + c[3])) as f32,
        (0.5 * (c[2] + c[6])) as f32,
        c[4] as f32,
        (0.5 * (c[5] + c[7])) as f32,
        c[8] as f32,
    ]
}

pub(super) fn unpack(c: &[f32; 6]) -> Matrix3<f64> {
    let [a, b, d, e, f, g] = c.map(f64::from);
    Matrix3::new(a, b, d, b, e, f, d, f, g)
}

/// What a pass keeps per sample: its mode and stated covariance, its bias estimate and
/// covariance if wanted, its Bingham exponent if the exact product is wanted.
pub(super) struct Pass {
    pub(super) states: Vec<Forward>,
    pub(super) bias: Option<Vec<ForwardBias>>,
    pub(super) exponents: Vec<Matrix4<f64>>,
}

/// A vector with room for `n` elements, or the error saying it cannot be allocated.
pub(super) fn room<T>(n: usize, what: &str) -> Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        Error::InvalidArgument(format!("cannot allocate the smoother's {n} {what}"))
    })?;
    Ok(v)
}

impl Pass {
    pub(super) fn new(n: usize, want_bias: bool, exact: bool) -> Result<Pass> {
        Ok(Pass {
            states: room(n, "samples")?,
            bias: if want_bias {
                Some(room(n, "bias samples")?)
            } else {
                None
            },
            exponents: if exact {
                room(n, "exponents")?
            } else {
                Vec::new()
            },
        })
    }
}
