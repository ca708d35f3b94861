#!/usr/bin/env bash
# Runs one G-code program through headless LinuxCNC on the simulated finestep chip and
# prints the figures: scripts/linuxcnc_run.sh PROGRAM.ngc [model|lockstep]
# With FINESTEP_ESTOP_AFTER=SECONDS, LinuxCNC's E-stop is pressed that long after the start.
# With FINESTEP_KILL_AFTER=PERIODS, LinuxCNC's realtime process is killed that many servo
# periods into the run and the chip's watchdog is checked (finestep-linuxcnc watchdog).
# With FINESTEP_WHEEL=AXIS:DETENTS[,DETENTS...] (e.g. Y:100,-40) the program is not run: the
# simulated hand wheel is turned and LinuxCNC jogs the axis halui selected; every axis must
# move by the detents times MPG_SCALE (linuxcnc/headless.py), every period checked as usual.
# With FINESTEP_LOOP=finestep or stepgen, the mill runs in closed loop through PID on the
# simulated closed-loop machine (docs/linuxcnc.md#closed-loop): finestep's stepgens with
# the machine on the simulated chip's pins, or LinuxCNC's software stepgen into the same
# machine (the fsplant HAL component); FINESTEP_PID=KEY=VALUE,... changes the PID tuning.
# It prints each joint's peak and RMS following error instead of the open-loop check.
# Exit status: 0 checked, 1 failed, 2 LinuxCNC's interpreter refused the program.
# Expects what scripts/linuxcnc.sh builds and installs (the finestep HAL module, the
# finestep and finestep-linuxcnc binaries, an ordinary user for rtapi). Outputs under
# build/linuxcnc/run/<program>/ (the generated INI and HAL, LinuxCNC's log, the recording).
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
program=$(readlink -f "$1")
target=${2:-model}
# The 3-axis mill, or the same with a rotary A for a program that turns A (an A word
# outside comments).
config=linuxcnc/mill.toml
if sed 's/([^)]*)//g; s/;.*//' "$program" | grep -qiE '(^|[^A-Z_#<])A *[-+]?[0-9.#[]'; then
    config=linuxcnc/mill-a.toml
fi
config=${FINESTEP_LINUXCNC_CONFIG:-$config}
rt_user=${FINESTEP_RT_USER:-finestep-rt}
name=$(basename "$program" .ngc)
[ -n "${FINESTEP_WHEEL:-}" ] && name=wheel
loop=${FINESTEP_LOOP:-open}
[ "$loop" = open ] || name=$name-$loop
work=$repo/build/linuxcnc/run/$name
rm -rf "$work"
mkdir -p "$work"
chmod 0777 "$work"

target/release/finestep-linuxcnc config --config "$config" --bus "sim:$work/chip.sock" \
    --display "$repo/linuxcnc/headless.py" --record --out "$work" --loop "$loop" ${FINESTEP_PID:+--pid "$FINESTEP_PID"} > /dev/null
joints=$(sed -n 's/^JOINTS = //p' "$work/finestep.ini")
period_ns=$(sed -n 's/^SERVO_PERIOD = //p' "$work/finestep.ini")

chip_pid=""
cleanup() { [ -n "$chip_pid" ] && kill "$chip_pid" 2>/dev/null; true; }
trap cleanup EXIT
if [ "$loop" != stepgen ]; then
    # The closed loop's machine on the chip's pins, as the INI's [PLANT] says.
    plant=()
    if [ "$loop" = finestep ]; then
        plant=(--lag-clocks "$(sed -n 's/^LAG_CLOCKS = //p' "$work/finestep.ini")"
            --counts-per-step "$(sed -n 's/^COUNTS_PER_STEP = //p' "$work/finestep.ini")")
    fi
    target/release/finestep sim-chip "$work/chip.sock" --target "$target" "${plant[@]}" > "$work/sim-chip.log" 2>&1 &
    chip_pid=$!
    for _ in $(seq 100); do [ -S "$work/chip.sock" ] && break; sleep 0.1; done
    [ -S "$work/chip.sock" ] || { cat "$work/sim-chip.log"; echo "linuxcnc_run: sim-chip did not come up"; exit 1; }
    chmod 0666 "$work/chip.sock"
fi

# The process of this run whose environment holds $2 (found through /proc, so that
# only this run's processes are ever signalled).
run_process() {
    local pid
    for pid in $(ls /proc | grep -E '^[0-9]+$'); do
        [ "$(cat "/proc/$pid/comm" 2>/dev/null)" = "$1" ] || continue
        tr '\0' '\n' < "/proc/$pid/environ" 2>/dev/null | grep -qxF "$2" && echo "$pid"
    done
    true
}

# Seconds the display waits for the program's end: LinuxCNC's task has been seen to keep
# a stale motion status after the chip finished (docs/linuxcnc.md), which would hang.
timeout=${FINESTEP_TIMEOUT:-900}
# A LinuxCNC process that crashes leaves its core in the run's folder. HOME is the run's
# folder too: LinuxCNC's tool table is a file mapped at $HOME/.tool.mmap that every
# LinuxCNC process (another run's, or rs274 in a conformance run) truncates and rewrites
# when it starts, killing a running task with SIGBUS (docs/linuxcnc.md).
ulimit -c unlimited 2>/dev/null || true
start=$(date +%s.%N)
status=0
if [ -z "${FINESTEP_KILL_AFTER:-}" ]; then
    env HOME="$work" RTAPI_UID="$(id -u "$rt_user")" RTAPI_FIFO_PATH="$work/rtapi_fifo" RUNTESTS=1 FINESTEP_TIMEOUT="$timeout" \
        FINESTEP_PROGRAM="$program" FINESTEP_SAMPLES="$work/samples.txt" FINESTEP_RESULT="$work/result.txt" \
        linuxcnc "$work/finestep.ini" > "$work/linuxcnc.log" 2>&1 || status=$?
else
    # LinuxCNC killed mid-program: once the driver has run FINESTEP_KILL_AFTER servo
    # periods, SIGKILL to this run's rtapi_app (the realtime process that holds the
    # chip's socket); then the chip is watched, and the rest of LinuxCNC sent home.
    env HOME="$work" RTAPI_UID="$(id -u "$rt_user")" RTAPI_FIFO_PATH="$work/rtapi_fifo" RUNTESTS=1 FINESTEP_TIMEOUT="$timeout" \
        FINESTEP_PROGRAM="$program" FINESTEP_SAMPLES="$work/samples.txt" FINESTEP_RESULT="$work/result.txt" \
        linuxcnc "$work/finestep.ini" > "$work/linuxcnc.log" 2>&1 &
    linuxcnc_pid=$!
    for _ in $(seq 1200); do
        running=0
        [ -f "$work/samples.txt" ] && running=$(awk '$NF == 1' "$work/samples.txt" | wc -l)
        [ "$running" -ge "$FINESTEP_KILL_AFTER" ] && break
        sleep 0.1
    done
    rtapi=$(run_process rtapi_app "RTAPI_FIFO_PATH=$work/rtapi_fifo")
    [ -n "$rtapi" ] || { echo "linuxcnc_run: no rtapi_app of this run"; exit 1; }
    kill -KILL $rtapi
    echo "$name: killed LinuxCNC's rtapi_app (pid $rtapi) after $running servo periods of the driver running"
    sleep 0.5
    watch=0
    target/release/finestep-linuxcnc watchdog --socket "$work/chip.sock" || watch=$?
    display=$(run_process headless.py "FINESTEP_RESULT=$work/result.txt")
    display=${display:-$(run_process python3 "FINESTEP_RESULT=$work/result.txt")}
    [ -n "$display" ] && kill -TERM $display
    for _ in $(seq 300); do kill -0 "$linuxcnc_pid" 2>/dev/null || break; sleep 0.1; done
    kill -0 "$linuxcnc_pid" 2>/dev/null && kill -TERM "$linuxcnc_pid"
    exit $watch
fi
end=$(date +%s.%N)
result=$(cat "$work/result.txt" 2>/dev/null || echo "no result (LinuxCNC exited $status)")
periods=$(wc -l < "$work/samples.txt" 2>/dev/null || echo 0)
rate=$(awk -v p="$periods" -v a="$start" -v b="$end" 'BEGIN { printf "%.0f", p / (b - a) }')
chip="the $target chip"
[ "$loop" = stepgen ] && chip="LinuxCNC's software stepgen"
[ "$loop" = open ] || chip="$chip, closed loop"
echo "$name: LinuxCNC on $chip: $result; $periods servo periods in $(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }') s ($rate periods/s incl. start-up)"
if [ "$result" != "ok" ]; then
    grep -iE "error|finestep" "$work/linuxcnc.log" | grep -v "terminated with an error" | head -20 || true
    # Exit status 2: LinuxCNC's own interpreter refused the program (not finestep's doing).
    grep -q "interp_error" "$work/linuxcnc.log" && exit 2
    # The recording up to the failure is still checked (a partial run's figures), as
    # the step timing the chip measured; the run fails either way.
    if [ "$loop" = open ] && [ -s "$work/samples.txt" ]; then
        echo "$name: the recording up to the failure:"
        target/release/finestep-linuxcnc check "$work/samples.txt" --joints "$joints" --period-ns "$period_ns" \
            --config "$config" --socket "$work/chip.sock" || true
    fi
    exit 1
fi
if [ "$loop" != open ]; then
    # The closed loop: LinuxCNC's following error per joint (joint.N.f-error).
    target/release/finestep-linuxcnc ferror "$work/samples.txt" --ini "$work/finestep.ini"
    exit 0
fi
if [ -n "${FINESTEP_ESTOP_AFTER:-}" ]; then
    # LinuxCNC's E-stop pressed mid-program (linuxcnc/headless.py): checked up to the
    # stop, then no step after it and none beyond the command.
    target/release/finestep-linuxcnc check "$work/samples.txt" --joints "$joints" --period-ns "$period_ns" --config "$config" --expect-stop \
        --socket "$work/chip.sock"
    exit 0
fi
# The open-loop check, then the step timing sim-chip measured at the chip's pins every
# clock (finestep-linuxcnc check --socket asks it; a violation fails the run).
target/release/finestep-linuxcnc check "$work/samples.txt" --joints "$joints" --period-ns "$period_ns" --config "$config" \
    --socket "$work/chip.sock"
if [ -n "${FINESTEP_WHEEL:-}" ]; then
    grep "^headless: hand wheel" "$work/linuxcnc.log" | sed 's/^headless: /  /'
    exit 0
fi
# The same program planned by finestep's own planner under the same limits (the model's
# fast path; its figure is the planned machining time).
if target/release/finestep run --fast --config "$config" "$program" --out "$work/finestep-run" > "$work/finestep-run.log" 2>&1; then
    sed -n 's/.* elements, \([0-9]*\) periods of [0-9.]* ms: \([0-9.]*\) s of machining.*/  finestep'"'"'s planner, same limits: \1 periods, \2 s of machining/p' "$work/finestep-run.log"
else
    echo "  finestep's planner: $(grep -m1 -iE "error|refused|unsupported" "$work/finestep-run.log" || tail -1 "$work/finestep-run.log")"
fi
