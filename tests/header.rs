//! The committed `include/bingham.h` must be exactly what cbindgen generates from `src/ffi/`
//! (and the `#[repr(C)]` structs of `src/ahrs/params.rs` and `src/ahrs/health.rs`).
//!
//! On drift this test fails; regenerate with `make header` (which runs this test with
//! `BINGHAM_WRITE_HEADER=1`, writing the file instead of comparing) and commit the result.

use std::path::Path;

fn generate() -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config =
        cbindgen::Config::from_file(root.join("cbindgen.toml")).expect("read cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(root.join("src/ffi/mod.rs"))
        // the AHRS parameters are a plain `#[repr(C)]` struct of the core, shared with C
        // (renamed `bingham_ahrs_params` by cbindgen.toml) instead of a mirrored copy
        .with_src(root.join("src/ahrs/params.rs"))
        .with_src(root.join("src/ahrs/health.rs"))
        .generate()
        .expect("cbindgen failed to generate the header");
    let mut out = Vec::new();
    bindings.write(&mut out);
    String::from_utf8(out).expect("header is UTF-8")
}

#[test]
fn committed_header_is_up_to_date() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("include/bingham.h");
    let generated = generate();
    if std::env::var_os("BINGHAM_WRITE_HEADER").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, &generated).expect("write include/bingham.h");
        eprintln!("wrote {}", path.display());
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed != generated {
        let first = committed
            .lines()
            .zip(generated.lines())
            .position(|(a, b)| a != b)
            .unwrap_or_else(|| committed.lines().count().min(generated.lines().count()));
        panic!(
            "include/bingham.h is out of date with src/ffi/ (first difference at line {}).\n\
             Regenerate it with `make header` and commit the result.",
            first + 1
        );
    }
}

#[test]
fn header_declares_the_api() {
    let h = generate();
    for name in [
        "bingham_version",
        "bingham_status_str",
        "bingham_last_error_message",
        "bingham_normalization_constant",
        "bingham_log_normalization_constant",
        "bingham_log_normalization_constant_saddlepoint",
        "bingham_log_normalization_hessian",
        "bingham_second_moment",
        "bingham_mle",
        "bingham_mle_samples",
        "bingham_multiply",
        "bingham_compose",
        "bingham_pdf",
        "bingham_log_pdf",
        "bingham_entropy",
        "bingham_kl_divergence",
        "bingham_sample",
        "bingham_rotate_left",
        "bingham_rotate_right",
        "bingham_mode",
    ] {
        assert!(
            h.contains(&format!("{name}(")),
            "{name} missing from the header"
        );
    }
    assert!(h.contains("typedef enum bingham_status {"));
    assert!(h.contains("BINGHAM_OK = 0,"));
    assert!(h.contains("BINGHAM_ERR_PANIC = 6,"));
    assert!(h.contains("#ifndef BINGHAM_H"));
    assert!(h.contains("#define BINGHAM_VERSION_MAJOR "));
    assert!(h.contains("extern \"C\" {"));
    assert!(!h.contains("uintptr_t"), "usize must map to size_t");
    for (part, value) in [
        ("MAJOR", env!("CARGO_PKG_VERSION_MAJOR")),
        ("MINOR", env!("CARGO_PKG_VERSION_MINOR")),
        ("PATCH", env!("CARGO_PKG_VERSION_PATCH")),
    ] {
        assert!(
            h.contains(&format!("#define BINGHAM_VERSION_{part} {value}\n")),
            "BINGHAM_VERSION_{part} must be {value} (Cargo.toml): edit src/ffi/version.rs, then `make header`"
        );
    }
}

#[cfg(not(panic = "unwind"))]
compile_error!("bingham must be built with panic = \"unwind\": the C boundary catches panics");

/// The C boundary relies on unwinding: `catch_unwind` in every export turns a panic into
/// `BINGHAM_ERR_PANIC`. With `panic = "abort"` a bug would kill the host process instead.
#[test]
fn panics_unwind() {
    let manifest =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml"))
            .expect("read Cargo.toml");
    let offending: Vec<&str> = manifest
        .lines()
        .map(str::trim)
        .filter(|l| !l.starts_with('#') && l.replace(' ', "").starts_with("panic=\"abort\""))
        .collect();
    assert!(
        offending.is_empty(),
        "Cargo.toml must not set panic = \"abort\": {offending:?}"
    );
}
