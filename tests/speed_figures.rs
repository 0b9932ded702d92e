//! Every measured speed figure has one home: `docs/speed.md` (issue 19, "one room per subject").
//!
//! A time per operation quoted in several places drifts: one copy is re-measured, another is
//! not or is rounded differently, and a reader cannot tell which to believe (the README gave the
//! d = 4 filter step as 2.0 µs in one section and 2.0–2.1 µs in another). So `docs/speed.md`
//! holds each figure once — what is measured, the benchmark that measures it, the machine, the
//! median — and every other document links to its row instead of quoting it.
//!
//! This test enforces that. It walks `src/`, `include/`, `README.md`, `docs/` (except
//! `docs/speed.md`) and the `*.py` / `*.md` files of `python/`, and fails with `file:line` for
//! every **speed figure**: a number followed by an optional space and a time unit of a single
//! operation — `µs` (micro sign or Greek mu), `us` or `ns`, as a whole word — such as `0.29 µs`,
//! `291 ns` or `2.2 us per sample`.
//!
//! Deliberately not matched:
//!
//! - `ms` and `s`: the documents use them for physical quantities — sensor latencies (`11 ms`),
//!   sample periods, filter time constants (`3 s`), how long a test runs — not for the cost of
//!   an operation;
//! - other units that merely start like one: `7 µrad` (the unit must end at a word boundary);
//! - numbers without a unit (`1e-6`, `10⁵ cases`) and units without a number (`tens of µs`,
//!   the `(µs)` of a table header).
//!
//! Benchmark targets ("≤ 0.3 µs") count as figures too; they belong in `docs/speed.md` beside
//! the medians. The benchmarks themselves (`benches/`) are not walked: their doc comments state
//! what they measure and their targets.
//!
//! Run it alone with `cargo test --release --test speed_figures`.

use std::fs;
use std::path::{Path, PathBuf};

/// Directory names never entered: build output, virtual environments and caches (a built
/// Python package holds copies of the sources).
const SKIPPED_DIRS: [&str; 6] = [
    "target",
    "build",
    "dist",
    "venv",
    "__pycache__",
    "node_modules",
];

/// The time units of one operation. `ms` is left out on purpose (see the module documentation).
const UNITS: [&str; 4] = ["\u{b5}s", "\u{3bc}s", "us", "ns"];

fn is_word_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// Horizontal white space that may sit between a number and its unit (space, tab, no-break,
/// thin and narrow no-break spaces).
fn is_gap(c: char) -> bool {
    matches!(c, ' ' | '\t' | '\u{a0}' | '\u{2009}' | '\u{202f}')
}

/// The speed figures in one line: each `number [gap] unit`, as written.
fn figures_in(line: &str) -> Vec<String> {
    let chars: Vec<char> = line.chars().collect();
    let mut found = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        // A number starts at a digit that does not continue a word (`x2`, `f64`).
        let starts_number = chars[i].is_ascii_digit() && (i == 0 || !is_word_char(chars[i - 1]));
        if !starts_number {
            i += 1;
            continue;
        }
        let start = i;
        while i < chars.len() && chars[i].is_ascii_digit() {
            i += 1;
        }
        if i + 1 < chars.len() && chars[i] == '.' && chars[i + 1].is_ascii_digit() {
            i += 1;
            while i < chars.len() && chars[i].is_ascii_digit() {
                i += 1;
            }
        }
        let mut j = i;
        while j < chars.len() && is_gap(chars[j]) {
            j += 1;
        }
        for unit in UNITS {
            let unit: Vec<char> = unit.chars().collect();
            let end = j + unit.len();
            if end <= chars.len()
                && chars[j..end] == unit[..]
                && (end == chars.len() || !is_word_char(chars[end]))
            {
                found.push(chars[start..end].iter().collect());
                i = end;
                break;
            }
        }
    }
    found
}

/// The files to check, sorted.
fn files(root: &Path) -> Vec<PathBuf> {
    fn walk(dir: &Path, keep: &dyn Fn(&Path) -> bool, out: &mut Vec<PathBuf>) {
        let Ok(entries) = fs::read_dir(dir) else {
            return;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            let name = entry.file_name().to_string_lossy().into_owned();
            if path.is_dir() {
                let skipped = name.starts_with('.')
                    || name.ends_with(".egg-info")
                    || SKIPPED_DIRS.contains(&name.as_str());
                if !skipped {
                    walk(&path, keep, out);
                }
            } else if keep(&path) {
                out.push(path);
            }
        }
    }
    let ext_in = |exts: &'static [&'static str]| {
        move |p: &Path| {
            p.extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| exts.contains(&e))
        }
    };
    let speed_md = root.join("docs").join("speed.md");
    let mut out = vec![root.join("README.md")];
    walk(
        &root.join("src"),
        &ext_in(&["rs", "h", "hpp", "c", "md"]),
        &mut out,
    );
    walk(
        &root.join("include"),
        &ext_in(&["h", "hpp", "md"]),
        &mut out,
    );
    walk(
        &root.join("docs"),
        &|p: &Path| ext_in(&["md"])(p) && p != speed_md,
        &mut out,
    );
    walk(&root.join("python"), &ext_in(&["py", "md"]), &mut out);
    out.sort();
    out
}

#[test]
fn the_matcher_finds_figures_and_nothing_else() {
    let hits = figures_in;
    assert_eq!(hits("about 0.29 µs for d = 2"), ["0.29 µs"]);
    assert_eq!(
        hits("0.29–0.30 μs (four runs: 291–299 ns)"),
        ["0.30 μs", "299 ns"]
    );
    assert_eq!(hits("`bingham_ahrs_update` 2.2 us per sample"), ["2.2 us"]);
    assert_eq!(
        hits("13ns, 4\u{a0}µs, 21 / 26 µs."),
        ["13ns", "4\u{a0}µs", "26 µs"]
    );
    for clean in [
        "sensor latency 11 ms, sample period 20 ms, a 3 s time constant",
        "an angular spread of ~7 µrad",
        "tolerance 1e-6, 10⁵ cases",
        "a single run's maximum is tens of µs; the table is in (µs)",
        "x2ns, f64us, 3 usages, 5 nsec, 2 nodes",
        "let us say 2 users",
    ] {
        assert!(hits(clean).is_empty(), "{clean:?} gave {:?}", hits(clean));
    }
}

#[test]
fn speed_figures_live_only_in_docs_speed_md() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    assert!(
        root.join("docs/speed.md").is_file(),
        "docs/speed.md, the home of every speed figure, is missing"
    );
    let files = files(root);
    assert!(
        files.iter().any(|p| p.ends_with("README.md")) && files.len() > 3,
        "the walk found too few files under {}",
        root.display()
    );
    let mut offenders = Vec::new();
    for path in &files {
        let Ok(bytes) = fs::read(path) else {
            continue;
        };
        let text = String::from_utf8_lossy(&bytes);
        for (k, line) in text.lines().enumerate() {
            let figures = figures_in(line);
            if !figures.is_empty() {
                let rel = path.strip_prefix(root).unwrap_or(path);
                offenders.push(format!(
                    "{}:{}: [{}] {}",
                    rel.display(),
                    k + 1,
                    figures.join(", "),
                    line.trim()
                ));
            }
        }
    }
    assert!(
        offenders.is_empty(),
        "{} line(s) quote a speed figure; give it a row in docs/speed.md (benchmark, machine, \
         median) and link to that row instead (issue 19: each measured figure has one home):\n{}",
        offenders.len(),
        offenders.join("\n")
    );
}
