#!/usr/bin/env bash
# Regenerates tests/conformance/NAME.rs274, the expected output of the quick conformance
# slice, from LinuxCNC's rs274 (installed by scripts/linuxcnc.sh --install) for each
# tests/conformance/NAME.ngc and compensated/NAME.ngc (cutter compensation, checked by
# finestep-planner's tests/cutter_comp.rs), or only those named as arguments. rs274 must
# accept each.
set -euo pipefail
cd "$(dirname "$0")/../tests/conformance"
../../scripts/linuxcnc.sh --install
files=("$@")
# A HOME of its own for rs274's $HOME/.tool.mmap (scripts/conformance.sh says why).
HOME=$(mktemp -d)
export HOME
trap 'rm -rf "$HOME"' EXIT
[ ${#files[@]} -eq 0 ] && files=(*.ngc compensated/*.ngc)
for f in "${files[@]}"; do
    # A path relative to tests/conformance (NAME.ngc or compensated/NAME.ngc).
    f=${f#*tests/conformance/}
    if ! rs274 -g -t tool.tbl "$f" > "${f%.ngc}.rs274" 2>/dev/null < /dev/null; then
        echo "rs274 refuses $f:"; tail -3 "${f%.ngc}.rs274"; exit 1
    fi
done
echo "conformance_expect: ${#files[@]} expectations written"
