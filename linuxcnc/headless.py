#!/usr/bin/python3
"""A DISPLAY for LinuxCNC with no X: runs one program and exits (LinuxCNC then shuts down).

LinuxCNC starts it as `headless.py -ini FILE`. It records the servo thread with
halsampler (when FINESTEP_SAMPLES names a file), resets the E-stop, turns the machine
on, homes every joint, opens FINESTEP_PROGRAM in auto mode, runs it, polls until the
interpreter is idle and motion has stopped, and writes "ok" or the first error to
FINESTEP_RESULT (also when LinuxCNC's task process exits under it). With FINESTEP_ESTOP_AFTER (seconds), it presses LinuxCNC's E-stop that
long after the start instead of waiting for the end. With FINESTEP_WHEEL=AXIS:DETENTS,...
(e.g. `Y:100,-40`) it runs no program: it selects the axis through halui and turns the
simulated hand wheel by each count of detents in turn (the `finestep.0.sim.wheel-edges`
pin), waits for LinuxCNC's jog to end and writes the distance the chip moved every axis
(its step counts over SCALE) next to the expected one (detents times MPG_SCALE). Like
AXIS, it loads the INI's POSTGUI_HALFILE once LinuxCNC (and halui) run. Needs Debian's
/usr/bin/python3 (its `linuxcnc` module).
"""

import os
import signal
import subprocess
import sys
import time

import linuxcnc


def halcmd(*args):
    return subprocess.run(["halcmd"] + list(args), check=True, capture_output=True, text=True).stdout.strip()


def ini_value(ini, section, key):
    """The INI's [section]key (first occurrence), or None."""
    current = None
    with open(ini) as text:
        for line in text:
            line = line.strip()
            if line.startswith("["):
                current = line.strip("[]")
            elif current == section and "=" in line and line.split("=", 1)[0].strip() == key:
                return line.split("=", 1)[1].strip()
    return None


class Failed(Exception):
    pass


def alive(pid):
    """Whether process `pid` runs (exists and is no zombie)."""
    try:
        with open("/proc/%d/stat" % pid) as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def run_process(comm, marker):
    """The pid of this run's process named `comm` (its environment holds `marker`), or None."""
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open("/proc/%s/comm" % entry) as f:
                if f.read().strip() != comm:
                    continue
            with open("/proc/%s/environ" % entry, "rb") as f:
                if marker.encode() in f.read().split(b"\0"):
                    return int(entry)
        except OSError:
            continue
    return None


def main():
    program = os.environ["FINESTEP_PROGRAM"]
    result_path = os.environ["FINESTEP_RESULT"]
    samples = os.environ.get("FINESTEP_SAMPLES")
    timeout = float(os.environ.get("FINESTEP_TIMEOUT", "3600"))
    estop_after = os.environ.get("FINESTEP_ESTOP_AFTER")
    stat, command, errors = linuxcnc.stat(), linuxcnc.command(), linuxcnc.error_channel()
    sampler = None
    if samples:
        sampler = subprocess.Popen(["halsampler", "-t"], stdout=open(samples, "w"))
    messages = []
    # LinuxCNC's task (milltask) has been seen to vanish mid-program with no message
    # (docs/linuxcnc.md): its status then stays as it was and the end never comes. Once
    # it is up, its pid is watched and its exit fails the run at once.
    task = []

    def poll():
        if task and not alive(task[0]):
            raise Failed("LinuxCNC's task (milltask, pid %d) exited; its status froze at line %d" % (
                task[0], stat.motion_line))
        stat.poll()
        while True:
            error = errors.poll()
            if not error:
                break
            kind, text = error
            if kind in (linuxcnc.NML_ERROR, linuxcnc.OPERATOR_ERROR):
                messages.append(text)
                raise Failed(text)
            print("headless: %s" % text, flush=True)

    def wait_for(condition, what, seconds=60.0):
        end = time.time() + seconds
        while time.time() < end:
            poll()
            if condition():
                return
            time.sleep(0.05)
        raise Failed("timed out waiting for %s (task state %d, mode %d, interpreter %d, estop %d, enabled %d)" % (
            what, stat.task_state, stat.task_mode, stat.interp_state, stat.estop, stat.enabled))

    outcome = "ok"
    ini = sys.argv[sys.argv.index("-ini") + 1] if "-ini" in sys.argv else None
    try:
        wait_for(lambda: stat.task_state != 0, "LinuxCNC to come up")
        pid = run_process("milltask", "FINESTEP_RESULT=" + result_path)
        if pid:
            task.append(pid)
        postgui = ini and ini_value(ini, "HAL", "POSTGUI_HALFILE")
        if postgui:
            halcmd("-i", ini, "-f", os.path.join(os.path.dirname(ini), postgui))
        command.state(linuxcnc.STATE_ESTOP_RESET)
        wait_for(lambda: stat.task_state == linuxcnc.STATE_ESTOP_RESET, "E-stop reset")
        command.state(linuxcnc.STATE_ON)
        wait_for(lambda: stat.task_state == linuxcnc.STATE_ON, "machine on")
        command.mode(linuxcnc.MODE_MANUAL)
        command.wait_complete()
        command.home(-1)
        wait_for(lambda: all(stat.homed[j] for j in range(stat.joints)), "homing")
        wheel = os.environ.get("FINESTEP_WHEEL")
        if wheel:
            outcome = turn_wheel(wheel, ini, stat, command, wait_for)
            return finish(outcome, sampler, result_path, command)
        command.mode(linuxcnc.MODE_AUTO)
        command.wait_complete()
        command.program_open(program)
        command.wait_complete()
        started = time.time()
        command.auto(linuxcnc.AUTO_RUN, 0)
        wait_for(lambda: stat.interp_state != linuxcnc.INTERP_IDLE, "the program to start", 10.0)
        if estop_after:
            end = time.time() + float(estop_after)
            while time.time() < end:
                poll()
                if stat.interp_state == linuxcnc.INTERP_IDLE:
                    raise Failed("the program ended before the E-stop")
                time.sleep(0.05)
            command.state(linuxcnc.STATE_ESTOP)
            wait_for(lambda: stat.task_state == linuxcnc.STATE_ESTOP, "the E-stop")
            print("headless: E-stop pressed %.1f s after the start" % (time.time() - started), flush=True)
            time.sleep(1.0)
            return finish("ok", sampler, result_path, command)
        wait_for(
            lambda: stat.interp_state == linuxcnc.INTERP_IDLE and stat.queue == 0 and stat.inpos,
            "the program to end",
            timeout,
        )
        print("headless: %s ran in %.1f s of wall time" % (os.path.basename(program), time.time() - started),
              flush=True)
        time.sleep(0.5)
    except Failed as error:
        outcome = "error: %s" % error
    return finish(outcome, sampler, result_path, command)


def turn_wheel(spec, ini, stat, command, wait_for):
    """Jogs one axis with the simulated hand wheel through halui's selection and LinuxCNC's
    jog pins; "ok" when every axis moved exactly as the detents say, else the figures."""
    axis, turns = spec.split(":")
    axis = axis.lower()
    coordinates = (ini_value(ini, "TRAJ", "COORDINATES") or "XYZ").lower()
    joints = len(coordinates)
    scales = [float(ini_value(ini, "JOINT_%d" % j, "SCALE")) for j in range(joints)]
    slots = [int(ini_value(ini, "JOINT_%d" % j, "FINESTEP_SLOT")) for j in range(joints)]
    mpg_scale = float(ini_value(ini, "AXIS_" + axis.upper(), "MPG_SCALE"))
    command.teleop_enable(1)
    command.wait_complete()
    wait_for(lambda: stat.motion_mode == linuxcnc.TRAJ_MODE_TELEOP, "teleop mode")
    halcmd("setp", "halui.axis.%s.select" % axis, "1")
    time.sleep(0.3)
    halcmd("setp", "halui.axis.%s.select" % axis, "0")
    if halcmd("getp", "halui.axis.%s.is-selected" % axis) != "TRUE":
        raise Failed("halui did not select axis %s" % axis)

    def counts():
        return [int(halcmd("getp", "finestep.0.stepgen.%02d.counts" % slot)) for slot in slots]

    start = counts()
    edges = 0
    detents = 0
    for turn in turns.split(","):
        detents += int(turn)
        edges += 4 * int(turn)
        halcmd("setp", "finestep.0.sim.wheel-edges", str(edges))
        # One edge every 10 000 clocks of the simulated chip, then LinuxCNC's jog: wait
        # until the wheel's detents and the step counts stand still.
        last, still = None, 0
        end = time.time() + 300
        while still < 10:
            if time.time() > end:
                raise Failed("the jog did not settle")
            now = (halcmd("getp", "finestep.0.mpg.detents"), counts())
            still = still + 1 if now == last else 0
            last = now
            time.sleep(0.2)
        print("headless: wheel at %s detents, chip at %s steps" % (last[0], last[1]), flush=True)
    moved = [(c - s) / scale for c, s, scale in zip(counts(), start, scales)]
    expected = [detents * mpg_scale if name == axis else 0.0 for name in coordinates]
    wheel_detents = int(halcmd("getp", "finestep.0.mpg.detents"))
    figures = "; ".join("%s moved %.4f, expected %.4f" % (name.upper(), m, e)
                        for name, m, e in zip(coordinates, moved, expected))
    print("headless: hand wheel %d detents (chip's MPG_DETENTS %d): %s" % (detents, wheel_detents, figures),
          flush=True)
    exact = all(abs(m - e) * scale < 0.5 for m, e, scale in zip(moved, expected, scales))
    return "ok" if exact and wheel_detents == detents else "error: hand wheel: " + figures


def finish(outcome, sampler, result_path, command):
    """Stops the recording, writes the outcome, leaves LinuxCNC in E-stop."""
    if sampler:
        sampler.send_signal(signal.SIGINT)
        sampler.wait()
    with open(result_path, "w") as out:
        out.write(outcome + "\n")
    try:
        command.state(linuxcnc.STATE_ESTOP)
    except Exception:  # LinuxCNC may already be going down
        pass
    return 0 if outcome == "ok" else 1


if __name__ == "__main__":
    sys.exit(main())
