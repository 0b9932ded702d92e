//! Build script: gives the shared library its SONAME and tells the C test harness
//! (`tests/c_tests.rs`) which target it is building for.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let target = std::env::var("TARGET").unwrap_or_default();
    let major = std::env::var("CARGO_PKG_VERSION_MAJOR").unwrap_or_else(|_| "0".into());
    // ELF platforms: `libbingham.so` gets the SONAME `libbingham.so.<major>`, so programs linked
    // against an installed copy record the ABI version (see `make install`).
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
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libbingham.so.{major}");
    }
    // For the cc crate in tests/c_tests.rs, which expects build-script-style target information.
    println!("cargo:rustc-env=BINGHAM_BUILD_TARGET={target}");
    println!(
        "cargo:rustc-env=BINGHAM_BUILD_HOST={}",
        std::env::var("HOST").unwrap_or_default()
    );
}
