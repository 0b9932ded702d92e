//! The argument kinds of the stateless C functions and the table of those functions
//! ([`SPECS`]): for each, its thin `extern "C"` wrapper, its arguments and how to check a result.

use bingham::ffi::*;

use crate::case::Case;
use crate::invariants::{
    check_dist_out, check_finite_out, check_hess, check_kl, check_lnc, check_lnc_sp, check_log_pdf,
    check_mle, check_mode, check_nc, check_pdf, check_sample, check_sm,
};

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Kind {
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

pub(crate) fn kind_len(k: Kind, d: usize, n: usize) -> usize {
    match k {
        Kind::M | Kind::S | Kind::DD => d * d,
        Kind::Z | Kind::U | Kind::D => d,
        Kind::X | Kind::ND => n * d,
        Kind::W | Kind::N => n,
        Kind::One => 1,
    }
}

/// The raw arguments of one call.
pub(crate) struct Call {
    pub(crate) d: usize,
    pub(crate) n: usize,
    pub(crate) seed: u64,
    pub(crate) inp: [*const f64; 4],
    pub(crate) out: [*mut f64; 3],
}

type CallFn = unsafe fn(&Call) -> bingham_status;
type CheckFn = fn(&Case, &[Option<Vec<f64>>]) -> Result<(), String>;

pub(crate) struct Spec {
    pub(crate) name: &'static str,
    pub(crate) call: CallFn,
    /// composition and rotations: d = 2 and d = 4 only
    pub(crate) only24: bool,
    /// the function takes a count n
    pub(crate) has_n: bool,
    pub(crate) inputs: &'static [(Kind, &'static str, bool)],
    pub(crate) outputs: &'static [(Kind, &'static str, bool)],
    /// relative share of the cases
    pub(crate) weight: f64,
    /// probability of a d in 5..=64 (the rest: 2, 3, 4)
    pub(crate) big_d: f64,
    /// invariants of a successful call's outputs
    pub(crate) check: CheckFn,
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

pub(crate) const SPECS: &[Spec] = &[
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
