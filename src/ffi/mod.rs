//! The C ABI (`include/bingham.h`): a thin layer over the core, holding all of the crate's
//! `unsafe` code and none of its mathematics.
//!
//! - [`version`]: `bingham_version` and the constants that become `#define`s in the header.
//! - [`status`]: `bingham_status` and `bingham_status_str`.
//! - [`guard`]: the panic guard every export runs in, pointer/length checks, copying in and out,
//!   and the thread-local last error message (`bingham_last_error_message`).
//! - `args` (crate-internal): the argument lists of the exports (`args!`): every pointer
//!   checked before any array is read, outputs written only after success.
//! - [`normalization`]: the normalization constant (`bingham_normalization_constant`, …).
//! - [`mle`]: maximum-likelihood fits (`bingham_mle`, `bingham_mle_samples`).
//! - [`distribution`]: the functions of a distribution (`bingham_second_moment`,
//!   `bingham_multiply`, `bingham_pdf`, `bingham_sample`, `bingham_mode`, …).
//! - [`observation`]: observations, noise and spread of orientations
//!   (`bingham_vector_observation`, `bingham_noise_from_angle_std`, `bingham_angular_spread`).
//! - [`deterministic`]: deterministic samples of a distribution (`bingham_deterministic_samples`).
//! - [`filter`]: the recursive filter handle `bingham_filter` (including the nonlinear predict
//!   and update through C callbacks).
//! - [`world`]: the filter's world-frame steps (`bingham_filter_predict_world`, …; Glover &
//!   Kaelbling's first-order model).
//! - [`ahrs`]: the IMU orientation filter handle `bingham_ahrs`.
//! - [`smooth`]: the offline smoother over a whole recording (`bingham_ahrs_smooth`).
//! - [`spin`]: the second-order (orientation and spin) filter handle `bingham_spin_filter`.
//!
//! Conventions (see the header's preamble): row-major `double` arrays, `z` in any order and
//! shift on input, sorted ascending with `z[d-1] = 0` on output, quaternions scalar first, F
//! with respect to the surface measure. Every function returns a `bingham_status` and writes its
//! outputs only on success.
//!
//! Pattern of every function: check `d` (before reading any array), check the required
//! pointers, read and validate the inputs, compute into library-owned buffers, and only then copy
//! into the caller's outputs. So on any error no output is touched, and outputs may overlap
//! inputs (in-place use, e.g. `bingham_multiply(d, m, z, m2, z2, m, z)`).
//!
//! The header is generated from this module by cbindgen (`cbindgen.toml`); the declarations
//! appear in the order of the modules below. `tests/header.rs` fails when the committed header
//! is stale — regenerate it with `make header`.

// One module per group (blank lines keep rustfmt from sorting them): the order is the header's.
pub mod version;

pub mod status;

pub mod guard;

pub(crate) mod args;

pub mod normalization;

pub mod mle;

pub mod distribution;

pub mod observation;

pub mod deterministic;

pub mod filter;

pub mod world;

pub mod nonlinear;

pub mod ahrs;

pub mod smooth;

pub mod spin;

pub use ahrs::*;
pub use deterministic::*;
pub use distribution::*;
pub use filter::*;
pub use guard::bingham_last_error_message;
pub use mle::*;
pub use nonlinear::*;
pub use normalization::*;
pub use observation::*;
pub use smooth::*;
pub use spin::*;
pub use status::{bingham_status, bingham_status_str};
pub use version::*;
pub use world::*;
