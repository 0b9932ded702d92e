//! The paths the documentation names exist, its Markdown links land on files and headings that
//! exist, and the version it asks users for is the crate's.
//!
//! Files move — a module becomes a folder, a test is renamed, an example is dropped — and the
//! prose that pointed at them is out of the compiler's view: a reader who follows
//! `src/ahrs/rest.rs` or `[accuracy](docs/accuracy/filter.md#…)` to nothing stops trusting the
//! rest of the page. Likewise a CMake snippet asking for `find_package(bingham 0.2)` when the crate
//! is 0.3 fails for everyone who copies it (0.x: the minor version must match).
//!
//! **What is read**: every Markdown file of the checkout (`README.md`, `docs/**/*.md`,
//! `CONTRIBUTING.md` when there is one, `python/README.md`, `tests/data/README.md`, …; build output
//! and virtual environments are not entered), all of it — prose, code spans and code blocks — and
//! the comments (`//`, `///`, `//!`) of `src/**/*.rs`.
//!
//! **What counts as a repository path** (`named_path`):
//!
//! 1. A *token* is a run of characters between delimiters: white space, backticks, quotes,
//!    `()[]<>{}`, `|`, `=`, `,`, `;`, `\`. A `{…}` group, or a `<…>` group inside a token, without
//!    white space stays part of it (`normalization_d{2..8}.csv`, `benches/<bench>.rs`). Trailing
//!    `.`, `,`, `:`, `;`, `!`, `?` are sentence punctuation and dropped, so are an ellipsis
//!    (`src/…`, `cmake/...` name the folder), a leading `./` and `*`/`_` emphasis around it.
//! 2. Not paths: URLs (`://`, `mailto:`), Rust paths (`::`, e.g. `crate::ffi::args`), absolute
//!    or variable paths (`/…`, `~…`, `$…`) and tokens starting with `../` (outside the
//!    repository, such as the sibling `../shared/`; relative Markdown links are checked by rule 5
//!    instead).
//! 3. A token is a repository path when it contains a `/` and its first component is one of the
//!    repository's top-level folders ([`TOP_DIRS`], plus any folder at the root of the checkout),
//!    or it is, without a `/`, a top-level file name ([`TOP_FILES`], plus any file at the root):
//!    `src/ahrs/rest.rs`, `tests/fuzz_ffi/`, `docs/speed.md`, `Makefile`, `Cargo.toml`. Names
//!    relative to something else are not checked: `rest.rs`, `quad/` (beside the file that names
//!    it), `lib/cmake/bingham/` (the install layout), `bingham/_lib/` (inside `python/`), nor are
//!    quotients such as `rad/s` or `1/R`. Paths under `target/` (or `target-*/`) are build outputs
//!    and skipped. A bare file name is not looked for elsewhere in the tree: the documents also
//!    name the reader's files (`example.c`, `main.cpp`) and outputs (`spin.csv`, `broad.json`).
//!    Prose that uses a slash for "or" after a top-level folder's name (`tests/benches`) reads as
//!    a path: write "tests and benches".
//! 4. Suffixes: `#anchor` is checked against the target's headings (rule 6) when the target is a
//!    Markdown file; a `:line` suffix (`:42`, `:42:7`, `:42-50`) is dropped; a trailing `/` means
//!    the path must be a folder. `{a,b}` and `{2..8}` are expanded and every expansion must exist;
//!    `*`, `?`, a placeholder `<name>` and a `{name}` are wildcards: the folder before the first
//!    wildcard component must exist and, when the wildcard is in the last component, at least one
//!    entry of it must match (`docs/accuracy/*.md`).
//!
//! In Markdown files, besides:
//!
//! 5. Links — `[text](target)`, `![alt](target)` and `[id]: target`, outside code spans and code
//!    blocks: every target that is not a URL is resolved as GitHub does, against the linking file's
//!    folder (`/…` against the repository root), and must exist, unless it leaves the repository or
//!    lands in `target/`. A bare `#anchor` points into the linking file itself.
//! 6. Anchors: a Markdown file's anchors are its headings' slugs — GitHub's rule: the heading's
//!    text (inline code and emphasis markers, link targets and HTML tags removed) lower-cased,
//!    every character other than a letter, a digit, `_`, `-` or a space removed, each space made a
//!    `-`, and a repeated slug given `-1`, `-2`, … — and the `id="…"` / `name="…"` of its HTML
//!    tags (the `<a id="…">` rows of `docs/speed.md`). Headings in code blocks do not count. Known
//!    differences: GitHub drops the underscores of `_emphasis_` in a heading, this keeps them, and
//!    GitHub keeps combining marks, which `char::is_alphanumeric` drops (no heading has either).
//!
//! **Versions** (`versions_are_the_crates`): every `find_package(bingham X.Y …)` in the Markdown
//! files, `cmake/`, `scripts/`, `examples/` and the `Makefile` must ask for the crate's
//! `major.minor` (`0.minor` before 1.0), and the README must have one; every
//! `libbingham.so.X.Y.Z` there must be the crate's version and every shorter
//! `libbingham.so.X[.Y]` its SONAME version (`0.minor` before 1.0, else the major: `build.rs`);
//! the Python package's version must come from `Cargo.toml` (`python/pyproject.toml` declares
//! it `dynamic` or states the crate's, and `python/setup.py` reads `Cargo.toml` and states no
//! other).
//! The header's `BINGHAM_VERSION_*` macros are checked by `tests/header.rs`; the `Makefile` and
//! the `cmake/*.in` templates take `@VERSION@` from `Cargo.toml` when installing.
//!
//! Run it alone with `cargo test --release --test doc_paths`.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// The repository's top-level folders. Folders present at the root of the checkout count too;
/// this list keeps a renamed or removed folder's old name a path, so that what still names it
/// is reported.
const TOP_DIRS: &[&str] = &[
    ".ci", "benches", "c_tests", "cmake", "docs", "examples", "include", "python", "scripts",
    "src", "testkit", "tests",
];

/// The repository's top-level files, and the conventional ones a document might name (a
/// license, a changelog, contributing notes) so that a mention of a missing one is reported.
const TOP_FILES: &[&str] = &[
    ".gitignore",
    "Cargo.lock",
    "Cargo.toml",
    "Makefile",
    "README.md",
    "bingham.pc.in",
    "build.rs",
    "cbindgen.toml",
    "CHANGELOG.md",
    "CONTRIBUTING.md",
    "LICENSE",
    "LICENSE-APACHE",
    "LICENSE-MIT",
];

/// Directory names never entered: version control, build output, virtual environments, caches.
const SKIPPED_DIRS: &[&str] = &[
    ".git",
    "target",
    "build",
    "dist",
    "venv",
    ".venv",
    "__pycache__",
    "node_modules",
];

/// Build output: `target/` and the `target-*/` folders of other toolchains (see `.gitignore`).
fn is_build_output(first_component: &str) -> bool {
    first_component == "target" || first_component.starts_with("target-")
}

fn skipped_dir(name: &str) -> bool {
    SKIPPED_DIRS.contains(&name) || is_build_output(name) || name.ends_with(".egg-info")
}

// ------------------------------------------------------------------------------------------------
// Tokens and paths

fn is_delimiter(c: char) -> bool {
    c.is_whitespace()
        || "`\"'()[]<>{}|=,;\\\u{201c}\u{201d}\u{2018}\u{2019}\u{ab}\u{bb}".contains(c)
}

/// The tokens of one line (rule 1 of the module documentation).
fn tokens(line: &str) -> Vec<String> {
    let chars: Vec<char> = line.chars().collect();
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let group_close = match c {
            '{' => Some('}'),
            '<' if !cur.is_empty() => Some('>'),
            _ => None,
        };
        if let Some(close) = group_close {
            let end = (i + 1..chars.len())
                .take_while(|&k| !chars[k].is_whitespace())
                .find(|&k| chars[k] == close);
            if let Some(k) = end {
                cur.extend(&chars[i..=k]);
                i = k + 1;
                continue;
            }
        }
        if is_delimiter(c) {
            if !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
            }
        } else {
            cur.push(c);
        }
        i += 1;
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// A path named in a document: relative to the repository root, with a trailing `/` if it names
/// a folder, and the `#anchor` that followed it.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Named {
    path: String,
    anchor: Option<String>,
}

/// Drops a `:42`, `:42:7` or `:42-50` suffix.
fn strip_line_suffix(mut s: &str) -> &str {
    while let Some(k) = s.rfind(':') {
        let tail = &s[k + 1..];
        if !tail.is_empty() && tail.chars().all(|c| c.is_ascii_digit() || c == '-') {
            s = &s[..k];
        } else {
            break;
        }
    }
    s
}

/// The repository's top-level names: folders (`dirs`) and files (`files`).
struct TopLevel {
    dirs: BTreeSet<String>,
    files: BTreeSet<String>,
}

impl TopLevel {
    fn of(root: &Path) -> TopLevel {
        let mut dirs: BTreeSet<String> = TOP_DIRS.iter().map(|s| s.to_string()).collect();
        let mut files: BTreeSet<String> = TOP_FILES.iter().map(|s| s.to_string()).collect();
        for entry in fs::read_dir(root)
            .expect("readable repository root")
            .flatten()
        {
            let name = entry.file_name().to_string_lossy().into_owned();
            if entry.path().is_dir() {
                if !skipped_dir(&name) {
                    dirs.insert(name);
                }
            } else {
                files.insert(name);
            }
        }
        TopLevel { dirs, files }
    }

    /// The repository path a token names, if it names one (rules 1–4).
    fn named_path(&self, token: &str) -> Option<Named> {
        if token.contains("://") || token.starts_with("mailto:") || token.contains("::") {
            return None;
        }
        // emphasis around the token: `**src/ffi/**`, `_docs/speed.md_`
        let inner = token.trim_start_matches(['*', '_']);
        let lead = token.len() - inner.len();
        let mut s = inner;
        for _ in 0..lead {
            s = s.strip_suffix(['*', '_']).unwrap_or(s);
        }
        let s = s.trim_end_matches(['.', ',', ':', ';', '!', '?', '\u{2026}']);
        let (path, anchor) = match s.split_once('#') {
            Some((p, a)) => (p, Some(a.to_string()).filter(|a| !a.is_empty())),
            None => (s, None),
        };
        let mut path = strip_line_suffix(path).trim_end_matches(['.', '\u{2026}']);
        while let Some(rest) = path.strip_prefix("./") {
            path = rest;
        }
        if path.is_empty()
            || path.starts_with(['/', '~', '$'])
            || path.starts_with("../")
            || path == ".."
        {
            return None;
        }
        let is_path = match path.split_once('/') {
            Some((first, _)) => self.dirs.contains(first) && !is_build_output(first),
            None => self.files.contains(path),
        };
        is_path.then(|| Named {
            path: path.to_string(),
            anchor,
        })
    }

    /// Every repository path named in one line (the comment of a Rust line, or a Markdown line).
    fn paths_in(&self, line: &str) -> Vec<Named> {
        tokens(line)
            .iter()
            .filter_map(|t| self.named_path(t))
            .collect()
    }
}

/// The comment of a line of Rust, if it has one: from the first `//` outside a string literal.
fn rust_comment(line: &str) -> Option<&str> {
    let b = line.as_bytes();
    let mut in_str = false;
    let mut i = 0;
    while i + 1 < b.len() {
        match b[i] {
            b'\\' if in_str => {
                i += 2;
                continue;
            }
            b'"' => in_str = !in_str,
            b'\'' if !in_str && i + 2 < b.len() && b[i + 1] == b'"' && b[i + 2] == b'\'' => {
                i += 3; // the char literal '"'
                continue;
            }
            b'/' if !in_str && b[i + 1] == b'/' => {
                return Some(line[i..].trim_start_matches(['/', '!']));
            }
            _ => {}
        }
        i += 1;
    }
    None
}

// ------------------------------------------------------------------------------------------------
// Markdown: fences, links, headings

/// Whether a line opens or closes a fenced code block.
fn is_fence(line: &str) -> bool {
    let t = line.trim_start();
    t.starts_with("```") || t.starts_with("~~~")
}

/// The link targets of one Markdown line outside code spans (rule 5): `](target)` and a
/// reference definition `[id]: target`.
fn link_targets(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let trimmed = line.trim_start();
    if trimmed.starts_with('[') {
        if let Some(k) = trimmed.find("]:") {
            if !trimmed[..k].contains(['`', ']']) {
                if let Some(t) = trimmed[k + 2..].split_whitespace().next() {
                    out.push(t.trim_matches(['<', '>']).to_string());
                    return out;
                }
            }
        }
    }
    let chars: Vec<char> = line.chars().collect();
    let mut in_code = false;
    let mut i = 0;
    while i < chars.len() {
        if chars[i] == '`' {
            in_code = !in_code;
        } else if !in_code && chars[i] == ']' && chars.get(i + 1) == Some(&'(') {
            let mut j = i + 2;
            let mut target = String::new();
            if chars.get(j) == Some(&'<') {
                j += 1;
                while j < chars.len() && chars[j] != '>' {
                    target.push(chars[j]);
                    j += 1;
                }
            } else {
                let mut depth = 0;
                while j < chars.len() && !chars[j].is_whitespace() {
                    match chars[j] {
                        '(' => depth += 1,
                        ')' if depth == 0 => break,
                        ')' => depth -= 1,
                        _ => {}
                    }
                    target.push(chars[j]);
                    j += 1;
                }
            }
            if !target.is_empty() {
                out.push(target);
            }
            i = j;
            continue;
        }
        i += 1;
    }
    out
}

/// Whether a link target is a URL (`https:`, `mailto:`, …) rather than a path.
fn is_url(target: &str) -> bool {
    if target.contains("://") {
        return true;
    }
    match target.split_once(':') {
        Some((scheme, _)) => {
            !scheme.is_empty()
                && scheme
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
                && !scheme.contains('/')
        }
        None => false,
    }
}

/// `a/b/../c/./d` → `a/c/d`; `None` if it climbs out of the root.
fn normalize(path: &str) -> Option<String> {
    let mut parts: Vec<&str> = Vec::new();
    for part in path.split('/') {
        match part {
            "" | "." => {}
            ".." => {
                parts.pop()?;
            }
            p => parts.push(p),
        }
    }
    let mut out = parts.join("/");
    if path.ends_with('/') && !out.is_empty() {
        out.push('/');
    }
    Some(out)
}

/// The repository path a Markdown link in `from` (a path relative to the root) points to, if it
/// points into the repository outside the build output (rule 5).
fn link_path(from: &str, target: &str) -> Option<Named> {
    if is_url(target) {
        return None;
    }
    let (path, anchor) = match target.split_once('#') {
        Some((p, a)) => (p, Some(a.to_string()).filter(|a| !a.is_empty())),
        None => (target, None),
    };
    let path = path.split('?').next().unwrap_or("");
    let resolved = if path.is_empty() {
        from.to_string()
    } else if let Some(abs) = path.strip_prefix('/') {
        normalize(abs)?
    } else {
        let dir = from.rsplit_once('/').map_or("", |(d, _)| d);
        normalize(&format!("{dir}/{path}"))?
    };
    let first = resolved.split('/').next().unwrap_or("");
    if resolved.is_empty() || is_build_output(first) {
        return None;
    }
    Some(Named {
        path: resolved,
        anchor,
    })
}

/// GitHub's anchor for a heading's text (rule 6).
fn slug(heading: &str) -> String {
    // the rendered text: code spans kept verbatim, link targets and HTML tags dropped
    let chars: Vec<char> = heading.chars().collect();
    let mut text = String::new();
    let mut in_code = false;
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c == '`' {
            in_code = !in_code;
        } else if !in_code && c == ']' && chars.get(i + 1) == Some(&'(') {
            match chars[i..].iter().position(|&d| d == ')') {
                Some(k) => i += k,
                None => text.push(c),
            }
        } else if !in_code
            && c == '<'
            && chars
                .get(i + 1)
                .is_some_and(|d| d.is_ascii_alphabetic() || *d == '/')
        {
            match chars[i..].iter().position(|&d| d == '>') {
                Some(k) => i += k,
                None => text.push(c),
            }
        } else {
            text.push(c);
        }
        i += 1;
    }
    // not trimmed again: `Text <a id="x"></a>` renders as "Text " (GitHub: `text-`)
    text.to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The text of an ATX heading line (`## Text ##`), if the line is one.
fn heading_text(line: &str) -> Option<&str> {
    let indent = line.len() - line.trim_start_matches(' ').len();
    if indent > 3 {
        return None;
    }
    let t = &line[indent..];
    let level = t.len() - t.trim_start_matches('#').len();
    if !(1..=6).contains(&level) {
        return None;
    }
    let rest = &t[level..];
    if !(rest.is_empty() || rest.starts_with([' ', '\t'])) {
        return None;
    }
    let rest = rest.trim();
    // a closing sequence of `#`s after a space
    let without = rest.trim_end_matches('#');
    Some(if without.is_empty() || without.ends_with(' ') {
        without.trim_end()
    } else {
        rest
    })
}

/// The anchors of a Markdown text: its headings' slugs and its HTML `id` / `name` attributes.
fn anchors_of(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut in_fence = false;
    for line in text.lines() {
        if is_fence(line) {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        if let Some(h) = heading_text(line) {
            let s = slug(h);
            let n = seen.entry(s.clone()).or_insert(0);
            out.insert(if *n == 0 {
                s.clone()
            } else {
                format!("{s}-{n}")
            });
            *n += 1;
        }
        for attr in ["id=\"", "name=\""] {
            let mut rest = line;
            while let Some(k) = rest.find(attr) {
                let before = rest[..k].chars().last();
                rest = &rest[k + attr.len()..];
                if before.is_some_and(|c| c.is_alphanumeric() || c == '-' || c == '_') {
                    continue; // `data-id="…"` and the like
                }
                if let Some(end) = rest.find('"') {
                    out.insert(rest[..end].to_string());
                }
            }
        }
    }
    out
}

// ------------------------------------------------------------------------------------------------
// Existence

/// `*` and `?` matching on one file name.
fn wildcard_match(pattern: &[char], name: &[char]) -> bool {
    match pattern.split_first() {
        None => name.is_empty(),
        Some(('*', rest)) => (0..=name.len()).any(|k| wildcard_match(rest, &name[k..])),
        Some(('?', rest)) => !name.is_empty() && wildcard_match(rest, &name[1..]),
        Some((c, rest)) => name.first() == Some(c) && wildcard_match(rest, &name[1..]),
    }
}

/// Expands `{a,b}` and `{2..8}`; turns a placeholder `{name}`, `<name>` or an elided component
/// (`…`, `...`) into `*`.
fn expand(path: &str) -> Vec<String> {
    if path.split('/').any(|c| c == "\u{2026}" || c == "...") {
        let parts: Vec<&str> = path
            .split('/')
            .map(|c| {
                if c == "\u{2026}" || c == "..." {
                    "*"
                } else {
                    c
                }
            })
            .collect();
        return expand(&parts.join("/"));
    }
    let Some(open) = path.find(['{', '<']) else {
        return vec![path.to_string()];
    };
    let close_char = if path[open..].starts_with('{') {
        '}'
    } else {
        '>'
    };
    let Some(len) = path[open..].find(close_char) else {
        return vec![path.to_string()];
    };
    let (head, inner, tail) = (
        &path[..open],
        &path[open + 1..open + len],
        &path[open + len + 1..],
    );
    let choices: Vec<String> = if close_char == '>' {
        vec!["*".to_string()]
    } else if inner.contains(',') {
        inner.split(',').map(str::to_string).collect()
    } else if let Some((a, b)) = inner
        .split_once("..")
        .and_then(|(a, b)| Some((a.parse::<i64>().ok()?, b.parse::<i64>().ok()?)))
    {
        (a.min(b)..=a.max(b)).map(|k| k.to_string()).collect()
    } else {
        vec!["*".to_string()]
    };
    choices
        .iter()
        .flat_map(|c| expand(&format!("{head}{c}{tail}")))
        .collect()
}

/// Why `path` (relative to `root`, wildcards allowed) names nothing, if it does not exist.
fn missing(root: &Path, path: &str) -> Option<String> {
    for p in expand(path) {
        let wants_dir = p.ends_with('/');
        let parts: Vec<&str> = p.trim_end_matches('/').split('/').collect();
        match parts.iter().position(|c| c.contains(['*', '?'])) {
            None => {
                // `docs/speed.md/` does not exist for the file system: look the name up without
                // its `/`, then ask for a folder
                let full = root.join(p.trim_end_matches('/'));
                if !full.exists() {
                    return Some(if p == path {
                        "does not exist".to_string()
                    } else {
                        format!("{p} does not exist")
                    });
                }
                if wants_dir && !full.is_dir() {
                    return Some("is not a folder".to_string());
                }
            }
            Some(k) => {
                let dir = parts[..k].join("/");
                let full = root.join(&dir);
                if !full.is_dir() {
                    return Some(format!("its folder {dir}/ does not exist"));
                }
                if k + 1 == parts.len() {
                    let pattern: Vec<char> = parts[k].chars().collect();
                    let any = fs::read_dir(&full)
                        .into_iter()
                        .flatten()
                        .flatten()
                        .any(|e| {
                            let name: Vec<char> = e.file_name().to_string_lossy().chars().collect();
                            wildcard_match(&pattern, &name) && (!wants_dir || e.path().is_dir())
                        });
                    if !any {
                        return Some(format!("no entry of {dir}/ matches {}", parts[k]));
                    }
                }
            }
        }
    }
    None
}

/// Checks named paths and anchors against a checkout, caching each Markdown file's anchors.
struct Checker {
    root: PathBuf,
    top: TopLevel,
    anchors: BTreeMap<String, BTreeSet<String>>,
    /// How many paths were checked (a guard against an extractor that silently finds nothing).
    checked: usize,
}

impl Checker {
    fn new(root: &Path) -> Checker {
        Checker {
            root: root.to_path_buf(),
            top: TopLevel::of(root),
            anchors: BTreeMap::new(),
            checked: 0,
        }
    }

    /// What is wrong with one named path: it does not exist, or its anchor is not in it.
    fn problem(&mut self, named: &Named) -> Option<String> {
        self.checked += 1;
        // a file being checked is known by its text (the controls' sample pages are not on disk)
        if !self.anchors.contains_key(&named.path) {
            if let Some(why) = missing(&self.root, &named.path) {
                return Some(why);
            }
        }
        let anchor = named.anchor.as_deref()?;
        if !named.path.ends_with(".md") || named.path.contains(['*', '?', '{', '<']) {
            return None;
        }
        let root = &self.root;
        let anchors = self.anchors.entry(named.path.clone()).or_insert_with(|| {
            anchors_of(&fs::read_to_string(root.join(&named.path)).unwrap_or_default())
        });
        let found = anchors.contains(anchor) || anchors.contains(&anchor.to_lowercase());
        (!found).then(|| format!("no heading or id `{anchor}` in {}", named.path))
    }

    /// The problems of one Markdown file's text, as `file:line → path: why`.
    fn check_markdown(&mut self, file: &str, text: &str) -> Vec<String> {
        self.anchors.insert(file.to_string(), anchors_of(text));
        let mut out = Vec::new();
        let mut in_fence = false;
        for (k, line) in text.lines().enumerate() {
            let fence = is_fence(line);
            if fence {
                in_fence = !in_fence;
            }
            let mut named: Vec<(String, Named)> = self
                .top
                .paths_in(line)
                .into_iter()
                .map(|n| (render(&n), n))
                .collect();
            if !in_fence && !fence {
                for target in link_targets(line) {
                    if let Some(n) = link_path(file, &target) {
                        named.push((target, n));
                    }
                }
            }
            let mut seen = BTreeSet::new();
            for (shown, n) in named {
                if !seen.insert(n.clone()) {
                    continue;
                }
                if let Some(why) = self.problem(&n) {
                    out.push(format!("{file}:{} → {shown}: {why}", k + 1));
                }
            }
        }
        out
    }

    /// The problems of one Rust file's comments, as `file:line → path: why`.
    fn check_rust(&mut self, file: &str, text: &str) -> Vec<String> {
        let mut out = Vec::new();
        for (k, line) in text.lines().enumerate() {
            let Some(comment) = rust_comment(line) else {
                continue;
            };
            let mut seen = BTreeSet::new();
            for n in self.top.paths_in(comment) {
                if !seen.insert(n.clone()) {
                    continue;
                }
                if let Some(why) = self.problem(&n) {
                    out.push(format!("{file}:{} → {}: {why}", k + 1, render(&n)));
                }
            }
        }
        out
    }
}

fn render(n: &Named) -> String {
    match &n.anchor {
        Some(a) => format!("{}#{a}", n.path),
        None => n.path.clone(),
    }
}

/// The files under `dir` (relative to `root`, `/`-separated, sorted) whose names `keep` accepts.
fn files_under(root: &Path, dir: &str, keep: &dyn Fn(&str) -> bool) -> Vec<String> {
    fn walk(root: &Path, dir: &Path, keep: &dyn Fn(&str) -> bool, out: &mut Vec<String>) {
        let Ok(entries) = fs::read_dir(dir) else {
            return;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            let name = entry.file_name().to_string_lossy().into_owned();
            if path.is_dir() {
                if !skipped_dir(&name) && !name.starts_with('.') {
                    walk(root, &path, keep, out);
                }
            } else if keep(&name) {
                let rel = path.strip_prefix(root).unwrap_or(&path);
                out.push(rel.to_string_lossy().replace('\\', "/"));
            }
        }
    }
    let mut out = Vec::new();
    walk(root, &root.join(dir), keep, &mut out);
    out.sort();
    out
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

// ------------------------------------------------------------------------------------------------
// Versions

/// The crate's version, `major.minor` (what `find_package` asks for) and SONAME version.
struct CrateVersion {
    full: String,
    major_minor: String,
    soversion: String,
}

fn crate_version() -> CrateVersion {
    let (major, minor) = (
        env!("CARGO_PKG_VERSION_MAJOR"),
        env!("CARGO_PKG_VERSION_MINOR"),
    );
    CrateVersion {
        full: env!("CARGO_PKG_VERSION").to_string(),
        major_minor: format!("{major}.{minor}"),
        soversion: if major == "0" {
            format!("0.{minor}")
        } else {
            major.to_string()
        },
    }
}

/// The version numbers stated in one line: `("find_package", "0.3")` for
/// `find_package(bingham 0.3 …)`, `("libbingham.so", "0.3.0")` for `libbingham.so.0.3.0`.
/// Placeholders (`<version>`, `@VERSION@`, `$(VERSION)`) state none.
fn versions_in(line: &str) -> Vec<(&'static str, String)> {
    let mut out = Vec::new();
    // the leading run of digits and dots; none if a placeholder follows (`0.<minor>`, `1.@X@`)
    let number = |s: &str| -> String {
        let run: String = s
            .chars()
            .take_while(|c| c.is_ascii_digit() || *c == '.')
            .collect();
        let next = s[run.len()..].chars().next();
        if next.is_some_and(|c| c.is_alphanumeric() || "<@${_".contains(c)) {
            return String::new();
        }
        run.trim_end_matches('.').to_string()
    };
    let mut rest = line;
    while let Some(k) = rest.find("find_package(bingham") {
        rest = &rest[k + "find_package(bingham".len()..];
        if rest.starts_with([' ', '\t']) {
            let v = number(rest.trim_start());
            if !v.is_empty() {
                out.push(("find_package", v));
            }
        }
    }
    let mut rest = line;
    while let Some(k) = rest.find("libbingham.so.") {
        rest = &rest[k + "libbingham.so.".len()..];
        let v = number(rest);
        if !v.is_empty() {
            out.push(("libbingham.so", v));
        }
    }
    out
}

/// What is wrong with a stated version, if anything.
fn version_problem(kind: &str, stated: &str, v: &CrateVersion) -> Option<String> {
    match kind {
        "find_package" => (stated != v.major_minor).then(|| {
            format!(
                "find_package(bingham {stated}) but the crate is {} (ask for {})",
                v.full, v.major_minor
            )
        }),
        _ if stated.split('.').count() >= 3 => (stated != v.full).then(|| {
            format!(
                "libbingham.so.{stated} but the crate is {} (libbingham.so.{})",
                v.full, v.full
            )
        }),
        _ => (stated != v.soversion).then(|| {
            format!(
                "libbingham.so.{stated} but the SONAME version is {} (crate {})",
                v.soversion, v.full
            )
        }),
    }
}

// ------------------------------------------------------------------------------------------------
// Positive controls

#[test]
fn the_extractor_finds_paths_and_nothing_else() {
    let top = TopLevel::of(root());
    let line = "See `src/ahrs/rest.rs`, [the guide](docs/guide.md#filter) and tests/fuzz_ffi/. \
                Run ./scripts/install-deps.sh; `Makefile`, Cargo.toml:12, `src/lib.rs:40:5` \
                docs/accuracy/*.md, tests/data/normalization_d{2..8}.csv, `benches/<bench>.rs`, \
                **include/bingham.h**, (python/bingham/ahrs.py), \u{201c}c_tests/api_util.h\u{201d}, \
                cmake/..., src/\u{2026}, docs/\u{2026}#anchor, src/\u{2026}/mod.rs, the \
                docs/design.md's layout.";
    let found: Vec<String> = top.paths_in(line).iter().map(render).collect();
    assert_eq!(
        found,
        [
            "src/ahrs/rest.rs",
            "docs/guide.md#filter",
            "tests/fuzz_ffi/",
            "scripts/install-deps.sh",
            "Makefile",
            "Cargo.toml",
            "src/lib.rs",
            "docs/accuracy/*.md",
            "tests/data/normalization_d{2..8}.csv",
            "benches/<bench>.rs",
            "include/bingham.h",
            "python/bingham/ahrs.py",
            "c_tests/api_util.h",
            "cmake/",
            "src/",
            "docs/#anchor",
            "src/\u{2026}/mod.rs",
            "docs/design.md",
        ]
    );
    let not_paths = "rad/s, 1/R, NaN/Inf, `rest.rs`, `quad/`, `crate::ffi::args`, \
                     https://example.com/src/x.rs, <https://example.com/docs/y.md>, \
                     target/release/libbingham.so, `target-old/x`, ../shared/data/broad, \
                     /usr/lib/x, ~/src/x, $PWD/target/x, lib/cmake/bingham/, bingham/_lib/, \
                     `BINGHAM_LIB=/path/to/libbingham.so`, <Eigen/Core>, python, docs, mod.rs";
    assert_eq!(top.paths_in(not_paths), []);

    // the comment of a Rust line, not a `//` inside a string
    assert_eq!(
        rust_comment(r#"let u = "http://x//y"; // see src/x.rs"#),
        Some(" see src/x.rs")
    );
    assert_eq!(rust_comment(r#"let u = "a // b";"#), None);
    assert_eq!(
        rust_comment("/// `docs/guide.md`"),
        Some(" `docs/guide.md`")
    );

    // links: relative to the linking file, not in code spans, URLs and escapes skipped
    let links = link_targets("[a](speed.md#x), ![b](../README.md), `[c](nope.md)`, [d](<e f.md>)");
    assert_eq!(links, ["speed.md#x", "../README.md", "e f.md"]);
    assert_eq!(
        link_targets("[ref]: docs/guide.md#filter"),
        ["docs/guide.md#filter"]
    );
    let resolve = |from: &str, t: &str| link_path(from, t).map(|n| render(&n));
    assert_eq!(
        resolve("docs/accuracy/ahrs.md", "../speed.md#ahrs").as_deref(),
        Some("docs/speed.md#ahrs")
    );
    assert_eq!(
        resolve("docs/guide.md", "#filter").as_deref(),
        Some("docs/guide.md#filter")
    );
    assert_eq!(
        resolve("docs/guide.md", "/src/ffi/").as_deref(),
        Some("src/ffi/")
    );
    assert_eq!(resolve("README.md", "../shared/data/broad"), None);
    assert_eq!(resolve("README.md", "target/demo/x.svg"), None);
    assert_eq!(resolve("README.md", "https://example.com/a.md"), None);
    assert_eq!(resolve("README.md", "mailto:someone@example.com"), None);

    // globs
    assert_eq!(
        expand("a/d{2..4}.csv"),
        ["a/d2.csv", "a/d3.csv", "a/d4.csv"]
    );
    assert_eq!(expand("docs/accuracy/{ahrs,filter}.md").len(), 2);
    assert_eq!(expand("benches/<bench>.rs"), ["benches/*.rs"]);
    assert_eq!(expand("src/\u{2026}/mod.rs"), ["src/*/mod.rs"]);
    assert_eq!(missing(root(), "src/\u{2026}/mod.rs"), None);
    assert!(wildcard_match(
        &"*.md".chars().collect::<Vec<_>>(),
        &"ahrs.md".chars().collect::<Vec<_>>()
    ));
}

#[test]
fn slugs_follow_githubs_rule() {
    assert_eq!(slug("C API overview"), "c-api-overview");
    assert_eq!(
        slug("The d = 3, 4 quadrature in detail (`src/normalization/quad/`)"),
        "the-d--3-4-quadrature-in-detail-srcnormalizationquad"
    );
    assert_eq!(
        slug("What the test asserts (CI, `cargo test --release --test glover_table1`)"),
        "what-the-test-asserts-ci-cargo-test---release---test-glover_table1"
    );
    assert_eq!(slug("Use it from C / CMake"), "use-it-from-c--cmake");
    assert_eq!(
        slug("See [the guide](docs/guide.md) <a id=\"x\"></a>"),
        "see-the-guide-"
    );
    assert_eq!(
        slug("Glover & Kaelbling, reproduced"),
        "glover--kaelbling-reproduced"
    );
    let text = "# Top\n## Notes\n```sh\n# not a heading\n```\n## Notes\n<a id=\"row-1\"></a>\n";
    let anchors = anchors_of(text);
    let expected: BTreeSet<String> = ["top", "notes", "notes-1", "row-1"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    assert_eq!(anchors, expected);
}

#[test]
fn made_up_paths_are_flagged() {
    let mut checker = Checker::new(root());
    // a sample page placed in docs/, so that its relative links resolve against docs/
    let sample = "\
## Made up
Real: `docs/speed.md`, `src/`, `src/lib.rs`, docs/accuracy/*.md, [here](#made-up),
[guide](guide.md#filter), [up](../README.md).
Made up: `src/no_such_module.rs` and `tests/fuzz_ffi/no_such_case.rs:12`.
Links: [x](no_such_page.md), [y](guide.md#no-such-heading), [z](#no-such-anchor-here).
Globs: docs/accuracy/*.nope, `tests/data/normalization_d{2..9}.csv`, `docs/speed.md/`.
```sh
./scripts/no_such_script.sh   # a path in a code block is checked too
```
";
    let problems = checker.check_markdown("docs/sample.md", sample);
    let expected = [
        "docs/sample.md:4 → src/no_such_module.rs: does not exist",
        "docs/sample.md:4 → tests/fuzz_ffi/no_such_case.rs: does not exist",
        "docs/sample.md:5 → no_such_page.md: does not exist",
        "docs/sample.md:5 → guide.md#no-such-heading: no heading or id `no-such-heading` in docs/guide.md",
        "docs/sample.md:5 → #no-such-anchor-here: no heading or id `no-such-anchor-here` in docs/sample.md",
        "docs/sample.md:6 → docs/accuracy/*.nope: no entry of docs/accuracy/ matches *.nope",
        "docs/sample.md:6 → tests/data/normalization_d{2..9}.csv: tests/data/normalization_d9.csv does not exist",
        "docs/sample.md:6 → docs/speed.md/: is not a folder",
        "docs/sample.md:8 → scripts/no_such_script.sh: does not exist",
    ];
    assert_eq!(problems, expected, "got:\n{}", problems.join("\n"));

    let rust = "fn f() {} // see `src/lib.rs` and src/ahrs/no_such_file.rs\n\
                let s = \"src/not_a_comment.rs\";\n\
                /// [the guide](docs/guide.md#no-such-heading)\n";
    assert_eq!(
        checker.check_rust("src/sample.rs", rust),
        [
            "src/sample.rs:1 → src/ahrs/no_such_file.rs: does not exist",
            "src/sample.rs:3 → docs/guide.md#no-such-heading: no heading or id `no-such-heading` in docs/guide.md",
        ]
    );

    let v = CrateVersion {
        full: "0.3.1".into(),
        major_minor: "0.3".into(),
        soversion: "0.3".into(),
    };
    let stated = versions_in(
        "find_package(bingham 0.2 REQUIRED) find_package(bingham) find_package(bingham <version>) \
         libbingham.so.0.3.0 libbingham.so.0.3 libbingham.so.0 libbingham.so.$(VERSION). \
         libbingham.so.0.<minor>, find_package(bingham <major>.<minor>), libbingham.so.@VERSION@",
    );
    assert_eq!(
        stated,
        [
            ("find_package", "0.2".to_string()),
            ("libbingham.so", "0.3.0".to_string()),
            ("libbingham.so", "0.3".to_string()),
            ("libbingham.so", "0".to_string()),
        ]
    );
    let wrong: Vec<String> = stated
        .iter()
        .filter_map(|(kind, s)| version_problem(kind, s, &v))
        .collect();
    assert_eq!(
        wrong,
        [
            "find_package(bingham 0.2) but the crate is 0.3.1 (ask for 0.3)",
            "libbingham.so.0.3.0 but the crate is 0.3.1 (libbingham.so.0.3.1)",
            "libbingham.so.0 but the SONAME version is 0.3 (crate 0.3.1)",
        ]
    );
}

// ------------------------------------------------------------------------------------------------
// The checks

#[test]
fn documented_paths_exist() {
    let root = root();
    let mut checker = Checker::new(root);
    let markdown = files_under(root, "", &|name| name.ends_with(".md"));
    let rust = files_under(root, "src", &|name| name.ends_with(".rs"));
    assert!(
        markdown.iter().any(|f| f == "README.md")
            && markdown.iter().any(|f| f == "docs/guide.md")
            && rust.iter().any(|f| f == "src/lib.rs"),
        "the walk missed README.md, docs/guide.md or src/lib.rs under {}",
        root.display()
    );
    let mut problems = Vec::new();
    for file in &markdown {
        let text = fs::read_to_string(root.join(file)).expect("readable Markdown");
        problems.extend(checker.check_markdown(file, &text));
    }
    for file in &rust {
        let text = fs::read_to_string(root.join(file)).expect("readable Rust source");
        problems.extend(checker.check_rust(file, &text));
    }
    assert!(
        checker.checked > 300,
        "only {} paths found in {} Markdown and {} Rust files: is the extractor broken?",
        checker.checked,
        markdown.len(),
        rust.len()
    );
    assert!(
        problems.is_empty(),
        "{} named path(s) or anchor(s) do not exist in the checkout (file:line → path: why); \
         point the text to where the file now is (rules: tests/doc_paths.rs):\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn versions_are_the_crates() {
    let root = root();
    let v = crate_version();
    let mut files = files_under(root, "", &|name| name.ends_with(".md"));
    for dir in ["cmake", "scripts", "examples"] {
        files.extend(files_under(root, dir, &|_| true));
    }
    files.push("Makefile".to_string());
    let mut problems = Vec::new();
    let mut readme_asks = 0;
    let mut stated_count = 0;
    for file in &files {
        let Ok(text) = fs::read_to_string(root.join(file)) else {
            continue; // not text
        };
        for (k, line) in text.lines().enumerate() {
            for (kind, stated) in versions_in(line) {
                stated_count += 1;
                if file == "README.md" && kind == "find_package" {
                    readme_asks += 1;
                }
                if let Some(why) = version_problem(kind, &stated, &v) {
                    problems.push(format!("{file}:{}: {why}", k + 1));
                }
            }
        }
    }
    if readme_asks == 0 {
        problems.push(format!(
            "README.md: the CMake snippet asks for no version; it should read \
             `find_package(bingham {} REQUIRED)`",
            v.major_minor
        ));
    }

    // the Python package's version is the crate's
    let pyproject =
        fs::read_to_string(root.join("python/pyproject.toml")).expect("python/pyproject.toml");
    let project: Vec<&str> = pyproject
        .lines()
        .skip_while(|l| l.trim() != "[project]")
        .skip(1)
        .take_while(|l| !l.trim_start().starts_with('['))
        .collect();
    let literal = project.iter().find_map(|l| {
        let (key, value) = l.split_once('=')?;
        (key.trim() == "version").then(|| value.trim().trim_matches('"').to_string())
    });
    let dynamic = project.iter().any(|l| {
        l.split_once('=')
            .is_some_and(|(k, val)| k.trim() == "dynamic" && val.contains("\"version\""))
    });
    match literal {
        Some(stated) if stated != v.full => problems.push(format!(
            "python/pyproject.toml: version {stated}, but the crate is {}",
            v.full
        )),
        Some(_) => {}
        None if !dynamic => problems.push(
            "python/pyproject.toml: [project] neither states the version nor declares it dynamic"
                .to_string(),
        ),
        None => {
            let setup = fs::read_to_string(root.join("python/setup.py")).expect("python/setup.py");
            if !setup.contains("Cargo.toml") {
                problems.push(
                    "python/setup.py: the version is dynamic (pyproject.toml) but setup.py does \
                     not read it from Cargo.toml"
                        .to_string(),
                );
            }
            for (k, line) in setup.lines().enumerate() {
                let compact: String = line.chars().filter(|c| !c.is_whitespace()).collect();
                for quote in ['"', '\''] {
                    if let Some(rest) = compact.strip_prefix(&format!("version={quote}")) {
                        let stated = rest.split(quote).next().unwrap_or("");
                        if stated != v.full {
                            problems.push(format!(
                                "python/setup.py:{}: version {stated}, but the crate is {}",
                                k + 1,
                                v.full
                            ));
                        }
                    }
                }
            }
        }
    }
    assert!(
        stated_count > 0,
        "no version found in {} files: is the extractor broken?",
        files.len()
    );
    assert!(
        problems.is_empty(),
        "{} stated version(s) differ from the crate's ({}; find_package asks for {}, SONAME \
         libbingham.so.{}):\n{}",
        problems.len(),
        v.full,
        v.major_minor,
        v.soversion,
        problems.join("\n")
    );
}
