//! Builds and runs the C and C++ programs in `c_tests/` against the library built by cargo.
//!
//! The programs link `libbingham.a` (plus the system libraries Rust's standard library needs)
//! that cargo built for this very test run (in `target/<profile>/deps/`, next to this test's
//! own executable); one program links `libbingham.so` instead. If the library is missing there,
//! the harness falls back to `target/<profile>/` and, failing that, builds it with cargo. Compilers come from the
//! `cc` crate (honouring `CC`, `CXX`, `CFLAGS`, … as usual). The C++ reference test needs Eigen 3
//! (`libeigen3-dev`, found in `/usr/include/eigen3` or via `EIGEN3_INCLUDE_DIR`).
//!
//! Every program counts its checks and exits non-zero on any failure; its output is shown.
//!
//! Each program is compiled to an object file, then linked against the library. Compiling the
//! Eigen programs is most of this test's time (about 2 of its 2.5 minutes on 2 cores) and does
//! not depend on the library, so an object is reused when nothing it was compiled from changed:
//! the same compiler command and version, and every file the compiler read (its `-MD` list:
//! the source, `include/`, `c_tests/`, Eigen's and the system's headers) of unchanged size and
//! modification time ([`compile`]). Linking and running happen every time. Delete
//! `target/<profile>/c_tests/` to compile everything again.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

const STRICT: &[&str] = &["-Wall", "-Wextra", "-Werror", "-pedantic"];

/// `target/<profile>/`, from `target/<profile>/deps/c_tests-<hash>`.
fn profile_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("current_exe");
    exe.parent()
        .and_then(Path::parent)
        .expect("test executable lives in target/<profile>/deps")
        .to_path_buf()
}

/// The directory holding `libbingham.a` and `libbingham.so`.
///
/// `cargo test` builds every crate type of the library into `target/<profile>/deps/` (next to
/// this test's executable) but does not copy them up to `target/<profile>/`; prefer those fresh
/// copies, then `target/<profile>/`, and as a last resort build the library with cargo.
fn lib_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let have = |d: &Path| d.join("libbingham.a").is_file() && d.join("libbingham.so").is_file();
        let deps = std::env::current_exe()
            .expect("current_exe")
            .parent()
            .expect("deps dir")
            .to_path_buf();
        if have(&deps) {
            return deps;
        }
        let dir = profile_dir();
        if !have(&dir) {
            let release = dir.file_name().is_some_and(|n| n == "release");
            let target_dir = dir.parent().expect("target dir");
            let mut cmd = Command::new(env!("CARGO"));
            cmd.args(["build", "--lib", "--manifest-path"])
                .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml"))
                .env("CARGO_TARGET_DIR", target_dir);
            if release {
                cmd.arg("--release");
            }
            let status = cmd.status().expect("run cargo build");
            assert!(status.success(), "cargo build of the library failed");
        }
        assert!(
            have(&dir),
            "libbingham.a/.so not found in {}",
            dir.display()
        );
        dir
    })
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn out_dir() -> PathBuf {
    let d = profile_dir().join("c_tests");
    std::fs::create_dir_all(&d).expect("create c_tests output dir");
    d
}

fn eigen_include() -> PathBuf {
    if let Some(p) = std::env::var_os("EIGEN3_INCLUDE_DIR") {
        return PathBuf::from(p);
    }
    for p in ["/usr/include/eigen3", "/usr/local/include/eigen3"] {
        if Path::new(p).join("Eigen/Dense").is_file() {
            return PathBuf::from(p);
        }
    }
    panic!("Eigen 3 not found: install libeigen3-dev (`make test` does) or set EIGEN3_INCLUDE_DIR");
}

#[derive(Clone, Copy, PartialEq)]
enum Link {
    Static,
    Shared,
}

/// Compiles `c_tests/<source>` and links it to an executable named `<name>`; returns its path.
fn build(source: &str, name: &str, std: &str, extra: &[&str], link: Link) -> PathBuf {
    let cpp = source.ends_with(".cpp");
    let compiler = cc::Build::new()
        .cargo_metadata(false)
        .cargo_warnings(false)
        .cargo_debug(false)
        .emit_rerun_if_env_changed(false)
        .target(env!("BINGHAM_BUILD_TARGET"))
        .host(env!("BINGHAM_BUILD_HOST"))
        .opt_level(2)
        .debug(false)
        .cpp(cpp)
        .try_get_compiler()
        .expect("find a C/C++ compiler");
    let exe = out_dir().join(name);
    let obj = out_dir().join(format!("{name}.o"));
    let lib = lib_dir();
    let mut cc = compiler.to_command();
    cc.arg(format!("-std={std}"))
        .args(STRICT)
        .arg("-I")
        .arg(root().join("include"))
        .arg("-I")
        .arg(root().join("c_tests"))
        .args(extra)
        .arg("-c")
        .arg(root().join("c_tests").join(source))
        .arg("-o")
        .arg(&obj);
    compile(cc, &obj, source);
    let mut cmd = compiler.to_command();
    cmd.arg(&obj).arg("-o").arg(&exe);
    match link {
        // What `pkg-config --static --libs bingham` gives: the archive and Rust std's needs.
        Link::Static => {
            cmd.arg(lib.join("libbingham.a"))
                .args(["-lpthread", "-ldl", "-lm"]);
        }
        // The library's SONAME is libbingham.so.<major> (before 1.0 libbingham.so.0.<minor>,
        // build.rs): provide that name next to the program.
        Link::Shared => {
            let dir = out_dir().join("shared");
            std::fs::create_dir_all(&dir).expect("create dir");
            let soversion = match env!("CARGO_PKG_VERSION_MAJOR") {
                "0" => format!("0.{}", env!("CARGO_PKG_VERSION_MINOR")),
                major => major.to_string(),
            };
            let soname = dir.join(format!("libbingham.so.{soversion}"));
            let _ = std::fs::remove_file(&soname);
            std::os::unix::fs::symlink(lib.join("libbingham.so"), &soname).expect("symlink");
            cmd.arg("-L")
                .arg(lib)
                .arg(format!("-Wl,-rpath,{}", dir.display()))
                .args(["-lbingham", "-lpthread", "-lm"]);
        }
    }
    run_compiler(&mut cmd, &format!("linking {source}"));
    exe
}

/// Runs a compiler command; panics with the command and its output if it fails.
fn run_compiler(cmd: &mut Command, what: &str) {
    let output = cmd.output().expect("run the compiler");
    assert!(
        output.status.success(),
        "{what} failed:\n{}\n{}{}",
        shown(cmd),
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
}

fn shown(cmd: &Command) -> String {
    let words: Vec<_> = std::iter::once(cmd.get_program())
        .chain(cmd.get_args())
        .map(|a| a.to_string_lossy())
        .collect();
    words.join(" ")
}

/// Compiles with `cc` (a command ending in `-c <source> -o <obj>`) unless `obj` is still valid.
///
/// The key of an object, written to `<obj>.key` after a successful compilation: the command
/// line, the compiler's `--version`, then one line per file the compiler read (from `-MD`),
/// with its size and modification time. A compilation that failed leaves no key, so it is
/// repeated (with its diagnostics) on the next run; a key that matches means the same command
/// over the same files, which gave an object without a warning (`-Werror`) before.
fn compile(mut cc: Command, obj: &Path, source: &str) {
    let key_path = obj.with_extension("o.key");
    let dep_path = obj.with_extension("d");
    let version = Command::new(cc.get_program())
        .arg("--version")
        .output()
        .map(|o| {
            String::from_utf8_lossy(&o.stdout)
                .lines()
                .next()
                .unwrap_or("")
                .to_string()
        })
        .unwrap_or_default();
    let head = format!("{}\n{version}\n", shown(&cc));
    if obj.is_file() {
        if let Ok(key) = std::fs::read_to_string(&key_path) {
            if let Some(files) = key.strip_prefix(&head) {
                let unchanged = files.lines().all(|line| {
                    line.splitn(3, ' ')
                        .nth(2)
                        .and_then(|path| file_line(Path::new(path)))
                        .is_some_and(|now| now == line)
                });
                if unchanged && !files.is_empty() {
                    return;
                }
            }
        }
    }
    let _ = std::fs::remove_file(&key_path);
    cc.arg("-MD").arg("-MF").arg(&dep_path);
    run_compiler(&mut cc, &format!("compiling {source}"));
    let deps = std::fs::read_to_string(&dep_path).expect("read the compiler's -MD output");
    let mut key = head;
    for path in dep_files(&deps) {
        let line = file_line(Path::new(&path))
            .unwrap_or_else(|| panic!("{path} (read by the compiler) has no metadata"));
        key.push_str(&line);
        key.push('\n');
    }
    std::fs::write(&key_path, key).expect("write the object's key");
}

/// `<modification time in ns> <size> <path>` of a file, or `None` if it cannot be read.
fn file_line(path: &Path) -> Option<String> {
    let meta = std::fs::metadata(path).ok()?;
    let modified = meta
        .modified()
        .ok()?
        .duration_since(std::time::UNIX_EPOCH)
        .ok()?;
    Some(format!(
        "{} {} {}",
        modified.as_nanos(),
        meta.len(),
        path.display()
    ))
}

/// The prerequisites of a make rule as the compiler writes it with `-MD` (`obj: a b \`, ...;
/// a space in a name escaped as `\ `).
fn dep_files(rule: &str) -> Vec<String> {
    let body = rule.split_once(": ").map_or(rule, |(_, b)| b);
    let mut files = Vec::new();
    let mut word = String::new();
    let mut chars = body.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&' ') => {
                word.push(' ');
                chars.next();
            }
            '\\' if chars.peek() == Some(&'\n') => {
                chars.next();
            }
            c if c.is_whitespace() => {
                if !word.is_empty() {
                    files.push(std::mem::take(&mut word));
                }
            }
            c => word.push(c),
        }
    }
    if !word.is_empty() {
        files.push(word);
    }
    files
}

fn run(exe: &Path) {
    let output = Command::new(exe).output().expect("run test program");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    print!("{stdout}");
    eprint!("{stderr}");
    assert!(
        output.status.success(),
        "{} failed ({}):\n{stdout}{stderr}",
        exe.display(),
        output.status
    );
}

#[test]
fn header_compiles_as_c99() {
    let exe = build(
        "header_c99.c",
        "header_c99",
        "c99",
        &["-Wstrict-prototypes", "-Wmissing-prototypes", "-Wshadow"],
        Link::Static,
    );
    run(&exe);
}

#[test]
fn header_compiles_as_cxx11() {
    let exe = build(
        "header_cxx11.cpp",
        "header_cxx11",
        "c++11",
        &["-Wshadow"],
        Link::Static,
    );
    run(&exe);
}

#[test]
fn header_works_with_the_shared_library() {
    let exe = build(
        "header_c99.c",
        "header_c99_shared",
        "c99",
        &[],
        Link::Shared,
    );
    run(&exe);
}

#[test]
fn c_api_errors_and_success_paths() {
    let exe = build("api_errors.c", "api_errors", "c99", &[], Link::Static);
    run(&exe);
}

#[test]
fn cpp_eigen_references() {
    let inc = eigen_include();
    let inc = inc.to_str().expect("UTF-8 path");
    // Eigen itself is not -pedantic/-Wextra clean on every compiler: include it as a system header.
    let exe = build(
        "reference_eigen.cpp",
        "reference_eigen",
        "c++11",
        &["-isystem", inc],
        Link::Static,
    );
    run(&exe);
}

#[test]
fn cpp_deterministic_eigen_references() {
    let inc = eigen_include();
    let inc = inc.to_str().expect("UTF-8 path");
    let exe = build(
        "deterministic_eigen.cpp",
        "deterministic_eigen",
        "c++11",
        &["-isystem", inc],
        Link::Static,
    );
    run(&exe);
}

#[test]
fn c_filter_api() {
    let exe = build("filter_api.c", "filter_api", "c99", &[], Link::Static);
    run(&exe);
}

#[test]
fn cpp_filter_eigen_references() {
    let inc = eigen_include();
    let inc = inc.to_str().expect("UTF-8 path");
    let exe = build(
        "filter_eigen.cpp",
        "filter_eigen",
        "c++11",
        &["-isystem", inc],
        Link::Static,
    );
    run(&exe);
}

#[test]
fn cpp_vector_eigen_references() {
    let inc = eigen_include();
    let inc = inc.to_str().expect("UTF-8 path");
    let exe = build(
        "vector_eigen.cpp",
        "vector_eigen",
        "c++11",
        &["-isystem", inc],
        Link::Static,
    );
    run(&exe);
}

/// The world-frame steps and the spin filter against Eigen references (`world_eigen.cpp`).
#[test]
fn cpp_world_eigen_references() {
    let inc = eigen_include();
    let inc = inc.to_str().expect("UTF-8 path");
    let exe = build(
        "world_eigen.cpp",
        "world_eigen",
        "c++11",
        &["-isystem", inc],
        Link::Static,
    );
    run(&exe);
}

/// The spin filter's C API (`spin_api.c`).
#[test]
fn c_spin_api() {
    let exe = build("spin_api.c", "spin_api", "c99", &[], Link::Static);
    run(&exe);
}

/// The world-frame steps' C API: success paths and error contract (`world_api.c`).
#[test]
fn c_world_api() {
    let exe = build("world_api.c", "world_api", "c99", &[], Link::Static);
    run(&exe);
}

#[test]
fn c_vector_and_ahrs_api() {
    let exe = build("ahrs_api.c", "ahrs_api", "c99", &[], Link::Static);
    run(&exe);
}

/// The C++17 wrapper (`include/bingham.hpp`) without Eigen, built as C++17 and as C++20.
#[test]
fn cpp_wrapper_plain() {
    for std in ["c++17", "c++20"] {
        let name = format!("wrapper_plain_{}", std.replace('+', "x"));
        let exe = build("wrapper_plain.cpp", &name, std, &["-Wshadow"], Link::Static);
        run(&exe);
    }
}

/// The wrapper's Eigen overloads (`include/bingham_eigen.hpp`), built as C++17 and as C++20.
#[test]
fn cpp_wrapper_eigen() {
    let inc = eigen_include();
    let inc = inc.to_str().expect("UTF-8 path");
    for std in ["c++17", "c++20"] {
        let name = format!("wrapper_eigen_{}", std.replace('+', "x"));
        let exe = build(
            "wrapper_eigen.cpp",
            &name,
            std,
            &["-isystem", inc],
            Link::Static,
        );
        run(&exe);
    }
}
