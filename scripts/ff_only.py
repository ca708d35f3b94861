#!/usr/bin/env python3
"""Flip-flops that will take a logic cell of their own on the iCE40, by register.

An iCE40 logic cell holds a LUT4, a carry and a flip-flop, and nextpnr packs a
flip-flop with the LUT4 that drives its D input only when that LUT4 drives nothing
else. A flip-flop loaded straight from a shared net (a register written from the bus
data, a copy of another register, a snapshot of positions) takes a cell of its own
with its LUT unused. On a full part these cells, not the logic, decide whether the
design fits and routes.

Reads the Yosys JSON a `scripts/bitstream.sh` iCE40 build writes (build/bitstream/
TARGET/*.json, after synth_ice40) and prints, per register (bit indices dropped), how
many of its flip-flops cannot pack with their driver, and the total.

    scripts/ff_only.py build/bitstream/ice40-hx8k/ice40_hx8k_breakout.json [N]
"""
import collections
import json
import re
import sys


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    shown = int(sys.argv[2]) if len(sys.argv) == 3 else 40
    with open(sys.argv[1]) as f:
        design = json.load(f)
    top = max(design["modules"].values(), key=lambda m: len(m.get("cells", {})))
    cells = top["cells"]
    driver, fanout = {}, collections.Counter()
    for name, cell in cells.items():
        for port, direction in cell["port_directions"].items():
            for bit in cell["connections"][port]:
                if direction == "output":
                    driver[bit] = cell["type"]
                else:
                    fanout[bit] += 1
    # The shortest name of each net bit (Yosys keeps the RTL's register names).
    bit_name = {}
    for net, info in top.get("netnames", {}).items():
        for bit in info["bits"]:
            if bit not in bit_name or len(net) < len(bit_name[bit]):
                bit_name[bit] = net
    alone, total = collections.Counter(), collections.Counter()
    for name, cell in cells.items():
        if not cell["type"].startswith("SB_DFF"):
            continue
        d_bit = cell["connections"]["D"][0]
        register = re.sub(r"\[\d+\]", "", bit_name.get(cell["connections"]["Q"][0], name))
        total[register] += 1
        if not (driver.get(d_bit) == "SB_LUT4" and fanout[d_bit] == 1):
            alone[register] += 1
    for register, count in alone.most_common(shown):
        print(f"{count:6d} of {total[register]:5d}  {register}")
    print(f"{sum(alone.values()):6d} of {sum(total.values()):5d}  flip-flops without a LUT4 of their own, in all")


if __name__ == "__main__":
    main()
