//! The crate's layering, locked in: every `crate::<module>` path in `src/` must point to the same
//! layer or one below, and the modules import one another without a circle. The layers, from the
//! bottom (docs/design.md, "Layout"):
//!
//! 0. kernels: `error`, `special`
//! 1. linear algebra: `linalg`, `quaternion`, `canonical` (the canonical form of `(M, z)`)
//! 2. `normalization`
//! 3. `distribution`
//! 4. built on the distribution: `mle`, `sampler`, `deterministic`, `observation`
//! 5. `filter`
//! 6. `ahrs`
//! 7. `ffi` (the C ABI)
//!
//! It also checks that `unsafe` appears only in `src/ffi/` and in the one module that calls the
//! SIMD kernels compiled for run-time detected CPU features (`normalization/quadrature/simd.rs`).

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

const LAYERS: &[(&str, u32)] = &[
    ("error", 0),
    ("special", 0),
    ("linalg", 1),
    ("quaternion", 1),
    ("canonical", 1),
    ("normalization", 2),
    ("distribution", 3),
    ("mle", 4),
    ("sampler", 4),
    ("deterministic", 4),
    ("observation", 4),
    ("filter", 5),
    ("ahrs", 6),
    ("ffi", 7),
];

/// The files allowed to contain `unsafe` (relative to `src/`).
const UNSAFE_HOMES: &[&str] = &["ffi/", "normalization/quadrature/simd.rs"];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in fs::read_dir(dir).expect("readable src/") {
        let p = e.expect("entry").path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The top-level module a file under `src/` belongs to (`lib` for `src/lib.rs`).
fn module_of(rel: &str) -> String {
    let first = rel.split('/').next().expect("non-empty");
    first.trim_end_matches(".rs").to_string()
}

/// The code of a line, without a `//` comment (doc comments included) and string contents are
/// not an issue here: module paths in strings do not occur in `src/`.
fn code(line: &str) -> &str {
    match line.find("//") {
        Some(i) => &line[..i],
        None => line,
    }
}

/// Every `crate::<name>` in the code of `text`.
fn crate_paths(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for line in text.lines() {
        let c = code(line);
        let mut rest = c;
        while let Some(i) = rest.find("crate::") {
            let after = &rest[i + 7..];
            let name: String = after
                .chars()
                .take_while(|ch| ch.is_ascii_alphanumeric() || *ch == '_')
                .collect();
            // `pub(crate)` and `$crate` are not paths into a module
            let before = &rest[..i];
            if !name.is_empty() && !before.ends_with('$') {
                out.insert(name);
            }
            rest = after;
        }
    }
    out
}

fn sources() -> Vec<(String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    files.sort();
    files
        .into_iter()
        .map(|p| {
            let rel = p
                .strip_prefix(&root)
                .expect("under src/")
                .to_string_lossy()
                .replace('\\', "/");
            (rel, fs::read_to_string(&p).expect("readable source"))
        })
        .collect()
}

#[test]
fn imports_run_down_the_layers() {
    let layer: BTreeMap<&str, u32> = LAYERS.iter().copied().collect();
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut wrong = Vec::new();
    for (rel, text) in sources() {
        let from = module_of(&rel);
        if from == "lib" {
            continue; // the crate root declares and re-exports every module
        }
        let Some(&lf) = layer.get(from.as_str()) else {
            wrong.push(format!(
                "{rel}: module `{from}` has no layer in tests/layering.rs"
            ));
            continue;
        };
        for to in crate_paths(&text) {
            if to == from {
                continue;
            }
            match layer.get(to.as_str()) {
                None => {
                    // items re-exported at the crate root (`crate::Bingham`, `crate::Error`)
                    if to.chars().next().is_some_and(|c| c.is_ascii_uppercase()) {
                        continue;
                    }
                    wrong.push(format!("{rel}: `crate::{to}` is not a known module"));
                }
                Some(&lt) if lt > lf => wrong.push(format!(
                    "{rel}: `{from}` (layer {lf}) uses `crate::{to}` (layer {lt}), which is above it"
                )),
                Some(_) => {
                    edges.entry(from.clone()).or_default().insert(to);
                }
            }
        }
    }
    // no circle among the modules (same-layer imports are allowed, circles are not)
    fn visit(
        n: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
        wrong: &mut Vec<String>,
    ) {
        match state.get(n) {
            Some(2) => return,
            Some(1) => {
                wrong.push(format!("import circle: {} -> {n}", stack.join(" -> ")));
                return;
            }
            _ => {}
        }
        state.insert(n.to_string(), 1);
        stack.push(n.to_string());
        for m in edges.get(n).into_iter().flatten() {
            visit(m, edges, state, stack, wrong);
        }
        stack.pop();
        state.insert(n.to_string(), 2);
    }
    let mut state = BTreeMap::new();
    for n in edges.keys() {
        visit(n, &edges, &mut state, &mut Vec::new(), &mut wrong);
    }
    assert!(
        wrong.is_empty(),
        "layering violations:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn unsafe_lives_in_the_ffi_and_the_simd_dispatch() {
    let mut wrong = Vec::new();
    for (rel, text) in sources() {
        if UNSAFE_HOMES.iter().any(|h| rel.starts_with(h)) {
            continue;
        }
        for (i, line) in text.lines().enumerate() {
            let c = code(line);
            if c.split(|ch: char| !(ch.is_ascii_alphanumeric() || ch == '_'))
                .any(|w| w == "unsafe")
            {
                wrong.push(format!("src/{rel}:{}: {}", i + 1, line.trim()));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "`unsafe` outside src/ffi/ and normalization/quadrature/simd.rs:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_checker_sees_paths_and_skips_comments() {
    let found = crate_paths(
        "use crate::linalg::{a, b};\n// crate::ffi in a comment\npub(crate) fn f() { crate::error::x(); }\n",
    );
    let want: BTreeSet<String> = ["linalg", "error"].iter().map(|s| s.to_string()).collect();
    assert_eq!(found, want);
    assert_eq!(
        module_of("normalization/quadrature/simd.rs"),
        "normalization"
    );
    assert_eq!(module_of("ahrs.rs"), "ahrs");
}
