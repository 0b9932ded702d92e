//! Transitional: `src/normalization/general.rs` includes this file with `#[path]` for the
//! reference-table reader, which now lives in the `testkit` crate with the other test helpers.
//! Delete this file when that include is replaced by `testkit::read_reference`.

pub use testkit::read_reference;
