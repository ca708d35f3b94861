#!/usr/bin/env bash
# The quick check before a commit: rustfmt, clippy, Verilator lint of every module and
# the library unit tests. The full suite (co-simulation, formal, flows) is `make test`.
set -euo pipefail
cd "$(dirname "$0")/.."
CARGO=${CARGO:-cargo}
GEN=build/gen
SOURCES=(hdl/*.v)

echo "check: cargo fmt --check"
"$CARGO" fmt --all --check
echo "check: cargo clippy --all-targets -D warnings"
"$CARGO" clippy -q --release --workspace --all-targets -- -D warnings
./scripts/regmap.sh "$GEN"
echo "check: verilator -Wall, every module as top"
for source in "${SOURCES[@]}"; do
    verilator --lint-only -Wall -I"$GEN" --top-module "$(basename "$source" .v)" "${SOURCES[@]}"
done
echo "check: unit tests (cargo test --lib)"
"$CARGO" test -q --release --workspace --lib
echo "check: all passed"
