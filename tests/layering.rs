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
//! 6. `ahrs`, and `smoother` on it (the offline smoother runs the AHRS twice)
//! 7. `ffi` (the C ABI)
//!
//! Between the files (the rules of [`file_rules`]): no file takes names from the module file of
//! a folder it lives in (shared names live in a sibling file, e.g. `filter/types.rs`), and no
//! files import one another in a circle.
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
    ("smoother", 6),
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

// --- files: no file takes items from its folder's module file, no circle between files -------

/// A token of Rust source, as far as module paths need it: identifiers, `::` and single
/// punctuation characters. Comments, string and character literals and numbers are dropped.
#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    PathSep,
    Punct(char),
}

fn tokens(text: &str) -> Vec<Tok> {
    let s: Vec<char> = text.chars().collect();
    let ident_char = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let mut out = Vec::new();
    let mut i = 0;
    // skips a string body from the opening quote at `j` (escapes honoured), returns the index
    // after the closing quote
    let string_end = |mut j: usize| {
        j += 1;
        while j < s.len() && s[j] != '"' {
            j += if s[j] == '\\' { 2 } else { 1 };
        }
        j + 1
    };
    // skips a character literal from its opening quote at `j` ('x', '\n', '\'', '\u{..}'),
    // returns the index after the closing quote
    let char_end = |j: usize| {
        if s.get(j + 1) == Some(&'\\') {
            let mut k = j + 3;
            while k < s.len() && s[k] != '\'' {
                k += 1;
            }
            k + 1
        } else {
            j + 3
        }
    };
    while i < s.len() {
        let c = s[i];
        let next = s.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < s.len() && s[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < s.len() {
                if s[i] == '/' && s.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if s[i] == '*' && s.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if c == '"' {
            i = string_end(i);
        } else if c == '\'' {
            // a character literal or a lifetime ('a)
            if next == Some('\\') || s.get(i + 2) == Some(&'\'') {
                i = char_end(i);
            } else {
                i += 1;
            }
        } else if c.is_ascii_digit() {
            while i < s.len()
                && (ident_char(s[i])
                    || (s[i] == '.' && s.get(i + 1).is_some_and(|d| d.is_ascii_digit())))
            {
                i += 1;
            }
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < s.len() && ident_char(s[i]) {
                i += 1;
            }
            let word: String = s[start..i].iter().collect();
            let raw = matches!(word.as_str(), "r" | "br")
                && (s.get(i) == Some(&'"') || s.get(i) == Some(&'#'));
            if raw {
                // r"…", r#"…"#, br"…"
                let mut hashes = 0;
                while s.get(i) == Some(&'#') {
                    hashes += 1;
                    i += 1;
                }
                i += 1;
                loop {
                    if i >= s.len() {
                        break;
                    }
                    if s[i] == '"' && (1..=hashes).all(|k| s.get(i + k) == Some(&'#')) {
                        i += 1 + hashes;
                        break;
                    }
                    i += 1;
                }
            } else if word == "b" && s.get(i) == Some(&'"') {
                i = string_end(i);
            } else if word == "b" && s.get(i) == Some(&'\'') {
                i = char_end(i);
            } else {
                out.push(Tok::Ident(word));
            }
        } else if c == ':' && next == Some(':') {
            out.push(Tok::PathSep);
            i += 2;
        } else {
            if !c.is_whitespace() {
                out.push(Tok::Punct(c));
            }
            i += 1;
        }
    }
    out
}

/// Parses the path (or `use` tree) starting at `toks[i]` below `prefix` into `out`, one entry
/// per leaf (`a::{b, c::*}` gives `a::b` and `a::c::*`); returns the index after it.
fn path_tree(toks: &[Tok], mut i: usize, prefix: Vec<String>, out: &mut Vec<Vec<String>>) -> usize {
    let mut path = prefix;
    loop {
        match toks.get(i) {
            Some(Tok::Ident(w)) => {
                path.push(w.clone());
                i += 1;
            }
            Some(Tok::Punct('*')) => {
                path.push("*".into());
                out.push(path);
                return i + 1;
            }
            Some(Tok::Punct('{')) => {
                i += 1;
                while i < toks.len() && toks[i] != Tok::Punct('}') {
                    i = path_tree(toks, i, path.clone(), out);
                    // `as alias` and the separating comma
                    while i < toks.len() && !matches!(toks[i], Tok::Punct(',') | Tok::Punct('}')) {
                        i += 1;
                    }
                    if toks.get(i) == Some(&Tok::Punct(',')) {
                        i += 1;
                    }
                }
                return i + 1;
            }
            _ => {
                out.push(path);
                return i;
            }
        }
        if toks.get(i) == Some(&Tok::PathSep) {
            i += 1;
        } else {
            out.push(path);
            return i;
        }
    }
}

/// One module path used in a file: the module the file is in at that point (its file's module,
/// or an inline `mod … { }` inside it) and the path's segments.
struct Use {
    at: Vec<String>,
    path: Vec<String>,
}

/// Every path of two or more segments (`a::b`, `a::{b, c}`) in the code of `text`, whose file
/// is module `module`.
fn paths_used(text: &str, module: &[String]) -> Vec<Use> {
    let toks = tokens(text);
    let mut out = Vec::new();
    let mut depth = 0usize;
    // inline modules open at this point, with the brace depth outside them
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut i = 0;
    while i < toks.len() {
        match &toks[i] {
            Tok::Punct('{') => depth += 1,
            Tok::Punct('}') => {
                depth = depth.saturating_sub(1);
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
            }
            Tok::Ident(w) if w == "mod" => {
                if let (Some(Tok::Ident(name)), Some(Tok::Punct('{'))) =
                    (toks.get(i + 1), toks.get(i + 2))
                {
                    inline.push((name.clone(), depth));
                }
            }
            // `pub(in crate::filter)` restricts visibility, it does not use the module
            Tok::Ident(w)
                if w == "in"
                    && i > 0
                    && toks[i - 1] == Tok::Punct('(')
                    && toks.get(i + 1).is_some_and(|t| matches!(t, Tok::Ident(_))) =>
            {
                let mut skipped = Vec::new();
                i = path_tree(&toks, i + 1, Vec::new(), &mut skipped);
                continue;
            }
            Tok::Ident(_)
                if toks.get(i + 1) == Some(&Tok::PathSep)
                    && (i == 0 || toks[i - 1] != Tok::PathSep) =>
            {
                let mut at = module.to_vec();
                at.extend(inline.iter().map(|(n, _)| n.clone()));
                let mut leaves = Vec::new();
                let end = path_tree(&toks, i, Vec::new(), &mut leaves);
                out.extend(leaves.into_iter().map(|path| Use {
                    at: at.clone(),
                    path,
                }));
                // the braces of a `use` group are balanced and skipped with it
                i = end;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    out
}

/// The module of a file under `src/` (`a/b/mod.rs` and `a/b.rs` are `a::b`; `lib.rs` the root).
fn module_path(rel: &str) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .trim_end_matches(".rs")
        .split('/')
        .map(String::from)
        .collect();
    if matches!(parts.last().map(String::as_str), Some("mod") | Some("lib")) {
        parts.pop();
    }
    parts
}

/// Where a path used in module `at` leads: the file module it reaches (walking its segments
/// while they name modules that have a file) and whether it takes items of that module (`X`
/// or `*` after the module) rather than naming the module itself. `None` for paths outside
/// the crate (`std::…`, `nalgebra::…`, `Self::…`, enum variants of imported types).
fn resolve(
    at: &[String],
    path: &[String],
    modules: &BTreeMap<Vec<String>, String>,
) -> Option<(Vec<String>, bool)> {
    let (mut base, mut k) = match path[0].as_str() {
        "crate" => (Vec::new(), 1),
        "self" => (at.to_vec(), 1),
        "super" => {
            let mut b = at.to_vec();
            let mut k = 0;
            while path.get(k).is_some_and(|s| s == "super") {
                b.pop()?;
                k += 1;
            }
            (b, k)
        }
        // a child module named without `self::` (`use noise::Noise;` in `filter/mod.rs`)
        name => {
            let mut child = at.to_vec();
            child.push(name.to_string());
            if !modules.contains_key(&child) {
                return None;
            }
            (at.to_vec(), 0)
        }
    };
    let mut takes_items = false;
    while let Some(seg) = path.get(k) {
        if seg == "self" {
            break;
        }
        if seg == "*" {
            takes_items = true;
            break;
        }
        let mut next = base.clone();
        next.push(seg.clone());
        if modules.contains_key(&next) {
            base = next;
            k += 1;
        } else {
            takes_items = true;
            break;
        }
    }
    // an inline module (`mod tests { }`) is part of its file
    while !modules.contains_key(&base) {
        base.pop()?;
    }
    Some((base, takes_items))
}

fn show(module: &[String]) -> String {
    if module.is_empty() {
        "crate".into()
    } else {
        module.join("::")
    }
}

/// The rules between the files of `src/` (given as `(path under src/, text)`); every path in
/// the code (a `use`, or a path in an expression or a type) counts, resolved to the file of the
/// module it reaches: `crate::filter::noise::Noise` and, inside `filter/`, `super::noise::Noise`
/// reach `filter/noise.rs`; `crate::filter::BinghamFilter` reaches `filter/mod.rs`.
///
/// 1. **No file takes items from the module file of a folder it lives in**: a file under
///    `a/` (at any depth) names no item of `a/mod.rs` (or of `a.rs` beside a folder `a/`) —
///    not `super::X`, `super::*` or `crate::a::X` for an `X` defined or re-exported there;
///    `super::sibling::X` and `crate::a::sibling::X` are fine. Shared names live in a file of
///    their own beside their users (`filter/types.rs`). A folder's module file declares its
///    children and re-exports their public names: it is the folder's front door, not its
///    pantry. Exempt: the crate root (`lib.rs`, the public facade) and unit-test files
///    (`…/tests.rs`: leaves nothing imports, which exist to reach what they test).
/// 2. **No circle between files**: in the graph with an edge from each file to every file its
///    paths reach, there is no cycle (a file reaching itself, through `self::` or an inline
///    `mod tests`, is no edge). `mod x;` is no edge either: declaring a child is not using it,
///    but a re-export (`pub use x::Y;`) is. So a child that takes a name from its folder's
///    module file, which declares and uses the child, closes a circle through it.
///
/// What it does not see: a method called on a value whose type has an `impl` block in another
/// file (`ct.march(…)` with `impl Contour` in `contour/path.rs`), and names a macro brings in.
/// `pub(in crate::a)` restricts visibility and is not a path used.
fn file_rules(files: &[(String, String)]) -> Vec<String> {
    let modules: BTreeMap<Vec<String>, String> = files
        .iter()
        .map(|(rel, _)| (module_path(rel), rel.clone()))
        .collect();
    let mut wrong = Vec::new();
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (rel, text) in files {
        let module = module_path(rel);
        // a unit-test file is a leaf (nothing imports it) that reaches what it tests
        let is_tests = module.last().is_some_and(|m| m == "tests");
        for u in paths_used(text, &module) {
            let Some((target, takes_items)) = resolve(&u.at, &u.path, &modules) else {
                continue;
            };
            let file = &modules[&target];
            if file == rel {
                continue;
            }
            edges.entry(rel.clone()).or_default().insert(file.clone());
            let ancestor = target.len() < module.len() && module.starts_with(&target);
            let exempt = target.is_empty() || is_tests;
            if ancestor && takes_items && !exempt {
                let message = format!(
                    "src/{rel}: `{}` takes an item from src/{file}, the module file of its folder `{}`",
                    u.path.join("::"),
                    show(&target)
                );
                if !wrong.contains(&message) {
                    wrong.push(message);
                }
            }
        }
    }
    // circles: depth-first search, each reported once (from its smallest file)
    fn visit(
        n: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
        circles: &mut BTreeSet<Vec<String>>,
    ) {
        match state.get(n) {
            Some(2) => return,
            Some(1) => {
                let from = stack.iter().position(|s| s == n).expect("on the stack");
                let mut circle = stack[from..].to_vec();
                let least = (0..circle.len()).min_by_key(|&j| &circle[j]).unwrap_or(0);
                circle.rotate_left(least);
                circles.insert(circle);
                return;
            }
            _ => {}
        }
        state.insert(n.to_string(), 1);
        stack.push(n.to_string());
        for m in edges.get(n).into_iter().flatten() {
            visit(m, edges, state, stack, circles);
        }
        stack.pop();
        state.insert(n.to_string(), 2);
    }
    let mut state = BTreeMap::new();
    let mut circles = BTreeSet::new();
    for n in edges.keys() {
        visit(n, &edges, &mut state, &mut Vec::new(), &mut circles);
    }
    for c in circles {
        wrong.push(format!(
            "import circle between files: src/{} -> src/{}",
            c.join(" -> src/"),
            c[0]
        ));
    }
    wrong
}

/// `file_rules` on a made-up tree: the violations it must find, and the forms it must accept.
#[test]
fn the_file_rules_catch_a_folder_import_and_a_circle() {
    fn check(files: &[(&str, &str)]) -> Vec<String> {
        let files: Vec<(String, String)> = files
            .iter()
            .map(|(rel, text)| (rel.to_string(), text.to_string()))
            .collect();
        file_rules(&files)
    }
    // filter/ as it was: children took `Mat` from filter/mod.rs, which uses them in turn
    let wrong = check(&[
        ("lib.rs", "pub mod filter;\n"),
        (
            "filter/mod.rs",
            "mod noise;\nmod nonlinear;\npub use noise::Noise;\ntype Mat = [f64; 4];\n",
        ),
        (
            "filter/noise.rs",
            "use super::Mat;\npub struct Noise(Mat);\n",
        ),
        ("filter/nonlinear/mod.rs", "mod steps;\n"),
        (
            "filter/nonlinear/steps.rs",
            "fn f() { let _ = crate::filter::Noise::new(); }\nuse super::super::*;\n",
        ),
    ]);
    let want = [
        "src/filter/noise.rs: `super::Mat` takes an item from src/filter/mod.rs, the module \
         file of its folder `filter`",
        "src/filter/nonlinear/steps.rs: `crate::filter::Noise::new` takes an item from \
         src/filter/mod.rs, the module file of its folder `filter`",
        "src/filter/nonlinear/steps.rs: `super::super::*` takes an item from src/filter/mod.rs, \
         the module file of its folder `filter`",
        "import circle between files: src/filter/mod.rs -> src/filter/noise.rs -> \
         src/filter/mod.rs",
    ];
    assert_eq!(wrong, want);
    // two siblings that use each other, one of them inside a function body
    let wrong = check(&[
        ("lib.rs", "mod ahrs;\n"),
        ("ahrs/mod.rs", "mod lowpass;\nmod magnetic;\n"),
        (
            "ahrs/lowpass.rs",
            "fn c() -> f64 { super::magnetic::TEST_TIME }\n",
        ),
        (
            "ahrs/magnetic.rs",
            "use super::lowpass::{self, c};\npub(super) const TEST_TIME: f64 = 1.0;\n",
        ),
    ]);
    assert_eq!(
        wrong,
        [
            "import circle between files: src/ahrs/lowpass.rs -> src/ahrs/magnetic.rs -> \
          src/ahrs/lowpass.rs"
        ]
    );
    // literals that look like the end of a string or a character
    let wrong = check(&[
        ("lib.rs", "mod a;\nmod b;\n"),
        (
            "a.rs",
            "const Q: char = '\\'';\nconst B: u8 = b'\\'';\nconst S: &str = \"\\\" crate::b::X\";\nfn f<'a>(x: &'a str) -> &'a str { x }\n",
        ),
        ("b.rs", "pub const X: u8 = crate::a::B;\n"),
    ]);
    assert!(wrong.is_empty(), "{wrong:#?}");
    // the accepted forms: siblings, a grandparent's sibling, an inline test module, a unit-test
    // file, a visibility path, the crate root, and paths in comments and strings
    let steps = r#"use crate::filter::types::Mat;
use super::super::types;
use crate::Mat as M;
// super::super::Mat in a comment, /* crate::filter::Mat */ in another
const S: &str = "crate::filter::Mat";
pub(in crate::filter) fn f() {}
#[cfg(test)]
mod tests {
    use super::*;
}
"#;
    let wrong = check(&[
        ("lib.rs", "pub mod filter;\npub use filter::Mat;\n"),
        (
            "filter/mod.rs",
            "mod nonlinear;\nmod types;\n#[cfg(test)]\nmod tests;\npub use types::Mat;\n",
        ),
        ("filter/types.rs", "pub type Mat = [f64; 4];\n"),
        ("filter/tests.rs", "use super::*;\n"),
        ("filter/nonlinear/mod.rs", "mod steps;\n"),
        ("filter/nonlinear/steps.rs", steps),
    ]);
    assert!(wrong.is_empty(), "{wrong:#?}");
}

#[test]
fn files_import_siblings_not_their_folder_and_without_circles() {
    let wrong = file_rules(&sources());
    assert!(
        wrong.is_empty(),
        "file-level import violations:\n{}",
        wrong.join("\n")
    );
}
