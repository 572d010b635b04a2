"""Importing our code changes nothing of the process: no environment variable is set and no
MAVLink dialect is picked as a side effect of an import (the agent picks its dialect where
it builds its link, `vehicle_agents/fcu/dialect.py`). A tool that embeds the agent, the
simulator or the hub keeps the environment it had."""

from __future__ import annotations

import json
import os
import subprocess
import sys

PACKAGES = ("protocol", "common", "vehicle_agents", "simulator", "backend", "gcs")

# Imported in a fresh interpreter: this test process has long since loaded all of these.
_PROBE = """
import importlib, json, os, pkgutil, sys
before = dict(os.environ)
names = []
for package in {packages!r}:
    module = importlib.import_module(package)
    names.append(package)
    for info in pkgutil.walk_packages(module.__path__, package + "."):
        if info.name.endswith("__main__") or ".migrations" in info.name:
            continue  # a program, not a library: running it is its purpose
        importlib.import_module(info.name)
        names.append(info.name)
after = dict(os.environ)
changed = {{k: after.get(k) for k in set(before) | set(after) if before.get(k) != after.get(k)}}
print(json.dumps({{
    "modules": names,
    "changed": changed,
    "mavutil": "pymavlink.mavutil" in sys.modules,
}}))
"""


def test_importing_every_module_leaves_the_process_as_it_was() -> None:
    clean = {k: v for k, v in os.environ.items() if not k.startswith("MAVLINK")}
    result = subprocess.run(
        [sys.executable, "-c", _PROBE.format(packages=PACKAGES)],
        capture_output=True,
        text=True,
        env=clean,
        timeout=120,
        check=True,
    )
    found = json.loads(result.stdout.splitlines()[-1])
    assert "vehicle_agents.agent" in found["modules"]
    assert "simulator.server" in found["modules"]
    assert found["changed"] == {}
    assert not found["mavutil"], "an import chose mavutil's dialect from the environment"
