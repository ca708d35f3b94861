#!/usr/bin/env bash
# make conformance: finestep's G-code interpretation against LinuxCNC's own interpreter.
# Installs linuxcnc-uspace (scripts/linuxcnc.sh --install), runs `rs274 -g -t TOOLTABLE` on
# every .ngc file the package ships (in the file's folder, so that its subroutines are
# found), and compares with `finestep conformance`: one table, build/conformance/report.txt
# per program, build/conformance/diffs/ per disagreement.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/linuxcnc.sh --install
out=build/conformance
rm -rf "$out"
mkdir -p "$out/rs274"
table=tests/conformance/tool.tbl
# rs274's tool table lives in a file mapped at $HOME/.tool.mmap, which every LinuxCNC
# process sharing a HOME truncates and rewrites at start: a running LinuxCNC's task then
# dies of SIGBUS (docs/linuxcnc.md). These runs get a HOME of their own; cargo and rustup
# keep finding theirs (by default under the real HOME).
export RUSTUP_HOME="${RUSTUP_HOME:-$HOME/.rustup}" CARGO_HOME="${CARGO_HOME:-$HOME/.cargo}"
export HOME="$PWD/$out/home"
mkdir -p "$HOME"
manifest="$out/manifest.tsv"
: > "$manifest"
i=0
# shellcheck disable=SC2046
for f in $(dpkg -L linuxcnc-uspace | grep -E '\.ngc$' | sort); do
    [ -f "$f" ] || continue
    i=$((i + 1))
    o="$PWD/$out/rs274/$(printf '%03d' "$i").out"
    status=0
    (cd "$(dirname "$f")" && timeout 10 rs274 -g -t "$OLDPWD/$table" "$f" > "$o" 2> "$o.err" < /dev/null) || status=$?
    printf '%s\t%s\t%s\n' "$status" "$f" "$o" >> "$manifest"
done
cargo run --release -q -p finestep-cli -- conformance "$manifest" --out "$out" --tool-table "$table"
