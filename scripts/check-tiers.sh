#!/usr/bin/env bash
# `make tiers` (the first step of `make quick`): every integration test binary of the crate is
# assigned to exactly one tier of `make test`, so a new test file cannot escape both (it would
# then run in neither `make quick` nor the slow tier, and CI would never run it).
#
# Usage: scripts/check-tiers.sh "QUICK NAMES" "SLOW NAMES"  (the Makefile's QUICK_TESTS and
# SLOW_TESTS). The binaries are found as cargo finds them (autotests): tests/<name>.rs and
# tests/<name>/main.rs. Fails when a binary is in no tier or in both, when a tier names a binary
# that does not exist, or when Cargo.toml declares [[test]] targets (this script does not read
# them; extend it first).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
quick=" ${1:-} "
slow=" ${2:-} "

if grep -Eq '^\[\[test\]\]|^autotests *= *false' "$ROOT/Cargo.toml"; then
    echo "check-tiers: Cargo.toml declares [[test]] targets or autotests = false; this script only" \
        "knows tests/<name>.rs and tests/<name>/main.rs" >&2
    exit 1
fi

binaries=()
for f in "$ROOT"/tests/*.rs "$ROOT"/tests/*/main.rs; do
    [ -e "$f" ] || continue
    case "$f" in
        */main.rs) binaries+=("$(basename "$(dirname "$f")")") ;;
        *) binaries+=("$(basename "$f" .rs)") ;;
    esac
done

failed=0
for b in "${binaries[@]}"; do
    in_quick=0 in_slow=0
    [[ $quick == *" $b "* ]] && in_quick=1
    [[ $slow == *" $b "* ]] && in_slow=1
    if [ $((in_quick + in_slow)) -eq 0 ]; then
        echo "check-tiers: tests/$b is in no tier: add it to QUICK_TESTS or SLOW_TESTS in the Makefile" >&2
        failed=1
    elif [ $((in_quick + in_slow)) -eq 2 ]; then
        echo "check-tiers: tests/$b is in both tiers (QUICK_TESTS and SLOW_TESTS in the Makefile)" >&2
        failed=1
    fi
done
for name in $quick $slow; do
    if [[ " ${binaries[*]} " != *" $name "* ]]; then
        echo "check-tiers: the Makefile names a test binary '$name' that does not exist" \
            "(no tests/$name.rs or tests/$name/main.rs)" >&2
        failed=1
    fi
done
for name in $(printf '%s\n' $quick | sort | uniq -d) $(printf '%s\n' $slow | sort | uniq -d); do
    echo "check-tiers: '$name' is named twice in one tier" >&2
    failed=1
done
[ $failed -eq 0 ] || exit 1
echo "check-tiers: ${#binaries[@]} test binaries, each in one tier"
