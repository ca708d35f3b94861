#!/usr/bin/env bash
# Installs Debian's LinuxCNC (linuxcnc-uspace, about 180 MB without recommends) when
# `rs274`, its standalone interpreter, is missing. Idempotent; apt's lock makes a second
# caller wait. Extra packages to install alongside may be given as arguments.
set -euo pipefail
missing=()
command -v rs274 >/dev/null 2>&1 || missing+=(linuxcnc-uspace)
for p in "$@"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
[ ${#missing[@]} -eq 0 ] && exit 0
SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
echo "linuxcnc_setup: installing ${missing[*]} with apt"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
