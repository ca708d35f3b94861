#!/usr/bin/env bash
# The open-tool flows as `make test` runs them: the ECP5 and iCE40 bitstreams and the
# MachXO2 packing (its fit), each held to constraints/flow_limits.txt.
#
# A target marked `meet` must build a bitstream that meets its constrained clock, as
# `make bitstream-*` demands, on the one seed the flow uses: no retry on other seeds (the
# three-seed sweep is in `make report`), so a build with a thin margin fails here. The
# MachXO2 CPLD configuration does not fit its 1280 cells yet (`fit`): it is packed. Each
# target's logic-cell count must stay under its recorded ceiling. Every line printed says
# which target is met and which is not; a flow that stops early leaves a summary without
# figures and fails here by name.
#
# The ECP5 flow (the longest) runs beside the iCE40 flows and the MachXO2 packing: the
# machine has two cores.
set -euo pipefail
cd "$(dirname "$0")/.."
limits=constraints/flow_limits.txt
mkdir -p build/bitstream

run() {
    # target, extra flags; the log goes beside the outputs. The summary, not the exit
    # status, decides below.
    local target=$1; shift
    ./scripts/bitstream.sh "$target" --allow-timing-fail "$@" > "build/bitstream/$target.check.log" 2>&1 || true
}

# The register map's constants once, before the flows that read them run side by side.
./scripts/regmap.sh build/gen
start=$SECONDS
run ecp5 &
ecp5_pid=$!
trap 'kill "$ecp5_pid" 2>/dev/null || true' EXIT
run ice40-hx8k
run ice40-up5k
run machxo2-1200 --pack-only
wait "$ecp5_pid" || true
trap - EXIT

field() { sed -n "s/^$2=//p" "build/bitstream/$1/summary.txt" | head -1; }
number() { [[ $1 =~ ^[0-9]+([.][0-9]+)?$ ]]; }

# judge TARGET KIND CEILING: sets `line` and `ok` for the flow whose outputs are in
# build/bitstream/TARGET.
judge() {
    local dir=$1 kind=$2 cells_ceiling=$3
    local status fmax target_mhz cells avail seed
    status=$(field "$dir" status)
    fmax=$(field "$dir" fmax_mhz)
    target_mhz=$(field "$dir" target_mhz)
    seed=$(field "$dir" seed)
    cells=$(sed -nE 's/^used_(TRELLIS_COMB|ICESTORM_LC)=//p' "build/bitstream/$dir/summary.txt" | head -1)
    avail=$(sed -nE 's/^avail_(TRELLIS_COMB|ICESTORM_LC)=//p' "build/bitstream/$dir/summary.txt" | head -1)
    line="flows: $dir: $status, ${cells:-?}/${avail:-?} logic cells, Fmax ${fmax:--} MHz (target $target_mhz MHz, seed ${seed:-?})"
    ok=1
    case $kind in
        meet)
            [ "$status" = ok ] || { ok=0; line+="; the clock is not met"; } ;;
        fit)
            [ "$status" = packed ] || ok=0
            line+="; does not fit yet" ;;
    esac
    if [ -z "$cells" ]; then
        ok=0
        line+="; no cell count (the flow stopped early: build/bitstream/$dir.check.log)"
    elif [ "$cells_ceiling" != - ] && [ "$cells" -gt "$cells_ceiling" ]; then
        ok=0
        line+="; over the ceiling of $cells_ceiling cells"
    fi
}

failed=0
while read -r target kind cells_ceiling; do
    case $target in ''|'#'*) continue ;; esac
    case $kind in
        meet|fit) ;;
        *) echo "flows: $limits: unknown kind '$kind' for $target"; failed=1; continue ;;
    esac
    if [ "$cells_ceiling" != - ] && ! number "$cells_ceiling"; then
        echo "flows: $limits: the ceiling of $target is not a number: '$cells_ceiling'"; failed=1; continue
    fi
    if [ ! -f "build/bitstream/$target/summary.txt" ]; then
        echo "flows: $target: no summary (see build/bitstream/$target.check.log)"; failed=1; continue
    fi
    judge "$target" "$kind" "$cells_ceiling"
    if [ $ok = 1 ]; then echo "$line: PASS"; else echo "$line: FAIL"; failed=1; fi
done < "$limits"
echo "flows: $((SECONDS - start)) s"
exit $failed
