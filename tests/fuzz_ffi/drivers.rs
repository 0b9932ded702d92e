//! The drivers: the number of cases and the seeds (environment), running the cases of one
//! function or the call sequences of one harness with the crash reporter, and the tests of the
//! stateless functions.

use std::collections::BTreeMap;
use std::time::Duration;
use std::time::Instant;

use testkit::fuzz::{env_count, CaseSlot};
use testkit::mix;

use crate::case::{gen_case, run_case};
use crate::kinds::SPECS;
use crate::status::status_name;

fn total_cases() -> u64 {
    env_count("BINGHAM_FUZZ_CASES", 250_000)
}

/// The base seed, XOR-ed into every case's seed. A seed other than 0 is scrambled first: XOR-ing
/// a small number into the case index would only reorder the cases of seed 0.
pub(crate) fn base_seed() -> u64 {
    match env_count("BINGHAM_FUZZ_SEED", 0) {
        0 => 0,
        s => mix(s),
    }
}

pub(crate) fn stats_wanted() -> bool {
    std::env::var_os("BINGHAM_FUZZ_STATS").is_some()
}

/// `Some((label, seed))` when a single case is to be reproduced.
pub(crate) fn repro() -> Option<(String, u64)> {
    let s = std::env::var("BINGHAM_FUZZ_REPRO").ok()?;
    let (label, seed) = s
        .rsplit_once(':')
        .expect("BINGHAM_FUZZ_REPRO=<label>:<seed>");
    Some((label.to_string(), seed.parse().expect("seed")))
}

/// The share of the cases for the distribution functions vs. the filter and the small helpers.
pub(crate) const SHARE_DISTRIBUTION: f64 = 0.75;
pub(crate) const SHARE_FILTER: f64 = 0.22;

/// Share of `BINGHAM_FUZZ_CASES` for the vector observation, rotation noise and angular spread
/// functions (on top of the shares above) and for the AHRS calls.
pub(crate) const SHARE_VECTOR: f64 = 0.06;
pub(crate) const SHARE_AHRS: f64 = 0.05;

/// Share of `BINGHAM_FUZZ_CASES` for the deterministic samples and the nonlinear filter steps (on
/// top of the shares above).
pub(crate) const SHARE_NONLINEAR: f64 = 0.1;

/// Share of `BINGHAM_FUZZ_CASES` for the spin filter's call sequences (on top of the shares
/// above).
pub(crate) const SHARE_SPIN: f64 = 0.04;

pub(crate) fn cases_for(weight: f64, total_weight: f64, share: f64) -> u64 {
    ((total_cases() as f64) * share * weight / total_weight).ceil() as u64
}

#[derive(Default, Clone)]
/// What the cases of one function gave: counts per status, time.
pub(crate) struct Stats {
    cases: u64,
    by_status: BTreeMap<&'static str, u64>,
    time: Duration,
}

/// Runs `count` cases of `label` from `gen_and_run(seed)`, collecting up to 20 failures.
pub(crate) fn drive(
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

/// Runs random call sequences until `target` calls were made (or the one sequence named by
/// `BINGHAM_FUZZ_REPRO=label:seed`), collecting up to 20 failures with their reproduction line.
/// `sequence(seed, verbose)` returns the number of calls it made. `tag` keeps the seeds of
/// different harnesses apart.
pub(crate) fn run_sequences(
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
