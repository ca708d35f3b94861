#!/usr/bin/env bash
# Writes the Verilog headers the RTL includes into the directory given (default
# build/gen), for the HDL flows outside cargo: the register map's constants
# (finestep_regs.vh, from hdl/registers.toml), the interface's constants
# (finestep_interface.vh) and each module's elaboration checks (<module>_checks.vh), from
# hdl/interface.toml.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-build/gen}
mkdir -p "$out"
cargo run -q --release -p finestep-regmap -- headers "$out"
