//! Build script: gives the shared library its SONAME and tells the C test harness
//! (`tests/c_tests.rs`) which target it is building for.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let target = std::env::var("TARGET").unwrap_or_default();
    let major = std::env::var("CARGO_PKG_VERSION_MAJOR").unwrap_or_else(|_| "0".into());
    let minor = std::env::var("CARGO_PKG_VERSION_MINOR").unwrap_or_else(|_| "0".into());
    // ELF platforms: `libbingham.so` gets the SONAME `libbingham.so.<major>` (before 1.0
    // `libbingham.so.0.<minor>`: a 0.x release may change the ABI, as 0.3 changed the AHRS
    // parameters), so programs linked against an installed copy record the ABI version and do
    // not load an incompatible one (see `make install`).
    let soversion = if major == "0" {
        format!("0.{minor}")
    } else {
        major
    };
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if matches!(
        os.as_str(),
        "linux"
            | "android"
            | "freebsd"
            | "netbsd"
            | "openbsd"
            | "dragonfly"
            | "illumos"
            | "solaris"
    ) {
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libbingham.so.{soversion}");
    }
    // For the cc crate in tests/c_tests.rs, which expects build-script-style target information.
    println!("cargo:rustc-env=BINGHAM_BUILD_TARGET={target}");
    println!(
        "cargo:rustc-env=BINGHAM_BUILD_HOST={}",
        std::env::var("HOST").unwrap_or_default()
    );
}
