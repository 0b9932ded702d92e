#!/usr/bin/env bash
# Installs bingham into a temporary prefix with `make install` and checks what a user gets:
# the file layout and symlinks, the SONAME, pkg-config, a C++11 program built with
# -Wall -Wextra -Werror against the shared library and against the static one, and (when
# cmake is available) a CMake project using pkg_check_modules.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
make=${MAKE:-make}
cxx=${CXX:-c++}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix="$tmp/prefix"
version=$(sed -n 's/^version *= *"\([^"]*\)".*/\1/p' "$root/Cargo.toml" | head -n 1)
major=${version%%.*}

fail() { echo "install-test: FAILED: $*" >&2; exit 1; }

"$make" -C "$root" --no-print-directory install PREFIX="$prefix" >/dev/null

# layout
lib="$prefix/lib"
for f in "include/bingham.h" "lib/libbingham.a" "lib/libbingham.so.$version" "lib/pkgconfig/bingham.pc"; do
    [ -f "$prefix/$f" ] || fail "missing $f"
done
[ "$(readlink "$lib/libbingham.so")" = "libbingham.so.$major" ] || fail "libbingham.so -> libbingham.so.$major"
[ "$(readlink "$lib/libbingham.so.$major")" = "libbingham.so.$version" ] || fail "libbingham.so.$major -> libbingham.so.$version"
readelf -d "$lib/libbingham.so.$version" | grep -q "Library soname: \[libbingham.so.$major\]" ||
    fail "SONAME is not libbingham.so.$major"

# exported symbols: exactly the functions the header declares
declared=$(grep -E '^[a-z].*\bbingham_[a-z0-9_]+\(' "$prefix/include/bingham.h" |
    grep -oE '\bbingham_[a-z0-9_]+\(' | tr -d '(' | sort -u)
exported=$(nm -D --defined-only "$lib/libbingham.so.$version" | awk '$2 == "T" && $3 ~ /^bingham_/ {print $3}' | sort -u)
[ -n "$declared" ] || fail "no declarations found in the header"
[ "$declared" = "$exported" ] || fail "exported symbols differ from the header: $(diff <(echo "$declared") <(echo "$exported") | grep '^[<>]' | tr '\n' ' ')"

# pkg-config
export PKG_CONFIG_PATH="$lib/pkgconfig"
[ "$(pkg-config --modversion bingham)" = "$version" ] || fail "pkg-config --modversion"
cflags=$(pkg-config --cflags bingham)
libs=$(pkg-config --libs bingham)
[[ "$libs" == *-lbingham* ]] || fail "pkg-config --libs: $libs"
[[ "$(pkg-config --static --libs bingham)" == *-lpthread* ]] || fail "Libs.private"

example="$root/examples/c/cpp_example.cpp"
flags=(-std=c++11 -Wall -Wextra -Werror -pedantic)

# shared: records libbingham.so.<major>, runs with the installed library
# shellcheck disable=SC2086
"$cxx" "${flags[@]}" "$example" $cflags $libs -o "$tmp/example_shared"
readelf -d "$tmp/example_shared" | grep -q "Shared library: \[libbingham.so.$major\]" ||
    fail "the program does not record NEEDED libbingham.so.$major"
LD_LIBRARY_PATH="$lib" "$tmp/example_shared" >/dev/null || fail "shared example did not run"

# static: the archive plus Libs.private, no runtime dependency on libbingham
# shellcheck disable=SC2086
"$cxx" "${flags[@]}" "$example" $cflags "$lib/libbingham.a" \
    $(pkg-config --static --libs-only-l bingham | sed 's/-lbingham//') -o "$tmp/example_static"
if readelf -d "$tmp/example_static" | grep -q "libbingham"; then fail "static example needs libbingham.so"; fi
"$tmp/example_static" >/dev/null || fail "static example did not run"

# C: the same header from C99
printf '#include <bingham.h>\n#include <stdio.h>\nint main(void) { puts(bingham_version()); return 0; }\n' > "$tmp/c_example.c"
# shellcheck disable=SC2086
"${CC:-cc}" -std=c99 -Wall -Wextra -Werror -pedantic "$tmp/c_example.c" $cflags $libs -o "$tmp/c_example"
[ "$(LD_LIBRARY_PATH="$lib" "$tmp/c_example")" = "$version" ] || fail "C example"

# CMake, as shown in the README (only if cmake is installed)
if command -v cmake >/dev/null 2>&1; then
    mkdir -p "$tmp/cmake"
    cp "$example" "$tmp/cmake/main.cpp"
    cat > "$tmp/cmake/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.10)
project(bingham_user CXX)
set(CMAKE_CXX_STANDARD 11)
find_package(PkgConfig REQUIRED)
pkg_check_modules(BINGHAM REQUIRED IMPORTED_TARGET bingham)
add_executable(example main.cpp)
target_compile_options(example PRIVATE -Wall -Wextra -Werror)
target_link_libraries(example PRIVATE PkgConfig::BINGHAM)
CMAKE
    cmake -S "$tmp/cmake" -B "$tmp/cmake/build" >/dev/null
    cmake --build "$tmp/cmake/build" >/dev/null
    LD_LIBRARY_PATH="$lib" "$tmp/cmake/build/example" >/dev/null || fail "CMake example did not run"
    cmake_note="shared, static, C, CMake"
else
    cmake_note="shared, static, C (cmake not installed: CMake check skipped)"
fi

echo "install-test: ok ($cmake_note; SONAME libbingham.so.$major)"
