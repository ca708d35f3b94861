#!/usr/bin/env bash
# Loads a board's bitstream (from `make bitstream-*`, under build/bitstream/) with
# openFPGALoader (Debian's `openfpgaloader`), into SRAM (lost at power-off) or into the
# configuration flash.
#
#   scripts/flash.sh BOARD [sram|flash]        (make flash BOARD=... [MODE=flash])
#
# BOARD: colorlight-5a75b (ECP5; no programmer on the board: a JTAG adapter on J27,
# CABLE=ft2232 unless set), ice40-hx8k (iCE40-HX8K breakout, its FT2232H),
# icebreaker (iCEBreaker, its FT2232H). When openFPGALoader is missing, no cable answers
# `--detect`, or DRY_RUN=1, prints the command instead of running it and exits 0.
# Bring-up: docs/boards/<board>.md.
set -euo pipefail
cd "$(dirname "$0")/.."

usage() { sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
[ $# -ge 1 ] || usage
board=$1
mode=${2:-sram}

# Each board: the bitstream's build target and top, and how openFPGALoader reaches it.
case $board in
    colorlight-5a75b)
        target=ecp5; top=colorlight_5a75b; ext=bit
        cable=(-c "${CABLE:-ft2232}") ;;
    ice40-hx8k)
        target=ice40-hx8k; top=ice40_hx8k_breakout; ext=bin
        cable=(-b ice40_generic) ;;
    icebreaker)
        target=ice40-up5k; top=icebreaker; ext=bin
        cable=(-b ice40_generic) ;;
    *)
        echo "flash: unknown board '$board' (colorlight-5a75b, ice40-hx8k, icebreaker)" >&2
        exit 2 ;;
esac
case $mode in
    sram) mode_args=(-m) ;;
    flash) mode_args=(-f) ;;
    *) echo "flash: unknown mode '$mode' (sram, flash)" >&2; exit 2 ;;
esac

bitstream=build/bitstream/$target/$top.$ext
command=(openFPGALoader "${cable[@]}" "${mode_args[@]}" "$bitstream")

why=""
if [ "${DRY_RUN:-0}" = 1 ]; then
    why="dry run (DRY_RUN=1)"
elif ! command -v openFPGALoader >/dev/null 2>&1; then
    why="openFPGALoader is not installed (apt-get install openfpgaloader)"
elif ! openFPGALoader "${cable[@]}" --detect >/dev/null 2>&1; then
    why="no cable answers (openFPGALoader ${cable[*]} --detect failed)"
fi
if [ -n "$why" ]; then
    echo "flash: $why; the command is:"
    echo "  ${command[*]}"
    [ -f "$bitstream" ] || echo "flash: $bitstream is not built yet: make bitstream-${target%%-*}"
    exit 0
fi
if [ ! -f "$bitstream" ]; then
    echo "flash: $bitstream is not built: make bitstream-${target%%-*}" >&2
    exit 1
fi
echo "flash: ${command[*]}"
exec "${command[@]}"
