#!/usr/bin/env bash
# `make valgrind`: runs under valgrind (memcheck), failing on any error or definite/indirect leak:
#
# 1. every C/C++ test (c_tests/) and example (examples/c/), built without sanitizers against
#    the static library (JOBS at a time, default the number of CPUs);
# 2. the Rust fuzz harness of the C ABI (tests/fuzz_ffi/) with exactly-sized buffers
#    (BINGHAM_FUZZ_EXACT_BUFFERS=1), so that any read or write of the library beyond a caller's
#    array, or any use of uninitialized memory, is reported. BINGHAM_VALGRIND_FUZZ_CASES cases
#    (default 20000; 0 skips this part).
#
# Installs valgrind with apt-get when it is missing (as root, or with sudo).
set -euo pipefail
. "$(dirname "$0")/c_programs.sh"

if ! command -v valgrind >/dev/null 2>&1; then
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    echo "valgrind: installing valgrind"
    $sudo apt-get update && $sudo apt-get install -y valgrind
fi

VALGRIND=(valgrind -q --error-exitcode=99 --leak-check=full
          --errors-for-leak-kinds=definite,indirect --show-leak-kinds=definite,indirect
          --track-origins=yes)

ensure_library
OUT="$TARGET_DIR/valgrind"
mkdir -p "$OUT"

check_one() {
    local src=$1 rel exe rc t0
    rel=${src#"$ROOT"/}
    t0=$SECONDS
    exe=$(build_program "$src" "$OUT" -g -O2)
    rc=$?
    [ $rc -eq 2 ] && return 2
    if [ $rc -ne 0 ]; then
        echo "FAIL $rel: does not compile"
        return 1
    fi
    if (cd "$OUT" && "${VALGRIND[@]}" "$exe" >"$exe.log" 2>&1); then
        echo "ok   $rel ($((SECONDS - t0)) s, build and run)"
    else
        echo "FAIL $rel (exit status $?); output:"
        tail -n 60 "$exe.log"
        return 1
    fi
}

start=$SECONDS
failed=0
run_programs check_one || failed=1

cases=${BINGHAM_VALGRIND_FUZZ_CASES:-20000}
if [ "$cases" != 0 ]; then
    # cargo runs the test executable through the runner (build scripts and the compiler run
    # natively)
    host=$(rustc -vV | sed -n 's/^host: //p')
    runner_var="CARGO_TARGET_$(echo "$host" | tr 'a-z-' 'A-Z_')_RUNNER"
    t0=$SECONDS
    if (cd "$ROOT" && env "$runner_var=${VALGRIND[*]}" BINGHAM_FUZZ_EXACT_BUFFERS=1 \
            BINGHAM_FUZZ_CASES="$cases" BINGHAM_FUZZ_TIMEOUT=600 \
            "$CARGO" test --release --quiet --test fuzz_ffi >"$OUT/fuzz_ffi.log" 2>&1); then
        echo "ok   tests/fuzz_ffi/, $cases cases, exact buffers ($((SECONDS - t0)) s)"
    else
        echo "FAIL tests/fuzz_ffi/ under valgrind; output:"
        tail -n 80 "$OUT/fuzz_ffi.log"
        failed=1
    fi
fi

if [ $failed -ne 0 ]; then
    echo "valgrind: FAILED"
    exit 1
fi
echo "valgrind: $RAN programs and the fuzz harness clean ($((SECONDS - start)) s)"
