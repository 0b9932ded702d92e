//! Every function `include/bingham.h` exports is present in each of the API's mirrors, the
//! places that must change with it and that nothing else keeps in step:
//!
//! - `tests/fuzz_ffi/`: called there (the harness claims every export; see `docs/guarantees.md`);
//! - `c_tests/`: called in a C or C++ program that `tests/c_tests.rs` builds (or in a header
//!   those programs include);
//! - `docs/guide.md`: named in the first column of one of the guide's `| function | what |`
//!   tables;
//! - `python/bingham/_library.py`: a key of `_SIGNATURES` (the ctypes binding);
//! - `include/bingham.hpp`: used by the C++ wrapper.
//!
//! A mirror may leave a function out only through its exemption list below, each entry with its
//! reason; an exemption must name an export that is really absent from that mirror, so that the
//! lists cannot go stale. Where a mirror is a list of names (`_SIGNATURES`, the guide's tables)
//! the other direction is checked as well: every name in it is an export.
//!
//! The exports are read from the header's declarations and cross-checked against the
//! `#[no_mangle]` functions of `src/ffi/`, which are parsed independently (the header itself is
//! checked against cbindgen's output by `tests/header.rs`). Comments and string literals are
//! removed from code before it is searched, so a function named only in a comment, a message or
//! a doc string does not count as called.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

// ---- the exemption lists (name, reason) -------------------------------------------------------

/// Exports `tests/fuzz_ffi/` does not call.
const FUZZ_EXEMPT: &[(&str, &str)] = &[];

/// Exports no program of `c_tests/` calls.
const C_TESTS_EXEMPT: &[(&str, &str)] = &[];

/// Exports the guide's function tables leave out.
const GUIDE_EXEMPT: &[(&str, &str)] = &[];

/// Exports the Python binding does not declare (`_SIGNATURES`).
const PYTHON_EXEMPT: &[(&str, &str)] = &[];

/// Exports the C++ wrapper does not use.
const HPP_EXEMPT: &[(&str, &str)] = &[
    (
        "bingham_filter_dim",
        "bingham::Filter keeps the d it was created with: Filter::dim() is noexcept and needs no \
         library call (0 for a moved-from filter, where the C call would fail)",
    ),
    (
        "bingham_ahrs_update_batch_spread",
        "Ahrs::update_batch's Eigen overload takes optional spread and health outputs and calls \
         bingham_ahrs_update_batch_health, which covers the spread-only form (health NULL)",
    ),
    (
        "bingham_nonlinear_options_default",
        "bingham::NonlinearOptions carries the defaults as member initializers (an aggregate, \
         no library call); c_tests/wrapper_plain.cpp checks them against this function",
    ),
    (
        "bingham_deterministic_samples",
        "not wrapped yet: the C++ wrapper has no deterministic-sampling function (the \
         nonlinear steps use the samples inside the library); C++ callers use the C function",
    ),
    (
        "bingham_deterministic_sample_count",
        "the capacity query of bingham_deterministic_samples, which the wrapper does not wrap \
         (see there)",
    ),
];

// ---- reading the sources ----------------------------------------------------------------------

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap_or_else(|e| panic!("read {rel}: {e}"))
}

/// The files directly in `dir` (relative to the repository) whose names end in one of `exts`,
/// sorted.
fn files(dir: &str, exts: &[&str]) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join(dir))
        .unwrap_or_else(|e| panic!("read_dir {dir}: {e}"))
        .map(|e| e.expect("dir entry").path())
        .filter(|p| {
            p.extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| exts.contains(&e))
        })
        .collect();
    v.sort();
    v
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

#[derive(Clone, Copy, PartialEq)]
enum Lang {
    C,
    Rust,
}

/// `src` with comments and string and character literals replaced by spaces (line breaks
/// kept). Rust's block comments nest and it has raw strings (`r"…"`, `r#"…"#`, also with a `b`
/// prefix) and lifetimes (`'a`, not a literal); C's block comments do not nest.
fn code_only(src: &str, lang: Lang) -> String {
    let c: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    let blank = |out: &mut String, ch: char| out.push(if ch == '\n' { '\n' } else { ' ' });
    let mut i = 0;
    while i < c.len() {
        let next = c.get(i + 1).copied();
        let prev_ident = i > 0 && is_ident(c[i - 1]);
        if c[i] == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if c[i] == '/' && next == Some('*') {
            let mut depth = 0usize;
            loop {
                if i >= c.len() {
                    break;
                }
                if c[i] == '/' && c.get(i + 1) == Some(&'*') && (depth == 0 || lang == Lang::Rust) {
                    depth += 1;
                    i += 2;
                    out.push_str("  ");
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    out.push_str("  ");
                    if depth == 0 {
                        break;
                    }
                } else {
                    blank(&mut out, c[i]);
                    i += 1;
                }
            }
        } else if lang == Lang::Rust
            && !prev_ident
            && (c[i] == 'r' || (c[i] == 'b' && next == Some('r')))
            && {
                let s = if c[i] == 'b' { i + 2 } else { i + 1 };
                let h = c[s..].iter().take_while(|&&ch| ch == '#').count();
                c.get(s + h) == Some(&'"')
            }
        {
            // a raw string: r, any number of #, ", up to " and as many #
            let s = if c[i] == 'b' { i + 2 } else { i + 1 };
            let hashes = c[s..].iter().take_while(|&&ch| ch == '#').count();
            let mut j = s + hashes + 1;
            while j < c.len() && !(c[j] == '"' && c[j + 1..].iter().take(hashes).all(|&h| h == '#'))
            {
                j += 1;
            }
            let end = (j + 1 + hashes).min(c.len());
            for &ch in &c[i..end] {
                blank(&mut out, ch);
            }
            i = end;
        } else if c[i] == '"' {
            blank(&mut out, c[i]);
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    blank(&mut out, c[i]);
                    i += 1;
                }
                if i < c.len() {
                    blank(&mut out, c[i]);
                    i += 1;
                }
            }
            i += 1;
            out.push(' ');
        } else if c[i] == '\'' && next == Some('\\') {
            // an escaped character literal: past the escaped character, up to the closing quote
            let mut j = i + 3;
            while j < c.len() && c[j] != '\'' {
                j += 1;
            }
            for &ch in &c[i..(j + 1).min(c.len())] {
                blank(&mut out, ch);
            }
            i = j + 1;
        } else if c[i] == '\'' && c.get(i + 2) == Some(&'\'') {
            out.push_str("   ");
            i += 3;
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// The identifiers of `code` that start with `bingham_`, each with whether it is followed (after
/// white space) by `(`, i.e. called or declared.
fn identifiers(code: &str) -> Vec<(String, bool)> {
    let c: Vec<char> = code.chars().collect();
    let mut v = Vec::new();
    let mut i = 0;
    while i < c.len() {
        if is_ident(c[i]) && (i == 0 || !is_ident(c[i - 1])) {
            let start = i;
            while i < c.len() && is_ident(c[i]) {
                i += 1;
            }
            let word: String = c[start..i].iter().collect();
            if word.starts_with("bingham_") {
                let mut j = i;
                while j < c.len() && c[j].is_whitespace() {
                    j += 1;
                }
                v.push((word, c.get(j) == Some(&'(')));
            }
        } else {
            i += 1;
        }
    }
    v
}

/// The `bingham_*` functions called in `code` (comments and literals already removed).
fn called(code: &str) -> BTreeSet<String> {
    identifiers(code)
        .into_iter()
        .filter(|(_, call)| *call)
        .map(|(w, _)| w)
        .collect()
}

// ---- the exports ------------------------------------------------------------------------------

/// The functions declared by `include/bingham.h`, in its order: every line outside comments
/// that starts a declaration (`<type> bingham_x(`, not a `typedef`) at column 0.
fn exports() -> Vec<String> {
    let header = code_only(&read("include/bingham.h"), Lang::C);
    let mut v = Vec::new();
    for line in header.lines() {
        if !line.starts_with(|c: char| c.is_ascii_lowercase()) || line.starts_with("typedef") {
            continue;
        }
        let Some(paren) = line.find('(') else {
            continue;
        };
        let before = line[..paren].trim_end();
        let name_start = before.rfind(|c: char| !is_ident(c)).map_or(0, |i| i + 1);
        let name = &before[name_start..];
        if name.starts_with("bingham_") {
            v.push(name.to_string());
        }
    }
    v
}

/// The `#[no_mangle] pub (unsafe) extern "C" fn bingham_*` of `src/ffi/*.rs` (the attribute
/// looked for in code, the name read from the line of the `fn` that follows it).
fn rust_exports() -> BTreeSet<String> {
    let mut s = BTreeSet::new();
    for path in files("src/ffi", &["rs"]) {
        let raw = std::fs::read_to_string(&path).unwrap();
        let code = code_only(&raw, Lang::Rust);
        let mut no_mangle = false;
        for (line, code_line) in raw.lines().map(str::trim).zip(code.lines().map(str::trim)) {
            if code_line == "#[no_mangle]" {
                no_mangle = true;
            } else if no_mangle && !code_line.starts_with("#[") {
                let rest = line
                    .strip_prefix("pub unsafe extern \"C\" fn ")
                    .or_else(|| line.strip_prefix("pub extern \"C\" fn "))
                    .unwrap_or_else(|| panic!("{}: #[no_mangle] before `{line}`", path.display()));
                s.insert(rest.chars().take_while(|&c| is_ident(c)).collect());
                no_mangle = false;
            }
        }
    }
    s
}

// ---- the mirrors ------------------------------------------------------------------------------

fn fuzz_calls() -> BTreeSet<String> {
    let mut s = BTreeSet::new();
    for path in files("tests/fuzz_ffi", &["rs"]) {
        s.extend(called(&code_only(
            &std::fs::read_to_string(&path).unwrap(),
            Lang::Rust,
        )));
    }
    s
}

/// The C and C++ sources of `c_tests/` that `tests/c_tests.rs` builds, and every header there.
fn c_test_sources() -> Vec<PathBuf> {
    let harness = read("tests/c_tests.rs");
    files("c_tests", &["c", "cpp", "h", "hpp"])
        .into_iter()
        .filter(|p| {
            let name = p.file_name().unwrap().to_str().unwrap();
            name.ends_with(".h")
                || name.ends_with(".hpp")
                || harness.contains(&format!("\"{name}\""))
        })
        .collect()
}

fn c_test_calls() -> BTreeSet<String> {
    let mut s = BTreeSet::new();
    for path in c_test_sources() {
        s.extend(called(&code_only(
            &std::fs::read_to_string(&path).unwrap(),
            Lang::C,
        )));
    }
    s
}

fn hpp_uses() -> BTreeSet<String> {
    identifiers(&code_only(&read("include/bingham.hpp"), Lang::C))
        .into_iter()
        .map(|(w, _)| w)
        .collect()
}

/// The keys of `_SIGNATURES` in `python/bingham/_library.py`, in their order (a key given twice
/// appears twice: a dict literal would keep only the last).
fn python_signatures() -> Vec<String> {
    let src = read("python/bingham/_library.py");
    let start = src
        .find("\n_SIGNATURES = {\n")
        .expect("`_SIGNATURES = {` in python/bingham/_library.py");
    let body = &src[start + 1..];
    let end = body.find("\n}\n").expect("the end of _SIGNATURES");
    body[..end]
        .lines()
        .filter_map(|l| {
            let key = l.strip_prefix("    \"")?;
            let (name, rest) = key.split_once('"')?;
            rest.starts_with(':').then(|| name.to_string())
        })
        .collect()
}

/// The names in the first column of the guide's `| function | what |` tables, with the line each
/// comes from. A cell holds code spans such as `` `bingham_filter_new(d, m0, z0, &f)` ``; outside
/// parentheses a span names functions in one of three forms: a full name (`bingham_pdf`),
/// an alternative to the previous name's last words (`bingham_rotate_left/right`:
/// `bingham_rotate_right`), or a shorthand starting with `_` (`_free(f)` after
/// `bingham_spin_filter_new`, `_spread(…)` after `bingham_ahrs_update_batch`): appended to the
/// row's first name, or to that name cut after one of its `_`-separated words, the longest
/// such stem that makes an export. Anything else is an error.
fn guide_names(exports: &BTreeSet<String>) -> (Vec<(usize, String)>, Vec<String>) {
    let guide = read("docs/guide.md");
    let lines: Vec<&str> = guide.lines().collect();
    let mut names = Vec::new();
    let mut errors = Vec::new();
    let first_cell = |l: &str| l.split('|').nth(1).map(str::trim).map(str::to_string);
    let mut i = 0;
    while i < lines.len() {
        let is_table = lines[i].starts_with('|')
            && first_cell(lines[i]).as_deref() == Some("function")
            && lines.get(i + 1).is_some_and(|l| l.starts_with("|---"));
        if !is_table {
            i += 1;
            continue;
        }
        i += 2;
        while i < lines.len() && lines[i].starts_with('|') {
            let lineno = i + 1;
            let cell = first_cell(lines[i]).unwrap_or_default();
            let mut row_first: Option<String> = None;
            let spans: Vec<&str> = cell.split('`').skip(1).step_by(2).collect();
            if spans.is_empty() {
                errors.push(format!("docs/guide.md:{lineno}: no code span in `{cell}`"));
            }
            for span in spans {
                // the span outside parentheses
                let mut depth = 0i32;
                let outer: String = span
                    .chars()
                    .map(|ch| {
                        let keep = depth == 0 && ch != '(';
                        match ch {
                            '(' => depth += 1,
                            ')' => depth -= 1,
                            _ => {}
                        }
                        if keep && ch != ')' {
                            ch
                        } else {
                            ' '
                        }
                    })
                    .collect();
                let mut prev: Option<String> = None;
                for (k, part) in outer.split('/').enumerate() {
                    let word = part.trim();
                    if word.is_empty() || !word.chars().all(is_ident) {
                        errors.push(format!(
                            "docs/guide.md:{lineno}: cannot read `{span}` as function names"
                        ));
                        break;
                    }
                    let name = if k > 0 {
                        // an alternative to the previous name's last words
                        let p = prev.clone().unwrap_or_default();
                        let words: Vec<&str> = p.split('_').collect();
                        let alt = word.split('_').count();
                        if words.len() <= alt {
                            errors.push(format!(
                                "docs/guide.md:{lineno}: `{span}`: no name before `/{word}`"
                            ));
                            break;
                        }
                        format!("{}_{word}", words[..words.len() - alt].join("_"))
                    } else if word.starts_with("bingham_") {
                        word.to_string()
                    } else if word.starts_with('_') {
                        let Some(first) = &row_first else {
                            errors.push(format!(
                                "docs/guide.md:{lineno}: shorthand `{word}` before any full name"
                            ));
                            break;
                        };
                        let words: Vec<&str> = first.split('_').collect();
                        let resolved = (1..=words.len())
                            .rev()
                            .map(|n| format!("{}{word}", words[..n].join("_")))
                            .find(|c| exports.contains(c));
                        match resolved {
                            Some(r) => r,
                            None => {
                                errors.push(format!(
                                    "docs/guide.md:{lineno}: shorthand `{word}` (after `{first}`) \
                                     is no exported function"
                                ));
                                break;
                            }
                        }
                    } else {
                        errors.push(format!(
                            "docs/guide.md:{lineno}: `{word}` in `{span}` is not a bingham_ name"
                        ));
                        break;
                    };
                    if row_first.is_none() {
                        row_first = Some(name.clone());
                    }
                    prev = Some(name.clone());
                    names.push((lineno, name));
                }
            }
            i += 1;
        }
    }
    (names, errors)
}

// ---- the checks -------------------------------------------------------------------------------

/// One line per export missing from `present` (and not exempted), and per exemption that is not
/// an export or not missing. `how` says what presence means, `advice` what to do when missing.
fn check_mirror(
    mirror: &str,
    how: &str,
    advice: &str,
    present: &BTreeSet<String>,
    exempt: &[(&str, &str)],
) -> Vec<String> {
    let exports: Vec<String> = exports();
    let export_set: BTreeSet<&str> = exports.iter().map(String::as_str).collect();
    let mut problems = Vec::new();
    let mut exempted = BTreeMap::new();
    for &(name, reason) in exempt {
        if exempted.insert(name, reason).is_some() {
            problems.push(format!("{mirror}: `{name}` is exempted twice"));
        }
        if reason.split_whitespace().count() < 5 {
            problems.push(format!(
                "{mirror}: the exemption of `{name}` needs a reason (got {reason:?})"
            ));
        }
        if !export_set.contains(name) {
            problems.push(format!(
                "{mirror}: `{name}` is exempted but include/bingham.h exports no such function \
                 (remove the stale exemption)"
            ));
        } else if present.contains(name) {
            problems.push(format!(
                "{mirror}: `{name}` is exempted but {how} (remove the stale exemption)"
            ));
        }
    }
    for name in &exports {
        if !present.contains(name) && !exempted.contains_key(name.as_str()) {
            problems.push(format!(
                "{mirror}: `{name}` is exported by include/bingham.h but not {how}: {advice}"
            ));
        }
    }
    problems
}

fn fail_on(problems: Vec<String>) {
    assert!(
        problems.is_empty(),
        "{} problem(s):\n  {}",
        problems.len(),
        problems.join("\n  ")
    );
}

#[test]
fn header_exports_are_the_ffi_functions() {
    let exports = exports();
    // positive control: names the parser must find, in the header's order
    for known in [
        "bingham_version",
        "bingham_mode",
        "bingham_filter_free",
        "bingham_filter_update_gated",
        "bingham_nonlinear_options_default",
        "bingham_ahrs_params_from_rate",
        "bingham_ahrs_update_batch_health",
        "bingham_spin_filter_angular_spread",
    ] {
        assert!(exports.iter().any(|e| e == known), "{known} not found");
    }
    assert_eq!(exports[0], "bingham_version", "the header's first function");
    let set: BTreeSet<String> = exports.iter().cloned().collect();
    assert_eq!(set.len(), exports.len(), "a function declared twice");
    let rust = rust_exports();
    assert!(rust.len() >= 70, "only {} exports in src/ffi/", rust.len());
    assert_eq!(
        set,
        rust,
        "the header's declarations differ from src/ffi/'s #[no_mangle] functions \
         (header only: {:?}; src/ffi only: {:?})",
        set.difference(&rust).collect::<Vec<_>>(),
        rust.difference(&set).collect::<Vec<_>>()
    );
}

#[test]
fn code_only_removes_comments_and_literals() {
    let c = "a(); // bingham_x(\n/* bingham_y( /* */ bingham_z (1);\n\
             s = \"bingham_s(\\\" bingham_t(\"; c = '\"'; bingham_u(c);";
    let want: BTreeSet<String> = ["bingham_z", "bingham_u"].map(String::from).into();
    assert_eq!(called(&code_only(c, Lang::C)), want);
    let rust = "/* a /* nested */ bingham_x( */ bingham_a(r#\"bingham_b(\"#);\n\
                fn f<'a>(x: &'a str) { bingham_c(b'x', '\\'', r\"bingham_d(\") }";
    let want: BTreeSet<String> = ["bingham_a", "bingham_c"].map(String::from).into();
    assert_eq!(called(&code_only(rust, Lang::Rust)), want);
    // a function pointer is used, not called
    let ids = identifiers("binary(bingham_multiply, a) bingham_mode (x)");
    assert_eq!(
        ids,
        vec![
            ("bingham_multiply".to_string(), false),
            ("bingham_mode".to_string(), true)
        ]
    );
}

#[test]
fn every_export_is_fuzzed() {
    let calls = fuzz_calls();
    // positive control: functions the harness has always called
    assert!(calls.contains("bingham_mode") && calls.contains("bingham_ahrs_update"));
    fail_on(check_mirror(
        "tests/fuzz_ffi/",
        "called in tests/fuzz_ffi/",
        "add a case in the harness's style (NULL, misaligned, NaN, hostile values, outputs \
         untouched on error) or exempt it in tests/api_mirrors.rs with the reason",
        &calls,
        FUZZ_EXEMPT,
    ));
}

#[test]
fn every_export_is_called_by_a_c_test() {
    let sources = c_test_sources();
    assert!(
        sources.iter().any(|p| p.ends_with("api_errors.c"))
            && sources.iter().any(|p| p.ends_with("wrapper_plain.cpp")),
        "the C test programs were not found: {sources:?}"
    );
    let calls = c_test_calls();
    assert!(calls.contains("bingham_mode") && calls.contains("bingham_spin_filter_step"));
    fail_on(check_mirror(
        "c_tests/",
        "called in a program of c_tests/ built by tests/c_tests.rs",
        "add a call with an asserted result",
        &calls,
        C_TESTS_EXEMPT,
    ));
}

#[test]
fn every_export_is_in_the_guide_table() {
    let exports: BTreeSet<String> = exports().into_iter().collect();
    let (names, mut problems) = guide_names(&exports);
    // positive control: a plain row, an alternative and a shorthand
    for known in [
        "bingham_mle",
        "bingham_rotate_right",
        "bingham_spin_filter_free",
    ] {
        assert!(
            names.iter().any(|(_, n)| n == known),
            "the guide's tables were not read: {known} missing from {names:?}"
        );
    }
    for (line, name) in &names {
        if !exports.contains(name) {
            problems.push(format!(
                "docs/guide.md:{line}: the function table names `{name}`, which include/bingham.h \
                 does not export"
            ));
        }
    }
    let present: BTreeSet<String> = names.into_iter().map(|(_, n)| n).collect();
    problems.extend(check_mirror(
        "docs/guide.md",
        "named in a `| function | what |` table of docs/guide.md",
        "add a row in its style",
        &present,
        GUIDE_EXEMPT,
    ));
    fail_on(problems);
}

#[test]
fn every_export_has_a_python_signature() {
    let keys = python_signatures();
    assert!(keys.iter().any(|k| k == "bingham_mle"), "{keys:?}");
    let exports: BTreeSet<String> = exports().into_iter().collect();
    let mut problems = Vec::new();
    let mut seen = BTreeSet::new();
    for k in &keys {
        if !seen.insert(k.clone()) {
            problems.push(format!(
                "python/bingham/_library.py: `{k}` appears twice in _SIGNATURES"
            ));
        }
        if !exports.contains(k) {
            problems.push(format!(
                "python/bingham/_library.py: _SIGNATURES declares `{k}`, which include/bingham.h \
                 does not export"
            ));
        }
    }
    problems.extend(check_mirror(
        "python/bingham/_library.py",
        "declared in _SIGNATURES",
        "add its restype and argtypes",
        &seen,
        PYTHON_EXEMPT,
    ));
    fail_on(problems);
}

#[test]
fn every_export_is_used_by_the_cpp_wrapper() {
    let uses = hpp_uses();
    assert!(uses.contains("bingham_multiply") && uses.contains("bingham_ahrs_health"));
    fail_on(check_mirror(
        "include/bingham.hpp",
        "used by the C++ wrapper",
        "wrap it, or exempt it in tests/api_mirrors.rs with the reason",
        &uses,
        HPP_EXEMPT,
    ));
}
