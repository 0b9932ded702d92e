#!/usr/bin/env bash
# `make sanitize`: builds every C/C++ test (c_tests/) and example (examples/c/) with
# AddressSanitizer and UndefinedBehaviorSanitizer against the static library and runs them
# (JOBS at a time, default the number of CPUs); any report fails the run.
#
# - ASan checks every memory access of the C/C++ code (including what the library wrote into
#   caller buffers, as the tests read it back) and intercepts malloc/free for the whole process,
#   so the library's heap use (Rust allocates with malloc) is checked for double and invalid
#   frees, and LeakSanitizer reports leaks at exit (ASAN_OPTIONS=detect_leaks=1).
# - The Rust code itself is not instrumented (that needs a nightly compiler); `make valgrind`
#   runs tests/fuzz_ffi/ under memcheck with exactly-sized buffers for that.
# - Each executable is checked to really contain the ASan runtime (nm/ldd), so a compiler that
#   silently ignored -fsanitize could not pass.
set -euo pipefail
. "$(dirname "$0")/c_programs.sh"

ensure_library
OUT="$TARGET_DIR/sanitize"
mkdir -p "$OUT"
# -O1 -g1: the optimization level the sanitizers' documentation suggests, and line tables
# (function, file and line in every report) without the full debug information of Eigen's
# templates; the Eigen programs then compile in about half the time of -O2 -g (reference_eigen.cpp
# 55 s -> 29 s on the 2-core CI VM) and run about 15 % slower.
FLAGS=(-g1 -O1 -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"

check_one() {
    local src=$1 rel exe rc t0
    rel=${src#"$ROOT"/}
    t0=$SECONDS
    exe=$(build_program "$src" "$OUT" "${FLAGS[@]}")
    rc=$?
    [ $rc -eq 2 ] && return 2
    if [ $rc -ne 0 ]; then
        echo "FAIL $rel: does not compile with sanitizers"
        return 1
    fi
    # (grep -c, not grep -q: an early exit of grep would make nm fail with SIGPIPE)
    if [ "$(nm "$exe" 2>/dev/null | grep -c '__asan_init')" = 0 ] &&
        [ "$(ldd "$exe" 2>/dev/null | grep -c 'libasan')" = 0 ]; then
        echo "FAIL $rel: the executable does not contain the AddressSanitizer runtime"
        return 1
    fi
    if (cd "$OUT" && "$exe" >"$exe.log" 2>&1); then
        echo "ok   $rel ($((SECONDS - t0)) s, build and run)"
    else
        echo "FAIL $rel (exit status $?); output:"
        tail -n 60 "$exe.log"
        return 1
    fi
}

start=$SECONDS
if run_programs check_one; then
    echo "sanitize: $RAN programs clean under ASan + UBSan + LeakSanitizer ($((SECONDS - start)) s)"
else
    echo "sanitize: FAILED"
    exit 1
fi
