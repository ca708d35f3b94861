#!/usr/bin/python3
"""A DISPLAY for LinuxCNC with no X: runs one program and exits (LinuxCNC then shuts down).

LinuxCNC starts it as `headless.py -ini FILE`. It records the servo thread with
halsampler (when FINESTEP_SAMPLES names a file), resets the E-stop, turns the machine
on, homes every joint, opens FINESTEP_PROGRAM in auto mode, runs it, polls until the
interpreter is idle and motion has stopped, and writes "ok" or the first error to
FINESTEP_RESULT. With FINESTEP_ESTOP_AFTER (seconds), it presses LinuxCNC's E-stop that
long after the start instead of waiting for the end. Needs Debian's /usr/bin/python3
(its `linuxcnc` module).
"""

import os
import signal
import subprocess
import sys
import time

import linuxcnc


class Failed(Exception):
    pass


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

    def poll():
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
    try:
        wait_for(lambda: stat.task_state != 0, "LinuxCNC to come up")
        command.state(linuxcnc.STATE_ESTOP_RESET)
        wait_for(lambda: stat.task_state == linuxcnc.STATE_ESTOP_RESET, "E-stop reset")
        command.state(linuxcnc.STATE_ON)
        wait_for(lambda: stat.task_state == linuxcnc.STATE_ON, "machine on")
        command.mode(linuxcnc.MODE_MANUAL)
        command.wait_complete()
        command.home(-1)
        wait_for(lambda: all(stat.homed[j] for j in range(stat.joints)), "homing")
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
