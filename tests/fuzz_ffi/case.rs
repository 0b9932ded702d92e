//! One case of a stateless C function: its random (valid or hostile) arguments, the status the
//! header prescribes for them, and the call with its checks of the status, the buffers and the
//! last error message.

use bingham::ffi::bingham_status::*;
use bingham::ffi::*;
use testkit::fuzz::{
    congruence, dangling, extreme, non_finite, orthogonal, z_moderate, z_vector, Buf,
};
use testkit::{norm, Rng64};

use crate::kinds::Kind::*;
use crate::kinds::{kind_len, Call, Kind, Spec, SPECS};
use crate::status::{check_error_message, last_error, prime_last_error, status_code, status_name};

/// What was done to the arguments of a case (for the expected status and the report).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Attack {
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
pub(crate) struct Case {
    pub(crate) spec: usize,
    pub(crate) seed: u64,
    pub(crate) d: usize,
    pub(crate) n: usize,
    /// the input arrays (None: NULL)
    pub(crate) inputs: Vec<Option<Vec<f64>>>,
    /// which outputs are requested (false: NULL, only for optional ones or attacks)
    pub(crate) out_present: Vec<bool>,
    pub(crate) attack: Attack,
    /// pointer tweaks: (is_input, index, byte offset) for misalignment
    pub(crate) misalign: Option<(bool, usize, usize)>,
    /// arrays replaced by a dangling pointer (invalid d)
    pub(crate) dangling: bool,
    /// "moderate" inputs: z within the documented exact range, M exactly orthogonal
    pub(crate) moderate: bool,
}

fn pick_d(rng: &mut Rng64, spec: &Spec) -> usize {
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

fn gen_input(rng: &mut Rng64, k: Kind, d: usize, n: usize, moderate: bool) -> Vec<f64> {
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
            let center = rng.unit_vector(d);
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
        U => rng.unit_vector(d),
        One | D | DD | N | ND => unreachable!("not an input kind"),
    }
}

/// Makes an input finite but unacceptable or extreme; returns a description.
pub(crate) fn spoil(rng: &mut Rng64, k: Kind, a: &mut [f64], d: usize) -> String {
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
                let u = rng.unit_vector(d);
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

pub(crate) fn gen_case(spec_idx: usize, seed: u64) -> Case {
    let spec = &SPECS[spec_idx];
    let mut rng = Rng64::new(seed);
    let roll = rng.uniform();
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
        let r = rng.uniform();
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

/// Runs one case; Err describes the failure.
pub(crate) fn run_case(case: &Case, verbose: bool) -> Result<bingham_status, String> {
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
