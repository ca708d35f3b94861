#!/usr/bin/env bash
# Writes the register map's Verilog constants (finestep_regs.vh) into the directory
# given (default build/gen), from hdl/registers.toml, for the HDL flows outside cargo.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-build/gen}
mkdir -p "$out"
cargo run -q --release -p finestep-regmap -- verilog "$out/finestep_regs.vh"
