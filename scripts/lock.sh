#!/usr/bin/env bash
# Writes the Python lock files in requirements/ from pyproject.toml:
#   scripts/lock.sh                  keeps every version already locked; adds, drops or moves
#                                    only what a change to pyproject.toml asks for
#   scripts/lock.sh --upgrade        moves every package to the newest version allowed
#   scripts/lock.sh -P fastapi ...   moves these packages only (uv's --upgrade-package)
#
# One lock per install set, each resolved within the one before it, so a package has the
# same version in all of them:
#   requirements/agent.txt   the agent: the base dependencies (a drone's install)
#   requirements/hub.txt     plus the `hub` extra (scripts/setup.sh, the hub's image)
#   requirements/simulator.txt  the base set plus the `simulator` extra (the simulator's
#                            image), resolved within hub.txt so it shares its versions
#   requirements/dev.txt     plus the `dev` extra (scripts/setup.sh --dev, CI)
# Each is universal (one file for every platform and every Python from 3.11 on, with
# environment markers where they differ) and lists the sha256 of every wheel and sdist of
# each pinned version, so `pip install --require-hashes -r` takes it on Linux x86_64 and
# aarch64 alike. uv resolves from PyPI; pip's own index settings do not apply here.
set -euo pipefail
cd "$(dirname "$0")/.."

uv=.venv/bin/uv
if [ ! -x "$uv" ]; then
    # `scripts/setup.sh --dev` installs uv (it is in the dev extra); before that, fetch it.
    [ -x .venv/bin/python ] || python3 -m venv .venv
    .venv/bin/python -m pip install -q uv
fi

# name  extra  resolved within
locks=(
    "agent  -      -"
    "hub    hub    agent"
    "simulator simulator hub"
    "dev    dev    hub"
)
mkdir -p requirements
for lock in "${locks[@]}"; do
    read -r name extra within <<<"$lock"
    args=(pyproject.toml --universal --python-version 3.11 --generate-hashes --quiet
        --no-emit-package fleet-gcs --custom-compile-command "scripts/lock.sh"
        --output-file "requirements/$name.txt")
    [ "$extra" != "-" ] && args+=(--extra "$extra")
    [ "$within" != "-" ] && args+=(--constraint "requirements/$within.txt")
    echo "==> requirements/$name.txt"
    "$uv" pip compile "${args[@]}" "$@"
done
