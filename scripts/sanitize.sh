#!/usr/bin/env bash
# `make sanitize`: builds every C/C++ test (c_tests/) and example (examples/c/) with
# AddressSanitizer and UndefinedBehaviorSanitizer against the static library and runs them;
# any report fails the run.
#
# - ASan checks every memory access of the C/C++ code (including the library's writes into
#   caller buffers as seen from C, e.g. sentinel-checked outputs) and intercepts malloc/free for
#   the whole process, so the library's heap use (Rust allocates with malloc) is checked for
#   double frees and invalid frees, and LeakSanitizer reports leaks at exit.
# - The Rust code itself is not instrumented (that needs a nightly compiler); tests/fuzz_ffi.rs
#   under valgrind (`make valgrind`) covers the library's own accesses.
# - Each executable is checked to really contain the ASan runtime (nm/ldd), so a compiler that
#   silently ignores -fsanitize cannot pass.
set -euo pipefail
. "$(dirname "$0")/c_programs.sh"

ensure_library
OUT="$TARGET_DIR/sanitize"
mkdir -p "$OUT"
FLAGS=(-g -O2 -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"

failed=0
ran=0
start=$SECONDS
while read -r src; do
    rel=${src#"$ROOT"/}
    set +e
    exe=$(build_program "$src" "$OUT" "${FLAGS[@]}")
    rc=$?
    set -e
    if [ $rc -eq 2 ]; then continue; fi
    if [ $rc -ne 0 ]; then
        echo "FAIL $rel: does not compile with sanitizers"
        failed=1
        continue
    fi
    # (grep -c, not grep -q: an early exit of grep would make nm fail with SIGPIPE)
    if [ "$(nm "$exe" 2>/dev/null | grep -c '__asan_init')" = 0 ] &&
        [ "$(ldd "$exe" 2>/dev/null | grep -c 'libasan')" = 0 ]; then
        echo "FAIL $rel: the executable does not contain the AddressSanitizer runtime"
        failed=1
        continue
    fi
    t0=$SECONDS
    if (cd "$OUT" && "$exe" >"$exe.log" 2>&1); then
        echo "ok   $rel ($((SECONDS - t0)) s)"
    else
        echo "FAIL $rel (exit status $?); output:"
        tail -n 60 "$exe.log"
        failed=1
    fi
    ran=$((ran + 1))
done < <(program_sources)

if [ $ran -eq 0 ]; then
    echo "sanitize: no program was run"
    exit 1
fi
if [ $failed -ne 0 ]; then
    echo "sanitize: FAILED"
    exit 1
fi
echo "sanitize: $ran programs clean under ASan + UBSan + LeakSanitizer ($((SECONDS - start)) s)"
