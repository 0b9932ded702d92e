#!/usr/bin/env bash
# `make cross-aarch64`: builds the library for aarch64-unknown-linux-gnu and runs integration
# tests under qemu-user (docs/testing.md, "aarch64"). Debian/Ubuntu, as root or with sudo.
#
# rustup cannot download a target here, and Debian's `rustc` (1.63 on bookworm) is older than
# the crate's rust-version. Debian's `rustc-web` (a newer Rust, packaged for the browsers) has a
# standard library for arm64 of the same version: the script fetches rustc-web, its standard
# libraries for the host and for arm64 and the LLVM it links against with `apt-get download`
# (arm64 package lists in a private directory: the system's dpkg architectures are not changed)
# and unpacks them with `dpkg-deb -x` into $TARGET_DIR/aarch64-toolchain, without installing
# them (rustc-web would replace /usr/bin/rustc). The host's cargo drives that rustc (RUSTC), so
# the host toolchain is untouched. Installed with apt-get when missing: gcc-aarch64-linux-gnu
# (the linker and the arm64 C library) and qemu-user (the tests).
#
# Environment: CARGO, TARGET_DIR (default target), AARCH64_TESTS (the integration test binaries
# run under qemu), AARCH64_SKIP (tests skipped by name, with the reason in the Makefile).
set -euo pipefail

cargo=${CARGO:-cargo}
target_dir=$(realpath -m "${TARGET_DIR:-target}")
tests=${AARCH64_TESTS:-}
skip=${AARCH64_SKIP:-}
triple=aarch64-unknown-linux-gnu
tc="$target_dir/aarch64-toolchain"
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"

missing=()
command -v aarch64-linux-gnu-gcc >/dev/null 2>&1 || missing+=(gcc-aarch64-linux-gnu libc6-dev-arm64-cross)
command -v qemu-aarch64 >/dev/null 2>&1 || missing+=(qemu-user)
command -v dpkg-deb >/dev/null 2>&1 && command -v apt-get >/dev/null 2>&1 || {
    echo "cross-aarch64: needs Debian's apt-get and dpkg-deb" >&2
    exit 1
}
if [ ${#missing[@]} -gt 0 ]; then
    echo "cross-aarch64: installing ${missing[*]}"
    $sudo apt-get update
    $sudo apt-get install -y --no-install-recommends "${missing[@]}"
fi

# The crate's rust-version (Cargo.toml) and the oldest rustc accepted.
need=$(sed -n 's/^rust-version *= *"\([^"]*\)".*/\1/p' Cargo.toml | head -n 1)

if [ ! -x "$tc/rustc" ]; then
    work="$target_dir/aarch64-apt"
    rm -rf "$work" "$tc.new"
    mkdir -p "$work/lists/partial" "$work/cache/archives/partial" "$work/debs" "$tc.new"
    apt_opts=(-o "APT::Architectures::=$(dpkg --print-architecture)" -o "APT::Architectures::=arm64"
              -o "Dir::State::Lists=$work/lists" -o "Dir::Cache=$work/cache")
    echo "cross-aarch64: the package lists for $(dpkg --print-architecture) and arm64 (private: $work/lists)"
    apt-get "${apt_opts[@]}" update >/dev/null
    version=$(apt-cache "${apt_opts[@]}" policy rustc-web | sed -n 's/^ *Candidate: *//p')
    arm_version=$(apt-cache "${apt_opts[@]}" policy libstd-rust-web-dev:arm64 | sed -n 's/^ *Candidate: *//p')
    if [ -z "$version" ] || [ "$version" = "(none)" ] || [ "$version" != "$arm_version" ]; then
        echo "cross-aarch64: no rustc-web with an arm64 standard library of the same version" \
             "(rustc-web: '${version:-none}', libstd-rust-web-dev:arm64: '${arm_version:-none}')" >&2
        exit 1
    fi
    upstream=${version%%+*}
    series=$(echo "$upstream" | cut -d. -f1,2)
    llvm=$(apt-cache "${apt_opts[@]}" depends "libstd-rust-web-$series" | sed -n 's/^ *Depends: *\(libllvm[0-9]*\).*/\1/p' | head -n 1)
    echo "cross-aarch64: Debian's rustc-web $version (crate needs >= $need), $llvm"
    (cd "$work/debs" && apt-get "${apt_opts[@]}" download \
        "rustc-web=$version" "libstd-rust-web-$series=$version" "libstd-rust-web-dev=$version" \
        "libstd-rust-web-dev:arm64=$version" "$llvm" 2>&1 | grep -v "^W: Download is performed unsandboxed" || true)
    for deb in "$work"/debs/*.deb; do
        dpkg-deb -x "$deb" "$tc.new"
    done
    # rustc finds its standard libraries from its own path (usr/lib/rustlib/<triple>/lib); the
    # wrapper points the loader at the unpacked librustc_driver and libLLVM
    cat > "$tc.new/rustc" <<EOF
#!/bin/sh
LD_LIBRARY_PATH="$tc/usr/lib/$(uname -m)-linux-gnu\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}" exec "$tc/usr/bin/rustc" "\$@"
EOF
    chmod +x "$tc.new/rustc"
    rm -rf "$tc"
    mv "$tc.new" "$tc"
    rm -rf "$work"
fi

have=$("$tc/rustc" -V | awk '{print $2}')
if [ "$(printf '%s\n%s\n' "$need" "$have" | sort -V | head -n 1)" != "$need" ]; then
    echo "cross-aarch64: rustc $have is older than the crate's rust-version $need" >&2
    exit 1
fi
[ -d "$tc/usr/lib/rustlib/$triple/lib" ] || {
    echo "cross-aarch64: no standard library for $triple in $tc" >&2
    exit 1
}
echo "cross-aarch64: $("$tc/rustc" -V) for $triple (host: $(rustc -V 2>/dev/null || echo '?'))"

export RUSTC="$tc/rustc"
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_RUNNER="qemu-aarch64 -L /usr/aarch64-linux-gnu"
export CC_aarch64_unknown_linux_gnu=aarch64-linux-gnu-gcc
cross_dir="$target_dir/aarch64"

"$cargo" build --release --lib --target "$triple" --target-dir "$cross_dir"
ls -l "$cross_dir/$triple/release/libbingham.so" "$cross_dir/$triple/release/libbingham.a"
file "$cross_dir/$triple/release/libbingham.so" 2>/dev/null || true

if [ -n "$tests" ]; then
    skip_args=()
    for t in $skip; do
        skip_args+=(--skip "$t")
    done
    "$cargo" test --release --no-fail-fast --target "$triple" --target-dir "$cross_dir" \
        $(for t in $tests; do printf -- '--test %s ' "$t"; done) -- "${skip_args[@]}"
fi
echo "cross-aarch64: built and tested for $triple"
