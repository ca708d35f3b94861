#!/usr/bin/env bash
# `make test`'s stages one after another (each a make target), stopping at the first that
# fails, then the minutes each took: where a fresh clone's half hour goes.
#   scripts/test_stages.sh TARGET...      MAKE names the make to call (default make)
set -uo pipefail
cd "$(dirname "$0")/.."
times=()
for target in "$@"; do
    start=$(date +%s)
    if ! ${MAKE:-make} --no-print-directory "$target"; then
        echo "make test: stage $target failed after $(( $(date +%s) - start )) s"
        exit 1
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
