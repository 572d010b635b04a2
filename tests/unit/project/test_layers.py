"""Imports point one way: the import-linter contracts in pyproject.toml hold, and an import
that points up breaks one of them (so it fails this test, not a review). docs/architecture.md
draws the same layers and names every package."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[3]
CONFIG = ROOT / "pyproject.toml"
PACKAGES = ("protocol", "common", "vehicle_agents", "simulator", "backend", "gcs", "gcs_client")
LINT_IMPORTS = Path(sys.executable).with_name("lint-imports")


def lint_imports(tree: Path) -> subprocess.CompletedProcess[str]:
    """`lint-imports` over the packages found first in `tree`, with our contracts."""
    environment = {**os.environ, "PYTHONPATH": str(tree)}
    return subprocess.run(
        [str(LINT_IMPORTS), "--no-cache", str(CONFIG)],
        capture_output=True,
        text=True,
        cwd=tree,
        env=environment,
        timeout=120,
        check=False,
    )


def test_every_import_keeps_its_layer() -> None:
    result = lint_imports(ROOT)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "0 broken" in result.stdout


# An import each contract forbids: the module that imports, and what it imports.
UPWARD = {
    "storage imports the api": ("backend/storage/upward.py", "backend.api.security"),
    "realtime imports the hub": ("backend/realtime/upward.py", "backend.hub"),
    "the domain imports the fleet": ("backend/safety/upward.py", "backend.fleet.registry"),
    "the hub imports the agent": ("backend/fleet/upward.py", "vehicle_agents.fcu.missions"),
    "the agent imports the hub": ("vehicle_agents/upward.py", "backend.errors"),
    "the simulator imports the agent": ("simulator/upward.py", "vehicle_agents.config"),
    "the protocol imports common": ("protocol/upward.py", "common.retry"),
    "the hub imports the command line": ("backend/api/upward.py", "gcs.launcher"),
    "the agent imports the database": ("vehicle_agents/upward.py", "sqlalchemy"),
    "the registry imports the store": ("backend/fleet/registry.py", "backend.storage.models"),
    "a route imports the hub": ("backend/api/system.py", "backend.hub.services"),
    "a route takes the whole hub": ("backend/api/vehicles.py", "backend.hub.services"),
    "a feature's route imports the hub": ("backend/formation/routes.py", "backend.hub.start"),
    "one feature imports another": ("backend/formation/upward.py", "backend.survey.service"),
    "manual control imports the scans": ("backend/manual_control/upward.py", "backend.scans.views"),
    "the client imports the protocol": ("gcs_client/upward.py", "protocol.messages"),
    "the client imports the web framework": ("gcs_client/upward.py", "fastapi"),
    "the flight controller link imports the hub link": (
        "vehicle_agents/fcu/upward.py",
        "vehicle_agents.hub.link",
    ),
    "an agent feature imports the wiring": (
        "vehicle_agents/control/upward.py",
        "vehicle_agents.agent",
    ),
    "the simulated vehicle imports the transport": (
        "simulator/vehicle/upward.py",
        "simulator.server",
    ),
    "the simulator's parameters import a vehicle": (
        "simulator/params/upward.py",
        "simulator.copter",
    ),
    "the settings import auth": ("backend/settings/production.py", "backend.auth.password_policy"),
    "a message imports the decoders": ("protocol/messages/base.py", "protocol.messages.codec"),
    "one domain's messages import another's": (
        "protocol/messages/manual.py",
        "protocol.messages.commands",
    ),
}


@pytest.fixture(scope="module")
def tree(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A copy of our packages, to plant an import in."""
    copy = tmp_path_factory.mktemp("tree")
    for package in PACKAGES:
        shutil.copytree(
            ROOT / package, copy / package, ignore=shutil.ignore_patterns("__pycache__")
        )
    untouched = lint_imports(copy)  # so what breaks a contract below is the planted import
    assert untouched.returncode == 0, untouched.stdout + untouched.stderr
    return copy


@pytest.mark.parametrize(("module", "imported"), UPWARD.values(), ids=UPWARD.keys())
def test_an_upward_import_breaks_a_contract(tree: Path, module: str, imported: str) -> None:
    planted = tree / module
    before = planted.read_text() if planted.exists() else None
    planted.write_text(f"{before or ''}\nimport {imported}  # noqa\n")
    try:
        result = lint_imports(tree)
    finally:
        if before is None:
            planted.unlink()
        else:
            planted.write_text(before)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "BROKEN" in result.stdout
    assert imported.split(".")[0] in result.stdout


# -- docs/architecture.md draws the same layers ---------------------------------------------

ARCHITECTURE = ROOT / "docs" / "architecture.md"
# A layer's line in the page's hub drawing: its modules and packages, then what they do.
_LAYER_LINE = re.compile(r"^ ((?:[a-z_0-9]+(?:/|\.py)(?: │ |  ))*[a-z_0-9]+(?:/|\.py))(?:\s|$)")


def _contract(contract_id: str) -> dict[str, Any]:
    config = tomllib.loads(CONFIG.read_text())["tool"]["importlinter"]["contracts"]
    (contract,) = [c for c in config if c["id"] == contract_id]
    return dict(contract)


def _members(layer: str) -> frozenset[str]:
    """``"safety | auth"`` -> {"safety", "auth"} (``:`` joins siblings that may import each
    other, ``|`` independent ones)."""
    return frozenset(name.strip() for name in re.split(r"[|:]", layer))


def _drawn_hub_layers() -> list[frozenset[str]]:
    text = ARCHITECTURE.read_text()
    start = text.index("Inside the hub, top to bottom")
    block = text[text.index("```", start) + 3 : text.index("```", text.index("```", start) + 3)]
    layers = []
    for line in block.splitlines():
        if match := _LAYER_LINE.match(line):
            names = re.split(r" │ |  ", match.group(1))
            layers.append(frozenset(name.removesuffix("/").removesuffix(".py") for name in names))
    return layers


def test_the_architecture_page_draws_the_hubs_layers_as_the_contract_has_them() -> None:
    contract = [_members(layer) for layer in _contract("hub")["layers"]]
    assert _drawn_hub_layers() == contract


def test_the_architecture_page_names_every_package() -> None:
    text = ARCHITECTURE.read_text()
    tabled = set(re.findall(r"^\| `([a-z_0-9/.]+)` \|", text, flags=re.MULTILINE))
    wanted = {f"{package}/" for package in PACKAGES if package != "backend"}  # by its parts
    for layer in _contract("hub")["layers"]:
        for name in _members(layer):
            module = ROOT / "backend" / f"{name}.py"
            wanted.add(f"backend/{name}.py" if module.exists() else f"backend/{name}/")
    assert wanted - tabled == set()
