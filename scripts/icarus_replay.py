#!/usr/bin/env python3
"""Two simulators, one answer (docs/verification.md): the RTL under Icarus Verilog, driven by
a cocotb testbench (scripts/icarus_replay_tb.py) with the pin stimulus recorded from the
Verilator lockstep runs, every output pin compared with Verilator's on every clock.

  scripts/icarus_replay.py [--quick]

1. Runs pin-level lockstep tests of finestep-cosim (Verilated RTL against the model) with
   FINESTEP_PIN_RECORD_DIR=build/icarus/records: each TopLockstep writes its inputs every
   clock (run-length) and the outputs Verilator drove at every change.
2. Builds finestep_top (hdl/, Verilog-2005: iverilog -g2005) behind
   sim/icarus/finestep_top_pins.v for each variant the records use and replays every
   record under cocotb; fails at the first clock whose outputs differ.

--quick (make test): streaming over SPI, an E-stop mid-move, the encoders and the probe.
The full run (make test-long) records every test of top_smoke, top_faults and top_feedback.
"""

import argparse
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "build" / "icarus"
RECORDS = OUT / "records"

QUICK = {
    "top_smoke": ["spi_stream_moves_exactly"],
    "top_faults": ["estop_halts_mid_move"],
    "top_feedback": ["probe_latches_everything_on_one_clock"],
}
FULL = {"top_smoke": None, "top_faults": None, "top_feedback": None}

VARIANTS = {
    "full": {},
    "motion": {"HAS_SPINDLE": 0, "HAS_OUTPUTS": 0, "N_GPIO": 0, "HAS_PBP": 0},
    "motion-no-mpg": {"HAS_SPINDLE": 0, "HAS_OUTPUTS": 0, "N_GPIO": 0, "HAS_MPG": 0, "HAS_PBP": 0},
    # STEP_DIGIT as rust/finestep-rtl-sys's SERIAL_TOP_DIGIT (the CPLD boards' engine)
    "motion-serial": {"HAS_SPINDLE": 0, "HAS_OUTPUTS": 0, "N_GPIO": 0, "STEP_DIGIT": 4, "HAS_PBP": 0},
}


def record(selection):
    shutil.rmtree(RECORDS, ignore_errors=True)
    RECORDS.mkdir(parents=True)
    env = dict(os.environ, FINESTEP_PIN_RECORD_DIR=str(RECORDS))
    for test, names in selection.items():
        cmd = ["cargo", "test", "--release", "-q", "-p", "finestep-cosim", "--test", test, "--"]
        if names:
            cmd += ["--exact"] + names
        r = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit(f"icarus: recording {test} failed:\n{r.stdout[-3000:]}{r.stderr[-3000:]}")
    return sorted(RECORDS.glob("*.pins"))


def variant_of(path):
    with open(path) as f:
        for line in f:
            if line.startswith("variant "):
                return line.split()[1]
    sys.exit(f"icarus: {path}: no variant line")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true")
    p.add_argument("--no-record", action="store_true", help="replay the records already in build/icarus/records")
    args = p.parse_args()
    from cocotb_tools.runner import get_results, get_runner

    subprocess.run([str(ROOT / "scripts" / "regmap.sh"), str(ROOT / "build" / "gen")], check=True,
                   stdout=subprocess.DEVNULL)
    start = time.time()
    records = sorted(RECORDS.glob("*.pins")) if args.no_record else record(QUICK if args.quick else FULL)
    if not records:
        sys.exit("icarus: no pin record")
    print(f"icarus: {len(records)} records from the Verilator lockstep in {time.time() - start:.0f} s")
    sources = sorted((ROOT / "hdl").glob("*.v")) + [ROOT / "sim" / "icarus" / "finestep_top_pins.v"]
    runner = get_runner("icarus")
    built = set()
    failed, clocks = [], 0
    for rec in records:
        variant = variant_of(rec)
        build_dir = OUT / f"sim_{variant}"
        if variant not in built:
            runner.build(sources=sources, includes=[ROOT / "build" / "gen"], hdl_toplevel="finestep_top_pins",
                         parameters=VARIANTS[variant], build_dir=build_dir, build_args=["-g2005", "-Wall"],
                         always=True, timescale=("1ns", "1ps"), log_file=OUT / f"build_{variant}.log")
            warnings = [l for l in (OUT / f"build_{variant}.log").read_text().splitlines()
                        if "warning" in l.lower() and "timescale" not in l]
            for w in warnings[:10]:
                print(f"icarus: {w}")
            built.add(variant)
        t0 = time.time()
        log = OUT / f"{rec.stem}.log"
        xml = OUT / f"{rec.stem}.xml"
        runner.test(test_module="icarus_replay_tb", hdl_toplevel="finestep_top_pins", build_dir=build_dir,
                    test_dir=ROOT / "scripts", extra_env={"FINESTEP_REPLAY": str(rec)}, results_xml=str(xml),
                    log_file=log)
        ran, fails = get_results(xml)
        n = sum(int(line.split()[1]) for line in rec.read_text().splitlines() if line.startswith("I "))
        if ran == 1 and fails == 0:
            clocks += n
            seconds = time.time() - t0
            print(f"icarus: {rec.stem}: {n} clocks, every output pin every clock as Verilator "
                  f"({seconds:.0f} s, {n / max(seconds, 1e-3):.0f} clocks/s)")
        else:
            failed.append(rec.stem)
            text = log.read_text() if log.exists() else ""
            why = [line for line in text.splitlines() if "AssertionError" in line or "cycle" in line][:4]
            print(f"icarus: {rec.stem}: FAILED ({log})")
            for line in why:
                print(f"    {line.strip()}")
    print(f"icarus: {len(records) - len(failed)} of {len(records)} records equal, {clocks} clocks compared, "
          f"{time.time() - start:.0f} s")
    if failed:
        sys.exit(1)


if __name__ == "__main__":
    main()
