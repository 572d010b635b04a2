#!/usr/bin/env bash
# Installs everything the project needs, idempotently:
#   scripts/setup.sh          the hub, agent and dashboard (for `make demo`)
#   scripts/setup.sh --dev    plus test tools, Chromium and docker-compose (for `make test`)
# Python packages come from the locks in requirements/ (scripts/lock.sh writes them),
# npm packages from frontend/package-lock.json.
set -euo pipefail
cd "$(dirname "$0")/.."

dev=0
[ "${1:-}" = "--dev" ] && dev=1

as_root() {
    if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

apt_install() {
    local missing=()
    for package in "$@"; do
        dpkg -s "$package" >/dev/null 2>&1 || missing+=("$package")
    done
    [ ${#missing[@]} -eq 0 ] && return 0
    echo "==> installing Debian packages: ${missing[*]}"
    as_root apt-get update -qq
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
}

need_node=1
command -v node >/dev/null && command -v npm >/dev/null && need_node=0
python_ok=1
python3 -c 'import sys, venv, ensurepip; sys.exit(sys.version_info < (3, 11))' 2>/dev/null || python_ok=0
if [ $need_node -eq 1 ] || [ $python_ok -eq 0 ]; then
    apt_install python3 python3-venv nodejs npm
fi
if [ $dev -eq 1 ]; then
    # The browser tests drive Debian's Chromium; the compose test validates the file;
    # docs/integrator.md's client steps, which the suite runs, use curl.
    apt_install chromium docker-compose curl
fi

if [ ! -x .venv/bin/python ]; then
    echo "==> creating .venv"
    python3 -m venv .venv
fi
lock="requirements/hub.txt"
[ $dev -eq 1 ] && lock="requirements/dev.txt"
echo "==> installing Python packages ($lock)"
.venv/bin/python -m pip install -q --upgrade pip
# The exact versions and hashes scripts/lock.sh wrote, then the project itself on top.
.venv/bin/python -m pip install -q --require-hashes -r "$lock"
.venv/bin/python -m pip install -q --no-deps -e .

cd frontend
if [ ! -d node_modules ] || [ package-lock.json -nt node_modules/.package-lock.json ]; then
    echo "==> installing npm packages"
    npm ci --no-audit --no-fund --loglevel=error
fi
echo "==> building the dashboard"
npm run --silent build >/dev/null
