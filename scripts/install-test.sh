#!/usr/bin/env bash
# Installs bingham into a temporary prefix with `make install` and checks what a user gets:
# the file layout and symlinks, the SONAME, pkg-config, a C++11 program built with
# -Wall -Wextra -Werror against the shared library and against the static one, a CMake project
# using pkg_check_modules, and a CMake project using the installed CMake package
# (find_package(bingham <major>.<minor>): C and C++17 with Eigen, shared and static targets;
# the version check accepting this version and refusing the next minor and major).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
make=${MAKE:-make}
cxx=${CXX:-c++}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix="$tmp/prefix"
version=$(sed -n 's/^version *= *"\([^"]*\)".*/\1/p' "$root/Cargo.toml" | head -n 1)
major=${version%%.*}
# the SONAME's version: the major version, before 1.0 0.<minor> (build.rs)
minor=${version#*.}
minor=${minor%%.*}
if [ "$major" = 0 ]; then soversion="0.$minor"; else soversion="$major"; fi

fail() { echo "install-test: FAILED: $*" >&2; exit 1; }

"$make" -C "$root" --no-print-directory install PREFIX="$prefix" >/dev/null

# layout
lib="$prefix/lib"
for f in "include/bingham.h" "include/bingham.hpp" "include/bingham_eigen.hpp" "lib/libbingham.a" \
    "lib/libbingham.so.$version" "lib/pkgconfig/bingham.pc" "lib/cmake/bingham/binghamConfig.cmake" \
    "lib/cmake/bingham/binghamConfigVersion.cmake"; do
    [ -f "$prefix/$f" ] || fail "missing $f"
done
[ "$(readlink "$lib/libbingham.so")" = "libbingham.so.$soversion" ] || fail "libbingham.so -> libbingham.so.$soversion"
[ "$(readlink "$lib/libbingham.so.$soversion")" = "libbingham.so.$version" ] || fail "libbingham.so.$soversion -> libbingham.so.$version"
readelf -d "$lib/libbingham.so.$version" | grep -q "Library soname: \[libbingham.so.$soversion\]" ||
    fail "SONAME is not libbingham.so.$soversion"
# installed without debug info (`make install` strips it; the build keeps it)
if readelf -S "$lib/libbingham.so.$version" | grep -q '\.debug_info'; then
    fail "libbingham.so has debug info"
fi
if readelf -S "$lib/libbingham.a" 2>/dev/null | grep -q '\.debug_info'; then
    fail "libbingham.a has debug info"
fi
so_bytes=$(stat -c %s "$lib/libbingham.so.$version")
[ "$so_bytes" -le $((2 * 1024 * 1024)) ] || fail "libbingham.so is $so_bytes bytes (more than 2 MiB)"

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

# shared: records libbingham.so.<soversion>, runs with the installed library
# shellcheck disable=SC2086
"$cxx" "${flags[@]}" "$example" $cflags $libs -o "$tmp/example_shared"
readelf -d "$tmp/example_shared" | grep -q "Shared library: \[libbingham.so.$soversion\]" ||
    fail "the program does not record NEEDED libbingham.so.$soversion"
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

# CMake (scripts/install-deps.sh installs it)
command -v cmake >/dev/null 2>&1 || fail "cmake is not installed (scripts/install-deps.sh installs it)"
cmake_quiet() { "$@" >"$tmp/cmake.log" 2>&1 || { cat "$tmp/cmake.log" >&2; return 1; }; }

# ... with pkg-config, as shown in the README
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
cmake_quiet cmake -S "$tmp/cmake" -B "$tmp/cmake/build" || fail "CMake (pkg-config) configure"
cmake_quiet cmake --build "$tmp/cmake/build" || fail "CMake (pkg-config) build"
LD_LIBRARY_PATH="$lib" "$tmp/cmake/build/example" >/dev/null || fail "CMake example did not run"

# ... with the CMake package: find_package(bingham <major>.<minor>), C and C++17 with Eigen
want="${version%.*}"
pkg="$tmp/cmake_package"
mkdir -p "$pkg"
cp "$root/examples/cpp/tracking_eigen.cpp" "$pkg/tracking.cpp"
printf '#include <bingham.h>\n#include <stdio.h>\nint main(void) { puts(bingham_version()); return 0; }\n' > "$pkg/main.c"
cat > "$pkg/CMakeLists.txt" <<CMAKE
cmake_minimum_required(VERSION 3.10)
project(bingham_package_user C CXX)
find_package(bingham $want REQUIRED)
find_package(Eigen3 REQUIRED NO_MODULE)
set(CMAKE_CXX_STANDARD 17)
set(CMAKE_CXX_STANDARD_REQUIRED ON)
set(CMAKE_CXX_EXTENSIONS OFF)
set(CMAKE_C_STANDARD 99)
add_compile_options(-Wall -Wextra -Werror -pedantic)
add_executable(c_shared main.c)
target_link_libraries(c_shared PRIVATE bingham::bingham)
add_executable(c_static main.c)
target_link_libraries(c_static PRIVATE bingham::bingham_static)
add_executable(cpp_shared tracking.cpp)
target_link_libraries(cpp_shared PRIVATE bingham::bingham Eigen3::Eigen)
add_executable(cpp_static tracking.cpp)
target_link_libraries(cpp_static PRIVATE bingham::bingham_static Eigen3::Eigen)
CMAKE
cmake_quiet cmake -S "$pkg" -B "$pkg/build" -DCMAKE_PREFIX_PATH="$prefix" ||
    fail "CMake package: find_package(bingham $want) failed"
cmake_quiet cmake --build "$pkg/build" || fail "CMake package: build"
readelf -d "$pkg/build/c_shared" | grep -q "Shared library: \[libbingham.so.$soversion\]" ||
    fail "CMake package: bingham::bingham does not record NEEDED libbingham.so.$soversion"
for exe in c_static cpp_static; do
    if readelf -d "$pkg/build/$exe" | grep -q "libbingham"; then fail "CMake package: $exe needs libbingham.so"; fi
done
# (CMake records the imported library's directory as the build tree's RPATH: no LD_LIBRARY_PATH)
[ "$("$pkg/build/c_shared")" = "$version" ] || fail "CMake package: C program (shared)"
[ "$("$pkg/build/c_static")" = "$version" ] || fail "CMake package: C program (static)"
out_shared=$("$pkg/build/cpp_shared") || fail "CMake package: C++ program (shared) did not run"
out_static=$("$pkg/build/cpp_static") || fail "CMake package: C++ program (static) did not run"
[[ "$out_shared" == *"RMS error "*" deg over "* && "$out_shared" == "$out_static" ]] || fail "CMake package: C++ output: $out_shared"

# the version file: this version and no version are accepted, the next minor and major are not
# (0.x: the minor must match), nor a 32-bit consumer
minor=$(echo "$version" | cut -d. -f2)
check_version() {  # check_version REQUEST EXPECTED(0|1)
    local dir="$tmp/cmake_version_$1" found
    mkdir -p "$dir"
    printf 'cmake_minimum_required(VERSION 3.10)\nproject(v NONE)\nfind_package(bingham %s QUIET)\nfile(WRITE "${CMAKE_BINARY_DIR}/found" "${bingham_FOUND}")\n' "$1" > "$dir/CMakeLists.txt"
    cmake_quiet cmake -S "$dir" -B "$dir/build" -DCMAKE_PREFIX_PATH="$prefix" || fail "CMake version check $1"
    found=$(cat "$dir/build/found")
    case "$found" in 1 | TRUE | ON) found=1 ;; *) found=0 ;; esac
    [ "$found" = "$2" ] || fail "find_package(bingham $1): found=$found, expected $2"
}
check_version "$version" 1
check_version "" 1
check_version "$major.$((minor + 1))" 0
check_version "$((major + 1)).0" 0
[ "$major" = 0 ] && [ "$minor" -gt 0 ] && check_version "0.$((minor - 1))" 0
cmake_note="shared, static, C, CMake with pkg-config and with find_package(bingham $want)"

echo "install-test: ok ($cmake_note; SONAME libbingham.so.$soversion)"
