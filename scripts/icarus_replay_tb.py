"""The cocotb testbench of the second simulator (scripts/icarus_replay.py): replays one pin
record of a Verilator lockstep run (FINESTEP_REPLAY, written by finestep-cosim's
TopLockstep with FINESTEP_PIN_RECORD_DIR set) into finestep_top under Icarus Verilog,
through sim/icarus/finestep_top_pins.v, whose comparator checks every output pin on every
clock against the outputs the Verilated top drove on that clock (`!==`: an X or Z differs).
The test sets the inputs and the expected outputs only where the record changes them and
lets the simulator run the clocks in between; it fails on the first clock that differs,
naming the pins."""

import os

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import Timer

PERIOD = 10  # ns: rising edge of clock n (n = 1, 2, ...) at 10n - 5, compared at 10n
OUTPUT_NAMES = {24: "spi_miso", 25: "spi_miso_oe", 26: "irq", 27: "bus_ad_oe", 28: "coolant_mist",
                29: "coolant_flood", 30: "light", 48: "spindle_pwm", 49: "spindle_dir", 50: "spindle_en",
                51: "dac_cs_n", 52: "dac_sck", 53: "dac_sdi"}


def pin_name(bit):
    if bit < 24:
        return f"{('pin_a', 'pin_b', 'pin_en')[bit // 8]}[{bit % 8}]"
    if 32 <= bit < 48:
        return f"bus_ad_out[{bit - 32}]"
    if bit >= 56:
        return f"gpio[{bit - 56}]"
    return OUTPUT_NAMES.get(bit, f"outputs bit {bit}")


def read_record(path):
    inputs, outputs = [], []
    with open(path) as f:
        for line in f:
            kind, *rest = line.split()
            if kind == "I":
                inputs.append((int(rest[0]), int(rest[1], 16)))
            elif kind == "O":
                outputs.append((int(rest[0]), int(rest[1], 16)))
    return inputs, outputs


def timeline(inputs, changes):
    """(time in ns, signal, value): the inputs of clock c+1 set at 10c + 2 (after clock c's
    compare, before its rising edge), clock n's expected outputs at 10n - 2. The power-on
    outputs (the record's cycle 0) are before any clock and reset: Verilator starts every
    flip-flop at 0 (--x-initial fast), Icarus at X; they are not compared."""
    events, cycle = [], 0
    for cycles, word in inputs:
        events.append((PERIOD * cycle + 2, "in_word", word))
        cycle += cycles
    expected = changes[0][1]
    events.append((PERIOD - 2, "expect_word", expected))
    for n, word in changes[1:]:
        events.append((PERIOD * n - 2, "expect_word", word))
    events.sort(key=lambda e: e[0])
    return events, cycle


@cocotb.test()
async def replay(dut):
    path = os.environ["FINESTEP_REPLAY"]
    name = os.path.basename(path)
    inputs, changes = read_record(path)
    events, total = timeline(inputs, changes)
    assert total > 0 and changes, f"{name}: an empty record"
    dut.clk.value = 0
    dut.in_word.value = inputs[0][1]
    dut.expect_word.value = changes[0][1]
    cocotb.start_soon(Clock(dut.clk, PERIOD, "ns").start(start_high=False))
    now = 0
    for at, signal, value in events:
        if at > now:
            await Timer(at - now, "ns")
            now = at
        getattr(dut, signal).value = value
    end = PERIOD * total + 1  # just after the last compare
    await Timer(end - now, "ns")
    compared = int(dut.compared.value)
    if int(dut.mismatch.value):
        cycle = int(dut.mismatch_cycle.value)
        expected = int(dut.mismatch_expected.value)
        actual = dut.mismatch_actual.value
        if actual.is_resolvable:
            differ = int(actual) ^ expected
            pins = [f"{pin_name(b)}: Verilator {expected >> b & 1}, Icarus {int(actual) >> b & 1}"
                    for b in range(64) if differ >> b & 1]
        else:
            text = str(actual)
            pins = [f"{pin_name(63 - i)}: Verilator {expected >> (63 - i) & 1}, Icarus {c}"
                    for i, c in enumerate(text) if c not in "01" or int(c) != expected >> (63 - i) & 1]
        raise AssertionError(f"{name}: clock {cycle} of {total}: " + "; ".join(pins))
    assert compared == total, f"{name}: {compared} clocks compared, the record has {total}"
    dut._log.info("replay %s: %d clocks, every output pin on every clock equal to Verilator's (%d changes)",
                  name, compared, len(changes) - 1)
