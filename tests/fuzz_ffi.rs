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

mod common;
mod fuzz_common;

use std::collections::BTreeMap;
use std::os::raw::{c_int, c_void};
use std::time::{Duration, Instant};

use bingham::ffi::*;
use bingham_status::*;
use fuzz_common::*;

// ---- argument kinds ---------------------------------------------------------------------------

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Kind {
    /// d×d orthogonal matrix
    M,
    /// d concentrations
    Z,
    /// d×d second moment
    S,
    /// n×d unit vectors
    X,
    /// n weights
    W,
    /// d-vector, unit
    U,
    /// one double (output)
    One,
    /// d doubles (output)
    D,
    /// d×d doubles (output)
    DD,
    /// n doubles (output)
    N,
    /// n×d doubles (output)
    ND,
}

fn kind_len(k: Kind, d: usize, n: usize) -> usize {
    match k {
        Kind::M | Kind::S | Kind::DD => d * d,
        Kind::Z | Kind::U | Kind::D => d,
        Kind::X | Kind::ND => n * d,
        Kind::W | Kind::N => n,
        Kind::One => 1,
    }
}

/// The raw arguments of one call.
struct Call {
    d: usize,
    n: usize,
    seed: u64,
    inp: [*const f64; 4],
    out: [*mut f64; 3],
}

type CallFn = unsafe fn(&Call) -> bingham_status;
type CheckFn = fn(&Case, &[Option<Vec<f64>>]) -> Result<(), String>;

struct Spec {
    name: &'static str,
    call: CallFn,
    /// composition and rotations: d = 2 and d = 4 only
    only24: bool,
    /// the function takes a count n
    has_n: bool,
    inputs: &'static [(Kind, &'static str, bool)],
    outputs: &'static [(Kind, &'static str, bool)],
    /// relative share of the cases
    weight: f64,
    /// probability of a d in 5..=64 (the rest: 2, 3, 4)
    big_d: f64,
    /// invariants of a successful call's outputs
    check: CheckFn,
}

// Thin wrappers with one signature (SAFETY for all: the pointers come from `run_case`, which
// allocates every array with the length the header prescribes for (d, n), or passes NULL,
// misaligned or dangling pointers only where the function must refuse them before any access).
unsafe fn c_nc(c: &Call) -> bingham_status {
    bingham_normalization_constant(c.d, c.inp[0], c.out[0], c.out[1])
}
unsafe fn c_lnc(c: &Call) -> bingham_status {
    bingham_log_normalization_constant(c.d, c.inp[0], c.out[0], c.out[1])
}
unsafe fn c_lnc_sp(c: &Call) -> bingham_status {
    bingham_log_normalization_constant_saddlepoint(c.d, c.inp[0], c.out[0], c.out[1])
}
unsafe fn c_hess(c: &Call) -> bingham_status {
    bingham_log_normalization_hessian(c.d, c.inp[0], c.out[0], c.out[1], c.out[2])
}
unsafe fn c_sm(c: &Call) -> bingham_status {
    bingham_second_moment(c.d, c.inp[0], c.inp[1], c.out[0])
}
unsafe fn c_mle(c: &Call) -> bingham_status {
    bingham_mle(c.d, c.inp[0], c.out[0], c.out[1])
}
unsafe fn c_mles(c: &Call) -> bingham_status {
    bingham_mle_samples(c.d, c.n, c.inp[0], c.inp[1], c.out[0], c.out[1])
}
unsafe fn c_mul(c: &Call) -> bingham_status {
    bingham_multiply(
        c.d, c.inp[0], c.inp[1], c.inp[2], c.inp[3], c.out[0], c.out[1],
    )
}
unsafe fn c_comp(c: &Call) -> bingham_status {
    bingham_compose(
        c.d, c.inp[0], c.inp[1], c.inp[2], c.inp[3], c.out[0], c.out[1],
    )
}
unsafe fn c_pdf(c: &Call) -> bingham_status {
    bingham_pdf(c.d, c.inp[0], c.inp[1], c.n, c.inp[2], c.out[0])
}
unsafe fn c_lpdf(c: &Call) -> bingham_status {
    bingham_log_pdf(c.d, c.inp[0], c.inp[1], c.n, c.inp[2], c.out[0])
}
unsafe fn c_ent(c: &Call) -> bingham_status {
    bingham_entropy(c.d, c.inp[0], c.inp[1], c.out[0])
}
unsafe fn c_kl(c: &Call) -> bingham_status {
    bingham_kl_divergence(c.d, c.inp[0], c.inp[1], c.inp[2], c.inp[3], c.out[0])
}
unsafe fn c_samp(c: &Call) -> bingham_status {
    bingham_sample(c.d, c.inp[0], c.inp[1], c.seed, c.n, c.out[0])
}
unsafe fn c_rotl(c: &Call) -> bingham_status {
    bingham_rotate_left(c.d, c.inp[0], c.inp[1], c.inp[2], c.out[0], c.out[1])
}
unsafe fn c_rotr(c: &Call) -> bingham_status {
    bingham_rotate_right(c.d, c.inp[0], c.inp[1], c.inp[2], c.out[0], c.out[1])
}
unsafe fn c_mode(c: &Call) -> bingham_status {
    bingham_mode(c.d, c.inp[0], c.inp[1], c.out[0])
}

use Kind::*;

const SPECS: &[Spec] = &[
    Spec {
        name: "bingham_normalization_constant",
        call: c_nc,
        only24: false,
        has_n: false,
        inputs: &[(Z, "z", false)],
        outputs: &[(One, "f", false), (D, "df", true)],
        weight: 8.0,
        big_d: 0.15,
        check: check_nc,
    },
    Spec {
        name: "bingham_log_normalization_constant",
        call: c_lnc,
        only24: false,
        has_n: false,
        inputs: &[(Z, "z", false)],
        outputs: &[(One, "log_f", false), (D, "dlog_f", true)],
        weight: 12.0,
        big_d: 0.15,
        check: check_lnc,
    },
    Spec {
        name: "bingham_log_normalization_constant_saddlepoint",
        call: c_lnc_sp,
        only24: false,
        has_n: false,
        inputs: &[(Z, "z", false)],
        outputs: &[(One, "log_f", false), (D, "dlog_f", true)],
        weight: 6.0,
        big_d: 0.3,
        check: check_lnc_sp,
    },
    Spec {
        name: "bingham_log_normalization_hessian",
        call: c_hess,
        only24: false,
        has_n: false,
        inputs: &[(Z, "z", false)],
        outputs: &[
            (One, "log_f", false),
            (D, "dlog_f", true),
            (DD, "d2log_f", false),
        ],
        weight: 6.0,
        big_d: 0.05,
        check: check_hess,
    },
    Spec {
        name: "bingham_second_moment",
        call: c_sm,
        only24: false,
        has_n: false,
        inputs: &[(M, "m", false), (Z, "z", false)],
        outputs: &[(DD, "s", false)],
        weight: 8.0,
        big_d: 0.1,
        check: check_sm,
    },
    Spec {
        name: "bingham_mle",
        call: c_mle,
        only24: false,
        has_n: false,
        inputs: &[(S, "s", false)],
        outputs: &[(DD, "m", false), (D, "z", false)],
        weight: 8.0,
        big_d: 0.02,
        check: check_mle,
    },
    Spec {
        name: "bingham_mle_samples",
        call: c_mles,
        only24: false,
        has_n: true,
        inputs: &[(X, "x", false), (W, "w", true)],
        outputs: &[(DD, "m", false), (D, "z", false)],
        weight: 5.0,
        big_d: 0.02,
        check: check_dist_out,
    },
    Spec {
        name: "bingham_multiply",
        call: c_mul,
        only24: false,
        has_n: false,
        inputs: &[
            (M, "m1", false),
            (Z, "z1", false),
            (M, "m2", false),
            (Z, "z2", false),
        ],
        outputs: &[(DD, "m", false), (D, "z", false)],
        weight: 8.0,
        big_d: 0.1,
        check: check_dist_out,
    },
    Spec {
        name: "bingham_compose",
        call: c_comp,
        only24: true,
        has_n: false,
        inputs: &[
            (M, "m1", false),
            (Z, "z1", false),
            (M, "m2", false),
            (Z, "z2", false),
        ],
        outputs: &[(DD, "m", false), (D, "z", false)],
        weight: 10.0,
        big_d: 0.05,
        check: check_dist_out,
    },
    Spec {
        name: "bingham_pdf",
        call: c_pdf,
        only24: false,
        has_n: true,
        inputs: &[(M, "m", false), (Z, "z", false), (X, "x", false)],
        outputs: &[(N, "p", false)],
        weight: 6.0,
        big_d: 0.1,
        check: check_pdf,
    },
    Spec {
        name: "bingham_log_pdf",
        call: c_lpdf,
        only24: false,
        has_n: true,
        inputs: &[(M, "m", false), (Z, "z", false), (X, "x", false)],
        outputs: &[(N, "log_p", false)],
        weight: 6.0,
        big_d: 0.1,
        check: check_log_pdf,
    },
    Spec {
        name: "bingham_entropy",
        call: c_ent,
        only24: false,
        has_n: false,
        inputs: &[(M, "m", false), (Z, "z", false)],
        outputs: &[(One, "h", false)],
        weight: 6.0,
        big_d: 0.1,
        check: check_finite_out,
    },
    Spec {
        name: "bingham_kl_divergence",
        call: c_kl,
        only24: false,
        has_n: false,
        inputs: &[
            (M, "m1", false),
            (Z, "z1", false),
            (M, "m2", false),
            (Z, "z2", false),
        ],
        outputs: &[(One, "kl", false)],
        weight: 6.0,
        big_d: 0.1,
        check: check_kl,
    },
    Spec {
        name: "bingham_sample",
        call: c_samp,
        only24: false,
        has_n: true,
        inputs: &[(M, "m", false), (Z, "z", false)],
        outputs: &[(ND, "x_out", false)],
        weight: 5.0,
        big_d: 0.05,
        check: check_sample,
    },
    Spec {
        name: "bingham_rotate_left",
        call: c_rotl,
        only24: true,
        has_n: false,
        inputs: &[(M, "m", false), (Z, "z", false), (U, "u", false)],
        outputs: &[(DD, "m_out", false), (D, "z_out", false)],
        weight: 6.0,
        big_d: 0.05,
        check: check_dist_out,
    },
    Spec {
        name: "bingham_rotate_right",
        call: c_rotr,
        only24: true,
        has_n: false,
        inputs: &[(M, "m", false), (Z, "z", false), (U, "u", false)],
        outputs: &[(DD, "m_out", false), (D, "z_out", false)],
        weight: 6.0,
        big_d: 0.05,
        check: check_dist_out,
    },
    Spec {
        name: "bingham_mode",
        call: c_mode,
        only24: false,
        has_n: false,
        inputs: &[(M, "m", false), (Z, "z", false)],
        outputs: &[(D, "mode", false)],
        weight: 8.0,
        big_d: 0.2,
        check: check_mode,
    },
];

// ---- one case ---------------------------------------------------------------------------------

/// What was done to the arguments of a case (for the expected status and the report).
#[derive(Clone, Debug, PartialEq)]
enum Attack {
    None,
    /// d outside 2..64 (or n*d overflowing): arrays are dangling or tiny and must not be touched
    BadDim,
    /// a required pointer is NULL
    Null(String),
    /// a pointer is not aligned for double
    Misaligned(String),
    /// a NaN/Inf entry in an input
    NonFinite(String),
    /// a finite but unacceptable or extreme input (non-orthogonal M, non-unit x, bad S, …)
    Bad(String),
    /// an output aliases an input (valid in-place use)
    Alias(usize, usize),
}

#[derive(Debug)]
struct Case {
    spec: usize,
    seed: u64,
    d: usize,
    n: usize,
    /// the input arrays (None: NULL)
    inputs: Vec<Option<Vec<f64>>>,
    /// which outputs are requested (false: NULL, only for optional ones or attacks)
    out_present: Vec<bool>,
    attack: Attack,
    /// pointer tweaks: (is_input, index, byte offset) for misalignment
    misalign: Option<(bool, usize, usize)>,
    /// arrays replaced by a dangling pointer (invalid d)
    dangling: bool,
    /// "moderate" inputs: z within the documented exact range, M exactly orthogonal
    moderate: bool,
}

fn pick_d(rng: &mut Rng, spec: &Spec) -> usize {
    if rng.chance(spec.big_d) {
        // 5..=64, biased to the small end, the extremes included
        match rng.below(6) {
            0 => 64,
            1 => 5,
            2 => 5 + rng.below(60),
            _ => 5 + rng.below(8),
        }
    } else {
        2 + rng.below(3)
    }
}

fn gen_input(rng: &mut Rng, k: Kind, d: usize, n: usize, moderate: bool) -> Vec<f64> {
    match k {
        M => orthogonal(rng, d),
        Z => {
            if moderate {
                z_moderate(rng, d)
            } else {
                z_vector(rng, d)
            }
        }
        S => {
            let m = orthogonal(rng, d);
            let w: Vec<f64> = match rng.below(6) {
                0 => vec![1.0; d],
                // (moderate: eigenvalue ratios ≥ 1e-6, i.e. |z| up to about 1e6)
                1 if moderate => (0..d).map(|_| rng.log_uniform(-6.0, 0.0)).collect(),
                1 => (0..d).map(|_| rng.log_uniform(-12.0, 0.0)).collect(),
                2 => (0..d).map(|_| rng.log_uniform(-3.0, 0.0)).collect(),
                _ => (0..d).map(|_| rng.range(0.05, 1.0)).collect(),
            };
            let scale = if moderate {
                1.0
            } else {
                rng.log_uniform(-3.0, 3.0)
            };
            let w: Vec<f64> = w.iter().map(|v| v * scale).collect();
            congruence(&m, &w, d)
        }
        X => {
            let center = unit_vector(rng, d);
            let spread = rng.log_uniform(-6.0, 1.0);
            (0..n)
                .flat_map(|_| {
                    let v: Vec<f64> = center.iter().map(|c| c + spread * rng.normal()).collect();
                    let nv = norm(&v);
                    let sign = if rng.chance(0.5) { 1.0 } else { -1.0 };
                    v.into_iter()
                        .map(move |x| sign * x / nv)
                        .collect::<Vec<_>>()
                })
                .collect()
        }
        W => (0..n)
            .map(|_| match rng.below(8) {
                0 => 0.0,
                1 => rng.log_uniform(-10.0, 10.0),
                _ => rng.range(0.01, 1.0),
            })
            .collect(),
        U => unit_vector(rng, d),
        One | D | DD | N | ND => unreachable!("not an input kind"),
    }
}

/// Makes an input finite but unacceptable or extreme; returns a description.
fn spoil(rng: &mut Rng, k: Kind, a: &mut [f64], d: usize) -> String {
    if a.is_empty() {
        return "empty".into();
    }
    match k {
        M => match rng.below(6) {
            0 => {
                let eps = rng.log_uniform(-9.0, 0.0);
                let i = rng.below(a.len());
                a[i] += eps;
                format!("M[{i}] += {eps:e}")
            }
            1 => {
                a.iter_mut().for_each(|v| *v = 0.0);
                "M = 0".into()
            }
            2 => {
                let s = rng.log_uniform(-3.0, 3.0);
                a.iter_mut().for_each(|v| *v *= s);
                format!("M *= {s:e}")
            }
            3 => {
                for r in 0..d {
                    a[r * d + d - 1] = a[r * d];
                }
                "M: last column = first".into()
            }
            4 => {
                let i = rng.below(a.len());
                let v = extreme(rng);
                a[i] = v;
                format!("M[{i}] = {v:e}")
            }
            _ => {
                let eps = rng.log_uniform(-8.0, -5.0);
                a.iter_mut().for_each(|v| *v *= 1.0 + eps);
                format!("M *= 1 + {eps:e}")
            }
        },
        Z => {
            let i = rng.below(a.len());
            let v = extreme(rng);
            a[i] = v;
            if rng.chance(0.3) {
                let j = rng.below(a.len());
                a[j] = -v;
                format!("z[{i}] = {v:e}, z[{j}] = {:e}", -v)
            } else {
                format!("z[{i}] = {v:e}")
            }
        }
        S => match rng.below(6) {
            0 => {
                let (r, c) = (rng.below(d), rng.below(d));
                let v = rng.log_uniform(-12.0, 0.0);
                a[r * d + c] += v;
                format!("S[{r},{c}] += {v:e} (asymmetric)")
            }
            1 => {
                a.iter_mut().for_each(|v| *v = 0.0);
                "S = 0".into()
            }
            2 => {
                // negative or zero eigenvalue: S − λ u uᵀ with λ ≥ the smallest eigenvalue is
                // hard to arrange exactly; subtract a large multiple of the identity instead
                let t: f64 = (0..d).map(|i| a[i * d + i]).sum();
                let c = t * rng.range(0.0, 2.0) / d as f64;
                for i in 0..d {
                    a[i * d + i] -= c;
                }
                format!("S −= {c:e}·I")
            }
            3 => {
                let s = extreme(rng).abs();
                a.iter_mut().for_each(|v| *v *= s);
                format!("S *= {s:e}")
            }
            4 => {
                // rank deficient: u uᵀ
                let u = unit_vector(rng, d);
                for r in 0..d {
                    for c in 0..d {
                        a[r * d + c] = u[r] * u[c];
                    }
                }
                "S = u uᵀ".into()
            }
            _ => {
                let i = rng.below(a.len());
                let v = extreme(rng);
                a[i] = v;
                format!("S[{i}] = {v:e}")
            }
        },
        X | U => {
            let rows = a.len() / d;
            let r = rng.below(rows);
            let row = &mut a[r * d..(r + 1) * d];
            match rng.below(4) {
                0 => {
                    let eps = rng.log_uniform(-9.0, 0.0) * if rng.chance(0.5) { 1.0 } else { -0.5 };
                    row.iter_mut().for_each(|v| *v *= 1.0 + eps);
                    format!("row {r} *= 1 + {eps:e}")
                }
                1 => {
                    row.iter_mut().for_each(|v| *v = 0.0);
                    format!("row {r} = 0")
                }
                2 => {
                    let i = rng.below(d);
                    let v = extreme(rng);
                    row[i] = v;
                    format!("row {r}[{i}] = {v:e}")
                }
                _ => {
                    let s = extreme(rng);
                    row.iter_mut().for_each(|v| *v *= s);
                    format!("row {r} *= {s:e}")
                }
            }
        }
        W => match rng.below(4) {
            0 => {
                let i = rng.below(a.len());
                a[i] = -rng.log_uniform(-300.0, 3.0);
                format!("w[{i}] = {:e}", a[i])
            }
            1 => {
                a.iter_mut().for_each(|v| *v = 0.0);
                "w = 0".into()
            }
            2 => {
                a.iter_mut().for_each(|v| *v = f64::MAX);
                "w = MAX".into()
            }
            _ => {
                let i = rng.below(a.len());
                let v = extreme(rng);
                a[i] = v;
                format!("w[{i}] = {v:e}")
            }
        },
        _ => unreachable!(),
    }
}

fn gen_case(spec_idx: usize, seed: u64) -> Case {
    let spec = &SPECS[spec_idx];
    let mut rng = Rng::new(seed);
    let roll = rng.unit();
    let mut attack = Attack::None;
    let mut d = pick_d(&mut rng, spec);
    if spec.only24 && rng.chance(0.97) {
        d = if rng.chance(0.5) { 2 } else { 4 };
    }
    let mut n = if spec.has_n {
        match rng.below(10) {
            0 => 0,
            1 => 1,
            _ => 1 + rng.below(d + 6),
        }
    } else {
        0
    };
    if spec.name == "bingham_mle_samples" && n == 0 && rng.chance(0.7) {
        n = 1 + rng.below(2 * d + 2);
    }
    let moderate = rng.chance(0.5);
    let mut dangling = false;
    if roll < 0.05 {
        attack = Attack::BadDim;
        if spec.has_n && rng.chance(0.3) {
            // n*d overflows (or exceeds isize::MAX bytes): refused before any access
            n = match rng.below(3) {
                0 => usize::MAX,
                1 => usize::MAX / d + 1,
                _ => (isize::MAX as usize) / 8 / d + 1,
            };
            dangling = true;
        } else {
            d = *rng.pick(&[0, 1, 65, 66, 100, 1 << 20, usize::MAX / 2, usize::MAX]);
            dangling = d > 65 || rng.chance(0.5);
            if !dangling {
                n = n.min(3);
            }
        }
    }
    // inputs with valid content (tiny dummies when d is absurd)
    let len_d = if d > 65 { 1 } else { d };
    let mut inputs: Vec<Option<Vec<f64>>> = spec
        .inputs
        .iter()
        .map(|&(k, _, optional)| {
            if optional && rng.chance(0.3) {
                None
            } else if dangling || !(2..=64).contains(&d) {
                Some(vec![0.5; kind_len(k, len_d, n.min(8))])
            } else {
                Some(gen_input(&mut rng, k, d, n, moderate))
            }
        })
        .collect();
    let mut out_present: Vec<bool> = spec
        .outputs
        .iter()
        .map(|&(_, _, optional)| !(optional && rng.chance(0.3)))
        .collect();
    let mut misalign = None;
    if attack == Attack::None {
        let r = rng.unit();
        let n_in = spec.inputs.len();
        let n_out = spec.outputs.len();
        if r < 0.06 {
            // NULL: a required input or output (array arguments with n = 0 may be NULL)
            let total = n_in + n_out;
            let k = rng.below(total);
            if k < n_in {
                inputs[k] = None;
                attack = Attack::Null(spec.inputs[k].1.into());
            } else {
                out_present[k - n_in] = false;
                attack = Attack::Null(spec.outputs[k - n_in].1.into());
            }
        } else if r < 0.10 {
            let total = n_in + n_out;
            let k = rng.below(total);
            let off = 1 + rng.below(7);
            if k < n_in {
                if inputs[k].is_none() {
                    inputs[k] = Some(vec![0.5; kind_len(spec.inputs[k].0, d, n)]);
                }
                misalign = Some((true, k, off));
                attack = Attack::Misaligned(spec.inputs[k].1.into());
            } else {
                out_present[k - n_in] = true;
                misalign = Some((false, k - n_in, off));
                attack = Attack::Misaligned(spec.outputs[k - n_in].1.into());
            }
        } else if r < 0.22 {
            let present: Vec<usize> = (0..n_in)
                .filter(|&i| inputs[i].as_ref().is_some_and(|v| !v.is_empty()))
                .collect();
            if !present.is_empty() {
                let k = *rng.pick(&present);
                let a = inputs[k].as_mut().unwrap();
                let i = rng.below(a.len());
                a[i] = non_finite(&mut rng);
                attack = Attack::NonFinite(format!("{}[{i}] = {}", spec.inputs[k].1, a[i]));
            }
        } else if r < 0.40 {
            let present: Vec<usize> = (0..n_in)
                .filter(|&i| inputs[i].as_ref().is_some_and(|v| !v.is_empty()))
                .collect();
            if !present.is_empty() {
                let k = *rng.pick(&present);
                let kind = spec.inputs[k].0;
                let what = spoil(&mut rng, kind, inputs[k].as_mut().unwrap(), d);
                attack = Attack::Bad(format!("{}: {what}", spec.inputs[k].1));
            }
        } else if r < 0.47 {
            // an output aliasing an input of the same length
            let pairs: Vec<(usize, usize)> = (0..n_out)
                .flat_map(|o| (0..n_in).map(move |i| (o, i)))
                .filter(|&(o, i)| {
                    let (ko, ki) = (spec.outputs[o].0, spec.inputs[i].0);
                    inputs[i].is_some()
                        && (ko == DD && (ki == M || ki == S) || ko == D && (ki == Z || ki == U))
                })
                .collect();
            if !pairs.is_empty() {
                let (o, i) = *rng.pick(&pairs);
                out_present[o] = true;
                attack = Attack::Alias(o, i);
            }
        }
    }
    Case {
        spec: spec_idx,
        seed,
        d,
        n,
        inputs,
        out_present,
        attack,
        misalign,
        dangling,
        moderate,
    }
}

/// The status the header prescribes for this case, if determined by the arguments alone.
fn expected(case: &Case) -> Option<bingham_status> {
    let spec = &SPECS[case.spec];
    match &case.attack {
        Attack::BadDim => return Some(BINGHAM_ERR_INVALID_DIMENSION),
        Attack::Null(_) | Attack::Misaligned(_) => {
            if spec.name == "bingham_mle_samples" && case.n == 0 {
                return Some(BINGHAM_ERR_INVALID_ARGUMENT);
            }
            // arrays of length 0 (n = 0) may be NULL/anything
            let null_matters = match &case.attack {
                Attack::Null(name) | Attack::Misaligned(name) => {
                    let k = spec
                        .inputs
                        .iter()
                        .map(|a| (a.0, a.1))
                        .chain(spec.outputs.iter().map(|a| (a.0, a.1)))
                        .find(|a| a.1 == name)
                        .unwrap()
                        .0;
                    let optional = spec
                        .inputs
                        .iter()
                        .chain(spec.outputs.iter())
                        .any(|a| a.1 == name && a.2);
                    let is_null = matches!(case.attack, Attack::Null(_));
                    !(is_null && optional) && (kind_len(k, case.d, case.n) > 0 || !spec.has_n)
                }
                _ => unreachable!(),
            };
            if null_matters {
                return Some(BINGHAM_ERR_NULL_ARGUMENT);
            }
            return None;
        }
        _ => {}
    }
    if spec.name == "bingham_mle_samples" && case.n == 0 {
        return Some(BINGHAM_ERR_INVALID_ARGUMENT);
    }
    if let Attack::NonFinite(_) = case.attack {
        return Some(BINGHAM_ERR_INVALID_ARGUMENT);
    }
    if spec.only24 && case.d != 2 && case.d != 4 {
        // the arrays are validated before the dimension is refused: INVALID_ARGUMENT for bad
        // values (including z whose span overflows), else INVALID_DIMENSION
        return match case.attack {
            Attack::Bad(_) => None,
            _ if z_span_overflows(case) => None,
            _ => Some(BINGHAM_ERR_INVALID_DIMENSION),
        };
    }
    None
}

/// Some concentration input spans more than the largest double (max z − min z overflows,
/// e.g. z = (MAX, −MAX)): refused as INVALID_ARGUMENT.
fn z_span_overflows(case: &Case) -> bool {
    let spec = &SPECS[case.spec];
    spec.inputs.iter().zip(&case.inputs).any(|(a, v)| {
        a.0 == Z
            && v.as_ref().is_some_and(|z| {
                let mx = z.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
                let mn = z.iter().cloned().fold(f64::INFINITY, f64::min);
                !(mx - mn).is_finite()
            })
    })
}

/// Where the header promises success: exactly orthogonal M, z within the documented range, and
/// no spoiled input.
fn must_succeed(case: &Case) -> bool {
    let spec = &SPECS[case.spec];
    if !matches!(case.attack, Attack::None | Attack::Alias(..)) {
        return false;
    }
    // log F, its gradient and Hessian: OK for every finite z whose span is representable,
    // not only moderate ones (issue 13)
    if matches!(
        spec.name,
        "bingham_log_normalization_constant" | "bingham_log_normalization_hessian"
    ) && !z_span_overflows(case)
    {
        return true;
    }
    if !case.moderate {
        return false;
    }
    if spec.only24 && case.d != 2 && case.d != 4 {
        return false;
    }
    match spec.name {
        "bingham_normalization_constant" => false, // may over/underflow by design
        "bingham_mle_samples" => false,            // samples may be degenerate (singular scatter)
        "bingham_pdf" => false,                    // may overflow to +Inf by design (documented)
        _ => true,
    }
}

#[derive(Default, Clone)]
struct Stats {
    cases: u64,
    by_status: BTreeMap<&'static str, u64>,
    time: Duration,
}

/// Runs one case; Err describes the failure.
fn run_case(case: &Case, verbose: bool) -> Result<bingham_status, String> {
    let spec = &SPECS[case.spec];
    let (d, n) = (case.d, case.n);
    let mut in_bufs: Vec<Option<Buf>> = case
        .inputs
        .iter()
        .map(|a| a.as_ref().map(|v| Buf::from(v)))
        .collect();
    let out_len = |k: Kind| {
        if case.dangling || !(2..=64).contains(&d) {
            1
        } else {
            kind_len(k, d, n)
        }
    };
    let mut out_bufs: Vec<Option<Buf>> = spec
        .outputs
        .iter()
        .zip(&case.out_present)
        .map(|(&(k, _, _), &p)| p.then(|| Buf::sentinel(out_len(k))))
        .collect();
    let mut call = Call {
        d,
        n,
        seed: case.seed,
        inp: [std::ptr::null(); 4],
        out: [std::ptr::null_mut(); 3],
    };
    for (i, b) in in_bufs.iter_mut().enumerate() {
        if let Some(b) = b {
            call.inp[i] = if case.dangling { dangling() } else { b.ptr() };
        }
    }
    for (i, b) in out_bufs.iter_mut().enumerate() {
        if let Some(b) = b {
            call.out[i] = if case.dangling { dangling() } else { b.ptr() };
        }
    }
    if let Some((is_in, k, off)) = case.misalign {
        if is_in {
            call.inp[k] = in_bufs[k].as_mut().unwrap().misaligned(off);
        } else {
            call.out[k] = out_bufs[k].as_mut().unwrap().misaligned(off);
        }
    }
    let mut alias = None;
    if let Attack::Alias(o, i) = case.attack {
        call.out[o] = in_bufs[i].as_mut().unwrap().ptr();
        alias = Some((o, i));
    }
    if verbose {
        eprintln!("{case:#?}");
    }
    let in_before: Vec<Option<Vec<u64>>> =
        in_bufs.iter().map(|b| b.as_ref().map(Buf::bits)).collect();
    let primed = prime_last_error(spec.name);

    // SAFETY: see the wrappers: every pointer is NULL, misaligned (refused), dangling (d or n
    // refused first), or a buffer of the length the header prescribes.
    let status = unsafe { (spec.call)(&call) };

    let code = status_code(status);
    if !(0..=7).contains(&code) || status == BINGHAM_ERR_CALLBACK {
        // (no callback is involved here)
        return Err(format!("status code {code}: {}", last_error()));
    }
    if status == BINGHAM_ERR_PANIC {
        return Err(format!("panic caught: {}", last_error()));
    }
    if let Some(want) = expected(case) {
        if status != want {
            let msg = if status != BINGHAM_OK {
                last_error()
            } else {
                String::new()
            };
            return Err(format!(
                "status {} where the header prescribes {} ({msg})",
                status_name(status),
                status_name(want)
            ));
        }
    }
    if spec.only24 && d != 2 && d != 4 && (2..=64).contains(&d) && status == BINGHAM_OK {
        return Err("OK for a dimension other than 2 and 4".into());
    }
    if status != BINGHAM_OK && must_succeed(case) {
        return Err(format!(
            "status {} for inputs where success is documented: {}",
            status_name(status),
            last_error()
        ));
    }
    // inputs: unchanged (except an alias after success), guards intact
    for (i, b) in in_bufs.iter().enumerate() {
        let Some(b) = b else { continue };
        if !b.guards_ok() {
            return Err(format!(
                "guard words around input `{}` changed",
                spec.inputs[i].1
            ));
        }
        let aliased_ok = alias.is_some_and(|(_, ai)| ai == i) && status == BINGHAM_OK;
        if !aliased_ok && Some(b.bits()) != in_before[i] {
            return Err(format!("input `{}` was modified", spec.inputs[i].1));
        }
    }
    for (o, b) in out_bufs.iter().enumerate() {
        let Some(b) = b else { continue };
        let name = spec.outputs[o].1;
        let misaligned_here = case.misalign.is_some_and(|(is_in, k, _)| !is_in && k == o);
        if status != BINGHAM_OK || case.dangling || misaligned_here {
            if !b.untouched() {
                return Err(format!(
                    "output `{name}` written although the status is {}",
                    status_name(status)
                ));
            }
        } else if alias.is_some_and(|(ao, _)| ao == o) {
            if !b.untouched() {
                return Err(format!("output `{name}` written although it was aliased"));
            }
        } else {
            if !b.guards_ok() {
                return Err(format!("guard words around output `{name}` overwritten"));
            }
            if !b.fully_written() {
                return Err(format!("output `{name}` not completely written"));
            }
        }
    }
    if status != BINGHAM_OK {
        if let Err(e) = check_error_message(spec.name) {
            return Err(format!("{e} (primed with {primed:?})"));
        }
        return Ok(status);
    }
    // success: collect outputs (from the aliased input where aliased) and check invariants
    let outs: Vec<Option<Vec<f64>>> = (0..spec.outputs.len())
        .map(|o| match alias {
            Some((ao, ai)) if ao == o => in_bufs[ai].as_ref().map(Buf::values),
            _ => out_bufs[o].as_ref().map(Buf::values),
        })
        .collect();
    for (o, v) in outs.iter().enumerate() {
        if let Some(v) = v {
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                if !(spec.name == "bingham_pdf" && v[i] == f64::INFINITY) {
                    return Err(format!(
                        "output `{}`[{i}] = {} is not finite",
                        spec.outputs[o].1, v[i]
                    ));
                }
            }
        }
    }
    (spec.check)(case, &outs)?;
    Ok(status)
}

// ---- invariants per function ------------------------------------------------------------------

/// The tolerance on Σω: 1e-12, or 1e-9 when some shifted concentration is beyond 1e300 (far
/// outside the documented exact range |z| ≤ 1e6; for d = 4 and |z| near the largest double the
/// quadrature loses some digits, e.g. Σω = 1 − 9e-12 for z = (−MAX, −MAX, −3.6e6, −1.35)).
fn omega_tol(c: &Case) -> f64 {
    let spec = &SPECS[c.spec];
    let extreme = spec.inputs.iter().zip(&c.inputs).any(|(a, v)| {
        a.0 == Z
            && v.as_ref().is_some_and(|z| {
                let mx = z.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
                z.iter().any(|&x| x - mx < -1e300)
            })
    });
    if extreme {
        1e-9
    } else {
        STATE_TOL
    }
}

fn check_nc(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    let f = o[0].as_ref().unwrap()[0];
    if f.is_nan() || f <= 0.0 || !f.is_normal() {
        return Err(format!("F = {f:e} is not a positive normal number"));
    }
    if let Some(df) = &o[1] {
        let w: Vec<f64> = df.iter().map(|v| v / f).collect();
        check_omega_tol(&w, omega_tol(c)).map_err(|e| format!("df/F: {e}"))?;
    }
    Ok(())
}

fn check_lnc(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    if let Some(w) = &o[1] {
        check_omega_tol(w, omega_tol(c)).map_err(|e| format!("dlog_f: {e}"))?;
    }
    Ok(())
}

fn check_lnc_sp(_c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    if let Some(w) = &o[1] {
        if let Some(i) = w.iter().position(|v| *v < 0.0) {
            return Err(format!("saddlepoint dlog_f[{i}] = {} < 0", w[i]));
        }
    }
    Ok(())
}

fn check_hess(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    let d = c.d;
    if let Some(w) = &o[1] {
        check_omega_tol(w, omega_tol(c)).map_err(|e| format!("dlog_f: {e}"))?;
    }
    let h = o[2].as_ref().unwrap();
    for i in 0..d {
        // variances of x_i² ≥ 0 up to rounding (-1e-15; -1e-12 for concentrations beyond
        // 1e300, where d = 4 loses digits, e.g. -1.9e-14 at z = (−MAX, −MAX, −3.6e6, 0))
        let hii = h[i * d + i];
        if hii < -omega_tol(c) * 1e-3 {
            return Err(format!("Hessian diagonal [{i}] = {hii:e} < 0"));
        }
        let scale = (0..d).map(|j| h[i * d + j].abs()).fold(0.0, f64::max);
        let row: f64 = (0..d).map(|j| h[i * d + j]).sum();
        if row.abs() > 1e-10 * scale + 1e-14 {
            return Err(format!("Hessian row {i} sums to {row:e} (scale {scale:e})"));
        }
        for j in 0..i {
            let (a, b) = (h[i * d + j], h[j * d + i]);
            if (a - b).abs() > 1e-12 * a.abs().max(b.abs()) {
                return Err(format!(
                    "Hessian not symmetric at ({i},{j}): {a:e} vs {b:e}"
                ));
            }
        }
    }
    Ok(())
}

fn check_sm(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    let d = c.d;
    let s = o[0].as_ref().unwrap();
    let tr: f64 = (0..d).map(|i| s[i * d + i]).sum();
    if (tr - 1.0).abs() > omega_tol(c) {
        return Err(format!("trace S = 1 + {:e}", tr - 1.0));
    }
    for i in 0..d {
        if s[i * d + i] < 0.0 {
            return Err(format!("S[{i},{i}] = {:e} < 0", s[i * d + i]));
        }
        for j in 0..i {
            if (s[i * d + j] - s[j * d + i]).abs() > 1e-15 {
                return Err(format!("S not symmetric at ({i},{j})"));
            }
        }
    }
    Ok(())
}

fn check_dist_out(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    check_state(o[0].as_ref().unwrap(), o[1].as_ref().unwrap(), c.d)
}

fn check_mle(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    check_dist_out(c, o)?;
    if c.moderate && c.attack == Attack::None && c.d <= 4 {
        // round trip: the fit's second moment equals the normalized input
        let d = c.d;
        let (m, z) = (o[0].as_ref().unwrap(), o[1].as_ref().unwrap());
        let mut lf = 0.0;
        let mut w = vec![0.0; d];
        // SAFETY: valid buffers of length d.
        let st =
            unsafe { bingham_log_normalization_constant(d, z.as_ptr(), &mut lf, w.as_mut_ptr()) };
        if st != BINGHAM_OK {
            return Err(format!("log F of the fit failed: {}", last_error()));
        }
        let s_fit = congruence(m, &w, d);
        let s_in = c.inputs[0].as_ref().unwrap();
        let tr: f64 = (0..d).map(|i| s_in[i * d + i]).sum();
        for (a, b) in s_fit.iter().zip(s_in) {
            if (a - b / tr).abs() > 1e-9 {
                return Err(format!(
                    "MLE round trip: |S_fit − S| = {:e}",
                    (a - b / tr).abs()
                ));
            }
        }
    }
    Ok(())
}

fn check_pdf(_c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    let Some(p) = o[0].as_ref() else {
        return Ok(()); // n = 0: NULL allowed
    };
    if let Some(i) = p.iter().position(|v| v.is_nan() || *v < 0.0) {
        return Err(format!("p[{i}] = {} is not a density value", p[i]));
    }
    Ok(())
}

fn check_log_pdf(_c: &Case, _o: &[Option<Vec<f64>>]) -> Result<(), String> {
    Ok(()) // finiteness is checked for every output
}

fn check_finite_out(_c: &Case, _o: &[Option<Vec<f64>>]) -> Result<(), String> {
    Ok(())
}

fn check_kl(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    let kl = o[0].as_ref().unwrap()[0];
    // KL ≥ 0; rounding of terms as large as the concentrations allows a little below
    let scale: f64 = [1, 3]
        .iter()
        .filter_map(|&i| c.inputs[i].as_ref())
        .flat_map(|z| {
            let mx = z.iter().cloned().fold(f64::MIN, f64::max);
            z.iter().map(move |v| (v - mx).abs())
        })
        .fold(1.0, f64::max);
    if kl < -1e-12 * scale {
        return Err(format!("KL = {kl:e} < 0 (scale {scale:e})"));
    }
    Ok(())
}

fn check_sample(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    let Some(x) = o[0].as_ref() else {
        return Ok(()); // n = 0: NULL allowed
    };
    for (k, row) in x.chunks_exact(c.d).enumerate() {
        check_unit(row, 1e-12).map_err(|e| format!("sample {k}: {e}"))?;
    }
    Ok(())
}

fn check_mode(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    let v = o[0].as_ref().unwrap();
    check_unit(v, 1e-12)?;
    if c.moderate && c.attack == Attack::None {
        // the mode is the column of the input M with the largest z (when that is unique)
        let (m, z) = (c.inputs[0].as_ref().unwrap(), c.inputs[1].as_ref().unwrap());
        let d = c.d;
        let top = (0..d).max_by(|&a, &b| z[a].total_cmp(&z[b])).unwrap();
        if (0..d).filter(|&i| z[i] == z[top]).count() == 1 {
            let dot: f64 = (0..d).map(|r| m[r * d + top] * v[r]).sum();
            if (dot.abs() - 1.0).abs() > 1e-9 {
                return Err(format!(
                    "mode is not column {top} of M: |dot| = {}",
                    dot.abs()
                ));
            }
        }
    }
    Ok(())
}

// ---- drivers ----------------------------------------------------------------------------------

fn total_cases() -> u64 {
    env_count("BINGHAM_FUZZ_CASES", 250_000)
}

/// The base seed, XOR-ed into every case's seed. A seed other than 0 is scrambled first: XOR-ing
/// a small number into the case index would only reorder the cases of seed 0.
fn base_seed() -> u64 {
    match env_count("BINGHAM_FUZZ_SEED", 0) {
        0 => 0,
        s => mix(s),
    }
}

fn stats_wanted() -> bool {
    std::env::var_os("BINGHAM_FUZZ_STATS").is_some()
}

/// `Some((label, seed))` when a single case is to be reproduced.
fn repro() -> Option<(String, u64)> {
    let s = std::env::var("BINGHAM_FUZZ_REPRO").ok()?;
    let (label, seed) = s
        .rsplit_once(':')
        .expect("BINGHAM_FUZZ_REPRO=<label>:<seed>");
    Some((label.to_string(), seed.parse().expect("seed")))
}

/// The share of the cases for the distribution functions vs. the filter and the small helpers.
const SHARE_DISTRIBUTION: f64 = 0.75;
const SHARE_FILTER: f64 = 0.22;

fn cases_for(weight: f64, total_weight: f64, share: f64) -> u64 {
    ((total_cases() as f64) * share * weight / total_weight).ceil() as u64
}

/// Runs `count` cases of `label` from `gen_and_run(seed)`, collecting up to 20 failures.
fn drive(
    label: &'static str,
    label_id: u64,
    count: u64,
    mut gen_and_run: impl FnMut(u64, bool) -> Result<&'static str, String>,
) -> Stats {
    let slot = CaseSlot::new(label);
    let mut stats = Stats::default();
    if let Some((l, seed)) = repro() {
        if l == label {
            slot.enter(seed);
            let r = gen_and_run(seed, true);
            slot.leave();
            match r {
                Ok(s) => eprintln!("{label} case seed {seed}: passed ({s})"),
                Err(e) => panic!("{label} case seed {seed}: {e}"),
            }
        }
        return stats;
    }
    let mut failures = Vec::new();
    let start = Instant::now();
    for i in 0..count {
        let seed = mix(base_seed() ^ (label_id << 48) ^ i);
        slot.enter(seed);
        let r = gen_and_run(seed, false);
        slot.leave();
        stats.cases += 1;
        match r {
            Ok(s) => *stats.by_status.entry(s).or_default() += 1,
            Err(e) => {
                *stats.by_status.entry("FAILED").or_default() += 1;
                if failures.len() < 20 {
                    failures.push(format!(
                        "  {label} case seed {seed}: {e}\n    reproduce: BINGHAM_FUZZ_REPRO={label}:{seed} \
                         cargo test --release --test fuzz_ffi -- --nocapture"
                    ));
                }
            }
        }
    }
    stats.time = start.elapsed();
    if stats_wanted() {
        eprintln!(
            "{label:<48} {:>9} cases {:>8.2} s {:>9.1} µs/case  {:?}",
            stats.cases,
            stats.time.as_secs_f64(),
            stats.time.as_secs_f64() * 1e6 / stats.cases.max(1) as f64,
            stats.by_status
        );
    }
    let failed = stats.by_status.get("FAILED").copied().unwrap_or(0);
    assert!(
        failures.is_empty(),
        "{failed} of {} {label} cases failed:\n{}",
        stats.cases,
        failures.join("\n")
    );
    stats
}

fn fuzz_spec(idx: usize) {
    let spec = &SPECS[idx];
    let total_weight: f64 = SPECS.iter().map(|s| s.weight).sum();
    let count = cases_for(spec.weight, total_weight, SHARE_DISTRIBUTION);
    drive(spec.name, idx as u64 + 1, count, |seed, verbose| {
        let case = gen_case(idx, seed);
        run_case(&case, verbose).map(status_name)
    });
}

macro_rules! fuzz_tests {
    ($($test:ident => $idx:expr),* $(,)?) => {
        $(
            #[test]
            fn $test() {
                fuzz_spec($idx);
            }
        )*
        #[test]
        fn every_function_has_a_test() {
            let mut covered = vec![$($idx),*];
            covered.sort();
            assert_eq!(covered, (0..SPECS.len()).collect::<Vec<_>>());
        }
    };
}

fuzz_tests! {
    fuzz_normalization_constant => 0,
    fuzz_log_normalization_constant => 1,
    fuzz_log_normalization_constant_saddlepoint => 2,
    fuzz_log_normalization_hessian => 3,
    fuzz_second_moment => 4,
    fuzz_mle => 5,
    fuzz_mle_samples => 6,
    fuzz_multiply => 7,
    fuzz_compose => 8,
    fuzz_pdf => 9,
    fuzz_log_pdf => 10,
    fuzz_entropy => 11,
    fuzz_kl_divergence => 12,
    fuzz_sample => 13,
    fuzz_rotate_left => 14,
    fuzz_rotate_right => 15,
    fuzz_mode => 16,
}

// ---- the filter: random call sequences ----------------------------------------------------------
//
// One case is one sequence: a filter (created with random, sometimes hostile, parameters) and a
// "twin" created alike that receives only the calls that succeeded on the first. After every call:
// on error the state (read with get_state) is bit-for-bit unchanged and the message names the
// function; on success the state is a valid Bingham; and the two filters stay bit-identical, which
// shows that a failed call also left the hidden state (warm start, noise caches) unaffected.

/// A sentinel handle value: a pointer output that must stay untouched on error.
fn handle_sentinel() -> *mut bingham_filter {
    0xDEAD_BEE0usize as *mut bingham_filter
}

fn filter_state(f: *const bingham_filter, d: usize) -> (Vec<f64>, Vec<f64>) {
    let mut m = vec![0.0; d * d];
    let mut z = vec![0.0; d];
    // SAFETY: f is a live handle of dimension d; buffers of length d*d and d.
    let st = unsafe { bingham_filter_get_state(f, m.as_mut_ptr(), z.as_mut_ptr()) };
    assert_eq!(st, BINGHAM_OK, "get_state: {}", last_error());
    (m, z)
}

fn state_bits(f: *const bingham_filter, d: usize) -> Vec<u64> {
    let (m, z) = filter_state(f, d);
    m.iter().chain(&z).map(|v| v.to_bits()).collect()
}

/// Filter noise parameters: mostly realistic (identity or rotated mode, |z| from 1e-3 to 1e7),
/// sometimes extreme (up to 1e13 and beyond, all equal = uniform noise).
fn filter_noise(rng: &mut Rng, d: usize) -> (Vec<f64>, Vec<f64>) {
    let m = if rng.chance(0.5) {
        identity(d)
    } else {
        orthogonal(rng, d)
    };
    let mut z: Vec<f64> = (0..d)
        .map(|_| match rng.below(10) {
            0 => 0.0,
            1 => -rng.log_uniform(7.0, 13.0),
            2 => -rng.log_uniform(-3.0, 0.0),
            _ => -rng.log_uniform(0.0, 7.0),
        })
        .collect();
    match rng.below(12) {
        0 => z.iter_mut().for_each(|v| *v = 0.0),
        1 => {
            let v = -rng.log_uniform(0.0, 4.0);
            z.iter_mut().for_each(|x| *x = v);
        }
        2 => {
            let i = rng.below(d);
            z[i] = -rng.log_uniform(13.0, 300.0);
        }
        _ => {}
    }
    // the mode column gets the largest z most of the time (zero-mean noise)
    if rng.chance(0.8) {
        let top = (0..d).max_by(|&a, &b| z[a].total_cmp(&z[b])).unwrap();
        z.swap(0, top);
        let mut zz = vec![0.0; d];
        // column 0 of the identity is (1, 0, …): the identity quaternion is the mode
        zz[0] = z[0];
        zz[1..].copy_from_slice(&z[1..]);
        z = zz;
    }
    (m, z)
}

/// A measurement relative to the current state: the mode, near it, antipodal, orthogonal, or
/// random.
fn filter_measurement(rng: &mut Rng, m: &[f64], d: usize) -> Vec<f64> {
    let mode: Vec<f64> = (0..d).map(|r| m[r * d + d - 1]).collect();
    match rng.below(6) {
        0 => mode,
        1 => mode.iter().map(|v| -v).collect(),
        2 => (0..d).map(|r| m[r * d]).collect(), // orthogonal to the mode
        3 => {
            let s = rng.log_uniform(-8.0, 0.0);
            let v: Vec<f64> = mode.iter().map(|x| x + s * rng.normal()).collect();
            let n = norm(&v);
            v.iter().map(|x| x / n).collect()
        }
        _ => unit_vector(rng, d),
    }
}

/// What the next call does to one of its array arguments.
#[derive(Debug, Clone, PartialEq)]
enum FAttack {
    None,
    NullHandle,
    MisalignedHandle,
    Null(usize),
    Misaligned(usize),
    NonFinite(usize),
    /// finite but not acceptable (e.g. non-unit, non-orthogonal) or extreme
    Bad(usize),
}

struct FArgs {
    arrays: Vec<Vec<f64>>,
    kinds: Vec<Kind>,
    attack: FAttack,
    desc: String,
}

fn spoil_filter_args(rng: &mut Rng, a: &mut FArgs, d: usize) {
    let k = a.arrays.len();
    let r = rng.unit();
    a.attack = if r < 0.70 || k == 0 {
        FAttack::None
    } else if r < 0.74 {
        FAttack::NullHandle
    } else if r < 0.76 {
        FAttack::MisalignedHandle
    } else if r < 0.81 {
        FAttack::Null(rng.below(k))
    } else if r < 0.84 {
        FAttack::Misaligned(rng.below(k))
    } else if r < 0.91 {
        let i = rng.below(k);
        let j = rng.below(a.arrays[i].len());
        a.arrays[i][j] = non_finite(rng);
        FAttack::NonFinite(i)
    } else {
        let i = rng.below(k);
        let kind = a.kinds[i];
        let what = match kind {
            // the scalar kappa (passed by value): negative, or finite but extreme
            One => {
                a.arrays[i][0] = if rng.chance(0.5) {
                    -rng.log_uniform(-300.0, 300.0)
                } else {
                    extreme(rng)
                };
                format!("kappa = {:e}", a.arrays[i][0])
            }
            // a 3-vector (body / reference) of any filter
            _ if a.arrays[i].len() == 3 => spoil(rng, U, &mut a.arrays[i], 3),
            _ => spoil(rng, kind, &mut a.arrays[i], d),
        };
        a.desc = format!("{} spoiled: {what}", a.desc);
        FAttack::Bad(i)
    };
    // kappa is passed by value: no pointer to make NULL or misaligned
    if let FAttack::Null(i) | FAttack::Misaligned(i) = a.attack {
        if a.kinds.get(i) == Some(&One) {
            a.attack = FAttack::None;
        }
    }
}

/// Calls one filter function on `f` with the arrays of `a` (as the attack says), sets
/// `out_*` where the function has outputs; returns the status.
///
/// # Safety
/// `f` is a live handle of dimension `d`; array lengths match the function.
unsafe fn filter_call(
    op: usize,
    f: *mut bingham_filter,
    a: &FArgs,
    outs: &mut [Buf],
    out_ptr: &mut [*mut bingham_filter; 1],
    out_dim: &mut [usize; 2],
) -> bingham_status {
    let mut bufs: Vec<Buf> = a.arrays.iter().map(|v| Buf::from(v)).collect();
    let mut p: Vec<*const f64> = bufs.iter_mut().map(|b| b.ptr() as *const f64).collect();
    let mut fp = f;
    let mut op_out: Vec<*mut f64> = outs.iter_mut().map(|b| b.ptr()).collect();
    let n_in = p.len();
    match a.attack {
        FAttack::NullHandle => fp = std::ptr::null_mut(),
        FAttack::MisalignedHandle => fp = f.cast::<u8>().wrapping_add(4).cast(),
        FAttack::Null(i) if i < n_in => p[i] = std::ptr::null(),
        FAttack::Null(i) if i - n_in < op_out.len() => op_out[i - n_in] = std::ptr::null_mut(),
        FAttack::Misaligned(i) if i < n_in => p[i] = bufs[i].misaligned(1 + i % 7),
        FAttack::Misaligned(i) if i - n_in < op_out.len() => {
            op_out[i - n_in] = outs[i - n_in].misaligned(3)
        }
        _ => {}
    }
    let o = |i: usize| op_out.get(i).copied().unwrap_or(std::ptr::null_mut());
    // SAFETY: forwarded; pointers are valid buffers, NULL, misaligned or the handle.
    let st = unsafe {
        match op {
            0 => bingham_filter_predict(fp, p[0], p[1]),
            1 => bingham_filter_predict_rotation(fp, p[0], p[1], p[2]),
            2 => bingham_filter_update(fp, p[0], p[1], p[2]),
            3 => bingham_filter_set_state(fp, p[0], p[1]),
            4 => bingham_filter_log_likelihood(fp, p[0], p[1], p[2], o(0)),
            9 => bingham_filter_update_vector(fp, p[0], p[1], a.arrays[2][0]),
            10 => bingham_filter_log_likelihood_vector(fp, p[0], p[1], a.arrays[2][0], o(0)),
            11 => bingham_filter_angular_spread(fp, o(0)),
            5 => bingham_filter_get_state(fp, o(0), o(1)),
            6 => bingham_filter_mode(fp, o(0)),
            7 => {
                let dp = if matches!(a.attack, FAttack::Null(_)) {
                    std::ptr::null_mut()
                } else if matches!(a.attack, FAttack::Misaligned(_)) {
                    out_dim.as_mut_ptr().cast::<u8>().wrapping_add(3).cast()
                } else {
                    out_dim.as_mut_ptr()
                };
                bingham_filter_dim(fp, dp)
            }
            8 => {
                let op = if matches!(a.attack, FAttack::Null(_)) {
                    std::ptr::null_mut()
                } else if matches!(a.attack, FAttack::Misaligned(_)) {
                    out_ptr.as_mut_ptr().cast::<u8>().wrapping_add(2).cast()
                } else {
                    out_ptr.as_mut_ptr()
                };
                bingham_filter_clone(fp, op)
            }
            _ => unreachable!(),
        }
    };
    for (i, b) in bufs.iter().enumerate() {
        assert!(
            b.values()
                .iter()
                .zip(&a.arrays[i])
                .all(|(x, y)| x.to_bits() == y.to_bits())
                && b.guards_ok(),
            "filter op {op}: input {i} was modified"
        );
    }
    st
}

const FILTER_OPS: [&str; 12] = [
    "bingham_filter_predict",
    "bingham_filter_predict_rotation",
    "bingham_filter_update",
    "bingham_filter_set_state",
    "bingham_filter_log_likelihood",
    "bingham_filter_get_state",
    "bingham_filter_mode",
    "bingham_filter_dim",
    "bingham_filter_clone",
    "bingham_filter_update_vector",
    "bingham_filter_log_likelihood_vector",
    "bingham_filter_angular_spread",
];

/// A direction (unit 3-vector) for `bingham_filter_update_vector`: random, or an axis, or a
/// tiny perturbation of one (exactly (anti)parallel pairs of body and reference included).
fn direction(rng: &mut Rng) -> Vec<f64> {
    match rng.below(4) {
        0 => {
            let mut v = vec![0.0; 3];
            v[rng.below(3)] = if rng.chance(0.5) { 1.0 } else { -1.0 };
            v
        }
        1 => {
            let mut v = vec![0.0, 0.0, 1.0];
            v[0] = rng.log_uniform(-12.0, -4.0);
            let n = norm(&v);
            v.iter().map(|x| x / n).collect()
        }
        _ => unit_vector(rng, 3),
    }
}

/// A concentration of a direction measurement: mostly realistic, sometimes 0 or huge.
fn vector_kappa(rng: &mut Rng) -> f64 {
    match rng.below(10) {
        0 => 0.0,
        1 => rng.log_uniform(6.0, 300.0),
        2 => rng.log_uniform(-300.0, -3.0),
        _ => rng.log_uniform(-3.0, 6.0),
    }
}

/// Runs one random sequence; returns the number of calls made and their statuses.
fn filter_sequence(
    seed: u64,
    verbose: bool,
    stats: &mut BTreeMap<String, u64>,
) -> Result<u64, String> {
    let mut rng = Rng::new(seed);
    let mut calls = 0u64;
    let count = |stats: &mut BTreeMap<String, u64>, op: &str, st: bingham_status| {
        let op = op.trim_start_matches("bingham_filter_");
        *stats
            .entry(format!("{op}:{}", status_name(st)))
            .or_default() += 1;
    };

    // --- creation, possibly hostile
    let d_try = match rng.below(20) {
        0 => *rng.pick(&[0usize, 1, 3, 5, 8, 64, 65, usize::MAX]),
        1..=9 => 2,
        _ => 4,
    };
    let dl = if (2..=64).contains(&d_try) { d_try } else { 2 };
    let mut m0 = if rng.chance(0.3) {
        identity(dl)
    } else {
        orthogonal(&mut rng, dl)
    };
    let mut z0 = if rng.chance(0.5) {
        z_moderate(&mut rng, dl)
    } else {
        z_vector(&mut rng, dl)
    };
    let mut args = FArgs {
        arrays: vec![m0.clone(), z0.clone()],
        kinds: vec![M, Z],
        attack: FAttack::None,
        desc: String::new(),
    };
    if rng.chance(0.3) {
        spoil_filter_args(&mut rng, &mut args, dl);
    }
    let mut out = [handle_sentinel()];
    {
        let mut bufs: Vec<Buf> = args.arrays.iter().map(|v| Buf::from(v)).collect();
        let mut p: Vec<*const f64> = bufs.iter_mut().map(|b| b.ptr() as *const f64).collect();
        let mut op = out.as_mut_ptr();
        let dang = !(2..=64).contains(&d_try);
        match args.attack {
            FAttack::Null(i) => p[i] = std::ptr::null(),
            FAttack::Misaligned(i) => p[i] = bufs[i].misaligned(5),
            FAttack::NullHandle => op = std::ptr::null_mut(),
            FAttack::MisalignedHandle => op = op.cast::<u8>().wrapping_add(1).cast(),
            _ => {}
        }
        if dang {
            p = vec![dangling(); 2];
        }
        prime_last_error("bingham_filter_new");
        // SAFETY: buffers of length dl*dl and dl (dl = d_try when d_try is 2 or 4; otherwise
        // the function must refuse d before reading; dangling pointers prove it).
        let st = unsafe { bingham_filter_new(d_try, p[0], p[1], op) };
        calls += 1;
        count(stats, "new", st);
        if verbose {
            eprintln!(
                "new(d = {d_try}, {:?}, attack {:?}) -> {}",
                args.arrays,
                args.attack,
                status_name(st)
            );
        }
        if st == BINGHAM_ERR_PANIC {
            return Err(format!("bingham_filter_new panicked: {}", last_error()));
        }
        let want = if d_try != 2 && d_try != 4 {
            Some(BINGHAM_ERR_INVALID_DIMENSION)
        } else {
            match args.attack {
                FAttack::Null(_)
                | FAttack::Misaligned(_)
                | FAttack::NullHandle
                | FAttack::MisalignedHandle => Some(BINGHAM_ERR_NULL_ARGUMENT),
                FAttack::NonFinite(_) => Some(BINGHAM_ERR_INVALID_ARGUMENT),
                _ => None,
            }
        };
        if let Some(w) = want {
            if st != w {
                return Err(format!(
                    "bingham_filter_new: status {} instead of {}",
                    status_name(st),
                    status_name(w)
                ));
            }
        }
        if st != BINGHAM_OK {
            if out[0] != handle_sentinel() {
                return Err("bingham_filter_new wrote *out on error".into());
            }
            check_error_message("bingham_filter_new")?;
            // retry with valid parameters so that the sequence has a filter
            let d = if rng.chance(0.5) { 2 } else { 4 };
            m0 = orthogonal(&mut rng, d);
            z0 = z_moderate(&mut rng, d);
            // SAFETY: valid buffers.
            let st = unsafe { bingham_filter_new(d, m0.as_ptr(), z0.as_ptr(), out.as_mut_ptr()) };
            if st != BINGHAM_OK {
                return Err(format!(
                    "bingham_filter_new with valid parameters: {}",
                    last_error()
                ));
            }
        } else {
            m0 = args.arrays[0].clone();
            z0 = args.arrays[1].clone();
        }
    }
    let mut f = out[0];
    let d = m0.len().isqrt();
    let mut twin: *mut bingham_filter = std::ptr::null_mut();
    // SAFETY: the same (valid) parameters.
    let st = unsafe { bingham_filter_new(d, m0.as_ptr(), z0.as_ptr(), &mut twin) };
    if st != BINGHAM_OK {
        return Err(format!("twin creation failed: {}", last_error()));
    }
    let (m, z) = filter_state(f, d);
    check_state(&m, &z, d).map_err(|e| format!("new: state invalid: {e}"))?;

    // noises reused during the sequence (exercising the caches) and fresh ones
    let pool: Vec<(Vec<f64>, Vec<f64>)> = (0..3).map(|_| filter_noise(&mut rng, d)).collect();
    let steps = 1 + rng.below(40);
    let mut result = Ok(());
    for step in 0..steps {
        let op = match rng.below(25) {
            0..=5 => 0,
            6..=7 => 1,
            8..=13 => 2,
            14 => 3,
            15..=16 => 4,
            17 => 5,
            18 => 6,
            20..=21 => 9,
            22..=23 => 10,
            24 => 11,
            _ => {
                if rng.chance(0.5) {
                    7
                } else {
                    8
                }
            }
        };
        let name = FILTER_OPS[op];
        let (sm, _) = filter_state(f, d);
        let noise = if rng.chance(0.8) {
            pool[rng.below(pool.len())].clone()
        } else {
            filter_noise(&mut rng, d)
        };
        let mut a = match op {
            0 => FArgs {
                arrays: vec![noise.0, noise.1],
                kinds: vec![M, Z],
                attack: FAttack::None,
                desc: String::new(),
            },
            1 => FArgs {
                arrays: vec![unit_vector(&mut rng, d), noise.0, noise.1],
                kinds: vec![U, M, Z],
                attack: FAttack::None,
                desc: String::new(),
            },
            2 | 4 => FArgs {
                arrays: vec![filter_measurement(&mut rng, &sm, d), noise.0, noise.1],
                kinds: vec![U, M, Z],
                attack: FAttack::None,
                desc: String::new(),
            },
            3 => FArgs {
                arrays: vec![orthogonal(&mut rng, d), z_vector(&mut rng, d)],
                kinds: vec![M, Z],
                attack: FAttack::None,
                desc: String::new(),
            },
            9 | 10 => {
                let body = direction(&mut rng);
                // the reference: unrelated, equal, or opposite to the measured direction
                let reference = match rng.below(4) {
                    0 => body.clone(),
                    1 => body.iter().map(|v| -v).collect(),
                    _ => direction(&mut rng),
                };
                FArgs {
                    arrays: vec![body, reference, vec![vector_kappa(&mut rng)]],
                    kinds: vec![U, U, One],
                    attack: FAttack::None,
                    desc: String::new(),
                }
            }
            _ => FArgs {
                arrays: vec![],
                kinds: vec![],
                attack: FAttack::None,
                desc: String::new(),
            },
        };
        spoil_filter_args(&mut rng, &mut a, d);
        // outputs: array outputs count as argument indices after the inputs
        let out_kinds: &[Kind] = match op {
            4 | 10 => &[One],
            5 => &[DD, D],
            6 | 11 => &[D],
            _ => &[],
        };
        let n_args = a.arrays.len() + out_kinds.len() + usize::from(op == 7 || op == 8);
        if matches!(a.attack, FAttack::None) && op >= 4 && op != 9 && rng.chance(0.25) {
            let i = a.arrays.len() + rng.below(n_args - a.arrays.len());
            a.attack = if rng.chance(0.5) {
                FAttack::Null(i)
            } else {
                FAttack::Misaligned(i)
            };
        }
        if matches!(a.attack, FAttack::None) && op >= 5 && rng.chance(0.1) {
            a.attack = if rng.chance(0.5) {
                FAttack::NullHandle
            } else {
                FAttack::MisalignedHandle
            };
        }
        let mut outs: Vec<Buf> = out_kinds
            .iter()
            .map(|&k| Buf::sentinel(kind_len(k, d, 0)))
            .collect();
        let mut out_ptr = [handle_sentinel()];
        let mut out_dim = [usize::MAX; 2];
        let before = state_bits(f, d);
        prime_last_error(name);
        if verbose {
            eprintln!(
                "step {step}: {name} {:?} attack {:?} {}",
                a.arrays, a.attack, a.desc
            );
        }
        // SAFETY: f is live with dimension d; arrays have the lengths for d.
        let st = unsafe { filter_call(op, f, &a, &mut outs, &mut out_ptr, &mut out_dim) };
        calls += 1;
        count(stats, name, st);
        if verbose {
            eprintln!(
                "    -> {}, state z = {:?}",
                status_name(st),
                filter_state(f, d).1
            );
        }
        let ctx = format!("step {step} {name} (attack {:?} {})", a.attack, a.desc);
        let fail = |msg: String| Err(format!("{ctx}: {msg}"));
        if st == BINGHAM_ERR_PANIC {
            result = fail(format!("panic: {}", last_error()));
            break;
        }
        let want = match a.attack {
            FAttack::NullHandle
            | FAttack::MisalignedHandle
            | FAttack::Null(_)
            | FAttack::Misaligned(_) => Some(BINGHAM_ERR_NULL_ARGUMENT),
            FAttack::NonFinite(_) => Some(BINGHAM_ERR_INVALID_ARGUMENT),
            _ => None,
        };
        if let Some(w) = want {
            if st != w {
                result = fail(format!(
                    "status {} instead of {}",
                    status_name(st),
                    status_name(w)
                ));
                break;
            }
        }
        let after = state_bits(f, d);
        if st != BINGHAM_OK {
            if after != before {
                result = fail(format!(
                    "failed with {} but changed the state",
                    status_name(st)
                ));
                break;
            }
            if outs.iter().any(|b| !b.untouched())
                || out_ptr[0] != handle_sentinel()
                || out_dim != [usize::MAX; 2]
            {
                result = fail(format!(
                    "failed with {} but wrote an output",
                    status_name(st)
                ));
                break;
            }
            if let Err(e) = check_error_message(name) {
                result = fail(e);
                break;
            }
            if (op == 9 || op == 10) && d == 2 && matches!(a.attack, FAttack::None) {
                // a d = 2 filter has no orientation to observe a direction with
                if st != BINGHAM_ERR_INVALID_DIMENSION {
                    result = fail(format!(
                        "d = 2: {} instead of INVALID_DIMENSION",
                        status_name(st)
                    ));
                    break;
                }
                continue;
            }
            if matches!(a.attack, FAttack::None) && op != 3 {
                // valid arguments: the documented failures are NOT_CONVERGED / NUMERICAL only
                if st != BINGHAM_ERR_NOT_CONVERGED && st != BINGHAM_ERR_NUMERICAL {
                    result = fail(format!("valid arguments refused: {}", last_error()));
                    break;
                }
                if verbose {
                    eprintln!("    {}", last_error());
                }
            }
            continue;
        }
        // success
        if (op == 9 || op == 10) && d == 2 {
            result = fail("OK from a d = 2 filter".into());
            break;
        }
        if op >= 4 && op != 9 && after != before {
            result = fail("a read-only call changed the state".into());
            break;
        }
        let (m, z) = filter_state(f, d);
        if let Err(e) = check_state(&m, &z, d) {
            result = fail(format!("state invalid after success: {e}"));
            break;
        }
        match op {
            4 | 10 => {
                let v = outs[0].values()[0];
                if !v.is_finite() || !outs[0].guards_ok() {
                    result = fail(format!("log-likelihood {v}"));
                    break;
                }
            }
            11 => {
                let v = outs[0].values();
                let k = if d == 4 { 2.0 } else { 1.0 };
                // per axis and total: finite, in [0, k], the squares of the parts add up
                let parts: f64 = v[..d - 1].iter().map(|x| x * x).sum();
                if !outs[0].guards_ok()
                    || v.iter().any(|x| !x.is_finite() || *x < 0.0 || *x > k)
                    || (parts - v[d - 1] * v[d - 1]).abs() > 1e-9 * (v[d - 1] * v[d - 1]) + 1e-300
                {
                    result = fail(format!("angular spread {v:?}"));
                    break;
                }
            }
            5 => {
                let got: Vec<u64> = outs[0]
                    .values()
                    .iter()
                    .chain(&outs[1].values())
                    .map(|v| v.to_bits())
                    .collect();
                if got != after || !outs[0].guards_ok() || !outs[1].guards_ok() {
                    result = fail("get_state output differs from the state".into());
                    break;
                }
            }
            6 => {
                let v = outs[0].values();
                let col: Vec<f64> = (0..d).map(|r| m[r * d + d - 1]).collect();
                if v.iter().zip(&col).any(|(a, b)| a.to_bits() != b.to_bits())
                    || !outs[0].guards_ok()
                {
                    result = fail(format!("mode {v:?} is not the last column of M {col:?}"));
                    break;
                }
            }
            7 if out_dim[0] != d || out_dim[1] != usize::MAX => {
                result = fail(format!("dim wrote {out_dim:?}"));
                break;
            }
            8 => {
                let c = out_ptr[0];
                if c.is_null() || c == handle_sentinel() {
                    result = fail("clone returned no handle".into());
                    break;
                }
                if state_bits(c, d) != after {
                    result = fail("clone differs from the original".into());
                    break;
                }
                // continue with the clone half of the time (the original is freed)
                // SAFETY: both are live handles; the one not kept is freed once.
                unsafe {
                    if rng.chance(0.5) {
                        bingham_filter_free(f);
                        f = c;
                    } else {
                        bingham_filter_free(c);
                    }
                }
            }
            _ => {}
        }
        // the twin repeats the successful call (same arguments); states must agree bit for bit
        if op <= 3 || op == 9 {
            let mut twin_outs: Vec<Buf> = vec![];
            let mut tp = [handle_sentinel()];
            let mut td = [usize::MAX; 2];
            // SAFETY: twin is live with dimension d.
            let st2 = unsafe { filter_call(op, twin, &a, &mut twin_outs, &mut tp, &mut td) };
            if st2 != BINGHAM_OK {
                result = fail(format!("twin failed: {}", last_error()));
                break;
            }
        }
        if state_bits(twin, d) != state_bits(f, d) {
            result = fail("the twin (which saw only the successful calls) differs: a failed call changed hidden state".into());
            break;
        }
    }
    // SAFETY: live handles, freed once; free(NULL) is a no-op.
    unsafe {
        bingham_filter_free(f);
        bingham_filter_free(twin);
        bingham_filter_free(std::ptr::null_mut());
    }
    result.map(|()| calls)
}

#[test]
fn fuzz_filter_sequences() {
    // each sequence makes ~20 calls on average: count calls, not sequences
    let mut stats: BTreeMap<String, u64> = BTreeMap::new();
    run_sequences(
        "bingham_filter",
        "filter",
        99,
        cases_for(1.0, 1.0, SHARE_FILTER),
        |seed, verbose| filter_sequence(seed, verbose, &mut stats),
    );
    if stats_wanted() {
        eprintln!("bingham_filter statuses: {stats:?}");
    }
}

/// Runs random call sequences until `target` calls were made (or the one sequence named by
/// `BINGHAM_FUZZ_REPRO=label:seed`), collecting up to 20 failures with their reproduction line.
/// `sequence(seed, verbose)` returns the number of calls it made. `tag` keeps the seeds of
/// different harnesses apart.
fn run_sequences(
    label: &'static str,
    test: &str,
    tag: u64,
    target: u64,
    mut sequence: impl FnMut(u64, bool) -> Result<u64, String>,
) {
    let slot = CaseSlot::new(label);
    if let Some((l, seed)) = repro() {
        if l == label {
            slot.enter(seed);
            let r = sequence(seed, true);
            slot.leave();
            match r {
                Ok(n) => eprintln!("{label} case seed {seed}: passed ({n} calls)"),
                Err(e) => panic!("{label} case seed {seed}: {e}"),
            }
        }
        return;
    }
    let start = Instant::now();
    let (mut calls, mut i) = (0u64, 0u64);
    let mut failures = Vec::new();
    while calls < target {
        let seed = mix(base_seed() ^ (tag << 48) ^ i);
        i += 1;
        slot.enter(seed);
        let r = sequence(seed, false);
        slot.leave();
        match r {
            Ok(n) => calls += n,
            Err(e) => {
                calls += 1;
                if failures.len() < 20 {
                    failures.push(format!(
                        "  {label} case seed {seed}: {e}\n    reproduce: BINGHAM_FUZZ_REPRO={label}:{seed} \
                         cargo test --release --test fuzz_ffi fuzz_{test} -- --nocapture"
                    ));
                }
            }
        }
    }
    if stats_wanted() {
        let t = start.elapsed().as_secs_f64();
        eprintln!(
            "{label:<48} {calls:>9} calls ({i} sequences) {t:>8.2} s {:>9.1} µs/call",
            t * 1e6 / calls.max(1) as f64
        );
    }
    assert!(
        failures.is_empty(),
        "{} {test} sequences failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

// ---- vector observations, rotation noise, angular spread ---------------------------------------
//
// Scalar arguments (kappa, sigma) do not fit the table above: each function has its own case
// generator. Every case checks the status the header prescribes where the arguments determine
// it, that errors write nothing and name the function, that inputs stay unchanged, and the
// invariants of a successful result.

/// Share of `BINGHAM_FUZZ_CASES` for these three functions (on top of the shares above) and for
/// the AHRS calls.
const SHARE_VECTOR: f64 = 0.06;
const SHARE_AHRS: f64 = 0.05;

/// `R(q) v` for a unit quaternion q (scalar first), with the tests' textbook `R(q)`.
fn rotate(q: &[f64], v: &[f64]) -> [f64; 3] {
    let r = common::rot(&[q[0], q[1], q[2], q[3]]);
    [0, 1, 2].map(|i| r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2])
}

/// Calls `call` with input buffers (optionally NULL / misaligned) and sentinel outputs; checks
/// the generic contract and returns the status and the outputs' values.
struct Pointers {
    /// per input: None = valid, Some(0) = NULL, Some(k) = misaligned by k bytes
    inputs: Vec<Option<usize>>,
    outputs: Vec<Option<usize>>,
    /// all array pointers dangling (an invalid d must be refused first)
    dangling: bool,
}

fn run_arrays(
    name: &str,
    inputs: &[Vec<f64>],
    out_lens: &[usize],
    ptrs: &Pointers,
    call: impl FnOnce(&[*const f64], &[*mut f64]) -> bingham_status,
) -> Result<(bingham_status, Vec<Vec<f64>>), String> {
    let mut ib: Vec<Buf> = inputs.iter().map(|v| Buf::from(v)).collect();
    let mut ob: Vec<Buf> = out_lens.iter().map(|&n| Buf::sentinel(n)).collect();
    let before: Vec<Vec<u64>> = ib.iter().map(Buf::bits).collect();
    let pick = |b: &mut Buf, how: Option<usize>| match how {
        _ if ptrs.dangling => dangling(),
        None => b.ptr(),
        Some(0) => std::ptr::null_mut(),
        Some(k) => b.misaligned(k),
    };
    let ip: Vec<*const f64> = ib
        .iter_mut()
        .zip(&ptrs.inputs)
        .map(|(b, &h)| pick(b, h) as *const f64)
        .collect();
    let op: Vec<*mut f64> = ob
        .iter_mut()
        .zip(&ptrs.outputs)
        .map(|(b, &h)| pick(b, h))
        .collect();
    prime_last_error(name);
    let st = call(&ip, &op);
    let code = status_code(st);
    if !(0..=7).contains(&code) || st == BINGHAM_ERR_PANIC || st == BINGHAM_ERR_CALLBACK {
        return Err(format!("status {code}: {}", last_error()));
    }
    for (i, b) in ib.iter().enumerate() {
        if b.bits() != before[i] {
            return Err(format!("input {i} was modified"));
        }
    }
    if st != BINGHAM_OK {
        if ob.iter().any(|b| !b.untouched()) {
            return Err(format!("{} but an output was written", status_name(st)));
        }
        check_error_message(name)?;
        return Ok((st, vec![]));
    }
    for (i, b) in ob.iter().enumerate() {
        if !b.guards_ok() || !b.fully_written() {
            return Err(format!("output {i}: not exactly its length written"));
        }
        if let Some(v) = b.values().iter().find(|v| !v.is_finite()) {
            return Err(format!("output {i} holds {v}"));
        }
    }
    Ok((st, ob.iter().map(Buf::values).collect()))
}

/// NULL (Some(0)) or misaligned (Some(1..8)) for one of `n` pointers, else all valid.
fn pointer_attack(rng: &mut Rng, n: usize, p: f64) -> (Vec<Option<usize>>, bool) {
    let mut v = vec![None; n];
    if rng.chance(p) {
        v[rng.below(n)] = Some(if rng.chance(0.6) { 0 } else { 1 + rng.below(7) });
        return (v, true);
    }
    (v, false)
}

fn expect(st: bingham_status, want: Option<bingham_status>, what: &str) -> Result<(), String> {
    match want {
        Some(w) if w != st => Err(format!(
            "{what}: status {} where the header prescribes {} ({})",
            status_name(st),
            status_name(w),
            if st == BINGHAM_OK {
                String::new()
            } else {
                last_error()
            }
        )),
        _ => Ok(()),
    }
}

fn vector_observation_case(seed: u64, verbose: bool) -> Result<&'static str, String> {
    let mut rng = Rng::new(seed);
    let mut body = direction(&mut rng);
    let mut reference = if rng.chance(0.2) {
        body.iter()
            .map(|v| if rng.chance(0.5) { *v } else { -*v })
            .collect()
    } else {
        direction(&mut rng)
    };
    let mut kappa = vector_kappa(&mut rng);
    let (pins, mut pa) = pointer_attack(&mut rng, 4, 0.1);
    let mut want = pa.then_some(BINGHAM_ERR_NULL_ARGUMENT);
    let mut clean = !pa;
    let mut what = format!("pointers {pins:?}");
    if !pa {
        match rng.below(8) {
            0 => {
                let v = if rng.chance(0.5) {
                    &mut body
                } else {
                    &mut reference
                };
                v[rng.below(3)] = non_finite(&mut rng);
                want = Some(BINGHAM_ERR_INVALID_ARGUMENT);
                what = "non-finite vector".into();
            }
            1 => {
                kappa = if rng.chance(0.5) {
                    non_finite(&mut rng)
                } else {
                    -rng.log_uniform(-320.0, 308.0)
                };
                want = Some(BINGHAM_ERR_INVALID_ARGUMENT);
                what = format!("kappa = {kappa:e}");
            }
            2 => {
                let v = if rng.chance(0.5) {
                    &mut body
                } else {
                    &mut reference
                };
                what = spoil(&mut rng, U, v, 3);
                clean = false;
            }
            3 => {
                kappa = extreme(&mut rng);
                if !(0.0..=f64::MAX / 2.0).contains(&kappa) {
                    want = Some(BINGHAM_ERR_INVALID_ARGUMENT);
                }
                clean = false;
                what = format!("kappa = {kappa:e}");
            }
            _ => {}
        }
    }
    pa = pa || want.is_some();
    if verbose {
        eprintln!("body {body:?} reference {reference:?} kappa {kappa:e} {what}");
    }
    let ptrs = Pointers {
        inputs: pins[..2].to_vec(),
        outputs: pins[2..].to_vec(),
        dangling: false,
    };
    let name = "bingham_vector_observation";
    let r = run_arrays(
        name,
        &[body.clone(), reference.clone()],
        &[16, 4],
        &ptrs,
        |i, o| {
            // SAFETY: 3 readable doubles each (or NULL / misaligned), 16 and 4 writable doubles.
            unsafe { bingham_vector_observation(i[0], i[1], kappa, o[0], o[1]) }
        },
    );
    let (st, outs) = r?;
    expect(st, want, &what)?;
    if st != BINGHAM_OK {
        if clean && !pa && kappa <= 1e300 {
            return Err(format!("valid arguments refused: {}", last_error()));
        }
        return Ok(status_name(st));
    }
    let (m, z) = (&outs[0], &outs[1]);
    let e = orthogonality_error(m, 4);
    if e.is_nan() || e > STATE_TOL {
        return Err(format!("M not orthogonal: {e:e}"));
    }
    if z != &[-2.0 * kappa, -2.0 * kappa, 0.0, 0.0] {
        return Err(format!("z = {z:?} for kappa = {kappa:e}"));
    }
    // the exponent: qᵀ M Z Mᵀ q = kappa (rᵀ R(q) b − 1) for (normalized) b, r
    let (nb, nr) = (norm(&body), norm(&reference));
    let b: Vec<f64> = body.iter().map(|v| v / nb).collect();
    let r: Vec<f64> = reference.iter().map(|v| v / nr).collect();
    for _ in 0..3 {
        let q = unit_vector(&mut rng, 4);
        let lhs: f64 = (0..4)
            .map(|c| {
                let p: f64 = (0..4).map(|k| m[k * 4 + c] * q[k]).sum();
                z[c] * p * p
            })
            .sum();
        let rb = rotate(&q, &b);
        let rhs = kappa * (rb[0] * r[0] + rb[1] * r[1] + rb[2] * r[2] - 1.0);
        if (lhs - rhs).abs() > 1e-11 * kappa.max(1e-300) {
            return Err(format!("exponent {lhs:e} vs kappa (rᵀRb − 1) = {rhs:e}"));
        }
    }
    Ok("OK")
}

fn noise_case(seed: u64, verbose: bool) -> Result<&'static str, String> {
    let mut rng = Rng::new(seed);
    let d = if rng.chance(0.1) {
        *rng.pick(&[0usize, 1, 3, 5, 64, 65, usize::MAX])
    } else if rng.chance(0.5) {
        2
    } else {
        4
    };
    let bad_d = d != 2 && d != 4;
    let (sigma, mut want, mut must) = match rng.below(8) {
        0 => (rng.log_uniform(-6.0, 0.5), None, true),
        1 => (rng.log_uniform(-9.0, -6.0), None, false), // near the documented limit
        2 => (rng.log_uniform(0.5, 300.0), None, true),
        3 => (
            non_finite(&mut rng),
            Some(BINGHAM_ERR_INVALID_ARGUMENT),
            false,
        ),
        4 => (
            -rng.log_uniform(-320.0, 300.0) * f64::from(u8::from(rng.chance(0.9))),
            Some(BINGHAM_ERR_INVALID_ARGUMENT),
            false,
        ),
        5 => {
            let s = extreme(&mut rng);
            let want = (s <= 0.0).then_some(BINGHAM_ERR_INVALID_ARGUMENT);
            (s, want, s >= 1e-6)
        }
        _ => (rng.range(1e-3, 3.0), None, true),
    };
    let (pouts, pa) = pointer_attack(&mut rng, 2, 0.1);
    if pa {
        want = Some(BINGHAM_ERR_NULL_ARGUMENT);
        must = false;
    }
    if bad_d {
        want = Some(BINGHAM_ERR_INVALID_DIMENSION);
    }
    if verbose {
        eprintln!("d = {d}, sigma = {sigma:e}, pointers {pouts:?}");
    }
    let len = if bad_d { 1 } else { d };
    let ptrs = Pointers {
        inputs: vec![],
        outputs: pouts,
        dangling: bad_d && rng.chance(0.5),
    };
    let name = "bingham_noise_from_angle_std";
    let (st, outs) = run_arrays(name, &[], &[len * len, len], &ptrs, |_, o| {
        // SAFETY: d*d and d writable doubles, or dangling with an invalid d (refused first).
        unsafe { bingham_noise_from_angle_std(d, sigma, o[0], o[1]) }
    })?;
    expect(st, want, &format!("d = {d}, sigma = {sigma:e}"))?;
    if st != BINGHAM_OK {
        if must && !bad_d {
            return Err(format!(
                "sigma = {sigma:e} (d = {d}) refused: {}",
                last_error()
            ));
        }
        return Ok(status_name(st));
    }
    let (m, z) = (&outs[0], &outs[1]);
    check_state(m, z, d)?;
    // (a uniform result, z = 0, e.g. d = 2 with sigma > 4, has no distinguished mode)
    if z[0] != 0.0 && (0..d).any(|r| m[r * d + d - 1] != if r == 0 { 1.0 } else { 0.0 }) {
        return Err(format!("the mode is not the identity: M = {m:?}"));
    }
    // the second moment: E[x_0²] = (1 + E cos θ)/2, E cos θ = (1 − σ²) e^{−σ²/2} (d = 4),
    // e^{−2σ²} (d = 2)
    if (1e-4..=100.0).contains(&sigma) {
        let s2 = sigma * sigma;
        let c = if d == 4 {
            0.5 * (1.0 + (1.0 - s2) * (-0.5 * s2).exp())
        } else {
            0.5 * (1.0 + (-2.0 * s2).exp())
        };
        let mut s = vec![0.0; d * d];
        // SAFETY: valid buffers.
        let st = unsafe { bingham_second_moment(d, m.as_ptr(), z.as_ptr(), s.as_mut_ptr()) };
        if st != BINGHAM_OK {
            return Err(format!("second moment of the result: {}", last_error()));
        }
        if (s[0] - c).abs() > 1e-9 {
            return Err(format!("E[x_0²] = {} instead of {c}", s[0]));
        }
    }
    Ok("OK")
}

fn angular_spread_case(seed: u64, verbose: bool) -> Result<&'static str, String> {
    let mut rng = Rng::new(seed);
    let d = if rng.chance(0.08) {
        *rng.pick(&[0usize, 1, 3, 5, 64, 65, usize::MAX])
    } else if rng.chance(0.5) {
        2
    } else {
        4
    };
    let bad_d = d != 2 && d != 4;
    let dl = if bad_d { 2 } else { d };
    let moderate = rng.chance(0.5);
    let mut m = orthogonal(&mut rng, dl);
    let mut z = if moderate {
        z_moderate(&mut rng, dl)
    } else {
        z_vector(&mut rng, dl)
    };
    let (pins, pa) = pointer_attack(&mut rng, 3, 0.1);
    let mut want = pa.then_some(BINGHAM_ERR_NULL_ARGUMENT);
    let mut clean = moderate && !pa;
    if !pa {
        match rng.below(8) {
            0 => {
                let v = if rng.chance(0.5) { &mut m } else { &mut z };
                let i = rng.below(v.len());
                v[i] = non_finite(&mut rng);
                want = Some(BINGHAM_ERR_INVALID_ARGUMENT);
                clean = false;
            }
            1 => {
                spoil(&mut rng, M, &mut m, dl);
                clean = false;
            }
            2 => {
                spoil(&mut rng, Z, &mut z, dl);
                clean = false;
            }
            _ => {}
        }
    }
    if bad_d {
        want = Some(BINGHAM_ERR_INVALID_DIMENSION);
    }
    if verbose {
        eprintln!("d = {d}, m = {m:?}, z = {z:?}, pointers {pins:?}");
    }
    let ptrs = Pointers {
        inputs: pins[..2].to_vec(),
        outputs: pins[2..].to_vec(),
        dangling: bad_d && rng.chance(0.5),
    };
    let name = "bingham_angular_spread";
    let (st, outs) = run_arrays(name, &[m, z], &[dl], &ptrs, |i, o| {
        // SAFETY: d*d and d readable, d writable doubles (dangling only with an invalid d).
        unsafe { bingham_angular_spread(d, i[0], i[1], o[0]) }
    })?;
    expect(st, want, &format!("d = {d}"))?;
    if st != BINGHAM_OK {
        if clean && !bad_d {
            return Err(format!("valid arguments refused: {}", last_error()));
        }
        return Ok(status_name(st));
    }
    let v = &outs[0];
    let k = if d == 4 { 2.0 } else { 1.0 };
    let parts: f64 = v[..d - 1].iter().map(|x| x * x).sum();
    let total = v[d - 1] * v[d - 1];
    // all ≥ 0; at most the uniform distribution's total k √(1 − 1/d)
    if v.iter().any(|x| *x < 0.0) || v[d - 1] > k * (1.0 - 1.0 / d as f64).sqrt() * (1.0 + 1e-12) {
        return Err(format!("spread {v:?} out of range"));
    }
    if (parts - total).abs() > 1e-9 * total + 1e-300 {
        return Err(format!("Σ per-axis² = {parts:e} ≠ total² = {total:e}"));
    }
    Ok("OK")
}

#[test]
fn fuzz_vector_observation() {
    let n = cases_for(1.0, 3.0, SHARE_VECTOR);
    drive("bingham_vector_observation", 40, n, vector_observation_case);
}

#[test]
fn fuzz_noise_from_angle_std() {
    let n = cases_for(1.0, 3.0, SHARE_VECTOR);
    drive("bingham_noise_from_angle_std", 41, n, noise_case);
}

#[test]
fn fuzz_angular_spread() {
    let n = cases_for(1.0, 3.0, SHARE_VECTOR);
    drive("bingham_angular_spread", 42, n, angular_spread_case);
}

// ---- the AHRS: random sample streams ------------------------------------------------------------
//
// One case is an AHRS (sample time sometimes hostile) fed a simulated IMU stream through
// bingham_ahrs_update and the batch functions, with hostile samples mixed in (NaN/Inf, zero and
// huge vectors, subnormals, NULL and misaligned pointers, a NaN in the middle of a batch) and
// bingham_ahrs_set_state calls (valid starts near the truth, any orthogonal M, huge / tiny /
// repeated z, z spanning more than a double, non-orthogonal M, NaN/Inf), and a twin that
// receives only the calls that were accepted. After every call: a refused call leaves the AHRS
// bit-for-bit unchanged (quaternion, state, bias, spread, and the hidden state, through the
// twin) and the message names the function (and for a batch the sample); accepted calls leave a
// unit quaternion with w ≥ 0, a valid Bingham state, finite bias and spread; after set_state
// the state is the normalized Bingham(M, z) and the quaternion ± its mode.

fn ahrs_sentinel() -> *mut bingham_ahrs {
    0xDEAD_BEE0usize as *mut bingham_ahrs
}

/// Everything the getters show, as bits: q (4), M (16), z (4), bias (3), spread (4).
fn ahrs_bits(a: *const bingham_ahrs) -> Result<Vec<u64>, String> {
    let (mut q, mut m, mut z, mut b, mut s) = ([0.0; 4], [0.0; 16], [0.0; 4], [0.0; 3], [0.0; 4]);
    // SAFETY: a is live; buffers of the documented lengths.
    let sts = unsafe {
        [
            bingham_ahrs_quaternion(a, q.as_mut_ptr()),
            bingham_ahrs_state(a, m.as_mut_ptr(), z.as_mut_ptr()),
            bingham_ahrs_gyro_bias(a, b.as_mut_ptr()),
        ]
    };
    if sts.iter().any(|&st| st != BINGHAM_OK) {
        return Err(format!("a getter failed: {}", last_error()));
    }
    // SAFETY: as above.
    let st = unsafe { bingham_ahrs_angular_spread(a, s.as_mut_ptr()) };
    if st != BINGHAM_OK {
        // log F is total for every finite z: the moments of any valid state can be evaluated.
        return Err(format!("angular spread failed: {}", last_error()));
    }
    check_unit(&q, 1e-12).map_err(|e| format!("quaternion {q:?}: {e}"))?;
    if q[0] < 0.0 {
        return Err(format!("quaternion {q:?} with w < 0"));
    }
    check_state(&m, &z, 4).map_err(|e| format!("AHRS state: {e}"))?;
    if b.iter()
        .chain(&s)
        .any(|v| !v.is_finite() || (s.contains(v) && *v < 0.0))
    {
        return Err(format!("bias {b:?} / spread {s:?}"));
    }
    Ok(q.iter()
        .chain(&m)
        .chain(&z)
        .chain(&b)
        .chain(&s)
        .map(|v| v.to_bits())
        .collect())
}

/// A simulated IMU: a true orientation turning with a random smooth rate; gravity up, a field
/// pointing north and down (ENU), plus noise and occasional linear accelerations.
struct Imu {
    q: [f64; 4],
    w: [f64; 3],
}

impl Imu {
    fn sample(&mut self, rng: &mut Rng, dt: f64) -> [[f64; 3]; 3] {
        for w in self.w.iter_mut() {
            *w = 0.98 * *w + 0.1 * rng.normal();
        }
        let dt = if dt.is_finite() { dt.min(0.1) } else { 0.01 };
        let h = 0.5 * dt;
        let dq = [1.0, h * self.w[0], h * self.w[1], h * self.w[2]];
        let q = self.q;
        let mut p = [
            q[0] * dq[0] - q[1] * dq[1] - q[2] * dq[2] - q[3] * dq[3],
            q[0] * dq[1] + q[1] * dq[0] + q[2] * dq[3] - q[3] * dq[2],
            q[0] * dq[2] - q[1] * dq[3] + q[2] * dq[0] + q[3] * dq[1],
            q[0] * dq[3] + q[1] * dq[2] - q[2] * dq[1] + q[3] * dq[0],
        ];
        let n = norm(&p);
        p.iter_mut().for_each(|v| *v /= n);
        self.q = p;
        let conj = [p[0], -p[1], -p[2], -p[3]];
        let lin = if rng.chance(0.05) { 3.0 } else { 0.0 };
        let acc = rotate(&conj, &[lin, 0.0, 9.81]);
        let mag = rotate(&conj, &[0.0, 20.0, -40.0]);
        let gyr = [0, 1, 2].map(|i| self.w[i] + 0.002 * rng.normal());
        [
            gyr,
            acc.map(|v| v + 0.05 * rng.normal()),
            mag.map(|v| v + 0.3 * rng.normal()),
        ]
    }
}

/// Spoils one entry or vector of a sample; returns whether it is non-finite (must be refused).
fn spoil_sample(rng: &mut Rng, s: &mut [[f64; 3]; 3]) -> (bool, String) {
    let v = rng.below(3);
    match rng.below(4) {
        0 | 1 => {
            let i = rng.below(3);
            s[v][i] = non_finite(rng);
            (true, format!("sample[{v}][{i}] = {}", s[v][i]))
        }
        2 => {
            let i = rng.below(3);
            s[v][i] = extreme(rng);
            (false, format!("sample[{v}][{i}] = {:e}", s[v][i]))
        }
        _ => {
            let f = *rng.pick(&[0.0, 1e-300, 5e-324, 1e154, 1e300, f64::MAX, -1.0]);
            s[v].iter_mut().for_each(|x| *x *= f);
            (false, format!("sample[{v}] *= {f:e}"))
        }
    }
}

/// Arguments of `bingham_ahrs_set_state`: M (4×4 row-major) and z, with a description.
/// Realistic (the mode at or near the true orientation, a start uncertainty) or hostile: any
/// orthogonal M, huge / tiny / subnormal / positive / repeated z, z spanning more than a double,
/// any order and shift, M not orthogonal (or within the tolerance), NaN/Inf entries.
fn ahrs_state_args(rng: &mut Rng, truth: &[f64; 4]) -> (Vec<f64>, Vec<f64>, String) {
    let mut desc = String::new();
    let mut m = match rng.below(4) {
        0 => identity(4),
        1 => orthogonal(rng, 4),
        _ => {
            // columns q⊗i, q⊗j, q⊗k, q (left multiplication by q): the mode is q
            let s = if rng.chance(0.5) {
                0.0
            } else {
                rng.log_uniform(-6.0, 0.0)
            };
            let q: Vec<f64> = truth.iter().map(|v| v + s * rng.normal()).collect();
            let n = norm(&q);
            let [w, x, y, z] = [0, 1, 2, 3].map(|i| q[i] / n);
            let l = [[w, -x, -y, -z], [x, w, -z, y], [y, z, w, -x], [z, -y, x, w]];
            (0..16).map(|k| l[k / 4][(k % 4 + 1) % 4]).collect()
        }
    };
    let mut z: Vec<f64> = match rng.below(8) {
        0..=3 => {
            // a start uncertainty: the last column the most concentrated
            let k = rng.log_uniform(-1.0, 7.0);
            (0..4)
                .map(|i| {
                    if i == 3 {
                        0.0
                    } else {
                        -k * rng.range(0.5, 2.0)
                    }
                })
                .collect()
        }
        4 => z_vector(rng, 4),
        5 => (0..4)
            .map(|_| {
                *rng.pick(&[
                    -f64::MAX,
                    -1e300,
                    -1e200,
                    -1e15,
                    -1e-300,
                    -5e-324,
                    -0.0,
                    0.0,
                    5e-324,
                    1e300,
                    f64::MAX,
                ])
            })
            .collect(),
        6 => {
            // spanning about the largest double (beyond it: refused)
            let mut z = z_moderate(rng, 4);
            let i = rng.below(4);
            let j = (i + 1 + rng.below(3)) % 4;
            z[i] = *rng.pick(&[f64::MAX, 1e308, 9e307, 8.9e307]);
            z[j] = -*rng.pick(&[f64::MAX, 1e308, 9e307, 8.9e307, 1e300]);
            z
        }
        _ => vec![concentration(rng); 4], // uniform
    };
    if rng.chance(0.2) {
        let c = rng.range(-1e3, 1e3);
        z.iter_mut().for_each(|v| *v += c);
        desc += &format!("z += {c:e}; ");
    }
    if rng.chance(0.3) {
        // another order: the columns of M along
        let (i, j) = (rng.below(4), rng.below(4));
        z.swap(i, j);
        for r in 0..4 {
            m.swap(r * 4 + i, r * 4 + j);
        }
    }
    match rng.below(12) {
        0 => {
            let i = rng.below(16);
            m[i] = non_finite(rng);
            desc += &format!("M[{i}] = {}", m[i]);
        }
        1 => {
            let i = rng.below(4);
            z[i] = non_finite(rng);
            desc += &format!("z[{i}] = {}", z[i]);
        }
        2 | 3 => desc += &spoil(rng, M, &mut m, 4),
        _ => {}
    }
    (m, z, desc)
}

/// The status `bingham_ahrs_set_state` must return for valid pointers: `INVALID_ARGUMENT` for
/// NaN/Inf, M not orthogonal or z spanning more than a double, else `OK`; `None` where M is so
/// close to the orthogonality tolerance that rounding decides.
fn ahrs_state_expected(m: &[f64], z: &[f64]) -> Option<bingham_status> {
    if m.iter().chain(z).any(|v| !v.is_finite()) {
        return Some(BINGHAM_ERR_INVALID_ARGUMENT);
    }
    let e = orthogonality_error(m, 4);
    let mx = z.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let mn = z.iter().cloned().fold(f64::INFINITY, f64::min);
    if e.is_nan() || e > 2e-6 || !(mx - mn).is_finite() {
        Some(BINGHAM_ERR_INVALID_ARGUMENT)
    } else if e > 0.5e-6 {
        None
    } else {
        Some(BINGHAM_OK)
    }
}

/// After an accepted `bingham_ahrs_set_state(a, m, z)`: the state is the normalized
/// Bingham(m, z) (z sorted ascending and shifted to z[3] = 0, each column of M with its z, up
/// to sign and within groups of equal z), and the quaternion is ± the mode of Bingham(m, z),
/// exactly the last column of the state's M with w ≥ 0.
fn check_set_state(a: *const bingham_ahrs, m: &[f64], z: &[f64]) -> Result<(), String> {
    let (mut q, mut ms, mut zs) = ([0.0; 4], [0.0; 16], [0.0; 4]);
    // SAFETY: a is live; buffers of the documented lengths.
    let sts = unsafe {
        [
            bingham_ahrs_quaternion(a, q.as_mut_ptr()),
            bingham_ahrs_state(a, ms.as_mut_ptr(), zs.as_mut_ptr()),
        ]
    };
    if sts.iter().any(|&st| st != BINGHAM_OK) {
        return Err(format!("a getter failed: {}", last_error()));
    }
    let mut sorted = z.to_vec();
    sorted.sort_by(f64::total_cmp);
    let want_z: Vec<f64> = (0..4)
        .map(|k| if k == 3 { 0.0 } else { sorted[k] - sorted[3] })
        .collect();
    if zs.iter().zip(&want_z).any(|(a, b)| a != b) {
        return Err(format!("state z {zs:?}, expected {want_z:?}"));
    }
    let col = |m: &[f64], i: usize| -> Vec<f64> {
        let c: Vec<f64> = (0..4).map(|r| m[r * 4 + i]).collect();
        let n = norm(&c);
        c.iter().map(|v| v / n).collect()
    };
    let dot = |u: &[f64], v: &[f64]| -> f64 { u.iter().zip(v).map(|(a, b)| a * b).sum() };
    // |u|² within the span of the given columns whose z equals v (≈ 1 if u lies in it)
    let in_span = |u: &[f64], v: f64| -> f64 {
        (0..4)
            .filter(|&i| z[i] == v)
            .map(|i| dot(u, &col(m, i)).powi(2))
            .sum()
    };
    let tol = 1e-12 + 8.0 * orthogonality_error(m, 4);
    for (k, &v) in sorted.iter().enumerate() {
        let s = in_span(&col(&ms, k), v);
        if (s - 1.0).abs() > tol {
            return Err(format!(
                "state column {k} is not a principal direction of z = {v:e} (|proj|² = {s})"
            ));
        }
    }
    let c3: Vec<f64> = (0..4).map(|r| ms[r * 4 + 3]).collect();
    let want_q: Vec<f64> = if c3[0] < 0.0 {
        c3.iter().map(|v| -v).collect()
    } else {
        c3
    };
    if q.iter()
        .zip(&want_q)
        .any(|(a, b)| a.to_bits() != b.to_bits())
    {
        return Err(format!(
            "quaternion {q:?} is not ± the last column of the state's M {want_q:?}"
        ));
    }
    let s = in_span(&q, sorted[3]);
    if (s - 1.0).abs() > tol {
        return Err(format!(
            "quaternion {q:?} is not ± the mode of the given state (|proj|² = {s})"
        ));
    }
    Ok(())
}

fn ahrs_sequence(seed: u64, verbose: bool) -> Result<u64, String> {
    let mut rng = Rng::new(seed);
    let mut calls = 0u64;
    // --- parameters and creation, sometimes hostile (only sample_time is set by hand: the other
    // fields of bingham_ahrs_params may change)
    let dt = match rng.below(10) {
        0 => *rng.pick(&[0.0, -0.01, f64::NAN, f64::INFINITY, -f64::INFINITY]),
        1 => *rng.pick(&[1e-300, 5e-324, 1e-6, 10.0, 1e10, f64::MAX]),
        _ => *rng.pick(&[0.01, 0.005, 1.0 / 400.0, 0.02]),
    };
    let valid_dt = (1e-6..=1e3).contains(&dt);
    // SAFETY (all calls below): live handles and buffers of the documented lengths, or NULL /
    // misaligned pointers that must be refused before any access.
    let mut p: bingham_ahrs_params = unsafe { std::mem::zeroed() };
    let raw = |p: &bingham_ahrs_params| -> Vec<u8> {
        // SAFETY: a plain struct of doubles.
        unsafe {
            std::slice::from_raw_parts(
                (p as *const bingham_ahrs_params).cast::<u8>(),
                std::mem::size_of::<bingham_ahrs_params>(),
            )
        }
        .to_vec()
    };
    let before = raw(&p);
    prime_last_error("bingham_ahrs_params_default");
    let st = unsafe { bingham_ahrs_params_default(dt, &mut p) };
    calls += 1;
    if valid_dt != (st == BINGHAM_OK) || (!valid_dt && st != BINGHAM_ERR_INVALID_ARGUMENT) {
        return Err(format!("params_default({dt:e}): {}", status_name(st)));
    }
    if st != BINGHAM_OK {
        if raw(&p) != before {
            return Err("params_default wrote on error".into());
        }
        check_error_message("bingham_ahrs_params_default")?;
        // defaults for another period, then the hostile sample_time by hand
        let st = unsafe { bingham_ahrs_params_default(0.01, &mut p) };
        if st != BINGHAM_OK {
            return Err(format!("params_default(0.01): {}", last_error()));
        }
        p.sample_time = dt;
    } else if p.sample_time != dt {
        return Err(format!(
            "params_default: sample_time {} ≠ {dt}",
            p.sample_time
        ));
    }
    let mut out = [ahrs_sentinel()];
    let null_attack = rng.chance(0.05);
    prime_last_error("bingham_ahrs_new");
    let st = unsafe {
        if null_attack {
            if rng.chance(0.5) {
                bingham_ahrs_new(std::ptr::null(), out.as_mut_ptr())
            } else {
                bingham_ahrs_new(&p, std::ptr::null_mut())
            }
        } else {
            bingham_ahrs_new(&p, out.as_mut_ptr())
        }
    };
    calls += 1;
    let want = if null_attack {
        BINGHAM_ERR_NULL_ARGUMENT
    } else if !valid_dt {
        BINGHAM_ERR_INVALID_ARGUMENT
    } else {
        BINGHAM_OK
    };
    if st != want {
        return Err(format!(
            "bingham_ahrs_new (sample_time {dt:e}): {} instead of {} ({})",
            status_name(st),
            status_name(want),
            last_error()
        ));
    }
    if st != BINGHAM_OK {
        if out[0] != ahrs_sentinel() {
            return Err("bingham_ahrs_new wrote *out on error".into());
        }
        check_error_message("bingham_ahrs_new")?;
        if !null_attack && !last_error().contains("sample_time") {
            return Err(format!(
                "message does not name sample_time: {}",
                last_error()
            ));
        }
        let st = unsafe { bingham_ahrs_params_default(0.01, &mut p) };
        assert_eq!(st, BINGHAM_OK);
        let st = unsafe { bingham_ahrs_new(&p, out.as_mut_ptr()) };
        if st != BINGHAM_OK {
            return Err(format!("bingham_ahrs_new with defaults: {}", last_error()));
        }
    }
    let mut a = out[0];
    let mut twin: *mut bingham_ahrs = std::ptr::null_mut();
    if unsafe { bingham_ahrs_new(&p, &mut twin) } != BINGHAM_OK {
        return Err(format!("twin: {}", last_error()));
    }
    let dt = p.sample_time;
    if verbose {
        eprintln!("sample_time {dt:e}");
    }
    let mut imu = Imu {
        q: {
            let q = unit_vector(&mut rng, 4);
            if q[0] < 0.0 {
                [-q[0], -q[1], -q[2], -q[3]]
            } else {
                [q[0], q[1], q[2], q[3]]
            }
        },
        w: [0.0; 3],
    };
    let use_mag = rng.chance(0.8);
    let steps = 5 + rng.below(40);
    let mut result = Ok(());
    for step in 0..steps {
        let before = match ahrs_bits(a) {
            Ok(b) => b,
            Err(e) => {
                result = Err(format!("step {step}: {e}"));
                break;
            }
        };
        let r = rng.below(11);
        let res: Result<(), String> = (|| {
            if r < 6 {
                // --- one sample
                let mut s = imu.sample(&mut rng, dt);
                let (mut refuse, mut desc) = (false, String::new());
                if rng.chance(0.25) {
                    (refuse, desc) = spoil_sample(&mut rng, &mut s);
                }
                let mag_null = !use_mag || rng.chance(0.1);
                if refuse && mag_null && desc.starts_with("sample[2]") {
                    refuse = false; // the spoiled magnetometer is not passed
                }
                let mut bufs: Vec<Buf> = s.iter().map(|v| Buf::from(v)).collect();
                let mut ptr: Vec<*mut f64> = bufs.iter_mut().map(|b| b.ptr()).collect();
                if mag_null {
                    ptr[2] = std::ptr::null_mut();
                }
                let mut ap = a;
                let mut null = false;
                if rng.chance(0.05) {
                    null = true;
                    match rng.below(4) {
                        0 => ap = std::ptr::null_mut(),
                        1 => ptr[0] = std::ptr::null_mut(),
                        2 => ptr[1] = std::ptr::null_mut(),
                        _ => ptr[rng.below(2)] = bufs[0].misaligned(3),
                    }
                }
                prime_last_error("bingham_ahrs_update");
                let st = unsafe { bingham_ahrs_update(ap, ptr[0], ptr[1], ptr[2]) };
                calls += 1;
                if verbose {
                    eprintln!(
                        "step {step}: update {s:?} mag {} {desc} null {null} -> {}",
                        !mag_null,
                        status_name(st)
                    );
                }
                if st == BINGHAM_ERR_PANIC {
                    return Err(format!("panic: {}", last_error()));
                }
                let want = if null {
                    Some(BINGHAM_ERR_NULL_ARGUMENT)
                } else if refuse {
                    Some(BINGHAM_ERR_INVALID_ARGUMENT)
                } else {
                    None
                };
                expect(st, want, &desc)?;
                if st != BINGHAM_OK {
                    check_error_message("bingham_ahrs_update")?;
                    if ahrs_bits(a)? != before {
                        return Err(format!(
                            "refused sample ({}) changed the AHRS",
                            status_name(st)
                        ));
                    }
                    if !refuse && !null && desc.is_empty() && valid_dt && dt <= 0.1 {
                        return Err(format!("a clean sample refused: {}", last_error()));
                    }
                    return Ok(());
                }
                let st2 = unsafe { bingham_ahrs_update(twin, ptr[0], ptr[1], ptr[2]) };
                if st2 != BINGHAM_OK {
                    return Err(format!("twin refused an accepted sample: {}", last_error()));
                }
                ahrs_bits(a)?;
            } else if r < 8 {
                // --- a batch, possibly with a non-finite entry at sample k
                let n = rng.below(13);
                let mut g = vec![0.0; 3 * n];
                let mut ac = vec![0.0; 3 * n];
                let mut mg = vec![0.0; 3 * n];
                for k in 0..n {
                    let s = imu.sample(&mut rng, dt);
                    g[3 * k..3 * k + 3].copy_from_slice(&s[0]);
                    ac[3 * k..3 * k + 3].copy_from_slice(&s[1]);
                    mg[3 * k..3 * k + 3].copy_from_slice(&s[2]);
                }
                let mag_null = !use_mag;
                let bad = (n > 0 && rng.chance(0.4)).then(|| rng.below(n));
                if let Some(k) = bad {
                    let arr = match rng.below(if mag_null { 2 } else { 3 }) {
                        0 => &mut g,
                        1 => &mut ac,
                        _ => &mut mg,
                    };
                    arr[3 * k + rng.below(3)] = non_finite(&mut rng);
                }
                let with_spread = rng.chance(0.5);
                let spread_null = with_spread && rng.chance(0.3);
                let (mut bg, mut ba, mut bm) = (Buf::from(&g), Buf::from(&ac), Buf::from(&mg));
                let mut bq = Buf::sentinel(4 * n);
                let mut bs = Buf::sentinel(n);
                let mp = if mag_null {
                    std::ptr::null()
                } else {
                    bm.ptr() as *const f64
                };
                let sp = if spread_null {
                    std::ptr::null_mut()
                } else {
                    bs.ptr()
                };
                let name = if with_spread {
                    "bingham_ahrs_update_batch_spread"
                } else {
                    "bingham_ahrs_update_batch"
                };
                prime_last_error(name);
                let st = unsafe {
                    if with_spread {
                        bingham_ahrs_update_batch_spread(a, n, bg.ptr(), ba.ptr(), mp, bq.ptr(), sp)
                    } else {
                        bingham_ahrs_update_batch(a, n, bg.ptr(), ba.ptr(), mp, bq.ptr())
                    }
                };
                calls += 1;
                if verbose {
                    eprintln!(
                        "step {step}: {name} n = {n}, bad {bad:?} -> {}",
                        status_name(st)
                    );
                }
                if st == BINGHAM_ERR_PANIC {
                    return Err(format!("panic: {}", last_error()));
                }
                {
                    expect(
                        st,
                        bad.map(|_| BINGHAM_ERR_INVALID_ARGUMENT),
                        &format!("bad sample {bad:?}"),
                    )?;
                }
                // how many samples were processed
                let done = if st == BINGHAM_OK {
                    n
                } else {
                    check_error_message(name)?;
                    let msg = last_error();
                    let k = msg
                        .split("sample ")
                        .nth(1)
                        .and_then(|t| t.split(|c: char| !c.is_ascii_digit()).next())
                        .and_then(|t| t.parse::<usize>().ok())
                        .ok_or_else(|| format!("message does not name the sample: {msg}"))?;
                    if bad.is_some_and(|b| b != k) || k >= n {
                        return Err(format!(
                            "stopped at sample {k}, the bad one is {bad:?}: {msg}"
                        ));
                    }
                    k
                };
                let q = bq.values();
                let s = bs.values();
                if !bq.guards_ok() || !bs.guards_ok() {
                    return Err("guard words overwritten".into());
                }
                for k in 0..n {
                    let row = &q[4 * k..4 * k + 4];
                    if k < done {
                        check_unit(row, 1e-12).map_err(|e| format!("quat row {k}: {e}"))?;
                        if row[0] < 0.0 {
                            return Err(format!("quat row {k} with w < 0"));
                        }
                        if with_spread && !spread_null && !(s[k].is_finite() && s[k] >= 0.0) {
                            return Err(format!("spread[{k}] = {}", s[k]));
                        }
                    }
                }
                if !bq.untouched_range(4 * done, 4 * n) {
                    return Err(format!(
                        "quat rows from the refused sample {done} on were written"
                    ));
                }
                if (spread_null || !with_spread) && !bs.untouched() {
                    return Err("spread written although not passed".into());
                }
                if with_spread && !spread_null && !bs.untouched_range(done, n) {
                    return Err("spread written from the refused sample on".into());
                }
                // the twin replays the processed samples one by one
                for k in 0..done {
                    let st = unsafe {
                        bingham_ahrs_update(
                            twin,
                            g[3 * k..].as_ptr(),
                            ac[3 * k..].as_ptr(),
                            if mag_null {
                                std::ptr::null()
                            } else {
                                mg[3 * k..].as_ptr()
                            },
                        )
                    };
                    if st != BINGHAM_OK {
                        return Err(format!(
                            "twin refused sample {k} of an accepted batch: {}",
                            last_error()
                        ));
                    }
                }
                if done == 0 && ahrs_bits(a)? != before {
                    return Err("a batch refused at sample 0 changed the AHRS".into());
                }
            } else if r < 9 {
                // --- getters with NULL / misaligned arguments
                let which = rng.below(4);
                let null_handle = rng.chance(0.5);
                let mut buf = Buf::sentinel(16);
                let mut buf2 = Buf::sentinel(4);
                let op = if rng.chance(0.5) {
                    std::ptr::null_mut()
                } else {
                    buf.misaligned(4)
                };
                let (ap, o1, o2) = if null_handle {
                    (std::ptr::null(), buf.ptr(), buf2.ptr())
                } else if which == 1 && rng.chance(0.5) {
                    (a as *const _, buf.ptr(), op)
                } else {
                    (a as *const _, op, buf2.ptr())
                };
                let (name, st) = unsafe {
                    match which {
                        0 => ("bingham_ahrs_quaternion", bingham_ahrs_quaternion(ap, o1)),
                        1 => ("bingham_ahrs_state", bingham_ahrs_state(ap, o1, o2)),
                        2 => ("bingham_ahrs_gyro_bias", bingham_ahrs_gyro_bias(ap, o1)),
                        _ => (
                            "bingham_ahrs_angular_spread",
                            bingham_ahrs_angular_spread(ap, o1),
                        ),
                    }
                };
                calls += 1;
                expect(st, Some(BINGHAM_ERR_NULL_ARGUMENT), name)?;
                check_error_message(name)?;
                if !buf.untouched() || !buf2.untouched() {
                    return Err(format!("{name} wrote on error"));
                }
            } else if r < 10 {
                // --- clone (sometimes with NULL / misaligned arguments); continue with the copy
                let mut c = [ahrs_sentinel()];
                let attack = rng.below(8);
                let st = unsafe {
                    match attack {
                        0 => bingham_ahrs_clone(std::ptr::null(), c.as_mut_ptr()),
                        1 => bingham_ahrs_clone(a, std::ptr::null_mut()),
                        2 => bingham_ahrs_clone(
                            a,
                            c.as_mut_ptr().cast::<u8>().wrapping_add(3).cast(),
                        ),
                        _ => bingham_ahrs_clone(a, c.as_mut_ptr()),
                    }
                };
                calls += 1;
                if attack <= 2 {
                    expect(st, Some(BINGHAM_ERR_NULL_ARGUMENT), "clone")?;
                    check_error_message("bingham_ahrs_clone")?;
                    if c[0] != ahrs_sentinel() {
                        return Err("clone wrote *out on error".into());
                    }
                    return Ok(());
                }
                if st != BINGHAM_OK {
                    return Err(format!("clone: {}", last_error()));
                }
                if ahrs_bits(c[0])? != before {
                    unsafe { bingham_ahrs_free(c[0]) };
                    return Err("the clone differs from the original".into());
                }
                unsafe {
                    if rng.chance(0.5) {
                        bingham_ahrs_free(a);
                        a = c[0];
                    } else {
                        bingham_ahrs_free(c[0]);
                    }
                }
            } else {
                // --- set_state: a start / re-initialization Bingham(M, z), or hostile
                let (m, z, mut desc) = ahrs_state_args(&mut rng, &imu.q);
                let mut want = ahrs_state_expected(&m, &z);
                let (mut bm, mut bz) = (Buf::from(&m), Buf::from(&z));
                let (mut ap, mut mp, mut zp) = (a, bm.ptr() as *const f64, bz.ptr() as *const f64);
                if rng.chance(0.1) {
                    let null = rng.chance(0.5);
                    match rng.below(3) {
                        0 if null => ap = std::ptr::null_mut(),
                        0 => ap = a.cast::<u8>().wrapping_add(4).cast(),
                        1 if null => mp = std::ptr::null(),
                        1 => mp = bm.misaligned(1 + rng.below(7)),
                        _ if null => zp = std::ptr::null(),
                        _ => zp = bz.misaligned(1 + rng.below(7)),
                    }
                    desc = format!("{desc} (NULL / misaligned: a {ap:p} m {mp:p} z {zp:p})");
                    want = Some(BINGHAM_ERR_NULL_ARGUMENT);
                }
                prime_last_error("bingham_ahrs_set_state");
                let st = unsafe { bingham_ahrs_set_state(ap, mp, zp) };
                calls += 1;
                if verbose {
                    eprintln!(
                        "step {step}: set_state M {m:?} z {z:?} {desc} -> {}",
                        status_name(st)
                    );
                }
                if st == BINGHAM_ERR_PANIC {
                    return Err(format!("panic: {}", last_error()));
                }
                let same = |b: &Buf, v: &[f64]| {
                    b.guards_ok()
                        && b.values()
                            .iter()
                            .zip(v)
                            .all(|(x, y)| x.to_bits() == y.to_bits())
                };
                if !same(&bm, &m) || !same(&bz, &z) {
                    return Err(format!("set_state modified its input ({desc})"));
                }
                expect(st, want, &format!("bingham_ahrs_set_state ({desc})"))?;
                if st != BINGHAM_OK {
                    check_error_message("bingham_ahrs_set_state")?;
                    if ahrs_bits(a)? != before {
                        return Err(format!(
                            "refused set_state ({}, {desc}) changed the AHRS",
                            status_name(st)
                        ));
                    }
                    return Ok(());
                }
                let st2 = unsafe { bingham_ahrs_set_state(twin, m.as_ptr(), z.as_ptr()) };
                if st2 != BINGHAM_OK {
                    return Err(format!(
                        "twin refused an accepted set_state: {}",
                        last_error()
                    ));
                }
                ahrs_bits(a)?;
                check_set_state(a, &m, &z).map_err(|e| format!("set_state ({desc}): {e}"))?;
            }
            Ok(())
        })();
        if let Err(e) = res {
            result = Err(format!("step {step}: {e}"));
            break;
        }
        match (ahrs_bits(a), ahrs_bits(twin)) {
            (Ok(x), Ok(y)) if x == y => {}
            (Ok(_), Ok(_)) => {
                result = Err(format!(
                    "step {step}: the twin (fed only the accepted samples) differs: a refused sample changed hidden state"
                ));
                break;
            }
            (Err(e), _) | (_, Err(e)) => {
                result = Err(format!("step {step}: {e}"));
                break;
            }
        }
    }
    unsafe {
        bingham_ahrs_free(a);
        bingham_ahrs_free(twin);
        bingham_ahrs_free(std::ptr::null_mut());
    }
    result.map(|()| calls)
}

#[test]
fn fuzz_ahrs_sequences() {
    run_sequences(
        "bingham_ahrs",
        "ahrs",
        98,
        cases_for(1.0, 1.0, SHARE_AHRS),
        ahrs_sequence,
    );
}

// ---- deterministic samples and the nonlinear filter steps ------------------------------------------
//
// bingham_deterministic_sample_count / bingham_deterministic_samples: random and hostile d, scheme
// codes, lambda, capacity (zero, short, exact, larger, SIZE_MAX), NULL and misaligned pointers (also
// the size_t and int outputs), NaN/Inf and spoiled M and z, one fault at a time. An error has the
// prescribed status and writes nothing (sentinels, including the spare rows); success writes exactly
// `count` rows and weights (the rows beyond stay untouched) that satisfy the invariants.
//
// bingham_filter_predict_nonlinear / bingham_filter_update_nonlinear: random sequences on a filter
// and a twin (as for the filter above) with callbacks that succeed (identity, rotations, sign
// flips, smooth odd maps, outputs unit within the tolerance; quadratic, constant, huge and
// non-quadratic log-likelihoods) or fail in every way (non-zero return, NaN, ±Inf, non-unit or zero
// output, nothing written), always or only at the k-th call. A failing callback gives
// BINGHAM_ERR_CALLBACK after exactly k + 1 calls, with the state (and, through the twin, the hidden
// state) unchanged; invalid arguments are refused before the first call; the callbacks always see
// a unit vector, a NaN-filled output and their own user pointer.

/// Share of `BINGHAM_FUZZ_CASES` for the functions of this section (on top of the shares above).
const SHARE_NONLINEAR: f64 = 0.1;

fn max_samples(d: usize, scheme: c_int) -> usize {
    if scheme == BINGHAM_SAMPLES_TAC2016 {
        2 * d - 1
    } else {
        2 * d * d - 4 * d + 3
    }
}

/// A scheme code: mostly valid, sometimes not; and whether it is valid.
fn scheme_code(rng: &mut Rng) -> (c_int, bool) {
    if rng.chance(0.9) {
        (
            *rng.pick(&[BINGHAM_SAMPLES_TAC2016, BINGHAM_SAMPLES_MOMENTS]),
            true,
        )
    } else {
        let random = rng.next_u64() as c_int;
        let c = *rng.pick(&[-1, 2, 3, c_int::MIN, c_int::MAX, random]);
        (c, c == 0 || c == 1)
    }
}

fn dim_for_samples(rng: &mut Rng) -> usize {
    if rng.chance(0.06) {
        *rng.pick(&[0usize, 1, 65, 1000, usize::MAX])
    } else if rng.chance(0.06) {
        *rng.pick(&[5usize, 6, 8, 13, 64])
    } else {
        2 + rng.below(3)
    }
}

fn sample_count_case(seed: u64, verbose: bool) -> Result<&'static str, String> {
    let mut rng = Rng::new(seed);
    let d = dim_for_samples(&mut rng);
    let (scheme, scheme_ok) = scheme_code(&mut rng);
    let attack = if rng.chance(0.15) {
        Some(rng.below(8))
    } else {
        None
    };
    if verbose {
        eprintln!("d = {d}, scheme = {scheme}, pointer attack {attack:?}");
    }
    let mut out = [usize::MAX; 3];
    let p = match attack {
        Some(0) => std::ptr::null_mut(),
        Some(k) => out
            .as_mut_ptr()
            .cast::<u8>()
            .wrapping_add(k)
            .cast::<usize>(),
        None => out.as_mut_ptr(),
    };
    prime_last_error("bingham_deterministic_sample_count");
    // SAFETY: p is NULL, misaligned (refused) or points to a writable size_t.
    let st = unsafe { bingham_deterministic_sample_count(d, scheme, p) };
    let want = if !(2..=64).contains(&d) {
        BINGHAM_ERR_INVALID_DIMENSION
    } else if !scheme_ok {
        BINGHAM_ERR_INVALID_ARGUMENT
    } else if attack.is_some() {
        BINGHAM_ERR_NULL_ARGUMENT
    } else {
        BINGHAM_OK
    };
    expect(st, Some(want), &format!("d = {d}, scheme = {scheme}"))?;
    if st != BINGHAM_OK {
        if out != [usize::MAX; 3] {
            return Err(format!("{} but wrote {out:?}", status_name(st)));
        }
        check_error_message("bingham_deterministic_sample_count")?;
        return Ok(status_name(st));
    }
    if out != [max_samples(d, scheme), usize::MAX, usize::MAX] {
        return Err(format!("count {out:?} for d = {d}, scheme {scheme}"));
    }
    Ok("OK")
}

/// One fault of a `bingham_deterministic_samples` case.
#[derive(Debug, Clone, Copy, PartialEq)]
enum SampleFault {
    None,
    /// argument 0..6 (m, z, points, weights, count, reproduced): NULL (0) or misaligned by k
    Pointer(usize, usize),
    NonFinite,
    Lambda,
    SpoilM,
    SpoilZ,
    Scheme,
    Capacity,
}

const REPRODUCED_SENTINEL: c_int = 0x5A5A_5A5A;

fn deterministic_samples_case(seed: u64, verbose: bool) -> Result<&'static str, String> {
    let mut rng = Rng::new(seed);
    let d = dim_for_samples(&mut rng);
    let bad_d = !(2..=64).contains(&d);
    let dl = if bad_d { 2 } else { d };
    let mut fault = match rng.below(20) {
        0..=9 => SampleFault::None,
        10 | 11 => {
            let i = rng.below(6);
            // misaligned by k bytes (k = 4 would be aligned for the int `reproduced`)
            let k = if rng.chance(0.6) {
                0
            } else {
                *rng.pick(&[1usize, 2, 3, 5, 6, 7])
            };
            SampleFault::Pointer(i, k)
        }
        12 => SampleFault::NonFinite,
        13 => SampleFault::Lambda,
        14 => SampleFault::SpoilM,
        15 | 16 => SampleFault::SpoilZ,
        17 => SampleFault::Scheme,
        _ => SampleFault::Capacity,
    };
    let (mut scheme, scheme_ok) = scheme_code(&mut rng);
    if fault == SampleFault::Scheme {
        if scheme_ok {
            scheme = *rng.pick(&[-1, 2, c_int::MIN, c_int::MAX]);
        }
    } else if !scheme_ok {
        if fault == SampleFault::None {
            fault = SampleFault::Scheme;
        } else {
            scheme = BINGHAM_SAMPLES_MOMENTS;
        }
    }
    let len_scheme = if fault == SampleFault::Scheme {
        BINGHAM_SAMPLES_MOMENTS
    } else {
        scheme
    };
    let needed = max_samples(dl, len_scheme);
    let moderate = rng.chance(0.7) && fault != SampleFault::SpoilZ;
    let mut m = orthogonal(&mut rng, dl);
    let mut z = if moderate {
        z_moderate(&mut rng, dl)
    } else {
        z_vector(&mut rng, dl)
    };
    let mut lambda = match rng.below(6) {
        0 => 0.0,
        1 => 1.0,
        _ => rng.unit(),
    };
    let mut capacity = match rng.below(10) {
        0 => needed + 1 + rng.below(5),
        // the library writes at most the needed count: a capacity beyond the buffers is never
        // used (the buffers hold needed + 5 rows), and must not overflow anything
        1 => usize::MAX,
        _ => needed,
    };
    let mut desc = format!("{fault:?}");
    match fault {
        SampleFault::NonFinite => {
            let v = if rng.chance(0.5) { &mut m } else { &mut z };
            let i = rng.below(v.len());
            v[i] = non_finite(&mut rng);
        }
        SampleFault::Lambda => {
            lambda = match rng.below(3) {
                0 => non_finite(&mut rng),
                1 => -rng.log_uniform(-320.0, 300.0),
                _ => 1.0 + rng.log_uniform(-15.0, 300.0),
            };
            desc = format!("lambda = {lambda:e}");
        }
        SampleFault::SpoilM => desc = spoil(&mut rng, M, &mut m, dl),
        SampleFault::SpoilZ => desc = spoil(&mut rng, Z, &mut z, dl),
        SampleFault::Capacity => {
            capacity = if rng.chance(0.3) {
                0
            } else {
                needed - 1 - rng.below(needed.min(3))
            };
            desc = format!("capacity {capacity} < {needed}");
        }
        _ => {}
    }
    if verbose {
        eprintln!(
            "d = {d}, scheme {scheme}, lambda {lambda:e}, capacity {capacity}, {desc}\n m = {m:?}\n z = {z:?}"
        );
    }
    let rows = capacity.min(needed + 5);
    let mut mb = Buf::from(&m);
    let mut zb = Buf::from(&z);
    let (m_bits, z_bits) = (mb.bits(), zb.bits());
    let mut pb = Buf::sentinel(rows * dl);
    let mut wb = Buf::sentinel(rows);
    let mut count = [usize::MAX; 3];
    let mut reproduced = [REPRODUCED_SENTINEL; 3];
    let dang = bad_d && rng.chance(0.5);
    let mut ptrs: [*mut u8; 6] = [
        mb.ptr().cast(),
        zb.ptr().cast(),
        pb.ptr().cast(),
        wb.ptr().cast(),
        count.as_mut_ptr().cast(),
        reproduced.as_mut_ptr().cast(),
    ];
    if let SampleFault::Pointer(i, k) = fault {
        ptrs[i] = if k == 0 {
            std::ptr::null_mut()
        } else {
            ptrs[i].wrapping_add(k)
        };
    }
    if dang {
        ptrs = [dangling().cast(); 6];
    }
    prime_last_error("bingham_deterministic_samples");
    // SAFETY: m: d*d and z: d readable doubles, points: rows*d and weights: rows writable doubles
    // with rows >= the count the library may write, count and reproduced one element each; or
    // NULL / misaligned (refused) / dangling with an invalid d (refused before any access).
    let st = unsafe {
        bingham_deterministic_samples(
            d,
            ptrs[0] as *const f64,
            ptrs[1] as *const f64,
            scheme,
            lambda,
            capacity,
            ptrs[2].cast(),
            ptrs[3].cast(),
            ptrs[4].cast(),
            ptrs[5].cast(),
        )
    };
    let code = status_code(st);
    if !(0..=7).contains(&code) || st == BINGHAM_ERR_PANIC || st == BINGHAM_ERR_CALLBACK {
        return Err(format!("status {code}: {}", last_error()));
    }
    if mb.bits() != m_bits || zb.bits() != z_bits {
        return Err("an input was modified".into());
    }
    let tac = scheme == BINGHAM_SAMPLES_TAC2016;
    let (zmax, zmin) = z
        .iter()
        .fold((f64::NEG_INFINITY, f64::INFINITY), |(a, b), &v| {
            (a.max(v), b.min(v))
        });
    let span_overflows = !(zmax - zmin).is_finite();
    let want = if bad_d {
        Some(BINGHAM_ERR_INVALID_DIMENSION)
    } else {
        match fault {
            SampleFault::Scheme | SampleFault::NonFinite => Some(BINGHAM_ERR_INVALID_ARGUMENT),
            SampleFault::Lambda if tac => Some(BINGHAM_ERR_INVALID_ARGUMENT),
            // (`reproduced` may be NULL)
            SampleFault::Pointer(i, k) if i != 5 || k != 0 => Some(BINGHAM_ERR_NULL_ARGUMENT),
            SampleFault::Capacity => Some(BINGHAM_ERR_INVALID_DIMENSION),
            // (z spanning more than a double is refused like everywhere)
            _ if span_overflows => Some(BINGHAM_ERR_INVALID_ARGUMENT),
            SampleFault::None | SampleFault::Lambda | SampleFault::Pointer(..) if moderate => {
                Some(BINGHAM_OK)
            }
            _ => None,
        }
    };
    expect(st, want, &desc)?;
    let untouched = pb.untouched()
        && wb.untouched()
        && count == [usize::MAX; 3]
        && reproduced == [REPRODUCED_SENTINEL; 3];
    if st != BINGHAM_OK {
        if !untouched {
            return Err(format!("{} but an output was written", status_name(st)));
        }
        check_error_message("bingham_deterministic_samples")?;
        if !bad_d
            && fault == SampleFault::Capacity
            && !last_error().contains(&format!("the {needed} points"))
        {
            return Err(format!("message does not give the count: {}", last_error()));
        }
        // extreme z may fail (log F's moments); every other failure was expected
        let tolerated = fault == SampleFault::SpoilM
            || (!moderate && matches!(st, BINGHAM_ERR_NUMERICAL | BINGHAM_ERR_NOT_CONVERGED));
        if want.is_none() && !tolerated {
            return Err(format!("unexpected {}: {}", status_name(st), last_error()));
        }
        return Ok(status_name(st));
    }
    // success
    let n = count[0];
    if count[1..] != [usize::MAX; 2] || reproduced[1..] != [REPRODUCED_SENTINEL; 2] {
        return Err("wrote past count / reproduced".into());
    }
    let rep = reproduced[0];
    let no_rep = fault == SampleFault::Pointer(5, 0);
    if no_rep != (rep == REPRODUCED_SENTINEL) {
        return Err(format!("reproduced = {rep:#x} (NULL passed: {no_rep})"));
    }
    let expect_n = |r: c_int| {
        if r == 4 {
            max_samples(d, BINGHAM_SAMPLES_MOMENTS)
        } else {
            2 * d - 1
        }
    };
    // 2 (second moment) or, for MOMENTS only, 4 (fourth moments too)
    let rep_ok = rep == 2 || (rep == 4 && !tac);
    if !no_rep && (!rep_ok || n != expect_n(rep)) {
        return Err(format!(
            "count {n}, reproduced {rep} (scheme {scheme}, d = {d})"
        ));
    }
    if n > needed || (n != 2 * d - 1 && n != max_samples(d, BINGHAM_SAMPLES_MOMENTS)) {
        return Err(format!("count {n} (needed {needed})"));
    }
    if !pb.guards_ok() || !wb.guards_ok() {
        return Err("wrote outside the buffers".into());
    }
    if !pb.untouched_range(n * d, rows * d) || !wb.untouched_range(n, rows) {
        return Err("wrote rows beyond count".into());
    }
    let pts = pb.values();
    let ws = wb.values();
    let mut sum = 0.0;
    for k in 0..n {
        check_unit(&pts[k * d..(k + 1) * d], 1e-12).map_err(|e| format!("point {k}: {e}"))?;
        if !(ws[k].is_finite() && ws[k] >= 0.0) {
            return Err(format!("weight {k} = {}", ws[k]));
        }
        sum += ws[k];
    }
    if (sum - 1.0).abs() > 1e-12 {
        return Err(format!("weights sum to 1 + {:e}", sum - 1.0));
    }
    // the weighted second moment is the distribution's (moderate z, d <= 8)
    if moderate && d <= 8 {
        let mut s = vec![0.0; d * d];
        // SAFETY: valid buffers of lengths d*d, d, d*d.
        let st = unsafe { bingham_second_moment(d, m.as_ptr(), z.as_ptr(), s.as_mut_ptr()) };
        if st != BINGHAM_OK {
            return Err(format!("second moment: {}", last_error()));
        }
        for r in 0..d {
            for c in 0..d {
                let v: f64 = (0..n)
                    .map(|k| ws[k] * pts[k * d + r] * pts[k * d + c])
                    .sum();
                if (v - s[r * d + c]).abs() > 1e-11 {
                    return Err(format!(
                        "E[x xᵀ][{r}][{c}] = {v} from the points, {} exact",
                        s[r * d + c]
                    ));
                }
            }
        }
    }
    Ok("OK")
}

#[test]
fn fuzz_deterministic_sample_count() {
    let n = cases_for(1.0, 10.0, SHARE_NONLINEAR);
    drive(
        "bingham_deterministic_sample_count",
        50,
        n,
        sample_count_case,
    );
}

#[test]
fn fuzz_deterministic_samples() {
    let n = cases_for(5.0, 10.0, SHARE_NONLINEAR);
    drive(
        "bingham_deterministic_samples",
        51,
        n,
        deterministic_samples_case,
    );
}

// -- the callbacks

const CB_MAGIC: u64 = 0xB1E5_5ED0_CA11_BAC5;

/// What a callback does when it misbehaves.
#[derive(Debug, Clone, Copy, PartialEq)]
enum CbBad {
    Rc(c_int),
    Nan(usize),
    Inf(usize, f64),
    /// the (otherwise valid) output times this factor: not unit
    Scale(f64),
    Zero,
    /// returns 0 without writing
    Nothing,
}

/// What a callback does otherwise.
#[derive(Debug, Clone, PartialEq)]
enum CbGood {
    Identity,
    /// x -> x (+) u
    Rotate(Vec<f64>),
    Negate,
    /// x -> normalize(x + c x³) (odd)
    Cubic(f64),
    /// identity times s, |s − 1| within the tolerance
    AlmostUnit(f64),
    /// log L = xᵀ P x
    Quadratic(Vec<f64>),
    Constant(f64),
    /// log L = −kappa (1 − (vᵀx)²)²
    Quartic(f64, Vec<f64>),
}

#[derive(Debug, Clone)]
struct CbCtx {
    magic: u64,
    d: usize,
    good: CbGood,
    bad: Option<CbBad>,
    /// misbehave at this call only (None: at every call, if `bad` is set)
    fail_at: Option<usize>,
    calls: usize,
    /// the call at which the callback misbehaved
    triggered: Option<usize>,
    /// a contract violation seen by the callback (x not unit, output not NaN-filled, ...)
    violation: Option<String>,
}

impl CbCtx {
    fn new(d: usize, good: CbGood, bad: Option<CbBad>, fail_at: Option<usize>) -> CbCtx {
        CbCtx {
            magic: CB_MAGIC,
            d,
            good,
            bad,
            fail_at,
            calls: 0,
            triggered: None,
            violation: None,
        }
    }

    fn reset(&mut self) {
        self.calls = 0;
        self.triggered = None;
        self.violation = None;
    }

    /// The call index, and whether to misbehave now.
    fn enter(&mut self, x: &[f64]) -> bool {
        let k = self.calls;
        self.calls += 1;
        if self.violation.is_none() {
            if let Err(e) = check_unit(x, 1e-12) {
                self.violation = Some(format!("call {k}: x = {x:?}: {e}"));
            }
        }
        let now = self.bad.is_some() && self.fail_at.is_none_or(|j| j == k);
        if now && self.triggered.is_none() {
            self.triggered = Some(k);
        }
        now
    }
}

fn compose(x: &[f64], u: &[f64]) -> Vec<f64> {
    if x.len() == 2 {
        vec![x[0] * u[0] - x[1] * u[1], x[0] * u[1] + x[1] * u[0]]
    } else {
        vec![
            x[0] * u[0] - x[1] * u[1] - x[2] * u[2] - x[3] * u[3],
            x[0] * u[1] + x[1] * u[0] + x[2] * u[3] - x[3] * u[2],
            x[0] * u[2] - x[1] * u[3] + x[2] * u[0] + x[3] * u[1],
            x[0] * u[3] + x[1] * u[2] - x[2] * u[1] + x[3] * u[0],
        ]
    }
}

/// `bingham_transition_fn` driven by a `CbCtx`. Must not panic (it is called through C).
unsafe extern "C" fn fuzz_transition(
    x_in: *const f64,
    x_out: *mut f64,
    user: *mut c_void,
) -> c_int {
    // SAFETY: user is the CbCtx passed with this callback; x_in, x_out have d doubles each
    // (the library's contract, checked below as far as possible).
    let c = unsafe { &mut *user.cast::<CbCtx>() };
    if c.magic != CB_MAGIC {
        return 99;
    }
    let d = c.d;
    // SAFETY: as above.
    let (x, out) = unsafe {
        (
            std::slice::from_raw_parts(x_in, d),
            std::slice::from_raw_parts_mut(x_out, d),
        )
    };
    if c.violation.is_none() && !out.iter().all(|v| v.is_nan()) {
        c.violation = Some(format!("call {}: x_out = {out:?} not NaN-filled", c.calls));
    }
    let bad = c.enter(x);
    let mut y = match &c.good {
        CbGood::Rotate(u) => compose(x, u),
        CbGood::Negate => x.iter().map(|v| -v).collect(),
        CbGood::Cubic(k) => {
            let v: Vec<f64> = x.iter().map(|t| t + k * t * t * t).collect();
            let n = norm(&v);
            v.iter().map(|t| t / n).collect()
        }
        CbGood::AlmostUnit(s) => x.iter().map(|t| t * s).collect(),
        _ => x.to_vec(),
    };
    if bad {
        match c.bad {
            Some(CbBad::Rc(rc)) => return rc,
            Some(CbBad::Nan(i)) => y[i % d] = f64::NAN,
            Some(CbBad::Inf(i, s)) => y[i % d] = s * f64::INFINITY,
            Some(CbBad::Scale(s)) => y.iter_mut().for_each(|t| *t *= s),
            Some(CbBad::Zero) => y.iter_mut().for_each(|t| *t = 0.0),
            Some(CbBad::Nothing) | None => return 0,
        }
    }
    out.copy_from_slice(&y);
    0
}

/// `bingham_log_likelihood_fn` driven by a `CbCtx`. Must not panic.
unsafe extern "C" fn fuzz_log_likelihood(
    x: *const f64,
    log_l: *mut f64,
    user: *mut c_void,
) -> c_int {
    // SAFETY: user is the CbCtx passed with this callback; x has d doubles, log_l one.
    let c = unsafe { &mut *user.cast::<CbCtx>() };
    if c.magic != CB_MAGIC {
        return 99;
    }
    let d = c.d;
    // SAFETY: as above.
    let (x, out) = unsafe { (std::slice::from_raw_parts(x, d), &mut *log_l) };
    if c.violation.is_none() && !out.is_nan() {
        c.violation = Some(format!("call {}: *log_l = {out} not NaN", c.calls));
    }
    let bad = c.enter(x);
    let v = match &c.good {
        CbGood::Quadratic(p) => (0..d)
            .map(|i| (0..d).map(|j| x[i] * p[i * d + j] * x[j]).sum::<f64>())
            .sum(),
        CbGood::Constant(v) => *v,
        CbGood::Quartic(kappa, v) => {
            let c: f64 = (0..d).map(|i| v[i] * x[i]).sum();
            let s2 = 1.0 - c * c;
            -kappa * s2 * s2
        }
        _ => 0.0,
    };
    if bad {
        match c.bad {
            Some(CbBad::Rc(rc)) => return rc,
            Some(CbBad::Nan(_)) => *out = f64::NAN,
            Some(CbBad::Inf(_, s)) => *out = s * f64::INFINITY,
            Some(CbBad::Nothing) | None | Some(_) => return 0,
        }
        return 0;
    }
    *out = v;
    0
}

fn nonzero_rc(rng: &mut Rng) -> c_int {
    match rng.below(4) {
        0 => 1,
        1 => -1,
        2 => *rng.pick(&[c_int::MIN, c_int::MAX, 42]),
        _ => (rng.next_u64() as c_int) | 1,
    }
}

fn transition_ctx(rng: &mut Rng, d: usize) -> CbCtx {
    let good = match rng.below(6) {
        0 | 1 => CbGood::Identity,
        2 => CbGood::Rotate(unit_vector(rng, d)),
        3 => CbGood::Negate,
        4 => CbGood::Cubic(rng.range(-0.5, 0.5)),
        _ => CbGood::AlmostUnit(1.0 + rng.range(-1e-8, 1e-8)),
    };
    let bad = if rng.chance(0.5) {
        Some(match rng.below(6) {
            0 => CbBad::Rc(nonzero_rc(rng)),
            1 => CbBad::Nan(rng.below(4)),
            2 => CbBad::Inf(rng.below(4), if rng.chance(0.5) { 1.0 } else { -1.0 }),
            3 => CbBad::Scale(match rng.below(4) {
                0 => 1.0 + rng.log_uniform(-5.0, 0.0),
                1 => 1.0 - rng.log_uniform(-5.0, -0.1),
                2 => rng.log_uniform(10.0, 300.0),
                _ => rng.log_uniform(-320.0, -10.0),
            }),
            4 => CbBad::Zero,
            _ => CbBad::Nothing,
        })
    } else {
        None
    };
    let fail_at = if rng.chance(0.6) {
        Some(rng.below(25))
    } else {
        None
    };
    CbCtx::new(d, good, bad, fail_at)
}

fn likelihood_ctx(rng: &mut Rng, d: usize) -> CbCtx {
    let good = match rng.below(6) {
        0..=2 => {
            let m = orthogonal(rng, d);
            let top = if rng.chance(0.9) { 2.5 } else { 12.0 };
            let scale = rng.log_uniform(-3.0, top);
            let w: Vec<f64> = (0..d).map(|_| -scale * rng.unit()).collect();
            CbGood::Quadratic(congruence(&m, &w, d))
        }
        3 => CbGood::Constant(match rng.below(3) {
            0 => 0.0,
            1 => rng.range(-1e3, 1e3),
            _ => extreme(rng),
        }),
        _ => CbGood::Quartic(rng.log_uniform(-2.0, 2.0), unit_vector(rng, d)),
    };
    let bad = if rng.chance(0.5) {
        Some(match rng.below(4) {
            0 => CbBad::Rc(nonzero_rc(rng)),
            1 => CbBad::Nan(0),
            2 => CbBad::Inf(0, if rng.chance(0.5) { 1.0 } else { -1.0 }),
            _ => CbBad::Nothing,
        })
    } else {
        None
    };
    let fail_at = if rng.chance(0.6) {
        Some(rng.below(60))
    } else {
        None
    };
    CbCtx::new(d, good, bad, fail_at)
}

/// An argument fault of a nonlinear step.
#[derive(Debug, Clone, Copy, PartialEq)]
enum NlFault {
    None,
    NullHandle,
    MisalignedHandle,
    NullFn,
    /// m_w (0) or z_w (1): NULL
    NullNoise(usize),
    MisalignedNoise(usize),
    NonFiniteNoise(usize),
}

/// Runs one nonlinear sequence; returns the number of calls made.
fn nonlinear_sequence(
    seed: u64,
    verbose: bool,
    stats: &mut BTreeMap<String, u64>,
) -> Result<u64, String> {
    let mut rng = Rng::new(seed);
    let d = if rng.chance(0.5) { 2 } else { 4 };
    let m0 = orthogonal(&mut rng, d);
    let mut z0 = if rng.chance(0.7) {
        z_moderate(&mut rng, d)
    } else {
        z_vector(&mut rng, d)
    };
    let (zmax, zmin) = z0
        .iter()
        .fold((f64::NEG_INFINITY, f64::INFINITY), |(a, b), &v| {
            (a.max(v), b.min(v))
        });
    if !(zmax - zmin).is_finite() {
        // (refused by bingham_filter_new; the sequences of the filter test cover that)
        z0 = z_moderate(&mut rng, d);
    }
    let (mut f, mut twin) = (std::ptr::null_mut(), std::ptr::null_mut());
    // SAFETY: valid buffers and out-pointers.
    let (s1, s2) = unsafe {
        (
            bingham_filter_new(d, m0.as_ptr(), z0.as_ptr(), &mut f),
            bingham_filter_new(d, m0.as_ptr(), z0.as_ptr(), &mut twin),
        )
    };
    if s1 != BINGHAM_OK || s2 != BINGHAM_OK {
        return Err(format!("bingham_filter_new: {}", last_error()));
    }
    let pool: Vec<(Vec<f64>, Vec<f64>)> = (0..2).map(|_| filter_noise(&mut rng, d)).collect();
    if verbose {
        eprintln!("d = {d}, m0 = {m0:?}, z0 = {z0:?}, noise pool {pool:?}");
    }
    let steps = 1 + rng.below(12);
    let mut calls = 0u64;
    let mut result = Ok(());
    for step in 0..steps {
        let predict = rng.chance(0.5);
        let name = if predict {
            "bingham_filter_predict_nonlinear"
        } else {
            "bingham_filter_update_nonlinear"
        };
        let mut ctx = if predict {
            transition_ctx(&mut rng, d)
        } else {
            likelihood_ctx(&mut rng, d)
        };
        let (mut mw, mut zw) = pool[rng.below(pool.len())].clone();
        let fault = match rng.below(24) {
            0 => NlFault::NullHandle,
            1 => NlFault::MisalignedHandle,
            2 => NlFault::NullFn,
            3 if predict => NlFault::NullNoise(rng.below(2)),
            4 if predict => NlFault::MisalignedNoise(rng.below(2)),
            5 if predict => NlFault::NonFiniteNoise(rng.below(2)),
            _ => NlFault::None,
        };
        if let NlFault::NonFiniteNoise(i) = fault {
            let v = if i == 0 { &mut mw } else { &mut zw };
            let j = rng.below(v.len());
            v[j] = non_finite(&mut rng);
        }
        let mut mwb = Buf::from(&mw);
        let mut zwb = Buf::from(&zw);
        let mut mp = mwb.ptr() as *const f64;
        let mut zp = zwb.ptr() as *const f64;
        match fault {
            NlFault::NullNoise(0) => mp = std::ptr::null(),
            NlFault::NullNoise(_) => zp = std::ptr::null(),
            NlFault::MisalignedNoise(0) => mp = mwb.misaligned(3),
            NlFault::MisalignedNoise(_) => zp = zwb.misaligned(5),
            _ => {}
        }
        let fp = match fault {
            NlFault::NullHandle => std::ptr::null_mut(),
            NlFault::MisalignedHandle => f.cast::<u8>().wrapping_add(4).cast(),
            _ => f,
        };
        let before = state_bits(f, d);
        prime_last_error(name);
        if verbose {
            eprintln!("step {step}: {name} {fault:?} {ctx:?}");
        }
        let user = (&mut ctx as *mut CbCtx).cast::<c_void>();
        // SAFETY: f is live (or NULL / misaligned: refused); the callbacks match the contract;
        // noise buffers of d*d and d doubles, or NULL / misaligned (refused).
        let st = unsafe {
            if predict {
                let cb: bingham_transition_fn = if fault == NlFault::NullFn {
                    None
                } else {
                    Some(fuzz_transition)
                };
                bingham_filter_predict_nonlinear(fp, cb, user, mp, zp)
            } else {
                let cb: bingham_log_likelihood_fn = if fault == NlFault::NullFn {
                    None
                } else {
                    Some(fuzz_log_likelihood)
                };
                bingham_filter_update_nonlinear(fp, cb, user)
            }
        };
        calls += 1;
        *stats
            .entry(format!(
                "{}:{}",
                if predict { "predict" } else { "update" },
                status_name(st)
            ))
            .or_default() += 1;
        if verbose {
            eprintln!(
                "    -> {} after {} callback calls (triggered {:?}) {}",
                status_name(st),
                ctx.calls,
                ctx.triggered,
                if st == BINGHAM_OK {
                    String::new()
                } else {
                    last_error()
                }
            );
        }
        let ctx_desc = format!("step {step} {name} {fault:?} {ctx:?}");
        let fail = |msg: String| Err(format!("{ctx_desc}: {msg}"));
        let code = status_code(st);
        if !(0..=7).contains(&code) || st == BINGHAM_ERR_PANIC {
            result = fail(format!("status {code}: {}", last_error()));
            break;
        }
        if mwb
            .values()
            .iter()
            .zip(&mw)
            .any(|(a, b)| a.to_bits() != b.to_bits())
            || zwb
                .values()
                .iter()
                .zip(&zw)
                .any(|(a, b)| a.to_bits() != b.to_bits())
            || !mwb.guards_ok()
            || !zwb.guards_ok()
        {
            result = fail("the noise was modified".into());
            break;
        }
        if let Some(v) = &ctx.violation {
            result = fail(format!("callback contract violated by the library: {v}"));
            break;
        }
        let want = match fault {
            NlFault::None => None,
            NlFault::NonFiniteNoise(_) => Some(BINGHAM_ERR_INVALID_ARGUMENT),
            _ => Some(BINGHAM_ERR_NULL_ARGUMENT),
        };
        if let Some(w) = want {
            if st != w || ctx.calls != 0 {
                result = fail(format!(
                    "{} after {} callback calls instead of {} before any",
                    status_name(st),
                    ctx.calls,
                    status_name(w)
                ));
                break;
            }
        } else if let Some(k) = ctx.triggered {
            if st != BINGHAM_ERR_CALLBACK || ctx.calls != k + 1 {
                result = fail(format!(
                    "the callback misbehaved at call {k}: {} after {} calls ({})",
                    status_name(st),
                    ctx.calls,
                    last_error()
                ));
                break;
            }
        } else if !matches!(
            st,
            BINGHAM_OK | BINGHAM_ERR_NOT_CONVERGED | BINGHAM_ERR_NUMERICAL
        ) {
            result = fail(format!("valid call refused: {}", last_error()));
            break;
        }
        let after = state_bits(f, d);
        if st != BINGHAM_OK {
            if after != before {
                result = fail(format!("{} but the state changed", status_name(st)));
                break;
            }
            if let Err(e) = check_error_message(name) {
                result = fail(e);
                break;
            }
        } else {
            let (m, z) = filter_state(f, d);
            if let Err(e) = check_state(&m, &z, d) {
                result = fail(format!("state invalid after success: {e}"));
                break;
            }
            // the twin repeats the successful call
            ctx.reset();
            let user = (&mut ctx as *mut CbCtx).cast::<c_void>();
            // SAFETY: as above, with valid arguments.
            let st2 = unsafe {
                if predict {
                    bingham_filter_predict_nonlinear(
                        twin,
                        Some(fuzz_transition),
                        user,
                        mw.as_ptr(),
                        zw.as_ptr(),
                    )
                } else {
                    bingham_filter_update_nonlinear(twin, Some(fuzz_log_likelihood), user)
                }
            };
            if st2 != BINGHAM_OK {
                result = fail(format!("twin failed: {}", last_error()));
                break;
            }
        }
        if state_bits(twin, d) != state_bits(f, d) {
            result = fail(
                "the twin (which saw only the successful calls) differs: a failed call changed hidden state"
                    .into(),
            );
            break;
        }
        // now and then a linear step on both, to move the state and exercise the caches
        if rng.chance(0.3) {
            let (pm, pz) = &pool[rng.below(pool.len())];
            // SAFETY: live handles, valid noise buffers.
            let (a, b) = unsafe {
                (
                    bingham_filter_predict(f, pm.as_ptr(), pz.as_ptr()),
                    bingham_filter_predict(twin, pm.as_ptr(), pz.as_ptr()),
                )
            };
            if a != b {
                result = fail("linear predict differs between filter and twin".into());
                break;
            }
        }
    }
    // SAFETY: live handles, freed once.
    unsafe {
        bingham_filter_free(f);
        bingham_filter_free(twin);
    }
    result.map(|()| calls)
}

#[test]
fn fuzz_filter_nonlinear() {
    let mut stats: BTreeMap<String, u64> = BTreeMap::new();
    run_sequences(
        "bingham_filter_nonlinear",
        "filter_nonlinear",
        52,
        cases_for(4.0, 10.0, SHARE_NONLINEAR),
        |seed, verbose| nonlinear_sequence(seed, verbose, &mut stats),
    );
    if stats_wanted() {
        eprintln!("bingham_filter_nonlinear statuses: {stats:?}");
    }
}

// ---- the small helpers ------------------------------------------------------------------------

#[test]
fn fuzz_status_str_and_last_error_message() {
    let count = cases_for(1.0, 1.0, 1.0 - SHARE_DISTRIBUTION - SHARE_FILTER);
    if repro().is_some() {
        return; // reproducing a case of another test
    }
    let slot = CaseSlot::new("helpers");
    let known: Vec<String> = (0..=7)
        .map(|c| {
            // SAFETY: any int is accepted; the result is a static C string.
            let p = bingham_status_str(c);
            assert!(!p.is_null());
            // SAFETY: NUL-terminated static string.
            unsafe { std::ffi::CStr::from_ptr(p) }
                .to_str()
                .unwrap()
                .to_string()
        })
        .collect();
    assert!(
        known.iter().all(|s| !s.is_empty() && s != "unknown status"),
        "{known:?}"
    );
    for i in 0..count {
        let seed = mix(base_seed() ^ (77 << 48) ^ i);
        slot.enter(seed);
        let mut rng = Rng::new(seed);
        // status_str with any int
        let code = match rng.below(4) {
            0 => rng.below(10) as i32 - 2,
            1 => i32::MIN + rng.below(3) as i32,
            2 => i32::MAX - rng.below(3) as i32,
            _ => rng.next_u64() as i32,
        };
        let p = bingham_status_str(code);
        assert!(!p.is_null(), "status_str({code}) is NULL");
        // SAFETY: NUL-terminated static string.
        let s = unsafe { std::ffi::CStr::from_ptr(p) }
            .to_str()
            .expect("UTF-8");
        if (0..=7).contains(&code) {
            assert_eq!(s, known[code as usize]);
        } else {
            assert_eq!(s, "unknown status", "status_str({code})");
        }
        // a failing call with a message of varying length (the row number varies; "‖" and
        // other non-ASCII characters appear in some messages), then reads with random buffers
        let d = 2 + rng.below(4);
        let n = 1 + rng.below(300);
        let mut x = vec![0.0; n * d];
        for r in 0..n {
            x[r * d] = 1.0;
        }
        let bad = rng.below(n);
        x[bad * d] = 1.5;
        let (m, z) = (identity(d), vec![0.0; d]);
        let mut p_out = vec![0.0; n];
        // SAFETY: valid buffers.
        let st = unsafe {
            bingham_log_pdf(d, m.as_ptr(), z.as_ptr(), n, x.as_ptr(), p_out.as_mut_ptr())
        };
        assert_eq!(st, BINGHAM_ERR_INVALID_ARGUMENT);
        let full = last_error();
        assert!(full.contains(&format!("row {bad}")), "{full}");
        let len = match rng.below(4) {
            0 => 0,
            1 => rng.below(full.len() + 3),
            2 => full.len() + rng.below(3),
            _ => 1 + rng.below(8),
        };
        let mut buf = vec![0xA5u8; len + 16];
        let mut out_len = [usize::MAX; 2];
        let buf_null = len > 0 && rng.chance(0.05);
        let len_null = rng.chance(0.2);
        let len_misaligned = !len_null && rng.chance(0.05);
        let bp = if buf_null || (len == 0 && rng.chance(0.5)) {
            std::ptr::null_mut()
        } else {
            // SAFETY: within buf.
            unsafe { buf.as_mut_ptr().add(8) }.cast::<std::os::raw::c_char>()
        };
        let lp = if len_null {
            std::ptr::null_mut()
        } else if len_misaligned {
            out_len
                .as_mut_ptr()
                .cast::<u8>()
                .wrapping_add(1)
                .cast::<usize>()
        } else {
            out_len.as_mut_ptr()
        };
        // SAFETY: bp is NULL or has len writable bytes (8 guard bytes on each side); lp NULL,
        // valid, or misaligned (refused).
        let st = unsafe { bingham_last_error_message(bp, len, lp) };
        let ctx = format!("seed {seed}: len {len}, buf NULL {buf_null}, out_len NULL {len_null}, misaligned {len_misaligned}, message {full:?}");
        assert!(
            buf[..8].iter().all(|&b| b == 0xA5) && buf[8 + len..].iter().all(|&b| b == 0xA5),
            "wrote outside the buffer: {ctx}"
        );
        assert_eq!(last_error(), full, "reading changed the message: {ctx}");
        if buf_null || len_misaligned {
            assert_eq!(st, BINGHAM_ERR_NULL_ARGUMENT, "{ctx}");
            assert!(
                buf.iter().all(|&b| b == 0xA5) && out_len == [usize::MAX; 2],
                "wrote on error: {ctx}"
            );
            continue;
        }
        assert_eq!(st, BINGHAM_OK, "{ctx}");
        if !len_null {
            assert_eq!(out_len, [full.len(), usize::MAX], "{ctx}");
        }
        if len > 0 && !bp.is_null() {
            let got = &buf[8..8 + len];
            let nul = got.iter().position(|&b| b == 0).expect("NUL-terminated");
            let s = std::str::from_utf8(&got[..nul]).expect("cut at a character boundary");
            assert!(full.starts_with(s), "{ctx}");
            assert!(nul < len, "{ctx}");
            // as long as fits, but possibly shorter to stay on a character boundary
            assert!(
                nul == full.len().min(len - 1) || (full.len() >= len && nul + 4 > len - 1),
                "{ctx}: copied {nul}"
            );
        } else {
            assert!(buf.iter().all(|&b| b == 0xA5), "{ctx}");
        }
        slot.leave();
    }
}
