#!/usr/bin/env bash
# `make test`'s stages one after another (each a make target), stopping at the first that
# fails, then the minutes each took: where a fresh clone's half hour goes.
#   scripts/test_stages.sh TARGET...      MAKE names the make to call (default make);
#   TEST_KEEP_GOING=1 runs every stage and fails at the end if one failed (a rehearsal
#   that shows every failure at once)
set -uo pipefail
cd "$(dirname "$0")/.."
times=()
failed=()
for target in "$@"; do
    start=$(date +%s)
    if ! ${MAKE:-make} --no-print-directory "$target"; then
        echo "make test: stage $target failed after $(( $(date +%s) - start )) s"
        [ "${TEST_KEEP_GOING:-0}" = 1 ] || exit 1
        failed+=("$target")
        target="$target (FAILED)"
    fi
    times+=("$target $(( $(date +%s) - start ))")
done
total=0
echo "make test: stage times"
for entry in "${times[@]}"; do
    seconds=${entry##* }
    total=$(( total + seconds ))
    awk -v t="${entry% *}" -v s="$seconds" 'BEGIN { printf "  %-20s %5d s  %5.1f min\n", t, s, s / 60 }'
done
awk -v s="$total" 'BEGIN { printf "  %-20s %5d s  %5.1f min\n", "total", s, s / 60 }'
if [ "${#failed[@]}" -gt 0 ]; then
    echo "make test: failed stages: ${failed[*]}"
    exit 1
fi
