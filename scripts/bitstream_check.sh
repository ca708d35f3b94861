#!/usr/bin/env bash
# The open-tool flows as `make test` runs them: the ECP5 and iCE40 bitstreams and the
# MachXO2 packing (its fit), each held to constraints/flow_limits.txt.
#
# A target the issue's figure is met for (`meet`) must build a bitstream that meets its
# constrained clock, as `make bitstream-*` demands. A target not yet met (`floor`) must
# still synthesise, place, route and pack, and its Fmax must not fall below the floor
# recorded there (the figure last measured, less a margin for the placer's spread): a
# change that costs speed or area fails here even before the target is reached. The
# MachXO2 CPLD configuration does not fit its 1280 cells yet: it is packed, and its cell
# count must stay under the recorded ceiling. Every line printed says which target is
# met and which is not; a flow that stops early leaves a summary without figures and
# fails here by name. A missed clock is retried on two more placement seeds (below).
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

# judge OUTDIR KIND FLOOR CEILING: sets `line` and `speed_ok` (the clock criterion) and
# `ok` (everything) for the flow whose outputs are in build/bitstream/OUTDIR.
judge() {
    local dir=$1 kind=$2 fmax_floor=$3 cells_ceiling=$4
    local status fmax target_mhz cells avail seed
    status=$(field "$dir" status)
    fmax=$(field "$dir" fmax_mhz)
    target_mhz=$(field "$dir" target_mhz)
    seed=$(field "$dir" seed)
    cells=$(sed -nE 's/^used_(TRELLIS_COMB|ICESTORM_LC)=//p' "build/bitstream/$dir/summary.txt" | head -1)
    avail=$(sed -nE 's/^avail_(TRELLIS_COMB|ICESTORM_LC)=//p' "build/bitstream/$dir/summary.txt" | head -1)
    line="flows: $target: $status, ${cells:-?}/${avail:-?} logic cells, Fmax ${fmax:--} MHz (target $target_mhz MHz, seed ${seed:-?})"
    ok=1
    speed_ok=1
    case $kind in
        meet)
            [ "$status" = ok ] || speed_ok=0 ;;
        floor)
            [ "$status" = ok ] || [ "$status" = timing-failed ] || ok=0
            awk -v a="${fmax:-0}" -v f="$fmax_floor" 'BEGIN { exit !(a >= f) }' || speed_ok=0
            line+="; target not met, floor $fmax_floor MHz" ;;
        fit)
            [ "$status" = packed ] || ok=0
            line+="; does not fit yet" ;;
    esac
    [ $speed_ok = 1 ] || ok=0
    if [ -z "$cells" ]; then
        ok=0
        line+="; no cell count (the flow stopped early: build/bitstream/$target.check.log)"
    elif [ "$cells_ceiling" != - ] && [ "$cells" -gt "$cells_ceiling" ]; then
        ok=0
        line+="; over the ceiling of $cells_ceiling cells"
    fi
}

# nextpnr's Fmax spreads by about 10 % (seen: 16 %) between placement seeds, and a
# change that leaves the logic the same can move a fixed seed's result that much. So a
# clock criterion missed on the target's own seed is tried on the next two seeds before
# it fails: a real loss of speed fails on all three, placement luck alone does not.
# The retries cost time only when the first seed misses.
RETRY_SEEDS=2

failed=0
while read -r target kind fmax_floor cells_ceiling; do
    case $target in ''|'#'*) continue ;; esac
    case $kind in
        meet|floor|fit) ;;
        *) echo "flows: $limits: unknown kind '$kind' for $target"; failed=1; continue ;;
    esac
    if [ "$kind" = floor ] && ! number "$fmax_floor"; then
        echo "flows: $limits: the floor of $target is not a number: '$fmax_floor'"; failed=1; continue
    fi
    if [ "$cells_ceiling" != - ] && ! number "$cells_ceiling"; then
        echo "flows: $limits: the ceiling of $target is not a number: '$cells_ceiling'"; failed=1; continue
    fi
    if [ ! -f "build/bitstream/$target/summary.txt" ]; then
        echo "flows: $target: no summary (see build/bitstream/$target.check.log)"; failed=1; continue
    fi
    judge "$target" "$kind" "$fmax_floor" "$cells_ceiling"
    first_seed=$(field "$target" seed)
    retry=1
    while [ $ok = 0 ] && [ $speed_ok = 0 ] && [ $retry -le $RETRY_SEEDS ] && number "${first_seed:-x}"; do
        echo "$line: missed; trying seed $((first_seed + retry))"
        seed=$((first_seed + retry))
        run "$target" --seed "$seed" --variant "seed$seed"
        if [ -f "build/bitstream/$target-seed$seed/summary.txt" ]; then
            judge "$target-seed$seed" "$kind" "$fmax_floor" "$cells_ceiling"
        fi
        retry=$((retry + 1))
    done
    if [ $ok = 1 ]; then echo "$line: PASS"; else echo "$line: FAIL"; failed=1; fi
done < "$limits"
echo "flows: $((SECONDS - start)) s"
exit $failed
