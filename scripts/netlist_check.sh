#!/usr/bin/env bash
# The synthesised netlist in lockstep (docs/verification.md, make netlist): for each
# family, scripts/netlist.sh writes the Yosys netlist of finestep_top, finestep-rtl-sys
# Verilates it with Yosys's cell models (feature netlist-FAMILY) and
# rust/finestep-cosim/tests/netlist.rs runs the pin-level lockstep tests on it against
# the model, every pin every clock. Prints per family the tests passed and the figure
# (clocks/s, bit-exact), or the first mismatch (pin, clock) as the test reports it.
#
#   scripts/netlist_check.sh [--quick] [FAMILY...]    FAMILY: ecp5 ice40 (default both)
#
# --quick (make test): the iCE40 netlist only: the figure's streamed move, a stream
# with its positions read back, one fault (E-stop mid-move) and the probe latching the
# encoders and positions on one clock (about 20 s of tests once built).
# Logs: build/netlist/FAMILY-tests.log.
set -euo pipefail
cd "$(dirname "$0")/.."

quick=0
families=()
for arg in "$@"; do
    case $arg in
        --quick) quick=1 ;;
        ecp5|ice40) families+=("$arg") ;;
        *) sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; exit 2 ;;
    esac
done
if [ ${#families[@]} -eq 0 ]; then
    if [ "$quick" = 1 ]; then families=(ice40); else families=(ecp5 ice40); fi
fi
filters=()
if [ "$quick" = 1 ]; then
    filters=(--exact netlist_lockstep_rate top_smoke::spi_stream_moves_exactly
             top_faults::estop_halts_mid_move top_feedback::probe_latches_everything_on_one_clock)
fi

./scripts/netlist.sh "${families[@]}"
failed=()
for family in "${families[@]}"; do
    log=build/netlist/$family-tests.log
    start=$SECONDS
    status=0
    cargo test --release -q -p finestep-cosim --features "netlist-$family" --test netlist -- \
        --nocapture "${filters[@]}" > "$log" 2>&1 || status=$?
    seconds=$((SECONDS - start))
    result=$(grep -E "^test result:" "$log" | tail -1 || true)
    figure=$(grep -oE "netlist lockstep: .*" "$log" | tail -1 || true)
    if [ "$status" -ne 0 ]; then
        # The failures as the tests report them: the first mismatching pin and clock.
        grep -A12 "panicked at" "$log" | head -80 || true
        [ -n "$result" ] || tail -30 "$log"
        echo "netlist: $family: FAILED in ${seconds} s (${result:-no test result}); log $log"
        failed+=("$family")
    else
        echo "netlist: $family: ${result#test result: } in ${seconds} s (build included)"
        echo "netlist: $family: ${figure#netlist lockstep: }"
    fi
done
if [ ${#failed[@]} -gt 0 ]; then
    echo "netlist: failed: ${failed[*]}"
    exit 1
fi
