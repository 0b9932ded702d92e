# Shared by scripts/sanitize.sh and scripts/valgrind.sh (sourced, not run): finds the C/C++
# programs (c_tests/*.c, c_tests/*.cpp, examples/c/*.c, examples/c/*.cpp, examples/cpp/*.cpp),
# builds them against the static library with extra flags, and runs them.
#
# Standards: C programs are built as C99, C++ programs as C++11, unless the source has a line
# `// standards: c++17 c++20` (the C++ wrapper's tests and examples): then it is built and run
# once per listed standard (the entry is SOURCE@STANDARD).
#
# Environment: CARGO_TARGET_DIR (default target), CARGO (default cargo), CC (default cc),
# CXX (default c++), EIGEN3_INCLUDE_DIR (default /usr/include/eigen3).

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
TARGET_DIR=${CARGO_TARGET_DIR:-$ROOT/target}
LIB="$TARGET_DIR/release/libbingham.a"
CARGO=${CARGO:-cargo}
CC=${CC:-cc}
CXX=${CXX:-c++}
STATIC_LIBS=(-lpthread -ldl -lm)

eigen_dir() {
    local d
    for d in "${EIGEN3_INCLUDE_DIR:-}" /usr/include/eigen3 /usr/local/include/eigen3; do
        if [ -n "$d" ] && [ -f "$d/Eigen/Dense" ]; then
            echo "$d"
            return 0
        fi
    done
    return 1
}

# Builds (or confirms up to date) libbingham.a, release profile.
ensure_library() {
    (cd "$ROOT" && "$CARGO" build --release --lib --quiet)
    [ -f "$LIB" ] || { echo "no $LIB after cargo build" >&2; return 1; }
}

# Prints the programs, one per line: SOURCE, or SOURCE@STANDARD for each standard a source
# lists in a `// standards: ...` line.
program_sources() {
    local f stds s
    for f in "$ROOT"/c_tests/*.c "$ROOT"/c_tests/*.cpp "$ROOT"/examples/c/*.c "$ROOT"/examples/c/*.cpp \
        "$ROOT"/examples/cpp/*.cpp; do
        [ -e "$f" ] || continue
        stds=$(sed -n 's|^// standards: *||p' "$f" | head -n 1)
        if [ -z "$stds" ]; then
            echo "$f"
        else
            for s in $stds; do echo "$f@$s"; done
        fi
    done
}

# build_program SOURCE OUTDIR FLAGS... : compiles SOURCE against libbingham.a into OUTDIR and
# prints the executable's path. Programs that include Eigen get it as a system include (a
# program that needs Eigen is skipped, with a note on stderr, when Eigen is not installed).
build_program() {
    local src=$1 outdir=$2
    shift 2
    local name exe compiler std std_override="" extra=()
    case "$src" in
        *@*) std_override=${src##*@} src=${src%@*} ;;
    esac
    name=$(basename "${src%.*}")
    [ -n "$std_override" ] && name="${name}_${std_override//+/x}"
    case "$src" in
        "$ROOT"/examples/*) name="example_$name" ;;
    esac
    exe="$outdir/$name"
    case "$src" in
        *.cpp) compiler=$CXX std=-std=c++11 ;;
        *) compiler=$CC std=-std=c99 ;;
    esac
    [ -n "$std_override" ] && std="-std=$std_override"
    if grep -qE '#include [<"](Eigen/|bingham_eigen.hpp)' "$src"; then
        local e
        if ! e=$(eigen_dir); then
            echo "skipping $src: Eigen 3 not found (install libeigen3-dev or set EIGEN3_INCLUDE_DIR)" >&2
            return 2
        fi
        extra+=(-isystem "$e")
    fi
    "$compiler" "$std" -Wall -Wextra "$@" -I"$ROOT/include" -I"$ROOT/c_tests" "${extra[@]}" \
        "$src" "$LIB" "${STATIC_LIBS[@]}" -o "$exe" >&2 || return 1
    echo "$exe"
}

# run_programs CHECK_FUNCTION: runs `CHECK_FUNCTION SOURCE` for every program, JOBS at a time
# (default: the number of CPUs). The function prints its report and returns 0 (ok), 1 (failed)
# or 2 (skipped). Reports are printed in program order; returns 1 if any failed or none ran.
run_programs() {
    local check=$1 jobs=${JOBS:-$(nproc 2>/dev/null || echo 2)}
    local tmp i=0 src failed=0 ran=0
    tmp=$(mktemp -d)
    while read -r src; do
        while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do sleep 0.2; done
        ( set +e; "$check" "$src" >"$tmp/$i.out" 2>&1; echo $? >"$tmp/$i.rc" ) &
        i=$((i + 1))
    done < <(program_sources)
    wait
    local k
    for ((k = 0; k < i; k++)); do
        cat "$tmp/$k.out"
        case $(cat "$tmp/$k.rc") in
            0) ran=$((ran + 1)) ;;
            2) ;;
            *) ran=$((ran + 1)); failed=1 ;;
        esac
    done
    rm -rf "$tmp"
    RAN=$ran
    [ "$ran" -gt 0 ] && [ "$failed" -eq 0 ]
}
