//! Property/fuzz tests of the C ABI: every exported function, called through its `extern "C"`
//! signature with raw pointers, with arbitrary dimensions (0, 1, 2..64, 65, huge), NULL and
//! misaligned pointers, NaN/±Inf, subnormals, huge and positive concentrations, non-orthogonal
//! M, non-unit vectors, aliased outputs, and random sequences of filter calls.
//!
//! Every case checks:
//! - the process survives (a crash handler prints the running case if it does not), and the
//!   status is a known code other than `BINGHAM_ERR_PANIC`;
//! - the status is the one the header prescribes where it is determined by the arguments
//!   (invalid `d` → `INVALID_DIMENSION`, NULL/misaligned → `NULL_ARGUMENT`, NaN/Inf →
//!   `INVALID_ARGUMENT`);
//! - input arrays are never written (unless aliased to an output of a successful call) and no
//!   byte around any array changes (guard words);
//! - an error leaves every output buffer and the filter state bit-for-bit unchanged and replaces
//!   this thread's last error message by one naming the function;
//! - success writes every output completely, with finite values satisfying the invariants:
//!   M orthonormal to 1e-12, z ascending with z[d−1] = 0, ω ≥ 0 summing to 1 within 1e-12,
//!   probabilities ≥ 0, unit vectors unit.
//!
//! Deterministic (SplitMix64): each case has its own seed, printed on failure. Environment:
//! - `BINGHAM_FUZZ_CASES` (default 250000): total number of cases over all functions;
//! - `BINGHAM_FUZZ_SEED` (default 0): base seed (a different seed gives different cases);
//! - `BINGHAM_FUZZ_REPRO=<label>:<seed>`: run that one case only, printing its inputs;
//! - `BINGHAM_FUZZ_STATS=1`: print per-function status counts and timings.
//!
//! The modules, in the order a case runs through them: [`kinds`] (the table of the stateless
//! functions), [`case`] (one case: arguments, call, checks), [`invariants`] (per function),
//! [`drivers`] (case counts, seeds, the loops and the tests of the stateless functions), then
//! the stateful and special harnesses [`filter`] (the world-frame steps included), [`spin`],
//! [`vectors`], [`ahrs_inputs`] and [`ahrs`], [`smooth`] (the offline smoother), [`samples`],
//! [`nonlinear`], [`defaults`] (the functions that fill a struct with defaults), [`helpers`];
//! [`status`] reads statuses and the
//! last error message. `tests/api_mirrors.rs` fails if an export is called nowhere here.
//! The generic generators, buffers and the crash reporter are in `testkit::fuzz`.

// Exempt from two lints of Cargo.toml's [lints]: the harness calls the exports through thin
// `unsafe fn` adapters ([`kinds`]) and unsafe blocks whose arguments are the hostile case itself
// (what the library must survive), not a contract a `// SAFETY:` comment could state.
#![allow(unsafe_op_in_unsafe_fn, clippy::undocumented_unsafe_blocks)]

mod ahrs;
mod ahrs_inputs;
mod case;
mod defaults;
mod drivers;
mod filter;
mod helpers;
mod invariants;
mod kinds;
mod nonlinear;
mod samples;
mod smooth;
mod spin;
mod status;
mod vectors;
