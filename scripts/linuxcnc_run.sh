#!/usr/bin/env bash
# Runs one G-code program through headless LinuxCNC on the simulated finestep chip and
# prints the figures: scripts/linuxcnc_run.sh PROGRAM.ngc [model|lockstep]
# Expects what scripts/linuxcnc.sh builds and installs (the finestep HAL module, the
# finestep and finestep-linuxcnc binaries, an ordinary user for rtapi). Outputs under
# build/linuxcnc/run/<program>/ (the generated INI and HAL, LinuxCNC's log, the recording).
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
program=$(readlink -f "$1")
target=${2:-model}
config=${FINESTEP_LINUXCNC_CONFIG:-linuxcnc/mill.toml}
rt_user=${FINESTEP_RT_USER:-finestep-rt}
name=$(basename "$program" .ngc)
work=$repo/build/linuxcnc/run/$name
rm -rf "$work"
mkdir -p "$work"
chmod 0777 "$work"

chip_pid=""
cleanup() { [ -n "$chip_pid" ] && kill "$chip_pid" 2>/dev/null; true; }
trap cleanup EXIT
target/release/finestep sim-chip "$work/chip.sock" --target "$target" > "$work/sim-chip.log" 2>&1 &
chip_pid=$!
for _ in $(seq 100); do [ -S "$work/chip.sock" ] && break; sleep 0.1; done
[ -S "$work/chip.sock" ] || { cat "$work/sim-chip.log"; echo "linuxcnc_run: sim-chip did not come up"; exit 1; }
chmod 0666 "$work/chip.sock"

target/release/finestep-linuxcnc config --config "$config" --bus "sim:$work/chip.sock" \
    --display "$repo/linuxcnc/headless.py" --record --out "$work" > /dev/null
joints=$(sed -n 's/^JOINTS = //p' "$work/finestep.ini")

start=$(date +%s.%N)
status=0
env RTAPI_UID="$(id -u "$rt_user")" RTAPI_FIFO_PATH="$work/rtapi_fifo" RUNTESTS=1 \
    FINESTEP_PROGRAM="$program" FINESTEP_SAMPLES="$work/samples.txt" FINESTEP_RESULT="$work/result.txt" \
    linuxcnc "$work/finestep.ini" > "$work/linuxcnc.log" 2>&1 || status=$?
end=$(date +%s.%N)
result=$(cat "$work/result.txt" 2>/dev/null || echo "no result (LinuxCNC exited $status)")
periods=$(wc -l < "$work/samples.txt" 2>/dev/null || echo 0)
rate=$(awk -v p="$periods" -v a="$start" -v b="$end" 'BEGIN { printf "%.0f", p / (b - a) }')
echo "$name: LinuxCNC on the $target chip: $result; $periods servo periods in $(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }') s ($rate periods/s incl. start-up)"
if [ "$result" != "ok" ]; then
    grep -iE "error|finestep" "$work/linuxcnc.log" | head -20 || true
    exit 1
fi
target/release/finestep-linuxcnc check "$work/samples.txt" --joints "$joints"
